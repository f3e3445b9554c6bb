#include "phymul/vtk.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <ostream>
#include <stdexcept>
#include <system_error>
#include <tuple>

#include "io/vtk_appended.hpp"

namespace phymul {

namespace {

// errno is the only reason iostreams leave behind; it can be stale, so fall back to a generic
// word rather than blame an unrelated earlier error.
std::string errno_reason(int err) { return err != 0 ? std::strerror(err) : "I/O error"; }

std::string xml_escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// Shortest representation that parses back to the same bits, so results written and read
// again compare exactly (restarts, regression checks against stored frames).
void append_double(std::string& out, double value) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  if (ec != std::errc{}) throw std::logic_error("to_chars failed for a double");
  out.append(buffer, end);
}

void append_integer(std::string& out, long long value) {
  char buffer[24];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, value);
  if (ec != std::errc{}) throw std::logic_error("to_chars failed for an integer");
  out.append(buffer, end);
}

void check_finite(std::string_view what, std::span<const double> values) {
  for (size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      throw std::invalid_argument(
          fmt::format("write_vtu: {} value {} at index {} is not finite", what, values[i], i));
    }
  }
}

void validate_vtu_input(std::span<const Vec3> points, std::span<const Cell> cells,
                        std::span<const PointField> point_fields,
                        std::span<const CellField> cell_fields) {
  for (size_t i = 0; i < points.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(points[i][k])) {
        throw std::invalid_argument(fmt::format(
            "write_vtu: point {} coordinate {} is not finite ({})", i, k, points[i][k]));
      }
    }
  }
  for (size_t c = 0; c < cells.size(); ++c) {
    for (const int node : cells[c].node_span()) {
      if (node < 0 || size_t(node) >= points.size()) {
        throw std::invalid_argument(fmt::format(
            "write_vtu: cell {} refers to node {}, outside 0..{}", c, node, points.size()));
      }
    }
  }
  for (const PointField& field : point_fields) {
    if (field.components != 1 && field.components != 3) {
      throw std::invalid_argument(
          fmt::format("write_vtu: point field '{}' has {} components, expected 1 or 3", field.name,
                      field.components));
    }
    const size_t expected = points.size() * size_t(field.components);
    if (field.values.size() != expected) {
      throw std::invalid_argument(
          fmt::format("write_vtu: point field '{}' has {} values, expected {} ({} points x {})",
                      field.name, field.values.size(), expected, points.size(), field.components));
    }
    check_finite(fmt::format("point field '{}'", field.name), field.values);
  }
  for (const CellField& field : cell_fields) {
    if (field.values.size() != cells.size()) {
      throw std::invalid_argument(
          fmt::format("write_vtu: cell field '{}' has {} values, expected {} (one per cell)",
                      field.name, field.values.size(), cells.size()));
    }
  }
}

// One line per tuple keeps the files readable and diffable without costing much size.
void write_double_array(std::ostream& os, std::string_view name, int components,
                        std::span<const double> values) {
  os << fmt::format(
      "        <DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" "
      "format=\"ascii\">\n",
      xml_escape(name), components);
  // One write per array: the stream's per-insert cost was a third of a frame's.
  std::string text;
  text.reserve(values.size() * 25 + values.size() / size_t(components) * 11);
  for (size_t i = 0; i < values.size(); i += size_t(components)) {
    text += "          ";
    for (int k = 0; k < components; ++k) {
      if (k > 0) text += ' ';
      append_double(text, values[i + size_t(k)]);
    }
    text += '\n';
  }
  os << text << "        </DataArray>\n";
}

}  // namespace

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write) {
  std::filesystem::path tmp = path;
  tmp += ".tmp";
  const auto discard_tmp = [&] {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
  };
  const auto fail = [&](const std::string& reason) {
    discard_tmp();
    throw std::runtime_error(fmt::format("cannot write {}: {}", path.string(), reason));
  };

  errno = 0;
  std::ofstream os(tmp, std::ios::binary | std::ios::trunc);
  if (!os.is_open()) fail(errno_reason(errno));
  try {
    write(os);
  } catch (...) {
    os.close();
    discard_tmp();
    throw;
  }
  errno = 0;
  os.flush();
  if (!os) fail(errno_reason(errno));
  os.close();
  if (os.fail()) fail(errno_reason(errno));

  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) fail(ec.message());
}

namespace {

// Connectivity of an unstructured grid as VTK stores it.
struct CellArrays {
  std::vector<int> connectivity;
  std::vector<long long> offsets;  // Int64: the running sum outgrows Int32 before node ids do
  std::vector<std::uint8_t> types;
};

template <class Integer>
void write_integer_array(std::ostream& os, std::string_view type, std::string_view name,
                         std::span<const Integer> values) {
  os << fmt::format("        <DataArray type=\"{}\" Name=\"{}\" format=\"ascii\">\n", type,
                    xml_escape(name));
  std::string text;
  text.reserve(values.size() * 18);
  for (const Integer value : values) {
    text += "          ";
    append_integer(text, value);
    text += '\n';
  }
  os << text << "        </DataArray>\n";
}

// The arrays of one file, as text in place or as raw bytes appended after the XML.
class ArrayWriter {
 public:
  ArrayWriter(std::ostream& os, VtuEncoding encoding) : os_(os), encoding_(encoding) {}
  void doubles(std::string_view name, int components, std::span<const double> values) {
    if (encoding_ == VtuEncoding::ascii)
      write_double_array(os_, name, components, values);
    else
      appended_.add(os_, "Float64", xml_escape(name), components, values);
  }
  template <class Integer>
  void integers(std::string_view type, std::string_view name, std::span<const Integer> values) {
    if (encoding_ == VtuEncoding::ascii)
      write_integer_array(os_, type, name, values);
    else
      appended_.add(os_, type, xml_escape(name), 0, values);
  }
  void finish() {
    if (encoding_ == VtuEncoding::binary) appended_.write(os_);
  }

 private:
  std::ostream& os_;
  VtuEncoding encoding_;
  AppendedData appended_;
};

// Vec3 is three packed doubles, so the points are their coordinates in a row.
static_assert(sizeof(Vec3) == 3 * sizeof(double));
std::span<const double> coordinates(std::span<const Vec3> points) {
  return {reinterpret_cast<const double*>(points.data()), points.size() * 3};
}

void write_grid(const std::filesystem::path& path, std::span<const Vec3> points,
                const CellArrays& cells, std::span<const PointField> point_fields,
                std::span<const CellField> cell_fields, VtuEncoding encoding) {
  write_file_atomically(path, [&](std::ostream& os) {
    os << (encoding == VtuEncoding::ascii
               ? "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
                 "byte_order=\"LittleEndian\">\n"
               : "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                 "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
    os << "  <UnstructuredGrid>\n";
    os << fmt::format("    <Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", points.size(),
                      cells.types.size());
    ArrayWriter arrays(os, encoding);
    os << "      <PointData>\n";
    for (const PointField& field : point_fields)
      arrays.doubles(field.name, field.components, field.values);
    os << "      </PointData>\n";
    os << "      <CellData>\n";
    for (const CellField& field : cell_fields) arrays.integers("Int32", field.name, field.values);
    os << "      </CellData>\n";
    os << "      <Points>\n";
    arrays.doubles("Points", 3, coordinates(points));
    os << "      </Points>\n";
    os << "      <Cells>\n";
    arrays.integers("Int32", "connectivity", std::span<const int>(cells.connectivity));
    arrays.integers("Int64", "offsets", std::span<const long long>(cells.offsets));
    arrays.integers("UInt8", "types", std::span<const std::uint8_t>(cells.types));
    os << "      </Cells>\n";
    os << "    </Piece>\n"
          "  </UnstructuredGrid>\n";
    arrays.finish();
    os << "</VTKFile>\n";
  });
}

}  // namespace

void write_vtu(const std::filesystem::path& path, std::span<const Vec3> points,
               std::span<const Cell> cells, std::span<const PointField> point_fields,
               std::span<const CellField> cell_fields, VtuEncoding encoding) {
  // Validate before opening anything so that bad input leaves no file behind.
  validate_vtu_input(points, cells, point_fields, cell_fields);
  CellArrays arrays;
  arrays.connectivity.reserve(cells.size() * std::tuple_size_v<decltype(Cell::nodes)>);
  arrays.offsets.reserve(cells.size());
  arrays.types.reserve(cells.size());
  for (const Cell& cell : cells) {
    for (const int node : cell.node_span()) arrays.connectivity.push_back(node);
    arrays.offsets.push_back(static_cast<long long>(arrays.connectivity.size()));
    arrays.types.push_back(std::uint8_t(vtk_cell_type(cell.type)));
  }
  write_grid(path, points, arrays, point_fields, cell_fields, encoding);
}

void write_points_vtu(const std::filesystem::path& path, std::span<const Vec3> points,
                      std::span<const PointField> point_fields, VtuEncoding encoding) {
  validate_vtu_input(points, {}, point_fields, {});
  constexpr std::uint8_t kVtkVertex = 1;
  CellArrays arrays;
  for (int i = 0; i < int(points.size()); ++i) {
    arrays.connectivity.push_back(i);
    arrays.offsets.push_back(i + 1);
    arrays.types.push_back(kVtkVertex);
  }
  write_grid(path, points, arrays, point_fields, {}, encoding);
}

void write_pvd(const std::filesystem::path& path, std::span<const PvdEntry> entries) {
  for (size_t i = 0; i < entries.size(); ++i) {
    if (!std::isfinite(entries[i].time)) {
      throw std::invalid_argument(
          fmt::format("write_pvd: time of entry {} ('{}') is not finite ({})", i, entries[i].file,
                      entries[i].time));
    }
  }
  write_file_atomically(path, [&](std::ostream& os) {
    os << "<?xml version=\"1.0\"?>\n"
          "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
          "  <Collection>\n";
    std::string line;
    for (const PvdEntry& entry : entries) {
      line.assign("    <DataSet timestep=\"");
      append_double(line, entry.time);
      line += "\" group=\"\" part=\"0\" file=\"";
      line += xml_escape(entry.file);
      line += "\"/>\n";
      os << line;
    }
    os << "  </Collection>\n"
          "</VTKFile>\n";
  });
}

}  // namespace phymul

// VTK XML meshes: unstructured grids (.vtu) and closed polygon surfaces (.vtp), one Piece,
// arrays in ASCII, inline base64 or appended data (raw or base64), plain or zlib-compressed,
// as VTK, ParaView and 3D Slicer write them.
#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <climits>
#include <cmath>
#include <pugixml.hpp>

#include "io/mesh_text.hpp"
#include "io/vtk_xml_data.hpp"
#include "phymul/mesh_io.hpp"

namespace phymul {
namespace {

using pugi::xml_node;
using vtkxml::Scalar;

constexpr long long kMaxCount = INT_MAX / 8;

std::string shown(std::string_view text) {
  return std::string(text.substr(0, 32)) + (text.size() > 32 ? "..." : "");
}

// One file: its bytes, its XML (parsed up to the appended data, which may be binary) and how
// it stores binary arrays. Every problem is a MeshFileError at an element's line and column.
class Source {
 public:
  Source(std::string_view bytes, std::string name);
  // The single <Piece> of a file whose VTKFile type is `type`; `extension` names the format.
  xml_node piece(std::string_view type, std::string_view extension) const;
  const std::string& name() const { return name_; }

  [[noreturn]] void fail_at(size_t offset, const std::string& message) const;
  [[noreturn]] void fail(xml_node at, const std::string& message) const;
  long long whole(xml_node at, const char* attribute, bool required = true) const;
  xml_node array(xml_node parent, std::string_view name) const;  // DataArray by Name
  // The array's values: `count` of them (a different number is refused).
  std::vector<double> reals(xml_node array, size_t count) const;
  std::vector<long long> integers(xml_node array, size_t count) const;

 private:
  void read_layout();
  size_t offset_of(xml_node node) const;
  std::string_view text_of(xml_node array, size_t& offset) const;
  Scalar type_of(xml_node array) const;
  std::string binary(xml_node array, Scalar type, size_t count) const;
  template <class T>
  std::vector<T> ascii(xml_node array, Scalar type, size_t count) const;

  std::string_view bytes_;
  std::string name_;
  std::string xml_;  // the XML part, parsed in place
  pugi::xml_document doc_;
  vtkxml::Layout layout_;
  std::string_view appended_;  // after the '_' that starts it
  size_t appended_at_ = 0;     // its offset in the file
  bool appended_base64_ = false, has_appended_ = false;
};

Source::Source(std::string_view bytes, std::string name) : bytes_(bytes), name_(std::move(name)) {
  const size_t first = bytes.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos || bytes[first] != '<')
    throw MeshFileError(name_, 1, 1,
                        fmt::format("expected a VTK XML file (starting with '<?xml' or "
                                    "'<VTKFile'), found '{}'",
                                    shown(bytes.substr(first == std::string_view::npos ? 0 : first,
                                                       bytes.find('\n', first) - first))));
  // Appended data may hold any byte: the XML is read up to its start and closed there.
  const size_t tag = bytes.find("<AppendedData");
  size_t xml_end = bytes.size();
  if (tag != std::string_view::npos) {
    const size_t close = bytes.find('>', tag);
    if (close == std::string_view::npos) fail_at(tag, "the <AppendedData> tag is cut (truncated?)");
    xml_end = close + 1;
    const size_t underscore = bytes.find_first_not_of(" \t\r\n", xml_end);
    if (bytes[close - 1] != '/') {
      if (underscore == std::string_view::npos || bytes[underscore] != '_')
        fail_at(std::min(underscore, bytes.size()),
                "expected '_' to start the appended data after <AppendedData>");
      const size_t end = bytes.rfind("</AppendedData>");
      appended_at_ = underscore + 1;
      appended_ = bytes.substr(appended_at_, end != std::string_view::npos && end > underscore
                                                 ? end - appended_at_
                                                 : std::string_view::npos);
      has_appended_ = true;
    }
  }
  xml_.assign(bytes.substr(0, xml_end));
  if (has_appended_) xml_ += "</AppendedData></VTKFile>";
  const pugi::xml_parse_result r = doc_.load_buffer_inplace(
      xml_.data(), xml_.size(), pugi::parse_default & ~pugi::parse_eol, pugi::encoding_utf8);
  if (!r)
    fail_at(std::min(size_t(std::max<ptrdiff_t>(r.offset, 0)), xml_end),
            fmt::format("not well-formed XML: {}", r.description()));
  read_layout();
}

void Source::read_layout() {
  const xml_node root = doc_.document_element();
  if (std::string_view(root.name()) != "VTKFile")
    fail(root,
         fmt::format("expected <VTKFile> as the root element, found <{}>", shown(root.name())));
  const std::string_view header = root.attribute("header_type").as_string("UInt32");
  if (header != "UInt32" && header != "UInt64")
    fail(root, fmt::format("header_type '{}': expected UInt32 or UInt64", shown(header)));
  layout_.header_bytes = header == "UInt64" ? 8 : 4;
  const std::string_view order = root.attribute("byte_order").as_string("LittleEndian");
  if (order != "LittleEndian" && order != "BigEndian")
    fail(root, fmt::format("byte_order '{}': expected LittleEndian or BigEndian", shown(order)));
  layout_.big_endian = order == "BigEndian";
  const std::string_view compressor = root.attribute("compressor").value();
  if (!compressor.empty() && compressor != "vtkZLibDataCompressor")
    fail(root, fmt::format("compressor '{}' is not supported: expected vtkZLibDataCompressor or "
                           "none (write with zlib compression, or none)",
                           shown(compressor)));
  layout_.zlib = !compressor.empty();
  if (!has_appended_) return;
  const xml_node appended = root.child("AppendedData");
  const std::string_view encoding = appended.attribute("encoding").value();
  if (encoding != "raw" && encoding != "base64")
    fail(appended,
         fmt::format("AppendedData encoding '{}': expected raw or base64", shown(encoding)));
  appended_base64_ = encoding == "base64";
}

xml_node Source::piece(std::string_view type, std::string_view extension) const {
  const xml_node root = doc_.document_element();
  const std::string_view found = root.attribute("type").value();
  if (found != type)
    fail(root, fmt::format("this VTK XML file holds '{}', a {} file holds {}", shown(found),
                           extension, type));
  const xml_node data = root.child(std::string(type).c_str());
  if (!data) fail(root, fmt::format("<VTKFile> has no <{}> element", type));
  const xml_node piece = data.child("Piece");
  if (!piece) fail(data, fmt::format("<{}> has no <Piece>", type));
  if (piece.next_sibling("Piece"))
    fail(piece.next_sibling("Piece"),
         "a second <Piece>: only files of one piece are read (ParaView: Merge Blocks)");
  return piece;
}

size_t Source::offset_of(xml_node node) const {
  const ptrdiff_t at = node.offset_debug();
  return at > 0 ? size_t(at) - (node.type() == pugi::node_element ? 1 : 0) : 0;
}

void Source::fail_at(size_t offset, const std::string& message) const {
  offset = std::min(offset, bytes_.size());
  const std::string_view before = bytes_.substr(0, offset);
  const int line = int(std::count(before.begin(), before.end(), '\n')) + 1;
  const size_t start = before.rfind('\n');
  const int column = int(offset - (start == std::string_view::npos ? 0 : start + 1)) + 1;
  throw MeshFileError(name_, line, column, message);
}

void Source::fail(xml_node at, const std::string& message) const {
  fail_at(offset_of(at), message);
}

long long Source::whole(xml_node at, const char* attribute, bool required) const {
  const pugi::xml_attribute a = at.attribute(attribute);
  if (!a) {
    if (!required) return 0;
    fail(at, fmt::format("<{}> has no {} attribute", at.name(), attribute));
  }
  const std::string_view text = a.value();
  long long value = -1;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc{} || end != text.data() + text.size() || value < 0 || value > kMaxCount)
    fail(at, fmt::format("{} must be a whole number in [0, {}], found '{}'", attribute, kMaxCount,
                         shown(text)));
  return value;
}

xml_node Source::array(xml_node parent, std::string_view name) const {
  for (xml_node a : parent.children("DataArray"))
    if (a.attribute("Name").value() == name) return a;
  fail(parent, fmt::format("<{}> has no DataArray named '{}'", parent.name(), name));
}

Scalar Source::type_of(xml_node array) const {
  const std::string_view type = array.attribute("type").value();
  const auto scalar = vtkxml::scalar_named(type);
  if (!scalar)
    fail(array, fmt::format("DataArray '{}' has type '{}': expected Int8 ... Int64, UInt8 ... "
                            "UInt64, Float32 or Float64",
                            array.attribute("Name").value(), shown(type)));
  return *scalar;
}

// The array's text in the file (ascii and inline base64), and its offset there.
std::string_view Source::text_of(xml_node array, size_t& offset) const {
  const xml_node text = array.first_child();
  offset = offset_of(array);
  if (!text || (text.type() != pugi::node_pcdata && text.type() != pugi::node_cdata)) return {};
  offset = size_t(text.value() - xml_.data());
  return bytes_.substr(offset, std::char_traits<char>::length(text.value()));
}

std::string Source::binary(xml_node array, Scalar type, size_t count) const {
  const std::string_view format = array.attribute("format").value();
  std::string_view data;
  size_t at = 0;
  bool base64 = true;
  if (format == "binary") {
    data = text_of(array, at);
  } else if (format != "appended") {
    fail(array, fmt::format("DataArray '{}' has format '{}': expected ascii, binary or appended",
                            array.attribute("Name").value(), shown(format)));
  } else {
    if (!has_appended_)
      fail(array, "the array is appended but the file has no <AppendedData> (truncated?)");
    const long long offset = whole(array, "offset");
    if (size_t(offset) > appended_.size())
      fail(array, fmt::format("offset {} is beyond the {} bytes of appended data (truncated?)",
                              offset, appended_.size()));
    data = appended_.substr(size_t(offset));
    at = appended_at_ + size_t(offset);
    base64 = appended_base64_;
  }
  try {
    vtkxml::ByteStream in(data, base64);
    return vtkxml::read_block(in, layout_, std::uint64_t(count) * std::uint64_t(size_of(type)));
  } catch (const vtkxml::DataError& e) {
    fail(array,
         fmt::format("DataArray '{}' ({} values of {}): {}{}", array.attribute("Name").value(),
                     count, array.attribute("type").value(), e.what(),
                     e.offset == std::string_view::npos
                         ? ""
                         : fmt::format(" (at byte {} of the file)", at + e.offset)));
  }
}

template <class T>
std::vector<T> Source::ascii(xml_node array, Scalar type, size_t count) const {
  size_t base = 0;
  const std::string_view text = text_of(array, base);
  std::vector<T> out;
  out.reserve(std::min(count, text.size() / 2 + 1));
  size_t at = 0;
  for (;;) {
    at = text.find_first_not_of(" \t\r\n", at);
    if (at == std::string_view::npos) break;
    const size_t end = std::min(text.find_first_of(" \t\r\n", at), text.size());
    const std::string_view token = text.substr(at, end - at);
    T value{};
    const auto [stop, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc{} || stop != token.data() + token.size())
      fail_at(base + at, fmt::format("expected a number ({}) in DataArray '{}', found '{}'",
                                     array.attribute("type").value(),
                                     array.attribute("Name").value(), shown(token)));
    if (out.size() == count)
      fail_at(base + at, fmt::format("DataArray '{}' holds more than its {} values",
                                     array.attribute("Name").value(), count));
    if constexpr (std::is_floating_point_v<T>)
      if (type == Scalar::float32) value = double(float(value));  // as VTK reads it
    out.push_back(value);
    at = end;
  }
  if (out.size() != count)
    fail_at(base + text.size(), fmt::format("DataArray '{}' holds {} values, expected {}",
                                            array.attribute("Name").value(), out.size(), count));
  return out;
}

std::vector<double> Source::reals(xml_node array, size_t count) const {
  const Scalar type = type_of(array);
  if (std::string_view(array.attribute("format").value()) == "ascii")
    return ascii<double>(array, type, count);
  return vtkxml::to_reals(binary(array, type, count), type, layout_.big_endian);
}

std::vector<long long> Source::integers(xml_node array, size_t count) const {
  const Scalar type = type_of(array);
  if (!vtkxml::is_integer(type))
    fail(array, fmt::format("DataArray '{}' must hold integers, its type is {}",
                            array.attribute("Name").value(), array.attribute("type").value()));
  if (std::string_view(array.attribute("format").value()) == "ascii")
    return ascii<long long>(array, type, count);
  return vtkxml::to_integers(binary(array, type, count), type, layout_.big_endian);
}

// NumberOfPoints points, finite, divided by `divisor`.
std::vector<Vec3> read_points(const Source& in, xml_node piece, double divisor) {
  const long long n = in.whole(piece, "NumberOfPoints");
  const xml_node points = piece.child("Points");
  if (!points) in.fail(piece, "<Piece> has no <Points>");
  const xml_node array = points.child("DataArray");
  if (!array) in.fail(points, "<Points> has no <DataArray>");
  const long long components = in.whole(array, "NumberOfComponents", false);
  if (components != 3)
    in.fail(array, fmt::format("the points have {} components (NumberOfComponents), expected 3",
                               std::max(components, 1LL)));
  const std::vector<double> xyz = in.reals(array, size_t(n) * 3);
  std::vector<Vec3> out(static_cast<size_t>(n));
  for (size_t i = 0; i < out.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      const double c = xyz[3 * i + size_t(a)];
      if (!std::isfinite(c))
        in.fail(array, fmt::format("point {} has a non-finite {} coordinate ({})", i, "xyz"[a], c));
      out[i][a] = c / divisor;
    }
  return out;
}

struct Cells {
  xml_node offsets_at, connectivity_at;
  std::vector<long long> offsets, connectivity;  // offsets: the end of each cell's nodes
  long long size(size_t c) const { return offsets[c] - (c == 0 ? 0 : offsets[c - 1]); }
  long long start(size_t c) const { return c == 0 ? 0 : offsets[c - 1]; }
};

// Offsets increasing (no cell without nodes, none over `most_nodes`) up to the connectivity's
// size, and every node a point's index.
Cells read_cells(const Source& in, xml_node parent, long long n, long long points,
                 long long most_nodes) {
  Cells c;
  c.offsets_at = in.array(parent, "offsets");
  c.offsets = in.integers(c.offsets_at, size_t(n));
  for (size_t i = 0; i < c.offsets.size(); ++i) {
    const long long before = c.start(i), o = c.offsets[i];
    if (o <= before)
      in.fail(c.offsets_at, fmt::format("offsets must increase (offset {} is {}, the one before "
                                        "{}): every cell has nodes",
                                        i, o, before));
    if (o > INT_MAX)
      in.fail(c.offsets_at, fmt::format("offset {} is {}, over the limit of {}", i, o, INT_MAX));
    if (o - before > most_nodes)
      in.fail(c.offsets_at, fmt::format("cell {} has {} nodes; supported cells have at most {}", i,
                                        o - before, most_nodes));
  }
  c.connectivity_at = in.array(parent, "connectivity");
  c.connectivity = in.integers(c.connectivity_at, size_t(c.offsets.empty() ? 0 : c.offsets.back()));
  for (size_t j = 0; j < c.connectivity.size(); ++j)
    if (c.connectivity[j] < 0 || c.connectivity[j] >= points) {
      const size_t cell = size_t(
          std::upper_bound(c.offsets.begin(), c.offsets.end(), (long long)j) - c.offsets.begin());
      in.fail(
          c.connectivity_at,
          fmt::format("node {} of cell {} is {}, outside the {} points [0, {}]",
                      (long long)j - c.start(cell), cell, c.connectivity[j], points, points - 1));
    }
  return c;
}

// Volume or surface cells of the types the legacy reader takes, not both.
void set_cell_types(const Source& in, xml_node cells_at, const Cells& raw, Mesh& mesh) {
  const xml_node types_at = in.array(cells_at, "types");
  const std::vector<long long> types = in.integers(types_at, raw.offsets.size());
  mesh.cells.resize(types.size());
  for (size_t c = 0; c < types.size(); ++c) {
    const auto type = mesh_io::cell_type_of_vtk(types[c]);
    if (!type)
      in.fail(types_at, fmt::format("cell {} has VTK type {}, not supported: expected {}", c,
                                    types[c], mesh_io::kVtkCellTypes));
    if (raw.size(c) != node_count(*type))
      in.fail(raw.offsets_at,
              fmt::format("cell {} is a {} (type {}) and needs {} nodes, it lists {}", c,
                          cell_type_name(*type), types[c], node_count(*type), raw.size(c)));
    if (c > 0 && is_volumetric(*type) != is_volumetric(mesh.cells[0].type))
      in.fail(types_at, fmt::format("cell {} is a {} but cell 0 is a {}: a mesh has volume cells "
                                    "or surface cells, not both",
                                    c, cell_type_name(*type), cell_type_name(mesh.cells[0].type)));
    Cell& cell = mesh.cells[c];
    cell.type = *type;
    for (long long k = 0; k < raw.size(c); ++k)
      cell.nodes[size_t(k)] = int(raw.connectivity[size_t(raw.start(c) + k)]);
  }
}

void check_points_used(const Source& in, xml_node piece, const Mesh& mesh, std::string_view by) {
  std::vector<char> used(mesh.points.size(), 0);
  for (const Cell& c : mesh.cells)
    for (int i : c.node_span()) used[size_t(i)] = 1;
  for (size_t i = 0; i < used.size(); ++i)
    if (!used[i])
      in.fail(piece.child("Points").child("DataArray"),
              fmt::format("point {} is used by no {} (a node without a cell has no mass); remove "
                          "it from the mesh",
                          i, by));
}

}  // namespace

Mesh parse_vtu_mesh(std::string_view bytes, const std::string& name, double divisor) {
  const Source in(bytes, name);
  const xml_node piece = in.piece("UnstructuredGrid", ".vtu");
  Mesh mesh;
  mesh.points = read_points(in, piece, divisor);
  const long long n = in.whole(piece, "NumberOfCells");
  if (n == 0) in.fail(piece, "the mesh has no cells (NumberOfCells is 0)");
  const xml_node cells = piece.child("Cells");
  if (!cells) in.fail(piece, "<Piece> has no <Cells>");
  const Cells raw = read_cells(in, cells, n, (long long)mesh.points.size(), 8);
  set_cell_types(in, cells, raw, mesh);
  check_points_used(in, piece, mesh, "cell");
  return mesh;  // point and cell data are not needed
}

Mesh parse_vtp_mesh(std::string_view bytes, const std::string& name, double divisor,
                    std::vector<std::string>* notes) {
  const Source in(bytes, name);
  const xml_node piece = in.piece("PolyData", ".vtp");
  Mesh mesh;
  mesh.points = read_points(in, piece, divisor);
  for (const auto& [attribute, what] :
       {std::pair("NumberOfVerts", "vertices (Verts)"), std::pair("NumberOfLines", "lines"),
        std::pair("NumberOfStrips",
                  "triangle strips (Strips; ParaView's Triangulate filter "
                  "makes them triangles)")})
    if (const long long k = in.whole(piece, attribute, false); k > 0)
      in.fail(piece, fmt::format("the file holds {} {}: only polygons (Polys) make a closed "
                                 "surface",
                                 k, what));
  const long long n = in.whole(piece, "NumberOfPolys");
  if (n == 0) in.fail(piece, "the file holds no polygon (NumberOfPolys is 0)");
  const xml_node polys = piece.child("Polys");
  if (!polys) in.fail(piece, "<Piece> has no <Polys>");
  const Cells raw = read_cells(in, polys, n, (long long)mesh.points.size(), INT_MAX);
  // Polygons are split into triangles from their first vertex, as OBJ and PLY faces.
  for (size_t c = 0; c < raw.offsets.size(); ++c) {
    if (raw.size(c) < 3)
      in.fail(raw.offsets_at,
              fmt::format("polygon {} has {} vertices (3 or more)", c, raw.size(c)));
    const long long* v = raw.connectivity.data() + raw.start(c);
    for (long long k = 1; k + 1 < raw.size(c); ++k) {
      Cell t;
      t.type = CellType::triangle;
      t.nodes[0] = int(v[0]), t.nodes[1] = int(v[k]), t.nodes[2] = int(v[k + 1]);
      mesh.cells.push_back(t);
    }
  }
  check_points_used(in, piece, mesh, "polygon");
  return mesh_io::finish_surface(std::move(mesh), name, notes);
}

}  // namespace phymul

// The VTK writer is checked against independent readers (meshio and Python's xml.etree), so a
// file that only our own code can parse does not pass.
#include "phymul/vtk.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

namespace phymul {
namespace {

namespace fs = std::filesystem;

// The machine's default python3 may be another interpreter without Debian's meshio.
constexpr const char* kPython = "/usr/bin/python3";

using Record = std::vector<std::string>;  // whitespace-separated tokens of one output line

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string shell_quote(const std::string& text) {
  std::string out = "'";
  for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

struct CommandResult {
  int status = -1;
  std::string out;
  std::string err;
};

CommandResult run_command(const std::string& command, const fs::path& stderr_file) {
  CommandResult result;
  FILE* pipe = popen((command + " 2>" + shell_quote(stderr_file.string())).c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer{};
  size_t n = 0;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0)
    result.out.append(buffer.data(), n);
  result.status = pclose(pipe);
  result.err = read_text(stderr_file);
  return result;
}

std::vector<Record> split_records(const std::string& text, char separator = '\0') {
  std::vector<Record> records;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    Record record;
    if (separator == '\0') {
      std::istringstream tokens(line);
      std::string token;
      while (tokens >> token) record.push_back(token);
    } else {
      std::string token;
      std::istringstream tokens(line);
      while (std::getline(tokens, token, separator)) record.push_back(token);
    }
    if (!record.empty()) records.push_back(record);
  }
  return records;
}

double parse_double(const std::string& text) {
  double value = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc{} || end != text.data() + text.size()) {
    throw std::runtime_error("not a double: '" + text + "'");
  }
  return value;
}

long long parse_integer(const std::string& text) {
  long long value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc{} || end != text.data() + text.size()) {
    throw std::runtime_error("not an integer: '" + text + "'");
  }
  return value;
}

// Bit equality: also tells -0.0 from 0.0 and catches the last-ulp losses that == on
// printed-and-reparsed values would hide only if both sides rounded the same way.
::testing::AssertionResult same_bits(const std::vector<double>& expected,
                                     const std::vector<std::string>& got_tokens,
                                     const std::string& what) {
  if (expected.size() != got_tokens.size()) {
    return ::testing::AssertionFailure()
           << what << ": expected " << expected.size() << " values, read " << got_tokens.size();
  }
  for (size_t i = 0; i < expected.size(); ++i) {
    const double got = parse_double(got_tokens[i]);
    if (std::bit_cast<std::uint64_t>(got) != std::bit_cast<std::uint64_t>(expected[i])) {
      char wrote[32];
      *std::to_chars(wrote, wrote + sizeof wrote, expected[i]).ptr = '\0';
      return ::testing::AssertionFailure()
             << what << "[" << i << "]: wrote " << wrote << ", read back " << got_tokens[i];
    }
  }
  return ::testing::AssertionSuccess();
}

std::vector<long long> parse_integers(const std::vector<std::string>& tokens) {
  std::vector<long long> values;
  for (const std::string& token : tokens) values.push_back(parse_integer(token));
  return values;
}

class VtkTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::random_device entropy;
    dir_ = fs::temp_directory_path() / (std::string("phymul_vtk_") + info->name() + "_" +
                                        std::to_string(getpid()) + "_" + std::to_string(entropy()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  // Runs `script` with /usr/bin/python3 and the given arguments; returns its stdout lines.
  std::string run_python(const std::string& script, const std::vector<fs::path>& args) {
    const fs::path script_file = dir_ / "reader.py";
    {
      std::ofstream out(script_file);
      out << script;
    }
    std::string command = std::string(kPython) + " " + shell_quote(script_file.string());
    for (const fs::path& arg : args) command.append(" ").append(shell_quote(arg.string()));
    const CommandResult result = run_command(command, dir_ / "python.err");
    EXPECT_EQ(result.status, 0) << command << " failed:\n" << result.err;
    return result.out;
  }

  // A missing meshio must fail the suite: skipping would let unreadable files go unnoticed.
  ::testing::AssertionResult meshio_available() {
    const CommandResult result =
        run_command(std::string(kPython) + " -c 'import meshio'", dir_ / "import.err");
    if (result.status == 0) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure()
           << kPython << " cannot import meshio; install the Debian package python3-meshio "
           << "(apt-get install python3-meshio; `make test` installs it).\n"
           << result.err;
  }

  fs::path dir_;
};

constexpr const char* kVtuReader = R"PY(
import sys
import xml.etree.ElementTree as ET
import numpy as np
import meshio

path = sys.argv[1]
# Raw appended data is not XML: parse what comes before it (closing the root by hand).
raw = open(path, "rb").read()
cut = raw.find(b"<AppendedData")
root = ET.fromstring(raw if cut < 0 else raw[:cut] + b"</VTKFile>")
print("root", root.tag, root.get("type"), root.get("version"), root.get("byte_order"),
      root.get("header_type", "-"))
for da in root.iter("DataArray"):
    print("array", da.get("Name"), da.get("type"), da.get("format"),
          da.get("NumberOfComponents", "-"))

def floats(a):
    return " ".join(repr(float(x)) for x in np.asarray(a).ravel())

def ints(a):
    return " ".join(str(int(x)) for x in np.asarray(a).ravel())

# meshio stores wedges in gmsh order; its writer maps them back to VTK order the same way.
try:
    from meshio._vtk_common import meshio_to_vtk_order
except ImportError:
    def meshio_to_vtk_order(cell_type):
        return None

m = meshio.read(path)
print("points", m.points.shape[0], m.points.shape[1], m.points.dtype, floats(m.points))
for block in m.cells:
    data = block.data
    order = meshio_to_vtk_order(block.type)
    if order is not None:
        data = data[:, order]
    print("cells", block.type, data.shape[0], data.shape[1], ints(data))
for name, a in m.point_data.items():
    a = np.asarray(a)
    comps = 1 if a.ndim == 1 else a.shape[1]
    print("point_data", name, a.shape[0], comps, a.dtype, floats(a))
for name, blocks in m.cell_data.items():
    for a in blocks:
        a = np.asarray(a)
        print("cell_data", name, a.size, a.dtype, ints(a))
)PY";

const char* meshio_name(CellType type) {
  switch (type) {
    case CellType::triangle:
      return "triangle";
    case CellType::quad:
      return "quad";
    case CellType::tetra:
      return "tetra";
    case CellType::hexa:
      return "hexahedron";
    case CellType::wedge:
      return "wedge";
  }
  return "?";
}

const std::vector<double> kAwkward = {1.0 / 3.0,
                                      1e-300,
                                      -2.5e7,
                                      -0.0,
                                      0.1 + 0.2,
                                      std::numeric_limits<double>::denorm_min(),
                                      std::numeric_limits<double>::max(),
                                      -std::numeric_limits<double>::min(),
                                      std::nextafter(1.0, 2.0),
                                      2.0 / 3.0 * 1e-3,
                                      123456789.12345678,
                                      -1e-17};

// Each pass over the list flips the sign and moves one ulp towards zero, so that no two
// values repeat and none overflows.
double awkward(size_t i) {
  double value = kAwkward[i % kAwkward.size()];
  for (size_t pass = 0; pass < i / kAwkward.size(); ++pass) value = -std::nextafter(value, 0.0);
  return value;
}

struct Written {
  std::vector<Vec3> points;
  std::vector<Cell> cells;
  std::vector<double> displacement;
  std::vector<double> scalar;
  std::vector<int> component;
};

Cell make_cell(CellType type, std::initializer_list<int> nodes) {
  Cell cell;
  cell.type = type;
  std::copy(nodes.begin(), nodes.end(), cell.nodes.begin());
  return cell;
}

Written make_data(std::vector<Cell> cells, int point_count) {
  Written w;
  w.cells = std::move(cells);
  size_t k = 0;
  for (int i = 0; i < point_count; ++i) {
    w.points.emplace_back(awkward(k), awkward(k + 1), awkward(k + 2));
    k += 3;
  }
  for (int i = 0; i < 3 * point_count; ++i) w.displacement.push_back(awkward(k++));
  for (int i = 0; i < point_count; ++i) w.scalar.push_back(awkward(k++) - 0.5);
  for (size_t c = 0; c < w.cells.size(); ++c) {
    w.component.push_back(c % 2 == 0 ? int(c) - 7 : std::numeric_limits<int>::max() - int(c));
  }
  return w;
}

// What the root element and each DataArray declare for the encoding.
struct Declared {
  std::string version, header_type, format;
};
Declared declared(VtuEncoding encoding) {
  if (encoding == VtuEncoding::ascii) return {"0.1", "-", "ascii"};
  return {"1.0", "UInt64", "appended"};
}

// `records` is meshio's reading of the file written from `w`; every number must match.
void check_round_trip(const Written& w, const std::vector<Record>& records, VtuEncoding encoding) {
  const Declared d = declared(encoding);
  std::vector<Record> arrays;
  const Record* points = nullptr;
  std::vector<const Record*> cell_blocks;
  std::map<std::string, const Record*> point_data;
  std::vector<const Record*> component_blocks;
  bool saw_root = false;
  for (const Record& r : records) {
    if (r[0] == "root") {
      saw_root = true;
      EXPECT_EQ(r, (Record{"root", "VTKFile", "UnstructuredGrid", d.version, "LittleEndian",
                           d.header_type}));
    } else if (r[0] == "array") {
      arrays.push_back(r);
    } else if (r[0] == "points") {
      points = &r;
    } else if (r[0] == "cells") {
      cell_blocks.push_back(&r);
    } else if (r[0] == "point_data") {
      point_data[r.at(1)] = &r;
    } else if (r[0] == "cell_data") {
      ASSERT_EQ(r.at(1), "component");
      component_blocks.push_back(&r);
    }
  }
  ASSERT_TRUE(saw_root);

  // Declared types matter to ParaView even where meshio would convert silently.
  std::map<std::string, Record> array_by_name;
  for (const Record& r : arrays) array_by_name[r.at(1)] = r;
  EXPECT_EQ(array_by_name["Points"], (Record{"array", "Points", "Float64", d.format, "3"}));
  EXPECT_EQ(array_by_name["displacement"],
            (Record{"array", "displacement", "Float64", d.format, "3"}));
  EXPECT_EQ(array_by_name["pressure"], (Record{"array", "pressure", "Float64", d.format, "1"}));
  for (const auto& [name, r] : array_by_name) EXPECT_EQ(r.at(3), d.format) << name;
  EXPECT_EQ(array_by_name["component"].at(2), "Int32");
  EXPECT_TRUE(array_by_name["connectivity"].at(2) == "Int32" ||
              array_by_name["connectivity"].at(2) == "Int64");
  EXPECT_TRUE(array_by_name["offsets"].at(2) == "Int32" ||
              array_by_name["offsets"].at(2) == "Int64");
  EXPECT_EQ(array_by_name["types"].at(2), "UInt8");

  ASSERT_NE(points, nullptr);
  ASSERT_GE(points->size(), 4u);
  EXPECT_EQ(parse_integer(points->at(1)), static_cast<long long>(w.points.size()));
  EXPECT_EQ(points->at(2), "3");
  EXPECT_EQ(points->at(3), "float64");
  std::vector<double> coordinates;
  for (const Vec3& p : w.points) coordinates.insert(coordinates.end(), {p.x(), p.y(), p.z()});
  EXPECT_TRUE(same_bits(coordinates, {points->begin() + 4, points->end()}, "points"));

  // meshio groups consecutive cells of one type into a block; rebuild that grouping.
  struct Block {
    CellType type;
    std::vector<long long> nodes;
    std::vector<long long> component;
    size_t count = 0;
  };
  std::vector<Block> expected;
  for (size_t c = 0; c < w.cells.size(); ++c) {
    const Cell& cell = w.cells[c];
    if (expected.empty() || expected.back().type != cell.type)
      expected.push_back({cell.type, {}, {}, 0});
    for (const int n : cell.node_span()) expected.back().nodes.push_back(n);
    expected.back().component.push_back(w.component[c]);
    ++expected.back().count;
  }
  ASSERT_EQ(cell_blocks.size(), expected.size());
  ASSERT_EQ(component_blocks.size(), expected.size());
  for (size_t b = 0; b < expected.size(); ++b) {
    const Record& r = *cell_blocks[b];
    SCOPED_TRACE("cell block " + std::to_string(b));
    ASSERT_GE(r.size(), 4u);
    EXPECT_EQ(r[1], meshio_name(expected[b].type));
    EXPECT_EQ(parse_integer(r[2]), static_cast<long long>(expected[b].count));
    EXPECT_EQ(parse_integer(r[3]), node_count(expected[b].type));
    EXPECT_EQ(parse_integers({r.begin() + 4, r.end()}), expected[b].nodes);

    const Record& d = *component_blocks[b];
    ASSERT_GE(d.size(), 4u);
    EXPECT_EQ(parse_integer(d[2]), static_cast<long long>(expected[b].count));
    EXPECT_EQ(d[3], "int32");
    EXPECT_EQ(parse_integers({d.begin() + 4, d.end()}), expected[b].component);
  }

  ASSERT_EQ(point_data.size(), 2u);
  ASSERT_TRUE(point_data.count("displacement"));
  ASSERT_TRUE(point_data.count("pressure"));
  const Record& disp = *point_data["displacement"];
  ASSERT_GE(disp.size(), 5u);
  EXPECT_EQ(parse_integer(disp[2]), static_cast<long long>(w.points.size()));
  EXPECT_EQ(disp[3], "3");
  EXPECT_EQ(disp[4], "float64");
  EXPECT_TRUE(same_bits(w.displacement, {disp.begin() + 5, disp.end()}, "displacement"));
  const Record& pressure = *point_data["pressure"];
  ASSERT_GE(pressure.size(), 5u);
  EXPECT_EQ(parse_integer(pressure[2]), static_cast<long long>(w.points.size()));
  EXPECT_EQ(pressure[3], "1");
  EXPECT_TRUE(same_bits(w.scalar, {pressure.begin() + 5, pressure.end()}, "pressure"));
}

void write_data(const fs::path& file, const Written& w, VtuEncoding encoding = VtuEncoding::ascii) {
  const std::vector<PointField> point_fields = {{"displacement", 3, w.displacement},
                                                {"pressure", 1, w.scalar}};
  const std::vector<CellField> cell_fields = {{"component", w.component}};
  write_vtu(file, w.points, w.cells, point_fields, cell_fields, encoding);
}

constexpr VtuEncoding kEncodings[] = {VtuEncoding::ascii, VtuEncoding::binary};
const char* encoding_name(VtuEncoding encoding) {
  return encoding == VtuEncoding::ascii ? "ascii" : "binary";
}

// Separate nodes per cell, and a second hexa after the wedge so meshio splits 4 blocks.
Written mixed_volume() {
  return make_data({make_cell(CellType::hexa, {0, 1, 2, 3, 4, 5, 6, 7}),
                    make_cell(CellType::tetra, {8, 9, 10, 11}),
                    make_cell(CellType::wedge, {12, 13, 14, 15, 16, 17}),
                    make_cell(CellType::hexa, {25, 24, 23, 22, 21, 20, 19, 18})},
                   26);
}

TEST_F(VtkTest, VolumeMeshRoundTripsBitForBitThroughMeshio) {
  ASSERT_TRUE(meshio_available());
  const Written w = mixed_volume();
  const fs::path file = dir_ / "mixed.vtu";
  write_data(file, w);
  EXPECT_FALSE(fs::exists(dir_ / "mixed.vtu.tmp"));
  const std::string out = run_python(kVtuReader, {file});
  check_round_trip(w, split_records(out), VtuEncoding::ascii);
}

TEST_F(VtkTest, BinaryVolumeMeshRoundTripsBitForBitThroughMeshio) {
  ASSERT_TRUE(meshio_available());
  const Written w = mixed_volume();
  const fs::path file = dir_ / "mixed.vtu";
  write_data(file, w, VtuEncoding::binary);
  EXPECT_FALSE(fs::exists(dir_ / "mixed.vtu.tmp"));
  const std::string out = run_python(kVtuReader, {file});
  check_round_trip(w, split_records(out), VtuEncoding::binary);
}

TEST_F(VtkTest, SurfaceMeshRoundTripsBitForBitThroughMeshio) {
  ASSERT_TRUE(meshio_available());
  const Written w =
      make_data({make_cell(CellType::triangle, {0, 1, 2}), make_cell(CellType::triangle, {2, 1, 3}),
                 make_cell(CellType::quad, {1, 4, 5, 3})},
                6);
  for (const VtuEncoding encoding : kEncodings) {
    SCOPED_TRACE(encoding_name(encoding));
    const fs::path file = dir_ / "surface.vtu";
    write_data(file, w, encoding);
    const std::string out = run_python(kVtuReader, {file});
    check_round_trip(w, split_records(out), encoding);
  }
}

// VTK's own reader (what ParaView and scripts/render.py use): every array as VTK holds it.
constexpr const char* kVtkReader = R"PY(
import sys
from vtkmodules.vtkCommonCore import vtkCommand
from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
from vtkmodules.util.numpy_support import vtk_to_numpy

def floats(a):
    return " ".join(repr(float(x)) for x in vtk_to_numpy(a).ravel())

def ints(a):
    return " ".join(str(int(x)) for x in vtk_to_numpy(a).ravel())

reader = vtkXMLUnstructuredGridReader()
errors = []
reader.AddObserver(vtkCommand.ErrorEvent, lambda obj, event: errors.append(event))
reader.GetExecutive().AddObserver(vtkCommand.ErrorEvent, lambda obj, event: errors.append(event))
reader.SetFileName(sys.argv[1])
reader.Update()
g = reader.GetOutput()
print("errors", len(errors))
print("sizes", g.GetNumberOfPoints(), g.GetNumberOfCells())
print("points", floats(g.GetPoints().GetData()))
for data, kind in ((g.GetPointData(), "point_data"), (g.GetCellData(), "cell_data")):
    for i in range(data.GetNumberOfArrays()):
        a = data.GetArray(i)
        values = floats(a) if kind == "point_data" else ints(a)
        print(kind, a.GetName(), a.GetNumberOfComponents(), a.GetDataTypeAsString(), values)
print("connectivity", ints(g.GetCells().GetConnectivityArray()))
print("offsets", ints(g.GetCells().GetOffsetsArray()))
print("types", ints(g.GetCellTypesArray()))
)PY";

// `records` is VTK's reading of the file written from `w`; every number must match.
void check_vtk_reading(const Written& w, const std::vector<Record>& records) {
  std::map<std::string, Record> by_key;
  for (const Record& r : records)
    by_key[r[0] == "point_data" || r[0] == "cell_data" ? r.at(1) : r[0]] = r;
  EXPECT_EQ(by_key["errors"], (Record{"errors", "0"}));
  EXPECT_EQ(by_key["sizes"],
            (Record{"sizes", std::to_string(w.points.size()), std::to_string(w.cells.size())}));
  std::vector<double> coordinates;
  for (const Vec3& p : w.points) coordinates.insert(coordinates.end(), {p.x(), p.y(), p.z()});
  const Record& points = by_key["points"];
  ASSERT_FALSE(points.empty());
  EXPECT_TRUE(same_bits(coordinates, {points.begin() + 1, points.end()}, "points"));
  for (const auto& [name, values, components] :
       {std::tuple{"displacement", &w.displacement, "3"}, {"pressure", &w.scalar, "1"}}) {
    const Record& r = by_key[name];
    ASSERT_GE(r.size(), 4u) << name;
    EXPECT_EQ(r[2], components);
    EXPECT_EQ(r[3], "double");
    EXPECT_TRUE(same_bits(*values, {r.begin() + 4, r.end()}, name));
  }
  const Record& component = by_key["component"];
  ASSERT_GE(component.size(), 4u);
  EXPECT_EQ(component[3], "int");
  EXPECT_EQ(parse_integers({component.begin() + 4, component.end()}),
            std::vector<long long>(w.component.begin(), w.component.end()));
  std::vector<long long> connectivity, offsets = {0}, types;
  for (const Cell& cell : w.cells) {
    for (const int n : cell.node_span()) connectivity.push_back(n);
    offsets.push_back(static_cast<long long>(connectivity.size()));
    types.push_back(vtk_cell_type(cell.type));
  }
  const Record& c = by_key["connectivity"];
  const Record& o = by_key["offsets"];
  const Record& t = by_key["types"];
  ASSERT_FALSE(c.empty() || o.empty() || t.empty());
  EXPECT_EQ(parse_integers({c.begin() + 1, c.end()}), connectivity);
  EXPECT_EQ(parse_integers({o.begin() + 1, o.end()}), offsets);
  EXPECT_EQ(parse_integers({t.begin() + 1, t.end()}), types);
}

TEST_F(VtkTest, BinaryAndAsciiRoundTripBitForBitThroughVtk) {
  const CommandResult probe =
      run_command(std::string(kPython) + " -c 'import vtkmodules.vtkIOXML'", dir_ / "import.err");
  if (probe.status != 0)
    GTEST_SKIP() << "SKIPPED LOUDLY: " << kPython << " cannot import vtkmodules (python3-vtk9; "
                 << "make deps-demo installs it)";
  const Written w = mixed_volume();
  for (const VtuEncoding encoding : kEncodings) {
    SCOPED_TRACE(encoding_name(encoding));
    const fs::path file = dir_ / (std::string(encoding_name(encoding)) + ".vtu");
    write_data(file, w, encoding);
    check_vtk_reading(w, split_records(run_python(kVtkReader, {file})));
  }
}

TEST_F(VtkTest, PvdListsTimesAndEscapedFileNames) {
  const std::vector<PvdEntry> entries = {{0.0, "frames/frame_0000.vtu"},
                                         {1.0 / 3.0, "frames/frame_0001.vtu"},
                                         {1e-300, "a&b <c> \"d\" 'e'.vtu"},
                                         {2.5e7, "frame_9999.vtu"}};
  const fs::path file = dir_ / "series.pvd";
  write_pvd(file, entries);
  EXPECT_FALSE(fs::exists(dir_ / "series.pvd.tmp"));
  const std::string out = run_python(R"PY(
import sys
import xml.etree.ElementTree as ET
root = ET.parse(sys.argv[1]).getroot()
print("\t".join(["root", root.tag, root.get("type"), root.get("version")]))
for child in root:
    print("\t".join(["child", child.tag]))
for ds in root.iter("DataSet"):
    print("\t".join(["dataset", repr(float(ds.get("timestep"))), ds.get("group"),
                     ds.get("part"), ds.get("file")]))
)PY",
                                     {file});
  const std::vector<Record> records = split_records(out, '\t');
  ASSERT_EQ(records.size(), 2 + entries.size()) << out;
  EXPECT_EQ(records[0], (Record{"root", "VTKFile", "Collection", "0.1"}));
  EXPECT_EQ(records[1], (Record{"child", "Collection"}));
  for (size_t i = 0; i < entries.size(); ++i) {
    const Record& r = records[2 + i];
    SCOPED_TRACE("entry " + std::to_string(i));
    ASSERT_EQ(r.size(), 5u);
    EXPECT_EQ(r[0], "dataset");
    EXPECT_TRUE(same_bits({entries[i].time}, {r[1]}, "timestep"));
    EXPECT_EQ(r[2], "");
    EXPECT_EQ(r[3], "0");
    EXPECT_EQ(r[4], entries[i].file);
  }
}

TEST_F(VtkTest, PvdRejectsNonFiniteTime) {
  const std::vector<PvdEntry> entries = {{std::nan(""), "a.vtu"}};
  EXPECT_THROW(write_pvd(dir_ / "bad.pvd", entries), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir_ / "bad.pvd"));
}

TEST_F(VtkTest, AtomicWriteReplacesTheFileAndLeavesNoTemporary) {
  const fs::path file = dir_ / "out.txt";
  write_file_atomically(file, [](std::ostream& os) { os << "first\n"; });
  EXPECT_EQ(read_text(file), "first\n");
  write_file_atomically(file, [](std::ostream& os) { os << "second\n"; });
  EXPECT_EQ(read_text(file), "second\n");
  EXPECT_FALSE(fs::exists(dir_ / "out.txt.tmp"));
}

TEST_F(VtkTest, AtomicWriteWithFailingWriterLeavesNothing) {
  const fs::path file = dir_ / "fail.txt";
  EXPECT_THROW(write_file_atomically(file,
                                     [](std::ostream& os) {
                                       os << "partial";
                                       throw std::runtime_error("writer gave up");
                                     }),
               std::runtime_error);
  EXPECT_FALSE(fs::exists(file));
  EXPECT_FALSE(fs::exists(dir_ / "fail.txt.tmp"));
}

TEST_F(VtkTest, AtomicWriteWithFailingWriterKeepsThePreviousFile) {
  const fs::path file = dir_ / "keep.txt";
  write_file_atomically(file, [](std::ostream& os) { os << "good\n"; });
  EXPECT_THROW(
      write_file_atomically(file, [](std::ostream&) { throw std::logic_error("writer gave up"); }),
      std::logic_error);
  EXPECT_EQ(read_text(file), "good\n");
  EXPECT_FALSE(fs::exists(dir_ / "keep.txt.tmp"));
}

TEST_F(VtkTest, AtomicWriteIntoMissingDirectoryNamesPathAndReason) {
  const fs::path file = dir_ / "no_such_dir" / "frame_0001.vtu";
  try {
    write_file_atomically(file, [](std::ostream& os) { os << "x"; });
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(file.string()), std::string::npos) << message;
    EXPECT_NE(message.find("No such file or directory"), std::string::npos) << message;
  }
  EXPECT_FALSE(fs::exists(dir_ / "no_such_dir"));
}

TEST_F(VtkTest, NonFiniteValuesThrowAndLeaveNoFile) {
  Written w = make_data({make_cell(CellType::tetra, {0, 1, 2, 3})}, 4);
  const fs::path file = dir_ / "nan.vtu";

  Written bad_point = w;
  bad_point.points[2].y() = std::nan("");
  try {
    write_data(file, bad_point);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("point 2"), std::string::npos) << e.what();
  }

  Written bad_field = w;
  bad_field.displacement[7] = std::numeric_limits<double>::quiet_NaN();
  try {
    write_data(file, bad_field);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("displacement"), std::string::npos) << message;
    EXPECT_NE(message.find("index 7"), std::string::npos) << message;
  }

  Written infinite = w;
  infinite.scalar[1] = -std::numeric_limits<double>::infinity();
  EXPECT_THROW(write_data(file, infinite), std::invalid_argument);

  EXPECT_FALSE(fs::exists(file));
  EXPECT_FALSE(fs::exists(dir_ / "nan.vtu.tmp"));
}

// The binary writer validates as the text one does: bad input throws before the file is
// opened, so a frame written earlier under the same name stays as it was.
TEST_F(VtkTest, BinaryBadInputThrowsAndKeepsThePreviousFile) {
  const Written w = make_data({make_cell(CellType::tetra, {0, 1, 2, 3})}, 4);
  const fs::path file = dir_ / "frame.vtu";
  write_data(file, w, VtuEncoding::binary);
  const std::string good = read_text(file);

  Written bad_point = w;
  bad_point.points[2].y() = std::nan("");
  try {
    write_data(file, bad_point, VtuEncoding::binary);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("point 2"), std::string::npos) << e.what();
  }
  Written bad_field = w;
  bad_field.scalar[3] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(write_data(file, bad_field, VtuEncoding::binary), std::invalid_argument);
  std::vector<double> short_displacement(w.displacement.begin(), w.displacement.end() - 1);
  const std::vector<PointField> short_fields = {{"displacement", 3, short_displacement}};
  EXPECT_THROW(write_vtu(file, w.points, w.cells, short_fields, {}, VtuEncoding::binary),
               std::invalid_argument);
  std::vector<Cell> out_of_range = w.cells;
  out_of_range[0].nodes[3] = 4;
  EXPECT_THROW(write_vtu(file, w.points, out_of_range, {}, {}, VtuEncoding::binary),
               std::invalid_argument);
  EXPECT_THROW(write_points_vtu(file, bad_point.points, {}, VtuEncoding::binary),
               std::invalid_argument);

  EXPECT_TRUE(read_text(file) == good);
  EXPECT_FALSE(fs::exists(dir_ / "frame.vtu.tmp"));
  EXPECT_FALSE(fs::exists(dir_ / "missing" / "frame.vtu"));
  EXPECT_THROW(write_data(dir_ / "missing" / "frame.vtu", w, VtuEncoding::binary),
               std::runtime_error);
}

TEST_F(VtkTest, SizeMismatchThrowsNamingFieldAndSizes) {
  Written w = make_data({make_cell(CellType::tetra, {0, 1, 2, 3})}, 4);
  const fs::path file = dir_ / "size.vtu";

  std::vector<double> short_displacement(w.displacement.begin(), w.displacement.end() - 1);
  const std::vector<PointField> bad_points = {{"displacement", 3, short_displacement}};
  try {
    write_vtu(file, w.points, w.cells, bad_points, {});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("displacement"), std::string::npos) << message;
    EXPECT_NE(message.find("expected 12"), std::string::npos) << message;
    EXPECT_NE(message.find("has 11"), std::string::npos) << message;
  }

  const std::vector<int> two_components = {1, 2};
  const std::vector<CellField> bad_cells = {{"component", two_components}};
  try {
    write_vtu(file, w.points, w.cells, {}, bad_cells);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("component"), std::string::npos) << message;
    EXPECT_NE(message.find("expected 1"), std::string::npos) << message;
  }

  std::vector<Cell> out_of_range = w.cells;
  out_of_range[0].nodes[3] = 4;
  EXPECT_THROW(write_vtu(file, w.points, out_of_range, {}, {}), std::invalid_argument);

  EXPECT_FALSE(fs::exists(file));
}

}  // namespace
}  // namespace phymul

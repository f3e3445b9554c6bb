// VTK XML meshes (.vtu, .vtp) in each encoding, from hand-made files whose binary parts
// Python's base64 and zlib wrote; our own writer's files read back bit for bit; damaged files
// name the element's line and what is wrong.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <bit>
#include <cstring>

#include "phymul/mesh_io.hpp"
#include "phymul/vtk.hpp"
#include "support/process.hpp"

namespace phymul {
namespace {

// Two tetrahedra on five points (0.1, 0.2, 0.3 are not floats: a Float32 path would show).
const std::vector<Vec3> kPoints = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.1, 0.2, 0.3}};
const std::vector<std::array<int, 4>> kTetra = {{0, 1, 2, 3}, {1, 2, 3, 4}};

std::string array(std::string_view type, std::string_view name, std::string_view format,
                  std::string_view text, int components = 1) {
  return fmt::format(
      "<DataArray type=\"{}\" Name=\"{}\"{} format=\"{}\">{}</DataArray>", type, name,
      components > 1 ? fmt::format(" NumberOfComponents=\"{}\"", components) : "", format, text);
}

// Line 6: the points' DataArray; 9, 10, 11: connectivity, offsets, types.
std::string grid(std::string_view file_attributes, const std::string& points,
                 const std::string& connectivity, const std::string& offsets,
                 const std::string& types, std::string_view appended = "",
                 std::string_view counts = "NumberOfPoints=\"5\" NumberOfCells=\"2\"") {
  return fmt::format(R"(<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian"{}>
  <UnstructuredGrid>
    <Piece {}>
      <Points>
        {}
      </Points>
      <Cells>
        {}
        {}
        {}
      </Cells>
    </Piece>
  </UnstructuredGrid>{}
</VTKFile>
)",
                     file_attributes, counts, points, connectivity, offsets, types, appended);
}

std::string ascii_grid() {
  return grid("", array("Float64", "Points", "ascii", "0 0 0 1 0 0 0 1 0 0 0 1 0.1 0.2 0.3", 3),
              array("Int32", "connectivity", "ascii", "0 1 2 3\n 1 2 3 4"),
              array("Int32", "offsets", "ascii", "4 8"), array("UInt8", "types", "ascii", "10 10"));
}

void expect_two_tetrahedra(const Mesh& mesh) {
  ASSERT_EQ(mesh.points.size(), kPoints.size());
  for (size_t i = 0; i < kPoints.size(); ++i) EXPECT_EQ(mesh.points[i], kPoints[i]) << i;
  ASSERT_EQ(mesh.cells.size(), kTetra.size());
  for (size_t c = 0; c < kTetra.size(); ++c) {
    EXPECT_EQ(mesh.cells[c].type, CellType::tetra);
    const auto nodes = mesh.cells[c].node_span();
    EXPECT_EQ(std::vector<int>(nodes.begin(), nodes.end()),
              std::vector<int>(kTetra[c].begin(), kTetra[c].end()));
  }
}

TEST(VtkXml, AsciiArraysReadExactly) {
  expect_two_tetrahedra(parse_vtu_mesh(ascii_grid(), "a.vtu"));
  const Mesh mm = parse_vtu_mesh(ascii_grid(), "a.vtu", 1000.0);
  EXPECT_EQ(mm.points[4], Vec3(0.1, 0.2, 0.3) / 1000.0);
}

std::string one_stream_grid();

// VTK encodes the byte count and the data as two base64 chunks (a padded header); meshio
// encodes them as one.
TEST(VtkXml, InlineBase64WithTheHeaderInAChunkOfItsOwnOrNot) {
  const std::string vtk_style = grid(
      R"( header_type="UInt32")",
      array(
          "Float64", "Points", "binary",
          "eAAAAA==AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA8D8AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA"
          "AAADwPwAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAPA/mpmZmZmZuT+amZmZmZnJPzMzMzMzM9M/",
          3),
      array(
          "Int64", "connectivity", "binary",
          "QAAAAA==AAAAAAAAAAABAAAAAAAAAAIAAAAAAAAAAwAAAAAAAAABAAAAAAAAAAIAAAAAAAAAAwAAAAAAAAAEAAAA"
          "AAAAAA=="),
      array("Int64", "offsets", "binary", "EAAAAA==BAAAAAAAAAAIAAAAAAAAAA=="),
      array("UInt8", "types", "binary", "AgAAAA==Cgo="));
  expect_two_tetrahedra(parse_vtu_mesh(vtk_style, "vtk.vtu"));
  expect_two_tetrahedra(parse_vtu_mesh(one_stream_grid(), "meshio.vtu"));
}

std::string one_stream_grid() {
  return grid(
      R"( header_type="UInt64")",
      array("Float64", "Points", "binary",
            "eAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAADwPwAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA"
            "A\n"
            "          "
            "AAAAAAPA/AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA8D+amZmZmZm5P5qZmZmZmck/MzMzMzMz0z8=",
            3),
      array("Int64", "connectivity", "binary",
            "QAAAAAAAAAAAAAAAAAAAAAEAAAAAAAAAAgAAAAAAAAADAAAAAAAAAAEAAAAAAAAAAgAAAAAAAAADAAAAAAAAAA"
            "QAA"
            "AAAAAAA"),
      array("Int64", "offsets", "binary", "EAAAAAAAAAAEAAAAAAAAAAgAAAAAAAAA"),
      array("UInt8", "types", "binary", "AgAAAAAAAAAKCg=="));
}

// Points in four zlib blocks of 32 bytes (the last of 24), the rest in one each.
const std::string kZlibPoints64 =
    "BAAAAAAAAAAgAAAAAAAAABgAAAAAAAAADgAAAAAAAAAOAAAAAAAAAA4AAAAAAAAAFwAAAAAAAAA=eJxjYMAHPtgDAAI/"
    "ATB4nGNgwAc+2AMAAj8BMHicY2DABz7YAwACPwEweJybNRMEdtrPAtMn7Y3B4LI9AKF8C3M=";
const std::string kZlibConnectivity64 =
    "AQAAAAAAAABAAAAAAAAAAAAAAAAAAAAAFgAAAAAAAAA=eJxjYIAARijNBKWZCYizQGkAAfAAEQ==";
const std::string kZlibOffsets64 =
    "AQAAAAAAAAAQAAAAAAAAAAAAAAAAAAAADgAAAAAAAAA=eJxjYYAADigNAACQAA0=";
const std::string kZlibTypes64 = "AQAAAAAAAAACAAAAAAAAAAAAAAAAAAAACgAAAAAAAAA=eJzj4gIAACAAFQ==";

std::string zlib_inline_grid() {
  return grid(R"( header_type="UInt64" compressor="vtkZLibDataCompressor")",
              array("Float64", "Points", "binary", kZlibPoints64, 3),
              array("Int64", "connectivity", "binary", kZlibConnectivity64),
              array("Int64", "offsets", "binary", kZlibOffsets64),
              array("UInt8", "types", "binary", kZlibTypes64));
}

TEST(VtkXml, InlineZlibBlocksInflateToTheMesh) {
  expect_two_tetrahedra(parse_vtu_mesh(zlib_inline_grid(), "z.vtu"));
}

std::string appended_array(std::string_view type, std::string_view name, size_t offset,
                           int components = 1) {
  return fmt::format(
      "<DataArray type=\"{}\" Name=\"{}\"{} format=\"appended\" offset=\"{}\"/>", type, name,
      components > 1 ? fmt::format(" NumberOfComponents=\"{}\"", components) : "", offset);
}

// The four arrays appended one after the other, in `encoding`, each at its offset.
std::string appended_grid(std::string_view attributes, std::string_view encoding,
                          const std::array<std::string, 4>& blocks, std::string_view types) {
  std::array<size_t, 4> at{};
  for (size_t k = 1; k < 4; ++k) at[k] = at[k - 1] + blocks[k - 1].size();
  const std::string appended = fmt::format(
      "\n  <AppendedData encoding=\"{}\">\n   _{}{}{}{}\n  "
      "</AppendedData>",
      encoding, blocks[0], blocks[1], blocks[2], blocks[3]);
  return grid(attributes, appended_array("Float64", "Points", at[0], 3),
              appended_array(types, "connectivity", at[1]), appended_array(types, "offsets", at[2]),
              appended_array("UInt8", "types", at[3]), appended);
}

// A raw block: the byte count (UInt64) and the values, in either byte order.
template <class T>
std::string raw(const std::vector<T>& values, bool big) {
  std::string out;
  const auto put = [&](auto v) {
    char b[sizeof v];
    std::memcpy(b, &v, sizeof v);
    if (big) std::reverse(b, b + sizeof v);
    out.append(b, sizeof v);
  };
  put(std::uint64_t(values.size() * sizeof(T)));
  for (const T v : values) put(v);
  return out;
}

std::string byte_count(std::uint64_t n) {
  return raw(std::vector<char>{}, false)
      .replace(0, 8, std::string(reinterpret_cast<const char*>(&n), 8));
}

std::array<std::string, 4> raw_blocks(bool big) {
  std::vector<double> xyz;
  for (const Vec3& p : kPoints) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
  return {raw(xyz, big), raw(std::vector<std::int32_t>{0, 1, 2, 3, 1, 2, 3, 4}, big),
          raw(std::vector<std::int32_t>{4, 8}, big), raw(std::vector<std::uint8_t>{10, 10}, big)};
}

std::string unhex(std::string_view hex) {
  std::string out;
  for (size_t i = 0; i + 1 < hex.size(); i += 2)
    out += char(std::stoi(std::string(hex.substr(i, 2)), nullptr, 16));
  return out;
}

TEST(VtkXml, AppendedRawPlainBigEndianAndZlib) {
  for (const bool big : {false, true}) {
    std::string file = appended_grid(R"( header_type="UInt64")", "raw", raw_blocks(big), "Int32");
    if (big) file.replace(file.find("LittleEndian"), 12, "BigEndian");
    SCOPED_TRACE(big ? "big-endian" : "little-endian");
    expect_two_tetrahedra(parse_vtu_mesh(file, "raw.vtu"));
  }
  // UInt32 headers; the points in four blocks (Python's zlib.compress).
  const std::array<std::string, 4> zlib = {
      unhex(
          "0400000020000000180000000e0000000e0000000e00000017000000789c6360c0073ed80300023f0130789"
          "c6360c0073ed80300023f0130789c6360c0073ed80300023f0130789c9b35130476dacf02d327ed8dc1e0b2"
          "3d00a17c0b73"),
      unhex("01000000400000000000000016000000789c636080004628cd04a5990988b340690001f00011"),
      unhex("0100000010000000000000000e000000789c636180000e280d000090000d"),
      unhex("0100000002000000000000000a000000789ce3e2020000200015")};
  expect_two_tetrahedra(parse_vtu_mesh(
      appended_grid(R"( compressor="vtkZLibDataCompressor")", "raw", zlib, "Int64"), "z.vtu"));
}

TEST(VtkXml, AppendedBase64OffsetsCountCharacters) {
  const std::string file =
      appended_grid(R"( header_type="UInt64" compressor="vtkZLibDataCompressor")", "base64",
                    {kZlibPoints64, kZlibConnectivity64, kZlibOffsets64, kZlibTypes64}, "Int64");
  expect_two_tetrahedra(parse_vtu_mesh(file, "b.vtu"));
}

// A unit cube of six quads, every one facing inward: a closed surface of 12 triangles once
// split and turned.
const char* kCube = R"(<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
  <PolyData>
    <Piece NumberOfPoints="8" NumberOfVerts="0" NumberOfLines="0" NumberOfStrips="0" NumberOfPolys="6">
      <Points>
        <DataArray type="Float32" NumberOfComponents="3" format="ascii">
          0 0 0  1 0 0  1 1 0  0 1 0  0 0 1  1 0 1  1 1 1  0 1 1
        </DataArray>
      </Points>
      <Polys>
        <DataArray type="Int64" Name="connectivity" format="ascii">
          0 1 2 3  4 7 6 5  0 4 5 1  1 5 6 2  2 6 7 3  3 7 4 0
        </DataArray>
        <DataArray type="Int64" Name="offsets" format="ascii">4 8 12 16 20 24</DataArray>
      </Polys>
    </Piece>
  </PolyData>
</VTKFile>
)";

TEST(VtkXml, PolyDataPolygonsBecomeAnOutwardClosedSurface) {
  std::vector<std::string> notes;
  const Mesh mesh = parse_vtp_mesh(kCube, "cube.vtp", 1.0, &notes);
  ASSERT_EQ(mesh.points.size(), 8u);
  ASSERT_EQ(mesh.cells.size(), 12u);
  double six = 0.0;
  for (const Cell& c : mesh.cells) {
    ASSERT_EQ(c.type, CellType::triangle);
    const auto& x = mesh.points;
    six += x[size_t(c.nodes[0])].dot(x[size_t(c.nodes[1])].cross(x[size_t(c.nodes[2])]));
  }
  EXPECT_DOUBLE_EQ(six / 6.0, 1.0);  // outward, the unit cube
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("inside out"), std::string::npos) << notes[0];
}

TEST(VtkXml, OurWriterReadsBackBitForBit) {
  testing::TempDir dir;
  const std::vector<Vec3> points = {{0.1, 0.2, 0.3}, {1.0 / 3, 0, 0}, {0, 1e-300, 0},
                                    {0, 0, 7.77e5},  {1, 1, 1},       {-2, 0.5, 2}};
  std::vector<Cell> cells(2);
  cells[0].type = CellType::tetra, cells[0].nodes = {0, 1, 2, 3};
  cells[1].type = CellType::tetra, cells[1].nodes = {1, 2, 3, 4};
  cells.push_back(cells[0]);
  cells[2].nodes = {5, 1, 2, 3};
  const std::vector<double> field(points.size() * 3, 0.5);
  const std::vector<int> ids(cells.size(), 7);
  for (const VtuEncoding e : {VtuEncoding::ascii, VtuEncoding::binary}) {
    const auto path = dir.path() / "frame.vtu";
    write_vtu(path, points, cells, std::vector<PointField>{{"u", 3, field}},
              std::vector<CellField>{{"id", ids}}, e);
    const Mesh mesh = read_mesh_file(path);
    ASSERT_EQ(mesh.points.size(), points.size());
    for (size_t i = 0; i < points.size(); ++i) EXPECT_EQ(mesh.points[i], points[i]);
    ASSERT_EQ(mesh.cells.size(), cells.size());
    for (size_t c = 0; c < cells.size(); ++c) {
      const auto got = mesh.cells[c].node_span(), want = cells[c].node_span();
      EXPECT_TRUE(std::equal(got.begin(), got.end(), want.begin(), want.end())) << c;
    }
  }
}

// Each damaged file, and the place and message it must give.
TEST(VtkXml, DamagedFilesNameTheElementAndWhatIsWrong) {
  const auto fails = [](const std::string& text, const std::string& expected) {
    try {
      parse_vtu_mesh(text, "d.vtu");
      ADD_FAILURE() << "read without complaint; expected " << expected;
    } catch (const MeshFileError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos)
          << "expected: " << expected << "\n     got: " << e.what();
    }
  };
  const std::string good = ascii_grid();
  const auto edit = [&](std::string from, std::string to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  fails("# vtk DataFile Version 4.2\n", "d.vtu:1:1: expected a VTK XML file");
  fails("<VTKFile type=\"UnstructuredGrid\"><Unstr", "not well-formed XML");
  fails(edit("VTKFile type", "VTKFilf type"), "d.vtu:16:3: not well-formed XML: Start-end tags");
  fails(edit("UnstructuredGrid\" version", "PolyData\" version"),
        "d.vtu:2:1: this VTK XML file holds 'PolyData', a .vtu file holds UnstructuredGrid");
  fails(edit("0.1 0.2 0.3", "0.1 nan 0.3"),
        "d.vtu:6:9: point 4 has a non-finite y coordinate (nan)");
  fails(edit("0.1 0.2 0.3", "0.1 0.2"), "holds 14 values, expected 15");
  fails(edit("0.1 0.2 0.3", "0.1 0.2 0.3 4"), "d.vtu:6:123: DataArray 'Points' holds more than");
  fails(edit("0.1 0.2 0.3", "0.1 x 0.3"), "d.vtu:6:115: expected a number (Float64) in DataArray");
  fails(edit(">4 8<", ">4 3<"),
        "d.vtu:11:9: offsets must increase (offset 1 is 3, the one before 4)");
  fails(edit("1 2 3 4<", "1 2 3 5<"),
        "d.vtu:9:9: node 3 of cell 1 is 5, outside the 5 points [0, 4]");
  fails(edit("10 10", "10 24"), "d.vtu:12:9: cell 1 has VTK type 24, not supported");
  fails(edit("10 10", "10 5"), "cell 1 is a triangle (type 5) and needs 3 nodes, it lists 4");
  fails(edit("NumberOfCells=\"2\"", "NumberOfCells=\"99999999999\""),
        "d.vtu:4:5: NumberOfCells must be a whole number in [0, 268435455]");
  // Binary damage: a cut base64 group, bytes that are not base64, a bad zlib stream, a
  // count over the limit, and more points than the data holds.
  const std::string z = zlib_inline_grid();
  const auto zedit = [&](std::string from, std::string to) {
    std::string s = z;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  fails(zedit("eJzj4gIAACAAFQ==", "eJzj4gIAACA"),
        "d.vtu:11:9: DataArray 'types' (2 values of UInt8): zlib block 0 needs 10 bytes, at most 9 "
        "are left (truncated, or a wrong count?) (at byte 933 of the file)");
  std::string cut = one_stream_grid();
  cut.replace(cut.find("AgAAAAAAAAAKCg=="), 16, "AgAAAAAAAAAKCg=");
  fails(cut,
        "d.vtu:12:9: DataArray 'types' (2 values of UInt8): the base64 data ends inside a "
        "group of four characters, after 3 (truncated?)");
  fails(zedit("eJzj4gIAACAAFQ==", "eJzj4g*AACAAFQ=="), "byte 0x2a ('*') is not base64");
  fails(zedit("eJzj4gIAACAAFQ==", "eJzj4gIAACBAFQ=="),
        "DataArray 'types' (2 values of UInt8): zlib block 0 of 1 does not inflate to its 2 bytes");
  fails(zedit(R"(NumberOfPoints="5")", R"(NumberOfPoints="200000000")"),
        "d.vtu:6:9: DataArray 'Points' (600000000 values of Float64): its header says 120 bytes "
        "of data, the counts in the XML need 4800000000");
  fails(zedit(R"(NumberOfPoints="5")", R"(NumberOfPoints="6")"),
        "its header says 120 bytes of data, the counts in the XML need 144");
  fails(zedit(R"(compressor="vtkZLibDataCompressor")", R"(compressor="vtkLZ4DataCompressor")"),
        "d.vtu:2:1: compressor 'vtkLZ4DataCompressor' is not supported");
  // Raw appended: a byte count over the limit, one the data cannot hold, a file cut short.
  std::array<std::string, 4> blocks = raw_blocks(false);
  const std::string u64 = R"( header_type="UInt64")";
  blocks[0].replace(0, 8, byte_count(3ull << 30));
  fails(appended_grid(u64, "raw", blocks, "Int32"),
        "d.vtu:6:9: DataArray 'Points' (15 values of Float64): its header claims 3221225472 "
        "bytes, over the limit of 2^31 bytes (at byte ");
  blocks = raw_blocks(false);
  blocks[0].replace(0, 8, byte_count(1440));
  std::string six = appended_grid(u64, "raw", blocks, "Int32");
  six.replace(six.find(R"(NumberOfPoints="5")"), 18, R"(NumberOfPoints="60")");
  fails(six,
        "d.vtu:6:9: DataArray 'Points' (180 values of Float64): the array's data needs 1440 "
        "bytes, at most 189 are left (truncated, or a wrong count?)");
  const std::string whole = appended_grid(u64, "raw", raw_blocks(false), "Int32");
  fails(whole.substr(0, whole.find("   _") + 54),
        "d.vtu:6:9: DataArray 'Points' (15 values of Float64): the array's data needs 120 bytes, "
        "at most 42 are left");
}

void expect_same(const Mesh& got, const Mesh& want) {
  ASSERT_EQ(got.points.size(), want.points.size());
  for (size_t i = 0; i < want.points.size(); ++i) EXPECT_EQ(got.points[i], want.points[i]) << i;
  ASSERT_EQ(got.cells.size(), want.cells.size());
  for (size_t c = 0; c < want.cells.size(); ++c) {
    EXPECT_EQ(got.cells[c].type, want.cells[c].type);
    EXPECT_EQ(got.cells[c].nodes, want.cells[c].nodes) << c;
  }
}

// tests/data/vtkxml: what VTK and meshio wrote from a legacy .vtk grid and an OBJ surface.
TEST(VtkXml, FilesVtkAndMeshioWroteAreTheirOriginals) {
  const auto dir = testing::source_dir() / "tests/data/vtkxml";
  const Mesh block = read_mesh_file(testing::source_dir() / "examples/meshes/block.vtk");
  for (const char* name : {"block_zlib.vtu", "block_appended_base64.vtu"}) {
    SCOPED_TRACE(name);
    expect_same(read_mesh_file(dir / name), block);
  }
  const Mesh octahedron =
      read_mesh_file(testing::source_dir() / "tests/data/surfaces/octahedron.obj");
  for (const char* name : {"octahedron_appended_zlib.vtp", "octahedron_binary.vtp"}) {
    SCOPED_TRACE(name);
    expect_same(read_mesh_file(dir / name), octahedron);
  }
}

// Cut anywhere, a binary file is refused with a MeshFileError or reads whole.
TEST(VtkXml, EveryPrefixIsRefusedCleanlyOrReadsWhole) {
  for (const std::string& file :
       {zlib_inline_grid(),
        appended_grid(R"( header_type="UInt64")", "raw", raw_blocks(false), "Int32")}) {
    for (size_t n = 0; n < file.size(); n += 3) {
      try {
        const Mesh m = parse_vtu_mesh(file.substr(0, n), "cut.vtu");
        expect_two_tetrahedra(m);
      } catch (const MeshFileError& e) {
        EXPECT_EQ(e.file, "cut.vtu");
        EXPECT_FALSE(e.message.empty());
      }
    }
  }
}

}  // namespace
}  // namespace phymul

// STL surfaces, ASCII and binary (each triangle lists its three vertices: the copies are
// merged into shared points by finish_surface).
#include <fmt/format.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "io/mesh_text.hpp"
#include "phymul/mesh_io.hpp"

namespace phymul {
namespace {

using mesh_io::Lexer;
using mesh_io::Token;

constexpr size_t kHeader = 80, kRecord = 50;
constexpr std::uint32_t kMaxTriangles = 50'000'000;  // 2.5 GB of binary STL

void add_triangle(Mesh& mesh, const std::array<Vec3, 3>& corners) {
  Cell c;
  c.type = CellType::triangle;
  for (int k = 0; k < 3; ++k) {
    c.nodes[size_t(k)] = int(mesh.points.size());
    mesh.points.push_back(corners[size_t(k)]);
  }
  mesh.cells.push_back(c);
}

float little_endian_float(const char* at) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, at, 4);
  if constexpr (std::endian::native == std::endian::big) bits = __builtin_bswap32(bits);
  return std::bit_cast<float>(bits);
}

// 80-byte header, a triangle count, then 50 bytes per triangle: normal, three vertices
// (little-endian float32), two attribute bytes.
Mesh parse_binary(std::string_view bytes, const std::string& name, double divisor) {
  std::uint32_t count = 0;
  std::memcpy(&count, bytes.data() + kHeader, 4);
  if constexpr (std::endian::native == std::endian::big) count = __builtin_bswap32(count);
  if (count > kMaxTriangles)
    throw MeshFileError(
        name, 0, 0,
        fmt::format("binary STL: {} triangles is over the limit of {}", count, kMaxTriangles));
  Mesh mesh;
  mesh.points.reserve(size_t(count) * 3);
  mesh.cells.reserve(count);
  for (std::uint32_t t = 0; t < count; ++t) {
    const char* record = bytes.data() + kHeader + 4 + size_t(t) * kRecord;
    std::array<Vec3, 3> corners;
    for (int v = 0; v < 3; ++v)
      for (int a = 0; a < 3; ++a) {
        const double c = little_endian_float(record + 12 + 12 * v + 4 * a);
        if (!std::isfinite(c))
          throw MeshFileError(name, 0, 0,
                              fmt::format("binary STL: triangle {} has a non-finite coordinate "
                                          "({})",
                                          t, c));
        corners[size_t(v)][a] = c / divisor;
      }
    add_triangle(mesh, corners);
  }
  return mesh;
}

// solid NAME / facet normal n n n / outer loop / vertex x y z (3) / endloop / endfacet /
// endsolid NAME
Mesh parse_ascii(std::string_view text, const std::string& name, double divisor) {
  mesh_io::check_text(text, name);
  Lexer in(text, name);
  in.expect("solid", "at the start of an ASCII STL file");
  in.rest_of_line();  // the solid's name
  Mesh mesh;
  for (;;) {
    const Token word = in.next("'facet' or 'endsolid'");
    if (word.text == "endsolid") break;
    if (word.text != "facet")
      in.fail(word,
              fmt::format("expected 'facet' or 'endsolid', found '{}'", word.text.substr(0, 24)));
    in.expect("normal", "after 'facet'");
    for (int a = 0; a < 3; ++a) in.number("a normal component");
    in.expect("outer", "after the facet's normal");
    in.expect("loop", "after 'outer'");
    std::array<Vec3, 3> corners;
    for (auto& corner : corners) {
      in.expect("vertex", "in a facet's loop (a facet has three vertices)");
      for (int a = 0; a < 3; ++a) corner[a] = in.number("a vertex coordinate") / divisor;
    }
    in.expect("endloop", "after three vertices (a facet has three)");
    in.expect("endfacet", "after 'endloop'");
    add_triangle(mesh, corners);
  }
  return mesh;
}

}  // namespace

Mesh parse_stl_mesh(std::string_view bytes, const std::string& name, double divisor,
                    std::vector<std::string>* notes) {
  // Binary files may begin with "solid" too: the size that the count announces decides.
  if (bytes.size() >= kHeader + 4) {
    std::uint32_t count = 0;
    std::memcpy(&count, bytes.data() + kHeader, 4);
    if constexpr (std::endian::native == std::endian::big) count = __builtin_bswap32(count);
    if (bytes.size() == kHeader + 4 + size_t(count) * kRecord)
      return mesh_io::finish_surface(parse_binary(bytes, name, divisor), name, notes);
  }
  if (bytes.substr(0, 5) != "solid")
    throw MeshFileError(name, 0, 0,
                        fmt::format("neither ASCII STL (it would start with 'solid') nor binary "
                                    "STL ({} bytes, where 84 + 50 per announced triangle are "
                                    "expected): truncated?",
                                    bytes.size()));
  return mesh_io::finish_surface(parse_ascii(bytes, name, divisor), name, notes);
}

}  // namespace phymul

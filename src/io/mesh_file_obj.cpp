// Wavefront OBJ surfaces: `v x y z [w]` vertices and `f` polygons (indices 1-based or negative
// from the end, with optional /texture/normal parts), split into triangles from their first
// vertex. Other statements (normals, texture coordinates, groups, materials) are skipped.
#include <fmt/format.h>

#include <charconv>
#include <climits>

#include "io/mesh_text.hpp"
#include "phymul/mesh_io.hpp"

namespace phymul {
namespace {

using mesh_io::Lexer;
using mesh_io::Token;

// The vertex index of a face corner ("7", "7/2", "7//3", "-1"), 0-based.
int corner_index(const Lexer& in, const Token& t, size_t vertices) {
  const std::string_view head = t.text.substr(0, t.text.find('/'));
  long long index = 0;
  const auto [end, ec] = std::from_chars(head.data(), head.data() + head.size(), index);
  if (ec != std::errc{} || end != head.data() + head.size() || index == 0)
    in.fail(t, fmt::format("expected a vertex index (1-based, or negative from the end), found "
                           "'{}'",
                           t.text.substr(0, 24)));
  const long long resolved = index > 0 ? index - 1 : (long long)vertices + index;
  if (resolved < 0 || resolved >= (long long)vertices)
    in.fail(t, fmt::format("vertex {} does not exist ({} vertices so far)", index, vertices));
  return int(resolved);
}

void read_face(Lexer& in, const Token& word, Mesh& mesh) {
  const Token rest = in.rest_of_line();
  Lexer corners(rest.text, in.name());
  std::vector<int> polygon;
  while (!corners.at_end()) {
    const Token t = corners.next("a vertex index");
    const Token at{t.text, rest.line, rest.column + int(t.text.data() - rest.text.data())};
    polygon.push_back(corner_index(in, at, mesh.points.size()));
  }
  if (polygon.size() < 3)
    in.fail(word, fmt::format("a face needs 3 vertices or more, found {}", polygon.size()));
  for (size_t k = 1; k + 1 < polygon.size(); ++k) {
    Cell c;
    c.type = CellType::triangle;
    c.nodes[0] = polygon[0], c.nodes[1] = polygon[k], c.nodes[2] = polygon[k + 1];
    mesh.cells.push_back(c);
  }
}

}  // namespace

Mesh parse_obj_mesh(std::string_view text, const std::string& name, double divisor,
                    std::vector<std::string>* notes) {
  mesh_io::check_text(text, name);
  Lexer in(text, name);
  Mesh mesh;
  while (!in.at_end()) {
    const Token word = in.next("a statement");
    if (word.text == "v") {
      if (mesh.points.size() >= size_t(INT_MAX / 8))
        in.fail(word, "too many vertices for one mesh");
      Vec3 p;
      for (int a = 0; a < 3; ++a) p[a] = in.number("a vertex coordinate") / divisor;
      mesh.points.push_back(p);
      in.rest_of_line();  // an optional weight
    } else if (word.text == "f") {
      read_face(in, word, mesh);
    } else if (word.text == "l" || word.text == "p") {
      in.fail(word, "lines and points are not a surface: only faces ('f') make one");
    } else {
      in.rest_of_line();  // comments, normals, texture coordinates, groups, materials
    }
  }
  std::vector<char> used(mesh.points.size(), 0);
  for (const Cell& c : mesh.cells)
    for (int i : c.node_span()) used[size_t(i)] = 1;
  for (size_t i = 0; i < used.size(); ++i)
    if (!used[i])
      throw MeshFileError(name, 0, 0,
                          fmt::format("vertex {} (1-based) is used by no face; remove it", i + 1));
  return mesh_io::finish_surface(std::move(mesh), name, notes);
}

}  // namespace phymul

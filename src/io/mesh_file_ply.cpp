// PLY surfaces (ASCII, binary little- or big-endian): the `vertex` element's x, y, z and the
// `face` element's index list (vertex_indices or vertex_index), polygons split into triangles
// from their first vertex; other elements and properties are read past.
#include <fmt/format.h>

#include <bit>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstring>
#include <optional>

#include "io/mesh_text.hpp"
#include "phymul/mesh_io.hpp"

namespace phymul {
namespace {

using mesh_io::Lexer;
using mesh_io::Token;

enum class Format { ascii, little, big };

struct Type {
  int size = 0;  // bytes; 0: unknown
  bool floating = false, is_signed = false;
};

std::optional<Type> type_of(std::string_view name) {
  if (name == "char" || name == "int8") return Type{1, false, true};
  if (name == "uchar" || name == "uint8") return Type{1, false, false};
  if (name == "short" || name == "int16") return Type{2, false, true};
  if (name == "ushort" || name == "uint16") return Type{2, false, false};
  if (name == "int" || name == "int32") return Type{4, false, true};
  if (name == "uint" || name == "uint32") return Type{4, false, false};
  if (name == "float" || name == "float32") return Type{4, true, true};
  if (name == "double" || name == "float64") return Type{8, true, true};
  return std::nullopt;
}

struct Property {
  std::string name;
  Type type;
  std::optional<Type> count;  // a list: the type of its length
};

struct Element {
  std::string name;
  long long count = 0;
  std::vector<Property> properties;
};

struct Header {
  Format format = Format::ascii;
  std::vector<Element> elements;
  size_t body = 0;  // offset of the data
  int body_line = 0;
};

Type parse_type(Lexer& in, std::string_view what) {
  const Token t = in.next(what);
  const auto type = type_of(t.text);
  if (!type)
    in.fail(t, fmt::format("unknown PLY type '{}' (char, uchar, short, ushort, int, uint, float, "
                           "double or their int8 ... float64 names)",
                           t.text.substr(0, 24)));
  return *type;
}

Header parse_header(std::string_view bytes, const std::string& name) {
  const size_t end = bytes.find("end_header");
  if (!bytes.starts_with("ply") || end == std::string_view::npos)
    throw MeshFileError(name, 1, 1,
                        "not a PLY file: it must start with 'ply' and have an "
                        "'end_header' line");
  const std::string_view text = bytes.substr(0, end);
  mesh_io::check_text(text, name);
  Lexer in(text, name);
  in.expect("ply", "at the start of a PLY file");
  Header h;
  in.expect("format", "after 'ply'");
  const Token format = in.next("ascii, binary_little_endian or binary_big_endian");
  if (format.text == "ascii")
    h.format = Format::ascii;
  else if (format.text == "binary_little_endian")
    h.format = Format::little;
  else if (format.text == "binary_big_endian")
    h.format = Format::big;
  else
    in.fail(format, fmt::format("unknown PLY format '{}'", format.text.substr(0, 24)));
  in.rest_of_line();  // the version
  while (!in.at_end()) {
    const Token word = in.next("a header line");
    if (word.text == "comment" || word.text == "obj_info") {
      in.rest_of_line();
    } else if (word.text == "element") {
      Element e;
      e.name = std::string(in.next("an element name").text);
      e.count = in.integer("the element count", 0, INT_MAX / 8);
      h.elements.push_back(e);
    } else if (word.text == "property") {
      if (h.elements.empty()) in.fail(word, "a property before any element");
      Property p;
      const Token kind = in.next("a property type or 'list'");
      if (kind.text == "list") {
        p.count = parse_type(in, "the list's length type");
        p.type = parse_type(in, "the list's item type");
      } else {
        const auto type = type_of(kind.text);
        if (!type) in.fail(kind, fmt::format("unknown PLY type '{}'", kind.text.substr(0, 24)));
        p.type = *type;
      }
      p.name = std::string(in.next("a property name").text);
      h.elements.back().properties.push_back(p);
    } else {
      in.fail(word, fmt::format("unexpected '{}' in the PLY header", word.text.substr(0, 24)));
    }
  }
  h.body = bytes.find('\n', end);
  h.body = h.body == std::string_view::npos ? bytes.size() : h.body + 1;
  h.body_line = int(std::count(bytes.begin(), bytes.begin() + long(h.body), '\n')) + 1;
  return h;
}

// Reads numbers one after the other from the body, in the header's format.
class Body {
 public:
  // An ASCII body is read by a lexer over the whole file, past the header, so that its
  // messages give the file's own line numbers.
  Body(std::string_view bytes, const Header& h, const std::string& name)
      : h_(h), name_(name), bytes_(bytes.substr(h.body)), text_(bytes, name) {
    if (h.format != Format::ascii) return;
    mesh_io::check_text(bytes_, name);
    for (int line = 1; line < h.body_line; ++line) text_.rest_of_line();
  }
  double value(const Type& type, std::string_view what) {
    if (h_.format == Format::ascii) return text_.number(what);
    if (at_ + size_t(type.size) > bytes_.size())
      throw MeshFileError(name_, 0, 0,
                          fmt::format("the binary data ends early, reading {} (truncated?)", what));
    std::uint64_t raw = 0;
    unsigned char b[8];
    std::memcpy(b, bytes_.data() + at_, size_t(type.size));
    at_ += size_t(type.size);
    const bool little = h_.format == Format::little;
    for (int k = 0; k < type.size; ++k)
      raw |= std::uint64_t(b[little ? k : type.size - 1 - k]) << (8 * k);
    if (type.floating)
      return type.size == 4 ? double(std::bit_cast<float>(std::uint32_t(raw)))
                            : std::bit_cast<double>(raw);
    if (type.is_signed) {
      const int shift = 64 - 8 * type.size;
      return double(std::int64_t(raw << shift) >> shift);
    }
    return double(raw);
  }
  Lexer& text() { return text_; }

 private:
  const Header& h_;
  const std::string& name_;
  std::string_view bytes_;
  Lexer text_;
  size_t at_ = 0;
};

long long whole(double v, long long min, long long max, const std::string& name,
                std::string_view what) {
  if (!(v >= double(min) && v <= double(max)) || v != std::floor(v))
    throw MeshFileError(
        name, 0, 0,
        fmt::format("{} must be a whole number in [{}, {}], found {}", what, min, max, v));
  return (long long)v;
}

void read_element(Body& in, const Element& e, Mesh& mesh, double divisor, const std::string& name) {
  const bool vertex = e.name == "vertex", face = e.name == "face";
  for (long long k = 0; k < e.count; ++k) {
    Vec3 p = Vec3::Zero();
    for (const Property& prop : e.properties) {
      if (!prop.count) {
        const double v = in.value(prop.type, fmt::format("{} {} of {}", e.name, prop.name, k));
        if (vertex && prop.name.size() == 1 && prop.name[0] >= 'x' && prop.name[0] <= 'z') {
          if (!std::isfinite(v))
            throw MeshFileError(name, 0, 0,
                                fmt::format("vertex {} has a non-finite {}", k, prop.name));
          p[prop.name[0] - 'x'] = v / divisor;
        }
        continue;
      }
      const long long n = whole(in.value(*prop.count, "a list length"), 0, 1000, name,
                                fmt::format("the length of {} {}'s {}", e.name, k, prop.name));
      std::vector<int> polygon;
      for (long long i = 0; i < n; ++i)
        polygon.push_back(int(whole(in.value(prop.type, "a list item"), 0, INT_MAX / 8, name,
                                    fmt::format("{} {}'s index", e.name, k))));
      if (!face || (prop.name != "vertex_indices" && prop.name != "vertex_index")) continue;
      if (n < 3)
        throw MeshFileError(name, 0, 0, fmt::format("face {} has {} vertices (3 or more)", k, n));
      for (size_t i = 1; i + 1 < polygon.size(); ++i) {
        Cell c;
        c.type = CellType::triangle;
        c.nodes[0] = polygon[0], c.nodes[1] = polygon[i], c.nodes[2] = polygon[i + 1];
        mesh.cells.push_back(c);
      }
    }
    if (vertex) mesh.points.push_back(p);
  }
}

}  // namespace

Mesh parse_ply_mesh(std::string_view bytes, const std::string& name, double divisor,
                    std::vector<std::string>* notes) {
  const Header h = parse_header(bytes, name);
  Body body(bytes, h, name);
  Mesh mesh;
  bool has_vertex = false, has_face = false;
  for (const Element& e : h.elements) {
    if (e.name == "vertex") {
      has_vertex = true;
      for (const char* axis : {"x", "y", "z"})
        if (std::none_of(e.properties.begin(), e.properties.end(),
                         [&](const Property& p) { return p.name == axis && !p.count; }))
          throw MeshFileError(name, 0, 0, fmt::format("the vertex element has no '{}'", axis));
    }
    has_face |= e.name == "face";
    // Allocation guard: every item takes at least a byte (binary) or two (text).
    if (e.count > (long long)(bytes.size() - h.body))
      throw MeshFileError(name, 0, 0,
                          fmt::format("{} {} elements cannot fit in the {} bytes of data "
                                      "(truncated, or a wrong count?)",
                                      e.count, e.name, bytes.size() - h.body));
    read_element(body, e, mesh, divisor, name);
  }
  if (!has_vertex || !has_face)
    throw MeshFileError(name, 0, 0, "a PLY surface needs a 'vertex' and a 'face' element");
  for (const Cell& c : mesh.cells)
    for (int i : c.node_span())
      if (size_t(i) >= mesh.points.size())
        throw MeshFileError(
            name, 0, 0,
            fmt::format("a face uses vertex {}, of {} vertices", i, mesh.points.size()));
  std::vector<char> used(mesh.points.size(), 0);
  for (const Cell& c : mesh.cells)
    for (int i : c.node_span()) used[size_t(i)] = 1;
  for (size_t i = 0; i < used.size(); ++i)
    if (!used[i])
      throw MeshFileError(name, 0, 0, fmt::format("vertex {} is used by no face; remove it", i));
  return mesh_io::finish_surface(std::move(mesh), name, notes);
}

}  // namespace phymul

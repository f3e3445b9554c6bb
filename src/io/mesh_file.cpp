#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>

#include "io/mesh_text.hpp"
#include "mesh/surface_check.hpp"
#include "phymul/camitk.hpp"
#include "phymul/mesh_io.hpp"

namespace phymul {

MeshFileError::MeshFileError(std::string file_name, int line_number, int column_number,
                             std::string text)
    : std::runtime_error(
          line_number > 0 ? fmt::format("{}:{}:{}: {}", file_name, line_number, column_number, text)
                          : fmt::format("{}: {}", file_name, text)),
      file(std::move(file_name)),
      line(line_number),
      column(column_number),
      message(std::move(text)) {}

namespace mesh_io {

namespace {

// A token as quoted in messages: short, printable.
std::string quoted(std::string_view text) {
  if (text.size() > 24) return fmt::format("'{}...'", text.substr(0, 21));
  return fmt::format("'{}'", text);
}

}  // namespace

Lexer::Lexer(std::string_view text, std::string name) : text_(text), name_(std::move(name)) {}

void Lexer::skip_space() {
  while (at_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[at_]))) {
    if (text_[at_] == '\n') ++line_, line_start_ = at_ + 1;
    ++at_;
  }
}

bool Lexer::at_end() {
  skip_space();
  return at_ >= text_.size();
}

Token Lexer::next(std::string_view expected) {
  skip_space();
  if (at_ >= text_.size())
    fail_here(fmt::format("expected {}, found the end of the file (truncated?)", expected));
  const size_t start = at_;
  while (at_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[at_]))) ++at_;
  last_ = {text_.substr(start, at_ - start), line_, int(start - line_start_) + 1};
  return last_;
}

Token Lexer::expect(std::string_view word, std::string_view context) {
  const Token t = next(fmt::format("'{}' {}", word, context));
  if (t.text != word)
    fail(t, fmt::format("expected '{}' {}, found {}", word, context, quoted(t.text)));
  return t;
}

long long Lexer::integer(std::string_view what, long long min, long long max) {
  const Token t = next(what);
  long long value = 0;
  const auto [end, ec] = std::from_chars(t.text.data(), t.text.data() + t.text.size(), value);
  if (ec != std::errc{} || end != t.text.data() + t.text.size())
    fail(t, fmt::format("expected {} (a whole number), found {}", what, quoted(t.text)));
  if (value < min || value > max)
    fail(t, fmt::format("{} must be in [{}, {}], found {}", what, min, max, value));
  return value;
}

double Lexer::number(std::string_view what) {
  const Token t = next(what);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(t.text.data(), t.text.data() + t.text.size(), value);
  if (ec != std::errc{} || end != t.text.data() + t.text.size())
    fail(t, fmt::format("expected {} (a number), found {}", what, quoted(t.text)));
  if (!std::isfinite(value)) fail(t, fmt::format("{} must be finite, found {}", what, t.text));
  return value;
}

Token Lexer::rest_of_line() {
  while (at_ < text_.size() && (text_[at_] == ' ' || text_[at_] == '\t' || text_[at_] == '\r'))
    ++at_;
  const size_t start = at_;
  while (at_ < text_.size() && text_[at_] != '\n') ++at_;
  std::string_view s = text_.substr(start, at_ - start);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  last_ = {s, line_, int(start - line_start_) + 1};
  if (at_ < text_.size()) ++at_, ++line_, line_start_ = at_;  // the newline
  return last_;
}

void Lexer::check_fits(long long count, int min_chars, const Token& at,
                       std::string_view what) const {
  const long long left = (long long)(text_.size() - std::min(at_, text_.size()));
  if (count > left / min_chars)
    fail(at, fmt::format("{} {} cannot fit in the {} bytes left in the file (truncated, or a "
                         "wrong count?)",
                         count, what, left));
}

void Lexer::fail(const Token& at, const std::string& message) const {
  throw MeshFileError(name_, at.line, at.column, message);
}

void Lexer::fail_here(const std::string& message) const {
  throw MeshFileError(name_, line_, int(at_ - line_start_) + 1, message);
}

std::optional<CellType> cell_type_of_vtk(long long code) {
  switch (code) {
    case 5:
      return CellType::triangle;
    case 9:
      return CellType::quad;
    case 10:
      return CellType::tetra;
    case 12:
      return CellType::hexa;
    case 13:
      return CellType::wedge;
    default:
      return std::nullopt;
  }
}

void check_text(std::string_view text, const std::string& name) {
  int line = 1;
  size_t line_start = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c == '\n') {
      ++line, line_start = i + 1;
    } else if ((c < 0x20 && c != '\t' && c != '\r') || c == 0x7f) {
      throw MeshFileError(
          name, line, int(i - line_start) + 1,
          fmt::format("byte 0x{:02x} is not text: only ASCII mesh files are read (write the "
                      "file as ASCII; binary VTK and Gmsh files are not supported)",
                      c));
    }
  }
}

void check_points_used(const Mesh& mesh, const std::vector<Token>& point_at, const Lexer& lexer) {
  std::vector<char> used(mesh.points.size(), 0);
  for (const Cell& c : mesh.cells)
    for (int i : c.node_span()) used[size_t(i)] = 1;
  for (size_t i = 0; i < used.size(); ++i)
    if (!used[i])
      lexer.fail(point_at[i], fmt::format("point {} is used by no cell (a node without a cell "
                                          "has no mass); remove it from the mesh",
                                          i));
}

Mesh finish_surface(Mesh mesh, const std::string& name, std::vector<std::string>* notes) {
  if (mesh.cells.empty()) throw MeshFileError(name, 0, 0, "the file holds no triangle");
  const size_t merged = merge_duplicate_points(mesh);
  SurfaceCheck check = check_closed_surface(mesh);
  if (!check.problems.empty())
    throw MeshFileError(name, 0, 0,
                        fmt::format("{}{}", fmt::join(check.problems, "; "),
                                    check.problems.size() >= 10 ? " (and maybe more)" : ""));
  if (notes) {
    if (merged > 0)
      notes->push_back(fmt::format("{}: {} repeated vertices merged ({} points left)", name, merged,
                                   mesh.points.size()));
    for (const std::string& repair : check.repairs)
      notes->push_back(fmt::format("{}: {}", name, repair));
  }
  return mesh;
}

}  // namespace mesh_io

Mesh read_mesh_file(const std::filesystem::path& path, double divisor,
                    std::vector<std::string>* notes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MeshFileError(path.string(), 0, 0, "cannot open the mesh file");
  std::ostringstream s;
  s << in.rdbuf();
  const std::string text = s.str();
  const std::string ext = path.extension().string();
  if (ext == ".vtk") return parse_vtk_mesh(text, path.string(), divisor);
  if (ext == ".msh") return parse_gmsh_mesh(text, path.string(), divisor);
  if (ext == ".stl") return parse_stl_mesh(text, path.string(), divisor, notes);
  if (ext == ".obj") return parse_obj_mesh(text, path.string(), divisor, notes);
  if (ext == ".ply") return parse_ply_mesh(text, path.string(), divisor, notes);
  if (ext == ".vtu") return parse_vtu_mesh(text, path.string(), divisor);
  if (ext == ".vtp") return parse_vtp_mesh(text, path.string(), divisor, notes);
  if (ext == ".pml") {  // its only exclusive component with cells
    const PmlModel pml = parse_pml(text, path.string(), divisor);
    if (notes) notes->insert(notes->end(), pml.notes.begin(), pml.notes.end());
    return pml_object_mesh(pml, "", nullptr, path.string());
  }
  throw MeshFileError(
      path.string(), 0, 0,
      fmt::format("unknown mesh file type '{}': expected .vtk (legacy VTK ASCII), "
                  ".vtu (VTK XML unstructured grid), .msh (Gmsh ASCII 4.1 or "
                  "2.2), or a closed surface: .stl (ASCII or binary), .obj, .ply "
                  "(ASCII or binary), .vtp (VTK XML PolyData), or a CamiTK physical model .pml",
                  ext));
}

}  // namespace phymul

// Internal to the mesh file readers: a whitespace tokenizer that knows where each token is,
// and the checks both formats share.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "phymul/mesh_io.hpp"

namespace phymul::mesh_io {

struct Token {
  std::string_view text;
  int line = 0, column = 0;
};

class Lexer {
 public:
  Lexer(std::string_view text, std::string name);

  // The next token, or a MeshFileError "expected <expected>, found the end of the file".
  Token next(std::string_view expected);
  bool at_end();
  // The next token must be `word`.
  Token expect(std::string_view word, std::string_view context);
  // Whole number in [min, max].
  long long integer(std::string_view what, long long min, long long max);
  double number(std::string_view what);  // finite
  // What is left of the current line (after the last token), trimmed; the newline is
  // consumed.
  Token rest_of_line();
  // Guards allocations: `count` items of at least `min_chars` characters each must fit in
  // what is left of the file.
  void check_fits(long long count, int min_chars, const Token& at, std::string_view what) const;

  [[noreturn]] void fail(const Token& at, const std::string& message) const;
  [[noreturn]] void fail_here(const std::string& message) const;
  const std::string& name() const { return name_; }
  Token last() const { return last_; }

 private:
  void skip_space();

  std::string_view text_;
  std::string name_;
  size_t at_ = 0;
  int line_ = 1;
  size_t line_start_ = 0;
  Token last_{};
};

// VTK's cell type codes that the readers take (legacy VTK and VTK XML), and the list for
// messages.
std::optional<CellType> cell_type_of_vtk(long long code);
constexpr const char* kVtkCellTypes =
    "5 (triangle), 9 (quad), 10 (tetra), 12 (hexahedron) or 13 (wedge)";

// Refuses NUL and other control bytes (binary files, garbage) at their line and column.
void check_text(std::string_view text, const std::string& name);

// A surface read from STL, OBJ or PLY made ready for use: points with the same coordinates
// merged, then checked as a closed surface and its orientation repaired
// (mesh/surface_check.hpp). Its problems are a MeshFileError; what was repaired is appended
// to `notes` (when given) as sentences naming the file.
Mesh finish_surface(Mesh mesh, const std::string& name, std::vector<std::string>* notes);

// The finished mesh's checks that the readers share: every point used by some cell.
void check_points_used(const Mesh& mesh, const std::vector<Token>& point_at, const Lexer& lexer);

}  // namespace phymul::mesh_io

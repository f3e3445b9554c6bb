// Legacy VTK ASCII unstructured grids: the classic CELLS layout (versions up to 4.2, each cell
// as its node count then its nodes) and the 5.1 layout (OFFSETS and CONNECTIVITY arrays).
#include <fmt/format.h>

#include <climits>
#include <optional>

#include "io/mesh_text.hpp"
#include "phymul/mesh_io.hpp"

namespace phymul {
namespace {

using mesh_io::Lexer;
using mesh_io::Token;

constexpr long long kMaxCount = INT_MAX / 8;

struct RawCell {
  std::vector<long long> nodes;
  Token at;
};

void read_points(Lexer& in, Mesh& mesh, std::vector<Token>& point_at, double divisor) {
  const Token at = in.last();
  const long long n = in.integer("the number of points", 1, kMaxCount);
  const Token type = in.next("the point data type (float or double)");
  if (type.text != "float" && type.text != "double")
    in.fail(type,
            fmt::format("expected the point data type 'float' or 'double', found '{}'", type.text));
  in.check_fits(n, 6, at, "points");
  mesh.points.resize(size_t(n));
  point_at.resize(size_t(n));
  for (long long i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      mesh.points[size_t(i)][a] =
          in.number(fmt::format("coordinate {} of point {}", "xyz"[a], i)) / divisor;
      if (a == 0) point_at[size_t(i)] = in.last();
    }
}

// Classic layout: CELLS n size, then per cell its node count and nodes.
std::vector<RawCell> read_classic_cells(Lexer& in, long long n, long long size) {
  in.check_fits(size, 2, in.last(), "cell entries");
  in.check_fits(n, 4, in.last(), "cells");
  std::vector<RawCell> cells(static_cast<size_t>(n));
  long long read = 0;
  for (long long c = 0; c < n; ++c) {
    const long long k = in.integer(fmt::format("the node count of cell {}", c), 1, 8);
    cells[size_t(c)].at = in.last();
    for (long long j = 0; j < k; ++j)
      cells[size_t(c)].nodes.push_back(
          in.integer(fmt::format("node {} of cell {}", j, c), LLONG_MIN, LLONG_MAX));
    read += k + 1;
  }
  if (read != size)
    in.fail(in.last(),
            fmt::format("CELLS announced {} entries, its {} cells hold {}", size, n, read));
  return cells;
}

// 5.1 layout: CELLS offsets connectivity, OFFSETS type (offsets), CONNECTIVITY type (nodes).
std::vector<RawCell> read_offset_cells(Lexer& in, long long offsets, long long connectivity) {
  in.expect("OFFSETS", "(VTK 5.1 cells)");
  in.next("the offsets' data type");
  in.check_fits(offsets + connectivity, 2, in.last(), "cell entries");
  std::vector<long long> offset(static_cast<size_t>(offsets));
  for (long long i = 0; i < offsets; ++i) {
    offset[size_t(i)] = in.integer(fmt::format("offset {}", i), 0, connectivity);
    if (i == 0 && offset[0] != 0) in.fail(in.last(), "the first offset must be 0");
    if (i > 0 && offset[size_t(i)] - offset[size_t(i - 1)] < 1)
      in.fail(in.last(), fmt::format("offsets must increase (offset {} is {}, the one before {})",
                                     i, offset[size_t(i)], offset[size_t(i - 1)]));
    if (i > 0 && offset[size_t(i)] - offset[size_t(i - 1)] > 8)
      in.fail(in.last(), fmt::format("cell {} has {} nodes; supported cells have at most 8", i - 1,
                                     offset[size_t(i)] - offset[size_t(i - 1)]));
  }
  if (offset.back() != connectivity)
    in.fail(in.last(), fmt::format("the last offset is {}, CELLS announced {} connectivity entries",
                                   offset.back(), connectivity));
  in.expect("CONNECTIVITY", "(VTK 5.1 cells)");
  in.next("the connectivity's data type");
  std::vector<RawCell> cells(static_cast<size_t>(offsets - 1));
  for (long long c = 0; c + 1 < offsets; ++c) {
    RawCell& cell = cells[size_t(c)];
    for (long long j = offset[size_t(c)]; j < offset[size_t(c + 1)]; ++j) {
      cell.nodes.push_back(in.integer(fmt::format("node {} of cell {}", j - offset[size_t(c)], c),
                                      LLONG_MIN, LLONG_MAX));
      if (j == offset[size_t(c)]) cell.at = in.last();
    }
  }
  return cells;
}

void read_cell_types(Lexer& in, const std::vector<RawCell>& raw, Mesh& mesh) {
  in.expect("CELL_TYPES", "after the cells");
  const long long n = in.integer("the number of cell types", 0, kMaxCount);
  if (n != (long long)raw.size())
    in.fail(in.last(), fmt::format("CELL_TYPES lists {} cells, CELLS has {}", n, raw.size()));
  const long long points = (long long)mesh.points.size();
  std::optional<bool> volumetric;
  int first_kind = -1;
  mesh.cells.resize(raw.size());
  for (size_t c = 0; c < raw.size(); ++c) {
    const long long code = in.integer(fmt::format("the type of cell {}", c), LLONG_MIN, LLONG_MAX);
    const auto type = mesh_io::cell_type_of_vtk(code);
    if (!type)
      in.fail(in.last(), fmt::format("cell {} has VTK type {}, not supported: expected {}", c, code,
                                     mesh_io::kVtkCellTypes));
    const RawCell& r = raw[c];
    if ((long long)r.nodes.size() != node_count(*type))
      in.fail(r.at, fmt::format("cell {} is a {} (type {}) and needs {} nodes, it lists {}", c,
                                cell_type_name(*type), code, node_count(*type), r.nodes.size()));
    if (!volumetric) {
      volumetric = is_volumetric(*type);
      first_kind = int(c);
    } else if (*volumetric != is_volumetric(*type)) {
      in.fail(in.last(),
              fmt::format("cell {} is a {} ({} cell) but cell {} is a {}: a mesh has volume "
                          "cells or surface cells, not both",
                          c, cell_type_name(*type), *volumetric ? "surface" : "volume", first_kind,
                          cell_type_name(mesh.cells[size_t(first_kind)].type)));
    }
    Cell& cell = mesh.cells[c];
    cell.type = *type;
    for (size_t j = 0; j < r.nodes.size(); ++j) {
      if (r.nodes[j] < 0 || r.nodes[j] >= points)
        in.fail(r.at, fmt::format("node {} of cell {} is {}, outside the {} points [0, {}]", j, c,
                                  r.nodes[j], points, points - 1));
      cell.nodes[j] = int(r.nodes[j]);
    }
  }
}

}  // namespace

Mesh parse_vtk_mesh(std::string_view text, const std::string& name, double divisor) {
  mesh_io::check_text(text, name);
  Lexer in(text, name);
  const Token magic = in.rest_of_line();
  if (!magic.text.starts_with("# vtk DataFile Version"))
    in.fail(magic, fmt::format("expected '# vtk DataFile Version x.y' (a legacy VTK file), found "
                               "'{}'",
                               magic.text.substr(0, 40)));
  in.rest_of_line();  // the title
  const Token format = in.next("ASCII or BINARY");
  if (format.text == "BINARY")
    in.fail(format, "binary VTK files are not supported: write the file as ASCII");
  if (format.text != "ASCII")
    in.fail(format, fmt::format("expected ASCII, found '{}'", format.text.substr(0, 40)));
  in.expect("DATASET", "after ASCII");
  const Token kind = in.next("UNSTRUCTURED_GRID");
  if (kind.text != "UNSTRUCTURED_GRID")
    in.fail(kind, fmt::format("expected DATASET UNSTRUCTURED_GRID, found '{}' (only unstructured "
                              "grids hold cells)",
                              kind.text.substr(0, 40)));
  Mesh mesh;
  std::vector<Token> point_at;
  const Token key = in.next("POINTS");
  if (key.text != "POINTS")
    in.fail(key, fmt::format("expected POINTS, found '{}'", key.text.substr(0, 40)));
  read_points(in, mesh, point_at, divisor);
  in.expect("CELLS", "after the points");
  const long long a = in.integer("the number of cells", 0, kMaxCount);
  const long long b = in.integer("the size of the cell list", 0, kMaxCount);
  // Both layouts start "CELLS a b": the 5.1 one is followed by OFFSETS.
  const bool offsets = b >= 0 && a > 0 && [&] {
    Lexer peek = in;
    return !peek.at_end() && peek.next("").text == "OFFSETS";
  }();
  std::vector<RawCell> raw = offsets ? read_offset_cells(in, a, b) : read_classic_cells(in, a, b);
  if (raw.empty()) in.fail(in.last(), "the mesh has no cells");
  read_cell_types(in, raw, mesh);
  mesh_io::check_points_used(mesh, point_at, in);
  return mesh;  // POINT_DATA and CELL_DATA that follow are not needed
}

}  // namespace phymul

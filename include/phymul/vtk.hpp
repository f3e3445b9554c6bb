// VTK XML output: unstructured grids (.vtu) and time series (.pvd) that ParaView opens.
#pragma once

#include <filesystem>
#include <functional>
#include <iosfwd>
#include <span>
#include <string>
#include <vector>

#include "phymul/mesh.hpp"
#include "phymul/scene.hpp"

namespace phymul {

// Writes through `path`.tmp and renames it onto `path` once complete, so that a reader never
// sees a partial file under the final name. Throws std::runtime_error naming the path on
// any I/O failure (and removes the temporary).
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(std::ostream&)>& write);

struct PointField {
  std::string name;
  int components = 3;              // 1 or 3
  std::span<const double> values;  // size = points * components
};

struct CellField {
  std::string name;
  std::span<const int> values;  // size = cells
};

// (VtuEncoding, how a .vtu holds its numbers, is a scene setting: scene.hpp.)

// One VTK XML UnstructuredGrid file (full double precision), written atomically.
void write_vtu(const std::filesystem::path& path, std::span<const Vec3> points,
               std::span<const Cell> cells, std::span<const PointField> point_fields,
               std::span<const CellField> cell_fields, VtuEncoding encoding = VtuEncoding::ascii);

// Points alone (one VTK_VERTEX cell each), e.g. tracked beads, written atomically.
void write_points_vtu(const std::filesystem::path& path, std::span<const Vec3> points,
                      std::span<const PointField> point_fields,
                      VtuEncoding encoding = VtuEncoding::ascii);

struct PvdEntry {
  double time = 0.0;  // s
  std::string file;   // relative to the .pvd
};

// A ParaView collection listing the frames, written atomically.
void write_pvd(const std::filesystem::path& path, std::span<const PvdEntry> entries);

}  // namespace phymul

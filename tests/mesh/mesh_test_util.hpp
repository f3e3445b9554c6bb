// Helpers shared by the mesh tests.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <initializer_list>
#include <string>

#include "phymul/mesh.hpp"

namespace phymul::mesh_test {

inline Cell cell_of(CellType type, std::initializer_list<int> nodes) {
  Cell cell;
  cell.type = type;
  std::copy(nodes.begin(), nodes.end(), cell.nodes.begin());
  return cell;
}

inline ::testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "\"" << text << "\" does not contain \"" << part << "\"";
}

// The MeshError message of validate(), or "" when it accepts the mesh.
inline std::string validation_error(const Mesh& mesh) {
  try {
    validate(mesh);
  } catch (const MeshError& e) {
    return e.what();
  }
  return "";
}

inline double total_measure(const Mesh& mesh) {
  double sum = 0.0;
  for (const Cell& cell : mesh.cells) sum += cell_measure(mesh.points, cell);
  return sum;
}

}  // namespace phymul::mesh_test

// Helpers shared by the reference finite element tests: the standard load cases on boxes.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "phymul/fem.hpp"
#include "phymul/mesh.hpp"

namespace phymul::fem_test {

constexpr double kCubeSize = 0.08;     // m, the Truth Cube
constexpr double kCubeYoung = 14.9e3;  // Pa

inline ::testing::AssertionResult contains(const std::string& text, const std::string& part) {
  if (text.find(part) != std::string::npos) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "\"" << text << "\" does not contain \"" << part << "\"";
}

inline void prescribe(fem::Problem& p, const std::vector<int>& nodes, int axis, double value) {
  for (int n : nodes) p.prescribed.push_back({n, axis, value});
}

// Cube of side kCubeSize compressed by `strain` (of its height) between plates that hold
// without slip: bottom fixed, top moved down, no lateral motion on either.
inline fem::Problem bonded_compression(int cells, double strain, double poisson,
                                       CellType type = CellType::hexa, int load_steps = 10) {
  fem::Problem p;
  p.mesh = make_box(Vec3::Constant(kCubeSize), {cells, cells, cells}, type);
  p.material = {fem::Law::neo_hookean, kCubeYoung, poisson};
  p.load_steps = load_steps;
  for (int axis = 0; axis < 3; ++axis) {
    prescribe(p, p.mesh.node_sets["bottom"], axis, 0.0);
    prescribe(p, p.mesh.node_sets["top"], axis, axis == 2 ? -strain * kCubeSize : 0.0);
  }
  return p;
}

// Uniaxial stress with rollers: the bottom slides on z = const, the top is moved in z and
// slides too; one bottom corner is pinned in x and y and the corner beside it along y in x,
// which removes the rigid motions without restraining the lateral contraction. The mesh is a
// box of side `size` with its minimum corner at the origin, so that corner is node 0.
inline fem::Problem uniaxial_rollers(double size, int cells, double strain, fem::Material material,
                                     CellType type = CellType::hexa) {
  fem::Problem p;
  p.mesh = make_box(Vec3::Constant(size), {cells, cells, cells}, type, Vec3::Constant(size / 2));
  p.material = material;
  prescribe(p, p.mesh.node_sets["bottom"], 2, 0.0);
  prescribe(p, p.mesh.node_sets["top"], 2, strain * size);
  const int beside = cells * (cells + 1);  // (0, size, 0)
  p.prescribed.push_back({0, 0, 0.0});
  p.prescribed.push_back({0, 1, 0.0});
  p.prescribed.push_back({beside, 0, 0.0});
  return p;
}

// Total reaction of a node set along an axis (N).
inline double set_reaction(const fem::Result& r, const std::vector<int>& nodes, int axis) {
  double sum = 0.0;
  for (int n : nodes) sum += r.reaction[n][axis];
  return sum;
}

inline std::vector<Vec3> deformed_points(const Mesh& mesh, const fem::Result& r) {
  std::vector<Vec3> points = mesh.points;
  for (std::size_t n = 0; n < points.size(); ++n) points[n] += r.displacement[n];
  return points;
}

inline double total_volume(const std::vector<Vec3>& points, const Mesh& mesh) {
  double sum = 0.0;
  for (const Cell& cell : mesh.cells) sum += cell_measure(points, cell);
  return sum;
}

}  // namespace phymul::fem_test

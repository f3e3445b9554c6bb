// Small models shared by the tests.
#pragma once

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "phymul/model.hpp"

namespace phymul::testing {

// A vector of three draws from `dist`, z first, then y, then x: the order GCC evaluates
// random_vec3(d, rng)'s arguments in (right to left; clang goes left to right), so
// that each compiler tests the same data, the data the tests' bounds were set on.
template <class Distribution>
Vec3 random_vec3(Distribution& dist, std::mt19937& rng) {
  const double z = dist(rng), y = dist(rng), x = dist(rng);
  return Vec3(x, y, z);
}

// The largest distance (m) between the same node in two states.
inline double largest_gap(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  double gap = 0.0;
  for (size_t i = 0; i < a.size(); ++i) gap = std::max(gap, (a[i] - b[i]).norm());
  return gap;
}

// Scratch of one force pass over a plan: its energy per block.
inline std::vector<double> block_scratch(const ParallelPlan& plan) {
  return std::vector<double>(size_t(plan.blocks()), 0.0);
}

inline MaterialSpec material(double stiffness, FrameMode frame = FrameMode::polar,
                             bool reaction = true) {
  MaterialSpec m;
  m.stiffness = stiffness;
  m.density = 1000.0;
  m.frame = frame;
  m.reaction = reaction;
  return m;
}

inline MaterialSpec surface_material(double stiffness, double mass, FrameMode frame) {
  MaterialSpec m = material(stiffness, frame);
  m.density.reset();
  m.mass = mass;
  return m;
}

inline Model single_component(const Mesh& mesh, const MaterialSpec& m) {
  Model model;
  add_elastic_component(model, "body", mesh, m);
  finalize(model);
  return model;
}

// The mesh with every node moved by up to `fraction` of `spacing` along each axis (a fixed
// seed): no node is its neighbours' centroid any more, so each takes the polar pass's fit and
// rotation (forces/shape_memory_batch.hpp, is_centred), as an irregular mesh's nodes do.
inline Mesh jittered(Mesh mesh, double spacing, double fraction = 0.05) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> offset(-fraction * spacing, fraction * spacing);
  for (Vec3& p : mesh.points) p += random_vec3(offset, rng);
  return mesh;
}

inline Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double z = n(rng), y = n(rng), x = n(rng), w = n(rng);  // as random_vec3
  Eigen::Quaterniond q(w, x, y, z);
  return q.normalized().toRotationMatrix();
}

// A turn by `angle` (rad) about a random axis.
inline Eigen::Quaterniond small_turn(std::mt19937& rng, double angle) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Vec3 axis = random_vec3(n, rng).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis));
}

// The closed surface around the cells of `mesh` whose centroid satisfies `keep`, in the
// mesh's node ids (the model's, for a single-component model).
template <class Keep>
inline VolumeConstraint surface_of_cells(const Mesh& mesh, const std::string& name, Keep keep) {
  Mesh part{mesh.points, {}, {}};
  for (const Cell& cell : mesh.cells) {
    Vec3 centroid = Vec3::Zero();
    for (int i : cell.node_span()) centroid += mesh.points[i];
    if (keep(centroid / cell.node_span().size())) part.cells.push_back(cell);
  }
  VolumeConstraint v;
  v.component = name;
  v.triangles = boundary_triangles(part);
  for (const Triangle& t : v.triangles) v.nodes.insert(v.nodes.end(), t.begin(), t.end());
  std::sort(v.nodes.begin(), v.nodes.end());
  v.nodes.erase(std::unique(v.nodes.begin(), v.nodes.end()), v.nodes.end());
  v.target_volume = enclosed_volume(mesh.points, v.triangles);
  return v;
}

// A rigid obstacle of the given shape, fixed (tests add motion where they need it).
inline RigidObstacle obstacle(RigidObstacle::Shape kind, const Vec3& point, const Vec3& axis,
                              double radius = 0.0, double length = 0.0) {
  RigidObstacle o;
  o.shape = kind;
  o.point = point;
  o.axis = axis.normalized();
  o.radius = radius;
  o.length = length;
  return o;
}

}  // namespace phymul::testing

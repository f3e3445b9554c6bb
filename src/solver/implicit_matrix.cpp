#include "solver/implicit_matrix.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <span>
#include <utility>

#include "model/neighbourhood.hpp"

namespace phymul {
namespace {

Block3 cross_matrix(const Vec3& v) {
  Block3 m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

// One memory node's pull derivative: per node it reads, d(pull)/d(x_node).
using Jacobian = std::vector<std::pair<int, Block3>>;

// d(normal) / d(x_j) at rest, per neighbour (position in the row), of the neighbourhood's
// unnormalised normal N (model/neighbourhood.hpp): the ring's sum of e_r x e_r+1 (its
// centroid terms cancel), or a flat interior node's pair (x_a - g) x (x_b - g).
std::vector<Block3> normal_derivative(const ShapeMemory& m, int k, std::span<const Vec3> rest,
                                      const Vec3& g0) {
  const auto nb = m.neighbours.row(k);
  const int count = int(nb.size());
  std::vector<Block3> d(size_t(count), Block3::Zero());
  auto e = [&](int r) { return Vec3(rest[size_t(nb[size_t(r)])] - g0); };
  if (m.surface) {
    for (int r = 0; r < count; ++r)
      d[size_t(r)] = -cross_matrix(e((r + 1) % count) - e((r + count - 1) % count));
    return d;
  }
  const std::array<int, 2>& pair = frame_pair(m, k);
  const Block3 through_centroid = (cross_matrix(e(pair[1])) - cross_matrix(e(pair[0]))) / count;
  for (int r = 0; r < count; ++r) d[size_t(r)] = through_centroid;
  d[size_t(pair[0])] -= cross_matrix(e(pair[1]));
  d[size_t(pair[1])] += cross_matrix(e(pair[0]));
  return d;
}

// d(pull)/dx at rest for memory node k: through the centroid g, and in polar mode with the
// reaction (the forces then the energy's gradient) through the fit's rotation, whose turn is
// theta = (tr S - S)^-1 (sum r_j x dx_j + w n0 x dN / |N|) with S = sum r_j r_j^T (+ w n0 n0^T).
Jacobian pull_derivative(const ShapeMemory& m, int k, std::span<const Vec3> rest) {
  const auto nb = m.neighbours.row(k);
  const int count = int(nb.size());
  Jacobian j;
  j.emplace_back(m.nodes[size_t(k)], -Block3::Identity());
  for (int r : nb) j.emplace_back(r, Block3::Identity() / count);
  if (m.frame != FrameMode::polar || !m.reaction) return j;
  const Vec3 g0 = centroid(nb, rest);
  const Vec3 c = rest[size_t(m.nodes[size_t(k)])] - g0;
  Block3 S = Block3::Zero();
  for (int r : nb) S += (rest[size_t(r)] - g0) * (rest[size_t(r)] - g0).transpose();
  const double weight = normal_weight(m, k);
  Vec3 n0 = Vec3::Zero();
  double length = 0.0;
  if (weight > 0.0 && count > 2) {
    const Vec3 N = neighbourhood_normal(m, k, rest, g0);
    length = N.norm();
    n0 = N / length;
    S += weight * n0 * n0.transpose();
  }
  const Eigen::LLT<Block3> turn(S.trace() * Block3::Identity() - S);
  if (turn.info() != Eigen::Success) return j;  // collinear neighbours: no rotation to fit
  const Block3 through_turn = -cross_matrix(c) * turn.solve(Block3::Identity());
  std::vector<Block3> dn;
  if (length > 0.0) dn = normal_derivative(m, k, rest, g0);
  for (int r = 0; r < count; ++r) {
    Block3 b = cross_matrix(rest[size_t(nb[size_t(r)])] - g0);
    if (length > 0.0) b += weight / length * cross_matrix(n0) * dn[size_t(r)];
    j[size_t(r) + 1].second += through_turn * b;
  }
  return j;
}

// J over the blocks: a node's own block, or a free rigid body's two (d/d move = J,
// d/d turn = -J [a]x); nodes held on every axis drop out.
Jacobian over_blocks(const Model& model, const ImplicitBlocks& blocks, const Jacobian& j) {
  Jacobian out;
  for (const auto& [node, jn] : j) {
    if (const int b = blocks.of_node[size_t(node)]; b >= 0) {
      out.emplace_back(b, jn);
      continue;
    }
    const int body = model.rigid_body_of.empty() ? -1 : model.rigid_body_of[size_t(node)];
    if (body < 0 || blocks.of_body[size_t(body)][0] < 0) continue;
    out.emplace_back(blocks.of_body[size_t(body)][0], jn);
    out.emplace_back(blocks.of_body[size_t(body)][1], Block3(jn * blocks.arm[size_t(node)]));
  }
  return out;
}

// Adds K J^T J: the pairs of blocks at or below the diagonal.
void add_memory_node(const Model& model, const Jacobian& j, double stiffness,
                     const ImplicitBlocks& blocks, std::vector<BlockEntry>& out) {
  const Jacobian by_block = over_blocks(model, blocks, j);
  for (const auto& [bp, jp] : by_block)
    for (const auto& [bq, jq] : by_block)
      if (bp >= bq) out.push_back({bp, bq, stiffness * jp.transpose() * jq});
}

// Adds each explicit finite-element cell's stiffness (each_cell_stiffness): block pairs
// through over_blocks' maps, at or below the diagonal.
void add_explicit_fem_cells(const Model& model, const ImplicitBlocks& blocks,
                            std::span<const Eigen::Quaterniond> cell_rotation,
                            std::vector<BlockEntry>& out) {
  std::array<Jacobian, 8> t;  // per corner, its node's map to the blocks
  each_cell_stiffness(
      model, cell_rotation, [&](const ExplicitFem& fem, int e, std::span<const Block3> k) {
        const int n = fem.nodes_per_cell;
        const int* cell = fem.cells.data() + size_t(e * n);
        for (int a = 0; a < n; ++a)
          t[size_t(a)] = over_blocks(model, blocks, {{cell[a], Block3::Identity()}});
        for (int a = 0; a < n; ++a)
          for (int b = 0; b < n; ++b)
            for (const auto& [p, tp] : t[size_t(a)])
              for (const auto& [q, tq] : t[size_t(b)])
                if (p >= q) out.push_back({p, q, tp.transpose() * k[size_t(a * n + b)] * tq});
      });
}

// The held axes' rows and columns zero, their diagonal one: decoupled unknowns that stay 0.
void hold_axes(const ImplicitBlocks& blocks, std::vector<BlockEntry>& entries) {
  for (BlockEntry& e : entries) hold_block_axes(blocks.unknown, e.row, e.col, e.value);
  for (int b = 0; b < int(blocks.unknown.size()); ++b) {
    Block3 one = Block3::Zero();
    for (int a = 0; a < 3; ++a)
      if (blocks.unknown[size_t(b)][size_t(a)] < 0) one(a, a) = 1.0;
    entries.push_back({b, b, one});
  }
}

}  // namespace

std::vector<int> doubled_group_of_node(const Model& model) {
  std::vector<int> group(size_t(model.node_count()), -1);
  for (int g = 0; g < model.doubled.rows(); ++g)
    for (int i : model.doubled.row(g)) group[size_t(i)] = g;
  return group;
}

ImplicitBlocks number_blocks(const Model& model, const std::array<std::vector<int>, 3>& unknown,
                             const std::vector<ImplicitSystem::Body>& body) {
  const int n = model.node_count();
  const std::vector<int> group = doubled_group_of_node(model);
  std::vector<int> of_group(size_t(model.doubled.rows()), -1);
  ImplicitBlocks b;
  b.of_node.assign(size_t(n), -1);
  for (int i = 0; i < n; ++i) {
    const std::array<int, 3> u{unknown[0][size_t(i)], unknown[1][size_t(i)], unknown[2][size_t(i)]};
    if (u[0] < 0 && u[1] < 0 && u[2] < 0) continue;
    const int g = group[size_t(i)];
    if (g >= 0 && of_group[size_t(g)] >= 0) {
      b.of_node[size_t(i)] = of_group[size_t(g)];
      continue;
    }
    b.of_node[size_t(i)] = int(b.unknown.size());
    if (g >= 0) of_group[size_t(g)] = b.of_node[size_t(i)];
    b.unknown.push_back(u);
  }
  for (const ImplicitSystem::Body& r : body) {
    if (r.move[0] < 0) {
      b.of_body.push_back({-1, -1});
      continue;
    }
    b.of_body.push_back({int(b.unknown.size()), int(b.unknown.size()) + 1});
    b.unknown.push_back(r.move);
    b.unknown.push_back(r.turn);
  }
  b.arm.assign(size_t(n), Block3::Zero());
  for (const RigidBody& r : model.rigid_bodies)
    for (size_t k = 0; k < r.nodes.size(); ++k)
      b.arm[size_t(r.nodes[k])] =
          -r.rest_orientation.toRotationMatrix() * cross_matrix(r.offset[k]);
  return b;
}

std::vector<FibreSegment> fibre_segments(const Model& model) {
  std::vector<FibreSegment> segments;
  for (const FibreBundle& fibres : model.fibres)
    for (int p = 0; p < fibres.polylines.rows(); ++p) {
      const auto line = fibres.polylines.row(p);
      for (size_t k = 0; k + 1 < line.size(); ++k) {
        const int i = line[k], j = line[k + 1];
        const Vec3 d = model.rest_position[size_t(j)] - model.rest_position[size_t(i)];
        if (d.norm() > 0.0)
          segments.push_back({{i, j}, d.normalized(), fibres.stiffness, fibres.max_contraction});
      }
    }
  return segments;
}

Block3 fibre_stiffness(const FibreSegment& f) {
  const Block3 along = f.direction * f.direction.transpose();
  return 0.5 * f.stiffness * (along + f.max_contraction * (Block3::Identity() - along));
}

std::vector<std::pair<int, int>> coupled_pattern(const Model& model, const ImplicitBlocks& blocks) {
  std::vector<std::pair<int, int>> pairs;
  auto couple = [&](const Jacobian& j) {
    const Jacobian by_block = over_blocks(model, blocks, j);
    for (const auto& [p, jp] : by_block)
      for (const auto& [q, jq] : by_block)
        if (p > q) pairs.emplace_back(p, q);
  };
  Jacobian read;
  for (const ShapeMemory& m : model.shape_memory)
    for (int k = 0; k < int(m.nodes.size()); ++k) {
      read.assign(1, {m.nodes[size_t(k)], Block3::Identity()});
      for (int j : m.neighbours.row(k)) read.emplace_back(j, Block3::Identity());
      couple(read);
    }
  for (const FibreSegment& f : fibre_segments(model))
    couple({{f.nodes[0], Block3::Identity()}, {f.nodes[1], Block3::Identity()}});
  for (const ExplicitFem& fem : model.explicit_fem)
    for (size_t e = 0; e < fem.volume.size(); ++e) {
      read.clear();
      for (int a = 0; a < fem.nodes_per_cell; ++a)
        read.emplace_back(fem.cells[e * size_t(fem.nodes_per_cell) + size_t(a)],
                          Block3::Identity());
      couple(read);
    }
  for (int b = 0; b < int(blocks.of_body.size()); ++b)
    if (blocks.of_body[size_t(b)][0] >= 0)
      pairs.emplace_back(blocks.of_body[size_t(b)][1], blocks.of_body[size_t(b)][0]);
  return pairs;
}

bool cells_on_their_blocks(const Model& model, const ImplicitBlocks& blocks) {
  for (const ExplicitFem& fem : model.explicit_fem)
    for (int i : fem.cells) {
      const int body = model.rigid_body_of.empty() ? -1 : model.rigid_body_of[size_t(i)];
      if (blocks.of_node[size_t(i)] < 0 && body >= 0 && blocks.of_body[size_t(body)][0] >= 0)
        return false;
    }
  return true;
}

std::vector<BlockEntry> coupled_matrix(const Model& model, const ImplicitBlocks& blocks, double h,
                                       std::span<const Eigen::Quaterniond> cell_rotation,
                                       bool cells) {
  std::vector<BlockEntry> entries;
  const double per_mass = 1.0 / (h * h) + model.damping / h;
  for (int i = 0; i < model.node_count(); ++i)
    if (const int b = blocks.of_node[size_t(i)]; b >= 0)
      entries.push_back({b, b, model.inertia[size_t(i)] * per_mass * Block3::Identity()});
  for (int b = 0; b < int(blocks.of_body.size()); ++b) {
    const auto [move, turn] = blocks.of_body[size_t(b)];
    if (move < 0) continue;
    const RigidBody& r = model.rigid_bodies[size_t(b)];
    entries.push_back({move, move, r.mass * per_mass * Block3::Identity()});
    entries.push_back({turn, turn, per_mass * Block3(r.inertia.asDiagonal())});
  }
  for (const ShapeMemory& m : model.shape_memory)
    for (int k = 0; k < int(m.nodes.size()); ++k)
      add_memory_node(model, pull_derivative(m, k, model.rest_position), m.stiffness, blocks,
                      entries);
  // A spring support is linear: its stiffness is exact.
  for (const SpringSupport& springs : model.springs)
    for (int i : springs.nodes)
      add_memory_node(model, {{i, Block3::Identity()}}, springs.stiffness, blocks, entries);
  for (const FibreSegment& f : fibre_segments(model)) {
    const Block3 k = fibre_stiffness(f);  // k = J^T J for J = k^(1/2): one block a node
    const Eigen::LLT<Block3> root(k);
    add_memory_node(model, {{f.nodes[0], root.matrixU()}, {f.nodes[1], -Block3(root.matrixU())}},
                    1.0, blocks, entries);
  }
  if (cells) add_explicit_fem_cells(model, blocks, cell_rotation, entries);
  hold_axes(blocks, entries);
  return entries;
}

}  // namespace phymul

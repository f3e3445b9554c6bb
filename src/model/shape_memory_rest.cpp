#include "model/shape_memory_rest.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "model/neighbourhood.hpp"
#include "model/parallel_plan.hpp"
#include "model/row_subset.hpp"

namespace phymul {
namespace {

// Most orthogonal pair of neighbour directions (largest |sin|), and that sine.
std::pair<std::array<int, 2>, double> best_pair(std::span<const int> nb, std::span<const Vec3> p,
                                                const Vec3& g) {
  std::array<int, 2> best{0, 1};
  double best_sin = -1.0;
  for (int a = 0; a < int(nb.size()); ++a) {
    const Vec3 da = (p[nb[a]] - g).normalized();
    for (int b = a + 1; b < int(nb.size()); ++b) {
      const double s = da.cross((p[nb[b]] - g).normalized()).norm();
      if (s > best_sin + 1e-12) best_sin = s, best = {a, b};
    }
  }
  return {best, best_sin};
}

Eigen::Matrix3d covariance_about(std::span<const int> nb, std::span<const Vec3> p, const Vec3& g) {
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (int j : nb) C += (p[j] - g) * (p[j] - g).transpose();
  return C;
}

}  // namespace

ShapeMemory build_shape_memory(const std::string& component, const Mesh& mesh, int first_node,
                               const MaterialSpec& material, std::span<const Vec3> rest) {
  ShapeMemory m;
  m.component = component;
  m.stiffness = material.stiffness.value_or(0.0);  // > 0 for elastic parts (add_elastic_component)
  m.frame = material.frame;
  m.reaction = material.reaction;
  m.surface = !mesh.volumetric();
  const Adjacency local = m.surface ? ordered_one_rings(mesh) : edge_neighbours(mesh);
  int rows = 0;  // exact sizes: arrays grown by doubling would keep up to twice their bytes
  for (int i = 0; i < local.rows(); ++i) rows += local.row(i).empty() ? 0 : 1;
  m.nodes.reserve(size_t(rows));
  m.neighbours.offsets.reserve(size_t(rows) + 1);
  m.neighbours.indices.reserve(local.indices.size());
  for (int i = 0; i < local.rows(); ++i) {
    if (local.row(i).empty()) continue;  // a node no cell uses carries no memory
    m.nodes.push_back(first_node + i);
    for (int j : local.row(i)) m.neighbours.indices.push_back(first_node + j);
    m.neighbours.offsets.push_back(int(m.neighbours.indices.size()));
  }
  memorise_rest_shape(m, rest);
  return m;
}

void memorise_rest_shape(ShapeMemory& m, std::span<const Vec3> rest) {
  const int count = int(m.nodes.size());
  // Normal weights and frame pairs are kept for the nodes that read them only
  // (ShapeMemory::framed).
  std::vector<char> framed(m.nodes.size(), 0);
  m.normal_weight.clear();
  m.frame_pair.clear();
  for (int k = 0; k < count; ++k) {
    const auto nb = m.neighbours.row(k);
    const Vec3 G0 = centroid(nb, rest);
    const auto [pair, sine] = nb.size() >= 2 ? best_pair(nb, rest, G0)
                                             : std::pair<std::array<int, 2>, double>{{0, 0}, 0.0};
    if (sine < 1e-3)
      throw std::invalid_argument(fmt::format(
          "component '{}': node {} has {} neighbour(s), all on one line; local shape memory "
          "needs at least three neighbours not on a line",
          m.component, m.nodes[k], nb.size()));
    const Eigen::Matrix3d C = covariance_about(nb, rest, G0);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
    const bool flat = eig.eigenvalues()(0) < 1e-2 * eig.eigenvalues()(2);
    const double weight = m.surface || flat ? C.trace() / double(nb.size()) : 0.0;
    framed[size_t(k)] = m.frame == FrameMode::frame ? !m.surface : weight > 0.0;
    if (!framed[size_t(k)]) continue;
    m.normal_weight.push_back(weight);
    if (!m.surface) m.frame_pair.push_back(pair);
  }
  m.normal_weight.shrink_to_fit();
  m.frame_pair.shrink_to_fit();
  m.framed = make_row_subset(framed);
  // In polar mode the rest frame is the identity by construction (A0 is symmetric), and
  // fit_neighbourhood recomputes c.
  m.rest_offset.clear();
  if (m.frame == FrameMode::frame) {
    m.rest_offset.reserve(m.nodes.size());
    for (int k = 0; k < count; ++k) {
      const Vec3 G0 = centroid(m.neighbours.row(k), rest);
      const Eigen::Matrix3d R0 = local_frame(m, k, rest, G0);
      m.rest_offset.push_back(R0.transpose() * (rest[m.nodes[k]] - G0));
    }
  }
  m.plan = plan_blocks(int(m.nodes.size()), [&m](int k, const std::function<void(int)>& visit) {
    visit(m.nodes[k]);  // a node's pass writes it and its neighbours
    for (int j : m.neighbours.row(k)) visit(j);
  });
  plan_polar_batches(m, rest);
}

bool is_centred(const ShapeMemory& m, int k, std::span<const Vec3> rest) {
  const auto row = m.neighbours.row(k);
  if (row.empty()) return false;
  const Vec3& X = rest[m.nodes[k]];
  Vec3 sum = Vec3::Zero();
  double longest = 0.0;
  for (int j : row) {
    sum += rest[j] - X;
    longest = std::max(longest, (rest[j] - X).norm());
  }
  return (sum / double(row.size())).norm() <=
         64.0 * std::numeric_limits<double>::epsilon() * longest;
}

namespace {

// The offsets of global id at which every centred node (m's centred ranges) finds its six
// neighbours, if they are the same for all.
std::optional<std::array<int, 6>> centred_stencil(const ShapeMemory& m) {
  std::optional<std::array<int, 6>> stencil;
  for (int b = 0; b < m.plan.blocks(); ++b)
    for (int p = m.centred_start[b]; p < m.plan.block_start[b + 1]; ++p) {
      const int k = m.batch_order[size_t(p)];
      const auto row = m.neighbours.row(k);
      if (row.size() != 6) return std::nullopt;
      std::array<int, 6> offsets;
      for (int j = 0; j < 6; ++j) offsets[size_t(j)] = row[size_t(j)] - m.nodes[k];
      std::sort(offsets.begin(), offsets.end());
      if (stencil && *stencil != offsets) return std::nullopt;
      stencil = offsets;
    }
  return stencil;
}

}  // namespace

bool polar_batches_planned(const ShapeMemory& m) {
  return int(m.batched_end.size()) == m.plan.blocks() &&
         int(m.centred_start.size()) == m.plan.blocks() && m.batch_order.size() == m.nodes.size();
}

void plan_polar_batches(ShapeMemory& m, std::span<const Vec3> rest) {
  m.batch_order.clear();
  m.batched_end.clear();
  m.centred_start.clear();
  if (m.frame != FrameMode::polar) {
    m.batch_order.shrink_to_fit();
    m.batched_end.shrink_to_fit();
    m.centred_start.shrink_to_fit();
    m.centred_on_stencil = false;
    return;
  }
  m.batch_order.reserve(m.nodes.size());
  m.batched_end.reserve(size_t(m.plan.blocks()));
  m.centred_start.reserve(size_t(m.plan.blocks()));
  std::vector<int> lanes, others, centred;
  // Lanes share their neighbour count and whether they carry the normal pair (framed): the
  // kernel reads the normal pair of every lane when its first lane has one (fit_batch).
  auto count = [&m](int k) {
    return 2 * int(m.neighbours.row(k).size()) + (m.framed.find(k) >= 0 ? 1 : 0);
  };
  for (int b = 0; b < m.plan.blocks(); ++b) {
    lanes.clear();
    others.clear();
    centred.clear();
    for (int k = m.plan.block_start[b]; k < m.plan.block_start[b + 1]; ++k) {
      const bool batchable = int(m.neighbours.row(k).size()) <= kShapeMemoryMaxBatchedNeighbours;
      (is_centred(m, k, rest) ? centred : batchable ? lanes : others).push_back(k);
    }
    std::stable_sort(lanes.begin(), lanes.end(), [&](int a, int c) { return count(a) < count(c); });
    for (size_t s = 0; s < lanes.size();) {
      size_t e = s;
      while (e < lanes.size() && count(lanes[e]) == count(lanes[s])) ++e;
      const size_t full = s + (e - s) / kShapeMemoryLanes * kShapeMemoryLanes;
      m.batch_order.insert(m.batch_order.end(), lanes.begin() + long(s),
                           lanes.begin() + long(full));
      others.insert(others.end(), lanes.begin() + long(full), lanes.begin() + long(e));
      s = e;
    }
    m.batched_end.push_back(int(m.batch_order.size()));
    std::sort(others.begin(), others.end());
    m.batch_order.insert(m.batch_order.end(), others.begin(), others.end());
    m.centred_start.push_back(int(m.batch_order.size()));
    m.batch_order.insert(m.batch_order.end(), centred.begin(), centred.end());
  }
  const auto stencil = centred_stencil(m);
  m.centred_on_stencil = stencil.has_value();
  m.centred_stencil = stencil.value_or(std::array<int, 6>{});
}

}  // namespace phymul

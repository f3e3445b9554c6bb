// Backward Euler by local/global iterations (projective dynamics, Bouaziz et al. 2014), for
// the shape memory of DESIGN 2.1. For fixed rotations the energy sum K/2 |A_k x - R_k c_k|^2
// (A_k x = x_i - mean of its neighbours) is quadratic with Hessian L = sum K A_k^T A_k, so
//   P = M (1/h^2 + c/h) + L
// is constant for a dt, and factorised once. Each iteration evaluates the full forces (the
// local step: every node's polar fit, and the forces through the rotation's derivative the
// fit adds), forms the backward-Euler residual
//   r(x) = f(x) + M/h^2 (x0 + h v0 - x) - c M (x - x0)/h
// and moves x by P^-1 r. Where the rotations minimise their terms this is the projective
// global step exactly; here the rotation-derivative forces stay in r, so the fixed point,
// r = 0, is this model's backward-Euler step and not a nearby model's. Volume constraints
// enter each solve linearised (a Schur complement on their gradients), then are projected
// exactly; doubled nodes share one unknown; held axes are eliminated. Rigid obstacles are
// projected after each solve like the volumes; on a node touching one, the residual's push
// into it is the obstacle's reaction, kept out of the solve and of the convergence test.
#include "solver/implicit_step.hpp"

#include <Eigen/OrderingMethods>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "constraints/constraints.hpp"
#include "constraints/contact.hpp"
#include "constraints/deformable_contact.hpp"
#include "constraints/doubled.hpp"
#include "forces/explicit_fem.hpp"
#include "model/explicit_fem_cells.hpp"
#include "model/workspace.hpp"
#include "phymul/forces.hpp"
#include "solver/implicit_anderson.hpp"
#include "solver/implicit_bodies.hpp"
#include "solver/implicit_contacts.hpp"
#include "solver/implicit_friction.hpp"
#include "solver/implicit_matrix.hpp"
#include "solver/implicit_needles.hpp"
#include "solver/implicit_pairs.hpp"
#include "solver/implicit_solve.hpp"

namespace phymul {
namespace {

// Most volume constraints a solve takes together (its Schur complement is on the stack).
constexpr int kMaxVolumes = kMaxJointVolumes;
using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxVolumes, kMaxVolumes>;
using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxVolumes, 1>;

// A step whose residual grew takes this share of its corrections from then on (down to
// kShortestStep): the iteration's matrix leaves out the Hessian's parts from the rotations'
// derivative and the volumes' curvature, and where those exceed it (a soft mode of the
// shape memory) the full correction overshoots.
constexpr double kShrink = 0.7, kShortestStep = 1.0 / 16.0;
// An overshooting mode need not make the residual grow: at alpha = 1 it may shrink by 0.7 to
// 0.95 a solve for dozens of solves (the muscle, the bladder on its floor), and by 0.4 to 0.6
// at alpha = 0.7. So a step still at alpha = 1 whose residual fell by less than kSlowRatio at
// its kSlowFrom-th solve or later takes kShrink from then on. Earlier, a slow solve is more
// often the contacts or the first guess settling (the prostate's steps, 1 to 4 solves, keep
// alpha = 1); a second shrink, or one after the residual grew, slowed the undershooting modes
// more than it gained (the hanging cube at 100 times its dt: twice the solves).
constexpr int kSlowFrom = 3;
constexpr double kSlowRatio = 0.5;

// m: a node this close to an obstacle's surface (or inside it) touches it. The projection puts
// it on the surface to round-off; the volume projection after it moves it by second-order
// amounts of the last correction, far below this.
constexpr double kTouching = 1e-9;
// m: a node this close to an obstacle that the residual presses towards it is a row of the
// next solve (which closes its gap), though not touching: after a solve that moved it off,
// the steps' shrunk corrections would only creep back (the biopsy at 5 ms: a node 50-100 nm
// above the probe, pressed with 0.076 N, for 200 solves).
constexpr double kNear = 1e-6;

// Share of the tolerance below which the last step's acceleration is taken for its convergence
// error, not continued (moving).
constexpr double kStillAcceleration = 0.03;

// Most blocks of L for the coupled factor (19 MB); beyond, the per-axis factors of L.
constexpr size_t kMostCoupledBlocks = size_t(1) << 18;

// With the coupled factor the volumes' gradients at rest are solved once, with it; an
// iteration takes those solves while its gradients are within this relative distance of them
// (measured: the prostate scenes' iterations the same up to 0.2 and with no refresh at all).
// A stale solve moves only the Schur complement's rate, not the fixed point: the residual is
// fitted to the current gradients.
constexpr double kStaleGradient = 0.5;

// A cell turned further than this (rad) from the rotation P took for it refactorises P with
// every cell's stiffness turned as the cell is now, when the step's last solve shrank the
// residual by less than kTurnedRatio: a step converging as P's should keeps it. The per-axis
// factors (which converge slowly anyway, and cost a second or more to refactorise at 20^3)
// only when the residual grew.
constexpr double kCellTurn = 0.02;
constexpr double kTurnedRatio = 0.25;

bool has_free_body(const Model& model) {
  return std::any_of(model.rigid_bodies.begin(), model.rigid_bodies.end(),
                     [](const RigidBody& r) { return !r.driven; });
}

void refuse_unsupported(const Model& model) {
  if (model.volumes.size() > size_t(kMaxVolumes))
    throw std::invalid_argument(
        "the implicit integrator does not support more than 16 volume constraints yet: use the "
        "verlet integrator");
}

// Per axis, each node's unknown: one per free node, one per doubled group (unless a member
// holds the group on that axis), -1 on held axes.
void number_unknowns(const Model& model, ImplicitSystem& s) {
  const int n = model.node_count();
  const std::vector<int> group = doubled_group_of_node(model);
  s.body.assign(model.rigid_bodies.size(), {});
  for (int a = 0; a < 3; ++a) {
    std::vector<int>& u = s.unknown[size_t(a)];
    u.assign(size_t(n), -1);
    std::vector<int> of_group(size_t(model.doubled.rows()), -1);
    int count = 0;
    for (int i = 0; i < n; ++i) {
      const int g = group[size_t(i)];
      if (g >= 0) {
        if (model.doubled_leader[size_t(g)][size_t(a)] >= 0) continue;
        if (of_group[size_t(g)] < 0) of_group[size_t(g)] = count++;
        u[size_t(i)] = of_group[size_t(g)];
      } else if (model.inverse_mass[size_t(i)][a] > 0.0) {
        u[size_t(i)] = count++;
      }
    }
    for (size_t b = 0; b < s.body.size(); ++b)
      if (!model.rigid_bodies[b].driven)
        s.body[b].move[size_t(a)] = count++, s.body[b].turn[size_t(a)] = count++;
    s.unknowns[size_t(a)] = count;
  }
}

// P = M (1/h^2 + c/h) + sum K A_k^T A_k (+ the springs' k) over one axis's unknowns (lower triangle
// and diagonal are what the factor reads; both halves are given to the ordering).
Eigen::SparseMatrix<double> global_matrix(const Model& model, const std::vector<int>& u, int count,
                                          int axis, double h,
                                          std::span<const Eigen::Quaterniond> cell_rotation) {
  std::vector<Eigen::Triplet<double>> entries;
  const double per_mass = 1.0 / (h * h) + model.damping / h;
  for (int i = 0; i < model.node_count(); ++i)
    if (u[size_t(i)] >= 0)
      entries.emplace_back(u[size_t(i)], u[size_t(i)], model.inertia[size_t(i)] * per_mass);
  std::vector<std::pair<int, double>> row;  // A_k's unknowns and coefficients
  for (const ShapeMemory& m : model.shape_memory) {
    for (int k = 0; k < int(m.nodes.size()); ++k) {
      const auto nb = m.neighbours.row(k);
      row.clear();
      if (u[size_t(m.nodes[size_t(k)])] >= 0) row.emplace_back(u[size_t(m.nodes[size_t(k)])], 1.0);
      for (int j : nb)
        if (u[size_t(j)] >= 0) row.emplace_back(u[size_t(j)], -1.0 / double(nb.size()));
      for (const auto& [p, cp] : row)
        for (const auto& [q, cq] : row) entries.emplace_back(p, q, m.stiffness * cp * cq);
    }
  }
  // A spring support is linear: its stiffness is exact on the diagonal.
  for (const SpringSupport& springs : model.springs)
    for (int i : springs.nodes)
      if (u[size_t(i)] >= 0) entries.emplace_back(u[size_t(i)], u[size_t(i)], springs.stiffness);
  // The fibre segments' stiffness (fibre_stiffness), this axis's share.
  for (const FibreSegment& f : fibre_segments(model)) {
    const int p = u[size_t(f.nodes[0])], q = u[size_t(f.nodes[1])];
    const double k = fibre_stiffness(f)(axis, axis);
    if (p >= 0) entries.emplace_back(p, p, k);
    if (q >= 0) entries.emplace_back(q, q, k);
    if (p >= 0 && q >= 0) entries.emplace_back(p, q, -k), entries.emplace_back(q, p, -k);
  }
  // The finite-element cells' stiffness, this axis's rows and columns of it.
  each_cell_stiffness(
      model, cell_rotation, [&](const ExplicitFem& fem, int e, std::span<const Block3> k) {
        const int n = fem.nodes_per_cell;
        const int* cell = fem.cells.data() + size_t(e * n);
        for (int a = 0; a < n; ++a)
          for (int b = 0; b < n; ++b)
            if (const int p = u[size_t(cell[a])], q = u[size_t(cell[b])]; p >= 0 && q >= 0)
              entries.emplace_back(p, q, k[size_t(a * n + b)](axis, axis));
      });
  Eigen::SparseMatrix<double> P(count, count);
  P.setFromTriplets(entries.begin(), entries.end());
  return P;
}

// The factor of one axis's matrix, in a fill-reducing order (approximate minimum degree).
std::shared_ptr<const ImplicitFactor> factorise(const Eigen::SparseMatrix<double>& P) {
  auto f = std::make_shared<ImplicitFactor>();
  f->position = minimum_degree_positions(P);
  std::vector<Eigen::Triplet<double>> entries;
  for (int col = 0; col < P.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(P, col); it; ++it) {
      const int r = f->position[size_t(it.row())], c = f->position[size_t(it.col())];
      if (r >= c) entries.emplace_back(r, c, it.value());
    }
  Eigen::SparseMatrix<double> permuted(P.rows(), P.cols());
  permuted.setFromTriplets(entries.begin(), entries.end());
  f->llt.compute(permuted);
  if (f->llt.info() != Eigen::Success)
    throw std::runtime_error("the implicit step's matrix is not positive definite");
  return f;
}

// P from its assembly less the cells (ImplicitSystem::without_cells) and the cells' stiffness
// turned by cell_rotation, factorised in place: allocates nothing.
void turn_cells(const Model& model, ImplicitSystem& s,
                std::span<const Eigen::Quaterniond> cell_rotation) {
  std::copy(s.without_cells.entry.begin(), s.without_cells.entry.end(), s.assembled.entry.begin());
  size_t k = 0;
  each_cell_stiffness(model, cell_rotation,
                      [&](const ExplicitFem&, int, std::span<const Block3> stiffness) {
                        for (const Block3& v : stiffness) {
                          const ImplicitSystem::CellSlot& c = s.cell_slot[k++];
                          if (c.slot.index < 0) continue;
                          Block3 value = v;
                          hold_block_axes(s.block_unknown, c.row_block, c.col_block, value);
                          if (c.slot.transposed) value.transposeInPlace();
                          s.assembled.entry[size_t(c.slot.index)].value += value;
                        }
                      });
  factorise_assembled(*s.coupled, s.assembled);
}

// The coupled assembly without the cells and each cell block pair's slot in it (see
// ImplicitSystem::cell_slot), for the analysed factor f.
void plan_cells(const Model& model, const ImplicitBlocks& blocks, double h, const BlockFactor& f,
                ImplicitSystem& s) {
  std::vector<BlockEntry> entries = coupled_matrix(model, blocks, h, {}, false);
  s.cell_slot.clear();
  for (const ExplicitFem& fem : model.explicit_fem) {  // each_cell_stiffness's order
    const int n = fem.nodes_per_cell;
    for (size_t e = 0; e < fem.volume.size(); ++e) {
      const int* cell = fem.cells.data() + e * size_t(n);
      for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
          const int p = blocks.of_node[size_t(cell[a])], q = blocks.of_node[size_t(cell[b])];
          s.cell_slot.push_back({{}, p, q});
          if (p >= 0 && q >= 0 && p >= q) entries.push_back({p, q, Block3::Zero()});
        }
    }
  }
  s.without_cells = assemble_blocks(f, std::move(entries));
  s.assembled = s.without_cells;
  for (ImplicitSystem::CellSlot& c : s.cell_slot)
    if (c.row_block >= 0 && c.col_block >= 0 && c.row_block >= c.col_block)
      c.slot = block_slot(f, s.without_cells, c.row_block, c.col_block);
}

// The three axes' coupled factor (solver/implicit_matrix.hpp) when L holds at most
// kMostCoupledBlocks blocks; false (nothing set) otherwise. With finite elements whose nodes
// have their own blocks, planned to be turned in place (turn_cells).
bool factorise_coupled(const Model& model, ImplicitSystem& s, double h,
                       std::span<const Eigen::Quaterniond> cell_rotation) {
  const ImplicitBlocks blocks = number_blocks(model, s.unknown, s.body);
  const int count = int(blocks.unknown.size());
  BlockFactor f = analyse_blocks(count, coupled_pattern(model, blocks), kMostCoupledBlocks);
  if (f.row.size() > kMostCoupledBlocks) return false;
  s.block_unknown = blocks.unknown;
  s.block_of_node = blocks.of_node;
  s.cell_slot.clear();
  if (!model.explicit_fem.empty() && cells_on_their_blocks(model, blocks)) {
    plan_cells(model, blocks, h, f, s);
    s.coupled = std::make_shared<BlockFactor>(std::move(f));
    turn_cells(model, s, cell_rotation);
    return true;
  }
  factorise_blocks(f, coupled_matrix(model, blocks, h, cell_rotation));
  s.coupled = std::make_shared<BlockFactor>(std::move(f));
  return true;
}

// One factor per axis of P with L = sum K A_k^T A_k; axes whose unknowns coincide share it
// (unless fibres or finite elements, whose stiffness depends on the direction, make the axes'
// matrices differ).
void factorise_axes(const Model& model, ImplicitSystem& s, double h,
                    std::span<const Eigen::Quaterniond> cell_rotation) {
  for (int a = 0; a < 3; ++a) {
    s.factor[size_t(a)] = nullptr;
    for (int b = 0;
         b < a && !s.factor[size_t(a)] && model.fibres.empty() && model.explicit_fem.empty(); ++b)
      if (s.unknown[size_t(b)] == s.unknown[size_t(a)]) s.factor[size_t(a)] = s.factor[size_t(b)];
    if (!s.factor[size_t(a)])
      s.factor[size_t(a)] = factorise(
          global_matrix(model, s.unknown[size_t(a)], s.unknowns[size_t(a)], a, h, cell_rotation));
  }
}

// Fields given per axis over the unknowns, each with where P^-1 times it goes.
struct Fields {
  using Field = std::array<Eigen::VectorXd, 3>;
  std::array<const Field*, 1 + kMaxVolumes> in{};
  std::array<Field*, 1 + kMaxVolumes> out{};
  int count = 0;
  void add(const Field& from, Field& to) {
    in[size_t(count)] = &from;
    out[size_t(count++)] = &to;
  }
};

void solve_fields(ImplicitSystem& s, const Fields& fields);
void gather(const ImplicitSystem& s, std::span<const Vec3> field, std::span<const int> nodes,
            std::array<Eigen::VectorXd, 3>& out);

// Each volume's gradient at the rest shape over the unknowns, and P^-1 times it.
void solve_rest_gradients(const Model& model, ImplicitSystem& s) {
  const size_t volumes = model.volumes.size();
  s.rest_gradient.resize(volumes);
  s.rest_solved.resize(volumes);
  std::vector<Vec3>& g = s.node_scratch;  // sized by prepare: refactorising allocates nothing
  std::fill(g.begin(), g.end(), Vec3::Zero());
  for (size_t l = 0; l < volumes; ++l) {
    for (int a = 0; a < 3; ++a) {
      s.rest_gradient[l][size_t(a)].setZero(s.unknowns[size_t(a)]);
      s.rest_solved[l][size_t(a)].setZero(s.unknowns[size_t(a)]);
    }
    volume_gradient(model.volumes[l], model.rest_position, g);
    gather(s, g, model.volumes[l].nodes, s.rest_gradient[l]);
  }
  Fields rest;
  for (size_t l = 0; l < volumes; ++l) rest.add(s.rest_gradient[l], s.rest_solved[l]);
  solve_fields(s, rest);
}

// Numbers the unknowns and factorises P for step h. Allocates: only on a model's first step
// and when dt changes.
void prepare(const Model& model, ImplicitSystem& s, double h,
             std::span<const Eigen::Quaterniond> cell_rotation) {
  refuse_unsupported(model);
  number_unknowns(model, s);
  s.coupled = nullptr;
  s.block_of_node.clear();
  for (auto& f : s.factor) f = nullptr;
  if (!factorise_coupled(model, s, h, cell_rotation)) {
    if (has_free_body(model))
      throw std::invalid_argument(
          "the implicit integrator takes free rigid bodies only where the three axes' factor "
          "fits (at most 2^18 blocks): drive the bodies ('motion') or use the verlet integrator");
    factorise_axes(model, s, h, cell_rotation);
  }
  size_t most = 0;
  for (int a = 0; a < 3; ++a) {
    const int m = s.unknowns[size_t(a)];
    most = std::max(most, size_t(m));
    s.residual[size_t(a)].setZero(m);
    s.correction[size_t(a)].setZero(m);
  }
  s.gradient.resize(model.volumes.size());
  s.solved_gradient.resize(model.volumes.size());
  for (size_t l = 0; l < model.volumes.size(); ++l)
    for (int a = 0; a < 3; ++a) {
      s.gradient[l][size_t(a)].setZero(s.unknowns[size_t(a)]);
      s.solved_gradient[l][size_t(a)].setZero(s.unknowns[size_t(a)]);
    }
  s.block.assign(std::max(most * 3 * (1 + model.volumes.size()), 3 * s.block_unknown.size()), 0.0);
  s.cell_fit.resize(cell_rotation.size());
  s.node_scratch.resize(size_t(model.node_count()));
  if (s.coupled) solve_rest_gradients(model, s);
  prepare_implicit_contacts(model, s);
  prepare_implicit_friction(model, s);
  prepare_implicit_needles(model, s);
  s.h = h;
}

// P again, for the finite-element cells' new rotations (cells_turned): its factor, the volumes'
// solves with it at rest, and none of the contacts' columns of P^-1 cached.
void refactorise(const Model& model, ImplicitSystem& s, double h,
                 std::span<const Eigen::Quaterniond> cell_rotation) {
  if (s.coupled) {
    if (s.cell_slot.empty())
      factorise_coupled(model, s, h, cell_rotation);
    else
      turn_cells(model, s, cell_rotation);
    solve_rest_gradients(model, s);
  } else {
    factorise_axes(model, s, h, cell_rotation);
  }
  for (int a = 0; a < 3; ++a) {
    std::fill(s.column_slot[size_t(a)].begin(), s.column_slot[size_t(a)].end(), -1);
    s.columns_used[size_t(a)] = 0;
  }
}

// P^-1 applied to the fields: with the coupled factor one solve each; with the per-axis
// factors one pass over each for all the fields of the axes that share it.
void solve_fields(ImplicitSystem& s, const Fields& io) {
  const int fields = io.count;
  const auto& in = io.in;
  const auto& out = io.out;
  if (fields == 0) return;
  double* x = s.block.data();
  if (s.coupled) {
    const BlockFactor& f = *s.coupled;
    for (int field = 0; field < fields; ++field) {
      for (int b = 0; b < f.blocks; ++b)
        for (int a = 0; a < 3; ++a) {
          const int u = s.block_unknown[size_t(b)][size_t(a)];
          x[3 * f.position[size_t(b)] + a] = u >= 0 ? (*in[size_t(field)])[size_t(a)][u] : 0.0;
        }
      solve_blocks(f, x);
      for (int b = 0; b < f.blocks; ++b)
        for (int a = 0; a < 3; ++a)
          if (const int u = s.block_unknown[size_t(b)][size_t(a)]; u >= 0)
            (*out[size_t(field)])[size_t(a)][u] = x[3 * f.position[size_t(b)] + a];
    }
    return;
  }
  for (int a = 0; a < 3; ++a) {
    if (a > 0 && (s.factor[size_t(a)] == s.factor[0] || (a == 2 && s.factor[2] == s.factor[1])))
      continue;  // solved with the first axis that shares its factor
    int axes[3], count = 0;
    for (int b = a; b < 3; ++b)
      if (s.factor[size_t(b)] == s.factor[size_t(a)]) axes[count++] = b;
    const ImplicitFactor& f = *s.factor[size_t(a)];
    const int k = count * fields, m = s.unknowns[size_t(a)];
    for (int u = 0; u < m; ++u) {
      double* r = x + size_t(f.position[size_t(u)]) * size_t(k);
      for (int q = 0; q < count; ++q)
        for (int field = 0; field < fields; ++field)
          r[q * fields + field] = (*in[size_t(field)])[size_t(axes[q])][u];
    }
    switch (k) {  // one axis or three, without or with one or two volume constraints
      case 3:
        solve_block<3>(f, x, k);
        break;
      case 6:
        solve_block<6>(f, x, k);
        break;
      case 9:
        solve_block<9>(f, x, k);
        break;
      default:
        solve_block<0>(f, x, k);
    }
    for (int u = 0; u < m; ++u) {
      const double* r = x + size_t(f.position[size_t(u)]) * size_t(k);
      for (int q = 0; q < count; ++q)
        for (int field = 0; field < fields; ++field)
          (*out[size_t(field)])[size_t(axes[q])][u] = r[q * fields + field];
    }
  }
}

// Sums a node field into the unknowns (a doubled group's members add up); a free rigid body's
// nodes into the body's (the force on the centre's motion, its moment, in the body's frame, on
// the turn).
void gather(const Model& model, const Data& d, const ImplicitSystem& s, std::span<const Vec3> field,
            std::array<Eigen::VectorXd, 3>& out) {
  for (int a = 0; a < 3; ++a) out[size_t(a)].setZero();
  for (int i = 0; i < model.node_count(); ++i) gather_node(s, i, field[size_t(i)], out);
  gather_bodies(model, d, s, field, out);
}

// A volume's gradient over some nodes' free axes only (the rest of `field` is not read): as
// in the explicit projection, which moves nodes by their inverse masses, a volume's pressure
// moves its free nodes and not the rigid bodies its surface is doubled with.
void gather(const ImplicitSystem& s, std::span<const Vec3> field, std::span<const int> nodes,
            std::array<Eigen::VectorXd, 3>& out) {
  for (int a = 0; a < 3; ++a) out[size_t(a)].setZero();
  for (int i : nodes) gather_node(s, i, field[size_t(i)], out);
}

double dot(const std::array<Eigen::VectorXd, 3>& p, const std::array<Eigen::VectorXd, 3>& q) {
  return p[0].dot(q[0]) + p[1].dot(q[1]) + p[2].dot(q[2]);
}

// The backward-Euler residual (N) per node into r, on every axis (held ones are not read).
void backward_euler_residual(const Model& model, const Data& d, double h, std::span<Vec3> r) {
  const Workspace& w = *d.work;
  const double c = model.damping;
  for (int i = 0; i < model.node_count(); ++i) {
    const Vec3 moved = d.x[size_t(i)] - w.x_start[size_t(i)];
    r[size_t(i)] = d.f[size_t(i)] + model.inertia[size_t(i)] / (h * h) *
                                        (h * w.v_start[size_t(i)] - (1.0 + c * h) * moved);
  }
  // A rigid node's inertia is its body's (add_body_inertia).
  for (const RigidBody& body : model.rigid_bodies)
    for (int i : body.nodes) r[size_t(i)] = d.f[size_t(i)];
}

// The nodes touching an obstacle at load_time, into work.contacts (push: the way the shape
// pushes) and d.obstacle_touching.
void find_contacts(const Model& model, Data& d, double load_time) {
  Workspace& w = *d.work;
  w.contacts.clear();
  w.implicit.touching_gap.clear();
  w.implicit.touching_obstacle.clear();
  std::fill(d.obstacle_touching.begin(), d.obstacle_touching.end(), -1);
  for (int k = 0; k < int(model.obstacles.size()); ++k) {
    const RigidObstacle& o = model.obstacles[size_t(k)];
    auto add = [&](int i) {
      const std::array<std::vector<int>, 3>& u = w.implicit.unknown;
      if (u[0][size_t(i)] < 0 && u[1][size_t(i)] < 0 && u[2][size_t(i)] < 0)
        return;  // held, or moved by a rigid body: the obstacle does not move it
      const SurfaceDistance sd =
          obstacle_distance(o, d.controls.obstacle_motion[size_t(k)], d.x[size_t(i)], load_time);
      const double gap = o.keep_inside ? -sd.distance : sd.distance;
      if (gap > kNear && w.implicit.held_by[size_t(i)] != k) return;
      w.contacts.push_back({i, o.keep_inside ? Vec3(-sd.normal) : sd.normal, 0.0});
      w.implicit.touching_gap.push_back(gap);
      w.implicit.touching_obstacle.push_back(k);
      if (gap <= kTouching || w.implicit.held_by[size_t(i)] == k)
        d.obstacle_touching[size_t(i)] = k;
    };
    if (o.nodes.empty())
      for (int i = 0; i < model.node_count(); ++i) add(i);
    else
      for (int i : o.nodes) add(i);
  }
}

// Takes out of the residual the volume constraints' pressures (the least-squares multipliers
// of their gradients) and, on touching nodes, the push into the obstacle (its reaction, added
// up per obstacle into d.contact_force). The normal parts on touching nodes are the contact's
// to balance: they take no part in the pressures' fit, as in the static residual.
void remove_reactions(const Model& model, Data& d, ImplicitSystem& s) {
  const std::vector<ObstacleContact>& contacts = d.work->contacts;
  const int volumes = int(model.volumes.size());
  const bool pairs = !s.pair_rows.empty();
  if (volumes > 0 || pairs) {
    Small gg(volumes, volumes);
    SmallVector gr(volumes);
    for (int l = 0; l < volumes; ++l) {
      gr[l] = dot(s.gradient[size_t(l)], s.residual);
      for (int m = 0; m <= l; ++m)
        gg(l, m) = gg(m, l) = dot(s.gradient[size_t(l)], s.gradient[size_t(m)]);
    }
    for (const ObstacleContact& c : contacts) {
      const double rn = node_value(s, s.residual, c.node).dot(c.push);
      for (int l = 0; l < volumes; ++l) {
        const double gl = node_value(s, s.gradient[size_t(l)], c.node).dot(c.push);
        gr[l] -= rn * gl;
        for (int m = 0; m <= l; ++m)
          gg(l, m) = gg(m, l) =
              gg(l, m) - gl * node_value(s, s.gradient[size_t(m)], c.node).dot(c.push);
      }
    }
    SmallVector p(volumes);
    if (pairs)
      fit_pressures_and_pair_forces(model, s, gg.data(), gr.data(), p.data());
    else
      p = gg.ldlt().solve(gr);
    for (int l = 0; l < volumes; ++l)
      for (int a = 0; a < 3; ++a) s.residual[size_t(a)] -= p[l] * s.gradient[size_t(l)][size_t(a)];
  }
  std::fill(d.contact_force.begin(), d.contact_force.end(), Vec3::Zero());
  s.active.clear();
  if (pairs) take_out_pair_forces(d, s);  // and the needles' rows
  for (size_t k = 0; k < contacts.size(); ++k) {
    const ObstacleContact& c = contacts[k];
    // The solve decides whom it holds.
    const double into = node_value(s, s.residual, c.node).dot(c.push);
    ImplicitSystem::Contact row;
    row.nodes[0] = c.node;
    row.push = c.push;
    row.gap = s.touching_gap[k];
    row.obstacle = s.touching_obstacle[k];
    row.into = into;
    s.active.push_back(row);
    if (into >= 0.0) continue;  // pulled away: the obstacle holds nothing
    // Near but not touching: a row of the solve, pressed, not yet the obstacle's to balance.
    if (row.gap > kTouching && s.held_by[size_t(c.node)] != row.obstacle) {
      s.active.back().into = 0.0;
      continue;
    }
    for (int a = 0; a < 3; ++a)
      if (const int u = s.unknown[size_t(a)][size_t(c.node)]; u >= 0)
        s.residual[size_t(a)][u] -= into * c.push[a];
    Vec3& force = d.contact_force[size_t(d.obstacle_touching[size_t(c.node)])];
    force -= into * c.push;
    if (model.obstacles[size_t(row.obstacle)].friction > 0.0)
      force +=
          add_friction(model, d, s, c.node, c.push, row.obstacle, -into, int(s.active.size()) - 1);
  }
}

// Largest residual nodal force (N) over the unknowns, the reactions taken out.
double largest_residual(const Model& model, Data& d, ImplicitSystem& s) {
  remove_reactions(model, d, s);
  double largest2 = 0.0;
  for (int i = 0; i < model.node_count(); ++i) {
    double r2 = 0.0;
    for (int a = 0; a < 3; ++a)
      if (const int u = s.unknown[size_t(a)][size_t(i)]; u >= 0)
        r2 += s.residual[size_t(a)][u] * s.residual[size_t(a)][u];
    largest2 = std::max(largest2, r2);
  }
  return std::sqrt(std::max(largest2, largest_body_residual2(model, s)));
}

// Whether the rest shape's solve of volume l's gradient stands for its current one: with
// the coupled factor (with the per-axis ones a stale solve slows the iterations), and the
// gradient within kStaleGradient of the rest one. Each iteration decides from its own state:
// a fresh workspace does the same.
bool rest_solve_stands(const ImplicitSystem& s, size_t l) {
  if (!s.coupled) return false;
  double moved = 0.0, size = 0.0;
  for (int a = 0; a < 3; ++a) {
    moved += (s.gradient[l][size_t(a)] - s.rest_gradient[l][size_t(a)]).squaredNorm();
    size += s.gradient[l][size_t(a)].squaredNorm();
  }
  return moved <= kStaleGradient * kStaleGradient * size;
}

// P^-1 times the residual into correction, and times each volume's gradient (or its rest
// shape's solve, where that stands) into solved_gradient.
void solve_residual_and_gradients(const Model& model, ImplicitSystem& s) {
  Fields io;
  io.add(s.residual, s.correction);
  for (size_t l = 0; l < model.volumes.size(); ++l)
    if (rest_solve_stands(s, l))
      for (int a = 0; a < 3; ++a) s.solved_gradient[l][size_t(a)] = s.rest_solved[l][size_t(a)];
    else
      io.add(s.gradient[l], s.solved_gradient[l]);
  solve_fields(s, io);
}

// The correction P^-1 (r - G^T mu), mu such that each volume reaches its target and each
// node an obstacle pushes stays on its surface, to first order (G: the volumes' gradients and
// the contacts' pushes over the unknowns).
void global_step(const Model& model, Data& d, ImplicitSystem& s, double load_time) {
  solve_residual_and_gradients(model, s);
  const int volumes = int(model.volumes.size());
  if (volumes == 0 && s.active.empty()) return;
  SmallVector rate(volumes);
  for (int l = 0; l < volumes; ++l) {
    const VolumeConstraint& c = model.volumes[size_t(l)];
    const double gap =
        target_volume(model, d.controls, size_t(l), load_time) - enclosed_volume(d.x, c.triangles);
    rate[l] = dot(s.gradient[size_t(l)], s.correction) - gap;
  }
  if (!s.active.empty()) {
    constrain_to_contacts(model, s, {rate.data(), size_t(volumes)});
    return;
  }
  Small schur(volumes, volumes);
  for (int l = 0; l < volumes; ++l)
    for (int m = 0; m <= l; ++m)
      schur(l, m) = schur(m, l) = dot(s.gradient[size_t(l)], s.solved_gradient[size_t(m)]);
  const SmallVector mu = schur.ldlt().solve(rate);
  for (int l = 0; l < volumes; ++l)
    for (int a = 0; a < 3; ++a)
      s.correction[size_t(a)] -= mu[l] * s.solved_gradient[size_t(l)][size_t(a)];
}

// The residual and the volumes' gradients at d.x over the unknowns; the largest residual
// nodal force (N).
double residual_at(const Model& model, Data& d, ImplicitSystem& s, double h, double load_time) {
  Workspace& w = *d.work;
  if (!model.obstacles.empty()) find_contacts(model, d, load_time);
  if (!model.contact_pairs.empty()) find_pair_contacts(model, d, s);
  backward_euler_residual(model, d, h, w.f_start);
  gather(model, d, s, w.f_start, s.residual);
  add_body_inertia(model, d, s, h);
  if (!model.needles.empty()) add_needle_rows(model, d, s, load_time);
  for (size_t l = 0; l < model.volumes.size(); ++l) {
    volume_gradient(model.volumes[l], w.volumes[l], d.x, w.f_start);
    gather(s, w.f_start, model.volumes[l].nodes, s.gradient[l]);
  }
  const double largest = largest_residual(model, d, s);
  if (!model.needles.empty()) update_needles(model, d, s, load_time, false);
  return largest;
}

// Each node the last step ended touching an obstacle (Data::obstacle_touching, which a
// checkpoint keeps) back on its surface, along its free axes, and held by the first solve:
// pressed nodes stay pressed, where a first solve without them would push them into the
// obstacle and its neighbours after them (the rigid probe at 400 mL: up to 14 solves a step).
void keep_touching(const Model& model, Data& d, double load_time) {
  for (int i = 0; i < int(d.obstacle_touching.size()); ++i) {
    const int k = d.obstacle_touching[size_t(i)];
    if (k < 0) continue;
    const RigidObstacle& o = model.obstacles[size_t(k)];
    const SurfaceDistance sd =
        obstacle_distance(o, d.controls.obstacle_motion[size_t(k)], d.x[size_t(i)], load_time);
    const double gap = o.keep_inside ? -sd.distance : sd.distance;
    const Vec3 push = o.keep_inside ? Vec3(-sd.normal) : sd.normal;
    for (int a = 0; a < 3 && gap > 0.0; ++a)
      if (model.inverse_mass[size_t(i)][a] > 0.0) d.x[size_t(i)][a] -= gap * push[a];
  }
  std::copy(d.obstacle_touching.begin(), d.obstacle_touching.end(),
            d.work->implicit.held_by.begin());
}

// The position constraints in the explicit steps' order, contact pairs included (their
// record, Data::pair_contacts, is scratch here: the residual's fit writes it again).
void project_positions(const Model& model, Data& d, double load_time) {
  Workspace& w = *d.work;
  apply_prescribed(model, d.x, load_time);
  apply_contacts(model, d.controls, d.x, load_time);
  if (!model.contact_pairs.empty()) {
    std::fill(w.pair_impulse.begin(), w.pair_impulse.end(), Vec3::Zero());
    apply_deformable_contacts(model, d.x, w, d.pair_contacts, d.dt, w.pair_impulse);
  }
  if (!model.needles.empty()) project_needles(model, d, w.implicit, load_time);
  project_volumes(model, d.controls, w, d.x, load_time, w.f_start);
  project_doubled(model, d.x);
}

// Whether the last step's acceleration is the motion's: its largest inertial force (N) above
// kStillAcceleration of the tolerance. Below, it is the last step's convergence error, which
// continuing it would double: the pushed 10^3 cube at rest, 100 times its dt, takes 1.1
// solves a step with it (tolerance 1e-9 N), 0.7 without; at a tenth of the tolerance the
// prostate's rigid probe at 50 mL would already lose some of the guess (1.3 -> 1.4 solves).
bool moving(const Model& model, std::span<const Vec3> acceleration, double tolerance) {
  for (size_t i = 0; i < acceleration.size(); ++i)
    if (model.inertia[i] * acceleration[i].norm() > kStillAcceleration * tolerance) return true;
  return false;
}

// The step's first iterate: x0 + h v0, and + h^2 a while the last step's acceleration is the
// motion's (its second order, which the solves would otherwise find: on the prostate scenes
// at 400 mL 1.9 solves a step instead of 2.5), touching nodes kept on their obstacles, the
// rigid bodies drifting with their momenta (their nodes with them), then the position
// constraints.
void first_guess(const Model& model, Data& d, double h, double load_time,
                 std::span<const Vec3> acceleration, double tolerance) {
  Workspace& w = *d.work;
  if (!moving(model, acceleration, tolerance)) acceleration = {};
  for (int i = 0; i < model.node_count(); ++i) {
    w.x_start[size_t(i)] = d.x[size_t(i)];
    w.v_start[size_t(i)] = d.v[size_t(i)];
    d.x[size_t(i)] += h * d.v[size_t(i)];
    if (!acceleration.empty()) d.x[size_t(i)] += h * h * acceleration[size_t(i)];
  }
  keep_touching(model, d, load_time);
  if (!model.contact_pairs.empty()) hold_pair_contacts(d, w.implicit);
  start_bodies(model, d, w.implicit, h, load_time);
  if (!model.needles.empty()) start_needles(model, d, w.implicit, load_time);
  project_positions(model, d, load_time);
}

// Which nodes the last solve held on which obstacle, and which of them slide on a rough one,
// in one number (equal sets, equal numbers; unequal ones differ but for a collision of the
// hash).
long held_signature(const ImplicitSystem& s) {
  unsigned long sum = 0;
  for (size_t i = 0; i < s.held_by.size(); ++i)
    if (s.held_by[i] >= 0)
      sum = sum * 1000003u + (i + 1) * unsigned(s.held_by[i] + 1) *
                                 (s.sliding.empty() ? 1u : 2u + unsigned(s.sliding[i]));
  return long(sum >> 1);
}

// The share of its corrections a step takes next, from its largest residual now and before
// the last solve, after `solves` solves.
double next_alpha(double alpha, double residual, double previous, int solves) {
  if (residual > previous) return std::max(kShrink * alpha, kShortestStep);
  if (alpha == 1.0 && solves >= kSlowFrom && residual > kSlowRatio * previous) return kShrink;
  return alpha;
}

// Explicit finite elements: each cell's rotation at x, and whether one turned more than
// kCellTurn from the one P took for it (Data::cell_rotation, which a checkpoint keeps); then
// they all become P's.
bool cells_turned(const Model& model, Data& d, ImplicitSystem& s) {
  if (d.cell_rotation.empty()) return false;
  std::copy(d.cell_rotation.begin(), d.cell_rotation.end(), s.cell_fit.begin());
  size_t first = 0;
  for (const ExplicitFem& fem : model.explicit_fem) {
    fit_cell_rotations(fem, model.rest_position, d.x,
                       std::span(s.cell_fit).subspan(first, fem.volume.size()));
    first += fem.volume.size();
  }
  double most = 0.0;
  for (size_t c = 0; c < s.cell_fit.size(); ++c)
    most = std::max(most, s.cell_fit[c].angularDistance(d.cell_rotation[c]));
  if (!(most > kCellTurn)) return false;
  std::copy(s.cell_fit.begin(), s.cell_fit.end(), d.cell_rotation.begin());
  return true;
}

// One backward-Euler step (step_implicit), its first guess continuing `acceleration` (empty:
// none, as in the static solver's steps from rest), which it then sets to the step's;
// Anderson-accelerated (implicit_anderson.hpp) where the model allows, unless `statics`.
void backward_euler_step(const Model& model, Data& d, double h, double load_time, int most,
                         double tolerance, std::span<Vec3> acceleration, bool statics) {
  Workspace& w = *d.work;
  ImplicitSystem& s = w.implicit;
  if (statics && !model.needles.empty())  // see check_implicit_scene
    throw std::invalid_argument(
        "the implicit static solver does not support needles: they are inserted in dynamics");
  if (statics && with_friction(model))  // see check_implicit_scene
    throw std::invalid_argument(
        "the implicit static solver does not support obstacles with friction: use the "
        "relaxation");
  if (!(s.h == h)) {
    prepare(model, s, h, d.cell_rotation);
    prepare_anderson(model, s, d.anderson, h);
    // Room for a record of every pair row (a checkpoint's or a copy's may hold only its own).
    d.pair_contacts.reserve(s.pair_rows.capacity());
  }
  const int n = model.node_count();
  first_guess(model, d, h, load_time, acceleration, tolerance);
  start_friction(model, d, s, load_time);
  AndersonHistory& history = d.anderson;
  begin_anderson_step(s, history);
  // Not in the static solver's steps: there the strip of ImplicitFibres.* took 7 steps with
  // it against 4 without.
  const bool accelerate = !s.anderson.before.empty() && !statics;
  s.iterations = 0;
  bool needles_moved = false;
  double alpha = 1.0, previous = std::numeric_limits<double>::infinity();
  for (;;) {
    compute_forces(model, d, load_time);  // the local step: each node's rotation
    s.residual_force = residual_at(model, d, s, h, load_time);
    if (s.residual_force <= tolerance && !model.needles.empty()) {
      // Converged with the needles as they stand: now a surface may give way or a point slide
      // (each once a step), and the step goes on from the same positions if one did.
      update_needles(model, d, s, load_time, true);
      needles_moved = needles_moved || s.needles_changed;
      if (s.needles_changed && s.iterations < most) {
        restart_anderson(s, history);
        continue;
      }
    }
    if (s.residual_force <= tolerance || s.iterations >= most) break;
    if (s.residual_force > previous) restart_anderson(s, history);
    alpha = next_alpha(alpha, s.residual_force, previous, s.iterations);
    history.alpha = alpha;
    const double turned_ratio = s.coupled ? kTurnedRatio : 1.0;
    if (!(s.residual_force < turned_ratio * previous) && cells_turned(model, d, s)) {
      refactorise(model, s, h, d.cell_rotation);
      restart_anderson(s, history);  // its iterates were P's before
      alpha = history.alpha = 1.0;
    }
    previous = s.residual_force;
    global_step(model, d, s, load_time);
    if (accelerate) {
      // A mix across solves that held different nodes would ignore the change: start anew.
      if (const long held = held_signature(s); held != history.held)
        restart_anderson(s, history), history.held = held;
      std::copy(d.x.begin(), d.x.end(), s.anderson.before.begin());
    }
    for (int a = 0; a < 3; ++a) {
      const std::vector<int>& u = s.unknown[size_t(a)];
      for (int i = 0; i < n; ++i)
        if (u[size_t(i)] >= 0) d.x[size_t(i)][a] += alpha * s.correction[size_t(a)][u[size_t(i)]];
    }
    move_bodies(model, d, s, alpha);
    // Mixed before the projections, one pass of them for both: f is then alpha times the
    // correction, zero where the iterations stop as before.
    if (accelerate) anderson_mix(s, history, s.anderson.before, d.x);
    // Exactly on the volumes (the linearised solve left them off by second-order terms).
    project_positions(model, d, load_time);
    ++s.iterations;
  }
  if (!model.needles.empty()) end_needles(model, d, s, load_time);
  d.load_time = load_time;
  for (int i = 0; i < n; ++i) d.v[size_t(i)] = (d.x[size_t(i)] - w.x_start[size_t(i)]) / h;
  end_bodies(model, d, s, h);
  // A surface that gave way (or a point that let go) jolts the tissue once: its acceleration
  // is not the motion's, and continued it would throw the next guess far off.
  for (size_t i = 0; i < acceleration.size(); ++i)
    acceleration[i] = needles_moved ? Vec3::Zero() : Vec3((d.v[i] - w.v_start[i]) / h);
}

}  // namespace

void step_implicit(const Model& model, Data& d, double h, double load_time) {
  backward_euler_step(model, d, h, load_time, model.settings.implicit_iterations,
                      model.settings.implicit_tolerance, d.acceleration, false);
}

void step_implicit(const Model& model, Data& d, double h, double load_time, int most,
                   double tolerance) {
  backward_euler_step(model, d, h, load_time, most, tolerance, {}, true);
}

double implicit_residual_force(const Data& d) { return d.work->implicit.residual_force; }
int implicit_iterations(const Data& d) { return d.work->implicit.iterations; }

}  // namespace phymul

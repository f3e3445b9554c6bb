// What an implicit step keeps between steps (Workspace::implicit): the global matrix of the
// local/global iterations, factorised for one dt, and the vectors its solves work in. Built by
// the first implicit step (solver/implicit_step.cpp) and again only when dt changes: the
// matrix depends on dt, the inertias, the damping and the held axes, and only dt can change
// during a run. A copy starts without a factor and makes its own on its first step.
#pragma once

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <array>
#include <limits>
#include <memory>
#include <vector>

#include "model/block_cholesky.hpp"

namespace phymul {

struct Model;

// Columns the implicit steps' Anderson acceleration keeps (Data::anderson).
inline constexpr int kAndersonDepth = 5;
// Whether it applies to the model's implicit steps: contact pairs and rigid bodies change
// the rows or unknowns from one iteration to the next in ways a mix across them would ignore.
bool anderson_applies(const Model& model);

// L L^T of one axis's matrix P, symmetrically permuted by a fill-reducing order beforehand
// (the factor itself in natural order, so that a solve permutes into a kept buffer and never
// allocates).
struct ImplicitFactor {
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>> llt;
  std::vector<int> position;  // per unknown: its row in the permuted matrix
};

struct ImplicitSystem {
  double h = std::numeric_limits<double>::quiet_NaN();  // s, the dt factorised for; NaN: none
  // Per axis: each node's unknown (doubled groups share one), -1 on a held axis.
  std::array<std::vector<int>, 3> unknown;
  std::array<int, 3> unknowns{0, 0, 0};
  // Per axis: its factor; axes holding the same nodes share one. Null where `coupled` is set.
  std::array<std::shared_ptr<const ImplicitFactor>, 3> factor;
  // Or one factor of the three axes together, by node blocks (solver/implicit_matrix.hpp),
  // where its factor is small enough; per block, each axis's unknown.
  std::shared_ptr<BlockFactor> coupled;
  // With explicit finite elements on the coupled factor: P less the cells' stiffness in the
  // factor's order (zero blocks where only cells couple), P itself, and per block pair of a
  // cell (solver/implicit_matrix.hpp's each_cell_stiffness order) where it sums (index -1: a
  // held node's, or above the diagonal), so that P is factorised again for turned cells in
  // place. Empty: P is assembled anew (the per-axis factors, or cells on a rigid body).
  struct CellSlot {
    BlockSlot slot;
    int row_block = -1, col_block = -1;
  };
  BlockAssembly without_cells, assembled;
  std::vector<CellSlot> cell_slot;
  std::vector<Eigen::Vector3d> node_scratch;  // a field over the nodes (rest gradients)
  std::vector<std::array<int, 3>> block_unknown;
  std::vector<int> block_of_node;  // -1: every axis held
  // Per rigid body, its unknowns on each axis (free bodies; -1 for driven ones): the motion of
  // its centre and its turn (a rotation vector in the body's principal frame), after the nodes';
  // and its state at the step's start.
  struct Body {
    std::array<int, 3> move{-1, -1, -1}, turn{-1, -1, -1};
    Eigen::Vector3d center, momentum, angular_momentum;
    Eigen::Quaterniond orientation;
  };
  std::vector<Body> body;
  // Per axis, unknowns long: the residual and the correction.
  std::array<Eigen::VectorXd, 3> residual, correction;
  // The solves' right-hand sides, row by row in the factor's order (solver/implicit_step.cpp).
  std::vector<double> block;
  // Per volume constraint and axis: its gradient over the unknowns and P^-1 times it (or,
  // with the coupled factor, times a gradient near it); the gradient at the rest shape and
  // P^-1 times it, solved with the coupled factor.
  std::vector<std::array<Eigen::VectorXd, 3>> gradient, solved_gradient;
  std::vector<std::array<Eigen::VectorXd, 3>> rest_gradient, rest_solved;
  // Frictionless contacts (solver/implicit_contacts.cpp): each row a constraint of the global
  // solve, push . (sum of weight_k dx_k) = -gap over up to four nodes. An obstacle's row: the
  // node it pushes, weight 1. A contact pair's (solver/implicit_pairs.cpp): the node, then
  // the other side's triangle with minus its barycentric weights, push the way out.
  struct Contact {
    std::array<int, 4> nodes{0, 0, 0, 0};
    std::array<double, 4> weights{1.0, 0.0, 0.0, 0.0};
    int count = 1;
    Eigen::Vector3d push = Eigen::Vector3d::Zero();
    double gap = 0.0;              // m, along push: how far the node is clear of the surface
    int obstacle = -1, pair = -1;  // whose row (the others -1); side: the node's in the pair
    // A needle's row (solver/implicit_needles.cpp), over an embedded point's four nodes:
    // `point` its track point, or -1 for the surface point the tip presses. Both ways.
    int needle = -1, point = -1;
    int side = 0;
    double into = 0.0;  // N: the residual's push along the row (< 0: into the surface)
    // A sticking node's row along a tangent of its obstacle (solver/implicit_friction.cpp):
    // the index in `active` of the node's normal row, whose release releases it; -1 otherwise.
    int normal_row = -1;
  };
  std::vector<Contact> active;
  std::vector<double> touching_gap;    // per Workspace::contacts entry: its gap
  std::vector<int> touching_obstacle;  // and its obstacle
  // The contact pairs' rows found this iteration (before `active` takes them), and the
  // least-squares fit of the volumes' pressures and their forces to the residual: its normal
  // equations (row-major), right-hand side, rows taken, and per row its force (N, >= 0).
  std::vector<Contact> pair_rows;
  // Per contact pair and side, the faces around each node (by global id, CSR): the faces a
  // node touching an edge or a corner of that side's surface gets a row for.
  struct FaceRing {
    std::vector<int> start, faces;
  };
  std::vector<std::array<FaceRing, 2>> face_rings;
  std::vector<double> fit, fit_rhs, pair_force;
  std::vector<int> fit_rows;
  std::vector<char> touching;  // per pair row: whether it may carry a force in the fit
  // Per node, the contact pair whose row the step's last solve held (-1: none), as held_by.
  std::vector<int> pair_held;
  // Columns of P^-1 at those nodes' unknowns, kept while the factor is: per axis owning a
  // factor (owner: the first axis sharing it), each unknown's slot (-1: none) and the slots.
  // With the coupled factor, in axis 0's: each block's slot, three columns (its axes) a slot,
  // each in the factor's order.
  std::array<int, 3> owner{0, 1, 2};
  std::array<std::vector<int>, 3> column_slot;
  std::array<std::vector<double>, 3> columns;
  std::array<int, 3> columns_used{0, 0, 0};
  std::unique_ptr<double[]> coupled_columns;  // uninitialised: pages touched as slots fill
  int column_capacity = 0;
  int row_capacity = 0;  // most rows (obstacles' and pairs') a solve takes
  // The Schur complement of volumes and contacts, row-major, and its right-hand side; the
  // whole system (all touching nodes) and its right-hand side, from which the solves of the
  // contacts still held are taken; per touching node whether it is held, and its multiplier.
  std::vector<double> schur, rhs, system, system_rhs;
  std::vector<char> held;
  std::vector<double> multiplier;
  std::vector<int> rows;  // the system's rows the solve takes
  // Per node, the obstacle the step's last solve held it against (-1: none): it stays a
  // constraint, on the surface or not, until its multiplier releases it.
  std::vector<int> held_by;
  // Coulomb friction on obstacles (solver/implicit_friction.cpp): per node, whether the last
  // residual found it sliding; per obstacle, its shape's shift over the step.
  std::vector<char> sliding;
  std::vector<Eigen::Vector3d> obstacle_shift;
  // Needles (solver/implicit_needles.cpp): per needle and track point, how it moves along the
  // shaft this step: 0 sticking (an axial row), +1 or -1 sliding that way under its friction;
  // and whether the last residual changed a needle's state (a puncture, a point let slide).
  std::vector<std::vector<signed char>> needle_slide;
  bool needles_changed = false;
  // Anderson acceleration of the iterations (solver/implicit_anderson.cpp), its history in
  // Data::anderson: the iterate the solve started from, and the last iteration's residual f
  // and image g, per node (empty: not used for this model); whether f and g are this step's,
  // and whether the history goes on into the next step.
  struct Anderson {
    std::vector<Eigen::Vector3d> before, f, g;
    bool has_last = false, carry = false;
  } anderson;
  // Per explicit finite-element cell: its rotation at the last iterate checked (cells_turned).
  std::vector<Eigen::Quaterniond> cell_fit;
  // The last step: global solves taken, and the largest residual nodal force (N) at its end.
  int iterations = 0;
  double residual_force = 0.0;

  ImplicitSystem() = default;
  // A copy refactorises on its first step rather than share a factor that its original may
  // replace (a new dt) while the copy runs on another thread.
  ImplicitSystem(const ImplicitSystem&) {}
  ImplicitSystem& operator=(const ImplicitSystem&) {
    *this = ImplicitSystem();
    return *this;
  }
  ImplicitSystem(ImplicitSystem&&) = default;
  ImplicitSystem& operator=(ImplicitSystem&&) = default;
};

// Node i's value of a field into its free axes' unknowns (added).
inline void gather_node(const ImplicitSystem& s, int i, const Eigen::Vector3d& value,
                        std::array<Eigen::VectorXd, 3>& out) {
  for (int a = 0; a < 3; ++a)
    if (const int u = s.unknown[size_t(a)][size_t(i)]; u >= 0) out[size_t(a)][u] += value[a];
}

// Whether node i has an unknown on any axis (the solve moves it).
inline bool moves(const ImplicitSystem& s, int i) {
  return s.unknown[0][size_t(i)] >= 0 || s.unknown[1][size_t(i)] >= 0 ||
         s.unknown[2][size_t(i)] >= 0;
}

// A node's value of a field over its unknowns (0 on held axes).
inline Eigen::Vector3d node_value(const ImplicitSystem& s,
                                  const std::array<Eigen::VectorXd, 3>& field, int i) {
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int a = 0; a < 3; ++a)
    if (const int u = s.unknown[size_t(a)][size_t(i)]; u >= 0) v[a] = field[size_t(a)][u];
  return v;
}

}  // namespace phymul

#include "phymul/simulator.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <cmath>
#include <limits>

#include "constraints/constraints.hpp"
#include "constraints/contact.hpp"
#include "constraints/coupled_volume.hpp"
#include "constraints/deformable_contact.hpp"
#include "constraints/doubled.hpp"
#include "forces/explicit_fem.hpp"
#include "forces/forces.hpp"
#include "model/state_fields.hpp"
#include "phymul/thread_team.hpp"
#include "solver/rigid.hpp"
#include "solver/runaway_guard.hpp"

namespace phymul {
namespace {

// Below this many nodes a thread team costs more than a per-node loop saves.
constexpr int kParallelFrom = 4096;

Vec3 free_axes(const Vec3& inverse_mass) {
  return (inverse_mass.array() > 0.0).cast<double>().matrix();
}

// a b + c, rounded once where the target has fused multiply-adds: spelled out, so that a
// loop's vector body and its scalar remainder round alike (GCC contracts each expression as
// it sees fit, and the thread count moves the remainders' bounds).
[[gnu::always_inline]] inline double mul_add(double a, double b, double c) {
#if defined(__FMA__)
  return std::fma(a, b, c);
#else
  return a * b + c;
#endif
}

// W f - c v, the damping on the free axes only.
// (A select rather than free_axes' product by 0 or 1: the same numbers but for the sign of a
// zero on a held axis, in a few instructions instead of conversions.)
[[gnu::always_inline]] inline double acceleration(double inverse_mass, double f, double v,
                                                  double c) {
  return mul_add(inverse_mass, f, -(c * (inverse_mass > 0.0 ? v : 0.0)));
}

// x + h (v + h/2 a), the drift with its half kick.
[[gnu::always_inline]] inline double drifted(double x, double v, double a, double h) {
  return mul_add(h, mul_add(0.5 * h, a, v), x);
}

[[gnu::always_inline]] inline Vec3 acceleration(const Vec3& inverse_mass, const Vec3& f,
                                                const Vec3& v, double c) {
  Vec3 a;
  for (int k = 0; k < 3; ++k) a[k] = acceleration(inverse_mass[k], f[k], v[k], c);
  return a;
}

// The node arrays as 3 n doubles: the per-node loops below act coordinate by coordinate, and
// over a flat array the compiler fills whole vector registers (four coordinates of 4/3 nodes)
// instead of one node's three.
double* flat(std::vector<Vec3>& p) { return p.data()->data(); }
const double* flat(const std::vector<Vec3>& p) { return p.data()->data(); }

double bounding_diagonal(const std::vector<Vec3>& p) {
  if (p.empty()) return 1.0;
  const auto [lo, hi] = bounding_box(p);
  return std::max((hi - lo).norm(), 1e-12);
}

int component_of(const Model& model, int node) {
  for (int c = 0; c < int(model.components.size()); ++c) {
    const std::vector<int>& nodes = model.components[c].nodes;
    if (std::find(nodes.begin(), nodes.end(), node) != nodes.end()) return c;
  }
  return -1;
}

}  // namespace

Simulator::Simulator(Model model) : model_(std::move(model)) {
  if (model_.inverse_mass.size() != model_.rest_position.size()) finalize(model_);
  state_ = make_state(model_);
  drift_rigid_bodies(model_, state_, 0.0, 0.0);  // driven bodies at their t = 0 pose
  const size_t n = model_.rest_position.size();
  x_start_.assign(n, Vec3::Zero());
  v_start_.assign(n, Vec3::Zero());
  if (model_.settings.integrator == Integrator::newton_cotes)  // only it needs them
    a1_.assign(n, Vec3::Zero());
  f_start_.assign(n, Vec3::Zero());
  if (model_.settings.integrator == Integrator::newton_cotes)  // see accelerations()
    scratch_.assign(n, Vec3::Zero());
  if (!model_.obstacles.empty()) contacts_.reserve(size_t(n) * model_.obstacles.size());
  contact_impulse_.assign(model_.obstacles.size(), Vec3::Zero());
  pair_impulse_.assign(model_.contact_pairs.size(), Vec3::Zero());
  if (!model_.contact_pairs.empty()) {
    deformable_ = std::make_shared<DeformableContactWorkspace>();
    deformable_->prepare(model_);
  }
  size_scale_ = bounding_diagonal(model_.rest_position);
  shortest_edge_ = runaway_edges(model_);
  shortest_edge_overall_ = shortest_edge_.empty() ? std::numeric_limits<double>::infinity()
                                                  : std::ranges::min(shortest_edge_);
  if (model_.settings.mode == SolveMode::static_equilibrium &&
      model_.settings.relaxation_mass_scaling)
    scale_masses_for_relaxation();
  const bool scaled = model_.settings.mode == SolveMode::dynamic && model_.settings.mass_scaling_dt;
  if (scaled) scale_masses_to(*model_.settings.mass_scaling_dt);
  // Dynamics take the inertias the steps use; static relaxation's fictitious ones are not.
  const double stable =
      model_.settings.dt_estimate == DtEstimate::power
          ? verlet_stable_step(highest_frequency(model_, state_, inertia()).omega(), model_.damping)
          : stable_time_step(model_, scaled ? inertia() : model_.mass);
  stable_dt_ = stable;
  model_.coupled_factor_valid = false;  // kept by another simulator, for other inertias
  dt_ = model_.settings.dt ? *model_.settings.dt : model_.settings.dt_safety * stable;
  if (!std::isfinite(dt_)) dt_ = 1e-3;  // no stiffness at all: any step is stable
  apply_position_constraints(model_, state_.x, 0.0, f_start_);  // free between steps
  compute_forces(model_, state_, 0.0);
  release_free_memory();
}

// Building a model (meshes, adjacency, sorting) frees about half as much as the model and
// the simulator keep, and the allocator keeps those holes resident for the whole run: a
// fifth of the memory of a large model. Giving their pages back costs a few microseconds.
void Simulator::release_free_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

// Static equilibrium does not depend on the masses; the time to reach it by pseudo-dynamics
// does. Lumped masses make corner and edge nodes 8 and 4 times lighter than interior ones
// while their stiffness is about the same: they alone set the stable step. Masses
// proportional to each node's stiffness row give every node the largest frequency, so the
// step stays and the slow modes speed up (Underwood's dynamic relaxation). Gravity keeps
// the true masses (Model::mass).
void Simulator::scale_masses_for_relaxation() {
  inertia_ = model_.mass;
  const std::vector<double> row = stiffness_row_sums(model_);
  double omega2 = 0.0;
  for (int i = 0; i < model_.node_count(); ++i) omega2 = std::max(omega2, row[i] / inertia_[i]);
  if (omega2 == 0.0) return;
  for (int i = 0; i < model_.node_count(); ++i) {
    // No stiffness, or nothing free to move (held, rigid): keeps its mass.
    if (row[i] == 0.0 || model_.inverse_mass[i] == Vec3::Zero()) continue;
    give_inertia(i, row[i] / omega2);
  }
}

// The node's inertia_ and the inverse mass of its free axes (held axes stay held).
void Simulator::give_inertia(int i, double inertia) {
  inertia_[size_t(i)] = inertia;
  for (int a = 0; a < 3; ++a)
    if (model_.inverse_mass[i][a] != 0.0) model_.inverse_mass[i][a] = 1.0 / inertia;
}

// Explicit FEM's mass scaling: the few light nodes that alone set the stable step (the
// corners of a mapped grid, 8 times lighter than interior nodes) get the inertia that lifts
// their Gershgorin limit to `target`. Gravity keeps the true masses (Model::mass), so
// equilibria do not change; the dynamics of those nodes are slowed (added_inertia() says
// by how much mass).
void Simulator::scale_masses_to(double target) {
  const std::vector<double> row = stiffness_row_sums(model_);
  inertia_ = model_.mass;
  bool scaled = false;
  for (int i = 0; i < model_.node_count(); ++i) {
    const double needed = row[i] * target * target / 4.0;  // 2 / sqrt(row / m) = target
    if (!(needed > inertia_[size_t(i)])) continue;
    give_inertia(i, needed);
    scaled = true;
  }
  if (!scaled) inertia_.clear();  // empty: the masses
}

double Simulator::added_inertia() const {
  double added = 0.0;
  for (size_t i = 0; i < inertia_.size(); ++i) added += inertia_[i] - model_.mass[i];
  return added;
}

void Simulator::step() {
  const double time = state_.time, previous_load = load_time_, load_time = state_.time + dt_;
  if (model_.settings.integrator == Integrator::verlet)
    step_verlet(dt_, load_time);
  else
    step_newton_cotes(dt_, load_time);
  state_.time = load_time;
  ++state_.step;
  checked_step(time, previous_load);
}

void Simulator::checked_step(double time, double previous_load) {
  try {
    check_stability();
  } catch (const InstabilityError&) {
    // Back to the last good state (both schemes keep x and v from before the step), so
    // that the run can write it.
    for (int i = 0; i < model_.node_count(); ++i)
      state_.x[i] = x_start_[i], state_.v[i] = v_start_[i];
    for (Eigen::Quaterniond& q : state_.rotation)
      if (!q.coeffs().allFinite()) q = Eigen::Quaterniond::Identity();
    state_.time = time;
    --state_.step;
    compute_forces(model_, state_, previous_load);
    load_time_ = previous_load;
    throw;
  }
}

// Velocity Verlet; the constraint projection enters the half-step velocity as the
// correction over dt (the reaction of the constraint).
void Simulator::step_verlet(double h, double load_time) {
  State& s = state_;
  drift(h);  // the first half kick too
  drift_rigid_bodies(model_, s, h, load_time);
  ContactStep contact = begin_contact_step(h);
  apply_position_constraints(model_, s.x, load_time, f_start_, contact);  // a is spent
  // The forces read the positions only: the velocities can wait for the half kick.
  compute_forces(model_, s, load_time);
  load_time_ = load_time;
  // The velocity projection below is linear: projecting the sum makes the kick tangent too.
  half_kick_from_positions(h);
  apply_contact_velocities(model_, s.x, s.v, load_time, contact);
  project_volume_velocities(model_, s.x, s.v, f_start_);  // a is spent
  project_doubled(model_, s.v);
  kick_rigid_bodies(model_, s, h);
  end_contact_step(h);
}

// The contact stages' bookkeeping; the shape's motion over the step runs from the load time
// of the current forces (load_time_) to the new one.
ContactStep Simulator::begin_contact_step(double dt) {
  std::fill(state_.obstacle_touching.begin(), state_.obstacle_touching.end(), -1);
  std::fill(contact_impulse_.begin(), contact_impulse_.end(), Vec3::Zero());
  std::fill(pair_impulse_.begin(), pair_impulse_.end(), Vec3::Zero());
  return ContactStep{x_start_,
                     load_time_,
                     dt,
                     state_.obstacle_touching,
                     contact_impulse_,
                     deformable_.get(),
                     &state_.pair_contacts,
                     pair_impulse_};
}

// Impulse over the step: the position stage's m dx / dt plus the velocity stage's m dv. At
// rest on a surface both are m a dt / 2, so this is the static reaction exactly, and during
// dynamics it is the mean contact force over the step (momentum balance).
void Simulator::end_contact_step(double dt) {
  for (size_t k = 0; k < contact_impulse_.size(); ++k)
    state_.contact_force[k] = contact_impulse_[k] / dt;
  for (size_t k = 0; k < pair_impulse_.size(); ++k)
    state_.pair_contact_force[k] = pair_impulse_[k] / dt;
}

// Without their part along the volume gradients (the pressure the projection would undo
// anyway), accelerations keep the drift on the constraint: the projection then corrects only
// second-order terms, and relaxation converges instead of stalling on that round trip.
void Simulator::accelerations(std::vector<Vec3>& a, std::span<Vec3> volume_scratch) {
  const double c = model_.damping;
  const int n = model_.node_count();
  for_each_index(n, team_pays(n, kParallelFrom), [&](int i) {
    a[i] = acceleration(model_.inverse_mass[i], state_.f[i], state_.v[i], c);
  });
  if (!volume_scratch.empty()) project_volume_velocities(model_, state_.x, a, volume_scratch);
  project_doubled(model_, a);
}

// Whether the nodes whose accelerations the constraints change are a good part of the
// model (a volume's surface around few interior nodes, as the prostate study's).
static bool mostly_constrained(const Model& model) {
  size_t constrained = 0;
  for (const VolumeConstraint& vc : model.volumes) constrained += vc.nodes.size();
  for (int g = 0; g < model.doubled.rows(); ++g) constrained += model.doubled.row(g).size();
  return 4 * constrained >= size_t(model.node_count());
}

// The first half kick and the drift, x += h (v + h/2 a), in one pass over the nodes. The
// nodes whose accelerations the constraints change (volume surfaces, doubled groups) get
// them projected first, and are moved again after the pass by the same expression (or, where
// they are most nodes, all accelerations are projected first). Rigid bodies are kicked first:
// their nodes' accelerations are zero (no free axis).
void Simulator::drift(double h) {
  State& s = state_;
  const int n = model_.node_count();
  const double c = model_.damping;
  const bool team = team_pays(n, kParallelFrom);
  kick_rigid_bodies(model_, s, h);
  if (mostly_constrained(model_)) {  // every acceleration once, projected, one moving pass
    {
      double* __restrict a = flat(f_start_);
      const double *__restrict v = flat(s.v), *__restrict f = flat(s.f),
                   *__restrict w = flat(model_.inverse_mass);
      for_each_lane(3 * n, team, [=](int e) { a[e] = acceleration(w[e], f[e], v[e], c); });
    }
    if (!model_.volumes.empty()) project_volume_velocities(model_, s.x, f_start_, x_start_);
    project_doubled(model_, f_start_);
    double* __restrict x = flat(s.x), * __restrict x0 = flat(x_start_), * __restrict v0 = flat(v_start_);
    const double* __restrict v = flat(s.v), * __restrict a = flat(f_start_);
    for_each_lane(3 * n, team, [=](int e) {
      x0[e] = x[e];
      v0[e] = v[e];  // the last good state, if the step fails its checks
      x[e] = drifted(x[e], v[e], a[e], h);
    });
    return;
  }
  auto constrained_accelerations = [&](std::span<const int> nodes) {
    const int m = int(nodes.size());
    for_each_index(m, team_pays(m, kParallelFrom), [&](int k) {
      const int i = nodes[size_t(k)];
      f_start_[i] = acceleration(model_.inverse_mass[i], s.f[i], s.v[i], c);
    });
  };
  for (const VolumeConstraint& vc : model_.volumes) constrained_accelerations(vc.nodes);
  for (int g = 0; g < model_.doubled.rows(); ++g) constrained_accelerations(model_.doubled.row(g));
  if (!model_.volumes.empty()) project_volume_velocities(model_, s.x, f_start_, x_start_);
  project_doubled(model_, f_start_);
  // Plain pointers: the vectors' own would be reloaded after every store.
  {
    double* __restrict x = flat(s.x), * __restrict x0 = flat(x_start_), * __restrict v0 = flat(v_start_);
    const double* __restrict v = flat(s.v), * __restrict f = flat(s.f), * __restrict w = flat(model_.inverse_mass);
    for_each_lane(3 * n, team, [=](int e) {
      x0[e] = x[e];
      v0[e] = v[e];  // the last good state, if the step fails its checks
      x[e] = drifted(x[e], v[e], acceleration(w[e], f[e], v[e], c), h);
    });
  }
  auto move_again = [&](std::span<const int> nodes) {
    const int m = int(nodes.size());
    for_each_index(m, team_pays(m, kParallelFrom), [&](int k) {
      const int i = nodes[size_t(k)];
      s.x[i] = x_start_[i] + h * (v_start_[i] + 0.5 * h * f_start_[i]);
    });
  };
  for (const VolumeConstraint& vc : model_.volumes) move_again(vc.nodes);
  for (int g = 0; g < model_.doubled.rows(); ++g) move_again(model_.doubled.row(g));
}

// v = (x - x_start) / h, then the half kick v += h/2 a(f, v), in one pass; doubled groups
// share their accelerations after it and are kicked again by the same expression.
void Simulator::half_kick_from_positions(double h) {
  State& s = state_;
  const int n = model_.node_count();
  const double c = model_.damping;
  {
    double* __restrict v = flat(s.v);
    const double *__restrict x = flat(s.x), *__restrict x0 = flat(x_start_),
                 *__restrict f = flat(s.f), *__restrict w = flat(model_.inverse_mass);
    for_each_lane(3 * n, team_pays(n, kParallelFrom), [=](int e) {
      const double moved = (x[e] - x0[e]) / h;
      v[e] = mul_add(0.5 * h, acceleration(w[e], f[e], moved, c), moved);
    });
  }
  if (model_.doubled.rows() == 0) return;
  Vec3* __restrict v = s.v.data();
  const Vec3 *__restrict x = s.x.data(), *__restrict x0 = x_start_.data(),
             *__restrict f = s.f.data(), *__restrict w = model_.inverse_mass.data();
  for (int g = 0; g < model_.doubled.rows(); ++g)
    for (int i : model_.doubled.row(g))
      f_start_[i] = acceleration(w[i], f[i], (x[i] - x0[i]) / h, c);
  project_doubled(model_, f_start_);
  for (int g = 0; g < model_.doubled.rows(); ++g)
    for (int i : model_.doubled.row(g)) v[i] = (x[i] - x0[i]) / h + 0.5 * h * f_start_[i];
}

// The paper's Newton-Cotes family: an Euler predictor, then the trapezoid rule on the
// accelerations at both ends (second order).
void Simulator::step_newton_cotes(double h, double load_time) {
  State& s = state_;
  const int n = model_.node_count();
  std::vector<Vec3>& a0 = f_start_;
  accelerations(a0, x_start_);  // x_start_ is filled below
  // Rigid bodies take the velocity Verlet splitting whatever the scheme: kick, drift here,
  // the second kick at the end with the forces at the new positions.
  kick_rigid_bodies(model_, s, h);
  for (int i = 0; i < n; ++i) {
    x_start_[i] = s.x[i];
    v_start_[i] = s.v[i];
    s.x[i] += h * s.v[i];
    s.v[i] += h * a0[i];
  }
  drift_rigid_bodies(model_, s, h, load_time);
  apply_prescribed(model_, s.x, load_time);
  compute_forces(model_, s, load_time);
  accelerations(a1_, scratch_);  // every other node-sized buffer is in use here
  for (int i = 0; i < n; ++i) {
    s.v[i] = v_start_[i] + 0.5 * h * (a0[i] + a1_[i]);
    s.x[i] = x_start_[i] + 0.5 * h * (v_start_[i] + s.v[i]);
    a1_[i] = s.x[i];  // spent: keep the unconstrained position instead
  }
  place_rigid_nodes(model_, s);
  ContactStep contact = begin_contact_step(h);
  apply_position_constraints(model_, s.x, load_time, f_start_, contact);  // a0 is spent
  for (int i = 0; i < n; ++i) s.v[i] += (s.x[i] - a1_[i]) / h;
  apply_contact_velocities(model_, s.x, s.v, load_time, contact);
  project_volume_velocities(model_, s.x, s.v, f_start_);
  project_doubled(model_, s.v);
  end_contact_step(h);
  compute_forces(model_, s, load_time);
  kick_rigid_bodies(model_, s, h);
  load_time_ = load_time;
}

InstabilityError Simulator::non_finite_energy() const {
  const State& s = state_;
  for (const ExplicitFem& fem : model_.explicit_fem) {
    const InvertedCell bad = first_inverted_cell(fem, model_.rest_position, s.x);
    if (bad.cell < 0) continue;
    return InstabilityError(
        fmt::format("the simulation stopped at t = {:.6g} s (step {}): a finite-element cell of "
                    "component '{}' is inverted (J = det F = {:.3g} at its centre; corners: "
                    "nodes {}). A node was pushed through the opposite side of its cell. Lower "
                    "or slow the load, refine the mesh there, take a smaller dt if the motion is "
                    "fast (dt {:.3g} s, stability estimate {:.3g} s), or use the shape-memory "
                    "model, which has no inverted state.",
                    s.time, s.step, fem.component, bad.J, fmt::join(bad.nodes, ", "), dt_,
                    stable_dt_),
        bad.nodes[0], s.time);
  }
  return InstabilityError(
      fmt::format("the simulation became unstable at t = {:.6g} s (step {}): the elastic energy "
                  "is not finite while every node is. Set simulation.dt smaller (now {:.3g} s, "
                  "stability estimate {:.3g} s) or check the stiffness and masses.",
                  s.time, s.step, dt_, stable_dt_),
      -1, s.time);
}

void Simulator::check_stability() const {
  const State& s = state_;
  auto unstable = [&](int i, const std::string& what) {
    const int c = component_of(model_, i);
    return InstabilityError(
        fmt::format("the simulation became unstable at t = {:.6g} s (step {}): node {} of "
                    "component '{}' {}. The time step is {:.3g} s and the stability estimate "
                    "is {:.3g} s: set simulation.dt smaller (or 'auto' with dt_safety below "
                    "0.5), add damping, or check the stiffness and masses.",
                    s.time, s.step, i, c >= 0 ? model_.components[c].name : "?", what, dt_,
                    stable_dt_),
        i, s.time);
  };
  const int n = model_.node_count();
  // A parallel look first, coordinate by coordinate over the flat arrays (whole vector
  // registers), without branches or square roots: every node passes when each coordinate of
  // its distance from rest, squared, is below a third of (1 - 1e-9) of the squared bound, and
  // each of its speed's below 1e150 (the squared speed is then finite; NaN fails every
  // comparison). The first bad node is then found in order by the exact test. In the same
  // pass, the runaway guard's first look: three times the largest squared coordinate step
  // bounds every node's squared step.
  const double bound = 10.0 * size_scale_, surely = (1.0 - 1e-9) * bound * bound / 3.0;
  constexpr double kFastest = 1e150;
  const double *__restrict x = flat(s.x), *__restrict v = flat(s.v),
               *__restrict rest = flat(model_.rest_position), *__restrict x0 = flat(x_start_);
  double largest_coordinate_step2 = 0.0;
  int doubtful = 0;
  // (Values, not references to the reductions: those would keep the loop out of the lanes.)
  auto step2 = [=](int e) { return (x[e] - x0[e]) * (x[e] - x0[e]); };
  auto bad = [=](int e) {
    const double moved = x[e] - rest[e];
    return int(!(moved * moved < surely)) | int(!(std::abs(v[e]) < kFastest));
  };
  if (team_pays(n, kParallelFrom)) {
    // clang-format off
#pragma omp parallel for simd schedule(static) firstprivate(step2, bad) \
    reduction(| : doubtful) reduction(max : largest_coordinate_step2)
    // clang-format on
    for (int e = 0; e < 3 * n; ++e)
      largest_coordinate_step2 = std::max(largest_coordinate_step2, step2(e)), doubtful |= bad(e);
  } else {
#pragma omp simd reduction(| : doubtful) reduction(max : largest_coordinate_step2)
    for (int e = 0; e < 3 * n; ++e)
      largest_coordinate_step2 = std::max(largest_coordinate_step2, step2(e)), doubtful |= bad(e);
  }
  const double largest_step2 = 3.0 * largest_coordinate_step2;
  const bool all_well = doubtful == 0;
  for (int i = 0; i < n && !all_well; ++i) {
    const double moved = (s.x[i] - model_.rest_position[i]).norm();
    const bool finite = std::isfinite(moved) && s.v[i].allFinite();
    if (finite && moved <= 10.0 * size_scale_) continue;
    throw unstable(
        i, finite ? fmt::format("moved {:.3g} m, more than 10 times the model's size ({:.3g} m)",
                                moved, size_scale_)
                  : std::string("has a non-finite position or velocity"));
  }
  // An inverted finite element leaves its nodes finite; its energy is the alarm.
  if (!std::isfinite(s.shape_memory_energy)) throw non_finite_energy();
  if (steps_surely_within_bound(largest_step2, shortest_edge_overall_)) return;
  if (const auto r = find_runaway(model_, shortest_edge_, x_start_, s.x))
    throw unstable(r->node,
                   fmt::format("moved {:.3g} m against its neighbours in one step, more than "
                               "{:g} of its shortest rest edge ({:.3g} m): a runaway, caught "
                               "before any number overflowed",
                               r->moved, kRunawayFraction, r->edge));
}

double Simulator::kinetic_energy() const {
  double e = 0.0;
  const std::vector<double>& inertia = this->inertia();
  for (int i = 0; i < model_.node_count(); ++i) e += 0.5 * inertia[i] * state_.v[i].squaredNorm();
  return e;
}

constexpr double kTouching = 1e-12;  // m, as obstacle_force counts contact

double Simulator::max_residual_force() {
  // f_start_ holds the residual and x_start_ the volume gradients: both free between steps.
  std::vector<Vec3>& r = f_start_;
  for (int i = 0; i < model_.node_count(); ++i)
    r[i] = state_.f[i].cwiseProduct(free_axes(model_.inverse_mass[i]));
  gather_doubled(model_, r);
  find_obstacle_contacts();
  remove_volume_pressures(r, x_start_, /*on_free_axes=*/true, contacts_);
  remove_contact_forces(r);
  add_deformable_contact_forces(state_.pair_contacts, dt_, r);
  double largest = 0.0;
  for (int i = 0; i < model_.node_count(); ++i) largest = std::max(largest, r[i].norm());
  return std::max(largest, rigid_residual(model_, state_));
}

// Takes out of r the part each volume constraint balances: its pressure, the least-squares
// multiplier of its gradient against r on the free axes. Removed along the free part of the
// gradient (residual) or the whole gradient (support reactions, which then carry the held
// part). Surfaces sharing nodes: Gauss-Seidel sweeps until what is left to take out is far
// below the tolerance (one pass is exact for disjoint ones).
void Simulator::remove_volume_pressures(std::vector<Vec3>& r, std::vector<Vec3>& grad,
                                        bool on_free_axes,
                                        std::span<const ObstacleContact> contact) const {
  if (model_.coupled_volumes &&
      remove_coupled_volume_pressures(model_, state_.x, r, grad, on_free_axes, contact))
    return;  // all pressures at once
  const int sweeps = model_.coupled_volumes ? 200 : 1;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    double largest_change = 0.0;
    for (const VolumeConstraint& c : model_.volumes) {
      volume_gradient(c, state_.x, grad);
      double rg = 0.0, gg = 0.0, longest = 0.0;
      for (int i : c.nodes) {
        const Vec3 free_grad = grad[i].cwiseProduct(free_axes(model_.inverse_mass[i]));
        if (on_free_axes) grad[i] = free_grad;
        rg += r[i].dot(free_grad);
        gg += free_grad.squaredNorm();
        longest = std::max(longest, grad[i].norm());
      }
      // Against an obstacle a node's push along the contact normal is the contact's to
      // balance, whatever its size: only its tangential part tells the pressure.
      for (const auto& [i, n, friction] : contact) {
        const Vec3 free_grad = grad[i].cwiseProduct(free_axes(model_.inverse_mass[i]));
        rg -= r[i].dot(n) * free_grad.dot(n);
        gg -= free_grad.dot(n) * free_grad.dot(n);
      }
      if (gg == 0.0) continue;
      const double pressure = rg / gg;
      for (int i : c.nodes) r[i] -= pressure * grad[i];
      largest_change = std::max(largest_change, std::abs(pressure) * longest);
    }
    if (largest_change <= 1e-3 * model_.settings.tolerance) break;
  }
}

// Touching: on the surface, or put on it by the last step's contact stage (the volume
// projection after it may have moved the node off by a hair).
void Simulator::find_obstacle_contacts() {
  contacts_.clear();
  for (const RigidObstacle& o : model_.obstacles) {
    auto add = [&](int i) {
      const SurfaceDistance d = obstacle_distance(o, state_.x[i], load_time_);
      const bool moved = state_.obstacle_touching[size_t(i)] == int(&o - model_.obstacles.data());
      if (std::abs(d.distance) > kTouching && !moved) return;
      contacts_.push_back({i, o.keep_inside ? Vec3(-d.normal) : d.normal, o.friction});
    };
    if (o.nodes.empty())
      for (int i = 0; i < model_.node_count(); ++i) add(i);
    else
      for (int i : o.nodes) add(i);
  }
}

// A node touching an obstacle can be pushed into it with any force: that part of its
// residual is the contact's reaction, not an imbalance.
void Simulator::remove_contact_forces(std::vector<Vec3>& r) const {
  for (const auto& [i, push, friction] : contacts_) {
    const double into = r[i].dot(push);
    if (into >= 0.0) continue;
    r[i] -= into * push;
    // Friction holds a tangential force up to mu times the normal one.
    const double tangential = r[i].norm(), bound = -friction * into;
    if (tangential > 0.0) r[i] *= tangential <= bound ? 0.0 : (tangential - bound) / tangential;
  }
}

std::vector<Vec3> Simulator::support_reactions() const {
  // Each volume constraint carries a pressure: the least-squares multiplier of its gradient
  // against the forces on the free axes (what max_residual_force takes out).
  std::vector<Vec3> reaction(state_.f);
  std::vector<Vec3> grad(state_.x.size(), Vec3::Zero());
  remove_volume_pressures(reaction, grad, /*on_free_axes=*/false);
  for (int i = 0; i < model_.node_count(); ++i) {
    const Vec3 held = Vec3::Ones() - free_axes(model_.inverse_mass[i]);
    reaction[i] = -reaction[i].cwiseProduct(held);
  }
  // A free rigid body is held by nothing: its nodes' forces move it.
  for (const RigidBody& body : model_.rigid_bodies)
    if (!body.driven)
      for (int i : body.nodes) reaction[i].setZero();
  return reaction;
}

std::vector<double> Simulator::component_volumes() const {
  std::vector<double> v;
  for (const Component& c : model_.components)
    v.push_back(c.boundary.empty() ? std::nan("") : enclosed_volume(state_.x, c.boundary));
  return v;
}

StaticResult Simulator::relax(double load_time, long max_iterations,
                              const std::function<void(long, double)>& progress, double tolerance) {
  static_progress_.step_iterations = 0;
  static_progress_.previous_kinetic = 0.0;
  static_progress_.fire_alpha = StaticProgress{}.fire_alpha;
  static_progress_.fire_downhill = 0;
  drift_rigid_bodies(model_, state_, 0.0, load_time);  // driven bodies at their new pose
  apply_position_constraints(model_, state_.x, load_time, f_start_);  // free between steps
  compute_forces(model_, state_, load_time);
  load_time_ = load_time;
  return continue_relax(load_time, max_iterations, progress, tolerance);
}

StaticResult Simulator::continue_relax(double load_time, long max_iterations,
                                       const std::function<void(long, double)>& progress,
                                       double tolerance) {
  StaticProgress& p = static_progress_;
  StaticResult result;
  for (;;) {
    result.residual = max_residual_force();
    if (result.residual < tolerance) {
      result.converged = true;
      break;
    }
    if (p.step_iterations >= max_iterations) break;
    if (model_.settings.integrator == Integrator::verlet)
      step_verlet(dt_, load_time);
    else
      step_newton_cotes(dt_, load_time);
    ++p.step_iterations;
    ++state_.step;
    checked_step(state_.time, load_time);
    if (model_.settings.relaxation == Relaxation::fire) {
      fire_update(p);
    } else if (model_.settings.relaxation == Relaxation::kinetic) {
      // Dynamic relaxation: at a kinetic-energy peak the system is nearest its minimum
      // along the current motion, so restart from rest there.
      const double kinetic = kinetic_energy();
      if (kinetic < p.previous_kinetic) {
        for (Vec3& v : state_.v) v.setZero();
        stop_rigid_bodies(state_);
        p.previous_kinetic = 0.0;
      } else {
        p.previous_kinetic = kinetic;
      }
    }
    if (progress && p.step_iterations % 256 == 0) progress(p.step_iterations, result.residual);
  }
  result.iterations = p.step_iterations;
  state_.time = load_time;
  return result;
}

// FIRE (Bitzek et al. 2006) at the scene's dt: while the motion goes downhill (power
// P = f.v > 0) the velocity is turned towards the force, v <- (1 - alpha) v + alpha |v| f/|f|
// in the mass metric, alpha shrinking after five downhill steps; uphill it restarts from
// rest. The force is the tangent one (volume pressure removed), as the motion's. On the
// Truth Cube compression it takes 303 iterations at 8^3 and 759 at 16^3 where kinetic
// damping took 430 and 1,391.
void Simulator::fire_update(StaticProgress& fire) {
  std::vector<Vec3>&a = f_start_, &volume_scratch = x_start_;  // free between steps
  accelerations(a, volume_scratch);
  find_obstacle_contacts();
  remove_contact_forces(a);  // what pushes into an obstacle is not downhill
  const int n = model_.node_count();
  const std::vector<double>& inertia = this->inertia();
  double power = 0.0, vv = 0.0, aa = 0.0;
  for (int i = 0; i < n; ++i) {
    power += inertia[i] * a[i].dot(state_.v[i]);
    vv += inertia[i] * state_.v[i].squaredNorm();
    aa += inertia[i] * a[i].squaredNorm();
  }
  if (!(power > 0.0)) {
    for (Vec3& v : state_.v) v.setZero();
    stop_rigid_bodies(state_);
    fire.fire_alpha = StaticProgress{}.fire_alpha;
    fire.fire_downhill = 0;
    return;
  }
  const double alpha = fire.fire_alpha;
  const double keep = 1.0 - alpha, turn = aa > 0.0 ? alpha * std::sqrt(vv / aa) : 0.0;
  for_each_index(n, team_pays(n, kParallelFrom),
                 [&](int i) { state_.v[i] = keep * state_.v[i] + turn * a[i]; });
  if (++fire.fire_downhill > 5) fire.fire_alpha *= 0.99;
}

StaticResult Simulator::solve_static(const std::function<void(long, double)>& progress) {
  static_progress_ = StaticProgress{};
  return static_load_steps(progress);
}

StaticResult Simulator::resume_static(const std::function<void(long, double)>& progress) {
  return static_load_steps(progress);
}

// The load steps from static_progress_ on: the one under way continues where it stopped.
StaticResult Simulator::static_load_steps(const std::function<void(long, double)>& progress) {
  // Intermediate equilibria only guide the path: loosely relaxed, they serve as well.
  constexpr double kIntermediate = 1000.0;
  const SimulationSpec& s = model_.settings;
  StaticProgress& p = static_progress_;
  StaticResult total;
  const bool resuming = p.load_step > 0;
  if (!resuming) p.load_step = 1;
  for (bool first = true; p.load_step <= s.load_steps; ++p.load_step, first = false) {
    const double load_time = s.duration * double(p.load_step) / double(s.load_steps);
    const long budget = s.max_iterations - p.iterations;
    const double tolerance = p.load_step < s.load_steps ? kIntermediate * s.tolerance : s.tolerance;
    const StaticResult r = resuming && first
                               ? continue_relax(load_time, budget, progress, tolerance)
                               : relax(load_time, budget, progress, tolerance);
    p.iterations += r.iterations;
    p.step_iterations = 0;
    total.iterations = p.iterations;
    total.residual = r.residual;
    total.converged = r.converged;
    if (!r.converged) break;
    // Between load steps too: a run can stop (and checkpoint) there even when no load step
    // needs 256 iterations.
    if (progress && p.load_step < s.load_steps) progress(r.iterations, r.residual);
  }
  return total;
}

void Simulator::restore(const State& state, double load_time, const StaticProgress& progress) {
  const std::string mismatch = state_shape_mismatch(model_, state);
  if (!mismatch.empty())
    throw std::invalid_argument("restore: the state does not fit the model: " + mismatch);
  assign_state(state_, state);
  load_time_ = load_time;
  static_progress_ = progress;
}

}  // namespace phymul

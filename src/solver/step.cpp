// One explicit step (DESIGN 2.3): velocity Verlet or the paper's Newton-Cotes trapezoid, the
// constraints projected within it, then the stability checks.
#include "solver/step.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "constraints/constraints.hpp"
#include "constraints/contact.hpp"
#include "constraints/coupled_volume.hpp"
#include "constraints/doubled.hpp"
#include "forces/explicit_fem.hpp"
#include "model/thread_team.hpp"
#include "model/workspace.hpp"
#include "phymul/simulation.hpp"
#include "solver/implicit_step.hpp"
#include "solver/rigid.hpp"
#include "solver/runaway_guard.hpp"

namespace phymul {
namespace {

// Below this many nodes a thread team costs more than a per-node loop saves.
constexpr int kParallelFrom = 4096;

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
// (A select rather than a product by 0 or 1: the same numbers but for the sign of a zero on
// a held axis, in a few instructions instead of conversions.)
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

int component_of(const Model& model, int node) {
  for (int c = 0; c < int(model.components.size()); ++c) {
    const std::vector<int>& nodes = model.components[c].nodes;
    if (std::find(nodes.begin(), nodes.end(), node) != nodes.end()) return c;
  }
  return -1;
}

// The contact stages' bookkeeping; the shape's motion over the step runs from the load time
// of the current forces (d.load_time) to the new one.
ContactStep begin_contact_step(Data& d, double dt) {
  Workspace& work = *d.work;
  std::fill(d.obstacle_touching.begin(), d.obstacle_touching.end(), -1);
  std::fill(work.contact_impulse.begin(), work.contact_impulse.end(), Vec3::Zero());
  std::fill(work.pair_impulse.begin(), work.pair_impulse.end(), Vec3::Zero());
  return ContactStep{work.x_start,        d.load_time,          dt,
                     d.obstacle_touching, work.contact_impulse, &d.pair_contacts,
                     work.pair_impulse,   work.pair_pushed,     &d.needles};
}

// Impulse over the step: the position stage's m dx / dt plus the velocity stage's m dv. At
// rest on a surface both are m a dt / 2, so this is the static reaction exactly, and during
// dynamics it is the mean contact force over the step (momentum balance).
void end_contact_step(Data& d, double dt) {
  Workspace& work = *d.work;
  for (size_t k = 0; k < work.contact_impulse.size(); ++k)
    d.contact_force[k] = work.contact_impulse[k] / dt;
  for (size_t k = 0; k < work.pair_impulse.size(); ++k)
    d.pair_contact_force[k] = work.pair_impulse[k] / dt;
}

// Whether the nodes whose accelerations the constraints change are a good part of the
// model (a volume's surface around few interior nodes, as the prostate study's).
bool mostly_constrained(const Model& model) {
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
void drift(const Model& model, Data& d, double h) {
  Workspace& work = *d.work;
  Data& s = d;
  const int n = model.node_count();
  const double c = model.damping;
  const bool team = team_pays(n, kParallelFrom);
  kick_rigid_bodies(model, s, h);
  if (mostly_constrained(model)) {  // every acceleration once, projected, one moving pass
    {
      double* __restrict a = flat(work.f_start);
      const double *__restrict v = flat(s.v), *__restrict f = flat(s.f),
                   *__restrict w = flat(model.inverse_mass);
      for_each_lane(3 * n, team, [=](int e) { a[e] = acceleration(w[e], f[e], v[e], c); });
    }
    if (!model.volumes.empty())
      project_volume_velocities(model, work, s.x, work.f_start, work.x_start);
    project_doubled(model, work.f_start);
    double* __restrict x = flat(s.x), * __restrict x0 = flat(work.x_start), * __restrict v0 = flat(work.v_start);
    const double* __restrict v = flat(s.v), * __restrict a = flat(work.f_start);
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
      work.f_start[i] = acceleration(model.inverse_mass[i], s.f[i], s.v[i], c);
    });
  };
  for (const VolumeConstraint& vc : model.volumes) constrained_accelerations(vc.nodes);
  for (int g = 0; g < model.doubled.rows(); ++g) constrained_accelerations(model.doubled.row(g));
  if (!model.volumes.empty())
    project_volume_velocities(model, work, s.x, work.f_start, work.x_start);
  project_doubled(model, work.f_start);
  // Plain pointers: the vectors' own would be reloaded after every store.
  {
    double* __restrict x = flat(s.x), * __restrict x0 = flat(work.x_start), * __restrict v0 = flat(work.v_start);
    const double* __restrict v = flat(s.v), * __restrict f = flat(s.f), * __restrict w = flat(model.inverse_mass);
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
      s.x[i] = work.x_start[i] + h * (work.v_start[i] + 0.5 * h * work.f_start[i]);
    });
  };
  for (const VolumeConstraint& vc : model.volumes) move_again(vc.nodes);
  for (int g = 0; g < model.doubled.rows(); ++g) move_again(model.doubled.row(g));
}

// v = (x - x_start) / h, then the half kick v += h/2 a(f, v), in one pass; doubled groups
// share their accelerations after it and are kicked again by the same expression.
void half_kick_from_positions(const Model& model, Data& d, double h) {
  Workspace& work = *d.work;
  Data& s = d;
  const int n = model.node_count();
  const double c = model.damping;
  {
    double* __restrict v = flat(s.v);
    const double *__restrict x = flat(s.x), *__restrict x0 = flat(work.x_start),
                 *__restrict f = flat(s.f), *__restrict w = flat(model.inverse_mass);
    for_each_lane(3 * n, team_pays(n, kParallelFrom), [=](int e) {
      const double moved = (x[e] - x0[e]) / h;
      v[e] = mul_add(0.5 * h, acceleration(w[e], f[e], moved, c), moved);
    });
  }
  if (model.doubled.rows() == 0) return;
  Vec3* __restrict v = s.v.data();
  const Vec3 *__restrict x = s.x.data(), *__restrict x0 = work.x_start.data(),
             *__restrict f = s.f.data(), *__restrict w = model.inverse_mass.data();
  for (int g = 0; g < model.doubled.rows(); ++g)
    for (int i : model.doubled.row(g))
      work.f_start[i] = acceleration(w[i], f[i], (x[i] - x0[i]) / h, c);
  project_doubled(model, work.f_start);
  for (int g = 0; g < model.doubled.rows(); ++g)
    for (int i : model.doubled.row(g)) v[i] = (x[i] - x0[i]) / h + 0.5 * h * work.f_start[i];
}

InstabilityError non_finite_energy(const Model& model, const Data& d) {
  const Data& s = d;
  for (const ExplicitFem& fem : model.explicit_fem) {
    const InvertedCell bad = first_inverted_cell(fem, model.rest_position, s.x);
    if (bad.cell < 0) continue;
    return InstabilityError(
        fmt::format("the simulation stopped at t = {:.6g} s (step {}): a finite-element cell of "
                    "component '{}' is inverted (J = det F = {:.3g} at its centre; corners: "
                    "nodes {}). A node was pushed through the opposite side of its cell. Lower "
                    "or slow the load, refine the mesh there, take a smaller dt if the motion is "
                    "fast (dt {:.3g} s, stability estimate {:.3g} s), or use the shape-memory "
                    "model, which has no inverted state.",
                    s.time, s.step, fem.component, bad.J, fmt::join(bad.nodes, ", "), d.dt,
                    d.stable_dt),
        bad.nodes[0], s.time);
  }
  return InstabilityError(
      fmt::format("the simulation became unstable at t = {:.6g} s (step {}): the elastic energy "
                  "is not finite while every node is. Set simulation.dt smaller (now {:.3g} s, "
                  "stability estimate {:.3g} s) or check the stiffness and masses.",
                  s.time, s.step, d.dt, d.stable_dt),
      -1, s.time);
}

void check_stability(const Model& model, const Data& d) {
  const Workspace& work = *d.work;
  const Data& s = d;
  auto unstable = [&](int i, const std::string& what) {
    const int c = component_of(model, i);
    return InstabilityError(
        fmt::format("the simulation became unstable at t = {:.6g} s (step {}): node {} of "
                    "component '{}' {}. The time step is {:.3g} s and the stability estimate "
                    "is {:.3g} s: set simulation.dt smaller (or 'auto' with dt_safety below "
                    "0.5), add damping, or check the stiffness and masses.",
                    s.time, s.step, i, c >= 0 ? model.components[c].name : "?", what, d.dt,
                    d.stable_dt),
        i, s.time);
  };
  const int n = model.node_count();
  // A parallel look first, coordinate by coordinate over the flat arrays (whole vector
  // registers), without branches or square roots: every node passes when each coordinate of
  // its distance from rest, squared, is below a third of (1 - 1e-9) of the squared bound, and
  // each of its speed's below 1e150 (the squared speed is then finite; NaN fails every
  // comparison). The first bad node is then found in order by the exact test. In the same
  // pass, the runaway guard's first look: three times the largest squared coordinate step
  // bounds every node's squared step.
  const double bound = 10.0 * model.size_scale, surely = (1.0 - 1e-9) * bound * bound / 3.0;
  constexpr double kFastest = 1e150;
  const double* __restrict x = flat(s.x), * __restrict v = flat(s.v), * __restrict rest = flat(model.rest_position), * __restrict x0 = flat(work.x_start);
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
    const double moved = (s.x[i] - model.rest_position[i]).norm();
    const bool finite = std::isfinite(moved) && s.v[i].allFinite();
    if (finite && moved <= 10.0 * model.size_scale) continue;
    throw unstable(
        i, finite ? fmt::format("moved {:.3g} m, more than 10 times the model's size ({:.3g} m)",
                                moved, model.size_scale)
                  : std::string("has a non-finite position or velocity"));
  }
  // An inverted finite element leaves its nodes finite; its energy is the alarm.
  if (!std::isfinite(s.shape_memory_energy)) throw non_finite_energy(model, d);
  if (steps_surely_within_bound(largest_step2, model.shortest_runaway_edge)) return;
  if (const auto r = find_runaway(model, model.runaway_edge, work.x_start, s.x))
    throw unstable(r->node,
                   fmt::format("moved {:.3g} m against its neighbours in one step, more than "
                               "{:g} of its shortest rest edge ({:.3g} m): a runaway, caught "
                               "before any number overflowed",
                               r->moved, kRunawayFraction, r->edge));
}

}  // namespace

void throw_not_finalized() {
  throw std::invalid_argument(
      "the model changed after finalize (its settings, say): call finalize(model) again before "
      "making or stepping its data");
}

void checked_step(const Model& model, Data& d, double time, double previous_load) {
  Workspace& work = *d.work;
  try {
    check_stability(model, d);
  } catch (const InstabilityError&) {
    // Back to the last good state (both schemes keep x and v from before the step), so
    // that the run can write it.
    for (int i = 0; i < model.node_count(); ++i) d.x[i] = work.x_start[i], d.v[i] = work.v_start[i];
    for (Eigen::Quaterniond& q : d.rotation)
      if (!q.coeffs().allFinite()) q = Eigen::Quaterniond::Identity();
    d.time = time;
    --d.step;
    compute_forces(model, d, previous_load);
    d.load_time = previous_load;
    throw;
  }
}

// Without their part along the volume gradients (the pressure the projection would undo
// anyway), accelerations keep the drift on the constraint: the projection then corrects only
// second-order terms, and relaxation converges instead of stalling on that round trip.
void accelerations(const Model& model, Data& d, std::vector<Vec3>& a,
                   std::span<Vec3> volume_scratch) {
  Workspace& work = *d.work;
  const double c = model.damping;
  const int n = model.node_count();
  for_each_index(n, team_pays(n, kParallelFrom),
                 [&](int i) { a[i] = acceleration(model.inverse_mass[i], d.f[i], d.v[i], c); });
  if (!volume_scratch.empty()) project_volume_velocities(model, work, d.x, a, volume_scratch);
  project_doubled(model, a);
}

namespace {

// The contact's and the volumes' velocity stages, alternated until the contact changes no
// velocity above round-off: without the rounds a node on both never comes to rest there.
void constrain_velocities(const Model& model, Data& d, double load_time, ContactStep& contact,
                          std::span<Vec3> grad) {
  Workspace& work = *d.work;
  auto contact_stage = [&] {
    return apply_contact_velocities(model, d.controls, d.x, d.v, load_time, contact);
  };
  auto volume_stage = [&] { project_volume_velocities(model, work, d.x, d.v, grad); };
  contact_stage();
  volume_stage();
  if (model.volumes.empty() || (model.obstacles.empty() && model.contact_pairs.empty())) return;
  // Frictionless obstacles alone: the alternation's limit in one solve first, the resting
  // nodes' pushes taken out of the volumes' projection (about six rounds fewer a step).
  auto hold = [&] {
    return resting_on_obstacles(model, d.controls, d.x, d.v, load_time, contact, work.contacts) &&
           project_coupled_volume_velocities_held(model, work, d.x, d.v, work.contacts,
                                                  contact.touching, contact.impulse);
  };
  alternate_contact_and_volume(contact_stage, volume_stage,
                               model.coupled_volumes && model.contact_pairs.empty(), hold,
                               1e-12 /* m/s */);
}

}  // namespace

// Velocity Verlet; the constraint projection enters the half-step velocity as the
// correction over dt (the reaction of the constraint).
void step_verlet(const Model& model, Data& d, double h, double load_time) {
  Workspace& work = *d.work;
  Data& s = d;
  drift(model, d, h);  // the first half kick too
  drift_rigid_bodies(model, s, h, load_time);
  ContactStep contact = begin_contact_step(d, h);
  apply_position_constraints(model, s.controls, work, s.x, load_time, work.f_start,
                             contact);  // a is spent
  // The forces read the positions only: the velocities can wait for the half kick.
  compute_forces(model, s, load_time);
  d.load_time = load_time;
  // The velocity projection below is linear: projecting the sum makes the kick tangent too.
  half_kick_from_positions(model, d, h);
  constrain_velocities(model, d, load_time, contact, work.f_start);  // a is spent
  project_doubled(model, s.v);
  kick_rigid_bodies(model, s, h);
  end_contact_step(d, h);
}

// The paper's Newton-Cotes family: an Euler predictor, then the trapezoid rule on the
// accelerations at both ends (second order).
void step_newton_cotes(const Model& model, Data& d, double h, double load_time) {
  Workspace& work = *d.work;
  Data& s = d;
  const int n = model.node_count();
  std::vector<Vec3>& a0 = work.f_start;
  accelerations(model, d, a0, work.x_start);  // work.x_start is filled below
  // Rigid bodies take the velocity Verlet splitting whatever the scheme: kick, drift here,
  // the second kick at the end with the forces at the new positions.
  kick_rigid_bodies(model, s, h);
  for (int i = 0; i < n; ++i) {
    work.x_start[i] = s.x[i];
    work.v_start[i] = s.v[i];
    s.x[i] += h * s.v[i];
    s.v[i] += h * a0[i];
  }
  drift_rigid_bodies(model, s, h, load_time);
  apply_prescribed(model, s.x, load_time);
  compute_forces(model, s, load_time);
  accelerations(model, d, work.a1, work.scratch);  // every other node-sized buffer is in use here
  for (int i = 0; i < n; ++i) {
    s.v[i] = work.v_start[i] + 0.5 * h * (a0[i] + work.a1[i]);
    s.x[i] = work.x_start[i] + 0.5 * h * (work.v_start[i] + s.v[i]);
    work.a1[i] = s.x[i];  // spent: keep the unconstrained position instead
  }
  place_rigid_nodes(model, s);
  ContactStep contact = begin_contact_step(d, h);
  apply_position_constraints(model, s.controls, work, s.x, load_time, work.f_start,
                             contact);  // a0 is spent
  for (int i = 0; i < n; ++i) s.v[i] += (s.x[i] - work.a1[i]) / h;
  constrain_velocities(model, d, load_time, contact, work.f_start);
  project_doubled(model, s.v);
  end_contact_step(d, h);
  compute_forces(model, s, load_time);
  kick_rigid_bodies(model, s, h);
  d.load_time = load_time;
}

void step(const Model& model, Data& d) {
  if (!finalized(model)) throw_not_finalized();
  const double time = d.time, previous_load = d.load_time, load_time = d.time + d.dt;
  if (model.settings.integrator == Integrator::verlet)
    step_verlet(model, d, d.dt, load_time);
  else if (model.settings.integrator == Integrator::implicit)
    step_implicit(model, d, d.dt, load_time);
  else
    step_newton_cotes(model, d, d.dt, load_time);
  d.time = load_time;
  ++d.step;
  checked_step(model, d, time, previous_load);
}

}  // namespace phymul

// The prostate study: for each filling and probe, the equilibrium under gravity alone, then
// the equilibria as the probe pushes, measured on the prostate.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "io/obstacle_surface.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "phymul/studies/prostate.hpp"
#include "phymul/vtk.hpp"

namespace phymul::prostate {
namespace {

constexpr double kDuration = 1.0;        // s of load time in the static scenes
constexpr long kMaxIterations = 200000;  // per equilibrium

int component_index(const Model& model, const std::string& name) {
  for (size_t c = 0; c < model.components.size(); ++c)
    if (model.components[c].name == name) return int(c);
  throw std::logic_error("prostate study: no component " + name);
}

Model compile(const Options& o, const SceneSettings& s) {
  return compile_scene(
      parse_scene(scene_text(o, s),
                  fmt::format("prostate_{:.0f}mL_{}.yaml", s.filling * 1e6, probe_name(s.probe))));
}

// Area (m^2) of the pressed faces projected on the plane normal to the push (z), at rest:
// the pressure that adds up to a force F is F over it.
double pressed_area(const Model& model) {
  double area = 0.0;
  for (const Triangle& t : model.pressures.at(0).faces) {
    const Vec3& a = model.rest_position[size_t(t[0])];
    const Vec3 n =
        0.5 * (model.rest_position[size_t(t[1])] - a).cross(model.rest_position[size_t(t[2])] - a);
    area += -n.z();
  }
  return area;
}

// Force (N) of a pressure on its faces at the current positions.
Vec3 pressure_resultant(const Model& model, const Data& state, double load_time) {
  const PressureLoad& p = model.pressures.at(0);
  Vec3 f = Vec3::Zero();
  for (const Triangle& t : p.faces) {
    const Vec3& a = state.x[size_t(t[0])];
    f -= 0.5 * (state.x[size_t(t[1])] - a).cross(state.x[size_t(t[2])] - a);
  }
  return p.pressure.at(load_time).x() * f;
}

struct Measures {
  double height = 0.0;  // m, top to bottom node
  Vec3 centre = Vec3::Zero();
};

Measures measure(const Model& model, const std::vector<Vec3>& x) {
  const Component& p = model.components[size_t(component_index(model, "prostate"))];
  Measures m;
  m.height = x[size_t(p.node_sets.at("top").front())].z() -
             x[size_t(p.node_sets.at("bottom").front())].z();
  for (int i : p.nodes) m.centre += x[size_t(i)];
  m.centre /= double(p.nodes.size());
  return m;
}

// Upward force (N) of the probe on the organs, from their equilibrium: what the weights and
// the held nodes' reactions leave over (the probe is the only other thing touching them).
double probe_force_from_balance(const Simulator& sim) {
  const Model& model = sim.model();
  const std::vector<Vec3> reactions = sim.support_reactions();
  double f = 0.0;
  for (int i = 0; i < model.node_count(); ++i)
    f -= model.mass[size_t(i)] * model.gravity.z() + reactions[size_t(i)].z();
  return f;
}

// The rigid probe's axis height at which it just touches the prostate: every prostate node
// above its surface, one on it.
double touching_axis_height(const Model& model, const Data& state, double radius) {
  const Component& p = model.components[size_t(component_index(model, "prostate"))];
  double z = std::numeric_limits<double>::infinity();
  for (int i : p.nodes) {
    const Vec3& x = state.x[size_t(i)];
    if (std::abs(x.x()) < radius)
      z = std::min(z, x.z() - std::sqrt(radius * radius - x.x() * x.x()));
  }
  return z;
}

// Where the probe's force goes at an equilibrium (FillingResult). The prostate's nodes, the
// stitched ones included, are one body: its neck force is what balances the rest on it.
void force_paths(const Simulator& sim, FillingResult& r) {
  const Model& model = sim.model();
  const int prostate = component_index(model, "prostate");
  const Component& p = model.components[size_t(prostate)];
  const Component& b = model.components[size_t(component_index(model, "bladder"))];
  const std::vector<Vec3> reactions = sim.support_reactions();
  double weight = 0.0;
  for (int i : p.nodes) {
    weight += model.mass[size_t(i)] * model.gravity.z();
    r.hold_force += reactions[size_t(i)].z();
  }
  for (int i : b.nodes)
    if (std::find(p.nodes.begin(), p.nodes.end(), i) == p.nodes.end())
      r.top_node_force += reactions[size_t(i)].z();
  const std::vector<Vec3>& pair = sim.data().pair_contact_force;
  // the force the pair's second component exerted on its first
  if (!pair.empty())
    r.contact_force = model.contact_pairs[0].components[0] == prostate ? pair[0].z() : -pair[0].z();
  r.neck_force = -(weight + r.probe_force + r.hold_force + r.contact_force);
}

StaticResult relax_to(Simulator& sim, double load_time) {
  // The scene's own cap where lower (the implicit static solver's hundred steps).
  const StaticResult r =
      sim.relax(load_time, std::min(kMaxIterations, sim.model().settings.max_iterations));
  if (!r.converged)
    throw std::runtime_error(fmt::format(
        "prostate study: no equilibrium at load time {:.3g} s after {} iterations (residual "
        "{:.3g} N above the tolerance {:.3g} N)",
        load_time, r.iterations, r.residual, sim.model().settings.tolerance));
  return r;
}

// The rigid probe at each equilibrium, beside its frame (<name>_obstacles_<k>.vtu), so that
// the pictures show it.
void write_obstacles(const std::filesystem::path& dir, const std::string& name, const Model& model,
                     const Frames& frames) {
  for (size_t k = 0; k < frames.size() && !model.obstacles.empty(); ++k)
    write_obstacle_surfaces(dir / fmt::format("{}_obstacles_{}.vtu", name, k), model.obstacles, {},
                            frames[k].time, frames[k].x);
}

// The scene, and every equilibrium as a .vtu of the series <name>.pvd (time: load time).
void write_run(const std::filesystem::path& dir, const std::string& name, const std::string& scene,
               const Model& model, const Frames& frames) {
  std::filesystem::create_directories(dir);
  write_file_atomically(dir / (name + ".yaml"), [&](std::ostream& o) { o << scene; });
  std::vector<PvdEntry> entries;
  std::vector<double> displacement(3 * size_t(model.node_count()));
  for (size_t k = 0; k < frames.size(); ++k) {
    for (int i = 0; i < model.node_count(); ++i)
      for (int d = 0; d < 3; ++d)
        displacement[3 * size_t(i) + d] = frames[k].x[size_t(i)][d] - frames[0].x[size_t(i)][d];
    const PointField fields[] = {{"probe_displacement", 3, displacement}};
    const CellField cells[] = {{"component", model.cell_component}};
    const std::string file = fmt::format("{}_{}.vtu", name, k);
    write_vtu(dir / file, frames[k].x, model.cells, fields, cells);
    entries.push_back({frames[k].time, file});
  }
  write_obstacles(dir, name, model, frames);
  write_pvd(dir / (name + ".pvd"), entries);
}

}  // namespace

SceneSettings study_scene(const Options& o, double filling, Probe probe) {
  SceneSettings s;
  s.filling = filling;
  s.probe = probe;
  s.duration = kDuration;
  s.load_steps = o.load_steps + 1;  // the first equilibrium is before the probe acts
  s.settle_fraction = 1.0 / s.load_steps;
  if (probe == Probe::pressure) {
    s.probe_axis_point = Vec3(0, 0, -o.prostate_radii.z() - o.probe_radius + o.probe_indent);
    s.pressure = 1.0;
    s.pressure = o.probe_force / pressed_area(compile(o, s));
  } else {
    s.probe_axis_point = Vec3(0, o.prostate_radii.y() + o.probe_radius, -1.0);  // out of reach
  }
  return s;
}

SceneSettings dynamic_scene(const Options& o, double filling, Probe probe) {
  SceneSettings s = study_scene(o, filling, probe);
  if (probe == Probe::rigid) {
    Simulator sim(compile(o, s));
    relax_to(sim, s.duration * s.settle_fraction);
    // Whole micrometres below touching: the scene file reads back the same number on any
    // build, and the probe starts just clear of the prostate.
    const double z = touching_axis_height(sim.model(), sim.data(), o.probe_radius);
    s.probe_axis_point.z() = std::floor(z * 1e6) * 1e-6;
  }
  s.dynamic = true;
  return s;
}

FillingResult run_filling(const Options& o, double filling, Probe probe,
                          const std::filesystem::path& out) {
  Frames frames_here;
  Frames* frames = out.empty() ? nullptr : &frames_here;
  SceneSettings s = study_scene(o, filling, probe);
  const double settle = s.duration * s.settle_fraction;
  FillingResult r;
  r.filling = filling;
  r.probe = probe;
  Data gravity_equilibrium;
  if (probe == Probe::rigid) {  // place the probe against the prostate's equilibrium
    Simulator sim(compile(o, s));
    r.iterations += relax_to(sim, settle).iterations;
    s.probe_axis_point.z() = touching_axis_height(sim.model(), sim.data(), o.probe_radius);
    gravity_equilibrium = sim.data();
  }
  Simulator sim(compile(o, s));
  const Model& model = sim.model();
  // The probe only touches that equilibrium: the run starts from it instead of relaxing
  // gravity again.
  if (probe == Probe::rigid) {
    gravity_equilibrium.dt = sim.dt();  // this model's step, a static solve from the start
    gravity_equilibrium.stable_dt = sim.stable_dt();
    gravity_equilibrium.load_time = settle;
    gravity_equilibrium.static_progress = {};
    sim.restore(gravity_equilibrium);
  }
  r.iterations += relax_to(sim, settle).iterations;
  r.before = sim.data().x;
  if (frames) frames->push_back({settle, sim.data().x});
  for (int k = 2; k <= s.load_steps; ++k) {
    const double t = s.duration * k / s.load_steps;
    r.iterations += relax_to(sim, t).iterations;
    if (frames) frames->push_back({t, sim.data().x});
  }
  r.after = sim.data().x;
  const Measures before = measure(model, r.before), after = measure(model, r.after);
  r.prostate_height = before.height;
  r.prostate_deformation_pct = 100.0 * (before.height - after.height) / before.height;
  r.centre_displacement = (after.centre - before.centre).norm();
  r.centre_lift = after.centre.z() - before.centre.z();
  r.bladder_volume = sim.component_volumes()[size_t(component_index(model, "bladder"))];
  r.probe_force = probe_force_from_balance(sim);
  force_paths(sim, r);
  if (probe == Probe::pressure)
    r.pressure_resultant = pressure_resultant(model, sim.data(), s.duration).z();
  else
    r.probe_contact_force = obstacle_force(model, sim.data(), 0).z();
  const Component& p = model.components[size_t(component_index(model, "prostate"))];
  const Component& b = model.components[size_t(component_index(model, "bladder"))];
  for (int i : p.nodes)
    if (std::find(b.nodes.begin(), b.nodes.end(), i) != b.nodes.end()) r.stitched.push_back(i);
  r.model_nodes = model.node_count();
  if (!out.empty()) write_run(out, run_name(filling, probe), scene_text(o, s), model, frames_here);
  return r;
}

std::string run_name(double filling, Probe probe) {
  return fmt::format("{:.0f}mL_{}", filling * 1e6, probe_name(probe));
}

Study run_study(const Options& o, const std::filesystem::path& out,
                const std::function<void(int, int, const std::string&)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  Study study;
  study.options = o;
  const int total = int(o.fillings.size() * o.probes.size());
  for (double filling : o.fillings)
    for (Probe probe : o.probes) {
      if (progress) progress(int(study.results.size()), total, run_name(filling, probe));
      study.results.push_back(run_filling(o, filling, probe, out));
    }
  study.wall_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return study;
}

}  // namespace phymul::prostate

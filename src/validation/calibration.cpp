// Stiffness from Young's modulus (K = alpha E h): calibration against the reference FEM on a
// bonded cube compression, and a check on a cantilever under gravity.
#include "phymul/calibration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "phymul/fem.hpp"
#include "phymul/model.hpp"
#include "phymul/simulator.hpp"

namespace phymul::calibration {
namespace {

double poisson_of(CellType type, const Options& o) {
  return type == CellType::tetra ? o.poisson_tetra : o.poisson_hexa;
}

void check_type(CellType type) {
  if (type != CellType::hexa && type != CellType::tetra)
    throw std::invalid_argument(
        fmt::format("calibration: mesh type must be hexa or tetra (got {})", cell_type_name(type)));
}

// The z-sum of the reactions on `nodes`, as a magnitude.
double z_force(const std::vector<Vec3>& reaction, const std::vector<int>& nodes) {
  double f = 0.0;
  for (int n : nodes) f += reaction[n].z();
  return std::abs(f);
}

const std::vector<int>& node_set(const Mesh& mesh, const std::string& name) {
  const auto it = mesh.node_sets.find(name);
  if (it == mesh.node_sets.end() || it->second.empty())
    throw std::logic_error("calibration: the box has no node set " + name);
  return it->second;
}

MaterialSpec shape_memory_material(double stiffness, double density) {
  MaterialSpec m;
  m.stiffness = stiffness;
  m.density = density;
  return m;
}

StaticResult relax_or_throw(Simulator& sim, double load_time, long max_iterations,
                            const std::string& what) {
  const StaticResult r = sim.relax(load_time, max_iterations);
  if (!r.converged)
    throw std::runtime_error(fmt::format(
        "calibration: the shape-memory {} did not reach equilibrium ({} iterations, residual "
        "{:.3g} N, tolerance {:.3g} N)",
        what, r.iterations, r.residual, sim.model().settings.tolerance));
  return r;
}

}  // namespace

double mean_edge_length(const Mesh& mesh) {
  const Adjacency adjacency = edge_neighbours(mesh);
  double sum = 0.0;
  long count = 0;
  for (int i = 0; i < adjacency.rows(); ++i)
    for (int j : adjacency.row(i))
      if (j > i) {
        sum += (mesh.points[j] - mesh.points[i]).norm();
        ++count;
      }
  if (count == 0) throw std::invalid_argument("mean_edge_length: the mesh has no edge");
  return sum / double(count);
}

Compression calibrate_compression(CellType type, int cells, const Options& o) {
  check_type(type);
  if (cells < 1) throw std::invalid_argument("calibration: cells must be >= 1");
  Compression c;
  c.type = type;
  c.cells = cells;
  c.poisson = poisson_of(type, o);
  const Mesh mesh = make_box(Vec3::Constant(o.edge), {cells, cells, cells}, type);
  c.h = mean_edge_length(mesh);
  const std::vector<int>& bottom = node_set(mesh, "bottom");
  const std::vector<int>& top = node_set(mesh, "top");
  const double push = o.strain * o.edge;  // m, downwards

  // Reference FEM (Neo-Hookean; at 2 % strain practically linear).
  fem::Problem problem;
  problem.mesh = mesh;
  problem.material = {fem::Law::neo_hookean, o.young, c.poisson};
  problem.load_steps = 2;
  for (int n : bottom)
    for (int a = 0; a < 3; ++a) problem.prescribed.push_back({n, a, 0.0});
  for (int n : top)
    for (int a = 0; a < 3; ++a) problem.prescribed.push_back({n, a, a == 2 ? -push : 0.0});
  const fem::Result solved = fem::solve_static(problem);
  if (!solved.converged)
    throw std::runtime_error("calibration: the reference FEM compression did not converge: " +
                             solved.message);
  c.fem_force = z_force(solved.reaction, top);
  c.fem_newton_iterations = solved.newton_iterations;

  // Shape memory at K = E h (alpha = 1): positions do not depend on K.
  const double k1 = o.young * c.h;
  Model model;
  const int id = add_elastic_component(model, "cube", mesh, shape_memory_material(k1, o.density));
  if (o.volume_constraint) add_volume_constraint(model, id);
  add_prescribed_displacement(model,
                              {bottom, {true, true, true}, Schedule::constant(Vec3::Zero())});
  add_prescribed_displacement(
      model, {top, {true, true, true}, Schedule{{0.0, 1.0}, {Vec3::Zero(), Vec3(0, 0, -push)}}});
  model.settings.tolerance = o.tolerance * k1 * o.strain * c.h;
  model.settings.max_iterations = o.max_iterations;
  finalize(model);
  Simulator sim(model);
  c.lsm_iterations = relax_or_throw(sim, 1.0, o.max_iterations, "compression").iterations;
  c.lsm_force_per_k = z_force(sim.support_reactions(), top) / k1;
  c.alpha = c.fem_force / (c.lsm_force_per_k * o.young * c.h);

  // Relaxed again with the calibrated K, from the equilibrium found (same positions).
  Model calibrated = model;
  const double k = c.alpha * o.young * c.h;
  for (ShapeMemory& s : calibrated.shape_memory) s.stiffness = k;
  calibrated.settings.tolerance = o.tolerance * k * o.strain * c.h;
  Simulator check(calibrated);
  check.state() = sim.state();
  c.lsm_iterations += relax_or_throw(check, 1.0, o.max_iterations, "compression").iterations;
  c.lsm_force = z_force(check.support_reactions(), top);
  c.force_rel_diff = (c.lsm_force - c.fem_force) / c.fem_force;
  return c;
}

Cantilever check_cantilever(CellType type, int cells, double alpha, const Options& o) {
  check_type(type);
  if (cells < 1) throw std::invalid_argument("calibration: cells must be >= 1");
  Cantilever c;
  c.type = type;
  c.cells = cells;
  c.alpha = alpha;
  std::array<int, 3> n{};
  for (int a = 0; a < 3; ++a) n[a] = std::max(1, int(std::lround(o.beam[a] / o.edge * cells)));
  // Fixed end at x = 0, beam along +x.
  const Mesh mesh = make_box(o.beam, n, type, 0.5 * o.beam);
  c.h = mean_edge_length(mesh);
  c.stiffness = alpha * o.beam_young * c.h;
  const std::vector<int>& fixed = node_set(mesh, "left");
  const std::vector<int>& tip = node_set(mesh, "right");
  const Vec3 g(0, 0, -o.gravity);

  fem::Problem problem;
  problem.mesh = mesh;
  problem.material = {fem::Law::neo_hookean, o.beam_young, poisson_of(type, o)};
  problem.body_force = o.density * g;
  problem.load_steps = 4;
  for (int node : fixed)
    for (int a = 0; a < 3; ++a) problem.prescribed.push_back({node, a, 0.0});
  const fem::Result solved = fem::solve_static(problem);
  if (!solved.converged)
    throw std::runtime_error("calibration: the reference FEM cantilever did not converge: " +
                             solved.message);
  for (int node : tip) c.fem_tip -= solved.displacement[node].z() / double(tip.size());

  Model model;
  const int id =
      add_elastic_component(model, "beam", mesh, shape_memory_material(c.stiffness, o.density));
  if (o.volume_constraint) add_volume_constraint(model, id);
  add_fixed_nodes(model, fixed);
  model.gravity = g;
  model.settings.gravity = g;
  const double heaviest = *std::max_element(model.mass.begin(), model.mass.end());
  model.settings.tolerance = o.tolerance * heaviest * o.gravity;
  model.settings.max_iterations = o.max_iterations;
  finalize(model);
  Simulator sim(model);
  c.lsm_iterations = relax_or_throw(sim, 1.0, o.max_iterations, "cantilever").iterations;
  for (int node : tip)
    c.lsm_tip -= (sim.state().x[node] - mesh.points[node]).z() / double(tip.size());

  const double L = o.beam.x(), b = o.beam.y(), t = o.beam.z();
  const double q = o.density * o.gravity * b * t;  // N/m
  c.euler_bernoulli_tip = q * std::pow(L, 4) / (8.0 * o.beam_young * b * t * t * t / 12.0);
  c.tip_ratio = c.lsm_tip / c.fem_tip;
  c.tip_rel_diff = c.tip_ratio - 1.0;
  return c;
}

Result run(const std::vector<CellType>& types, const std::vector<int>& resolutions,
           const Options& options) {
  const auto start = std::chrono::steady_clock::now();
  Result result;
  result.options = options;
  for (CellType type : types)
    for (int cells : resolutions) {
      Row row;
      row.compression = calibrate_compression(type, cells, options);
      if (options.cantilever)
        row.cantilever = check_cantilever(type, cells, row.compression.alpha, options);
      result.rows.push_back(row);
    }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

std::string table(const Result& r) {
  const Options& o = r.options;
  std::string s = fmt::format(
      "K = alpha * E * h (h: mean rest edge length). Calibration: {:g} mm cube, {:g} % bonded "
      "compression,\nshape memory {} volume constraint vs Neo-Hookean FEM (nu {:g} hexa, {:g} "
      "tetra).\n",
      o.edge * 1e3, o.strain * 100, o.volume_constraint ? "with" : "without", o.poisson_hexa,
      o.poisson_tetra);
  if (o.cantilever)
    s += fmt::format(
        "Check: {:g} x {:g} x {:g} mm cantilever under gravity, rho {:g} kg/m^3, E {:g} kPa; tip "
        "= mean downward displacement of the free end.\n",
        o.beam.x() * 1e3, o.beam.y() * 1e3, o.beam.z() * 1e3, o.density, o.beam_young * 1e-3);
  s += fmt::format("\n{:<6} {:>5} {:>7} {:>10} {:>10} {:>8} {:>9}", "mesh", "cells", "h mm",
                   "F_fem N", "F_lsm N", "alpha", "dF %");
  if (o.cantilever)
    s += fmt::format(" {:>10} {:>10} {:>10} {:>8}", "tip_fem mm", "tip_lsm mm", "tip_EB mm",
                     "dtip %");
  s += '\n';
  for (const Row& row : r.rows) {
    const Compression& c = row.compression;
    s += fmt::format("{:<6} {:>5} {:>7.3f} {:>10.4g} {:>10.4g} {:>8.4f} {:>9.2e}",
                     cell_type_name(c.type), c.cells, c.h * 1e3, c.fem_force, c.lsm_force, c.alpha,
                     c.force_rel_diff * 100);
    if (o.cantilever) {
      const Cantilever& t = row.cantilever;
      s += fmt::format(" {:>10.4f} {:>10.4f} {:>10.4f} {:>8.1f}", t.fem_tip * 1e3, t.lsm_tip * 1e3,
                       t.euler_bernoulli_tip * 1e3, t.tip_rel_diff * 100);
    }
    s += '\n';
  }
  s += fmt::format("({:.1f} s)\n", r.seconds);
  return s;
}

std::string json(const Result& r) {
  const Options& o = r.options;
  std::string s = fmt::format(
      "{{\n  \"options\": {{\"edge\": {}, \"strain\": {}, \"young\": {}, \"poisson_hexa\": {}, "
      "\"poisson_tetra\": {}, \"volume_constraint\": {}, \"tolerance\": {}, \"beam\": [{}, {}, "
      "{}], \"density\": {}, \"gravity\": {}, \"beam_young\": {}, \"cantilever\": {}}},\n"
      "  \"seconds\": {},\n  \"rows\": [",
      o.edge, o.strain, o.young, o.poisson_hexa, o.poisson_tetra, o.volume_constraint, o.tolerance,
      o.beam.x(), o.beam.y(), o.beam.z(), o.density, o.gravity, o.beam_young, o.cantilever,
      r.seconds);
  for (size_t i = 0; i < r.rows.size(); ++i) {
    const Compression& c = r.rows[i].compression;
    const Cantilever& t = r.rows[i].cantilever;
    s += fmt::format(
        "{}\n    {{\"type\": \"{}\", \"cells\": {}, \"h\": {}, \"poisson\": {}, \"fem_force\": {}, "
        "\"lsm_force_per_k\": {}, \"alpha\": {}, \"lsm_force\": {}, \"force_rel_diff\": {}, "
        "\"lsm_iterations\": {}",
        i ? "," : "", cell_type_name(c.type), c.cells, c.h, c.poisson, c.fem_force,
        c.lsm_force_per_k, c.alpha, c.lsm_force, c.force_rel_diff, c.lsm_iterations);
    if (o.cantilever)
      s += fmt::format(
          ", \"cantilever\": {{\"h\": {}, \"stiffness\": {}, \"fem_tip\": {}, \"lsm_tip\": {}, "
          "\"euler_bernoulli_tip\": {}, \"tip_ratio\": {}, \"tip_rel_diff\": {}, "
          "\"lsm_iterations\": {}}}",
          t.h, t.stiffness, t.fem_tip, t.lsm_tip, t.euler_bernoulli_tip, t.tip_ratio,
          t.tip_rel_diff, t.lsm_iterations);
    s += '}';
  }
  s += "\n  ]\n}\n";
  return s;
}

}  // namespace phymul::calibration

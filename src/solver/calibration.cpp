// Stiffness from Young's modulus (K = alpha E h): calibration against the reference FEM on a
// bonded cube compression, and a check on a cantilever under gravity.
#include "phymul/calibration.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <numeric>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "phymul/fem.hpp"
#include "phymul/model.hpp"
#include "phymul/simulation.hpp"

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

// The sum of the reactions on `nodes` along `axis`, as a magnitude.
double axis_force(const std::vector<Vec3>& reaction, const std::vector<int>& nodes, int axis) {
  double f = 0.0;
  for (int n : nodes) f += reaction[n][axis];
  return std::abs(f);
}

const std::vector<int>& node_set(const Mesh& mesh, const std::string& name) {
  const auto it = mesh.node_sets.find(name);
  if (it == mesh.node_sets.end() || it->second.empty())
    throw std::logic_error("calibration: the box has no node set " + name);
  return it->second;
}

// rms and largest |u_lsm - u_fem| over the nodes, divided by `scale`.
std::pair<double, double> displacement_difference(const std::vector<Vec3>& rest,
                                                  const std::vector<Vec3>& lsm_positions,
                                                  const std::vector<Vec3>& fem_displacement,
                                                  double scale) {
  double sum2 = 0.0, largest = 0.0;
  for (size_t i = 0; i < rest.size(); ++i) {
    const double d = (lsm_positions[i] - rest[i] - fem_displacement[i]).norm();
    sum2 += d * d;
    largest = std::max(largest, d);
  }
  return {std::sqrt(sum2 / double(rest.size())) / scale, largest / scale};
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

namespace {

// One bonded push applied to both models: `held` clamped, `pushed` moved by `push` along
// `axis`. The shape memory runs at K = E h, where its positions do not depend on K.
struct Push {
  const Mesh* mesh = nullptr;  // the shape memory's
  Mesh fem_mesh;               // the same nodes, cells the FEM takes
  std::vector<int> held, pushed;
  int axis = 2;
  double push = 0.0;  // m, signed
  fem::Material fem_material;
  int load_steps = 1;
  MaterialSpec lsm_material;  // stiffness: E h
  bool volume_constraint = true;
  double lsm_tolerance = 0.0;  // N
  long max_iterations = 0;
};

struct Pushed {
  fem::Result fem;
  double fem_force = 0.0;        // N, |axis reaction| on the pushed nodes
  double lsm_force_per_k = 0.0;  // N per N/m
  Model lsm;                     // at K = E h
  Data lsm_state;                // its equilibrium
  long lsm_iterations = 0;
};

Pushed push_both(const Push& p, const std::string& what) {
  Pushed r;
  fem::Problem problem;
  problem.mesh = p.fem_mesh;
  problem.material = p.fem_material;
  problem.load_steps = p.load_steps;
  for (int n : p.held)
    for (int a = 0; a < 3; ++a) problem.prescribed.push_back({n, a, 0.0});
  for (int n : p.pushed)
    for (int a = 0; a < 3; ++a) problem.prescribed.push_back({n, a, a == p.axis ? p.push : 0.0});
  r.fem = fem::solve_static(problem);
  if (!r.fem.converged)
    throw std::runtime_error(
        fmt::format("calibration: the reference FEM {} did not converge: {}", what, r.fem.message));
  r.fem_force = axis_force(r.fem.reaction, p.pushed, p.axis);

  const int id = add_elastic_component(r.lsm, "calibrated", *p.mesh, p.lsm_material);
  if (p.volume_constraint) add_volume_constraint(r.lsm, id);
  Vec3 end = Vec3::Zero();
  end[p.axis] = p.push;
  add_prescribed_displacement(r.lsm,
                              {p.held, {true, true, true}, Schedule::constant(Vec3::Zero())});
  add_prescribed_displacement(
      r.lsm, {p.pushed, {true, true, true}, Schedule{{0.0, 1.0}, {Vec3::Zero(), end}}});
  r.lsm.settings.tolerance = p.lsm_tolerance;
  r.lsm.settings.max_iterations = p.max_iterations;
  r.lsm.settings.mode = SolveMode::static_equilibrium;  // relaxation masses (Simulator)
  r.lsm.settings.relaxation = Relaxation::fire;         // no contact to stall it
  finalize(r.lsm);
  Simulator sim(r.lsm);
  r.lsm_iterations = relax_or_throw(sim, 1.0, p.max_iterations, what).iterations;
  r.lsm_force_per_k =
      axis_force(sim.support_reactions(), p.pushed, p.axis) / *p.lsm_material.stiffness;
  r.lsm_state = sim.data();
  return r;
}

}  // namespace

Compression calibrate_compression(CellType type, int cells, const Options& o) {
  check_type(type);
  if (cells < 1) throw std::invalid_argument("calibration: cells must be >= 1");
  Compression c;
  c.type = type;
  c.cells = cells;
  c.poisson = poisson_of(type, o);
  const Mesh mesh = make_box(Vec3::Constant(o.edge), {cells, cells, cells}, type);
  c.h = mean_edge_length(mesh);

  // Reference FEM Neo-Hookean (at 2 % strain practically linear).
  Push p;
  p.mesh = &mesh;
  p.fem_mesh = mesh;
  p.held = node_set(mesh, "bottom");
  p.pushed = node_set(mesh, "top");
  p.push = -o.strain * o.edge;
  p.fem_material = {fem::Law::neo_hookean, o.young, c.poisson};
  p.load_steps = 2;
  const double k1 = o.young * c.h;
  p.lsm_material = shape_memory_material(k1, o.density);
  p.volume_constraint = o.volume_constraint;
  p.lsm_tolerance = o.tolerance * k1 * o.strain * c.h;
  p.max_iterations = o.max_iterations;
  const Pushed r = push_both(p, "compression");
  c.fem_force = r.fem_force;
  c.fem_newton_iterations = r.fem.newton_iterations;
  c.lsm_iterations = r.lsm_iterations;
  c.lsm_force_per_k = r.lsm_force_per_k;
  c.alpha = c.fem_force / (c.lsm_force_per_k * o.young * c.h);
  std::tie(c.displacement_rms, c.displacement_max) =
      displacement_difference(mesh.points, r.lsm_state.x, r.fem.displacement, -p.push);

  // Relaxed again with the calibrated K, from the equilibrium found (same positions).
  Model calibrated = r.lsm;
  const double k = c.alpha * o.young * c.h;
  for (ShapeMemory& s : calibrated.shape_memory) s.stiffness = k;
  calibrated.settings.tolerance = o.tolerance * k * o.strain * c.h;
  Simulator check(calibrated);
  check.data() = r.lsm_state;
  c.lsm_iterations += relax_or_throw(check, 1.0, o.max_iterations, "compression").iterations;
  c.lsm_force = axis_force(check.support_reactions(), p.pushed, 2);
  c.force_rel_diff = (c.lsm_force - c.fem_force) / c.fem_force;
  return c;
}

namespace {

// The cells the FEM takes: hexahedra and tetrahedra as they are, wedges cut into three
// tetrahedra, every tetrahedron turned to a positive volume.
Mesh fem_cells(const std::string& name, const Mesh& mesh) {
  Mesh out;
  out.points = mesh.points;
  const auto add_tetra = [&](Cell t) {
    if (cell_measure(out.points, t) < 0.0) std::swap(t.nodes[1], t.nodes[2]);
    out.cells.push_back(t);
  };
  for (const Cell& cell : mesh.cells) {
    if (cell.type == CellType::hexa)
      out.cells.push_back(cell);
    else if (cell.type == CellType::tetra)
      add_tetra(cell);
    else if (cell.type == CellType::wedge)
      for (const Cell& t : wedge_tetrahedra(cell)) add_tetra(t);
    else
      throw std::invalid_argument(fmt::format(
          "object '{}': 'young' calibrates K against finite elements, which need a volumetric "
          "mesh (hexahedra, tetrahedra, wedges); this mesh has {} cells: give 'stiffness' instead",
          name, cell_type_name(cell.type)));
  }
  return out;
}

// The nodes within `band` of the lowest (or highest) coordinate along `axis`, and at least
// the `least` most extreme ones, so that a pointed end is still clamped on a triangle.
std::vector<int> end_nodes(const Mesh& mesh, int axis, double band, bool lowest, size_t least) {
  const auto key = [&](int n) {
    const double x = mesh.points[size_t(n)][axis];
    return lowest ? x : -x;
  };
  std::vector<int> order(mesh.points.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return key(a) < key(b); });
  const double limit = key(order.front()) + band;
  size_t count = 0;
  while (count < order.size() && (count < least || key(order[count]) <= limit)) ++count;
  order.resize(count);
  std::sort(order.begin(), order.end());
  return order;
}

}  // namespace

StiffnessCalibration calibrate_object(const std::string& name, const Mesh& mesh,
                                      const MaterialSpec& material, bool volume_constraint,
                                      int axis, double strain) {
  if (!material.young || !material.poisson)
    throw std::invalid_argument(
        fmt::format("object '{}': calibrating K needs the material's 'young' and 'poisson'", name));
  const double young = *material.young, poisson = *material.poisson;
  StiffnessCalibration c;
  c.component = name;
  c.young = young;
  c.poisson = poisson;
  c.axis = axis;
  c.strain = strain;
  Push p;
  p.mesh = &mesh;
  p.fem_mesh = fem_cells(name, mesh);
  c.h = mean_edge_length(mesh);
  p.axis = axis;
  p.held = end_nodes(mesh, axis, c.h / 4, true, 4);
  p.pushed = end_nodes(mesh, axis, c.h / 4, false, 4);
  std::vector<int> shared;
  std::set_intersection(p.held.begin(), p.held.end(), p.pushed.begin(), p.pushed.end(),
                        std::back_inserter(shared));
  if (!shared.empty())
    throw std::invalid_argument(fmt::format(
        "object '{}': too thin along {} to calibrate K by compressing it (its two ends share "
        "node {}): choose another 'calibration_axis' or give 'stiffness'",
        name, "xyz"[axis], shared.front()));
  c.held = int(p.held.size());
  c.pushed = int(p.pushed.size());
  const auto [low, high] = bounding_box(mesh.points);
  c.push = strain * (high[axis] - low[axis]);
  p.push = -c.push;
  p.fem_material = {fem::Law::linear, young, poisson};
  p.load_steps = 1;
  const double k1 = young * c.h;
  p.lsm_material = material;
  p.lsm_material.model = ElasticModel::shape_memory;
  p.lsm_material.stiffness = k1;
  p.volume_constraint = volume_constraint;
  const Options defaults;
  p.lsm_tolerance = defaults.tolerance * k1 * strain * c.h;
  p.max_iterations = defaults.max_iterations;
  const Pushed r = push_both(p, fmt::format("compression of object '{}'", name));
  c.fem_force = r.fem_force;
  c.fem_newton_iterations = r.fem.newton_iterations;
  c.lsm_iterations = r.lsm_iterations;
  c.stiffness = r.fem_force / r.lsm_force_per_k;
  c.alpha = c.stiffness / (young * c.h);
  std::tie(c.displacement_rms, c.displacement_max) =
      displacement_difference(mesh.points, r.lsm_state.x, r.fem.displacement, c.push);
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
    c.lsm_tip -= (sim.data().x[node] - mesh.points[node]).z() / double(tip.size());
  std::tie(c.displacement_rms, c.displacement_max) =
      displacement_difference(mesh.points, sim.data().x, solved.displacement, c.fem_tip);

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
  s += fmt::format("\n{:<6} {:>5} {:>7} {:>10} {:>10} {:>8} {:>9} {:>7}", "mesh", "cells", "h mm",
                   "F_fem N", "F_lsm N", "alpha", "dF %", "du %");
  if (o.cantilever)
    s += fmt::format(" {:>10} {:>10} {:>10} {:>8} {:>7}", "tip_fem mm", "tip_lsm mm", "tip_EB mm",
                     "dtip %", "du %");
  s += '\n';
  for (const Row& row : r.rows) {
    const Compression& c = row.compression;
    s += fmt::format("{:<6} {:>5} {:>7.3f} {:>10.4g} {:>10.4g} {:>8.4f} {:>9.2e} {:>7.1f}",
                     cell_type_name(c.type), c.cells, c.h * 1e3, c.fem_force, c.lsm_force, c.alpha,
                     c.force_rel_diff * 100, c.displacement_rms * 100);
    if (o.cantilever) {
      const Cantilever& t = row.cantilever;
      s += fmt::format(" {:>10.4f} {:>10.4f} {:>10.4f} {:>8.1f} {:>7.1f}", t.fem_tip * 1e3,
                       t.lsm_tip * 1e3, t.euler_bernoulli_tip * 1e3, t.tip_rel_diff * 100,
                       t.displacement_rms * 100);
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
        "\"lsm_iterations\": {}, \"displacement_rms\": {}, \"displacement_max\": {}",
        i ? "," : "", cell_type_name(c.type), c.cells, c.h, c.poisson, c.fem_force,
        c.lsm_force_per_k, c.alpha, c.lsm_force, c.force_rel_diff, c.lsm_iterations,
        c.displacement_rms, c.displacement_max);
    if (o.cantilever)
      s += fmt::format(
          ", \"cantilever\": {{\"h\": {}, \"stiffness\": {}, \"fem_tip\": {}, \"lsm_tip\": {}, "
          "\"euler_bernoulli_tip\": {}, \"tip_ratio\": {}, \"tip_rel_diff\": {}, "
          "\"lsm_iterations\": {}, \"displacement_rms\": {}, \"displacement_max\": {}}}",
          t.h, t.stiffness, t.fem_tip, t.lsm_tip, t.euler_bernoulli_tip, t.tip_ratio,
          t.tip_rel_diff, t.lsm_iterations, t.displacement_rms, t.displacement_max);
    s += '}';
  }
  s += "\n  ]\n}\n";
  return s;
}

}  // namespace phymul::calibration

// Input checks of solve_static.
#include "fem/input.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace phymul::fem {

namespace {

std::string number(double v) {
  std::ostringstream out;
  out.precision(12);
  out << v;
  return out.str();
}

[[noreturn]] void reject(const std::string& what) {
  throw std::invalid_argument("fem::solve_static: " + what);
}

void check_material(const Material& m) {
  if (m.law != Law::neo_hookean && m.law != Law::linear) {
    reject("material.law must be neo_hookean or linear (got " + std::to_string(int(m.law)) + ")");
  }
  if (m.hexa != HexaElement::mean_dilatation && m.hexa != HexaElement::incompatible_modes) {
    reject("material.hexa must be mean_dilatation or incompatible_modes (got " +
           std::to_string(int(m.hexa)) + ")");
  }
  if (!(m.young > 0.0) || !std::isfinite(m.young)) {
    reject("material.young must be finite and > 0 Pa (got " + number(m.young) + ")");
  }
  if (!(m.poisson > -1.0 && m.poisson < 0.5)) {
    reject("material.poisson must be in (-1, 0.5) (got " + number(m.poisson) + ")");
  }
}

void check_materials(const Problem& p) {
  if (p.materials.empty()) {
    check_material(p.material);
    return;
  }
  for (const Material& m : p.materials) check_material(m);
  if (p.cell_material.size() != p.mesh.cells.size()) {
    reject("cell_material must have one entry per cell (" + std::to_string(p.mesh.cells.size()) +
           "; got " + std::to_string(p.cell_material.size()) + ")");
  }
  for (std::size_t c = 0; c < p.cell_material.size(); ++c) {
    const int m = p.cell_material[c];
    if (m < 0 || std::size_t(m) >= p.materials.size()) {
      reject("cell_material[" + std::to_string(c) + "] must be in [0, " +
             std::to_string(p.materials.size()) + ") (got " + std::to_string(m) + ")");
    }
  }
}

void check_cells(const Mesh& mesh) {
  if (mesh.cells.empty()) reject("mesh.cells is empty");
  const std::size_t points = mesh.points.size();
  for (std::size_t c = 0; c < mesh.cells.size(); ++c) {
    const Cell& cell = mesh.cells[c];
    if (cell.type != CellType::hexa && cell.type != CellType::tetra) {
      reject("mesh.cells[" + std::to_string(c) + "] is a " + cell_type_name(cell.type) +
             "; only linear hexa and tetra cells are supported");
    }
    for (int k = 0; k < node_count(cell.type); ++k) {
      const int n = cell.nodes[k];
      if (n < 0 || std::size_t(n) >= points) {
        reject("mesh.cells[" + std::to_string(c) + "].nodes[" + std::to_string(k) +
               "] must be in [0, " + std::to_string(points) + ") (got " + std::to_string(n) + ")");
      }
    }
  }
  try {
    validate(mesh);
  } catch (const MeshError& e) {
    reject(std::string("invalid mesh: ") + e.what());
  }
}

void check_prescribed(const Problem& p) {
  const std::size_t points = p.mesh.points.size();
  for (std::size_t i = 0; i < p.prescribed.size(); ++i) {
    const Dirichlet& d = p.prescribed[i];
    const std::string name = "prescribed[" + std::to_string(i) + "]";
    if (d.node < 0 || std::size_t(d.node) >= points) {
      reject(name + ".node must be in [0, " + std::to_string(points) + ") (got " +
             std::to_string(d.node) + ")");
    }
    if (d.axis < 0 || d.axis > 2) {
      reject(name + ".axis must be 0, 1 or 2 (got " + std::to_string(d.axis) + ")");
    }
    if (!std::isfinite(d.value))
      reject(name + ".value must be finite (got " + number(d.value) + ")");
  }
}

void check_controls(const Problem& p) {
  if (p.load_steps < 1) {
    reject("load_steps must be >= 1 (got " + std::to_string(p.load_steps) + ")");
  }
  if (p.max_newton_iterations < 1) {
    reject("max_newton_iterations must be >= 1 (got " + std::to_string(p.max_newton_iterations) +
           ")");
  }
  if (!(p.tolerance > 0.0 && p.tolerance < 1.0)) {
    reject("tolerance must be in (0, 1) (got " + number(p.tolerance) + ")");
  }
  if (!(p.force_tolerance > 0.0)) {
    reject("force_tolerance must be > 0 N (got " + number(p.force_tolerance) + ")");
  }
  if (!p.nodal_force.empty() && p.nodal_force.size() != p.mesh.points.size()) {
    reject("nodal_force must be empty or have one entry per node (" +
           std::to_string(p.mesh.points.size()) + "; got " + std::to_string(p.nodal_force.size()) +
           ")");
  }
  for (std::size_t n = 0; n < p.nodal_force.size(); ++n) {
    if (!p.nodal_force[n].allFinite()) {
      reject("nodal_force[" + std::to_string(n) + "] must be finite");
    }
  }
  if (!p.body_force.allFinite()) {
    reject("body_force must be finite (got " + number(p.body_force.x()) + ", " +
           number(p.body_force.y()) + ", " + number(p.body_force.z()) + ")");
  }
}

}  // namespace

void check_problem(const Problem& problem) {
  check_materials(problem);
  check_controls(problem);
  check_cells(problem.mesh);
  check_prescribed(problem);
}

PrescribedValues prescribed_values(const Problem& problem) {
  const std::size_t dofs = 3 * problem.mesh.points.size();
  PrescribedValues out{std::vector<char>(dofs, 0), std::vector<double>(dofs, 0.0)};
  for (std::size_t i = 0; i < problem.prescribed.size(); ++i) {
    const Dirichlet& d = problem.prescribed[i];
    const std::size_t dof = 3 * std::size_t(d.node) + std::size_t(d.axis);
    if (out.mask[dof] && out.value[dof] != d.value) {
      reject("prescribed[" + std::to_string(i) + "] sets node " + std::to_string(d.node) +
             " axis " + std::to_string(d.axis) + " to " + number(d.value) +
             " m, but an earlier entry set it to " + number(out.value[dof]) + " m");
    }
    out.mask[dof] = 1;
    out.value[dof] = d.value;
  }
  return out;
}

}  // namespace phymul::fem

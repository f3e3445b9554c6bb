#include "forces/active_fibres.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

namespace phymul {

double activation_at(const FibreBundle& fibres, double t) {
  return std::clamp(fibres.activation.at(t).x(), 0.0, 1.0);
}

double add_fibre_forces(const FibreBundle& fibres, std::span<const Vec3> x, double load_time,
                        std::span<Vec3> f) {
  const double shortening = 1.0 - activation_at(fibres, load_time) * fibres.max_contraction;
  double energy = 0.0;
  int segment = 0;
  for (int p = 0; p < fibres.polylines.rows(); ++p) {
    const auto line = fibres.polylines.row(p);
    for (size_t k = 0; k + 1 < line.size(); ++k, ++segment) {
      const Vec3 d = x[line[k + 1]] - x[line[k]];
      const double length = d.norm();
      const double stretch = length - fibres.rest_length[segment] * shortening;
      if (stretch <= 0.0 || length == 0.0) continue;  // a fibre pulls, never pushes
      const Vec3 pull = fibres.stiffness * stretch * d / length;
      f[line[k]] += pull;
      f[line[k + 1]] -= pull;
      energy += 0.5 * fibres.stiffness * stretch * stretch;
    }
  }
  return energy;
}

namespace {

void check_fibre_parameters(const Component& c, double stiffness, double max_contraction,
                            const Schedule& activation) {
  if (!(stiffness > 0.0))
    throw std::invalid_argument(fmt::format(
        "object '{}': the fibre 'stiffness' must be > 0 N/m (got {})", c.name, stiffness));
  if (!(max_contraction > 0.0 && max_contraction < 1.0))
    throw std::invalid_argument(fmt::format(
        "object '{}': 'max_contraction' must be in (0, 1) (got {})", c.name, max_contraction));
  for (const Vec3& v : activation.values)
    if (!(v.x() >= 0.0 && v.x() <= 1.0))
      throw std::invalid_argument(
          fmt::format("object '{}': the activation must be in [0, 1] (got {})", c.name, v.x()));
}

const Component& component_at(const Model& model, int component) {
  if (component < 0 || component >= int(model.components.size()))
    throw std::invalid_argument(fmt::format("fibres: component {} is out of range", component));
  return model.components[component];
}

}  // namespace

void add_fibre_polylines(Model& model, int component, const std::vector<std::vector<int>>& lines,
                         double stiffness, double max_contraction, Schedule activation) {
  const Component& c = component_at(model, component);
  check_fibre_parameters(c, stiffness, max_contraction, activation);
  FibreBundle bundle;
  bundle.component = component;
  bundle.stiffness = stiffness;
  bundle.max_contraction = max_contraction;
  bundle.activation = std::move(activation);
  for (const std::vector<int>& line : lines) {
    if (line.size() < 2)
      throw std::invalid_argument(
          fmt::format("object '{}': a fibre needs at least two nodes", c.name));
    for (size_t k = 0; k < line.size(); ++k) {
      const int i = line[k];
      if (std::find(c.nodes.begin(), c.nodes.end(), i) == c.nodes.end())
        throw std::invalid_argument(
            fmt::format("object '{}': fibre node {} is not one of its nodes", c.name, i));
      bundle.polylines.indices.push_back(i);
      if (k == 0) continue;
      const double l0 = (model.rest_position[i] - model.rest_position[line[k - 1]]).norm();
      if (!(l0 > 0.0))
        throw std::invalid_argument(fmt::format(
            "object '{}': fibre nodes {} and {} coincide at rest", c.name, line[k - 1], i));
      bundle.rest_length.push_back(l0);
    }
    bundle.polylines.offsets.push_back(int(bundle.polylines.indices.size()));
  }
  model.fibres.push_back(std::move(bundle));
}

void add_fibres(Model& model, int component, const Vec3& direction, double stiffness,
                double max_contraction, Schedule activation) {
  const Component& c = component_at(model, component);
  if (!(direction.norm() > 0.0))
    throw std::invalid_argument(
        fmt::format("object '{}': the fibre 'direction' must be a non-zero vector", c.name));
  check_fibre_parameters(c, stiffness, max_contraction, activation);
  const Vec3 u = direction.normalized();
  // Nodes on one fibre share their position across the direction: key them by it, rounded
  // to a fraction of the component's size.
  Vec3 lo = model.rest_position[c.nodes.front()], hi = lo;
  for (int i : c.nodes)
    lo = lo.cwiseMin(model.rest_position[i]), hi = hi.cwiseMax(model.rest_position[i]);
  const double quantum = 1e-6 * std::max((hi - lo).norm(), 1e-300);
  std::map<std::array<long long, 3>, std::vector<std::pair<double, int>>> by_line;
  for (int i : c.nodes) {
    const Vec3& p = model.rest_position[i];
    const Vec3 across = p - p.dot(u) * u;
    const std::array<long long, 3> key{std::llround(across.x() / quantum),
                                       std::llround(across.y() / quantum),
                                       std::llround(across.z() / quantum)};
    by_line[key].push_back({p.dot(u), i});
  }
  std::vector<std::vector<int>> lines;
  for (auto& [key, line] : by_line) {
    if (line.size() < 2) continue;
    std::sort(line.begin(), line.end());
    lines.emplace_back();
    for (const auto& [along, i] : line) lines.back().push_back(i);
  }
  if (lines.empty())
    throw std::invalid_argument(fmt::format(
        "object '{}': no two nodes lie on a line along the fibre direction [{:.3g}, {:.3g}, "
        "{:.3g}]; fibres follow lines of mesh nodes",
        c.name, u.x(), u.y(), u.z()));
  add_fibre_polylines(model, component, lines, stiffness, max_contraction, std::move(activation));
}

}  // namespace phymul

// Needles in the model (Needle): parameters checked, tissues split into tetrahedra, the track
// sized so that a step allocates nothing.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "model/embedding.hpp"

namespace phymul {
namespace {

void check_at_least(double value, double min, const char* what, const std::string& unit) {
  if (!(value >= min) || !std::isfinite(value))
    throw std::invalid_argument(fmt::format("needle: '{}' must be a finite value >= {} {} (got {})",
                                            what, min, unit, value));
}

void check_tissue(const Model& model, const NeedleTissue& t) {
  if (t.component < 0 || size_t(t.component) >= model.components.size())
    throw std::invalid_argument(fmt::format("needle: no component {}", t.component));
  const Component& c = model.components[size_t(t.component)];
  if (c.kind == ObjectType::rigid || !c.volumetric)
    throw std::invalid_argument(fmt::format(
        "needle: '{}' must be a deformable volume object (tetrahedra, hexahedra or wedges) to "
        "be punctured; it is {}",
        c.name, c.kind == ObjectType::rigid ? "rigid" : "a surface"));
  check_at_least(t.puncture_force, 0.0, "puncture_force", "N");
  check_at_least(t.friction, 0.0, "friction", "N/m");
  check_at_least(t.cutting_force, 0.0, "cutting_force", "N");
}

// Track points are made every `spacing` of advance and released behind a retreating tip, so
// the depth range over spacing bounds them; one more per tissue for its entry point.
int track_capacity(const Needle& n) {
  double lo = n.depth.at(0.0).x(), hi = lo;
  for (const Vec3& v : n.depth.values) lo = std::min(lo, v.x()), hi = std::max(hi, v.x());
  return int(std::ceil((hi - lo) / n.spacing)) + int(n.tissues.size()) + 2;
}

}  // namespace

void add_needle(Model& model, Needle needle) {
  if (!(needle.direction.norm() > 0.0) || !needle.direction.allFinite())
    throw std::invalid_argument("needle: 'direction' must be a non-zero vector");
  needle.direction.normalize();
  if (!(needle.radius > 0.0))
    throw std::invalid_argument(
        fmt::format("needle: 'radius' must be > 0 m (got {})", needle.radius));
  if (!(needle.spacing > 0.0) || !std::isfinite(needle.spacing))
    throw std::invalid_argument(
        fmt::format("needle: 'spacing' must be > 0 m (got {})", needle.spacing));
  if (needle.tissues.empty())
    throw std::invalid_argument("needle: give at least one tissue it may puncture");
  for (NeedleTissue& t : needle.tissues) {
    check_tissue(model, t);
    t.tetrahedra = cell_tetrahedra(model, t.component);
  }
  if (needle.target_component >= 0) {
    if (size_t(needle.target_component) >= model.components.size())
      throw std::invalid_argument(fmt::format("needle: no component {}", needle.target_component));
    for (int i : needle.target.nodes)
      if (i < 0 || i >= model.node_count())
        throw std::invalid_argument(fmt::format("needle: target node {} out of range", i));
  }
  needle.track_capacity = track_capacity(needle);
  model.needles.push_back(std::move(needle));
}

}  // namespace phymul

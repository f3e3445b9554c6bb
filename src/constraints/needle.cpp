#include "constraints/needle.hpp"

#include <algorithm>
#include <cmath>

#include "model/embedding.hpp"

namespace phymul {
namespace {

// Per axis, the inverse mass of an embedded point: sum of w_k^2 / m_k over its nodes.
Vec3 point_inverse_mass(const Model& model, const EmbeddedPoint& p) {
  Vec3 w = Vec3::Zero();
  for (size_t k = 0; k < 4; ++k)
    w += p.weights[k] * p.weights[k] * model.inverse_mass[size_t(p.nodes[k])];
  return w;
}

}  // namespace

Vec3 move_point(const Model& model, const EmbeddedPoint& p, const Vec3& delta, std::span<Vec3> x,
                double dt) {
  const Vec3 w = point_inverse_mass(model, p);
  Vec3 impulse = Vec3::Zero();
  for (int a = 0; a < 3; ++a) {
    if (!(w[a] > 0.0)) continue;
    for (size_t k = 0; k < 4; ++k) {
      const double wi = model.inverse_mass[size_t(p.nodes[k])][a];
      if (wi > 0.0) x[size_t(p.nodes[k])][a] += p.weights[k] * wi * delta[a] / w[a];
    }
    impulse[a] = delta[a] / (w[a] * dt);  // sum of m dx / dt over the nodes
  }
  return impulse;
}

namespace {

// Inverse mass of the point along the unit direction d.
double along(const Vec3& w, const Vec3& d) { return w.dot(d.cwiseProduct(d)); }

struct Stage {
  const Model& model;
  const Needle& n;
  NeedleState& s;
  std::span<Vec3> x;
  double depth, time, dt;
  bool advancing;
  Vec3 impulse = Vec3::Zero();  // N s given to the tissues
  Vec3 tip() const { return needle_tip(n, depth); }
  double axial(const Vec3& p) const { return (p - n.base).dot(n.direction); }
};

// Before puncture: the tip holds the surface point it met (a sticking point contact) while
// it pushes; the surface gives way when that push exceeds the tissue's puncture force.
void press_or_puncture(Stage& g) {
  const int t = pressed_tissue(g.n, g.s, g.x, g.depth, g.advancing);
  if (t < 0) return;
  auto pressed = g.s.phase.begin() + std::ptrdiff_t(t);
  const Vec3 delta = g.tip() - g.s.contact.point.at(g.x);
  if (delta.dot(g.n.direction) < 0.0) {  // the surface is ahead of the tip: not pressed
    *pressed = needle_outside;
    return;
  }
  const Vec3 j = move_point(g.model, g.s.contact.point, delta, g.x, g.dt);
  g.impulse += j;
  const double push = j.dot(g.n.direction) / g.dt;
  if (push <= g.n.tissues[size_t(t)].puncture_force) return;
  *pressed = needle_punctured;
  if (g.s.punctures.size() < g.s.punctures.capacity())
    g.s.punctures.push_back({t, g.time, g.depth, push});
  if (g.s.track.size() < g.s.track.capacity()) g.s.track.push_back(g.s.contact);
  g.s.contact.length = 0.0;
  g.s.last_point_depth = g.depth;
  g.s.tip_tissue = t;
}

// After puncture: every track point back on the shaft's axis, and along it at its anchor
// while the force that takes is within its share of the friction (friction x its length),
// else moved by that force only and anchored where it slid to (kinetic friction). While the
// tip advances, the newest point of the tissue it is in is being cut: it takes the cutting
// force instead of its friction.
void hold_track(Stage& g) {
  const Vec3& d = g.n.direction;
  for (size_t k = 0; k < g.s.track.size(); ++k) {
    TrackPoint& p = g.s.track[k];
    const NeedleTissue& tissue = g.n.tissues[size_t(p.tissue)];
    const Vec3 at = p.point.at(g.x);
    const double a = g.axial(at);
    const Vec3 lateral = (at - g.n.base) - a * d;
    const double w = along(point_inverse_mass(g.model, p.point), d);
    const bool cut = g.advancing && k + 1 == g.s.track.size() && p.tissue == g.s.tip_tissue;
    // Metres of slide per newton over the step (x = F w dt^2).
    const double per_newton = w * g.dt * g.dt;
    const double bound = tissue.friction * p.length * per_newton;
    const double wanted = p.anchor + g.depth - a;
    // The tissue being cut takes the cutting force alone: held by friction it would ride on
    // the tip, and the tip would never leave its cell.
    const double slide =
        cut ? tissue.cutting_force * per_newton : std::clamp(wanted, -bound, bound);
    if (slide != wanted) p.anchor = a + slide - g.depth;  // slid: it sticks where it went
    g.impulse += move_point(g.model, p.point, slide * d - lateral, g.x, g.dt);
  }
}

// Track points share the nodes of their cells, so moving one moves its neighbours a little:
// Gauss-Seidel sweeps of the lateral part alone until every point is on the axis.
void settle_on_axis(Stage& g) {
  constexpr int kSweeps = 64;
  const double tolerance = 1e-12 * g.n.spacing;
  for (int sweep = 0; sweep < kSweeps; ++sweep) {
    double worst = 0.0;
    for (const TrackPoint& p : g.s.track) {
      const Vec3 at = p.point.at(g.x);
      const Vec3 lateral = (at - g.n.base) - g.axial(at) * g.n.direction;
      worst = std::max(worst, lateral.norm());
      g.impulse += move_point(g.model, p.point, -lateral, g.x, g.dt);
    }
    if (worst <= tolerance) return;
  }
}

void apply_needle(Stage& g) {
  release_track(g.s, g.depth);
  press_or_puncture(g);
  extend_track(g.n, g.s, g.x, g.depth, g.advancing);
  hold_track(g);
  settle_on_axis(g);
  g.s.depth = g.depth;
  g.s.force = -g.impulse / g.dt;
}

}  // namespace

void release_track(NeedleState& s, double depth) {
  if (depth < s.depth) std::erase_if(s.track, [&](const TrackPoint& p) { return p.anchor > 0.0; });
  s.last_point_depth = std::min(s.last_point_depth, depth);
  for (size_t t = 0; t < s.phase.size(); ++t) {
    if (s.phase[t] != needle_punctured) continue;
    const bool held = std::any_of(s.track.begin(), s.track.end(),
                                  [&](const TrackPoint& p) { return p.tissue == int(t); });
    if (held) continue;
    s.phase[t] = needle_outside;
    if (s.tip_tissue == int(t)) s.tip_tissue = -1;
  }
}

// One point a tetrahedron: points embedded at different times are not on one line in the
// cell's own coordinates, and an affine cell cannot put three such points on the shaft.
void extend_track(const Needle& n, NeedleState& s, std::span<const Vec3> x, double depth,
                  bool advancing) {
  const double travel = depth - s.last_point_depth;
  if (!advancing || travel < n.spacing) return;
  s.last_point_depth = depth;
  s.tip_tissue = -1;
  for (size_t t = 0; t < s.phase.size(); ++t) {
    if (s.phase[t] != needle_punctured) continue;
    EmbeddedPoint p;
    if (!embed_point(n.tissues[t].tetrahedra, x, needle_tip(n, depth), p)) continue;
    s.tip_tissue = int(t);
    if (!s.track.empty() && s.track.back().point.nodes == p.nodes)
      s.track.back().length += travel;
    else if (s.track.size() < s.track.capacity())
      s.track.push_back({int(t), p, 0.0, travel});
    return;
  }
}

int pressed_tissue(const Needle& n, NeedleState& s, std::span<const Vec3> x, double depth,
                   bool advancing) {
  const auto pressed = std::find(s.phase.begin(), s.phase.end(), int(needle_pressed));
  if (pressed != s.phase.end()) return int(pressed - s.phase.begin());
  if (!advancing) return -1;
  for (size_t t = 0; t < s.phase.size(); ++t) {
    if (s.phase[t] != needle_outside) continue;
    EmbeddedPoint p;
    if (!embed_point(n.tissues[t].tetrahedra, x, needle_tip(n, depth), p)) continue;
    s.contact = {int(t), p, 0.0, 0.0};
    s.phase[t] = needle_pressed;
    return int(t);
  }
  return -1;
}

void apply_needles(const Model& model, const Controls& controls, std::span<Vec3> x,
                   double load_time, ContactStep& step) {
  if (!step.needles) return;
  for (size_t k = 0; k < model.needles.size(); ++k) {
    NeedleState& s = (*step.needles)[k];
    const double depth = controls.needle_depth[k].at(load_time).x();
    Stage g{model, model.needles[k], s, x, depth, load_time, step.dt, depth > s.depth};
    apply_needle(g);
  }
}

}  // namespace phymul

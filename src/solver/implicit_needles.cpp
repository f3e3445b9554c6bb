#include "solver/implicit_needles.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "constraints/needle.hpp"

namespace phymul {
namespace {

// Needle k at load_time: its depth, and whether it advances over the step.
struct NeedleAt {
  const Needle& n;
  NeedleState& st;
  double depth;
  bool advancing;
};

NeedleAt needle_at(const Model& model, Data& d, size_t k, double load_time) {
  const double depth = d.controls.needle_depth[k].at(load_time).x();
  return {model.needles[k], d.needles[k], depth, depth > d.needles[k].depth};
}

// Two unit directions across the shaft.
std::array<Vec3, 2> across(const Vec3& direction) {
  const Vec3 other = std::abs(direction.x()) < 0.9 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 first = direction.cross(other).normalized();
  return {first, direction.cross(first)};
}

// The row push . (sum of w_k dx_k) = -gap over the point's nodes, unless none moves.
void add_row(ImplicitSystem& s, int needle, int point, const EmbeddedPoint& p, const Vec3& push,
             double gap) {
  if (!moves(s, p.nodes[0]) && !moves(s, p.nodes[1]) && !moves(s, p.nodes[2]) &&
      !moves(s, p.nodes[3]))
    return;
  if (s.pair_rows.size() >= s.pair_rows.capacity() || int(s.pair_rows.size()) >= s.row_capacity)
    throw std::runtime_error("the implicit step takes at most " + std::to_string(s.row_capacity) +
                             " contact and needle rows at once; more hold now: use "
                             "'integrator: verlet'");
  ImplicitSystem::Contact row;
  row.nodes = p.nodes;
  row.weights = p.weights;
  row.count = 4;
  row.push = push;
  row.gap = gap;
  row.needle = needle;
  row.point = point;
  s.pair_rows.push_back(row);
}

// Whether track point j of needle k is the one the advancing tip cuts.
bool cut(const NeedleState& st, size_t j, bool advancing) {
  return advancing && j + 1 == st.track.size() && st.track[j].tissue == st.tip_tissue;
}

// The load (N along the shaft, on the tissue) a cut or sliding point takes; 0 for a sticking one.
double load(const Needle& n, const NeedleState& st, const ImplicitSystem& s, size_t k, size_t j,
            bool advancing) {
  const NeedleTissue& tissue = n.tissues[size_t(st.track[j].tissue)];
  if (cut(st, j, advancing)) return tissue.cutting_force;
  return s.needle_slide[k][j] * tissue.friction * st.track[j].length;
}

bool sticks(const NeedleState& st, const ImplicitSystem& s, size_t k, size_t j, bool advancing) {
  return s.needle_slide[k][j] == 0 && !cut(st, j, advancing);
}

// Moves a point's load into the residual: node k of the point takes w_k F.
void add_load(ImplicitSystem& s, const EmbeddedPoint& p, const Vec3& force) {
  for (size_t k = 0; k < 4; ++k) gather_node(s, p.nodes[k], p.weights[k] * force, s.residual);
}

// A pressed surface gives way: the point it held begins the track, cut by the tip.
void puncture(NeedleState& st, ImplicitSystem& s, size_t k, int tissue, double time, double depth,
              double push) {
  st.phase[size_t(tissue)] = needle_punctured;
  if (st.punctures.size() < st.punctures.capacity())
    st.punctures.push_back({tissue, time, depth, push});
  if (st.track.size() < st.track.capacity()) {
    st.track.push_back(st.contact);
    s.needle_slide[k].push_back(1);
  }
  st.contact.length = 0.0;
  st.last_point_depth = depth;
  st.tip_tissue = tissue;
}

}  // namespace

size_t needle_row_count(const Model& model) {
  size_t rows = 0;
  for (const Needle& n : model.needles) rows += 3 + 3 * size_t(n.track_capacity);
  return rows;
}

void prepare_implicit_needles(const Model& model, ImplicitSystem& s) {
  s.needle_slide.assign(model.needles.size(), {});
  for (size_t k = 0; k < model.needles.size(); ++k)
    s.needle_slide[k].reserve(size_t(model.needles[k].track_capacity));
}

void start_needles(const Model& model, Data& d, ImplicitSystem& s, double load_time) {
  s.needles_changed = false;
  for (size_t k = 0; k < model.needles.size(); ++k) {
    auto [n, st, depth, advancing] = needle_at(model, d, k, load_time);
    release_track(st, depth);
    pressed_tissue(n, st, d.x, depth, advancing);  // held until it pulls (update_needles)
    extend_track(n, st, d.x, depth, advancing);
    // A point of no length has no friction to stick by.
    s.needle_slide[k].clear();
    for (const TrackPoint& p : st.track)
      s.needle_slide[k].push_back(n.tissues[size_t(p.tissue)].friction * p.length > 0.0 ? 0 : 1);
  }
}

void add_needle_rows(const Model& model, Data& d, ImplicitSystem& s, double load_time) {
  if (model.contact_pairs.empty()) s.pair_rows.clear();
  for (size_t k = 0; k < model.needles.size(); ++k) {
    auto [n, st, depth, advancing] = needle_at(model, d, k, load_time);
    const Vec3 tip = needle_tip(n, depth);
    for (int phase : st.phase)
      if (phase == needle_pressed) {
        const Vec3 gap = st.contact.point.at(d.x) - tip;
        for (int a = 0; a < 3; ++a) add_row(s, int(k), -1, st.contact.point, Vec3::Unit(a), gap[a]);
      }
    const std::array<Vec3, 2> side = across(n.direction);
    for (size_t j = 0; j < st.track.size(); ++j) {
      const TrackPoint& p = st.track[j];
      const Vec3 from_base = p.point.at(d.x) - n.base;
      for (const Vec3& e : side) add_row(s, int(k), int(j), p.point, e, e.dot(from_base));
      if (sticks(st, s, k, j, advancing))
        add_row(s, int(k), int(j), p.point, n.direction,
                n.direction.dot(from_base) - (p.anchor + depth));
      else
        add_load(s, p.point, load(n, st, s, k, j, advancing) * n.direction);
    }
  }
}

void update_needles(const Model& model, Data& d, ImplicitSystem& s, double load_time, bool decide) {
  s.needles_changed = false;
  for (size_t k = 0; k < model.needles.size(); ++k) {
    auto [n, st, depth, advancing] = needle_at(model, d, k, load_time);
    Vec3 on_tissue = Vec3::Zero(), pressing = Vec3::Zero();
    for (size_t c = 0; c < s.pair_rows.size(); ++c) {
      const ImplicitSystem::Contact& row = s.pair_rows[c];
      if (row.needle != int(k)) continue;
      const Vec3 force = s.pair_force[c] * row.push;
      on_tissue += force;
      if (row.point < 0) {
        pressing += force;
        continue;
      }
      // A sticking point held beyond its friction slides, that way, for the rest of the step.
      const size_t j = size_t(row.point);
      const double bound = n.tissues[size_t(st.track[j].tissue)].friction * st.track[j].length;
      if (decide && row.push == n.direction && std::abs(s.pair_force[c]) > bound) {
        s.needle_slide[k][j] = s.pair_force[c] > 0.0 ? 1 : -1;
        s.needles_changed = true;
      }
    }
    for (size_t j = 0; j < st.track.size(); ++j)
      if (!sticks(st, s, k, j, advancing))
        on_tissue += load(n, st, s, k, j, advancing) * n.direction;
    st.force = -on_tissue;
    const double push = pressing.dot(n.direction);
    for (int t = 0; t < int(st.phase.size()) && decide; ++t) {
      if (st.phase[size_t(t)] != needle_pressed) continue;
      if (push > n.tissues[size_t(t)].puncture_force) puncture(st, s, k, t, load_time, depth, push);
      // The tip would pull the surface back: it lets go. (Below the step's tolerance the push
      // is its convergence error: a point just pressed carries none yet.)
      else if (push < -model.settings.implicit_tolerance)
        st.phase[size_t(t)] = needle_outside;
      else
        continue;
      s.needles_changed = true;
    }
  }
}

void project_needles(const Model& model, Data& d, const ImplicitSystem& s, double load_time) {
  constexpr int kSweeps = 64;  // as the explicit stage: points share their cells' nodes
  for (size_t k = 0; k < model.needles.size(); ++k) {
    auto [n, st, depth, advancing] = needle_at(model, d, k, load_time);
    const Vec3 tip = needle_tip(n, depth);
    const bool pressed =
        std::find(st.phase.begin(), st.phase.end(), int(needle_pressed)) != st.phase.end();
    for (int sweep = 0; sweep < kSweeps; ++sweep) {
      double worst = 0.0;
      if (pressed) {
        const Vec3 delta = tip - st.contact.point.at(d.x);
        worst = delta.norm();
        move_point(model, st.contact.point, delta, d.x, 1.0);
      }
      for (size_t j = 0; j < st.track.size(); ++j) {
        const TrackPoint& p = st.track[j];
        const Vec3 from_base = p.point.at(d.x) - n.base;
        const double a = n.direction.dot(from_base);
        Vec3 delta = a * n.direction - from_base;
        if (sticks(st, s, k, j, advancing)) delta += (p.anchor + depth - a) * n.direction;
        worst = std::max(worst, delta.norm());
        move_point(model, p.point, delta, d.x, 1.0);
      }
      if (worst <= 1e-12 * n.spacing) break;
    }
  }
}

void end_needles(const Model& model, Data& d, const ImplicitSystem& s, double load_time) {
  for (size_t k = 0; k < model.needles.size(); ++k) {
    auto [n, st, depth, advancing] = needle_at(model, d, k, load_time);
    for (size_t j = 0; j < st.track.size(); ++j)
      if (!sticks(st, s, k, j, advancing))  // it sticks where it slid to
        st.track[j].anchor = n.direction.dot(st.track[j].point.at(d.x) - n.base) - depth;
    st.depth = depth;
  }
}

}  // namespace phymul

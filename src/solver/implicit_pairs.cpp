#include "solver/implicit_pairs.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "constraints/deformable_contact.hpp"
#include "model/workspace.hpp"
#include "solver/implicit_contacts.hpp"

namespace phymul {
namespace {

// m: a node this close to the other side's surface (or inside it) touches it, as an
// obstacle's (solver/implicit_step.cpp).
constexpr double kTouching = 1e-9;
// m: a row this close to (or inside) the other side's surface may carry a force in the fit.
// With the touching distance alone, a node the volume projection moved 0.2 um off the surface
// carried nothing, the solve pressed it back in, the projections moved it out again: the 5 mm
// neck's four rows cycled through three sets (0.19, 0.23, 0.003 N) for ever.
constexpr double kCarrying = 1e-6;

// g_c . g_d: the rows' shared unknowns (a node, or doubled nodes sharing one).
double overlap(const ImplicitSystem& s, const ImplicitSystem::Contact& c,
               const ImplicitSystem::Contact& d) {
  double sum = 0.0;
  for (int k = 0; k < c.count; ++k)
    for (int l = 0; l < d.count; ++l)
      for (int a = 0; a < 3; ++a) {
        const int u = s.unknown[size_t(a)][size_t(c.nodes[size_t(k)])];
        if (u >= 0 && u == s.unknown[size_t(a)][size_t(d.nodes[size_t(l)])])
          sum += c.weights[size_t(k)] * d.weights[size_t(l)] * c.push[a] * d.push[a];
      }
  return sum;
}

// Node p's row against face f of the other side of pair k: p kept on the outer side of the
// face's plane, the contact point moving with the face's nodes by its closest point's weights.
void add_face_row(const Model& model, ImplicitSystem& s, int k, int side, int p, int f,
                  const std::vector<Vec3>& x) {
  const Triangle& t = model.contact_pairs[size_t(k)].faces[size_t(1 - side)][size_t(f)];
  const Vec3 b =
      closest_barycentric(x[size_t(p)], x[size_t(t[0])], x[size_t(t[1])], x[size_t(t[2])]);
  const Vec3 normal =
      (x[size_t(t[1])] - x[size_t(t[0])]).cross(x[size_t(t[2])] - x[size_t(t[0])]).normalized();
  ImplicitSystem::Contact row;
  row.nodes = {p, t[0], t[1], t[2]};
  row.weights = {1.0, -b[0], -b[1], -b[2]};
  row.count = 4;
  row.push = normal;
  row.gap = normal.dot(x[size_t(p)] - x[size_t(t[0])]);
  row.pair = k;
  row.side = side;
  if (!std::any_of(row.nodes.begin(), row.nodes.end(), [&](int i) { return moves(s, i); }))
    return;  // nothing the solve moves
  if (s.pair_rows.size() >= s.pair_rows.capacity() || int(s.pair_rows.size()) >= s.row_capacity)
    throw std::runtime_error("the implicit step takes at most " + std::to_string(s.row_capacity) +
                             " contact rows at once; more touch now: use 'integrator: verlet'");
  s.pair_rows.push_back(row);
}

// Side `side`'s rows of pair k at x against the other side's surface.
void find_side(const Model& model, Data& d, ImplicitSystem& s, int k, int side) {
  Workspace& w = *d.work;
  const ContactPair& pair = model.contact_pairs[size_t(k)];
  const int other = 1 - side;
  const std::vector<Vec3>& x = d.x;
  TriangleHash& hash = w.pair_hashes[size_t(k)][size_t(other)];
  const SurfaceReach reach = prepare_surface(pair, other, x, hash, w.vertex_normal);
  const ImplicitSystem::FaceRing& ring = s.face_rings[size_t(k)][size_t(other)];
  for (int p : pair.nodes[size_t(side)]) {
    if (!reach.contains(x[size_t(p)])) continue;
    // A node both surfaces share (stitched) is on the other one by construction.
    if (ring.start[size_t(p)] < ring.start[size_t(p) + 1]) continue;
    const SurfacePoint hit =
        nearest_surface_point(pair, other, hash, w.vertex_normal, x, x[size_t(p)], pair.margin);
    if (hit.face < 0 || (hit.depth > kTouching && s.pair_held[size_t(p)] != k)) continue;
    // The faces the closest point lies on: one inside a face, two on an edge, the ring at a
    // corner. A row each along its own normal: the closest point's direction turns as the
    // node slides past an edge or a corner, which a row fixed to it cannot follow (two balls
    // first touching corner on corner: the iterations stalled at 3.6e-3 N).
    const Triangle& t = pair.faces[size_t(other)][size_t(hit.face)];
    const Vec3& b = hit.weights;
    const int zeros = int(b[0] == 0.0) + int(b[1] == 0.0) + int(b[2] == 0.0);
    const int u = b[0] != 0.0 ? t[0] : b[1] != 0.0 ? t[1] : t[2];
    const int v = zeros == 1 ? (b[2] != 0.0 ? t[2] : t[1]) : -1;
    if (zeros == 0) {
      add_face_row(model, s, k, side, p, hit.face, x);
      continue;
    }
    for (int e = ring.start[size_t(u)]; e < ring.start[size_t(u) + 1]; ++e) {
      const int f = ring.faces[size_t(e)];
      const Triangle& tf = pair.faces[size_t(other)][size_t(f)];
      if (v < 0 || std::find(tf.begin(), tf.end(), v) != tf.end())
        add_face_row(model, s, k, side, p, f, x);
    }
  }
}

// Solves the fit over the volumes and the rows `taken` marks (s.fit: the full normal
// equations, s.fit_rhs their right-hand side, n = volumes + rows) into s.rhs, by row.
void solve_taken(ImplicitSystem& s, int volumes, int n) {
  int m = 0;
  for (int r = 0; r < n; ++r)
    if (r < volumes || s.held[size_t(r - volumes)]) s.fit_rows[size_t(m++)] = r;
  for (int i = 0; i < m; ++i) {
    const int r = s.fit_rows[size_t(i)];
    s.system_rhs[size_t(i)] = s.fit_rhs[size_t(r)];
    for (int j = 0; j < m; ++j)
      s.schur[size_t(i * m + j)] = s.fit[size_t(r * n + s.fit_rows[size_t(j)])];
  }
  solve_dense(s.schur.data(), s.system_rhs.data(), m);
  std::fill(s.rhs.begin(), s.rhs.begin() + n, 0.0);
  for (int i = 0; i < m; ++i) s.rhs[size_t(s.fit_rows[size_t(i)])] = s.system_rhs[size_t(i)];
}

}  // namespace

void prepare_pair_rows(const Model& model, ImplicitSystem& s) {
  s.face_rings.assign(model.contact_pairs.size(), {});
  size_t rows = 0;
  for (size_t k = 0; k < model.contact_pairs.size(); ++k)
    for (int side = 0; side < 2; ++side) {
      const std::vector<Triangle>& faces = model.contact_pairs[k].faces[size_t(side)];
      ImplicitSystem::FaceRing& ring = s.face_rings[k][size_t(side)];
      ring.start.assign(size_t(model.node_count()) + 1, 0);
      for (const Triangle& t : faces)
        for (int i : t) ++ring.start[size_t(i) + 1];
      size_t most = 0;
      for (int i = 0; i < model.node_count(); ++i) {
        most = std::max(most, size_t(ring.start[size_t(i) + 1]));
        ring.start[size_t(i) + 1] += ring.start[size_t(i)];
      }
      ring.faces.resize(3 * faces.size());
      std::vector<int> at(ring.start.begin(), ring.start.end() - 1);
      for (int f = 0; f < int(faces.size()); ++f)
        for (int i : faces[size_t(f)]) ring.faces[size_t(at[size_t(i)]++)] = f;
      rows += model.contact_pairs[k].nodes[size_t(1 - side)].size() * std::max<size_t>(most, 1);
    }
  s.pair_rows.reserve(rows);
}

void hold_pair_contacts(const Data& d, ImplicitSystem& s) {
  std::fill(s.pair_held.begin(), s.pair_held.end(), -1);
  for (const PairContact& c : d.pair_contacts)
    if (c.impulse > 0.0) s.pair_held[size_t(c.node)] = c.pair;
}

void find_pair_contacts(const Model& model, Data& d, ImplicitSystem& s) {
  s.pair_rows.clear();
  for (int k = 0; k < int(model.contact_pairs.size()); ++k)
    for (int side = 0; side < 2; ++side) find_side(model, d, s, k, side);
}

void fit_pressures_and_pair_forces(const Model& model, ImplicitSystem& s, const double* gg,
                                   const double* gr, double* pressure) {
  const int volumes = int(model.volumes.size()), rows = int(s.pair_rows.size());
  const int n = volumes + rows;
  double* N = s.fit.data();
  for (int l = 0; l < volumes; ++l) {
    s.fit_rhs[size_t(l)] = gr[l];
    for (int m = 0; m < volumes; ++m) N[l * n + m] = gg[l * volumes + m];
  }
  for (int c = 0; c < rows; ++c) {
    const ImplicitSystem::Contact& row = s.pair_rows[size_t(c)];
    const int r = volumes + c;
    s.fit_rhs[size_t(r)] = along(s, row, s.residual);
    for (int l = 0; l < volumes; ++l)
      N[r * n + l] = N[l * n + r] = along(s, row, s.gradient[size_t(l)]);
    for (int e = 0; e <= c; ++e)
      N[r * n + volumes + e] = N[(volumes + e) * n + r] = overlap(s, row, s.pair_rows[size_t(e)]);
    // A row clear of the surface carries nothing; a needle's holds both ways.
    s.held[size_t(c)] = row.needle >= 0 || row.gap <= kCarrying;
  }
  // A contact only pushes: non-negative least squares by active sets (Lawson and Hanson): the
  // row fitted pulling hardest (a positive coefficient: r along +g) is let go and the rest
  // fitted again; once none pulls, a touching row let go that the rest of the residual presses
  // into (g . (r - G^T c) < 0) is taken back. Letting every pulling row go at once can end on a
  // set that is not the fit, and the residual then jumps as the set does (the 5 mm neck: three
  // sets in turn, 0.19, 0.23 and 0.003 N, for ever).
  for (int c = 0; c < rows; ++c) s.touching[size_t(c)] = s.held[size_t(c)];
  for (int round = 0; round < 4 * rows + 4; ++round) {
    solve_taken(s, volumes, n);
    int worst = -1;
    for (int c = 0; c < rows; ++c)
      if (s.held[size_t(c)] && s.pair_rows[size_t(c)].needle < 0 &&
          s.rhs[size_t(volumes + c)] > (worst < 0 ? 0.0 : s.rhs[size_t(volumes + worst)]))
        worst = c;
    if (worst >= 0) {
      s.held[size_t(worst)] = 0;
      continue;
    }
    double most = 0.0;
    for (int c = 0; c < rows; ++c) {
      if (s.held[size_t(c)] || !s.touching[size_t(c)]) continue;
      double left = s.fit_rhs[size_t(volumes + c)];  // g . (r - G^T c)
      for (int e = 0; e < n; ++e) left -= N[(volumes + c) * n + e] * s.rhs[size_t(e)];
      if (left < most) most = left, worst = c;
    }
    if (worst < 0 || !(most < -1e-12 * (1.0 + std::abs(s.fit_rhs[size_t(volumes + worst)])))) break;
    s.held[size_t(worst)] = 1;
  }
  for (int l = 0; l < volumes; ++l) pressure[l] = s.rhs[size_t(l)];
  for (int c = 0; c < rows; ++c) s.pair_force[size_t(c)] = -s.rhs[size_t(volumes + c)];
}

void take_out_pair_forces(Data& d, ImplicitSystem& s) {
  d.pair_contacts.clear();
  std::fill(d.pair_contact_force.begin(), d.pair_contact_force.end(), Vec3::Zero());
  for (size_t c = 0; c < s.pair_rows.size(); ++c) {
    ImplicitSystem::Contact row = s.pair_rows[c];
    const double force = s.pair_force[c];
    // Pressed: carrying a force in the fit. Where a node presses into an edge or a corner, the
    // residual's push along each face's row need not tell which faces carry it.
    row.into = -force;
    s.active.push_back(row);
    if (force == 0.0) continue;
    for (int k = 0; k < row.count; ++k)
      for (int a = 0; a < 3; ++a)
        if (const int u = s.unknown[size_t(a)][size_t(row.nodes[size_t(k)])]; u >= 0)
          s.residual[size_t(a)][u] += force * row.weights[size_t(k)] * row.push[a];
    if (row.needle >= 0) continue;  // its force is the needle's (implicit_needles.cpp)
    d.pair_contact_force[size_t(row.pair)] += (row.side == 0 ? force : -force) * row.push;
    if (d.pair_contacts.size() == d.pair_contacts.capacity())
      throw std::runtime_error("the implicit step records at most " +
                               std::to_string(d.pair_contacts.capacity()) +
                               " pressed contact rows; more press now: use 'integrator: verlet'");
    d.pair_contacts.push_back(
        {row.pair, row.side, row.nodes[0], Triangle{row.nodes[1], row.nodes[2], row.nodes[3]},
         Vec3(-row.weights[1], -row.weights[2], -row.weights[3]), row.push, force * d.dt});
  }
}

}  // namespace phymul

#include "constraints/deformable_contact.hpp"

#include <algorithm>
#include <cmath>

namespace phymul {

Vec3 closest_barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Ericson, Real-Time Collision Detection, 5.1.5: Voronoi regions of the triangle.
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {1, 0, 0};
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return {1 - v - w, v, w};
}

void vertex_normals(const std::vector<Triangle>& faces, const std::vector<int>& nodes,
                    std::span<const Vec3> x, std::vector<Vec3>& normal) {
  for (int i : nodes) normal[size_t(i)].setZero();
  for (const Triangle& t : faces) {
    const Vec3 twice_area = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
    for (int i : t) normal[size_t(i)] += twice_area;
  }
  for (int i : nodes) normal[size_t(i)].normalize();
}

SurfacePoint nearest_surface_point(const ContactPair& pair, int other, TriangleHash& hash,
                                   const std::vector<Vec3>& vertex_normal, std::span<const Vec3> x,
                                   const Vec3& p, double margin) {
  const std::vector<Triangle>& faces = pair.faces[size_t(other)];
  double best = margin * margin;
  SurfacePoint found;
  hash.around(p, [&](int k) {
    const Triangle& t = faces[size_t(k)];
    const Vec3 w = closest_barycentric(p, x[t[0]], x[t[1]], x[t[2]]);
    const Vec3 q = w[0] * x[t[0]] + w[1] * x[t[1]] + w[2] * x[t[2]];
    const double d2 = (p - q).squaredNorm();
    if (d2 >= best) return;
    best = d2;
    found.face = k;
    found.weights = w;
  });
  if (found.face < 0) return found;
  const Triangle& t = faces[size_t(found.face)];
  const Vec3& w = found.weights;
  const Vec3 q = w[0] * x[t[0]] + w[1] * x[t[1]] + w[2] * x[t[2]];
  const double distance = std::sqrt(best);
  // Inside or outside: the sign along the interpolated vertex normal, right at edges and
  // corners too. The push itself goes straight to the closest point (the gradient of the
  // distance): a smoothed direction would not be normal to the surface, and its tangential
  // part would make the node creep along the surface for ever.
  const Vec3 smooth = w[0] * vertex_normal[size_t(t[0])] + w[1] * vertex_normal[size_t(t[1])] +
                      w[2] * vertex_normal[size_t(t[2])];
  if (distance == 0.0) {
    found.normal = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).normalized();
    return found;  // exactly on the surface
  }
  const bool outside = (p - q).dot(smooth) >= 0.0;
  found.depth = outside ? distance : -distance;
  found.normal = (outside ? Vec3(p - q) : Vec3(q - p)) / distance;
  return found;
}

SurfaceReach prepare_surface(const ContactPair& pair, int other, std::span<const Vec3> x,
                             TriangleHash& hash, std::vector<Vec3>& vertex_normal) {
  hash.build(pair.faces[size_t(other)], x, pair.margin);
  vertex_normals(pair.faces[size_t(other)], pair.nodes[size_t(other)], x, vertex_normal);
  SurfaceReach r{x[size_t(pair.nodes[size_t(other)][0])], x[size_t(pair.nodes[size_t(other)][0])]};
  for (int i : pair.nodes[size_t(other)])
    r.lo = r.lo.cwiseMin(x[size_t(i)]), r.hi = r.hi.cwiseMax(x[size_t(i)]);
  r.lo.array() -= pair.margin;
  r.hi.array() += pair.margin;
  return r;
}

namespace {

// n . (W n) for a per-axis inverse mass W.
double along(const Vec3& inverse_mass, const Vec3& n) {
  return n.dot(inverse_mass.cwiseProduct(n));
}

}  // namespace

void apply_deformable_contacts(const Model& model, std::span<Vec3> x, Workspace& work,
                               std::vector<PairContact>& contacts, double dt,
                               std::span<Vec3> pair_impulse) {
  contacts.clear();
  for (int sweep = 0; sweep < kPairContactSweeps; ++sweep) {
    bool any = false;
    for (size_t k = 0; k < model.contact_pairs.size(); ++k) {
      const ContactPair& pair = model.contact_pairs[k];
      for (int side = 0; side < 2; ++side) {
        const int other = 1 - side;
        TriangleHash& hash = work.pair_hashes[k][size_t(other)];
        const SurfaceReach reach = prepare_surface(pair, other, x, hash, work.vertex_normal);
        for (int p : pair.nodes[size_t(side)]) {
          if (!reach.contains(x[size_t(p)])) continue;
          const SurfacePoint hit =
              nearest_surface_point(pair, other, hash, work.vertex_normal, x, x[p], pair.margin);
          if (hit.face < 0 || hit.depth >= 0.0) continue;
          const Triangle& t = pair.faces[size_t(other)][size_t(hit.face)];
          const Vec3& n = hit.normal;
          const Vec3& b = hit.weights;
          double s = along(model.inverse_mass[size_t(p)], n);
          for (int j = 0; j < 3; ++j) s += b[j] * b[j] * along(model.inverse_mass[size_t(t[j])], n);
          if (s <= 0.0) continue;  // every node involved is held along n
          // C = (p - sum b_j x_j) . n is linear in the positions for fixed b and n: this
          // mass-weighted move brings it to zero exactly.
          const double lambda = -hit.depth / s;
          const Vec3 dp = lambda * model.inverse_mass[size_t(p)].cwiseProduct(n);
          x[size_t(p)] += dp;
          for (int j = 0; j < 3; ++j)
            x[size_t(t[j])] -= lambda * b[j] * model.inverse_mass[size_t(t[j])].cwiseProduct(n);
          // The multiplier is the impulse (times dt) on the node, and minus it on the triangle,
          // whether or not their supports hold them.
          pair_impulse[k] += (side == 0 ? lambda : -lambda) / dt * n;
          if (contacts.size() < contacts.capacity())  // never reallocates in a step
            contacts.push_back({int(k), side, p, t, b, n, lambda / dt});
          any = true;
        }
      }
    }
    if (!any) return;
  }
}

double apply_deformable_contact_velocities(const Model& model, std::span<Vec3> v,
                                           std::span<PairContact> contacts,
                                           std::span<Vec3> pair_impulse, std::span<double> pushed) {
  // Projected Gauss-Seidel: each record's impulse is accumulated and kept >= 0, and the sweeps
  // go on until no record changes a relative speed by more than kSettled. One plain pass (each
  // approach removed once, never given back) left, where two records share nodes (a node on a
  // face whose vertex rests on the node's own face), a node leaving its face at 3 cm/s for ever
  // while its position stood: kinetic energy the relaxations could not take out.
  constexpr double kSettled = 1e-12;  // m/s
  constexpr int kMostSweeps = 200;
  const size_t n = contacts.size();
  std::fill(pushed.begin(), pushed.begin() + std::ptrdiff_t(n), 0.0);
  double largest = 0.0;
  for (int sweep = 0; sweep < kMostSweeps; ++sweep) {
    double change = 0.0;
    for (size_t k = 0; k < n; ++k) {
      PairContact& c = contacts[k];
      const Vec3& normal = c.normal;
      const Vec3& b = c.weights;
      Vec3 surface = Vec3::Zero();
      for (int j = 0; j < 3; ++j) surface += b[j] * v[size_t(c.triangle[j])];
      const double approach = (v[size_t(c.node)] - surface).dot(normal);  // < 0: approaching
      double s = along(model.inverse_mass[size_t(c.node)], normal);
      for (int j = 0; j < 3; ++j)
        s += b[j] * b[j] * along(model.inverse_mass[size_t(c.triangle[j])], normal);
      if (s <= 0.0) continue;  // every node involved is held along the normal
      const double lambda = std::max(0.0, pushed[k] - approach / s) - pushed[k];
      if (lambda == 0.0) continue;
      pushed[k] += lambda;
      v[size_t(c.node)] += lambda * model.inverse_mass[size_t(c.node)].cwiseProduct(normal);
      for (int j = 0; j < 3; ++j)
        v[size_t(c.triangle[j])] -=
            lambda * b[j] * model.inverse_mass[size_t(c.triangle[j])].cwiseProduct(normal);
      pair_impulse[size_t(c.pair)] += (c.side == 0 ? lambda : -lambda) * normal;
      c.impulse += lambda;
      change = std::max(change, std::abs(lambda) * s);
    }
    largest = std::max(largest, change);
    if (change <= kSettled) break;
  }
  return largest;
}

void add_deformable_contact_forces(std::span<const PairContact> contacts, double dt,
                                   std::span<Vec3> r) {
  for (const PairContact& c : contacts) {
    const Vec3 f = c.impulse / dt * c.normal;
    r[size_t(c.node)] += f;
    for (int j = 0; j < 3; ++j) r[size_t(c.triangle[j])] -= c.weights[j] * f;
  }
}

}  // namespace phymul

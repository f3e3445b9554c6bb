#include "mesh/remesh_ops.hpp"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace phymul::remesh {
namespace {

constexpr int kMaxPasses = 200;  // each pass changes something or ends the loop
// A flip or collapse may turn a triangle's normal by at most ~75 degrees: no fold.
constexpr double kMinNormalCos = 0.25;

bool dead(const Triangle& t) { return t[0] < 0; }

Vec3 normal(const Work& w, const Triangle& t) {
  return (w.x[size_t(t[1])] - w.x[size_t(t[0])]).cross(w.x[size_t(t[2])] - w.x[size_t(t[0])]);
}

// The triangles around each vertex.
std::vector<std::vector<int>> around(const Work& w) {
  std::vector<std::vector<int>> out(w.x.size());
  for (int k = 0; k < int(w.t.size()); ++k)
    if (!dead(w.t[size_t(k)]))
      for (int v : w.t[size_t(k)]) out[size_t(v)].push_back(k);
  return out;
}

// Rotates t so that it starts with vertex a.
Triangle from(const Triangle& t, int a) {
  if (t[1] == a) return {t[1], t[2], t[0]};
  if (t[2] == a) return {t[2], t[0], t[1]};
  return t;
}

// The triangle running b -> a (the other side of edge a -> b), among those around a.
int other_side(const Work& w, const std::vector<int>& at_a, int a, int b) {
  for (int k : at_a) {
    const Triangle t = from(w.t[size_t(k)], a);
    if (t[2] == b) return k;
  }
  return -1;
}

struct Edge {
  double length;
  int a, b, triangle;  // triangle runs a -> b
};

// Each edge once, from the triangle that runs it with a < b.
std::vector<Edge> edges(const Work& w) {
  std::vector<Edge> out;
  for (int k = 0; k < int(w.t.size()); ++k) {
    const Triangle& t = w.t[size_t(k)];
    if (dead(t)) continue;
    for (size_t e = 0; e < 3; ++e) {
      const int a = t[e], b = t[(e + 1) % 3];
      if (a < b) out.push_back({(w.x[size_t(a)] - w.x[size_t(b)]).norm(), a, b, k});
    }
  }
  return out;
}

std::vector<int> neighbours(const Work& w, const std::vector<int>& triangles, int v) {
  std::vector<int> out;
  for (int k : triangles)
    for (int u : w.t[size_t(k)])
      if (u != v) out.push_back(u);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

bool split_pass(Work& w, double high) {
  const auto at = around(w);
  std::vector<Edge> long_edges;
  for (const Edge& e : edges(w))
    if (e.length > high) long_edges.push_back(e);
  std::sort(long_edges.begin(), long_edges.end(),
            [](const Edge& p, const Edge& q) { return p.length > q.length; });
  std::vector<char> touched(w.t.size(), 0);
  bool any = false;
  for (const Edge& e : long_edges) {
    const int o = other_side(w, at[size_t(e.a)], e.a, e.b);
    if (o < 0 || touched[size_t(e.triangle)] || touched[size_t(o)]) continue;
    const Triangle t1 = from(w.t[size_t(e.triangle)], e.a);  // a b c
    const Triangle t2 = from(w.t[size_t(o)], e.b);           // b a d
    const int m = int(w.x.size());
    w.x.push_back(0.5 * (w.x[size_t(e.a)] + w.x[size_t(e.b)]));
    w.t[size_t(e.triangle)] = {e.a, m, t1[2]};
    w.t[size_t(o)] = {e.b, m, t2[2]};
    w.t.push_back({m, e.b, t1[2]});
    w.t.push_back({m, e.a, t2[2]});
    touched[size_t(e.triangle)] = touched[size_t(o)] = 1;
    any = true;
  }
  return any;
}

// Whether moving a and b to p (merging them) keeps every surviving triangle around them
// unfolded and its edges at most `high`.
bool collapse_ok(const Work& w, const std::vector<int>& triangles, int a, int b, const Vec3& p,
                 double high) {
  for (int k : triangles) {
    const Triangle& t = w.t[size_t(k)];
    const bool has_a = std::find(t.begin(), t.end(), a) != t.end();
    const bool has_b = std::find(t.begin(), t.end(), b) != t.end();
    if (has_a && has_b) continue;  // removed
    Work moved{{w.x[size_t(t[0])], w.x[size_t(t[1])], w.x[size_t(t[2])]}, {}};
    for (size_t i = 0; i < 3; ++i)
      if (t[i] == a || t[i] == b) moved.x[i] = p;
    for (size_t i = 0; i < 3; ++i)
      if ((moved.x[i] - moved.x[(i + 1) % 3]).norm() > high) return false;
    const Vec3 before = normal(w, t), after = normal(moved, {0, 1, 2});
    if (after.norm() <= 1e-12 * before.norm() ||
        before.normalized().dot(after.normalized()) < kMinNormalCos)
      return false;
  }
  return true;
}

bool collapse_pass(Work& w, double low, double high) {
  const auto at = around(w);
  std::vector<Edge> short_edges;
  for (const Edge& e : edges(w))
    if (e.length < low) short_edges.push_back(e);
  std::sort(short_edges.begin(), short_edges.end(),
            [](const Edge& p, const Edge& q) { return p.length < q.length; });
  std::vector<char> touched(w.x.size(), 0);
  bool any = false;
  for (const Edge& e : short_edges) {
    const int a = e.a, b = e.b;
    if (touched[size_t(a)] || touched[size_t(b)]) continue;
    const auto na = neighbours(w, at[size_t(a)], a), nb = neighbours(w, at[size_t(b)], b);
    std::vector<int> common;
    std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
    if (common.size() != 2) continue;  // link condition: the result would not be a manifold
    if (at[size_t(common[0])].size() <= 3 || at[size_t(common[1])].size() <= 3) continue;
    if (na.size() + nb.size() - 4 < 3) continue;
    const Vec3 p = 0.5 * (w.x[size_t(a)] + w.x[size_t(b)]);
    std::vector<int> triangles = at[size_t(a)];
    triangles.insert(triangles.end(), at[size_t(b)].begin(), at[size_t(b)].end());
    if (!collapse_ok(w, triangles, a, b, p, high)) continue;
    w.x[size_t(a)] = p;
    for (int k : at[size_t(b)]) {
      Triangle& t = w.t[size_t(k)];
      if (std::find(t.begin(), t.end(), a) != t.end()) {
        t[0] = -1;  // one of the two triangles on the edge
        continue;
      }
      for (int& v : t)
        if (v == b) v = a;
    }
    for (int v : na) touched[size_t(v)] = 1;
    for (int v : nb) touched[size_t(v)] = 1;
    any = true;
  }
  return any;
}

int deviation(int valence) { return std::abs(valence - 6); }

// Whether flipping a -> b (triangles a b c and b a d) into c d keeps the two triangles
// unfolded against each other and against the ones they replace.
bool flip_ok(const Work& w, const Triangle& t1, const Triangle& t2) {
  const Triangle n1{t1[2], t1[0], t2[2]}, n2{t2[2], t1[1], t1[2]};
  const Vec3 o1 = normal(w, t1), o2 = normal(w, t2), f1 = normal(w, n1), f2 = normal(w, n2);
  const double tiny = 1e-12 * (o1.norm() + o2.norm());
  if (f1.norm() <= tiny || f2.norm() <= tiny) return false;
  const Vec3 mean = (o1.normalized() + o2.normalized()).normalized();
  return f1.normalized().dot(f2.normalized()) >= kMinNormalCos &&
         f1.normalized().dot(mean) >= kMinNormalCos && f2.normalized().dot(mean) >= kMinNormalCos;
}

bool flip_pass(Work& w) {
  const auto at = around(w);
  std::vector<int> valence(w.x.size(), 0);
  for (size_t v = 0; v < w.x.size(); ++v) valence[v] = int(at[v].size());
  std::vector<char> touched(w.x.size(), 0);
  bool any = false;
  for (const Edge& e : edges(w)) {
    const int o = other_side(w, at[size_t(e.a)], e.a, e.b);
    if (o < 0) continue;
    const Triangle t1 = from(w.t[size_t(e.triangle)], e.a), t2 = from(w.t[size_t(o)], e.b);
    const int a = e.a, b = e.b, c = t1[2], d = t2[2];
    if (touched[size_t(a)] || touched[size_t(b)] || touched[size_t(c)] || touched[size_t(d)] ||
        c == d)
      continue;
    const int before = deviation(valence[size_t(a)]) + deviation(valence[size_t(b)]) +
                       deviation(valence[size_t(c)]) + deviation(valence[size_t(d)]);
    const int after = deviation(valence[size_t(a)] - 1) + deviation(valence[size_t(b)] - 1) +
                      deviation(valence[size_t(c)] + 1) + deviation(valence[size_t(d)] + 1);
    if (after >= before || valence[size_t(a)] <= 3 || valence[size_t(b)] <= 3) continue;
    const auto nc = neighbours(w, at[size_t(c)], c);
    if (std::binary_search(nc.begin(), nc.end(), d)) continue;  // c d is an edge already
    if (!flip_ok(w, t1, t2)) continue;
    w.t[size_t(e.triangle)] = {c, a, d};
    w.t[size_t(o)] = {d, b, c};
    --valence[size_t(a)], --valence[size_t(b)], ++valence[size_t(c)], ++valence[size_t(d)];
    touched[size_t(a)] = touched[size_t(b)] = touched[size_t(c)] = touched[size_t(d)] = 1;
    any = true;
  }
  return any;
}

}  // namespace

void split_long(Work& w, double high) {
  for (int pass = 0; pass < kMaxPasses && split_pass(w, high); ++pass) {
  }
}

void collapse_short(Work& w, double low, double high) {
  for (int pass = 0; pass < kMaxPasses && collapse_pass(w, low, high); ++pass) {
  }
}

void flip_to_valence(Work& w) {
  for (int pass = 0; pass < kMaxPasses && flip_pass(w); ++pass) {
  }
}

void compact(Work& w) {
  std::vector<int> index(w.x.size(), -1);
  Work out;
  for (const Triangle& t : w.t) {
    if (dead(t)) continue;
    Triangle n{};
    for (size_t k = 0; k < 3; ++k) {
      int& i = index[size_t(t[k])];
      if (i < 0) {
        i = int(out.x.size());
        out.x.push_back(w.x[size_t(t[k])]);
      }
      n[k] = i;
    }
    out.t.push_back(n);
  }
  w = std::move(out);
}

void relax(Work& w) {
  std::vector<Vec3> centre(w.x.size(), Vec3::Zero()), n(w.x.size(), Vec3::Zero());
  std::vector<double> weight(w.x.size(), 0.0);
  for (const Triangle& t : w.t) {
    if (dead(t)) continue;
    const Vec3 area_normal = normal(w, t);
    const double area = area_normal.norm();
    const Vec3 c = (w.x[size_t(t[0])] + w.x[size_t(t[1])] + w.x[size_t(t[2])]) / 3.0;
    for (int v : t) {
      centre[size_t(v)] += area * c;
      weight[size_t(v)] += area;
      n[size_t(v)] += area_normal;
    }
  }
  for (size_t v = 0; v < w.x.size(); ++v) {
    if (!(weight[v] > 0.0) || !(n[v].norm() > 0.0)) continue;
    const Vec3 unit = n[v].normalized(), move = centre[v] / weight[v] - w.x[v];
    w.x[v] += move - unit.dot(move) * unit;
  }
}

}  // namespace phymul::remesh

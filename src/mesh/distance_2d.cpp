#include "mesh/distance_2d.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace phymul::detail {
namespace {

constexpr double kFar = std::numeric_limits<double>::infinity();

// Squared distance along one line of n samples, `stride` apart, spacing h, to the samples
// where f is finite (plus their f): the lower envelope of parabolas (Felzenszwalb and
// Huttenlocher, "Distance transforms of sampled functions", 2012).
void envelope_1d(double* f, int n, size_t stride, double h, std::vector<int>& v,
                 std::vector<double>& z, std::vector<double>& out) {
  auto at = [&](int q) { return f[size_t(q) * stride]; };
  auto cross = [&](int p, int q) {
    return ((at(q) + (q * h) * (q * h)) - (at(p) + (p * h) * (p * h))) / (2.0 * h * (q - p));
  };
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (!std::isfinite(at(q))) continue;
    double s = -kFar;
    while (k >= 0 && (s = cross(v[size_t(k)], q)) <= z[size_t(k)]) --k;
    if (k < 0) s = -kFar;
    ++k;
    v[size_t(k)] = q, z[size_t(k)] = s;
  }
  for (int q = 0, j = 0; q < n; ++q) {
    if (k < 0) {
      out[size_t(q)] = kFar;
      continue;
    }
    while (j < k && z[size_t(j + 1)] < q * h) ++j;
    const double d = (q - v[size_t(j)]) * h;
    out[size_t(q)] = d * d + at(v[size_t(j)]);
  }
  for (int q = 0; q < n; ++q) f[size_t(q) * stride] = out[size_t(q)];
}

// Squared distance of every pixel to the nearest pixel where `feature` holds `value`.
std::vector<double> squared_distance(const std::vector<unsigned char>& feature, unsigned char value,
                                     int na, int nb, double sa, double sb) {
  std::vector<double> d(feature.size());
  for (size_t i = 0; i < d.size(); ++i) d[i] = feature[i] == value ? 0.0 : kFar;
  const int n = std::max(na, nb);
  std::vector<int> v(size_t(n) + 1);
  std::vector<double> z(size_t(n) + 1), out(static_cast<size_t>(n));
  for (int b = 0; b < nb; ++b) envelope_1d(d.data() + size_t(b) * size_t(na), na, 1, sa, v, z, out);
  for (int a = 0; a < na; ++a) envelope_1d(d.data() + a, nb, size_t(na), sb, v, z, out);
  return d;
}

}  // namespace

std::vector<float> signed_distance_2d(const std::vector<unsigned char>& inside, int na, int nb,
                                      double sa, double sb, double limit) {
  std::vector<float> out(inside.size(), float(limit));
  if (std::find(inside.begin(), inside.end(), 1) == inside.end()) return out;
  const std::vector<double> to_inside = squared_distance(inside, 1, na, nb, sa, sb);
  const std::vector<double> to_outside = squared_distance(inside, 0, na, nb, sa, sb);
  const double half = 0.25 * (sa + sb);  // the boundary halfway between pixel centres
  for (size_t i = 0; i < out.size(); ++i) {
    const double d =
        inside[i] ? -(std::sqrt(to_outside[i]) - half) : std::sqrt(to_inside[i]) - half;
    out[i] = float(std::clamp(d, -limit, limit));  // no outside pixel: inf, clamped
  }
  return out;
}

}  // namespace phymul::detail

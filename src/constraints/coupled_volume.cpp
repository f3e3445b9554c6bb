#include "constraints/coupled_volume.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace phymul {
namespace {

constexpr int kMax = kMaxJointVolumes;
using Square = std::array<double, kMax * kMax>;  // row k, column l at [k * kMax + l]
using Column = std::array<double, kMax>;

// 1 on the axes a node is free to move along, 0 on those a position constraint holds.
Vec3 free_axes(const Vec3& inverse_mass) {
  return (inverse_mass.array() > 0.0).cast<double>().matrix();
}

// The scratch finalize sizes (model.cpp, mark_coupled_volumes).
bool usable(const Model& model) {
  if (model.volumes.empty() || model.volumes.size() > size_t(kMax)) return false;
  if (model.coupled_factor.size() != size_t(kMax * kMax)) return false;
  for (const VolumeConstraint& c : model.volumes)
    if (c.coupled_direction.size() != c.nodes.size() ||
        c.coupled_gradient.size() != c.nodes.size() || c.coupled_at.size() != c.nodes.size())
      return false;
  return true;
}

// 6 dV/dx of c at x into grad, zero on the nodes of every other surface (the products with
// their directions read there); returns 6 V. The factor 6 is taken out once by the callers.
double six_gradient(const Model& model, const VolumeConstraint& c, std::span<const Vec3> x,
                    std::span<Vec3> grad) {
  for (const VolumeConstraint& other : model.volumes)
    for (int i : other.nodes) grad[i].setZero();
  double six_volume = 0.0;
  for (const Triangle& t : c.triangles) {
    const Vec3 &a = x[t[0]], &b = x[t[1]], &d = x[t[2]];
    const Vec3 bd = b.cross(d);
    grad[t[0]] += bd;
    grad[t[1]] += d.cross(a);
    grad[t[2]] += a.cross(b);
    six_volume += a.dot(bd);
  }
  return six_volume;
}

double volume(const VolumeConstraint& c, std::span<const Vec3> x) {
  double six_volume = 0.0;
  for (const Triangle& t : c.triangles) six_volume += x[t[0]].dot(x[t[1]].cross(x[t[2]]));
  return six_volume / 6.0;
}

// At x: every direction d_k = w dV_k/dx (into the constraint's coupled_direction), the
// symmetric G W G^T (a_kl = dV_k/dx . d_l) and each volume V_k. One gradient pass per
// surface; `keep`: each 6 dV_k/dx and x into the constraint's coupled_gradient, coupled_at.
void linearise(const Model& model, std::span<const Vec3> x, std::span<Vec3> grad, Square& a,
               Column& volumes, bool keep) {
  constexpr double kSixth = 1.0 / 6.0;
  const int n = int(model.volumes.size());
  for (int k = 0; k < n; ++k) {
    const VolumeConstraint& c = model.volumes[size_t(k)];
    volumes[size_t(k)] = six_gradient(model, c, x, grad) / 6.0;
    for (size_t m = 0; m < c.nodes.size(); ++m) {
      const int i = c.nodes[m];
      c.coupled_direction[m] = kSixth * grad[i].cwiseProduct(model.inverse_mass[size_t(i)]);
      if (keep) c.coupled_gradient[m] = grad[i], c.coupled_at[m] = x[size_t(i)];
    }
    for (int l = 0; l <= k; ++l) {  // grad is dV_k/dx (times 6) here, d_l is stored
      const VolumeConstraint& o = model.volumes[size_t(l)];
      double product = 0.0;
      for (size_t m = 0; m < o.nodes.size(); ++m)
        product += grad[o.nodes[m]].dot(o.coupled_direction[m]);
      a[size_t(k * kMax + l)] = a[size_t(l * kMax + k)] = kSixth * product;
    }
  }
}

// The linearisation the last velocity projection kept is still the one at x: the same
// positions on every surface (a step's first projection, of the accelerations, comes at the
// positions of the last one's, whatever was computed in between: a monitor's residual).
bool kept_linearisation_at(const Model& model, std::span<const Vec3> x) {
  if (!model.coupled_factor_valid) return false;
  for (const VolumeConstraint& c : model.volumes)
    for (size_t m = 0; m < c.nodes.size(); ++m)
      if (c.coupled_at[m] != x[size_t(c.nodes[m])]) return false;
  return true;
}

// Lower Cholesky factor in place; false unless clearly positive definite (a surface held
// still has a zero row, two surfaces with dependent gradients a vanishing pivot).
bool cholesky(int n, Square& a) {
  for (int j = 0; j < n; ++j) {
    double pivot = a[size_t(j * kMax + j)];
    const double scale = pivot;
    for (int p = 0; p < j; ++p) pivot -= a[size_t(j * kMax + p)] * a[size_t(j * kMax + p)];
    if (!(scale > 0.0) || !(pivot > 1e-12 * scale)) return false;
    const double root = std::sqrt(pivot);
    a[size_t(j * kMax + j)] = root;
    for (int i = j + 1; i < n; ++i) {
      double s = a[size_t(i * kMax + j)];
      for (int p = 0; p < j; ++p) s -= a[size_t(i * kMax + p)] * a[size_t(j * kMax + p)];
      a[size_t(i * kMax + j)] = s / root;
    }
  }
  return true;
}

// b <- (L L^T)^-1 b.
void solve(int n, const Square& l, Column& b) {
  for (int i = 0; i < n; ++i) {
    for (int p = 0; p < i; ++p) b[size_t(i)] -= l[size_t(i * kMax + p)] * b[size_t(p)];
    b[size_t(i)] /= l[size_t(i * kMax + i)];
  }
  for (int i = n - 1; i >= 0; --i) {
    for (int p = i + 1; p < n; ++p) b[size_t(i)] -= l[size_t(p * kMax + i)] * b[size_t(p)];
    b[size_t(i)] /= l[size_t(i * kMax + i)];
  }
}

// field -= sum_k coefficient_k d_k.
void move_along_directions(const Model& model, const Column& coefficient, std::span<Vec3> field) {
  for (size_t k = 0; k < model.volumes.size(); ++k) {
    const VolumeConstraint& c = model.volumes[k];
    for (size_t m = 0; m < c.nodes.size(); ++m)
      field[size_t(c.nodes[m])] -= coefficient[k] * c.coupled_direction[m];
  }
}

}  // namespace

bool project_coupled_volumes(const Model& model, std::span<Vec3> x, double load_time,
                             std::span<Vec3> grad) {
  // Chord iterations on V_k(x0 + sum_j lambda_j d_j) = target_k with the Jacobian at x0,
  // G W G^T: exact to first order, so each iteration squares the relative error (1e-6 ->
  // 1e-12 -> round-off) and costs only the volumes, not their gradients.
  constexpr double kExact = 1e-13;      // relative; the sweeps stopped at 1e-12
  constexpr double kConverged = 1e-12;  // accepted where round-off stops the progress
  constexpr int kMaxIterations = 20;
  if (!usable(model)) return false;
  const int n = int(model.volumes.size());
  Square a{};
  Column volumes{}, targets{}, residual{};
  linearise(model, x, grad, a, volumes, /*keep=*/false);
  auto worst_error = [&] {
    double worst = 0.0;
    for (int k = 0; k < n; ++k) {
      residual[size_t(k)] = volumes[size_t(k)] - targets[size_t(k)];
      worst = std::max(worst, std::abs(residual[size_t(k)]) / std::abs(targets[size_t(k)]));
    }
    return worst;
  };
  for (int k = 0; k < n; ++k) targets[size_t(k)] = model.volumes[size_t(k)].target_at(load_time);
  double worst = worst_error();
  if (worst <= kExact) return true;
  if (!cholesky(n, a)) return false;
  for (int it = 0; it < kMaxIterations; ++it) {
    Column step = residual;
    solve(n, a, step);
    move_along_directions(model, step, x);
    for (int k = 0; k < n; ++k) volumes[size_t(k)] = volume(model.volumes[size_t(k)], x);
    const double before = worst;
    worst = worst_error();
    if (worst <= kExact || (worst <= kConverged && worst > 0.25 * before)) return true;
  }
  return false;
}

bool project_coupled_volume_velocities(const Model& model, std::span<const Vec3> x,
                                       std::span<Vec3> v, std::span<Vec3> grad) {
  constexpr double kSixth = 1.0 / 6.0;
  if (!usable(model)) return false;
  const int n = int(model.volumes.size());
  Square a{};
  if (kept_linearisation_at(model, x)) {
    std::copy_n(model.coupled_factor.begin(), kMax * kMax, a.begin());
  } else {
    model.coupled_factor_valid = false;
    Column volumes{};
    linearise(model, x, grad, a, volumes, /*keep=*/true);
    if (!cholesky(n, a)) return false;
    std::copy(a.begin(), a.end(), model.coupled_factor.begin());
    model.coupled_factor_valid = true;
  }
  Column rates{};  // dV_k/dt
  for (int k = 0; k < n; ++k) {
    const VolumeConstraint& c = model.volumes[size_t(k)];
    double rate = 0.0;
    for (size_t m = 0; m < c.nodes.size(); ++m)
      rate += c.coupled_gradient[m].dot(v[size_t(c.nodes[m])]);
    rates[size_t(k)] = kSixth * rate;
  }
  solve(n, a, rates);
  // v -= sum_k mu_k w dV_k/dx from the kept gradients: the directions' scratch may have been
  // overwritten since (the position projection, a residual's pressures).
  for (int k = 0; k < n; ++k) {
    const VolumeConstraint& c = model.volumes[size_t(k)];
    for (size_t m = 0; m < c.nodes.size(); ++m) {
      const int i = c.nodes[m];
      const Vec3 direction =
          kSixth * c.coupled_gradient[m].cwiseProduct(model.inverse_mass[size_t(i)]);
      v[size_t(i)] -= rates[size_t(k)] * direction;
    }
  }
  return true;
}

// A node against an obstacle may push along the contact normal with any force: that part of
// its residual and of the gradients is left out of the least squares.
void remove_contact_normals(const Model& model, std::span<const ObstacleContact> contact,
                            std::span<const Vec3> r, Square& a, Column& balanced) {
  const int n = int(model.volumes.size());
  for (const auto& [i, normal, friction] : contact) {
    std::array<double, kMax> along{};  // F_k . normal, F_k the free gradient part (over 6)
    for (int k = 0; k < n; ++k) {
      const VolumeConstraint& c = model.volumes[size_t(k)];
      const auto at = std::lower_bound(c.nodes.begin(), c.nodes.end(), i);
      if (at != c.nodes.end() && *at == i)
        along[size_t(k)] = c.coupled_direction[size_t(at - c.nodes.begin())].dot(normal);
    }
    const double r_along = r[size_t(i)].dot(normal);
    for (int k = 0; k < n; ++k) {
      balanced[size_t(k)] -= along[size_t(k)] * r_along;
      for (int l = 0; l < n; ++l) a[size_t(k * kMax + l)] -= along[size_t(k)] * along[size_t(l)];
    }
  }
}

bool remove_coupled_volume_pressures(const Model& model, std::span<const Vec3> x, std::span<Vec3> r,
                                     std::span<Vec3> grad, bool on_free_axes,
                                     std::span<const ObstacleContact> contact) {
  constexpr double kSixth = 1.0 / 6.0;
  if (!usable(model)) return false;
  const int n = int(model.volumes.size());
  Square a{};
  Column balanced{};
  // Between steps (a monitor's residual) the velocity projection has kept the gradients here.
  const bool kept = kept_linearisation_at(model, x);
  for (int k = 0; k < n; ++k) {
    const VolumeConstraint& c = model.volumes[size_t(k)];
    if (kept) {  // the same gradient, as six_gradient would leave it in grad
      for (const VolumeConstraint& other : model.volumes)
        for (int i : other.nodes) grad[i].setZero();
      for (size_t m = 0; m < c.nodes.size(); ++m) grad[c.nodes[m]] = c.coupled_gradient[m];
    } else {
      six_gradient(model, c, x, grad);
    }
    double rg = 0.0;
    for (size_t m = 0; m < c.nodes.size(); ++m) {
      const int i = c.nodes[m];
      const Vec3 free_part = grad[i].cwiseProduct(free_axes(model.inverse_mass[size_t(i)]));
      c.coupled_direction[m] = kSixth * (on_free_axes ? free_part : grad[i]);
      rg += free_part.dot(r[size_t(i)]);
    }
    balanced[size_t(k)] = kSixth * rg;
    for (int l = 0; l <= k; ++l) {  // F F^T: masking dV_k/dx is enough, d_l may be whole
      const VolumeConstraint& o = model.volumes[size_t(l)];
      double product = 0.0;
      for (size_t m = 0; m < o.nodes.size(); ++m) {
        const int i = o.nodes[m];
        product += grad[i]
                       .cwiseProduct(free_axes(model.inverse_mass[size_t(i)]))
                       .dot(o.coupled_direction[m]);
      }
      a[size_t(k * kMax + l)] = a[size_t(l * kMax + k)] = kSixth * product;
    }
  }
  if (on_free_axes) remove_contact_normals(model, contact, r, a, balanced);
  if (!cholesky(n, a)) return false;
  solve(n, a, balanced);
  move_along_directions(model, balanced, r);
  return true;
}

}  // namespace phymul

// The stable time step from the model's highest frequency found by power iteration, for
// `simulation.dt_estimate: power` (README "The prostate study", "Real time").
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "phymul/forces.hpp"
#include "phymul/simulation.hpp"

namespace phymul {
namespace {

// A start vector fixed by the node and axis alone (splitmix64), so the estimate does not
// depend on a library's random distributions: uniform in [-1, 1).
double start_component(int node, int axis) {
  uint64_t z = uint64_t(node) * 3 + uint64_t(axis) + 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return double(z >> 11) * 0x1.0p-52 - 1.0;
}

}  // namespace

FrequencyEstimate highest_frequency(const Model& model, const Data& state,
                                    const std::vector<double>& inertia, double load_time,
                                    int max_iterations) {
  // Power iteration on A = M^-1/2 (-df/dx) M^-1/2 over the free axes, A y by central
  // differences of the force routine along u = M^-1/2 y, scaled so that the largest nodal
  // move is 1e-5 of the model's size: far inside the forces' linear range, far above
  // their round-off.
  constexpr double kRelativeMove = 1e-5;
  constexpr double kSettled = 1e-4;  // residual over Rayleigh quotient: an eigenvector
  const int n = model.node_count();
  const auto [lo, hi] = bounding_box(model.rest_position);
  const double size = std::max((hi - lo).norm(), 1e-12);
  std::vector<Vec3> y(size_t(n), Vec3::Zero()), ay(size_t(n), Vec3::Zero());
  std::vector<double> root(size_t(n), 0.0);  // sqrt of each node's inertia
  for (int i = 0; i < n; ++i) {
    root[size_t(i)] = std::sqrt(inertia[size_t(i)]);
    for (int a = 0; a < 3; ++a)
      if (model.inverse_mass[size_t(i)][a] != 0.0) y[size_t(i)][a] = start_component(i, a);
  }
  Data plus = state, minus = state;
  FrequencyEstimate e;
  for (e.iterations = 0; e.iterations < max_iterations;) {
    double norm = 0.0, largest_move = 0.0;
    for (int i = 0; i < n; ++i) {
      norm += y[size_t(i)].squaredNorm();
      largest_move = std::max(largest_move, y[size_t(i)].norm() / root[size_t(i)]);
    }
    if (!(norm > 0.0) || !(largest_move > 0.0)) return FrequencyEstimate{};  // nothing free
    norm = std::sqrt(norm);
    for (Vec3& v : y) v /= norm;
    const double h = kRelativeMove * size * norm / largest_move;  // scales the unit y
    for (int i = 0; i < n; ++i) {
      const Vec3 u = h * y[size_t(i)] / root[size_t(i)];
      plus.x[size_t(i)] = state.x[size_t(i)] + u;
      minus.x[size_t(i)] = state.x[size_t(i)] - u;
    }
    plus.rotation = state.rotation, minus.rotation = state.rotation;  // same warm start
    compute_forces(model, plus, load_time);
    compute_forces(model, minus, load_time);
    double rayleigh = 0.0;
    for (int i = 0; i < n; ++i) {
      for (int a = 0; a < 3; ++a)
        ay[size_t(i)][a] =
            model.inverse_mass[size_t(i)][a] == 0.0
                ? 0.0
                : -(plus.f[size_t(i)][a] - minus.f[size_t(i)][a]) / (2.0 * h * root[size_t(i)]);
      rayleigh += y[size_t(i)].dot(ay[size_t(i)]);
    }
    double residual = 0.0;
    for (int i = 0; i < n; ++i) residual += (ay[size_t(i)] - rayleigh * y[size_t(i)]).squaredNorm();
    e.rayleigh = rayleigh;
    e.residual = std::sqrt(residual);
    ++e.iterations;
    if (e.residual <= kSettled * std::abs(rayleigh)) break;
    std::swap(y, ay);
  }
  return e;
}

double verlet_stable_step(double omega, double damping) {
  if (!(omega > 0.0)) return std::numeric_limits<double>::infinity();
  // Central differences with viscous damping c: dt < (2/w)(sqrt(1 + xi^2) - xi), xi = c/(2w).
  const double xi = damping / (2.0 * omega);
  return 2.0 / omega * (std::sqrt(1.0 + xi * xi) - xi);
}

}  // namespace phymul

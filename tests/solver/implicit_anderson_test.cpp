// Anderson acceleration of a fixed-point iteration (solver/implicit_anderson.hpp) on a linear
// contraction x -> D x + b (24 modes, the slowest contracting by 0.995 an iteration): the
// plain iteration needs thousands of iterations to 1e-10 of the fixed point (I - D)^-1 b, the
// accelerated one a tenth of them at most (measured: 5617 and 218); and a sequence of such
// iterations, one a step, with the history carried from each to the next.
#include "solver/implicit_anderson.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "support/models.hpp"

namespace phymul {
namespace {

// Iterations until |x - fixed point| < 1e-10 (or `most`), accelerated or not.
int iterations_to_fixed_point(bool accelerate, int most) {
  Model model;
  add_elastic_component(model, "block", make_box(Vec3(0.01, 0.01, 0.01), {1, 1, 1}, CellType::hexa),
                        testing::material(1.0));
  finalize(model);
  model.settings.integrator = Integrator::implicit;
  ImplicitSystem s;
  Data data = allocate_data(model);
  prepare_anderson(model, s, data.anderson, 1e-3);
  const size_t n = size_t(model.node_count());
  std::vector<Vec3> x(n, Vec3::Zero()), before(n), scale(n), shift(n), fixed(n);
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      // Contractions spread over [0.5, 0.995], the slowest first.
      scale[i][a] = 0.995 - 0.495 * double(3 * i + size_t(a)) / double(3 * n - 1);
      shift[i][a] = std::sin(double(3 * i + size_t(a)) + 1.0);
      fixed[i][a] = shift[i][a] / (1.0 - scale[i][a]);
    }
  for (int k = 1; k <= most; ++k) {
    before = x;
    for (size_t i = 0; i < n; ++i) x[i] = scale[i].cwiseProduct(x[i]) + shift[i];
    if (accelerate) anderson_mix(s, data.anderson, before, x);
    double error = 0.0;
    for (size_t i = 0; i < n; ++i) error = std::max(error, (x[i] - fixed[i]).norm());
    if (error < 1e-10) return k;
  }
  return most + 1;
}

TEST(ImplicitAnderson, AcceleratesASlowContractionToItsFixedPoint) {
  const int plain = iterations_to_fixed_point(false, 100000);
  const int accelerated = iterations_to_fixed_point(true, 100000);
  std::printf("to 1e-10 of the fixed point: %d iterations plain, %d accelerated\n", plain,
              accelerated);
  EXPECT_GT(plain, 4000);  // 0.995^k below 1e-10 / 200
  EXPECT_LT(10 * accelerated, plain);
}

// Consecutive steps' iterations differ by a constant (their inertial terms) and share the
// rest of the map: here x -> D x + b_s, b_s changing from step to step. The history carried
// from step to step holds D's differences already, and each later step reaches its fixed
// point in far fewer iterations than with a history started anew.
int steps_iterations(bool carry) {
  Model model;
  add_elastic_component(model, "block", make_box(Vec3(0.01, 0.01, 0.01), {1, 1, 1}, CellType::hexa),
                        testing::material(1.0));
  model.settings.integrator = Integrator::implicit;
  finalize(model);
  ImplicitSystem s;
  Data data = allocate_data(model);
  prepare_anderson(model, s, data.anderson, 1e-3);
  EXPECT_TRUE(s.anderson.carry);
  s.anderson.carry = carry;
  const size_t n = size_t(model.node_count());
  std::vector<Vec3> x(n, Vec3::Zero()), before(n), scale(n);
  // Three slow modes among fast ones, as P leaves a few of the model's modes to the
  // iterations.
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) scale[i][a] = 3 * i + size_t(a) < 3 ? 0.9 : 0.1;
  int total = 0;
  for (int step = 1; step <= 20; ++step) {
    begin_anderson_step(s, data.anderson);
    std::vector<Vec3> shift(n), fixed(n);
    for (size_t i = 0; i < n; ++i)
      for (int a = 0; a < 3; ++a) {
        shift[i][a] = std::sin(double(3 * i + size_t(a)) + 0.1 * step);
        fixed[i][a] = shift[i][a] / (1.0 - scale[i][a]);
      }
    for (int k = 1;; ++k) {
      before = x;
      for (size_t i = 0; i < n; ++i) x[i] = scale[i].cwiseProduct(x[i]) + shift[i];
      anderson_mix(s, data.anderson, before, x);
      double error = 0.0;
      for (size_t i = 0; i < n; ++i) error = std::max(error, (x[i] - fixed[i]).norm());
      if (error < 1e-10 || k == 100000) {
        total += k;
        break;
      }
    }
  }
  return total;
}

TEST(ImplicitAnderson, AHistoryCarriedFromStepToStepShortensTheLaterSteps) {
  const int fresh = steps_iterations(false), carried = steps_iterations(true);
  std::printf(
      "20 steps to 1e-10 of their fixed points: %d iterations with the history started "
      "anew each step, %d carried\n",
      fresh, carried);
  EXPECT_LT(2 * carried, fresh);
}

}  // namespace
}  // namespace phymul

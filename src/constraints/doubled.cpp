#include "constraints/doubled.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace phymul {

void project_doubled(const Model& model, std::span<Vec3> values) {
  for (int g = 0; g < model.doubled.rows(); ++g) {
    const auto group = model.doubled.row(g);
    for (int a = 0; a < 3; ++a) {
      double mean = 0.0;
      if (const int leader = model.doubled_leader[g][a]; leader >= 0) {
        mean = values[leader][a];
      } else {
        double total = 0.0;
        for (int i : group) mean += model.mass[i] * values[i][a], total += model.mass[i];
        mean /= total;
      }
      for (int i : group) values[i][a] = mean;
    }
  }
}

void gather_doubled(const Model& model, std::span<Vec3> residual) {
  for (int g = 0; g < model.doubled.rows(); ++g) {
    const auto group = model.doubled.row(g);
    Vec3 sum = Vec3::Zero();
    for (int i : group) sum += residual[i], residual[i].setZero();
    residual[group.front()] = sum;
  }
}

}  // namespace phymul

// Time-varying values: linear between events, held before the first and after the last.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <vector>

namespace phymul {

struct Schedule {
  std::vector<double> times;            // s, strictly increasing
  std::vector<Eigen::Vector3d> values;  // one per time, SI

  static Schedule constant(const Eigen::Vector3d& value) { return {{0.0}, {value}}; }
  bool empty() const { return times.empty(); }
  double end_time() const { return times.empty() ? 0.0 : times.back(); }

  Eigen::Vector3d at(double t) const {
    if (times.empty()) return Eigen::Vector3d::Zero();
    if (t <= times.front()) return values.front();
    if (t >= times.back()) return values.back();
    // times.front() < t < times.back(): the first later event has an earlier one before it.
    const size_t hi = size_t(std::upper_bound(times.begin(), times.end(), t) - times.begin());
    const double s = (t - times[hi - 1]) / (times[hi] - times[hi - 1]);
    return (1.0 - s) * values[hi - 1] + s * values[hi];
  }
};

}  // namespace phymul

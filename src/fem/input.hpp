// Input checks of solve_static: every problem is reported as std::invalid_argument naming the
// field, the accepted range and the value received.
#pragma once

#include <vector>

#include "phymul/fem.hpp"

namespace phymul::fem {

void check_problem(const Problem& problem);

// Prescribed value per global dof (3 node + axis) at full load, and which dofs are
// prescribed. Throws std::invalid_argument for a dof prescribed twice with different values.
struct PrescribedValues {
  std::vector<char> mask;
  std::vector<double> value;
};

PrescribedValues prescribed_values(const Problem& problem);

}  // namespace phymul::fem

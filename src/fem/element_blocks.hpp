// Adding a Gauss point's material tangent into an element matrix, shared by the element
// kernels (mean dilatation and incompatible modes).
#pragma once

#include <Eigen/Core>

#include "fem/constitutive.hpp"

namespace phymul::fem {

template <int NN>
using Stiffness = Eigen::Matrix<double, 3 * NN, 3 * NN>;

// The (i, k) sub-block K(3 a + i, 3 b + k) of an element matrix, as an NN x NN view.
template <int NN>
using NodeBlock = Eigen::Map<Eigen::Matrix<double, NN, NN>, 0, Eigen::Stride<9 * NN, 3>>;

template <int NN>
NodeBlock<NN> node_block(Stiffness<NN>& k, int i, int j) {
  return NodeBlock<NN>(k.data() + i + 3 * NN * j);
}

// K(ai, bk) += w sum_JL grad(a, J) A(iJ, kL) grad(b, L). A has the major symmetry of a
// hyperelastic tangent, so block (k, i) is the transpose of block (i, k).
template <int NN>
void add_material(Stiffness<NN>& k, const Eigen::Matrix<double, NN, 3>& grad, const Mat9& a,
                  double w) {
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) {
      const Eigen::Matrix<double, NN, 3> left = grad * (w * a.template block<3, 3>(3 * i, 3 * j));
      const Eigen::Matrix<double, NN, NN> block = left * grad.transpose();
      node_block<NN>(k, i, j) += block;
      if (j != i) node_block<NN>(k, j, i) += block.transpose();
    }
  }
}

}  // namespace phymul::fem

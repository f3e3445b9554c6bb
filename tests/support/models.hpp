// Small models shared by the tests.
#pragma once

#include <random>

#include "phymul/model.hpp"

namespace phymul::testing {

inline MaterialSpec material(double stiffness, FrameMode frame = FrameMode::polar,
                             bool reaction = true) {
  MaterialSpec m;
  m.stiffness = stiffness;
  m.density = 1000.0;
  m.frame = frame;
  m.reaction = reaction;
  return m;
}

inline MaterialSpec surface_material(double stiffness, double mass, FrameMode frame) {
  MaterialSpec m = material(stiffness, frame);
  m.density.reset();
  m.mass = mass;
  return m;
}

inline Model single_component(const Mesh& mesh, const MaterialSpec& m) {
  Model model;
  add_elastic_component(model, "body", mesh, m);
  finalize(model);
  return model;
}

inline Eigen::Matrix3d random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  return q.normalized().toRotationMatrix();
}

}  // namespace phymul::testing

// Local shape memory (DESIGN 2.1): each step, pull every node towards its attraction
// position (the rest memory it reads is compiled by model/shape_memory_rest.hpp).
#pragma once

#include <span>

#include "phymul/model.hpp"

namespace phymul {

// Attraction position (m) of memory node k given current positions x; updates the
// warm-started rotation q (polar mode).
Vec3 attraction_position(const ShapeMemory& memory, int k, std::span<const Vec3> rest,
                         std::span<const Vec3> x, Eigen::Quaterniond& q);

// Adds the shape-memory forces (N) of one component to f; returns its energy
// sum K |a - x|^2 / 2 (J). rotations: this component's slice of Data::rotation; blocks: the
// energy of each block of memory.plan (scratch, plan.blocks() long).
double add_shape_memory_forces(const ShapeMemory& memory, std::span<const Vec3> rest,
                               std::span<const Vec3> x, std::span<Eigen::Quaterniond> rotations,
                               std::span<Vec3> f, std::span<double> blocks);

// Rotation maximising trace(R^T A), by the iteration of Mueller et al. (2016), warm
// started from q. Unlike an SVD it never returns a reflection.
void extract_rotation(const Eigen::Matrix3d& A, Eigen::Quaterniond& q, int max_iterations = 12);

}  // namespace phymul

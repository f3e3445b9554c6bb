// Local shape memory (DESIGN 2.1): compile the rest memory of a component, then each step
// pull every node towards its attraction position.
#pragma once

#include <span>

#include "phymul/model.hpp"

namespace phymul {

// Rest memory of every node of `mesh`, whose node k is global node first_node + k with rest
// position rest[first_node + k]. Surface meshes use ordered one-rings, volume meshes edge
// neighbours.
ShapeMemory build_shape_memory(const std::string& component, const Mesh& mesh, int first_node,
                               const MaterialSpec& material, std::span<const Vec3> rest);

// Attraction position (m) of memory node k given current positions x; updates the
// warm-started rotation q (polar mode).
Vec3 attraction_position(const ShapeMemory& memory, int k, std::span<const Vec3> rest,
                         std::span<const Vec3> x, Eigen::Quaterniond& q);

// Adds the shape-memory forces (N) of one component to f; returns its energy
// sum K |a - x|^2 / 2 (J). rotations: this component's slice of State::rotation.
double add_shape_memory_forces(const ShapeMemory& memory, std::span<const Vec3> rest,
                               std::span<const Vec3> x, std::span<Eigen::Quaterniond> rotations,
                               std::span<Vec3> f);

// Rotation maximising trace(R^T A), by the iteration of Mueller et al. (2016), warm
// started from q. Unlike an SVD it never returns a reflection.
void extract_rotation(const Eigen::Matrix3d& A, Eigen::Quaterniond& q, int max_iterations = 12);

}  // namespace phymul

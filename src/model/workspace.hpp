// The buffers a step works in (Data::work): sized from the model by allocate_data, so that a
// step allocates nothing; never read across steps but through the positions they were
// computed at (the volume caches), so a fresh workspace gives the same results. Not saved by
// checkpoints.
#pragma once

#include <array>
#include <vector>

#include "mesh/spatial_hash.hpp"
#include "model/implicit_system.hpp"
#include "phymul/data.hpp"

namespace phymul {

// The velocity projection of one volume constraint keeps its gradient for the next position
// projection at the same positions (VolumeConstraint's nodes, in order).
struct VolumeCache {
  std::vector<Vec3> direction;    // joint projection's scratch: w dV/dx at its start
  std::vector<Vec3> gradient;     // 6 dV/dx of the last velocity projection
  std::vector<Vec3> gradient_at;  // the positions it was taken at (NaN: none)
};

// Position sweeps of the contact pairs' stage at most; they stop once no node is inside.
inline constexpr int kPairContactSweeps = 4;

// Most constraints the joint projection takes: its n x n system lives on the stack.
inline constexpr int kMaxJointVolumes = 16;

// The joint projection of surfaces sharing nodes (constraints/coupled_volume.hpp).
struct JointVolumeCache {
  // Cholesky factor of G W G^T, valid while every VolumeCache::gradient_at matches the
  // positions.
  std::vector<double> factor;
  bool factor_valid = false;
  std::vector<double> scatter;  // the gradients' scatter: 4 per node from a 32-byte boundary
};

struct Workspace {
  // Node-sized buffers, doubled up where their lives do not overlap (solver/step.cpp): the
  // positions and velocities at a step's start, the accelerations; the Newton-Cotes scheme's
  // second accelerations and projection scratch.
  std::vector<Vec3> x_start, v_start, f_start, a1, scratch;
  // Nodes touching an obstacle now (a residual's, an implicit solve's, an explicit velocity
  // stage's resting ones): scratch, filled and read within one call; reserved.
  std::vector<ObstacleContact> contacts;
  std::vector<Vec3> contact_impulse;  // per obstacle, N s, this step
  std::vector<Vec3> pair_impulse;     // per contact pair, N s, this step
  // Per Data::pair_contacts record: the impulse (N s, >= 0) its velocity stage gave so far.
  std::vector<double> pair_pushed;
  // The contact pairs' stage: each pair's two surfaces hashed, area-weighted vertex normals.
  std::vector<std::array<TriangleHash, 2>> pair_hashes;
  std::vector<Vec3> vertex_normal;
  std::vector<VolumeCache> volumes;  // per Model::volumes
  JointVolumeCache joint;
  // J per block of each shape memory's and each explicit FEM's parallel plan, each pass.
  std::vector<std::vector<double>> shape_memory_blocks, fem_blocks;
  ImplicitSystem implicit;  // integrator: implicit
};

}  // namespace phymul

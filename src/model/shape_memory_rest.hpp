// The rest memory of a shape-memory component (DESIGN 2.1), compiled once: neighbours,
// frames and normal pairs, the parallel plan and the batches of the polar pass. The force
// passes that read it are forces/shape_memory.hpp and forces/shape_memory_batch.hpp.
#pragma once

#include <span>
#include <string>

#include "phymul/model.hpp"

namespace phymul {

// The batched polar pass takes this many memory nodes at once (lanes of one vector).
inline constexpr int kShapeMemoryLanes = 4;
// Neighbour counts above this go the scalar way (tetrahedral meshes reach about 20).
inline constexpr int kShapeMemoryMaxBatchedNeighbours = 32;

// Rest memory of every node of `mesh`, whose node k is global node first_node + k with rest
// position rest[first_node + k]. Surface meshes use ordered one-rings, volume meshes edge
// neighbours.
ShapeMemory build_shape_memory(const std::string& component, const Mesh& mesh, int first_node,
                               const MaterialSpec& material, std::span<const Vec3> rest);

// (Re)computes the rest-shape data of `memory` (centroids, offsets, frames, plans) from the
// rest positions, for its nodes and neighbours as they stand (after stitching, say).
void memorise_rest_shape(ShapeMemory& memory, std::span<const Vec3> rest);

// Fills m.batch_order, m.batched_end and m.centred_start from m.plan and the rest positions
// (polar mode; frame mode keeps them empty and every node scalar).
void plan_polar_batches(ShapeMemory& m, std::span<const Vec3> rest);
// Whether m's batch plan still matches its parallel plan (else its nodes go the scalar way,
// in node order).
bool polar_batches_planned(const ShapeMemory& m);

// A memory node whose rest position is its rest neighbours' centroid to round-off (64
// machine epsilons of its longest rest offset): its pull is the current neighbours' centroid
// less its position, whatever the rotation, so neither fit nor rotation is needed.
bool is_centred(const ShapeMemory& m, int k, std::span<const Vec3> rest);

}  // namespace phymul

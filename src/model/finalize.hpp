// The parts of finalize (model.hpp): what is derived from the rest once the components,
// loads and constraints are in.
#pragma once

#include <cstddef>
#include <vector>

#include "phymul/model.hpp"

namespace phymul {

// Fills Model::rigid_bodies (nodes, mass, principal inertia, offsets) and
// Model::rigid_body_of from the node masses; the doubled partners of rigid nodes join the
// body. Throws std::invalid_argument on a degenerate body.
void finalize_rigid_bodies(Model& model);

// Connected groups of Model::doubled_pairs (each sorted, groups by first id).
std::vector<std::vector<int>> doubled_groups(const Model& model);

// Fills Model::doubled with the groups that no rigid body moves and makes a held axis of a
// member hold the whole group (inverse_mass). After the rigid bodies.
void finalize_doubled(Model& model);

// Indexes the triangles around each node of c, so that its gradient is gathered node by
// node, in parallel, rather than scattered from the triangles.
void index_volume_faces(VolumeConstraint& c);

// Lists in each VolumeConstraint::shared the nodes it shares with the earlier ones.
void index_shared_volume_nodes(Model& model);

// The joint gradient scatter's length for a model of `nodes` nodes: an aligned 32-byte slot
// per node, and the three doubles it may take to reach the first 32-byte boundary.
inline size_t coupled_scatter_size(size_t nodes) { return 4 * nodes + 3; }

// Per node: its shortest rest edge (m) where the runaway guard watches it (a node with a
// shape memory, free on every axis), infinity elsewhere.
std::vector<double> runaway_edges(const Model& model);

}  // namespace phymul

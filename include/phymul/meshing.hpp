// Volume meshing of a closed surface into tetrahedra (Gmsh's Delaunay mesher through its C++
// API, libgmsh-dev): an organ's boundary from a segmentation becomes a volumetric object.
#pragma once

#include "phymul/mesh.hpp"

namespace phymul {

// Tetrahedra filling the closed, outward surface (triangles only, as check_closed_surface
// leaves them), its triangles kept as their boundary faces and its points as the first
// points; `edge` (m) caps the tetrahedra's edges inside. Throws MeshError when the mesher
// fails (a surface it cannot fill).
Mesh fill_with_tetrahedra(const Mesh& surface, double edge);

struct TetraQuality {
  size_t tetrahedra = 0;
  double min_dihedral_deg = 0.0;  // smallest dihedral angle over all tetrahedra
  double max_radius_edge = 0.0;   // largest circumradius over shortest edge (regular: 0.612)
};
TetraQuality tetra_quality(const Mesh& mesh);

}  // namespace phymul

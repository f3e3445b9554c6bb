// Volume meshing of a closed surface into tetrahedra (Gmsh's Delaunay mesher through its C++
// API, libgmsh-dev): an organ's boundary from a segmentation becomes a volumetric object.
// Surface remeshing to a target edge (docs/meshing-remesh.md): a segmentation's fine, irregular
// triangles become ones of about one size, as the shape memory wants.
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

struct SurfaceQuality {
  size_t triangles = 0;
  double min_angle_deg = 0.0;  // smallest angle of any triangle (equilateral: 60)
  double max_aspect = 0.0;     // largest longest-edge over 2 sqrt(3) inradius (equilateral: 1)
  double edge_min = 0.0, edge_mean = 0.0, edge_max = 0.0;  // m, over the unique edges
};
SurfaceQuality surface_quality(const Mesh& surface);

// Volume (m^3) a closed outward triangle surface encloses.
double enclosed_volume(const Mesh& surface);

struct Remeshed {
  Mesh surface;  // closed, manifold, outward triangles
  SurfaceQuality quality;
  double deviation = 0.0;  // m: largest distance between the two surfaces, sampled both ways
  double volume_before = 0.0, volume_after = 0.0;  // m^3, enclosed
};

// Isotropic remeshing of a closed, outward triangle surface (as check_closed_surface leaves it;
// crossing triangles are not looked for again) to edges of about `edge` (m): split, collapse,
// flip, relax, project back onto the input (Botsch and Kobbelt 2004). Throws MeshError naming
// the allowed edge range when `edge` is too long for the surface (fewer than 20 triangles) or
// too short, and when the input is not closed, manifold and outward or the result is not.
Remeshed remesh_surface(const Mesh& closed_surface, double edge);

}  // namespace phymul

// Clean-up of an extracted triangle surface: Taubin smoothing and its largest part.
#pragma once

#include "phymul/mesh.hpp"

namespace phymul::detail {

// Taubin's lambda|mu smoothing ("A signal processing approach to fair surface design", 1995):
// a shrinking umbrella step then an inflating one, `iterations` pairs, so that the surface
// is smoothed without the shrinkage of plain Laplacian smoothing. Uniform weights.
void taubin_smooth(Mesh& surface, int iterations, double lambda = 0.5, double mu = -0.53);

// Merges the ends of edges shorter than `min_edge` (at their midpoint) while the surface stays
// closed and manifold, no triangle turns by more than 60 degrees and no edge grows past
// `max_edge`; at most `passes` sweeps over the triangles.
void collapse_short_edges(Mesh& surface, double min_edge, double max_edge, int passes = 8);

// 1 for an equilateral triangle, 0 for a degenerate one (2 sqrt(3) |cross| / sum of squares).
double triangle_quality(const Vec3& a, const Vec3& b, const Vec3& c);

// Turns the shared edge of two nearly coplanar triangles (normals within 18 degrees) when that
// improves the worse triangle's quality; at most `passes` sweeps. Returns the flips made.
int flip_edges(Mesh& surface, int passes = 5);

// Moves every point along its normal by one distance so that the surface encloses `volume`
// (Taubin's smoothing and the collapses shift it slightly).
void restore_volume(Mesh& surface, double volume);

struct LargestPart {
  Mesh mesh;                    // the closed part enclosing the most volume, unused points gone
  int dropped = 0;              // other parts (islands, cavities)
  double dropped_volume = 0.0;  // the magnitudes of their enclosed volumes, summed
};

// The connected part (triangles sharing points) that encloses the largest volume.
LargestPart largest_part(const Mesh& surface);

}  // namespace phymul::detail

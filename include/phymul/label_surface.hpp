// Label images (a segmentation: one whole number per voxel) and the closed surface around
// chosen labels, smoothed across thick slices, ready for fill_with_tetrahedra (meshing.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <span>
#include <vector>

#include "phymul/mesh.hpp"

namespace phymul {

// A voxel grid in its physical frame: voxel (i, j, k) has its centre at
// origin + axes * (i, j, k); `axes` (m per index step) may rotate, flip or shear.
struct LabelImage {
  std::array<int, 3> dims{0, 0, 0};
  std::vector<std::int32_t> labels;  // i fastest, then j, then k
  Eigen::Matrix3d axes = Eigen::Matrix3d::Zero();
  Vec3 origin = Vec3::Zero();  // m

  std::int32_t at(int i, int j, int k) const {
    return labels[size_t(i) + size_t(dims[0]) * (size_t(j) + size_t(dims[1]) * size_t(k))];
  }
  Vec3 spacing() const { return axes.colwise().norm().transpose(); }  // m along i, j, k
};

// How many voxels hold each label, background included.
std::map<std::int32_t, size_t> label_counts(const LabelImage& image);

struct LabelSurfaceReport {
  size_t voxels = 0;             // of the chosen labels
  double labelled_volume = 0.0;  // m^3: voxels x voxel volume
  double surface_volume = 0.0;   // m^3 enclosed by the surface
  Vec3 centroid = Vec3::Zero();  // m, of the enclosed volume
  std::array<Vec3, 2> box;       // m, axis-aligned in the physical frame
  int slice_axis = 2;            // the image axis sampled thickest (0 i, 1 j, 2 k)
  double grid_spacing = 0.0;     // m, of the resampling grid the surface came from
  // 0: coarsened to the edge and smoothed; 1: smoothed only; 2: as cut from the grid. The
  // first of these whose surface does not intersect itself is kept.
  int cleanup_stage = 0;
  int dropped_components = 0;   // islands and cavities left out (the largest part kept)
  double dropped_volume = 0.0;  // m^3, their enclosed volumes' magnitudes summed
};

// The closed, outward surface (triangles) around the voxels holding any of `labels`, in the
// image's physical frame (m). Across the thickest axis the slices' signed distances are
// interpolated (shape-based interpolation: no staircase), the result resampled on a grid of
// about edge / 2, cut at zero (marching tetrahedra: closed and manifold), reduced to its
// largest part, coarsened to about `edge` and Taubin-smoothed (less where that would fold
// it: see cleanup_stage). `edge` (m) is the triangles' intended size. Throws MeshError
// when no voxel holds a label (naming the labels present), or when the grid would be too big.
// `first_stage` skips the clean-ups before it.
Mesh label_surface(const LabelImage& image, std::span<const int> labels, double edge,
                   LabelSurfaceReport* report = nullptr, int first_stage = 0);

// The tetrahedra filling that surface (fill_with_tetrahedra, `edge` inside too), with the next
// clean-up stage's surface when the mesher refuses one; the surface used in `surface`.
Mesh label_volume(const LabelImage& image, std::span<const int> labels, double edge,
                  LabelSurfaceReport* report = nullptr, Mesh* surface = nullptr);

}  // namespace phymul

// NIfTI-1 label images (.nii, .nii.gz): the usual output of segmentation tools.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "phymul/label_surface.hpp"
#include "phymul/mesh_io.hpp"

namespace phymul {

// Limits on what is read, checked before anything is allocated.
inline constexpr int kNiftiMaxDim = 2048;                            // voxels along one axis
inline constexpr long long kNiftiMaxVoxels = 512LL * 512LL * 512LL;  // in all
inline constexpr double kNiftiMinVoxelMm = 1e-3, kNiftiMaxVoxelMm = 100.0;
// Where the first voxel may lie from the scanner's origin: a body is within metres of it.
inline constexpr double kNiftiMaxOriginMm = 1e5;

// One NIfTI-1 single-file image (magic "n+1"), either byte order, gzip-compressed or not
// (told by its first bytes, not its name). Voxel values must be whole numbers (uint8, int8,
// int16, uint16, int32, uint32, float32 or float64 holding integers); scl_slope/scl_inter are
// ignored, as label values are not intensities. The frame: the sform when sform_code > 0,
// else the qform (quaternion, qfac) when qform_code > 0, else pixdim scaling; lengths in the
// unit of xyzt_units (mm when unset), converted to metres. Throws MeshFileError naming the
// file and the header field, what was expected and what was found; what was assumed is
// appended to `notes`.
LabelImage read_nifti_labels(const std::filesystem::path& path,
                             std::vector<std::string>* notes = nullptr);

// The same from the file's bytes (gzip or not); `name` is used in messages.
LabelImage parse_nifti_labels(std::string_view bytes, const std::string& name,
                              std::vector<std::string>* notes = nullptr);

// True for a name ending in .nii or .nii.gz.
bool is_nifti_path(const std::filesystem::path& path);

}  // namespace phymul

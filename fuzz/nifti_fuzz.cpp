// libFuzzer target: the NIfTI-1 label image reader (raw or gzip, either byte order) and, for
// small images, the surface of their label 1. Any input is an image whose sizes and frame
// are within the limits, or a MeshFileError / MeshError with a message; any other exception,
// a crash, a hang or a sanitizer report is a finding.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "mesh_checks.hpp"
#include "phymul/label_surface.hpp"
#include "phymul/nifti.hpp"

namespace {

void check_image(const phymul::LabelImage& im) {
  const size_t count = size_t(im.dims[0]) * size_t(im.dims[1]) * size_t(im.dims[2]);
  const phymul::Vec3 mm = im.spacing() * 1e3;
  bool ok = im.labels.size() == count && im.origin.allFinite() && im.axes.allFinite() &&
            im.origin.cwiseAbs().maxCoeff() * 1e3 <= phymul::kNiftiMaxOriginMm;
  for (int a = 0; a < 3; ++a)
    ok = ok && im.dims[size_t(a)] >= 1 && im.dims[size_t(a)] <= phymul::kNiftiMaxDim &&
         mm[a] > phymul::kNiftiMinVoxelMm && mm[a] < phymul::kNiftiMaxVoxelMm;
  if (!ok) {
    std::fprintf(stderr, "the reader returned an image outside its limits\n");
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    const phymul::LabelImage image = phymul::parse_nifti_labels(bytes, "fuzz");
    check_image(image);
    if (image.labels.size() <= 4096) {
      const int labels[] = {1};
      const phymul::Mesh surface =
          phymul::label_surface(image, labels, 2.0 * image.spacing().maxCoeff());
      fuzz::check_mesh(surface);
    }
  } catch (const phymul::MeshFileError& e) {
    fuzz::check_error(e);
  } catch (const phymul::MeshError& e) {
    if (std::string(e.what()).empty()) std::abort();
  }
  return 0;
}

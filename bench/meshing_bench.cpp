// Volume meshing's time on one core (issue 23, item 9): a 20,480-triangle closed surface
// filled with about 50,000 tetrahedra, and a segmentation (prostate_00, labels 1 and 2) from
// its NIfTI file to a volume mesh.
#include <benchmark/benchmark.h>

#include "phymul/installation.hpp"
#include "phymul/label_surface.hpp"
#include "phymul/meshing.hpp"
#include "phymul/nifti.hpp"

namespace {

using namespace phymul;

// An ellipsoid of 30 x 25 x 20 mm semi-axes, 5 subdivisions (20,480 triangles), edge given
// in tenths of a mm as the argument. Gmsh grows the tetrahedra from the surface's triangles
// (0.9 mm here), the edge only caps them: about 238,000 come out whatever the edge.
void BM_FillClosedSurface(benchmark::State& state) {
  const Mesh surface = make_ellipsoid_surface(Vec3(0.030, 0.025, 0.020), 5);
  const double edge = double(state.range(0)) * 1e-4;
  size_t tetrahedra = 0;
  for (auto _ : state) {
    const Mesh volume = fill_with_tetrahedra(surface, edge);
    tetrahedra = volume.cells.size();
    benchmark::DoNotOptimize(volume.points.data());
  }
  state.counters["triangles"] = double(surface.cells.size());
  state.counters["tetrahedra"] = double(tetrahedra);
}
BENCHMARK(BM_FillClosedSurface)->Arg(30)->Unit(benchmark::kSecond)->Iterations(3);

// What `phymul mesh prostate_00.nii.gz --labels 1,2 --edge '4 mm'` computes: read, surface,
// tetrahedra (the writing of the .vtu aside).
void BM_ProstateImageToVolume(benchmark::State& state) {
  const auto path = share_directory() / "data" / "prostate_mri" / "prostate_00.nii.gz";
  const int labels[] = {1, 2};
  const double edge = double(state.range(0)) * 1e-3;
  size_t triangles = 0, tetrahedra = 0;
  for (auto _ : state) {
    const LabelImage image = read_nifti_labels(path);
    Mesh surface;
    const Mesh volume = label_volume(image, labels, edge, nullptr, &surface);
    triangles = surface.cells.size(), tetrahedra = volume.cells.size();
    benchmark::DoNotOptimize(volume.points.data());
  }
  state.counters["triangles"] = double(triangles);
  state.counters["tetrahedra"] = double(tetrahedra);
}
BENCHMARK(BM_ProstateImageToVolume)->Arg(4)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

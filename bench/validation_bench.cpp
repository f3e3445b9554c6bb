// The validation study's time: the Truth Cube table (three levels, shape memory and FEM) and
// the per-object stiffness calibration a scene giving `young` pays when it is compiled.
#include <benchmark/benchmark.h>

#include "phymul/calibration.hpp"
#include "phymul/installation.hpp"
#include "phymul/studies/truthcube.hpp"

namespace {

using namespace phymul;

// Everything `phymul truthcube` computes for its table, files and pictures aside (the shape
// memory's plate force includes its K calibration).
void BM_TruthCubeTable(benchmark::State& state) {
  const auto beads =
      truthcube::load_beads(share_directory() / "data" / "truthcube" / "uniaxial_positions.csv");
  truthcube::StudyOptions o;
  o.cells = int(state.range(0));
  for (auto _ : state) {
    const truthcube::Study study = truthcube::run_study(beads, o);
    benchmark::DoNotOptimize(study.results.data());
  }
  state.counters["cells"] = double(o.cells);
}
BENCHMARK(BM_TruthCubeTable)->Arg(8)->Unit(benchmark::kSecond)->MinTime(2.0);

// K from E on an 80 mm cube of n^3 hexahedra (E 14.9 kPa, nu 0.499, volume kept).
void BM_StiffnessFromYoung(benchmark::State& state) {
  const int n = int(state.range(0));
  const Mesh cube = make_box(Vec3::Constant(0.08), {n, n, n}, CellType::hexa);
  MaterialSpec m;
  m.young = 14.9e3;
  m.poisson = 0.499;
  m.density = 1000.0;
  for (auto _ : state)
    benchmark::DoNotOptimize(calibration::calibrate_object("cube", cube, m, true).stiffness);
  state.counters["nodes"] = double(cube.points.size());
}
BENCHMARK(BM_StiffnessFromYoung)->Arg(8)->Arg(16)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

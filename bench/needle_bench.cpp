// The biopsy scene (examples/prostate/biopsy.yaml) stepped on one thread with the needle in
// the gland: ns per node per step and the real-time factor dt / (time per step), which must
// reach 1 for the scene to run as fast as real time on one core. real_time_factor counts
// wall-clock time, cpu_real_time_factor this thread's CPU time (a busy machine's share).
// BM_BiopsyImplicit: whole runs in implicit steps of range(0) ms, from rest through the
// puncture to the end, each from a fresh Data.
#include <benchmark/benchmark.h>
#include <omp.h>

#include "implicit_runs.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "thread_cpu_time.hpp"

namespace {

using namespace phymul;

void BM_BiopsyStep(benchmark::State& state) {
  omp_set_num_threads(1);
  Simulator sim(compile_scene(load_scene(PHYMUL_SOURCE_DIR "/examples/prostate/biopsy.yaml")));
  // Past the puncture (about 1.16 s), the needle going on into the gland, then held there.
  while (sim.data().time < 1.3) sim.step();
  time_steps(state, sim);
  state.counters["track_points"] = double(sim.data().needles[0].track.size());
}
BENCHMARK(BM_BiopsyStep)->Unit(benchmark::kMicrosecond)->MinTime(1.0);

void BM_BiopsyImplicit(benchmark::State& state) {
  omp_set_num_threads(1);
  Scene scene = load_scene(PHYMUL_SOURCE_DIR "/examples/prostate/biopsy.yaml");
  scene.simulation.integrator = Integrator::implicit;
  scene.simulation.dt = double(state.range(0)) * 1e-3;
  double punctures = 0.0;
  time_implicit_runs(
      state, compile_scene(scene), scene.simulation.duration,
      [&](const Simulator& sim) { punctures = double(sim.data().needles[0].punctures.size()); });
  state.counters["punctures"] = punctures;
}
BENCHMARK(BM_BiopsyImplicit)
    ->Arg(2)
    ->Arg(5)
    ->ArgName("dt_ms")
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);

}  // namespace

BENCHMARK_MAIN();

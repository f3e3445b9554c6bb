// The biopsy scene (examples/prostate/biopsy.yaml) stepped on one thread with the needle in
// the gland: ns per node per step and the real-time factor dt / (time per step), which must
// reach 1 for the scene to run as fast as real time on one core. real_time_factor counts
// wall-clock time, cpu_real_time_factor this thread's CPU time (a busy machine's share).
// BM_BiopsyImplicit: whole runs in implicit steps of range(0) ms, from rest through the
// puncture to the end, each from a fresh Data.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <chrono>

#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "solver/implicit_step.hpp"
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
  const Model model = compile_scene(scene);
  double seconds = 0.0, cpu = 0.0, steps = 0.0, solves = 0.0, worst = 0.0, punctures = 0.0;
  for (auto _ : state) {
    Simulator sim(model);
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = thread_cpu_seconds();
    while (sim.data().time < scene.simulation.duration - 1e-12) {
      sim.step();
      steps += 1.0;
      solves += implicit_iterations(sim.data());
      worst = std::max(worst, implicit_residual_force(sim.data()));
    }
    cpu += thread_cpu_seconds() - cpu_start;
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    punctures = double(sim.data().needles[0].punctures.size());
  }
  const double dt = *scene.simulation.dt;
  state.counters["ns_per_node_step"] = seconds * 1e9 / (model.node_count() * steps);
  state.counters["solves_per_step"] = solves / steps;
  state.counters["worst_residual_N"] = worst;
  state.counters["punctures"] = punctures;
  state.counters["real_time_factor"] = dt * steps / seconds;
  state.counters["cpu_real_time_factor"] = dt * steps / cpu;
}
BENCHMARK(BM_BiopsyImplicit)
    ->Arg(2)
    ->Arg(5)
    ->ArgName("dt_ms")
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);

}  // namespace

BENCHMARK_MAIN();

// The prostate study's scenes (examples/prostate, as `phymul prostate --scenes` writes them)
// stepped in explicit dynamics: ns per node per step, and the real-time factor dt / (wall time
// per step), which must reach 1 for the study to run as fast as real time on one core.
#include <benchmark/benchmark.h>

#include <chrono>

#include "phymul/prostate.hpp"
#include "phymul/simulator.hpp"

namespace {

using namespace phymul;

void BM_ProstateStep(benchmark::State& state) {
  const double filling = double(state.range(0)) * 1e-6;
  const auto probe = state.range(1) == 0 ? prostate::Probe::pressure : prostate::Probe::rigid;
  const prostate::Options options;
  prostate::SceneSettings scene = prostate::study_scene(options, filling, probe);
  scene.dynamic = true;
  Simulator sim(compile_scene(parse_scene(prostate::scene_text(options, scene), "bench.yaml")));
  // Past the settling, into the probe's push (0.2 s of load time onwards).
  while (sim.state().time < 0.3) sim.step();
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) sim.step();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double steps = double(state.iterations()), nodes = sim.model().node_count();
  state.counters["nodes"] = nodes;
  state.counters["ns_per_node_step"] = seconds * 1e9 / (nodes * steps);
  state.counters["dt_us"] = sim.dt() * 1e6;
  state.counters["real_time_factor"] = sim.dt() * steps / seconds;
}
BENCHMARK(BM_ProstateStep)
    ->ArgsProduct({{50, 400}, {0, 1}})
    ->ArgNames({"mL", "rigid"})
    ->Unit(benchmark::kMicrosecond)
    ->MinTime(1.0);

}  // namespace

BENCHMARK_MAIN();

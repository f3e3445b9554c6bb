// The prostate study's scenes (as `phymul prostate --scenes` writes them: examples/prostate)
// stepped in explicit dynamics on one thread: ns per node per step, and the real-time factor
// dt / (time per step), which must reach 1 for the study to run as fast as real time on one
// core. real_time_factor counts wall-clock time, cpu_real_time_factor this thread's CPU time
// (what the step costs when a busy machine shares the core).
#include <benchmark/benchmark.h>
#include <omp.h>

#include "implicit_runs.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "phymul/studies/prostate.hpp"
#include "thread_cpu_time.hpp"

namespace {

using namespace phymul;

void BM_ProstateStep(benchmark::State& state) {
  omp_set_num_threads(1);
  const double filling = double(state.range(0)) * 1e-6;
  const auto probe = state.range(1) == 0 ? prostate::Probe::pressure : prostate::Probe::rigid;
  // The study's fine bladder (642 nodes) or the coarse one that runs in real time.
  const prostate::Options options =
      state.range(2) == 0 ? prostate::Options{} : prostate::coarse_bladder(prostate::Options{});
  const prostate::SceneSettings scene = prostate::dynamic_scene(options, filling, probe);
  Simulator sim(compile_scene(parse_scene(prostate::scene_text(options, scene), "bench.yaml")));
  // Past the settling, into the probe's push (0.2 s of load time onwards).
  while (sim.data().time < 0.3) sim.step();
  time_steps(state, sim);
  double mass = 0.0;
  for (double m : sim.model().mass) mass += m;
  state.counters["added_mass_pct"] = 100.0 * sim.added_inertia() / mass;
}
BENCHMARK(BM_ProstateStep)
    ->ArgsProduct({{50, 100, 200, 300, 400}, {0, 1}, {0, 1}})
    ->ArgNames({"mL", "rigid", "coarse"})
    ->Unit(benchmark::kMicrosecond)
    ->MinTime(1.0);

// The study's dynamic scene (fine bladder, the pressure probe or, range(2) = 1, the rigid
// one) in implicit steps of 5 ms, at most range(1) global solves each: whole runs, from rest
// through the probe's push to the scene's end, each from a fresh Data (its first step
// factorises): the real-time factor on one core.
void BM_ProstateImplicit(benchmark::State& state) {
  omp_set_num_threads(1);
  const double filling = double(state.range(0)) * 1e-6;
  const prostate::Options options{};
  const prostate::SceneSettings scene = prostate::dynamic_scene(
      options, filling, state.range(2) ? prostate::Probe::rigid : prostate::Probe::pressure);
  Scene parsed = parse_scene(prostate::scene_text(options, scene), "bench.yaml");
  parsed.simulation.integrator = Integrator::implicit;
  parsed.simulation.implicit_iterations = int(state.range(1));
  parsed.simulation.dt = 5e-3;
  Model model;
  try {
    model = compile_scene(parsed);
  } catch (const SceneError& e) {
    state.SkipWithError(e.what());
    return;
  }
  time_implicit_runs(state, model, scene.duration, [](const Simulator&) {});
}
BENCHMARK(BM_ProstateImplicit)
    ->ArgsProduct({{50, 400}, {5, 20}, {0, 1}})
    ->ArgNames({"mL", "iterations", "rigid"})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);

}  // namespace

BENCHMARK_MAIN();

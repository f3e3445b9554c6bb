// The prostate study's scenes (as `phymul prostate --scenes` writes them: examples/prostate)
// stepped in explicit dynamics on one thread: ns per node per step, and the real-time factor
// dt / (time per step), which must reach 1 for the study to run as fast as real time on one
// core. real_time_factor counts wall-clock time, cpu_real_time_factor this thread's CPU time
// (what the step costs when a busy machine shares the core).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <chrono>

#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "phymul/studies/prostate.hpp"
#include "solver/implicit_step.hpp"
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

// The study's scene (pressure probe, fine bladder) in implicit steps of 5 ms, at most
// range(1) global solves each: the real-time factor on one core. Scenes the implicit steps do
// not support report why.
void BM_ProstateImplicit(benchmark::State& state) {
  omp_set_num_threads(1);
  const double filling = double(state.range(0)) * 1e-6;
  const prostate::Options options{};
  const prostate::SceneSettings scene =
      prostate::dynamic_scene(options, filling, prostate::Probe::pressure);
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
  Simulator sim(std::move(model));
  while (sim.data().time < 0.3) sim.step();
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = thread_cpu_seconds();
  double solves = 0.0, worst = 0.0;
  for (auto _ : state) {
    sim.step();
    solves += implicit_iterations(sim.data());
    worst = std::max(worst, implicit_residual_force(sim.data()));
  }
  const double cpu = thread_cpu_seconds() - cpu_start;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double steps = double(state.iterations()), nodes = sim.model().node_count();
  state.counters["nodes"] = nodes;
  state.counters["ns_per_node_step"] = seconds * 1e9 / (nodes * steps);
  state.counters["dt_us"] = sim.dt() * 1e6;
  state.counters["solves_per_step"] = solves / steps;
  state.counters["worst_residual_N"] = worst;
  state.counters["real_time_factor"] = sim.dt() * steps / seconds;
  state.counters["cpu_real_time_factor"] = sim.dt() * steps / cpu;
}
BENCHMARK(BM_ProstateImplicit)
    ->ArgsProduct({{50, 400}, {5, 20}})
    ->ArgNames({"mL", "iterations"})
    ->Unit(benchmark::kMicrosecond)
    ->MinTime(1.0);

}  // namespace

BENCHMARK_MAIN();

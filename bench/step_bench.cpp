// One full step (shape memory or TLED + volume constraint + fixed base + pushed top) on hexahedral
// grids of n^3 cells; reports the time per node per step.
#include <benchmark/benchmark.h>
#include <omp.h>

#include "cube.hpp"
#include "phymul/scene.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/studies/prostate.hpp"

namespace {

using phymul::bench::cube_on_base;

// range(0): cells per edge, range(1): OpenMP threads.
void step_benchmark(benchmark::State& state, phymul::ElasticModel elasticity) {
  omp_set_num_threads(int(state.range(1)));
  phymul::Simulator sim(phymul::bench::pushed_cube(int(state.range(0)), elasticity));
  phymul::bench::time_steps(state, sim);
  state.counters["threads"] = double(state.range(1));
}

// One full step: shape memory (polar, reaction) or explicit finite elements (TLED), with the
// volume constraint, the fixed base, the pushed top and damping.
void BM_Step(benchmark::State& state) { step_benchmark(state, phymul::ElasticModel::shape_memory); }
void BM_StepFem(benchmark::State& state) { step_benchmark(state, phymul::ElasticModel::fem); }
BENCHMARK(BM_Step)
    ->ArgsProduct({{10, 20, 30, 40}, {1}})
    ->Args({40, 2})
    ->Unit(benchmark::kMillisecond);
// Implicit steps (backward Euler by local/global iterations) on the same pushed cube, at
// range(1) times the explicit scheme's dt, at most range(2) global solves a step (tolerance
// 1e-9 N: the cap is what stops them here). The factorisation, in the first step, is not
// timed. Beside BM_Step/n/1: the same grid, one thread.
void implicit_benchmark(benchmark::State& state, phymul::ElasticModel elasticity) {
  omp_set_num_threads(1);
  phymul::Model model = phymul::bench::pushed_cube(int(state.range(0)), elasticity);
  model.settings.integrator = phymul::Integrator::implicit;
  model.settings.implicit_iterations = int(state.range(2));
  model.settings.implicit_tolerance = 1e-9;
  phymul::finalize(model);
  phymul::Simulator sim(model);
  sim.set_dt(double(state.range(1)) * sim.dt());
  sim.step();
  phymul::bench::time_steps(state, sim);
  state.counters["dt_over_explicit"] = double(state.range(1));
  state.counters["ns_per_node_explicit_dt"] =
      state.counters["ns_per_node_step"] / double(state.range(1));
}
void BM_StepImplicit(benchmark::State& state) {
  implicit_benchmark(state, phymul::ElasticModel::shape_memory);
}
// The same with explicit finite elements (their stiffness in P, refactorised as cells turn):
// beside BM_StepFem/n/1.
void BM_StepFemImplicit(benchmark::State& state) {
  implicit_benchmark(state, phymul::ElasticModel::fem);
}
BENCHMARK(BM_StepFemImplicit)
    ->ArgsProduct({{10, 20}, {10, 100}, {5}})
    ->ArgNames({"n", "dt_x", "iterations"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StepImplicit)
    ->ArgsProduct({{10, 20}, {10, 100}, {5}})
    ->Args({20, 100, 20})
    ->ArgNames({"n", "dt_x", "iterations"})
    ->Unit(benchmark::kMillisecond);
// The 40^3 grid: its factor takes minutes and about a gigabyte; two steps are timed.
BENCHMARK(BM_StepImplicit)
    ->Args({40, 100, 5})
    ->ArgNames({"n", "dt_x", "iterations"})
    ->Iterations(2)
    ->Unit(benchmark::kMillisecond);

// Every shape-memory node of the model on the scalar path, in node order (the kernel before
// the batched one).
void scalar_kernel_only(phymul::Model& model) {
  for (phymul::ShapeMemory& m : model.shape_memory) {
    for (size_t k = 0; k < m.batch_order.size(); ++k) m.batch_order[k] = int(k);
    m.batched_end.assign(m.plan.block_start.begin(), m.plan.block_start.end() - 1);
    m.centred_start.assign(m.plan.block_start.begin() + 1, m.plan.block_start.end());
  }
}

// The same step with every shape-memory node on the scalar path, in node order (the kernel
// before the batched one): what the batched kernel gains, measured in one binary.
void BM_StepScalar(benchmark::State& state) {
  omp_set_num_threads(int(state.range(1)));
  phymul::Model model = phymul::bench::pushed_cube(int(state.range(0)));
  scalar_kernel_only(model);
  phymul::Simulator sim(std::move(model));
  phymul::bench::time_steps(state, sim);
  state.counters["threads"] = double(state.range(1));
}
BENCHMARK(BM_StepScalar)
    ->Args({10, 1})
    ->Args({40, 1})
    ->Args({40, 2})
    ->Unit(benchmark::kMillisecond);
// The prostate study's 50 mL scene (pressure probe, as bench/prostate_bench.cpp, one thread)
// with the batched kernel (range(0) = 1) or the scalar one (0): its bladder is a surface, every
// node of which carries the ring normal's pair.
void BM_ProstateKernel(benchmark::State& state) {
  using namespace phymul;
  omp_set_num_threads(1);
  const prostate::Options options;
  prostate::SceneSettings scene = prostate::study_scene(options, 50e-6, prostate::Probe::pressure);
  scene.dynamic = true;
  Model model = compile_scene(parse_scene(prostate::scene_text(options, scene), "bench.yaml"));
  if (state.range(0) == 0) scalar_kernel_only(model);
  Simulator sim(std::move(model));
  while (sim.data().time < 0.3) sim.step();  // past the settling, into the probe's push
  bench::time_steps(state, sim);
}
BENCHMARK(BM_ProstateKernel)->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_StepFem)->ArgsProduct({{10, 40}, {1}})->Args({40, 2})->Unit(benchmark::kMillisecond);

// Time to equilibrium: an 80 mm cube of n^3 hexahedra, volume kept, base fixed, top pushed
// 14.6 mm (18.25 %, the Truth Cube's last level) without slip, relaxed to 1e-6 N.
void BM_Equilibrium(benchmark::State& state) {
  using namespace phymul;
  Model model = cube_on_base(int(state.range(0)));
  add_prescribed_displacement(model, {model.components[0].node_sets.at("top"),
                                      {true, true, true},
                                      Schedule{{0.0, 1.0}, {Vec3::Zero(), Vec3(0, 0, -0.0146)}}});
  model.settings.mode = SolveMode::static_equilibrium;
  model.settings.tolerance = 1e-6;
  model.settings.load_steps = 4;
  model.settings.relaxation = Relaxation::fire;
  finalize(model);
  omp_set_num_threads(1);
  StaticResult result;
  for (auto _ : state) {
    Simulator sim(model);
    result = sim.solve_static();
  }
  state.counters["nodes"] = model.node_count();
  state.counters["iterations"] = double(result.iterations);
  state.counters["converged"] = result.converged ? 1 : 0;
}
BENCHMARK(BM_Equilibrium)->Arg(8)->Arg(16)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();

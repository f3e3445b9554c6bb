// One full step (shape memory + volume constraint + fixed base + gravity) on hexahedral
// grids of n^3 cells; reports the time per node per step.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <chrono>

#include "phymul/simulator.hpp"

namespace {

// An 80 mm cube of n^3 hexahedra, volume kept, on a fixed base; not finalized.
phymul::Model cube_on_base(int n,
                           phymul::ElasticModel elasticity = phymul::ElasticModel::shape_memory) {
  using namespace phymul;
  Model model;
  MaterialSpec material;
  material.model = elasticity;
  material.stiffness = 20.0;
  material.young = 14.9e3;  // the Truth Cube's silicone, compressible enough for explicit steps
  material.poisson = 0.45;
  material.density = 1000.0;
  const int c = add_elastic_component(
      model, "cube", make_box(Vec3(0.08, 0.08, 0.08), {n, n, n}, CellType::hexa), material);
  add_volume_constraint(model, c);
  add_fixed_nodes(model, model.components[c].node_sets.at("bottom"));
  return model;
}

// The cube's top pushed down 8 mm (10 %) in 50 ms without slip, then held: damped dynamics.
// (Until this session the block sagged under gravity instead; the shape memory hardly
// resists a uniform strain, so it collapsed into a tangle that the runaway guard now stops.)
phymul::Model block(int n, phymul::ElasticModel elasticity) {
  using namespace phymul;
  Model model = cube_on_base(n, elasticity);
  add_prescribed_displacement(model, {model.components[0].node_sets.at("top"),
                                      {true, true, true},
                                      Schedule{{0.0, 0.05}, {Vec3::Zero(), Vec3(0, 0, -0.008)}}});
  model.damping = 5.0;
  finalize(model);
  return model;
}

// range(0): cells per edge, range(1): OpenMP threads.
void step_benchmark(benchmark::State& state, phymul::ElasticModel elasticity) {
  const int n = int(state.range(0));
  omp_set_num_threads(int(state.range(1)));
  phymul::Simulator sim(block(n, elasticity));
  // Timed here as well so that the table shows plain nanoseconds per node and step.
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) sim.step();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double nodes = sim.model().node_count();
  state.counters["nodes"] = nodes;
  state.counters["threads"] = double(state.range(1));
  state.counters["ns_per_node_step"] = seconds * 1e9 / (nodes * double(state.iterations()));
}

// One full step: shape memory (polar, reaction) or explicit finite elements (TLED), with the
// volume constraint, the fixed base, the pushed top and damping.
void BM_Step(benchmark::State& state) { step_benchmark(state, phymul::ElasticModel::shape_memory); }
void BM_StepFem(benchmark::State& state) { step_benchmark(state, phymul::ElasticModel::fem); }
BENCHMARK(BM_Step)
    ->ArgsProduct({{10, 20, 30, 40}, {1}})
    ->Args({40, 2})
    ->Unit(benchmark::kMillisecond);
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

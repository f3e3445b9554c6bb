// One full step (shape memory + volume constraint + fixed base + gravity) on hexahedral
// grids of n^3 cells; reports ns per node per step.
#include <benchmark/benchmark.h>

#include "phymul/simulator.hpp"

namespace {

phymul::Model block(int n) {
  using namespace phymul;
  Model model;
  MaterialSpec material;
  material.stiffness = 20.0;
  material.density = 1000.0;
  const int c = add_elastic_component(
      model, "block", make_box(Vec3(0.08, 0.08, 0.08), {n, n, n}, CellType::hexa), material);
  add_volume_constraint(model, c);
  add_fixed_nodes(model, model.components[c].node_sets.at("bottom"));
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 5.0;
  finalize(model);
  return model;
}

void BM_Step(benchmark::State& state) {
  const int n = int(state.range(0));
  phymul::Simulator sim(block(n));
  for (auto _ : state) sim.step();
  const double nodes = sim.model().node_count();
  state.counters["nodes"] = nodes;
  state.counters["ns_per_node_step"] =
      benchmark::Counter(nodes * double(state.iterations()) * 1e-9,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Step)->Arg(10)->Arg(20)->Arg(30)->Arg(40)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

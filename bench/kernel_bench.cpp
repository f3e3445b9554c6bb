// The shape-memory pass alone (forces/shape_memory.cpp and its batched kernel) on the step
// benchmark's pushed cube, in the middle of its push: the rotations one step old, as a dynamic
// step finds them, so that the lanes take the Newton turns a step takes. Reports the time per
// memory node of one pass.
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <chrono>

#include "cube.hpp"
#include "forces/shape_memory.hpp"
#include "thread_cpu_time.hpp"

namespace {

using namespace phymul;

struct Snapshot {
  std::vector<Vec3> x;                       // at step s + 1
  std::vector<Eigen::Quaterniond> rotation;  // fitted at step s
};

// The pushed cube stepped into its push (40 steps: top moved, the block deforming).
Snapshot snapshot(Simulator& sim) {
  for (int s = 0; s < 40; ++s) sim.step();
  Snapshot snap;
  snap.rotation = sim.data().rotation;
  sim.step();
  snap.x = sim.data().x;
  return snap;
}

// The centred nodes' stencil runs (the grid's interior), or node by node (the reference).
Model with_stencil(Model model, bool stencil) {
  if (!stencil)
    for (ShapeMemory& m : model.shape_memory) m.centred_on_stencil = false;
  return model;
}

// The pushed cube at its snapshot, and the pass's inputs, reset (untimed) before each pass.
struct PassInputs {
  explicit PassInputs(int cells, bool stencil = true)
      : sim(with_stencil(bench::pushed_cube(cells), stencil)),
        snap(snapshot(sim)),
        m(sim.model().shape_memory[0]),
        rotation(snap.rotation),
        f(snap.x.size()),
        blocks(size_t(m.plan.blocks())) {}
  void reset() {
    std::copy(snap.rotation.begin(), snap.rotation.end(), rotation.begin());
    std::fill(f.begin(), f.end(), Vec3::Zero());
  }
  template <class Pass>
  double run(Pass pass) {
    return pass(m, sim.model().rest_position, snap.x, rotation, f, blocks);
  }
  Simulator sim;
  const Snapshot snap;
  const ShapeMemory& m;
  std::vector<Eigen::Quaterniond> rotation;
  std::vector<Vec3> f;
  std::vector<double> blocks;  // energy per block of the plan
};

template <class Pass>
void time_pass(benchmark::State& state, Pass pass, bool stencil = true) {
  omp_set_num_threads(int(state.range(1)));
  PassInputs in(int(state.range(0)), stencil);
  double energy = 0.0;
  double seconds = 0.0, cpu_seconds = 0.0;
  for (auto _ : state) {
    in.reset();
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = thread_cpu_seconds();
    energy = in.run(pass);
    cpu_seconds += thread_cpu_seconds() - cpu_start;
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  benchmark::DoNotOptimize(energy);
  state.counters["memory_nodes"] = double(in.m.nodes.size());
  const double passes = double(in.m.nodes.size()) * double(state.iterations());
  state.counters["ns_per_node"] = seconds * 1e9 / passes;
  // This thread's CPU time (one thread): the pass's cost when a busy machine shares the core.
  state.counters["cpu_ns_per_node"] = cpu_seconds * 1e9 / passes;
}
void BM_ShapeMemoryPass(benchmark::State& state) { time_pass(state, add_shape_memory_forces); }

BENCHMARK(BM_ShapeMemoryPass)
    ->Args({24, 1})
    ->Args({40, 1})
    ->Args({40, 2})
    ->Unit(benchmark::kMillisecond);

// The same pass with the grid's centred nodes node by node: what the stencil runs gain.
void BM_ShapeMemoryPassNoStencil(benchmark::State& state) {
  time_pass(state, add_shape_memory_forces, false);
}
BENCHMARK(BM_ShapeMemoryPassNoStencil)->Args({40, 1})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

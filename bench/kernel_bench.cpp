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
#include "forces/shape_memory_single.hpp"
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
  snap.rotation = sim.state().rotation;
  sim.step();
  snap.x = sim.state().x;
  return snap;
}

// The pushed cube at its snapshot, and the pass's inputs, reset (untimed) before each pass.
struct PassInputs {
  explicit PassInputs(int cells)
      : sim(bench::pushed_cube(cells)),
        snap(snapshot(sim)),
        m(sim.model().shape_memory[0]),
        rotation(snap.rotation),
        f(snap.x.size()) {}
  void reset() {
    std::copy(snap.rotation.begin(), snap.rotation.end(), rotation.begin());
    std::fill(f.begin(), f.end(), Vec3::Zero());
  }
  template <class Pass>
  double run(Pass pass) {
    return pass(m, sim.model().rest_position, snap.x, rotation, f);
  }
  Simulator sim;
  const Snapshot snap;
  const ShapeMemory& m;
  std::vector<Eigen::Quaterniond> rotation;
  std::vector<Vec3> f;
};

// pass: add_shape_memory_forces or its single-precision variant.
template <class Pass>
void time_pass(benchmark::State& state, Pass pass) {
  omp_set_num_threads(int(state.range(1)));
  PassInputs in(int(state.range(0)));
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

// The same pass with the polar batches in float lanes (forces/shape_memory_single.cpp).
void BM_ShapeMemoryPassSingle(benchmark::State& state) {
  time_pass(state, add_shape_memory_forces_single);
}

// Both passes alternately on the same snapshot, each iteration one of each: on a shared,
// loaded machine the best and the median of each, taken side by side, compare them where two
// separate benchmarks would each meet different load.
void BM_ShapeMemoryPassDoubleVsSingle(benchmark::State& state) {
  omp_set_num_threads(int(state.range(1)));
  PassInputs in(int(state.range(0)));
  std::vector<double> ns[2];  // per node: double, single
  double energy = 0.0;
  for (auto _ : state)
    for (int precision = 0; precision < 2; ++precision) {
      in.reset();
      const auto start = std::chrono::steady_clock::now();
      energy +=
          precision == 0 ? in.run(add_shape_memory_forces) : in.run(add_shape_memory_forces_single);
      ns[precision].push_back(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() * 1e9 /
          double(in.m.nodes.size()));
    }
  benchmark::DoNotOptimize(energy);
  for (std::vector<double>& t : ns) std::sort(t.begin(), t.end());
  const size_t median = ns[0].size() / 2;
  state.counters["double_best_ns_per_node"] = ns[0][0];
  state.counters["single_best_ns_per_node"] = ns[1][0];
  state.counters["double_median_ns_per_node"] = ns[0][median];
  state.counters["single_median_ns_per_node"] = ns[1][median];
  state.counters["speedup_best"] = ns[0][0] / ns[1][0];
  state.counters["speedup_median"] = ns[0][median] / ns[1][median];
}

BENCHMARK(BM_ShapeMemoryPass)
    ->Args({24, 1})
    ->Args({40, 1})
    ->Args({40, 2})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ShapeMemoryPassSingle)
    ->Args({24, 1})
    ->Args({40, 1})
    ->Args({40, 2})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ShapeMemoryPassDoubleVsSingle)
    ->Args({24, 1})
    ->Args({40, 1})
    ->Args({40, 2})
    ->Iterations(200)
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

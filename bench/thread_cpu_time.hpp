// The calling thread's CPU time, beside a benchmark's wall time: what a step costs on one core
// when a busy machine shares it (wall time then counts the waits too).
#pragma once

#include <benchmark/benchmark.h>
#include <time.h>

#include <chrono>

#include "phymul/simulation.hpp"

inline double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// Steps `sim` once per benchmark iteration and sets the counters every scene benchmark
// reports: nodes, ns per node and step (wall), dt, and the real-time factors on the wall
// clock and on this thread's CPU time.
inline void time_steps(benchmark::State& state, phymul::Simulator& sim) {
  const auto start = std::chrono::steady_clock::now();
  const double cpu_start = thread_cpu_seconds();
  for (auto _ : state) sim.step();
  const double cpu = thread_cpu_seconds() - cpu_start;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double steps = double(state.iterations()), nodes = sim.model().node_count();
  state.counters["nodes"] = nodes;
  state.counters["ns_per_node_step"] = seconds * 1e9 / (nodes * steps);
  state.counters["dt_us"] = sim.dt() * 1e6;
  state.counters["real_time_factor"] = sim.dt() * steps / seconds;
  state.counters["cpu_real_time_factor"] = sim.dt() * steps / cpu;
}

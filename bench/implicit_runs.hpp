// Whole runs in implicit steps, timed as a user runs them (bench/prostate_bench.cpp,
// bench/needle_bench.cpp): each from a fresh Data, from rest to `duration`, its first step
// factorising.
#pragma once

#include <algorithm>
#include <chrono>

#include "solver/implicit_step.hpp"
#include "thread_cpu_time.hpp"

// Sets nodes, ns per node and step (wall), dt, solves per step, the worst residual a step
// ended at, and the real-time factors on the wall clock and this thread's CPU time; `last`
// gets the final run's simulator for the benchmark's own counters.
template <class Last>
void time_implicit_runs(benchmark::State& state, const phymul::Model& model, double duration,
                        Last last) {
  double seconds = 0.0, cpu = 0.0, steps = 0.0, solves = 0.0, worst = 0.0, dt = 0.0;
  for (auto _ : state) {
    phymul::Simulator sim(model);
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = thread_cpu_seconds();
    while (sim.data().time < duration - 1e-12) {
      sim.step();
      steps += 1.0;
      solves += phymul::implicit_iterations(sim.data());
      worst = std::max(worst, phymul::implicit_residual_force(sim.data()));
    }
    cpu += thread_cpu_seconds() - cpu_start;
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    dt = sim.dt();
    last(sim);
  }
  const double nodes = model.node_count();
  state.counters["nodes"] = nodes;
  state.counters["ns_per_node_step"] = seconds * 1e9 / (nodes * steps);
  state.counters["dt_us"] = dt * 1e6;
  state.counters["solves_per_step"] = solves / steps;
  state.counters["worst_residual_N"] = worst;
  state.counters["real_time_factor"] = dt * steps / seconds;
  state.counters["cpu_real_time_factor"] = dt * steps / cpu;
}

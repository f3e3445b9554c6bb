// The benchmarks' model and timing, shared by the step, memory and interaction benchmarks.
#pragma once

#include <benchmark/benchmark.h>

#include <chrono>

#include "phymul/simulation.hpp"

namespace phymul::bench {

// An 80 mm cube of n^3 hexahedra, volume kept, on a fixed base; not finalized.
inline Model cube_on_base(int n, ElasticModel elasticity = ElasticModel::shape_memory) {
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
// (The block used to sag under gravity instead; the shape memory hardly resists a uniform
// strain, so it collapsed into a tangle that the runaway guard now stops.)
inline Model pushed_cube(int n, ElasticModel elasticity = ElasticModel::shape_memory) {
  Model model = cube_on_base(n, elasticity);
  add_prescribed_displacement(model, {model.components[0].node_sets.at("top"),
                                      {true, true, true},
                                      Schedule{{0.0, 0.05}, {Vec3::Zero(), Vec3(0, 0, -0.008)}}});
  model.damping = 5.0;
  finalize(model);
  return model;
}

// Times the benchmark's steps itself too, so that the table shows plain nanoseconds per node
// and step.
inline void time_steps(benchmark::State& state, Simulator& sim) {
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) sim.step();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double nodes = sim.model().node_count();
  state.counters["nodes"] = nodes;
  state.counters["ns_per_node_step"] = seconds * 1e9 / (nodes * double(state.iterations()));
}

}  // namespace phymul::bench

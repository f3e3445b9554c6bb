// Steps of organs in their environment: a block pressed by a rigid probe (contact with
// friction, volume kept) and two soft organs in contact with each other (spatial hash).
// Reports the time per node per step.
#include <benchmark/benchmark.h>

#include "cube.hpp"

namespace {

using namespace phymul;

MaterialSpec tissue(double stiffness) {
  MaterialSpec m;
  m.stiffness = stiffness;
  m.density = 1000.0;
  return m;
}

// Steps timed after `warmup` steps (so the contact is established), as ns per node.
void time_steps(benchmark::State& state, Simulator& sim, int warmup) {
  for (int k = 0; k < warmup; ++k) sim.step();
  bench::time_steps(state, sim);
}

// An 80 mm cube of n^3 hexahedra, top fixed, volume kept, gravity, with a 1 cm probe whose
// tip starts 6 mm inside the bottom face and keeps pushing up (friction 0.2).
void BM_ProbeStep(benchmark::State& state) {
  const int n = int(state.range(0));
  Model model;
  const int c = add_elastic_component(
      model, "tissue", make_box(Vec3(0.08, 0.08, 0.08), {n, n, n}, CellType::hexa), tissue(20.0));
  add_volume_constraint(model, c);
  add_fixed_nodes(model, model.components[c].node_sets.at("top"));
  RigidObstacle probe;
  probe.shape = RigidObstacle::Shape::probe;
  probe.point = Vec3(0, 0, -0.04 - 0.01 + 0.006);
  probe.radius = 0.01;
  probe.friction = 0.2;
  probe.motion = Schedule{{0.0, 10.0}, {Vec3::Zero(), Vec3(0, 0, 0.01)}};
  add_rigid_obstacle(model, probe);
  model.gravity = Vec3(0, 0, -9.81);
  model.damping = 5.0;
  finalize(model);
  Simulator sim(model);
  time_steps(state, sim, 20);
}
// A fixed number of steps, the same stretch of the run on every machine: the cube, soft for
// its weight (K = 20 N/m), hangs and tangles after about 0.23 s (700 steps at 20^3), where
// the runaway guard stops it; a faster step would otherwise run into that within the
// benchmark's time.
BENCHMARK(BM_ProbeStep)->Arg(20)->Arg(40)->Iterations(200)->Unit(benchmark::kMillisecond);

// Two soft 3 cm organs (icosphere volumes, 20 * 4^s surface triangles) pressed together
// along x, overlapping 1 mm at the start so the contact works from the first step.
void BM_TwoOrgansStep(benchmark::State& state) {
  const int s = int(state.range(0));
  Model model;
  const double r = 0.03;
  const int a = add_elastic_component(
      model, "prostate", make_ellipsoid_volume({r, r, r}, s, 2 * s, Vec3(-r + 0.0005, 0, 0)),
      tissue(20.0));
  const int b = add_elastic_component(
      model, "bladder", make_ellipsoid_volume({r, r, r}, s, 2 * s, Vec3(r - 0.0005, 0, 0)),
      tissue(20.0));
  add_contact_pair(model, a, b);
  std::vector<int> held;
  for (int i = 0; i < model.node_count(); ++i)
    if (std::abs(model.rest_position[i].x()) > 1.8 * r) held.push_back(i);
  add_fixed_nodes(model, held);
  model.damping = 5.0;
  finalize(model);
  Simulator sim(model);
  time_steps(state, sim, 20);
}
BENCHMARK(BM_TwoOrgansStep)->Arg(3)->Arg(4)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

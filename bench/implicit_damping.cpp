// Numerical damping of the implicit steps (docs/implicit.md): the example hanging cube and
// balloon without their physical damping, run by velocity Verlet and by backward Euler at
// several steps and iteration caps; prints CSV rows (scene, scheme, dt_s, cap, time_s,
// energy_J, iterations) of the mechanical energy (kinetic + shape memory + gravity's
// potential from rest) every 5 ms. Plot: scripts/plot_implicit_damping.py.
// Run: build/bench/phymul_implicit_damping examples > /tmp/damping.csv
#include <cstdio>
#include <filesystem>
#include <string>

#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "solver/implicit_step.hpp"

namespace {

using namespace phymul;

double mechanical_energy(const Model& model, const Data& d) {
  double e = kinetic_energy(model, d) + d.shape_memory_energy;
  for (int i = 0; i < model.node_count(); ++i)
    e -= model.mass[size_t(i)] * model.gravity.dot(d.x[size_t(i)] - model.rest_position[size_t(i)]);
  return e;
}

// dt_factor: times the explicit dt the scene's `dt: auto` picks; cap: implicit iterations.
void run(const std::filesystem::path& file, const char* scene_name, Integrator integrator,
         double dt_factor, int cap) {
  Scene scene = load_scene(file);
  scene.simulation.damping = 0.0;
  scene.simulation.integrator = integrator;
  scene.simulation.implicit_iterations = cap;
  scene.simulation.implicit_tolerance = 1e-9;
  Simulator sim(compile_scene(scene));
  sim.set_dt(dt_factor * sim.dt());
  const double end = scene.simulation.duration;
  double next = 0.0;
  const bool implicit = integrator == Integrator::implicit;
  while (sim.data().time < end) {
    if (sim.data().time >= next - 1e-12) {
      std::printf("%s,%s,%.6g,%d,%.6g,%.9g,%d\n", scene_name, implicit ? "implicit" : "verlet",
                  sim.dt(), implicit ? cap : 0, sim.data().time,
                  mechanical_energy(sim.model(), sim.data()),
                  implicit ? implicit_iterations(sim.data()) : 0);
      next += 5e-3;
    }
    sim.step();
  }
}

}  // namespace

int main(int argc, char** argv) {
  const std::filesystem::path examples = argc > 1 ? argv[1] : "examples";
  std::printf("scene,scheme,dt_s,cap,time_s,energy_J,iterations\n");
  for (const char* name : {"hanging_cube", "balloon"}) {
    const auto file = examples / (std::string(name) + ".yaml");
    run(file, name, Integrator::verlet, 1.0, 0);
    for (double factor : {1.0, 10.0, 100.0}) run(file, name, Integrator::implicit, factor, 1000);
    for (int cap : {2, 5}) run(file, name, Integrator::implicit, 10.0, cap);
  }
}

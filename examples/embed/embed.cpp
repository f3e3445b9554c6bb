// Runs a scene through phymul's library and prints the final positions: load, compile,
// step, read. usage: embed scene.yaml
#include <cmath>
#include <cstdio>
#include <exception>

#include "phymul/phymul.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s scene.yaml\n", argv[0]);
    return 2;
  }
  try {
    const phymul::Scene scene = phymul::load_scene(argv[1]);   // checked, errors located
    const phymul::Model model = phymul::compile_scene(scene);  // read-only from here on
    phymul::Data data = phymul::make_data(model);              // what a run changes
    // Whole steps up to the scene's duration, as `phymul run` takes them.
    const double duration = model.settings.duration;
    const long steps = std::lround(std::ceil(duration / data.dt - 1e-9));
    data.dt = duration / double(steps);
    for (long k = 0; k < steps; ++k) phymul::step(model, data);
    std::printf("t = %.17g s after %ld steps\n", data.time, steps);
    for (const phymul::Vec3& x : data.x) std::printf("%.17g %.17g %.17g\n", x.x(), x.y(), x.z());
  } catch (const std::exception& e) {  // SceneError lists every problem with its line
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}

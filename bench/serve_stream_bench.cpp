// The live view's streaming cost: `phymul serve` on the prostate scene in real time, one
// thread stepping, watched by no client and then by one (60 frames a second). The CPU time of
// the server's two threads (the stepping thread, named phymul-sim, and the network thread)
// in each phase gives what one client costs, as a share of one core and of the stepping.
// usage: phymul_serve_bench PHYMUL SCENE [SECONDS] > results_serve.json
#include <cstdio>
#include <cstdlib>

#include "serve/serve_client.hpp"

using namespace phymul::testing;

namespace {

struct Phase {
  double sim_cpu = 0, network_cpu = 0, wall = 0, simulated = 0;
  long frames = 0;
};

// CPU seconds of both threads over `seconds`; with a viewer, its frames and the time simulated.
Phase measure(const ServerProcess& server, Client* viewer, double seconds) {
  const double t0 = viewer ? viewer->state()["time"].get<double>() : 0.0;
  const double sim0 = server.thread_cpu_seconds("phymul-sim"),
               net0 = server.thread_cpu_seconds("phymul");
  const long f0 = viewer ? viewer->frames() : 0;
  const auto start = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  Phase p;
  p.simulated = viewer ? viewer->state()["time"].get<double>() - t0 : 0.0;
  p.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  p.sim_cpu = server.thread_cpu_seconds("phymul-sim") - sim0;
  p.network_cpu = server.thread_cpu_seconds("phymul") - net0;
  p.frames = viewer ? viewer->frames() - f0 : 0;
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s PHYMUL SCENE [SECONDS]\n", argv[0]);
    return 2;
  }
  setenv("PHYMUL_CLI", argv[1], 1);
  const double seconds = argc > 3 ? std::atof(argv[3]) : 20.0;
  ServerProcess server({argv[2], "--port", "0", "--threads", "1"});
  std::this_thread::sleep_for(std::chrono::seconds(2));
  // No client: the stepping alone (no frame is published for nobody).
  const Phase alone = measure(server, nullptr, seconds);
  Client viewer;
  if (!viewer.connect(server.port()).empty()) return 1;
  std::this_thread::sleep_for(std::chrono::seconds(1));
  // One client: the stepping thread publishes 60 frames a second, the network thread encodes
  // and sends them (and status ten times a second).
  const Phase watched = measure(server, &viewer, seconds);
  const double stepping = alone.sim_cpu / alone.wall;  // share of a core
  const double streaming = (watched.sim_cpu + watched.network_cpu) / watched.wall -
                           (alone.sim_cpu + alone.network_cpu) / alone.wall;
  std::printf(
      "{\n  \"scene\": \"%s\",\n  \"seconds_per_phase\": %.1f,\n"
      "  \"real_time_factor\": %.4f,\n"
      "  \"stepping_share_of_a_core\": %.4f,\n"
      "  \"stepping_share_of_a_core_one_client\": %.4f,\n"
      "  \"network_thread_share_of_a_core_no_client\": %.5f,\n"
      "  \"network_thread_share_of_a_core_one_client\": %.5f,\n"
      "  \"frames_per_second_to_the_client\": %.1f,\n"
      "  \"one_client_share_of_a_core\": %.5f,\n"
      "  \"one_client_share_of_the_stepping\": %.5f\n}\n",
      argv[2], seconds, watched.simulated / watched.wall, stepping, watched.sim_cpu / watched.wall,
      alone.network_cpu / alone.wall, watched.network_cpu / watched.wall,
      double(watched.frames) / watched.wall, streaming, streaming / stepping);
  return 0;
}

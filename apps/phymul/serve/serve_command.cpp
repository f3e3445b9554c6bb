// `phymul serve SCENE`: the live view. The scene steps on its own thread; the page and the
// stream are served from this one.
#include <fmt/format.h>
#include <omp.h>

#include <iostream>
#include <memory>
#include <regex>

#include "../commands.hpp"
#include "live_server.hpp"
#include "live_simulation.hpp"
#include "phymul/model.hpp"
#include "phymul/scene_io.hpp"

namespace phymul::cli {
namespace {

struct Settings {
  std::string scene, host = "127.0.0.1", token, pace = "realtime";
  int port = 8080, threads = 0;
  bool paused = false;
};

bool loopback(const std::string& host) {
  return host == "127.0.0.1" || host == "localhost" || host == "::1";
}

int serve(const Settings& s) {
  if (!loopback(s.host) && s.token.empty()) {
    std::cerr << fmt::format(
        "error: serve: --host {} lets other machines connect: give --token SECRET too (8 or "
        "more letters, digits, '-' or '_'), and open http://{}:{}/?token=SECRET\n",
        s.host, s.host, s.port);
    return 1;
  }
  if (!s.token.empty() && !std::regex_match(s.token, std::regex("[A-Za-z0-9_-]{8,256}"))) {
    std::cerr << "error: serve: --token must be 8 to 256 letters, digits, '-' or '_'\n";
    return 1;
  }
  if (s.threads > 0) omp_set_num_threads(s.threads);
  try {
    const Scene scene = load_scene(s.scene);
    if (scene.simulation.mode != SolveMode::dynamic) {
      std::cerr << fmt::format(
          "error: serve: {} is a static scene (simulation.mode: static); the live view steps "
          "dynamics: set mode: dynamic, or use phymul run\n",
          s.scene);
      return 1;
    }
    serve::LiveSimulation sim(compile_scene(scene), s.paused,
                              s.pace == "fast" ? serve::Pace::fast : serve::Pace::realtime);
    serve::LiveServer server(sim, {s.host, s.port, s.token}, serve::load_web_assets());
    const int port = server.listen();
    const std::string shown = s.host.find(':') != std::string::npos ? "[" + s.host + "]" : s.host;
    std::cout << fmt::format(
                     "phymul serve: {}: {} nodes, dt {:.3g} s; open http://{}:{}/{} "
                     "(Ctrl-C stops)\n",
                     s.scene, sim.model().node_count(), sim.dt(), shown, port,
                     s.token.empty() ? "" : "?token=" + s.token)
              << std::flush;
    sim.start();
    server.run();
    sim.stop();
    std::cout << "phymul serve: stopped\n";
    return 0;
  } catch (const SceneError& e) {
    for (const auto& d : e.diagnostics()) std::cerr << d.str() << '\n';
    std::cerr << fmt::format("{} problem(s) found\n", e.diagnostics().size());
    return 1;
  } catch (const std::exception& e) {  // a port taken, a host that does not resolve
    std::cerr << "error: serve: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

Command add_serve_command(CLI::App& parent) {
  auto s = std::make_shared<Settings>();
  CLI::App* app = parent.add_subcommand(
      "serve", "watch and steer a simulation in the browser (a page over HTTP, a WebSocket)");
  app->add_option("scene", s->scene, "scene file (YAML)")->required();
  app->add_option("--port", s->port, "TCP port (0: any free one, printed)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  app->add_option("--host", s->host,
                  "address to listen on; any but 127.0.0.1, localhost or ::1 needs --token")
      ->capture_default_str();
  app->add_option("--token", s->token,
                  "secret every client must give (the page's URL ?token=...), 8+ characters");
  app->add_flag("--paused", s->paused, "start paused (the page's play button starts it)");
  app->add_option("--pace", s->pace,
                  "realtime: simulated time follows the clock; fast: as "
                  "fast as it can")
      ->capture_default_str()
      ->check(CLI::IsMember({"realtime", "fast"}));
  app->add_option("--threads", s->threads,
                  "OpenMP threads of the steps (default: OMP_NUM_THREADS, "
                  "else every core)")
      ->check(CLI::Range(1, 1024));
  return {app, [s] { return serve(*s); }};
}

}  // namespace phymul::cli

// phymul serve under load: 20 clients watching the prostate scene for 30 s on 127.0.0.1. The
// simulation runs as fast as it can (--pace fast), so any time the streaming took from it
// would show in its speed; the server's memory must stay flat.
#include <gtest/gtest.h>

#include <memory>

#include "serve_client.hpp"

namespace phymul::testing {
namespace {

using Clock = std::chrono::steady_clock;

// Simulated seconds per wall-clock second over `wall`, read by a client's state requests.
double real_time_factor(Client& probe, std::chrono::milliseconds wall) {
  const json a = probe.state();
  const auto start = Clock::now();
  std::this_thread::sleep_for(wall);
  const json b = probe.state();
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return (b["time"].get<double>() - a["time"].get<double>()) / seconds;
}

TEST(ServeLoad, TwentyClientsForThirtySecondsLeaveTheSimulationsSpeedAndMemoryAlone) {
  ServerProcess server({scene_path("examples/prostate/50mL_rigid.yaml"), "--port", "0", "--threads",
                        "1", "--pace", "fast"});
  Client probe;
  ASSERT_EQ(probe.connect(server.port()), "");
  std::this_thread::sleep_for(1s);
  const double before = real_time_factor(probe, 5s);

  std::vector<std::unique_ptr<Client>> clients;
  for (int k = 0; k < 20; ++k) {
    clients.push_back(std::make_unique<Client>());
    ASSERT_EQ(clients.back()->connect(server.port()), "");
  }
  std::this_thread::sleep_for(3s);  // connections and their buffers set up
  const long memory_start = server.rss_kib();
  const double loaded = real_time_factor(probe, 27s);
  const long memory_end = server.rss_kib();
  long fewest = clients[0]->frames();
  for (const auto& c : clients) fewest = std::min(fewest, c->frames());
  clients.clear();
  const double after = real_time_factor(probe, 5s);

  const double alone = 0.5 * (before + after);
  std::printf(
      "real-time factor: %.4f alone (%.4f before, %.4f after), %.4f with 20 clients "
      "(%+.1f %%); server memory %ld -> %ld KiB; fewest frames a client got in 30 s: "
      "%ld\n",
      alone, before, after, loaded, 100 * (loaded / alone - 1), memory_start, memory_end, fewest);
  EXPECT_LT(std::abs(loaded / alone - 1), 0.10);
  EXPECT_LT(memory_end - memory_start, 2048);  // KiB
  EXPECT_GT(fewest, 30 * 20);                  // every client saw at least 20 frames a second
}

}  // namespace
}  // namespace phymul::testing

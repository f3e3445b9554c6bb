// phymul serve under load (these tests run alone: they measure speeds): 20 clients watching
// the prostate scene for 30 s on 127.0.0.1, and a client that stops reading. The simulation
// keeps its speed, the server its memory.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>

#include "serve_client.hpp"

namespace phymul::testing {
namespace {

using Clock = std::chrono::steady_clock;

// The simulation's speed over a window of wall-clock time: simulated seconds per wall-clock
// second (the real-time factor) and per CPU second of its own thread, and the share of a core
// that thread got.
struct Speed {
  double real_time_factor = 0.0, per_cpu_second = 0.0, core_share = 0.0;
};

Speed measure(const ServerProcess& server, Client& probe, std::chrono::milliseconds wall) {
  const double t0 = probe.state()["time"], cpu0 = server.thread_cpu_seconds("phymul-sim");
  const auto start = Clock::now();
  std::this_thread::sleep_for(wall);
  const double t1 = probe.state()["time"], cpu1 = server.thread_cpu_seconds("phymul-sim");
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return {(t1 - t0) / seconds, (t1 - t0) / (cpu1 - cpu0), (cpu1 - cpu0) / seconds};
}

TEST(ServeLoad, TwentyClientsForThirtySecondsLeaveTheSimulationsSpeedAndMemoryAlone) {
  ServerProcess server({scene_path("examples/prostate/50mL_rigid.yaml"), "--port", "0", "--threads",
                        "1", "--pace", "fast"});
  Client probe;
  ASSERT_EQ(probe.connect(server.port()), "");
  std::this_thread::sleep_for(1s);
  ASSERT_GT(server.thread_cpu_seconds("phymul-sim"), 0.0);
  const Speed before = measure(server, probe, 5s);

  std::vector<std::unique_ptr<Client>> clients;
  for (int k = 0; k < 20; ++k) {
    clients.push_back(std::make_unique<Client>());
    ASSERT_EQ(clients.back()->connect(server.port()), "");
  }
  std::this_thread::sleep_for(3s);  // connections and their buffers set up
  const long memory_start = server.rss_kib();
  const Speed loaded = measure(server, probe, 27s);
  const long memory_end = server.rss_kib();
  long fewest = clients[0]->frames();
  for (const auto& c : clients) fewest = std::min(fewest, c->frames());
  clients.clear();
  const Speed after = measure(server, probe, 5s);

  const double alone = 0.5 * (before.real_time_factor + after.real_time_factor);
  const double alone_cpu = 0.5 * (before.per_cpu_second + after.per_cpu_second);
  std::printf(
      "real-time factor: %.4f alone (%.4f before, %.4f after), %.4f with 20 clients (%+.1f %%)\n"
      "per CPU second of the simulation thread: %.4f alone, %.4f with 20 clients (%+.1f %%)\n"
      "share of a core the simulation thread got: %.2f before, %.2f with clients, %.2f after\n"
      "server memory %ld -> %ld KiB over 27 s; fewest frames a client got: %ld\n",
      alone, before.real_time_factor, after.real_time_factor, loaded.real_time_factor,
      100 * (loaded.real_time_factor / alone - 1), alone_cpu, loaded.per_cpu_second,
      100 * (loaded.per_cpu_second / alone_cpu - 1), before.core_share, loaded.core_share,
      after.core_share, memory_start, memory_end, fewest);
  // The streaming costs the simulation's own thread nothing (no lock it waits on, no copy
  // beyond the snapshot's)...
  EXPECT_LT(std::abs(loaded.per_cpu_second / alone_cpu - 1), 0.10);
  // ...and, when nothing else wants the machine's cores, no wall-clock time either. On a
  // machine shared with other work the clock measures that work instead: said, not checked.
  if (std::min({before.core_share, loaded.core_share, after.core_share}) > 0.9)
    EXPECT_LT(std::abs(loaded.real_time_factor / alone - 1), 0.10);
  else
    std::printf(
        "*** NOT CHECKED: the real-time factor's change, with the simulation thread "
        "getting under 90 %% of a core (other processes busy on this machine)\n");
  EXPECT_LT(memory_end - memory_start, 2048);  // KiB
  EXPECT_GT(fewest, 27 * 20);                  // every client saw at least 20 frames a second
}

// A client that stops reading (its thread stalled, a 4 KiB socket buffer) for 12 s while
// another watches: the simulation keeps its pace, the other client its frame rate, the
// server its memory, and the stalled client, once it reads again, gets the latest frames,
// not all the ones it missed (the server keeps a few frames' worth in the kernel for it).
TEST(ServeLoad, AStalledClientSlowsNothingAndGetsTheLatestFramesAfter) {
  ServerProcess server(
      {scene_path("examples/prostate/50mL_rigid.yaml"), "--port", "0", "--threads", "1"});
  Client stalled, watching;
  stalled.set_receive_buffer(4096);
  ASSERT_EQ(stalled.connect(server.port()), "");
  ASSERT_EQ(watching.connect(server.port()), "");
  std::this_thread::sleep_for(1s);
  // The pace before (real time, or what a sanitized build manages).
  const double p0 = watching.state()["time"];
  std::this_thread::sleep_for(3s);
  const double pace_before = (watching.state()["time"].get<double>() - p0) / 3.0;
  const long memory_before = server.rss_kib();
  const long frames_before = watching.frames();
  const double t0 = watching.state()["time"];
  stalled.stall_at_next_frame(12s);
  const auto start = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(11s);
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double simulated = watching.state()["time"].get<double>() - t0;
  const double rate = double(watching.frames() - frames_before) / wall;
  const long memory_during = server.rss_kib();
  // The stall over, it reads what the kernel's buffers held (about 4 MiB) and then the latest.
  std::this_thread::sleep_for(3s);
  std::printf(
      "pace %.3f before, %.3f during the stall; the watching client got %.1f frames a second; "
      "frames: stalled %ld, watching %ld; server memory %ld -> %ld KiB\n",
      pace_before, simulated / wall, rate, stalled.frames(), watching.frames(), memory_before,
      memory_during);
  EXPECT_NEAR(simulated / wall / pace_before, 1.0, 0.15);
  EXPECT_GT(rate, 30.0);
  EXPECT_LT(memory_during - memory_before, 2048);
  EXPECT_LT(stalled.frames(), 0.8 * watching.frames());
  // What it shows now is the run now, not seconds old frames queued for it.
  const std::string frame = stalled.last_frame();
  double shown = 0;
  std::memcpy(&shown, frame.data() + 8, 8);
  EXPECT_LT(watching.state()["time"].get<double>() - shown, 0.5);
  EXPECT_EQ(stalled.close_code(), 0);
}

}  // namespace
}  // namespace phymul::testing

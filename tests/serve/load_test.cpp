// phymul serve under load (these tests run alone: they measure speeds): 20 clients watching
// the prostate scene for 30 s on 127.0.0.1, and a client that stops reading. The simulation
// keeps its speed, the server its memory.
#include <gtest/gtest.h>

#include <algorithm>
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

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Windows alone and with the 20 clients alternate, and their medians are compared: a drift of
// the machine or of the run weighs on both sides, and one odd window on neither (in CI the
// first window alone once ran at 1.85 against 2.25 and 2.28 in the later ones).
TEST(ServeLoad, TwentyClientsForThirtySecondsLeaveTheSimulationsSpeedAndMemoryAlone) {
  ServerProcess server({scene_path("examples/prostate/50mL_rigid.yaml"), "--port", "0", "--threads",
                        "1", "--pace", "fast"});
  Client probe;
  ASSERT_EQ(probe.connect(server.port()), "");
  std::this_thread::sleep_for(1s);
  ASSERT_GT(server.thread_cpu_seconds("phymul-sim"), 0.0);

  constexpr int kCycles = 3;
  std::vector<Speed> alone, loaded;
  long memory_start = 0, memory_end = 0, fewest = -1;
  for (int cycle = 0; cycle < kCycles; ++cycle) {
    alone.push_back(measure(server, probe, 4s));
    std::vector<std::unique_ptr<Client>> clients;
    for (int k = 0; k < 20; ++k) {
      clients.push_back(std::make_unique<Client>());
      ASSERT_EQ(clients.back()->connect(server.port()), "");
    }
    std::this_thread::sleep_for(1s);  // connections and their buffers set up
    if (cycle == 0) memory_start = server.rss_kib();
    std::vector<long> frames0;
    for (const auto& c : clients) frames0.push_back(c->frames());
    loaded.push_back(measure(server, probe, 9s));
    memory_end = server.rss_kib();
    for (std::size_t k = 0; k < clients.size(); ++k) {
      const long got = clients[k]->frames() - frames0[k];
      fewest = fewest < 0 ? got : std::min(fewest, got);
    }
  }
  alone.push_back(measure(server, probe, 4s));

  const auto medians = [](const std::vector<Speed>& w, double Speed::*field) {
    std::vector<double> v;
    for (const Speed& s : w) v.push_back(s.*field);
    return median(v);
  };
  const double rtf_alone = medians(alone, &Speed::real_time_factor);
  const double rtf_loaded = medians(loaded, &Speed::real_time_factor);
  const double cpu_alone = medians(alone, &Speed::per_cpu_second);
  const double cpu_loaded = medians(loaded, &Speed::per_cpu_second);
  double least_share = 1.0;
  std::printf("windows (real-time factor, per CPU second, share of a core):\n");
  for (std::size_t k = 0; k < alone.size(); ++k) {
    for (const Speed* s : {&alone[k], k < loaded.size() ? &loaded[k] : nullptr}) {
      if (!s) continue;
      std::printf("  %-12s %.4f %.4f %.2f\n", s == &alone[k] ? "alone" : "20 clients",
                  s->real_time_factor, s->per_cpu_second, s->core_share);
      least_share = std::min(least_share, s->core_share);
    }
  }
  std::printf(
      "medians: real-time factor %.4f alone, %.4f with 20 clients (%+.1f %%); per CPU second of "
      "the simulation thread %.4f alone, %.4f with 20 clients (%+.1f %%)\n"
      "server memory %ld -> %ld KiB over %d connections of 20 clients; fewest frames a client "
      "got in 9 s: %ld\n",
      rtf_alone, rtf_loaded, 100 * (rtf_loaded / rtf_alone - 1), cpu_alone, cpu_loaded,
      100 * (cpu_loaded / cpu_alone - 1), memory_start, memory_end, kCycles, fewest);
  // The streaming costs the simulation's own thread nothing (no lock it waits on, no copy
  // beyond the snapshot's)...
  EXPECT_LT(std::abs(cpu_loaded / cpu_alone - 1), 0.10);
  // ...and, when nothing else wants the machine's cores, no wall-clock time either. On a
  // machine shared with other work the clock measures that work instead: said, not checked.
  if (least_share > 0.9)
    EXPECT_LT(std::abs(rtf_loaded / rtf_alone - 1), 0.10);
  else
    std::printf(
        "*** NOT CHECKED: the real-time factor's change, with the simulation thread "
        "getting under 90 %% of a core (other processes busy on this machine)\n");
  EXPECT_LT(memory_end - memory_start, 2048);  // KiB
  EXPECT_GT(fewest, 9 * 20);                   // every client saw at least 20 frames a second
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

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
  double seconds = 0.0;  // the window's wall-clock length
};

Speed measure(const ServerProcess& server, Client& probe, std::chrono::milliseconds wall) {
  const double t0 = probe.state()["time"], cpu0 = server.thread_cpu_seconds("phymul-sim");
  const auto start = Clock::now();
  std::this_thread::sleep_for(wall);
  const double t1 = probe.state()["time"], cpu1 = server.thread_cpu_seconds("phymul-sim");
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  return {(t1 - t0) / seconds, (t1 - t0) / (cpu1 - cpu0), (cpu1 - cpu0) / seconds, seconds};
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Short windows alone and with the 20 clients alternate, and each loaded window is compared with
// the mean of the windows alone on either side of it; the median of these ratios is asserted.
// A shared VM's speed drifts by +-8 % over tens of seconds: three long windows each way, even
// alternated, measured that drift (+10.5 % with the clients once in CI); a short window and
// its two neighbours, 5 s apart, see nearly the same machine.
struct Comparison {
  double real_time_factor = 0.0, per_cpu_second = 0.0;  // median ratio loaded / alone
};

Comparison compare(const std::vector<Speed>& alone, const std::vector<Speed>& loaded) {
  std::vector<double> rtf, cpu;
  for (std::size_t k = 0; k < loaded.size(); ++k) {
    const Speed &before = alone[k], &after = alone[k + 1], &with = loaded[k];
    rtf.push_back(2 * with.real_time_factor / (before.real_time_factor + after.real_time_factor));
    cpu.push_back(2 * with.per_cpu_second / (before.per_cpu_second + after.per_cpu_second));
  }
  return {median(rtf), median(cpu)};
}

TEST(ServeLoad, TwentyClientsForThirtySecondsLeaveTheSimulationsSpeedAndMemoryAlone) {
  ServerProcess server({scene_path("examples/prostate/50mL_rigid.yaml"), "--port", "0", "--threads",
                        "1", "--pace", "fast"});
  Client probe;
  ASSERT_EQ(probe.connect(server.port()), "");
  std::this_thread::sleep_for(1s);
  ASSERT_GT(server.thread_cpu_seconds("phymul-sim"), 0.0);

  // 12 cycles of 2.5 s with the clients (0.5 s to set up, 2 s measured): 30 s of 20 clients.
  constexpr int kCycles = 12;
  constexpr auto kWindow = 2s;
  std::vector<Speed> alone{measure(server, probe, kWindow)}, loaded;
  long memory_start = 0, memory_end = 0, fewest = -1;
  for (int cycle = 0; cycle < kCycles; ++cycle) {
    {
      std::vector<std::unique_ptr<Client>> clients;
      for (int k = 0; k < 20; ++k) {
        clients.push_back(std::make_unique<Client>());
        ASSERT_EQ(clients.back()->connect(server.port()), "");
      }
      std::this_thread::sleep_for(500ms);  // connections and their buffers set up
      if (cycle == 0) memory_start = server.rss_kib();
      std::vector<long> frames0;
      for (const auto& c : clients) frames0.push_back(c->frames());
      loaded.push_back(measure(server, probe, kWindow));
      memory_end = server.rss_kib();
      for (std::size_t k = 0; k < clients.size(); ++k) {
        const long got = clients[k]->frames() - frames0[k];
        fewest = fewest < 0 ? got : std::min(fewest, got);
      }
    }  // the clients close
    std::this_thread::sleep_for(500ms);
    alone.push_back(measure(server, probe, kWindow));
  }

  const Comparison change = compare(alone, loaded);
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
      "median change with 20 clients against the windows alone around them: real-time factor "
      "%+.1f %%, simulated time per CPU second of the simulation thread %+.1f %%\n"
      "server memory %ld -> %ld KiB over %d connections of 20 clients; fewest frames a client "
      "got in 2 s: %ld\n",
      100 * (change.real_time_factor - 1), 100 * (change.per_cpu_second - 1), memory_start,
      memory_end, kCycles, fewest);
  // The streaming costs the simulation's own thread nothing (no lock it waits on, no copy
  // beyond the snapshot's)...
  EXPECT_LT(std::abs(change.per_cpu_second - 1), 0.10);
  // ...and, when nothing else wants the machine's cores, no wall-clock time either. On a
  // machine shared with other work the clock measures that work instead: said, not checked.
  if (least_share > 0.9)
    EXPECT_LT(std::abs(change.real_time_factor - 1), 0.10);
  else
    std::printf(
        "*** NOT CHECKED: the real-time factor's change, with the simulation thread "
        "getting under 90 %% of a core (other processes busy on this machine)\n");
  EXPECT_LT(memory_end - memory_start, 2048);  // KiB
  EXPECT_GT(fewest, 2 * 20);                   // every client saw at least 20 frames a second
}

// A client that stops reading (its thread stalled, a 4 KiB socket buffer) for 12 s while
// another watches: the simulation keeps its pace, the other client its frame rate, the
// server its memory, and the stalled client, once it reads again, gets the latest frames,
// not all the ones it missed (the server keeps a few frames' worth in the kernel for it).
// The stall's window is compared with the mean of windows before and after it, in simulated
// time per CPU second of the simulation thread (what the server could take from it) and per
// wall-clock second where that thread has its core (a VM's speed drifts; see above).
TEST(ServeLoad, AStalledClientSlowsNothingAndGetsTheLatestFramesAfter) {
  ServerProcess server(
      {scene_path("examples/prostate/50mL_rigid.yaml"), "--port", "0", "--threads", "1"});
  Client stalled, watching;
  stalled.set_receive_buffer(4096);
  ASSERT_EQ(stalled.connect(server.port()), "");
  ASSERT_EQ(watching.connect(server.port()), "");
  std::this_thread::sleep_for(1s);
  // The pace before (real time, or what a sanitized build manages).
  const Speed before = measure(server, watching, 3s);
  const long memory_before = server.rss_kib();
  const long frames_before = watching.frames();
  stalled.stall_at_next_frame(12s);
  const Speed during = measure(server, watching, 11s);
  const double rate = double(watching.frames() - frames_before) / during.seconds;
  const long memory_during = server.rss_kib();
  // The stall over, it reads what the kernel's buffers held (about 4 MiB) and then the latest.
  std::this_thread::sleep_for(1500ms);
  const Speed after = measure(server, watching, 1500ms);
  const double cpu_change =
                   2 * during.per_cpu_second / (before.per_cpu_second + after.per_cpu_second),
               pace_change =
                   2 * during.real_time_factor / (before.real_time_factor + after.real_time_factor);
  std::printf(
      "pace (real-time factor, per CPU second, share of a core): before %.3f %.3f %.2f, during "
      "the stall %.3f %.3f %.2f, after %.3f %.3f %.2f; the watching client got %.1f frames a "
      "second; frames: stalled %ld, watching %ld; server memory %ld -> %ld KiB\n",
      before.real_time_factor, before.per_cpu_second, before.core_share, during.real_time_factor,
      during.per_cpu_second, during.core_share, after.real_time_factor, after.per_cpu_second,
      after.core_share, rate, stalled.frames(), watching.frames(), memory_before, memory_during);
  EXPECT_NEAR(cpu_change, 1.0, 0.15);
  // Paced to real time, or flat out with its core: the clock measures the server.
  if (before.real_time_factor > 0.95 || during.core_share > 0.9)
    EXPECT_NEAR(pace_change, 1.0, 0.15);
  else
    std::printf(
        "*** NOT CHECKED: the real-time factor's change, with the simulation thread "
        "getting under 90 %% of a core (other processes busy on this machine)\n");
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

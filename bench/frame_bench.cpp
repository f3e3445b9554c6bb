// What one frame of a run costs (ResultWriter::frame: the body's .vtu, the probe's surface
// .vtu and both .pvd series rewritten) on the prostate study's 50 mL rigid-probe scene, with
// the frames as text and as binary (output.format). A writer lists 41 frames, as the scene's
// one-second run does, then starts over, so the .pvd grows as in that run.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>

#include "phymul/results.hpp"
#include "phymul/scene_io.hpp"
#include "phymul/simulation.hpp"
#include "phymul/studies/prostate.hpp"

namespace {

using namespace phymul;

void BM_Frame(benchmark::State& state) {
  const VtuEncoding encoding = state.range(0) == 0 ? VtuEncoding::ascii : VtuEncoding::binary;
  const prostate::Options options;
  const prostate::SceneSettings scene =
      prostate::dynamic_scene(options, 50e-6, prostate::Probe::rigid);
  Simulator sim(compile_scene(parse_scene(prostate::scene_text(options, scene), "bench.yaml")));
  while (sim.data().time < 0.3) sim.step();  // the probe pushing: every field non-zero
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("phymul_frame_bench_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  constexpr int kFramesPerRun = 41;
  std::unique_ptr<ResultWriter> writer;
  long frames = 0;
  for (auto _ : state) {
    if (frames % kFramesPerRun == 0) {
      state.PauseTiming();
      writer = std::make_unique<ResultWriter>(dir, "frame", sim.model(), true, encoding);
      state.ResumeTiming();
    }
    writer->frame(sim);
    ++frames;
  }
  const auto bytes = std::filesystem::file_size(dir / "frame_000000.vtu") +
                     std::filesystem::file_size(dir / "frame_obstacles_000000.vtu");
  writer.reset();
  std::filesystem::remove_all(dir);
  state.counters["frame_bytes"] = double(bytes);
  state.counters["nodes"] = sim.model().node_count();
}
BENCHMARK(BM_Frame)->Arg(0)->Arg(1)->ArgName("binary")->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();

// Resident memory of a shape-memory model in a run: the step benchmark's pushed cube,
// built and stepped in a fresh process so that nothing else is counted. Prints one JSON
// object; `make bench` stores it in bench/memory.json.
#include <fmt/format.h>
#include <sys/resource.h>

#include <cstdlib>
#include <fstream>
#include <string>

#include "cube.hpp"

namespace {

long status_kib(const std::string& field) {  // from /proc/self/status, KiB
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(field + ":", 0) == 0) return std::atol(line.c_str() + field.size() + 1);
  return -1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace phymul;
  const int n = argc > 1 ? std::atoi(argv[1]) : 40;
  if (n < 1 || n > 200) {
    fmt::print(stderr, "phymul_memory: cells per edge must be in [1, 200] (got '{}')\n",
               argc > 1 ? argv[1] : "");
    return 1;
  }
  const long baseline = status_kib("VmRSS");
  Model model = bench::pushed_cube(n);
  const double nodes = model.node_count();
  Simulator sim(std::move(model));
  for (int k = 0; k < 10; ++k) sim.step();
  const long running = status_kib("VmRSS"), peak = status_kib("VmHWM");
  fmt::print(
      "{{\"cells\": {}, \"nodes\": {}, \"baseline_rss_kib\": {}, \"running_rss_kib\": {}, "
      "\"peak_rss_kib\": {}, \"running_bytes_per_node\": {:.0f}, \"peak_bytes_per_node\": "
      "{:.0f}}}\n",
      n, nodes, baseline, running, peak, (running - baseline) * 1024.0 / nodes,
      (peak - baseline) * 1024.0 / nodes);
}

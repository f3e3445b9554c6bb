#include "model/parallel_plan.hpp"

#include <algorithm>
#include <cstdint>
#include <set>

namespace phymul {
namespace {

// Few enough blocks that a colour holds several per thread on large models, enough that
// small ones still split; fixed by the model, never by the thread count.
int block_count(int items) { return std::clamp(items / 256, 1, 64); }

}  // namespace

ParallelPlan plan_blocks(int items,
                         const std::function<void(int, const std::function<void(int)>&)>& writes) {
  ParallelPlan plan;
  const int blocks = block_count(items);
  plan.block_start.assign(size_t(blocks) + 1, 0);
  for (int b = 0; b <= blocks; ++b) plan.block_start[b] = int(int64_t(items) * b / blocks);

  // Which blocks write each node; any two of them conflict.
  std::vector<std::vector<int>> writers;
  for (int b = 0; b < blocks; ++b)
    for (int item = plan.block_start[b]; item < plan.block_start[b + 1]; ++item)
      writes(item, [&](int node) {
        if (node >= int(writers.size())) writers.resize(size_t(node) + 1);
        if (writers[node].empty() || writers[node].back() != b) writers[node].push_back(b);
      });
  std::vector<std::set<int>> conflicts(static_cast<size_t>(blocks));
  for (const std::vector<int>& w : writers)
    for (size_t a = 0; a < w.size(); ++a)
      for (size_t c = a + 1; c < w.size(); ++c) {
        conflicts[w[a]].insert(w[c]);
        conflicts[w[c]].insert(w[a]);
      }

  // Greedy colouring in block order: deterministic.
  std::vector<int> colour(size_t(blocks), -1);
  int colours = 0;
  for (int b = 0; b < blocks; ++b) {
    std::vector<bool> taken(size_t(colours) + 1, false);
    for (int c : conflicts[b])
      if (colour[c] >= 0) taken[colour[c]] = true;
    colour[b] = int(std::find(taken.begin(), taken.end(), false) - taken.begin());
    colours = std::max(colours, colour[b] + 1);
  }
  plan.colour_start.assign(size_t(colours) + 1, 0);
  for (int c = 0; c < colours; ++c) {
    for (int b = 0; b < blocks; ++b)
      if (colour[b] == c) plan.colour_blocks.push_back(b);
    plan.colour_start[c + 1] = int(plan.colour_blocks.size());
  }
  return plan;
}

}  // namespace phymul

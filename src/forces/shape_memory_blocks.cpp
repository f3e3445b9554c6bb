#include <algorithm>
#include <set>

#include "forces/shape_memory.hpp"

namespace phymul {
namespace {

// Few enough blocks that a colour holds several of them per thread on the large grids,
// enough that small models still split; fixed by the model, never by the thread count.
int block_count(int memory_nodes) { return std::clamp(memory_nodes / 256, 1, 64); }

// Every global node that the force pass of memory node k writes: the node and its neighbours.
template <class Visit>
void for_each_written(const ShapeMemory& m, int k, Visit&& visit) {
  visit(m.nodes[k]);
  for (int j : m.neighbours.row(k)) visit(j);
}

}  // namespace

void plan_blocks(ShapeMemory& m) {
  const int count = int(m.nodes.size());
  const int blocks = block_count(count);
  m.block_start.assign(size_t(blocks) + 1, 0);
  for (int b = 0; b <= blocks; ++b) m.block_start[b] = int(int64_t(count) * b / blocks);

  // Which blocks write each node; any two of them conflict.
  int highest = 0;
  for (int k = 0; k < count; ++k)
    for_each_written(m, k, [&](int i) { highest = std::max(highest, i); });
  std::vector<std::vector<int>> writers(size_t(highest) + 1);
  for (int b = 0; b < blocks; ++b)
    for (int k = m.block_start[b]; k < m.block_start[b + 1]; ++k)
      for_each_written(m, k, [&](int i) {
        if (writers[i].empty() || writers[i].back() != b) writers[i].push_back(b);
      });
  std::vector<std::set<int>> conflicts(static_cast<size_t>(blocks));
  for (const std::vector<int>& w : writers)
    for (size_t a = 0; a < w.size(); ++a)
      for (size_t c = a + 1; c < w.size(); ++c)
        conflicts[w[a]].insert(w[c]), conflicts[w[c]].insert(w[a]);

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
  m.colour_start.assign(size_t(colours) + 1, 0);
  m.colour_blocks.clear();
  for (int c = 0; c < colours; ++c) {
    for (int b = 0; b < blocks; ++b)
      if (colour[b] == c) m.colour_blocks.push_back(b);
    m.colour_start[c + 1] = int(m.colour_blocks.size());
  }
  m.block_energy.assign(size_t(blocks), 0.0);
}

}  // namespace phymul

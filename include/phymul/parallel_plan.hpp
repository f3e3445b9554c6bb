// Deterministic parallel scatter: items (memory nodes, elements) that add into the forces of
// several nodes are cut into contiguous blocks, and the blocks coloured so that blocks of one
// colour write disjoint nodes. A colour runs in parallel; every nodal sum then keeps one
// order (colour, then item) whatever the number of threads.
#pragma once

#include <functional>
#include <vector>

#include "phymul/thread_team.hpp"

namespace phymul {

struct ParallelPlan {
  std::vector<int> block_start;              // item ranges, blocks + 1 entries
  std::vector<int> colour_start;             // ranges of colour_blocks, colours + 1 entries
  std::vector<int> colour_blocks;            // block ids, by colour
  mutable std::vector<double> block_energy;  // scratch of each pass, J per block
  int blocks() const { return int(block_start.size()) - 1; }
};

// writes(item, visit) calls visit(node) for every node the item adds into.
ParallelPlan plan_blocks(int items,
                         const std::function<void(int, const std::function<void(int)>&)>& writes);

// Runs block_work(b) (which returns the block's energy, J) over every block, colour by colour,
// the blocks of a colour in parallel; returns the energy summed in block order. A block's
// items are its own to order (the batched shape-memory kernel groups them).
template <class BlockWork>
double run_coloured_blocks(const ParallelPlan& plan, BlockWork&& block_work) {
  constexpr int kParallelFrom = 2048;  // items; below, a thread team costs more than it saves
  const int colours = int(plan.colour_start.size()) - 1;
  auto run = [&](int index) {
    const int b = plan.colour_blocks[index];
    plan.block_energy[b] = block_work(b);
  };
  if (team_pays(plan.block_start.back(), kParallelFrom)) {
#pragma omp parallel
    for (int c = 0; c < colours; ++c) {
#pragma omp for schedule(static)
      for (int index = plan.colour_start[c]; index < plan.colour_start[c + 1]; ++index) run(index);
    }
  } else {
    for (int index = 0; index < plan.colour_start.back(); ++index) run(index);
  }
  double energy = 0.0;
  for (double e : plan.block_energy) energy += e;
  return energy;
}

// Runs work(item) (which returns the item's energy, J) over every item, in item order within
// each block.
template <class Work>
double run_coloured(const ParallelPlan& plan, Work&& work) {
  return run_coloured_blocks(plan, [&](int b) {
    double energy = 0.0;
    for (int item = plan.block_start[b]; item < plan.block_start[b + 1]; ++item)
      energy += work(item);
    return energy;
  });
}

}  // namespace phymul

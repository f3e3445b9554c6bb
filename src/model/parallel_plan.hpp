// ParallelPlan (model.hpp) made and run: the blocks and colours of a model's scatter, and a
// pass over them, colour by colour, the blocks of a colour in parallel.
#pragma once

#include <functional>
#include <span>
#include <vector>

#include "model/thread_team.hpp"
#include "phymul/model.hpp"

namespace phymul {

// writes(item, visit) calls visit(node) for every node the item adds into.
ParallelPlan plan_blocks(int items,
                         const std::function<void(int, const std::function<void(int)>&)>& writes);

// Runs block_work(b) (which returns the block's energy, J) over every block, colour by colour,
// the blocks of a colour in parallel, each energy into block_energy[b] (plan.blocks() long);
// returns the energy summed in block order. A block's items are its own to order (the
// batched shape-memory kernel groups them).
template <class BlockWork>
double run_coloured_blocks(const ParallelPlan& plan, std::span<double> block_energy,
                           BlockWork&& block_work) {
  constexpr int kParallelFrom = 2048;  // items; below, a thread team costs more than it saves
  const int colours = int(plan.colour_start.size()) - 1;
  auto run = [&](int index) {
    const int b = plan.colour_blocks[index];
    block_energy[size_t(b)] = block_work(b);
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
  for (double e : block_energy) energy += e;
  return energy;
}

// Runs work(item) (which returns the item's energy, J) over every item, in item order within
// each block.
template <class Work>
double run_coloured(const ParallelPlan& plan, std::span<double> block_energy, Work&& work) {
  return run_coloured_blocks(plan, block_energy, [&](int b) {
    double energy = 0.0;
    for (int item = plan.block_start[b]; item < plan.block_start[b + 1]; ++item)
      energy += work(item);
    return energy;
  });
}

}  // namespace phymul

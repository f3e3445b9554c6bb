// Making a RowSubset (model.hpp) from a membership flag per row.
#pragma once

#include <span>

#include "phymul/model.hpp"

namespace phymul {

// member[k] != 0: row k is in the subset.
inline RowSubset make_row_subset(std::span<const char> member) {
  RowSubset s;
  s.bits.assign((member.size() + 63) / 64, 0);
  s.before.assign(s.bits.size(), 0);
  int count = 0;
  for (size_t k = 0; k < member.size(); ++k) {
    if (k % 64 == 0) s.before[k / 64] = count;
    if (!member[k]) continue;
    s.bits[k / 64] |= std::uint64_t(1) << (k % 64);
    ++count;
  }
  return s;
}

}  // namespace phymul

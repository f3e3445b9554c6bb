// A subset of the rows 0..n-1 of some per-row data, with membership and rank in O(1): one bit
// a row and a count every 64 rows. Data that only some rows have (the normal pairs of flat
// neighbourhoods, say) is then stored for those rows alone, at 1.5 bits a row for the rest.
#pragma once

#include <bit>
#include <cassert>
#include <cstdint>
#include <span>
#include <vector>

namespace phymul {

struct RowSubset {
  std::vector<std::uint64_t> bits;  // bit k % 64 of word k / 64: row k is a member
  std::vector<int> before;          // per word: members in the words before it

  // Position of row k among the members (in row order), or -1 when it is not one.
  int find(int k) const {
    assert(k >= 0 && size_t(k) < 64 * bits.size());
    const std::uint64_t word = bits[size_t(k) >> 6], bit = std::uint64_t(1) << (k & 63);
    if (!(word & bit)) return -1;
    return before[size_t(k) >> 6] + std::popcount(word & (bit - 1));
  }
};

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

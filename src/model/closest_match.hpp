// Did-you-mean: the known name closest to a misspelt one (scene keys, choices, node sets,
// object names).
#pragma once

#include <optional>
#include <span>
#include <string_view>

namespace phymul {

// Damerau-Levenshtein (optimal string alignment) distance.
int edit_distance(std::string_view a, std::string_view b);
// The candidate closest to `word` (case aside) when it is close enough to be a likely typo.
std::optional<std::string_view> closest_match(std::string_view word,
                                              std::span<const std::string_view> candidates);

}  // namespace phymul

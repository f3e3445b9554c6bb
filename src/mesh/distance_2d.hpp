// Signed Euclidean distance of a binary image's pixels to its boundary (exact, in the
// pixels' own lengths): the slices of a label image, to be interpolated between them.
#pragma once

#include <vector>

namespace phymul::detail {

// `inside` (na x nb, a fastest) as 0/1; spacing (sa, sb) along a and b. Returns, per pixel,
// the distance to the boundary between inside and outside pixels, taken halfway between
// their centres: negative inside, positive outside, clamped to [-limit, limit]. An image
// without inside pixels is `limit` everywhere.
std::vector<float> signed_distance_2d(const std::vector<unsigned char>& inside, int na, int nb,
                                      double sa, double sb, double limit);

}  // namespace phymul::detail

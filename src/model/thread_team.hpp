// Loops that open an OpenMP thread team only where it pays: enough items and more than one
// thread to give them. A team of one costs the runtime's set-up all the same, and GCC's libgomp
// allocates such a team on the heap every time it opens one (a step must not allocate:
// tests/solver/allocation_test.cpp), which an `if` clause does not avoid.
#pragma once

#ifdef _OPENMP
#include <omp.h>
#endif

namespace phymul {

inline bool team_pays(long items, long from) {
#ifdef _OPENMP
  return items >= from && omp_get_max_threads() > 1;
#else
  (void)items, (void)from;
  return false;
#endif
}

// body(i) for i in [0, count): split over a thread team when `team`, else in this thread.
template <class Body>
void for_each_index(int count, bool team, Body&& body) {
  if (team) {
#pragma omp parallel for schedule(static) firstprivate(body)
    for (int i = 0; i < count; ++i) body(i);
  } else {
    auto here = body;  // as for_each_lane's
    for (int i = 0; i < count; ++i) here(i);
  }
}

// The same in vector lanes either way: the iterations must be independent.
template <class Body>
void for_each_lane(int count, bool team, Body&& body) {
  if (team) {  // each thread its own copy, for the same reason as below
#pragma omp parallel for simd schedule(static) firstprivate(body)
    for (int i = 0; i < count; ++i) body(i);
  } else {
    // A copy whose address does not escape to the team's data: its captures stay in
    // registers, and the loop in the lanes.
    auto here = body;
#pragma omp simd
    for (int i = 0; i < count; ++i) here(i);
  }
}

}  // namespace phymul

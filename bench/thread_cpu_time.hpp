// The calling thread's CPU time, beside a benchmark's wall time: what a step costs on one core
// when a busy machine shares it (wall time then counts the waits too).
#pragma once

#include <time.h>

inline double thread_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

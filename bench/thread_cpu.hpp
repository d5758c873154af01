#pragma once
// CPU time of the calling thread, the clock of every per-plan timing in the
// benchmarks: the planners are single-threaded, and on a shared machine wall
// time would also count the other processes.
#include <time.h>

inline double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

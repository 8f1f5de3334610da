/* clock — seconds on a clock, for wall-time limits, flush intervals,
 * progress lines and figures: the one copy of the library, the programs
 * and the tests (header only, so that a program that links only the
 * shared library uses it too). Needs _POSIX_C_SOURCE >= 199309L. */
#ifndef CUP_UTIL_CLOCK_H
#define CUP_UTIL_CLOCK_H

#include <time.h>

/* Seconds on clock `which` (CLOCK_MONOTONIC, CLOCK_PROCESS_CPUTIME_ID,
 * CLOCK_THREAD_CPUTIME_ID): a system call of about a microsecond. */
static inline double clock_seconds(clockid_t which) {
  struct timespec ts;
  clock_gettime(which, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Monotonic seconds: differences are elapsed wall time. */
static inline double now_seconds(void) { return clock_seconds(CLOCK_MONOTONIC); }

/* Monotonic seconds to the kernel's tick (1-10 ms), for intervals of a
 * second or more checked very often: the run writer's flush interval,
 * asked at every sample (8 ns a call here against now_seconds' 50 ns, a
 * fifth of the precision rectifier's 2 ms run on its 10001 samples). */
static inline double tick_seconds(void) {
#ifdef CLOCK_MONOTONIC_COARSE
  return clock_seconds(CLOCK_MONOTONIC_COARSE);
#else
  return now_seconds();
#endif
}

#endif

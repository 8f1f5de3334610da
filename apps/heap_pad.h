/* heap_pad — the programs keep the heap memory they have touched.
 *
 * HDF5's file creation takes two 1 MiB buffers and frees them before the
 * run. glibc's malloc by default maps blocks of 128 KiB or more on their own
 * and unmaps them at free, and grows the heap 128 KiB at a time, so the
 * run's first allocations (each switch configuration's integrator, the
 * output buffers) fault in fresh pages: ~1.7 us each on the machine of
 * BENCHMARKS.md. With the heap grown 4 MiB at a time (M_TOP_PAD), those
 * buffers come from the heap and stay there when freed, and the run reuses
 * their pages: the full-bridge inverter's run (hmax = Ts/10, its own steps)
 * faulted 88 -> 23 times and took 0.78 -> 0.59 ms (medians of 21,
 * interleaved), the whole process 1940 -> 1758 faults. The library does
 * not touch the allocator (it is the process's); a program that links it
 * can do the same, or set GLIBC_TUNABLES=glibc.malloc.top_pad=4194304. */
#ifndef CATCHUP_APPS_HEAP_PAD_H
#define CATCHUP_APPS_HEAP_PAD_H

#ifdef __GLIBC__
#include <malloc.h>
#endif

static inline void heap_pad(void) {
#ifdef __GLIBC__
  (void)mallopt(M_TOP_PAD, 4 << 20);
#endif
}

#endif

/* heap — the one malloc interposer of the benchmarks and the tests (glibc:
 * malloc, calloc, realloc, free and the aligned allocations call glibc's own
 * entry points after the bookkeeping). Three modes, each off until asked:
 *
 *   peak   the most bytes held at once since cup_heapcount_reset, above what
 *          was held then (malloc_usable_size of each block). Always counted;
 *          preloaded (LD_PRELOAD=build/bench/libcatchup_heapcount.so) it gives
 *          catchup-bench and the QP peers' Python processes the same figure.
 *   count  while heap_counting is set, every allocation adds one to
 *          heap_calls: the tests' "a step allocates nothing".
 *   fault  while heap_tracking is set, the heap_fault_at-th allocation
 *          (counted in heap_fault_calls from 1) returns NULL, and
 *          heap_live_blocks counts the blocks taken minus those freed: the
 *          tests' "a failed create frees what it took". heap_spare, if set,
 *          is asked first (with the allocation's caller and 1 for a realloc)
 *          and may spare a dependency whose own out-of-memory path is broken:
 *          the next allocation is failed instead.
 *
 * Linked into a test program (CMake target catchup_heap, an object library)
 * or preloaded into any process. Off under AddressSanitizer, whose runtime
 * owns malloc: HEAP_INTERPOSED is 0 there, and the counters stay 0. Under
 * valgrind, whose own malloc replaces this one, nothing is counted either. */
#ifndef CUP_BENCH_HEAP_H
#define CUP_BENCH_HEAP_H

#if defined(__SANITIZE_ADDRESS__)                 /* GCC */
#define HEAP_INTERPOSED 0
#elif defined(__has_feature)                      /* clang */
#if __has_feature(address_sanitizer)
#define HEAP_INTERPOSED 0
#endif
#endif
#ifndef HEAP_INTERPOSED
#define HEAP_INTERPOSED 1
#endif

/* peak */
void cup_heapcount_reset(void);
long cup_heapcount_peak(void);

/* count */
extern volatile int heap_counting;
extern volatile long heap_calls;

/* fault */
extern volatile int heap_tracking;
extern volatile long heap_fault_at, heap_fault_calls, heap_live_blocks;
extern int (*heap_spare)(void *caller, int grow);

#endif

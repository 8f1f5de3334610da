/* heap — see heap.h. The peak mode is the heap a solver holds, for the
 * benchmarks: a resident-set figure counts pages, and on a set as small as
 * the paper circuit's (3 variables, 2 rows) it reads 0, 4, 8 or 20 kB
 * depending on which free holes the process's heap already had, not on the
 * solver. Python's own small objects come from its arenas (mmap), not
 * malloc, and are not counted; numpy's buffers and the solvers' C/C++
 * allocations are. Not part of the library: a harness plugin. */
#define _GNU_SOURCE
#include <errno.h>
#include <malloc.h>
#include <stddef.h>
#include "heap.h"

volatile int heap_counting, heap_tracking;
volatile long heap_calls, heap_fault_at = -1, heap_fault_calls, heap_live_blocks;
int (*heap_spare)(void *caller, int grow);

static long live, peak, base;   /* bytes; atomics: BLAS threads allocate too */

void cup_heapcount_reset(void) {
  long now = __atomic_load_n(&live, __ATOMIC_RELAXED);
  __atomic_store_n(&base, now, __ATOMIC_RELAXED);
  __atomic_store_n(&peak, now, __ATOMIC_RELAXED);
}

/* the most bytes held at once since the reset, above what was held at it */
long cup_heapcount_peak(void) {
  return __atomic_load_n(&peak, __ATOMIC_RELAXED) - __atomic_load_n(&base, __ATOMIC_RELAXED);
}

#if HEAP_INTERPOSED
/* glibc's own entry points, under the names it exports them by */
extern void *__libc_malloc(size_t n);
extern void *__libc_calloc(size_t k, size_t n);
extern void *__libc_realloc(void *p, size_t n);
extern void *__libc_memalign(size_t align, size_t n);
extern void __libc_free(void *p);

/* Before an allocation: count it, and 1 if fault mode refuses it. */
static int refused(void *caller, int grow) {
  if (heap_counting) heap_calls++;
  if (!heap_tracking || ++heap_fault_calls != heap_fault_at) return 0;
  if (heap_spare && heap_spare(caller, grow)) { heap_fault_at++; return 0; }
  return 1;
}

static void held(void *p) {
  if (!p) return;
  long now = __atomic_add_fetch(&live, (long)malloc_usable_size(p), __ATOMIC_RELAXED);
  long top = __atomic_load_n(&peak, __ATOMIC_RELAXED);
  while (now > top && !__atomic_compare_exchange_n(&peak, &top, now, 1, __ATOMIC_RELAXED,
                                                   __ATOMIC_RELAXED)) {
  }
}

/* A new block (not a realloc's): held bytes and, in fault mode, one more live block. */
static void *taken(void *p) {
  held(p);
  if (heap_tracking && p) heap_live_blocks++;
  return p;
}

void *malloc(size_t n) {
  if (refused(__builtin_return_address(0), 0)) return NULL;
  return taken(__libc_malloc(n));
}

void *calloc(size_t k, size_t n) {
  if (refused(__builtin_return_address(0), 0)) return NULL;
  return taken(__libc_calloc(k, n));
}

void free(void *p) {
  if (!p) return;
  __atomic_sub_fetch(&live, (long)malloc_usable_size(p), __ATOMIC_RELAXED);
  if (heap_tracking) heap_live_blocks--;
  __libc_free(p);
}

/* a failed realloc keeps the old block; realloc(p, 0) frees it */
void *realloc(void *p, size_t n) {
  if (refused(__builtin_return_address(0), 1)) return NULL;
  size_t old = p ? malloc_usable_size(p) : 0;
  void *q = __libc_realloc(p, n);
  if (q || n == 0) {
    __atomic_sub_fetch(&live, (long)old, __ATOMIC_RELAXED);
    held(q);
  }
  if (heap_tracking && q && !p) heap_live_blocks++;
  return q;
}

static void *aligned(void *caller, size_t align, size_t n) {
  if (refused(caller, 0)) return NULL;
  return taken(__libc_memalign(align, n));
}

void *memalign(size_t align, size_t n) { return aligned(__builtin_return_address(0), align, n); }

void *aligned_alloc(size_t align, size_t n) { return aligned(__builtin_return_address(0), align, n); }

void *valloc(size_t n) { return aligned(__builtin_return_address(0), 4096, n); }

int posix_memalign(void **out, size_t align, size_t n) {
  if (align < sizeof(void *) || (align & (align - 1))) return EINVAL;
  void *p = aligned(__builtin_return_address(0), align, n);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}
#endif

/* heapcount — the heap a solver holds, in bytes, for the benchmarks.
 *
 * A resident-set figure counts pages: on a set as small as the paper
 * circuit's (3 variables, 2 rows) it reads 0, 4, 8 or 20 kB depending on
 * which free holes the process's heap already had, not on the solver. This
 * shim, preloaded (LD_PRELOAD) into catchup-bench and into the QP peers'
 * Python processes alike, counts the bytes malloc hands out and takes back
 * (malloc_usable_size of each block), so both harnesses read the same
 * figure: the most bytes held at once since cup_heapcount_reset, above what
 * was held then. Python's own small objects come from its arenas (mmap), not
 * malloc, and are not counted; numpy's buffers and the solvers' C/C++
 * allocations are. Not part of the library: a benchmark tool. */
#define _GNU_SOURCE
#include <errno.h>
#include <malloc.h>
#include <stddef.h>

/* glibc's own entry points, under the names it exports them by */
extern void *__libc_malloc(size_t n);
extern void *__libc_calloc(size_t k, size_t n);
extern void *__libc_realloc(void *p, size_t n);
extern void *__libc_memalign(size_t align, size_t n);
extern void __libc_free(void *p);

static long live, peak, base;   /* bytes; atomics: BLAS threads allocate too */

static void held(void *p) {
  if (!p) return;
  long now = __atomic_add_fetch(&live, (long)malloc_usable_size(p), __ATOMIC_RELAXED);
  long top = __atomic_load_n(&peak, __ATOMIC_RELAXED);
  while (now > top && !__atomic_compare_exchange_n(&peak, &top, now, 1, __ATOMIC_RELAXED,
                                                   __ATOMIC_RELAXED)) {
  }
}

static void released(void *p) {
  if (p) __atomic_sub_fetch(&live, (long)malloc_usable_size(p), __ATOMIC_RELAXED);
}

void cup_heapcount_reset(void) {
  long now = __atomic_load_n(&live, __ATOMIC_RELAXED);
  __atomic_store_n(&base, now, __ATOMIC_RELAXED);
  __atomic_store_n(&peak, now, __ATOMIC_RELAXED);
}

/* the most bytes held at once since the reset, above what was held at it */
long cup_heapcount_peak(void) {
  return __atomic_load_n(&peak, __ATOMIC_RELAXED) - __atomic_load_n(&base, __ATOMIC_RELAXED);
}

void *malloc(size_t n) {
  void *p = __libc_malloc(n);
  held(p);
  return p;
}

void *calloc(size_t k, size_t n) {
  void *p = __libc_calloc(k, n);
  held(p);
  return p;
}

void free(void *p) {
  released(p);
  __libc_free(p);
}

/* a failed realloc keeps the old block; realloc(p, 0) frees it */
void *realloc(void *p, size_t n) {
  size_t old = p ? malloc_usable_size(p) : 0;
  void *q = __libc_realloc(p, n);
  if (q || n == 0) {
    __atomic_sub_fetch(&live, (long)old, __ATOMIC_RELAXED);
    held(q);
  }
  return q;
}

void *memalign(size_t align, size_t n) {
  void *p = __libc_memalign(align, n);
  held(p);
  return p;
}

void *aligned_alloc(size_t align, size_t n) { return memalign(align, n); }

int posix_memalign(void **out, size_t align, size_t n) {
  if (align < sizeof(void *) || (align & (align - 1))) return EINVAL;
  void *p = memalign(align, n);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}

void *valloc(size_t n) { return memalign(4096, n); }

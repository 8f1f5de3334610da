/* A counting allocator for the tests that check that a step, a projection
 * or an evolve allocates nothing: glibc interposition of malloc and its
 * kin; set `counting` around the code under test and read `alloc_count`.
 * Off under ASan, which interposes them itself (CUP_COUNTING is then 0).
 * Include it in one translation unit of a test program. */
#ifndef CUP_ALLOC_COUNT_H
#define CUP_ALLOC_COUNT_H

#include <stddef.h>

#if defined(__SANITIZE_ADDRESS__)
#define CUP_COUNTING 0
#else
#define CUP_COUNTING 1
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void *__libc_memalign(size_t, size_t);
static volatile long alloc_count = 0;
static volatile int counting = 0;
void *malloc(size_t n) { if (counting) alloc_count++; return __libc_malloc(n); }
void *calloc(size_t a, size_t b) { if (counting) alloc_count++; return __libc_calloc(a, b); }
void *realloc(void *q, size_t n) { if (counting) alloc_count++; return __libc_realloc(q, n); }
void *aligned_alloc(size_t al, size_t n) { if (counting) alloc_count++; return __libc_memalign(al, n); }
int posix_memalign(void **q, size_t al, size_t n) {
  if (counting) alloc_count++;
  *q = __libc_memalign(al, n);
  return *q ? 0 : 12;
}
#endif

#endif

/* block — many arrays carved from one allocation: a structure's set-up
 * walks its arrays twice, first to sum their sizes (base NULL), then to
 * hand out pieces of the one block (base set). One malloc and one free
 * instead of one per array: forming a switch configuration's integrators
 * made some 2,500 callocs on the full bridge, a third of their cost. */
#ifndef CUP_UTIL_BLOCK_H
#define CUP_UTIL_BLOCK_H
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

typedef struct block_arena {
  char *base;   /* NULL: sizing */
  size_t used;  /* bytes handed out (or summed) so far */
} block_arena;

/* count elements of size bytes, 16-byte aligned as malloc's (at least 16
 * bytes: no two arrays share an address); NULL while sizing. */
static inline void *block_take(block_arena *b, size_t count, size_t size) {
  size_t bytes = count * size;
  bytes = bytes ? (bytes + 15) & ~(size_t)15 : 16;
  void *q = b->base ? b->base + b->used : NULL;
  b->used += bytes;
  return q;
}

/* A short-lived scratch of bytes: the caller's buffer small (cap bytes,
 * on its stack) when it fits, zeroed if zero, else the heap's (NULL: no
 * memory); scratch_free frees the heap's alone (and NULL). A switch
 * configuration is formed inside its run: a malloc and a free were some
 * 250 instructions. */
static inline void *scratch_take(void *small, size_t cap, size_t bytes, int zero) {
  if (bytes <= cap) return zero ? memset(small, 0, bytes) : small;
  return zero ? calloc(bytes, 1) : malloc(bytes);
}
static inline void scratch_free(void *p, const void *small) {
  if (p != small) free(p);
}
#endif

/* lanes — two doubles side by side (GCC vector extensions: SSE2, in any
 * x86-64; plain code elsewhere). The time loop's small steps keep rows,
 * states or steps in lanes, each lane doing a scalar's arithmetic in the
 * scalar's order, so that the results are those of the one-at-a-time code
 * bit for bit, in fewer instructions. */
#ifndef CUP_UTIL_LANES_H
#define CUP_UTIL_LANES_H
#ifdef __SSE2__
#include <emmintrin.h>   /* the intrinsics GCC and clang both name (GCC's builtins are GCC's alone) */
#endif

typedef double v2d __attribute__((vector_size(16)));
typedef long long v2l __attribute__((vector_size(16)));

/* Entry j of the values v[0][0], v[0][1], v[1][0], ... */
static inline __attribute__((always_inline)) double v2_lane(const v2d *v, int j) {
  return v[j >> 1][j & 1];
}

static inline v2d v2_abs(v2d v) {
  return (v2d)((v2l)v & (v2l){0x7fffffffffffffffLL, 0x7fffffffffffffffLL});
}

/* a > b ? a : b and a < b ? a : b, lane by lane (b where unordered: SSE2's
 * maxpd and minpd exactly) */
static inline v2d v2_max(v2d a, v2d b) {
#ifdef __SSE2__
  return _mm_max_pd(a, b);
#else
  return (v2d){a[0] > b[0] ? a[0] : b[0], a[1] > b[1] ? a[1] : b[1]};
#endif
}

static inline v2d v2_min(v2d a, v2d b) {
#ifdef __SSE2__
  return _mm_min_pd(a, b);
#else
  return (v2d){a[0] < b[0] ? a[0] : b[0], a[1] < b[1] ? a[1] : b[1]};
#endif
}

/* mask ? 0 : v, lane by lane (mask lanes all ones or zero) */
static inline v2d v2_clear(v2l mask, v2d v) {
#ifdef __SSE2__
  return _mm_andnot_pd((v2d)mask, v);
#else
  return (v2d)(~mask & (v2l)v);
#endif
}

/* (a[i], b[j]) with lanes numbered 0, 1 in a and 2, 3 in b */
#ifdef __clang__
#define v2_shuffle(a, b, i, j) __builtin_shufflevector(a, b, i, j)
#else
#define v2_shuffle(a, b, i, j) __builtin_shuffle(a, b, (v2l){i, j})
#endif

/* mask ? a : b, lane by lane (mask lanes all ones or zero) */
static inline v2d v2_select(v2l mask, v2d a, v2d b) {
  return (v2d)(((v2l)a & mask) | ((v2l)b & ~mask));
}

#endif

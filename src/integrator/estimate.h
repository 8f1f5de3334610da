/* estimate — the opt-in error estimate of the fixed-step schemes by step
 * doubling: the integrator runs the scheme again at n/2 (half again the
 * work) and compares on the coarse grid,
 *     err(n) ~ max_j ||x_n(t_j) - x_{n/2}(t_j)||_inf,
 * which is err(n) itself for a first-order scheme (err(n/2) = 2 err(n)) and
 * 3 err(n) for a second-order one. This keeps the coarse run's states at
 * the compared points, at most CUP_ESTIMATE_POINTS of them (every s-th
 * coarse step, and T), so memory stays flat. */
#ifndef CUP_ESTIMATE_H
#define CUP_ESTIMATE_H

#include <math.h>

#define CUP_ESTIMATE_POINTS 4096

typedef struct estimate_ws {
  long n, stride;           /* the fine run's n (even); coarse steps between compared points */
  int dim, ok;
  double *X;                /* the coarse run at steps 0, s, 2s, ..., and at n/2 (last row) */
  double err;
} estimate_ws;

/* CUP_OK or CUP_ERR_NOMEM. */
int estimate_init(estimate_ws *E, long n, int dim);
void estimate_free(estimate_ws *E);
/* The coarse run's output stride (its output: every stride steps). */
static inline long estimate_stride(const estimate_ws *E) { return E->stride; }
/* A cup_sample_fn for the coarse run (ctx = E): keeps its states. */
int estimate_keep(long k, double t, const double *x, void *ctx);
/* After the coarse run: ok = it finished; comparisons start from 0. */
void estimate_start(estimate_ws *E, int ok);
/* The fine run's state at step k (1..n): compared when k is a point. */
void estimate_compare(estimate_ws *E, long k, const double *x);
/* The estimate so far; NaN if the coarse run failed. */
static inline double estimate_value(const estimate_ws *E) { return E->ok ? E->err : NAN; }

#endif

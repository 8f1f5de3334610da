/* estimate — the opt-in error estimate of the fixed-step schemes by step
 * doubling: the integrator runs the scheme again at n/2 (half again the
 * work) and compares on the coarse grid,
 *     err(n) ~ max_j ||x_n(t_j) - x_{n/2}(t_j)||_inf,
 * which is err(n) itself for a first-order scheme (err(n/2) = 2 err(n)) and
 * 3 err(n) for a second-order one. This keeps the coarse run's states at
 * the compared points, at most CUP_ESTIMATE_POINTS of them (every s-th
 * coarse step, and T), so memory stays flat.
 *
 * Samples between grid times are the scheme's states interpolated
 * linearly, and that interpolation has an error of its own, which the
 * grids' comparison does not see: up to h |x''| h / 8 on a smooth stretch,
 * up to h |x'(t+) - x'(t-)| / 4 across an event inside the step (a
 * diode's kink), and all of a jump. When samples fall inside a step
 * (estimate_samples), each step's second difference
 *     D_k = ||x_k - 2 x_{k-1} + x_{k-2}||_inf
 * (h^2 x'' on a smooth stretch; h (1 - f) |x'(t+) - x'(t-)| for a kink a
 * fraction f into step k, h f |...| for one in step k - 1) gives it: for
 * each step k with a sample inside, D_k D_{k+1} / (D_k + D_{k+1}), the
 * error itself at a kink and four times it on a smooth stretch
 * (estimate.c, interp_close). */
#ifndef CUP_ESTIMATE_H
#define CUP_ESTIMATE_H

#include <math.h>

#define CUP_ESTIMATE_POINTS 4096

typedef struct estimate_ws {
  long n, stride;           /* the fine run's n (even); coarse steps between compared points */
  int dim, ok;
  double *X;                /* the coarse run at steps 0, s, 2s, ..., and at n/2 (last row) */
  double err;
  /* the samples' interpolation (estimate_samples; interp = 0: none between grid times) */
  int interp, held, inside_last;   /* states held (0-2), the last one's step had a sample inside */
  int back_ok;              /* back: that step's backward difference */
  double back;
  long last_k;              /* the step of hist[0] */
  double h, t0, ds, jmax;   /* grid step; samples at t0 + j ds, j = 0..jmax */
  double *hist;             /* x_{last_k}, x_{last_k - 1} */
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
/* The fine run's output: CUP_OUTPUT_SAMPLES with samples between grid
 * times (o: the fine run's options) adds their interpolation's error.
 * CUP_OK or CUP_ERR_NOMEM. */
struct cup_integrator_options;
int estimate_samples(estimate_ws *E, const struct cup_integrator_options *o);
/* The fine run's state at grid step k that the next step starts from: x0
 * (k = 0), or the state after a jump at t_k (the interpolation's
 * differences start again from it). */
void estimate_anchor(estimate_ws *E, long k, const double *x);
/* The fine run's state at step k (1..n): compared when k is a point, and
 * its second difference taken (above). */
void estimate_compare(estimate_ws *E, long k, const double *x);
/* The estimate so far; NaN if the coarse run failed. */
static inline double estimate_value(const estimate_ws *E) { return E->ok ? E->err : NAN; }

#endif

/* estimate — the opt-in error estimate of the fixed-step schemes by step
 * doubling: a second run at n/2 (half again the work), and the largest
 * difference between the two on the coarse grid,
 *     err(n) ~ max_j ||x_n(t_j) - x_{n/2}(t_j)||_inf,
 * which is err(n) itself for a first-order scheme (err(n/2) = 2 err(n)) and
 * 3 err(n) for a second-order one. At most CUP_ESTIMATE_POINTS grid points
 * are compared (every s-th coarse step, and T), so memory stays flat. */
#ifndef CUP_ESTIMATE_H
#define CUP_ESTIMATE_H

#include "catchup/integrator.h"

#define CUP_ESTIMATE_POINTS 4096

typedef struct cup_estimate {
  cup_integrator *half;     /* the run at n/2 */
  long n, stride;           /* the fine run's n; coarse steps between compared points */
  int dim, ok;
  double *X;                /* the coarse run at steps 0, s, 2s, ..., and at n/2 (last row) */
  double err;
} cup_estimate;

/* Set up the run at n/2 (o->n even, checked by the integrator). */
int cup_estimate_init(cup_estimate *E, const cup_lcs *L, const cup_input *u,
                      const cup_integrator_options *o, char *errmsg);
void cup_estimate_free(cup_estimate *E);
/* Run the coarse run from x0 and keep its states at the compared points. */
void cup_estimate_prepare(cup_estimate *E, const double *x0);
/* The fine run's state at step k (1..n): compared when k is a point. */
void cup_estimate_compare(cup_estimate *E, long k, const double *x);
/* The estimate so far; NaN if the coarse run failed. */
static inline double cup_estimate_value(const cup_estimate *E) { return E->ok ? E->err : NAN; }

#endif

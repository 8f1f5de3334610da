/* tally — what the fixed-step loop books per step, shared by integrator.c's
 * loop and faststep.c's runs of steps. */
#ifndef CUP_INTEGRATOR_TALLY_H
#define CUP_INTEGRATOR_TALLY_H

#include <math.h>
#include "catchup/integrator.h"

/* t_k = k T / n computed from k alone: no accumulation, and t_n = T. */
static inline double tally_grid_time(long k, long n, double T, double h) {
  return k == n ? T : (double)k * h;
}

/* Whether a state has left its range: ||x||_1 beyond CUP_STATE_MAX (or NaN
 * or Inf in it, which the sum carries); no branch an entry. */
static inline int tally_state_beyond(const double *x, int n) {
  double s = 0;
  for (int j = 0; j < n; j++) s += fabs(x[j]);
  return !(s <= CUP_STATE_MAX);
}

/* The entry of largest magnitude (the first NaN), for the message. */
static inline int tally_state_worst(const double *x, int n) {
  int w = 0;
  for (int j = 0; j < n; j++) {
    if (isnan(x[j])) return j;
    if (fabs(x[j]) > fabs(x[w])) w = j;
  }
  return w;
}

static inline void tally_projection(cup_run_info *info, const cup_proj_info *pi) {
  if (pi->skipped) info->skipped++; else info->projected++;
  info->dual_iterations += pi->iterations;
  info->factorizations += pi->factorizations;
  if (!(pi->eps_cert <= info->max_eps_cert)) info->max_eps_cert = pi->eps_cert;
  if (!(pi->eta_cert <= info->max_eta_cert)) info->max_eta_cert = pi->eta_cert;
}

#endif

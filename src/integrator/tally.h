/* tally — what the fixed-step loop books per step, shared by integrator.c's
 * loop and faststep.c's runs of steps. */
#ifndef CUP_INTEGRATOR_TALLY_H
#define CUP_INTEGRATOR_TALLY_H

#include "catchup/integrator.h"

/* t_k = k T / n computed from k alone: no accumulation, and t_n = T. */
static inline double cup_grid_time(long k, long n, double T, double h) {
  return k == n ? T : (double)k * h;
}

static inline void cup_tally(cup_run_info *info, const cup_proj_info *pi) {
  if (pi->skipped) info->skipped++; else info->projected++;
  info->dual_iterations += pi->iterations;
  info->factorizations += pi->factorizations;
  if (!(pi->eps_cert <= info->max_eps_cert)) info->max_eps_cert = pi->eps_cert;
  if (!(pi->eta_cert <= info->max_eta_cert)) info->max_eta_cert = pi->eta_cert;
}

#endif

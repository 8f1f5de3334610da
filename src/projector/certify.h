/* certify — the primal point of a dual iterate, the certificates of a
 * candidate and the Farkas test (certify.c): shared by the projection
 * methods and the dispatcher, below both. */
#ifndef CUP_CERTIFY_H
#define CUP_CERTIFY_H

#include <float.h>
#include "proj_ws.h"

/* u = P^-1 v in place (any metric), allocation-free. */
void certify_metric_solve(cup_projector *p, double *v);
/* y = x + P^-1 C^T lam, s = C y + g with rounding bounds gam. */
void certify_eval_primal(cup_projector *p, const double *x, const double *g, const double *lam,
                         double *y, double *s, double *gam);
/* Certificates for candidate (lam, z) with slack s, gam at z; fills info's
 * eps_cert, eta_cert, violation, dual_value; sets p->v/has_v. Returns 1 when
 * both targets are met. */
int certify_candidate(cup_projector *p, const double *x, const double *lam,
                      const double *z, cup_proj_info *info);
/* Farkas test on a direction dlam >= 0 (copied into p->farkas when it
 * certifies emptiness); returns 1 if K is declared empty. */
int certify_farkas_test(cup_projector *p, const double *dlam, cup_proj_info *info);

/* A bound on ||z - y(lam)||_P for z = fl(x + u): a few ulps of ||x||_P <= scale
 * and of ||u||_P = un, times P's condition for a sparse metric (its solve is
 * backward stable). Inline: the small-set path pays for no call. */
static inline double certify_z_rounding(const cup_polyset *K, double scale, double un) {
  return 8 * DBL_EPSILON * (scale + K->solve_amp * un);
}

/* ||z - x||_P (scratch p->wn2). */
static inline double certify_step_norm(cup_projector *p, const double *z, const double *x) {
  for (int j = 0; j < p->n; j++) p->wn2[j] = z[j] - x[j];
  return cup_polyset_norm(p->K, p->wn2);
}

#endif

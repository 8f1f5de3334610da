/* First-order dual methods: the paper's projected gradient (Sec. 7, eq.
 *   lambda_{k+1} = [lambda_k - (1/L)(C P^-1 C^T lambda_k + C x + g)]_+ )
 * and its accelerated variant (FISTA with O'Donoghue-Candes gradient
 * restart). The gradient C P^-1 C^T lambda + b is the slack s(y(lambda)) of
 * the recovered primal point y = x + P^-1 C^T lambda, so one evaluation per
 * iteration gives both the step and the certificate. The methods pg and
 * fista run it from the warm start to max_iter; the dense active set
 * (activeset.c) runs it in bursts. */
#include <math.h>
#include <string.h>
#include "catchup.h"
#include "certify.h"
#include "firstorder.h"

/* The iteration aims each row's slack at AIM times its rounding bound
 * (gam at the current iterate) instead of 0: a dual iterate's primal point
 * approaches the projection from outside K, so on the rows active at the
 * answer its slack stays within rounding of 0 and never certainly >= 0;
 * with no feasible point to anchor eta (a jam: g < 0 puts the origin
 * outside K, no interior direction is known for a sparse set) eta would
 * stay infinite. Aimed inside, the iterate becomes certainly feasible once
 * it converges to within (AIM - 1) gam, as the Newton path's finishing
 * solve does; eps pays 2 sum lam_i AIM gam_i, a few ulps of S^2. */
#define AIM 16

#define SWAP(a, b) do { double *t_ = (a); (a) = (b); (b) = t_; } while (0)

int proj_firstorder(cup_projector *p, fo_ws *w, const double *x, int accelerated, int budget,
                    cup_proj_info *info) {
  const cup_polyset *K = p->K;
  int m = p->m;
  size_t msz = sizeof(double) * (size_t)m;
  info->method = accelerated ? CUP_PROJ_FISTA : CUP_PROJ_PG;
  double L = p->opt.lipschitz > 0 ? p->opt.lipschitz : K->lip;
  certify_eval_primal(p, x, p->g, p->lam, p->y, p->s, p->gam);
  if (!(L > 0)) {                       /* no row constrains x: K is everything */
    memset(p->lam, 0, msz);
    certify_eval_primal(p, x, p->g, p->lam, p->y, p->s, p->gam);
    return certify_candidate(p, x, p->lam, p->y, info) ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
  }
  double tau = 1.0 / L, t = 1;
  double *mu = w->wm2, *smu = w->wm3, *snap = w->wm4;
  if (accelerated) { memcpy(mu, p->lam, msz); memcpy(smu, p->s, msz); }
  memcpy(snap, p->lam, msz);
  int next_full = 0;
  for (int it = 0;; it++) {
    double eq = 0;
    for (int i = 0; i < m; i++) eq += 2 * p->lam[i] * (p->s[i] + p->gam[i]);
    if (!isfinite(eq)) return CUP_ERR_DIVERGED;
    int last = it >= budget;
    if (last || (eq <= info->eps_target && it >= next_full)) {
      if (certify_candidate(p, x, p->lam, p->y, info)) return CUP_OK;
      if (last) return CUP_WARN_NOT_CERTIFIED;
      next_full = it + 1 + it / 8;      /* eta pushes cost O(nnz): back off */
    }
    const double *src = accelerated ? mu : p->lam;
    const double *gsrc = accelerated ? smu : p->s;
    double *lnew = w->wm;
    for (int i = 0; i < m; i++) lnew[i] = fmax(0, src[i] - tau * (gsrc[i] - AIM * p->gam[i]));
    certify_eval_primal(p, x, p->g, lnew, p->y2, p->s2, p->gam2);
    p->iters++;
    if (accelerated) {
      double r = 0;
      for (int i = 0; i < m; i++) r += (mu[i] - lnew[i]) * (lnew[i] - p->lam[i]);
      double tn = r > 0 ? 1 : 0.5 * (1 + sqrt(1 + 4 * t * t));
      double beta = r > 0 ? 0 : (t - 1) / tn;
      for (int i = 0; i < m; i++) {
        mu[i] = lnew[i] + beta * (lnew[i] - p->lam[i]);
        smu[i] = p->s2[i] + beta * (p->s2[i] - p->s[i]);
      }
      t = tn;
    }
    SWAP(p->lam, w->wm);
    SWAP(p->y, p->y2);
    SWAP(p->s, p->s2);
    SWAP(p->gam, p->gam2);
    if ((it + 1) % 64 == 0) {           /* an empty K makes lambda grow along a Farkas ray */
      double *d = w->wm;                /* free now: holds the previous lambda */
      for (int i = 0; i < m; i++) d[i] = fmax(0, p->lam[i] - snap[i]);
      if (certify_farkas_test(p, d, info)) return CUP_ERR_EMPTY_SET;
      memcpy(snap, p->lam, msz);
    }
  }
}

/* ---- the methods pg and fista ------------------------------------------------- */

void proj_fo_lay_out(cup_projector *p, proj_carve *a, fo_ws *w) {
  size_t M = (size_t)p->m;
  w->wm = proj_carve_piece(a, M, sizeof(double));
  w->wm2 = proj_carve_piece(a, M, sizeof(double));
  w->wm3 = proj_carve_piece(a, M, sizeof(double));
  w->wm4 = proj_carve_piece(a, M, sizeof(double));
}

static void lay_out(cup_projector *p, proj_carve *a, void **ws) {
  fo_ws scratch, *w = PROJ_WS_CARVE(a, *ws, fo_ws, &scratch);
  proj_fo_lay_out(p, a, w);
}

/* Every call from the warm start (or from 0), to the iteration limit. */
static int solve(cup_projector *p, void *ws, const double *x, int accelerated, cup_proj_info *info) {
  if (p->opt.warm_start) memcpy(p->lam, p->lam_warm, sizeof(double) * (size_t)p->m);
  else memset(p->lam, 0, sizeof(double) * (size_t)p->m);
  return proj_firstorder(p, ws, x, accelerated, p->opt.max_iter, info);
}

static int solve_pg(cup_projector *p, void *ws, const double *x, cup_proj_info *info) {
  return solve(p, ws, x, 0, info);
}

static int solve_fista(cup_projector *p, void *ws, const double *x, cup_proj_info *info) {
  return solve(p, ws, x, 1, info);
}

static int takes_pg(const cup_polyset *K, const cup_projector_options *o) {
  (void)K;
  return o->method == CUP_PROJ_PG;
}

static int takes_fista(const cup_polyset *K, const cup_projector_options *o) {
  (void)K;
  return o->method == CUP_PROJ_FISTA;
}

static const proj_method pg_method = {
  .name = "pg", .takes = takes_pg, .lay_out = lay_out, .solve = solve_pg,
};
static const proj_method fista_method = {
  .name = "fista", .takes = takes_fista, .lay_out = lay_out, .solve = solve_fista,
};
const proj_method *const proj_pg = &pg_method;
const proj_method *const proj_fista = &fista_method;

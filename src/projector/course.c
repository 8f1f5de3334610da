/* course — see course.h. */
#include <math.h>
#include <string.h>
#include "catchup.h"
#include "certify.h"
#include "course.h"

int proj_course(cup_projector *p, const proj_slot *s, const double *x, double *z, cup_proj_info *info) {
  const cup_polyset *K = p->K;
  int n = p->n, m = p->m;
  polyset_slack(K, p->g, x, p->b, p->gam);
  double worst_raw = INFINITY;
  for (int i = 0; i < m; i++) worst_raw = la_min(worst_raw, p->b[i]);
  if (worst_raw >= 0) {                    /* x in K: returned unchanged, exactly */
    if (z != x) la_copy(z, x, n);
    la_zero(p->lam, m);
    info->skipped = 1;
    double worst = INFINITY;
    for (int i = 0; i < m; i++) worst = la_min(worst, p->b[i] - p->gam[i]);
    if (worst >= 0) {                      /* certainly inside: nothing to certify */
      info->eta_cert = info->eps_cert = 0;
      la_copy(p->anchor, x, n);           /* and a good anchor for later */
      la_copy(p->s_anchor, p->b, m);
      p->anchor_ok = 1;
      return info->status = CUP_OK;
    }
    la_copy(p->s, p->b, m);
    certify_candidate(p, x, p->lam, x, info);
    info->eps_cert = 0;                    /* z = x exactly: no excess at all */
    info->status = info->eta_cert <= info->eta_target ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
    return info->status;
  }
  if (!s) return info->status = CUP_ERR_ARG;
  int st = s->m->solve(p, s->ws, x, info);
  info->iterations = p->iters;
  info->factorizations = p->facts;
  info->row_updates = p->updates;
  info->status = st;
  if (st < 0) return st;
  const double *res = (p->opt.return_feasible && p->has_v) ? p->v : p->y;
  for (int j = 0; j < n; j++)              /* an overflowed iterate is an error, never an answer */
    if (!isfinite(res[j])) return info->status = CUP_ERR_DIVERGED;
  int active = 0;
  for (int i = 0; i < m; i++) active += p->lam[i] > 0;
  info->active = active;
  if (p->opt.warm_start) memcpy(p->lam_warm, p->lam, sizeof(double) * (size_t)m);
  memcpy(z, res, sizeof(double) * (size_t)n);
  return st;
}

int proj_general(cup_projector *p, const proj_slot *s, const double *x, double *z, cup_proj_info *info_out) {
  cup_proj_info local;
  cup_proj_info *info = info_out ? info_out : &local;
  if (!proj_start(p, x, z, info)) return info->status;
  return proj_course(p, s, x, z, info);
}

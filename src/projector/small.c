/* small — the auto method's first try on a small dense set (K->dense:
 * m <= 64 rows, dim <= 256): the dual LCP solved exactly by principal
 * pivoting (closed form on one or two active rows), the rows aimed a few
 * ulps inside K: the LCP step of lcp/step.h with W = I and h = 1. z is
 * then certainly in K (eta = 0) and eps is the weak-duality gap, as
 * certify_candidate computes it. What it cannot certify (a singular block, a set
 * without interior, a tolerance below rounding) goes to the dense active
 * set (activeset.c), its fallback. */
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "certify.h"
#include "course.h"
#include "activeset.h"
#include "small.h"
#include "lcp/step.h"

/* Returns 1 with z and info filled when the LCP certifies the targets; 0
 * leaves everything to the fallback. */
static int answer(cup_projector *p, void *ws, const double *x, double *z, cup_proj_info *info) {
  lcp_step *small = ws;
  if (!small) return 0;                            /* a set without rows */
  const cup_polyset *K = p->K;
  int n = p->n, m = p->m;
  if (!p->opt.warm_start) lcp_forget(&small->lcp);
  cup_proj_info ti;
  if (lcp_step_solve(small, p->g, x, p->y, info->scale, info->eps_target, info->eta_target, &ti))
    return 0;
  double un = ti.skipped ? 0 : certify_step_norm(p, p->y, x);   /* ||z - x||_P */
  double ebound = ti.skipped ? 0 : certify_z_rounding(K, info->scale, un);
  double eps = ti.eps_cert + ebound * ebound;
  if (!(eps <= info->eps_target)) return 0;
  info->eps_cert = eps;
  info->eta_cert = ti.eta_cert;
  info->violation = ti.violation;
  info->dual_value = -2 * small->lq - un * un;
  info->skipped = ti.skipped;
  info->iterations = ti.iterations;
  info->active = ti.active;
  info->method = ti.skipped ? p->opt.method : CUP_PROJ_ACTIVESET;
  memcpy(p->lam, small->lcp.lam, sizeof(double) * (size_t)m);
  if (p->opt.warm_start && !ti.skipped) memcpy(p->lam_warm, p->lam, sizeof(double) * (size_t)m);
  memcpy(z, p->y, sizeof(double) * (size_t)n);
  info->status = CUP_OK;
  return 1;
}

/* The projection: the LCP's answer, or the fallback's course. */
static int project(cup_projector *p, const proj_slot *s, const double *x, double *z, cup_proj_info *info_out) {
  cup_proj_info local;
  cup_proj_info *info = info_out ? info_out : &local;
  if (!proj_start(p, x, z, info)) return info->status;
  if (answer(p, s->ws, x, z, info)) return CUP_OK;
  return proj_course(p, &p->slot[s->fallback], x, z, info);
}

/* The LCP's matrices (a set without rows needs none: every point is in it). */
static int create(cup_projector *p, void **ws, char *errmsg) {
  if (p->m == 0) return CUP_OK;
  lcp_step *small = calloc(1, sizeof *small);
  *ws = small;
  int st = small ? lcp_step_init(small, p->K, NULL, 1.0) : CUP_ERR_NOMEM;
  return st ? fail_fmt(errmsg, st, "projector: out of memory") : CUP_OK;
}

static void free_ws(cup_projector *p, void *ws) {
  (void)p;
  if (ws) lcp_step_free(ws);
  free(ws);
}

static void reset(cup_projector *p, void *ws) {
  (void)p;
  lcp_step *small = ws;
  if (small) lcp_forget(&small->lcp);
}

/* lambda, its warm start and lambda^T q: what a step carries to the next. */
static void checkpoint(cup_projector *p, void *ws, ckpt *c) {
  (void)p;
  if (ws) lcp_step_checkpoint(ws, c);
}

/* The auto method on a small dense set, unless the options want what only
 * the certificates' anchors give: a user's feasible point (an anchor), or
 * the feasible point v itself as the answer (return_feasible). */
static int takes(const cup_polyset *K, const cup_projector_options *o) {
  return K->dense && o->method == CUP_PROJ_AUTO && !o->feasible_point && !o->return_feasible;
}

static const proj_method small_method = {
  .name = "small LCP", .exact = 1, .fallback = &proj_dense, .takes = takes, .create = create,
  .free = free_ws, .reset = reset, .checkpoint = checkpoint, .project = project,
};
const proj_method *const proj_small = &small_method;

/* projector — certified (eps, eta)-approximate projections onto a polyset
 * (paper, Sec. 2 definition; Sec. 7 dual method). This file: set-up, the
 * skip path, and the certificates every method returns through. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "catchup/projector.h"
#include "projector_impl.h"
#include "lcp/step.h"

#define U DBL_EPSILON

void cup_projector_options_default(cup_projector_options *o) {
  if (!o) return;
  memset(o, 0, sizeof *o);
  o->method = CUP_PROJ_AUTO;
  o->eps_abs = 0;
  o->eps_rel = 1e-10;
  o->eta_abs = 0;
  o->eta_rel = 1e-10;
  o->max_iter = 100000;
  o->warm_start = 1;
  o->return_feasible = 0;
  o->lipschitz = 0;
  o->feasible_point = NULL;
  o->factor_updates = 1;
}

const char *cup_proj_method_name(int method) {
  switch (method) {
    case CUP_PROJ_AUTO: return "auto";
    case CUP_PROJ_PG: return "pg";
    case CUP_PROJ_FISTA: return "fista";
    case CUP_PROJ_ACTIVESET: return "activeset";
  }
  return "unknown";
}

int cup_proj_method_parse(const char *name) {
  static const char *names[] = {"auto", "pg", "fista", "activeset"};
  if (!name) return -1;
  for (int k = 0; k < 4; k++)
    if (strcmp(name, names[k]) == 0) return k;
  return -1;
}

static void offset_changed(cup_projector *p) {
  const cup_polyset *K = p->K;
  p->gscale = 0;
  p->empty_row = -1;
  for (int i = 0; i < p->m; i++) {
    if (K->rownorm[i] > 0) {
      p->gscale = fmax(p->gscale, fabs(p->g[i]) / K->rownorm[i]);
    } else if (p->g[i] < 0 && p->empty_row < 0) {
      p->empty_row = i;              /* 0 >= -g_i > 0 is impossible */
    }
  }
  p->anchor_ok = -1;                 /* -1: to be rechecked against the new g */
  p->user_ok = p->user_pt ? -1 : 0;
}

static void *xalloc(size_t count, size_t size, int *fail) {
  void *q = calloc(count ? count : 1, size);
  if (!q) *fail = 1;
  return q;
}

int cup_projector_create(cup_projector **out, const cup_polyset *K,
                         const cup_projector_options *opt, char *errmsg) {
  if (!out) return cup_fail(errmsg, CUP_ERR_ARG, "projector: output pointer is NULL");
  *out = NULL;
  if (!K) return cup_fail(errmsg, CUP_ERR_ARG, "projector: polyset is NULL");
  cup_projector_options o;
  if (opt) o = *opt; else cup_projector_options_default(&o);
  if (o.method < CUP_PROJ_AUTO || o.method > CUP_PROJ_ACTIVESET)
    return cup_fail(errmsg, CUP_ERR_ARG, "projector: unknown method %d", (int)o.method);
  if (!(o.eps_abs >= 0) || !(o.eps_rel >= 0) || !(o.eta_abs >= 0) || !(o.eta_rel >= 0))
    return cup_fail(errmsg, CUP_ERR_ARG,
                    "projector: tolerances must be >= 0 (eps_abs %g, eps_rel %g, eta_abs %g, eta_rel %g)",
                    o.eps_abs, o.eps_rel, o.eta_abs, o.eta_rel);
  if (o.max_iter < 1)
    return cup_fail(errmsg, CUP_ERR_ARG, "projector: max_iter = %d, must be >= 1", o.max_iter);
  if (!(o.lipschitz >= 0) || isinf(o.lipschitz))
    return cup_fail(errmsg, CUP_ERR_ARG, "projector: lipschitz = %g, must be finite and >= 0", o.lipschitz);
  cup_projector *p = calloc(1, sizeof *p);
  if (!p) return cup_fail(errmsg, CUP_ERR_NOMEM, "projector: out of memory");
  p->K = K;
  p->opt = o;
  p->opt.feasible_point = NULL;
  int n = p->n = K->n, m = p->m = K->m, fail = 0;
  size_t N = (size_t)n, M = (size_t)m;
  p->g = xalloc(M, sizeof(double), &fail);
  p->lam = xalloc(M, sizeof(double), &fail);
  p->lam_warm = xalloc(M, sizeof(double), &fail);
  p->lam_fista = xalloc(M, sizeof(double), &fail);
  p->b = xalloc(M, sizeof(double), &fail);
  p->s = xalloc(M, sizeof(double), &fail);
  p->gam = xalloc(M, sizeof(double), &fail);
  p->sv = xalloc(M, sizeof(double), &fail);
  p->gamv = xalloc(M, sizeof(double), &fail);
  p->y = xalloc(N, sizeof(double), &fail);
  p->u = xalloc(N, sizeof(double), &fail);
  p->y2 = xalloc(N, sizeof(double), &fail);
  p->s2 = xalloc(M, sizeof(double), &fail);
  p->gam2 = xalloc(M, sizeof(double), &fail);
  p->v = xalloc(N, sizeof(double), &fail);
  p->s_v = xalloc(M, sizeof(double), &fail);
  p->anchor = xalloc(N, sizeof(double), &fail);
  p->s_anchor = xalloc(M, sizeof(double), &fail);
  p->inward = xalloc(N, sizeof(double), &fail);
  p->s_inward = xalloc(M, sizeof(double), &fail);
  p->farkas = xalloc(M, sizeof(double), &fail);
  p->wn = xalloc(N, sizeof(double), &fail);
  p->wn2 = xalloc(N, sizeof(double), &fail);
  p->wm = xalloc(M, sizeof(double), &fail);
  p->wm2 = xalloc(M, sizeof(double), &fail);
  p->wm3 = xalloc(M, sizeof(double), &fail);
  p->wm4 = xalloc(M, sizeof(double), &fail);
  p->iwm = xalloc(M, sizeof(int), &fail);
  p->act = xalloc(M, 1, &fail);
  p->act2 = xalloc(M, 1, &fail);
  if (opt && opt->feasible_point) {
    p->user_pt = xalloc(N, sizeof(double), &fail);
    p->s_user = xalloc(M, sizeof(double), &fail);
    if (!fail) memcpy(p->user_pt, opt->feasible_point, sizeof(double) * N);
  }
  if (K->dense) {
    p->dwork = xalloc(M * M + 6 * M, sizeof(double), &fail);
    for (int c = 0; c < CUP_DENSE_CACHE; c++) {
      p->cache[c].idx = xalloc(M, sizeof(int), &fail);
      p->cache[c].perm = xalloc(M, sizeof(int), &fail);
      p->cache[c].l = xalloc(M * M, sizeof(double), &fail);
    }
  }
  if (fail) {
    cup_projector_free(&p);
    return cup_fail(errmsg, CUP_ERR_NOMEM, "projector: out of memory");
  }
  memcpy(p->g, K->g0, sizeof(double) * M);
  offset_changed(p);
  if (p->user_pt) {
    for (int j = 0; j < n; j++)
      if (!isfinite(p->user_pt[j])) {
        cup_projector_free(&p);
        return cup_fail(errmsg, CUP_ERR_NONFINITE, "projector: feasible_point[%d] is not finite", j);
      }
  }
  int needs_newton = !K->dense && m > 0 &&
                     (o.method == CUP_PROJ_AUTO || o.method == CUP_PROJ_ACTIVESET);
  if (needs_newton) {
    int st = cup_newton_create(p, errmsg);
    if (st) { cup_projector_free(&p); return st; }
  }
  if (K->dense && m > 0 && o.method == CUP_PROJ_AUTO) {
    p->small = calloc(1, sizeof *p->small);
    int st = p->small ? cup_lcp_step_init(p->small, K, NULL, 1.0) : CUP_ERR_NOMEM;
    if (st) { cup_projector_free(&p); return cup_fail(errmsg, st, "projector: out of memory"); }
  }
  *out = p;
  return CUP_OK;
}

void cup_projector_free(cup_projector **pp) {
  if (!pp || !*pp) return;
  cup_projector *p = *pp;
  cup_newton_free(p);
  if (p->small) cup_lcp_step_free(p->small);
  free(p->small);
  free(p->g); free(p->lam); free(p->lam_warm); free(p->lam_fista); free(p->b); free(p->s); free(p->gam);
  free(p->sv); free(p->gamv); free(p->y); free(p->u); free(p->y2); free(p->s2); free(p->gam2); free(p->v); free(p->s_v); free(p->anchor);
  free(p->s_anchor); free(p->user_pt); free(p->s_user); free(p->inward); free(p->s_inward); free(p->farkas);
  free(p->wn); free(p->wn2); free(p->wm); free(p->wm2); free(p->wm3); free(p->wm4);
  free(p->iwm); free(p->act); free(p->act2); free(p->dwork);
  for (int c = 0; c < CUP_DENSE_CACHE; c++) {
    free(p->cache[c].idx); free(p->cache[c].perm); free(p->cache[c].l);
  }
  free(p);
  *pp = NULL;
}

int cup_projector_set_offset(cup_projector *p, const double *g) {
  if (!p || (!g && p->m > 0)) return CUP_ERR_ARG;
  for (int i = 0; i < p->m; i++)
    if (!isfinite(g[i])) return CUP_ERR_NONFINITE;
  if (p->m) memcpy(p->g, g, sizeof(double) * (size_t)p->m);
  offset_changed(p);
  return CUP_OK;
}

int cup_projector_set_tolerances(cup_projector *p, double eps_abs, double eps_rel,
                                 double eta_abs, double eta_rel) {
  if (!p) return CUP_ERR_ARG;
  if (!(eps_abs >= 0) || !(eps_rel >= 0) || !(eta_abs >= 0) || !(eta_rel >= 0))
    return CUP_ERR_ARG;
  p->opt.eps_abs = eps_abs; p->opt.eps_rel = eps_rel;
  p->opt.eta_abs = eta_abs; p->opt.eta_rel = eta_rel;
  return CUP_OK;
}

int cup_projector_offer_feasible(cup_projector *p, const double *w) {
  if (!p || !w) return 0;
  for (int j = 0; j < p->n; j++)
    if (!isfinite(w[j])) return 0;
  if (cup_slack(p->K, p->g, w, p->s_anchor, p->gamv) < 0) return 0;
  cup_copy(p->anchor, w, p->n);
  p->anchor_ok = 1;
  return 1;
}

void cup_projector_reset(cup_projector *p) {
  if (p && p->m) memset(p->lam_warm, 0, sizeof(double) * (size_t)p->m);
  if (p && p->small) cup_lcp_forget(&p->small->lcp);
}

const double *cup_projector_lambda(const cup_projector *p) { return p ? p->lam : NULL; }
const double *cup_projector_feasible(const cup_projector *p) {
  return p && p->has_v ? p->v : NULL;
}
const double *cup_projector_farkas(const cup_projector *p) { return p ? p->farkas : NULL; }

/* ---- linear algebra on the projector's workspace ------------------------------ */

void cup_metric_solve(cup_projector *p, double *v) {
  const cup_polyset *K = p->K;
  if (K->pkind == CUP_METRIC_SPARSE) cup_simplicial_solve(K->LP, v, p->wn2);
  else cup_metric_solve_diag(K, v);
}

void cup_eval_primal(cup_projector *p, const double *x, const double *g, const double *lam,
                     double *y, double *s, double *gam) {
  const cup_polyset *K = p->K;
  int n = p->n;
  if (K->dense) {
    memset(p->u, 0, sizeof(double) * (size_t)n);
    for (int i = 0; i < p->m; i++) {
      double li = lam[i];
      if (li == 0) continue;
      const double *bt = K->Bt + (size_t)i * n;
      for (int j = 0; j < n; j++) p->u[j] += bt[j] * li;
    }
  } else {
    cup_sparse_gatxy(&K->C, lam, p->u);     /* C^T lam by column gathers */
    cup_metric_solve(p, p->u);
  }
  for (int j = 0; j < n; j++) y[j] = x[j] + p->u[j];
  cup_slack(K, g, y, s, gam);
}

/* ---- certificates ------------------------------------------------------------- */

/* Check a trial point: slack and rounding bound into sv/gamv; 1 if certainly
 * feasible. */
static int verify_feasible(cup_projector *p, const double *w) {
  return cup_slack(p->K, p->g, w, p->sv, p->gamv) >= 0;
}

/* Is a stored anchor (user point or last feasible point) valid for the
 * current offset? Checks lazily after the offset changed. */
static int anchor_valid(cup_projector *p, const double *w, double *sw, int *state) {
  if (*state == -1) {
    double *gw = p->gamv;
    *state = cup_slack(p->K, p->g, w, sw, gw) >= 0 ? 1 : 0;
  }
  return *state == 1;
}

/* Segment z -> w (w certainly feasible with slack sw): the first point whose
 * slack beats its rounding bound. Writes the trial into p->wn; returns the
 * distance ||z - trial||_P, or INFINITY. */
static double segment_to(cup_projector *p, const double *z, const double *w,
                         const double *sw) {
  double t = 0;
  for (int i = 0; i < p->m; i++) {
    double si = p->s[i], gi = p->gam[i];
    if (si - gi >= 0) continue;
    if (sw[i] > 3 * gi) t = fmax(t, (3 * gi - si) / (sw[i] - si));
    else t = 1;
  }
  if (!(t <= 1)) t = 1;
  for (int j = 0; j < p->n; j++) p->wn[j] = z[j] + t * (w[j] - z[j]);
  if (t < 1 && !verify_feasible(p, p->wn)) {
    t = 1;
    memcpy(p->wn, w, sizeof(double) * (size_t)p->n);
    if (!verify_feasible(p, p->wn)) return INFINITY;
  } else if (t == 1 && !verify_feasible(p, p->wn)) {
    return INFINITY;
  }
  for (int j = 0; j < p->n; j++) p->wn2[j] = p->wn[j] - z[j];
  return cup_polyset_norm(p->K, p->wn2);
}

/* Push along the interior direction d (C d > 0): v = z + theta d. */
static double push_along_direction(cup_projector *p, const double *z) {
  const cup_polyset *K = p->K;
  if (!K->rdir) return INFINITY;
  double theta = 0;
  for (int i = 0; i < p->m; i++) {
    double si = p->s[i], gi = p->gam[i];
    if (si - gi >= 0) continue;
    if (!(K->Crdir[i] > 0)) return INFINITY;
    theta = fmax(theta, (3 * gi - si) / K->Crdir[i]);
  }
  for (int attempt = 0; attempt < 4; attempt++) {
    for (int j = 0; j < p->n; j++) p->wn[j] = z[j] + theta * K->rdir[j];
    if (verify_feasible(p, p->wn)) return theta * K->rdir_norm * (1 + 8 * U);
    theta = 2 * theta + DBL_MIN;
  }
  return INFINITY;
}

/* Keep the trial point in p->wn (slack in p->sv) if it is the nearest yet. */
static void keep_candidate(cup_projector *p, double dist, double *best) {
  if (dist < *best) {
    *best = dist;
    cup_copy(p->v, p->wn, p->n);
    cup_copy(p->s_v, p->sv, p->m);
    p->has_v = 1;
  }
}

/* A bound on ||z - y(lam)||_P for z = fl(x + u): a few ulps of ||x||_P <= scale
 * and of ||u||_P = un, times P's condition for a sparse metric (its solve is
 * backward stable). */
static double z_rounding(const cup_polyset *K, double scale, double un) {
  return 8 * U * (scale + K->solve_amp * un);
}

/* ||z - x||_P (scratch p->wn2). */
static double step_norm(cup_projector *p, const double *z, const double *x) {
  for (int j = 0; j < p->n; j++) p->wn2[j] = z[j] - x[j];
  return cup_polyset_norm(p->K, p->wn2);
}

int cup_certify(cup_projector *p, const double *x, const double *lam,
                const double *z, cup_proj_info *info) {
  const cup_polyset *K = p->K;
  int n = p->n, m = p->m;
  /* z = fl(x + u): the exact y(lam) = x + P^-1 C^T lam differs from z by e,
   * bounded elementwise by a few ulps of |x| + |u| (times P's condition for
   * a sparse metric, whose solve is backward stable). */
  double un = z != x ? step_norm(p, z, x) : 0;   /* ||z - x||_P = ||u||_P */
  double ebound = z_rounding(K, info->scale, un);
  double eps_z = ebound * ebound, viol = 0, worst = INFINITY, dq = 0;
  for (int i = 0; i < m; i++) {
    eps_z += 2 * lam[i] * (p->s[i] + p->gam[i]);
    viol = cup_max(viol, -p->s[i]);
    double sl = p->s[i] - p->gam[i];
    if (isnan(sl) || sl < worst) worst = sl;   /* a NaN row stays the minimum */
    dq -= 2 * lam[i] * p->b[i];
  }
  info->violation = viol;
  info->eps_cert = isnan(eps_z) ? NAN : cup_max(eps_z, 0);
  /* 2 q(lambda) = -||u||_P^2 - 2 lam^T b, reported as a lower bound on d^2. */
  info->dual_value = dq - un * un;

  p->has_v = 0;
  double eta = INFINITY;
  /* d_K(z) >= max_i violation_i / ||c_i||_{P^-1} (each halfspace contains K):
   * when that already exceeds the target, no anchor can help */
  double dlow = 0;
  for (int i = 0; i < m; i++)
    if (p->s[i] < 0 && K->rownorm[i] > 0) dlow = cup_max(dlow, -p->s[i] / K->rownorm[i]);
  if (worst >= 0) {
    eta = 0;
  } else if (dlow > info->eta_target) {
    eta = INFINITY;
  } else {
    double best = INFINITY;
    keep_candidate(p, push_along_direction(p, z), &best);
    if (!(best <= info->eta_target) && p->make_inward && !p->has_inward) {
      int it = p->iters;
      p->make_inward(p);               /* certification work, not dual iterations */
      p->iters = it;
    }
    if (!(best <= info->eta_target) && p->has_inward &&
        cup_slack(K, p->g, p->inward, p->s_inward, p->gamv) >= 0)
      keep_candidate(p, segment_to(p, z, p->inward, p->s_inward), &best);
    if (!(best <= info->eta_target) && p->user_pt &&
        anchor_valid(p, p->user_pt, p->s_user, &p->user_ok))
      keep_candidate(p, segment_to(p, z, p->user_pt, p->s_user), &best);
    if (!(best <= info->eta_target) &&
        anchor_valid(p, p->anchor, p->s_anchor, &p->anchor_ok))
      keep_candidate(p, segment_to(p, z, p->anchor, p->s_anchor), &best);
    eta = best;
  }
  info->eta_cert = eta;
  if (p->opt.return_feasible && p->has_v) {
    /* eps for v: 2 lam^T s(v) + ||v - y||_P^2, no cancellation; s(v) is
     * at most s_v plus its rounding bound */
    verify_feasible(p, p->v);
    double ev = 0;
    for (int i = 0; i < m; i++) ev += 2 * lam[i] * (p->sv[i] + p->gamv[i]);
    double dv = eta + ebound;
    info->eps_cert = fmax(ev + dv * dv, 0);
    info->eta_cert = 0;
  }
  /* Remember a certainly feasible point as the next anchor. */
  if (worst >= 0 || p->has_v) {
    cup_copy(p->anchor, worst >= 0 ? z : p->v, n);
    cup_copy(p->s_anchor, worst >= 0 ? p->s : p->s_v, m);
    p->anchor_ok = 1;
  }
  return info->eps_cert <= info->eps_target && info->eta_cert <= info->eta_target;
}

int cup_farkas_test(cup_projector *p, const double *dlam, cup_proj_info *info) {
  const cup_polyset *K = p->K;
  double sum = 0, gy = 0;
  for (int i = 0; i < p->m; i++) {
    if (dlam[i] < 0) return 0;
    sum += dlam[i];
    gy += p->g[i] * dlam[i];
  }
  if (!(sum > 0) || !(gy < 0)) return 0;
  cup_sparse_gatxy(&K->C, dlam, p->wn);          /* r = C^T y */
  memcpy(p->u, p->wn, sizeof(double) * (size_t)p->n);
  cup_metric_solve(p, p->u);                     /* ||r||_{P^-1}^2 = r^T P^-1 r */
  double rr = sqrt(fmax(cup_dot(p->wn, p->u, p->n), 0));
  double radius = rr > 0 ? -gy / rr : INFINITY;
  if (!(radius > 1e6 * fmax(info->scale, DBL_MIN))) return 0;
  for (int i = 0; i < p->m; i++) p->farkas[i] = dlam[i] / sum;
  info->farkas_gap = gy / sum;
  info->farkas_residual = rr / sum;
  return 1;
}

/* ---- the projection ----------------------------------------------------------- */

/* Small dense sets, auto method: the dual LCP solved exactly by principal
 * pivoting (closed form on one or two active rows), the rows aimed a few
 * ulps inside K: the LCP step (lcp/step.h) with W = I and h = 1. z is then
 * certainly in K (eta = 0) and eps is the weak-duality gap, as cup_certify
 * computes it. Returns 1 with z and info filled when that certifies the
 * targets; 0 leaves everything to the general path (a singular block, a
 * set without interior, a tolerance below rounding). */
static int project_small(cup_projector *p, const double *x, double *z, cup_proj_info *info) {
  const cup_polyset *K = p->K;
  int n = p->n, m = p->m;
  if (!p->opt.warm_start) cup_lcp_forget(&p->small->lcp);
  cup_proj_info ti;
  if (cup_lcp_step_solve(p->small, p->g, x, p->y, info->scale, info->eps_target, info->eta_target,
                         &ti))
    return 0;
  double un = ti.skipped ? 0 : step_norm(p, p->y, x);   /* ||z - x||_P */
  double ebound = ti.skipped ? 0 : z_rounding(K, info->scale, un);
  double eps = ti.eps_cert + ebound * ebound;
  if (!(eps <= info->eps_target)) return 0;
  info->eps_cert = eps;
  info->eta_cert = ti.eta_cert;
  info->violation = ti.violation;
  info->dual_value = -2 * p->small->lq - un * un;
  info->skipped = ti.skipped;
  info->iterations = ti.iterations;
  info->active = ti.active;
  info->method = ti.skipped ? p->opt.method : CUP_PROJ_ACTIVESET;
  memcpy(p->lam, p->small->lcp.lam, sizeof(double) * (size_t)m);
  if (p->opt.warm_start && !ti.skipped) memcpy(p->lam_warm, p->lam, sizeof(double) * (size_t)m);
  memcpy(z, p->y, sizeof(double) * (size_t)n);
  info->status = CUP_OK;
  return 1;
}

int cup_project(cup_projector *p, const double *x, double *z, cup_proj_info *info_out) {
  cup_proj_info local;
  cup_proj_info *info = info_out ? info_out : &local;
  *info = (cup_proj_info){.eta_cert = INFINITY};
  if (!p || !x || !z) return info->status = CUP_ERR_ARG;
  const cup_polyset *K = p->K;
  int n = p->n, m = p->m;
  for (int j = 0; j < n; j++)
    if (!isfinite(x[j])) return info->status = CUP_ERR_NONFINITE;
  p->has_v = 0;
  p->has_inward = 0;
  p->make_inward = NULL;
  p->iters = p->facts = p->updates = 0;
  double S = cup_max(cup_polyset_norm(K, x), p->gscale);
  if (!isfinite(S)) return info->status = CUP_ERR_DIVERGED;   /* ||x||_P overflowed */
  info->scale = S;
  info->eps_target = p->opt.eps_abs + (p->opt.eps_rel > 0 ? p->opt.eps_rel * S * S : 0);
  info->eta_target = p->opt.eta_abs + (p->opt.eta_rel > 0 ? p->opt.eta_rel * S : 0);
  info->method = p->opt.method;
  if (p->empty_row >= 0) {                 /* a row 0 >= -g_i with g_i < 0 */
    memset(p->farkas, 0, sizeof(double) * (size_t)m);
    p->farkas[p->empty_row] = 1;
    info->farkas_gap = p->g[p->empty_row];
    info->farkas_residual = 0;
    return info->status = CUP_ERR_EMPTY_SET;
  }
  if (p->small && !p->user_pt && !p->opt.return_feasible && project_small(p, x, z, info))
    return CUP_OK;
  cup_slack(K, p->g, x, p->b, p->gam);
  double worst_raw = INFINITY;
  for (int i = 0; i < m; i++) worst_raw = cup_min(worst_raw, p->b[i]);
  if (worst_raw >= 0) {                    /* x in K: returned unchanged, exactly */
    if (z != x) cup_copy(z, x, n);
    cup_zero(p->lam, m);
    info->skipped = 1;
    double worst = INFINITY;
    for (int i = 0; i < m; i++) worst = cup_min(worst, p->b[i] - p->gam[i]);
    if (worst >= 0) {                      /* certainly inside: nothing to certify */
      info->eta_cert = info->eps_cert = 0;
      cup_copy(p->anchor, x, n);           /* and a good anchor for later */
      cup_copy(p->s_anchor, p->b, m);
      p->anchor_ok = 1;
      return info->status = CUP_OK;
    }
    cup_copy(p->s, p->b, m);
    cup_certify(p, x, p->lam, x, info);
    info->eps_cert = 0;                    /* z = x exactly: no excess at all */
    info->status = info->eta_cert <= info->eta_target ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
    return info->status;
  }
  int method = p->opt.method, st;
  if (method == CUP_PROJ_AUTO || method == CUP_PROJ_ACTIVESET)
    st = K->dense ? cup_proj_dense_activeset(p, x, info) : cup_proj_sparse_newton(p, x, info);
  else {
    if (p->opt.warm_start) memcpy(p->lam, p->lam_warm, sizeof(double) * (size_t)m);
    else memset(p->lam, 0, sizeof(double) * (size_t)m);
    st = cup_proj_firstorder(p, x, method == CUP_PROJ_FISTA, p->opt.max_iter, info);
  }
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

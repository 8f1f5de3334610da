/* polyball — the P-metric projection onto S = K ∩ B, K = {C x + g >= 0},
 * B = {||x - c||_P <= r}.
 *
 * For the ball's multiplier mu >= 0, ||z - x||^2 + mu (||z - c||^2 - r^2)
 * = (1 + mu) ||z - x_mu||^2 + mu/(1 + mu) ||x - c||^2 - mu r^2 with
 * x_mu = (x + mu c)/(1 + mu), so the inner minimum over K is a polyset
 * projection of x_mu, and weak duality gives, for any mu >= 0,
 *     d_S(x)^2 >= (1 + mu) d_K(x_mu)^2 + mu/(1 + mu) ||x - c||^2 - mu r^2,
 * a lower bound computable from the polyset projector's own (d_K^2 >=
 * dual_value). With s = mu/(1 + mu), x_s = (1 - s) x + s c walks from x to c
 * and phi(s) = ||proj_K(x_s) - c||_P - r is nonincreasing (the dual is
 * concave in mu): regula falsi (Illinois) on s in [0, 1] finds its root,
 * one polyset projection per trial, warm-started.
 *
 * The answer is always a point certainly in S: the polyset's answer when it
 * is, else the point where the segment from it to an anchor (the projection
 * of c onto K, which is in S whenever S is not empty) enters the ball. If
 * that projection of c is farther than r from c by a certified margin, S is
 * empty: CUP_ERR_EMPTY_SET. The kind intersection's table ends the file. */
#include <float.h>
#include <math.h>
#include <string.h>
#include "catchup.h"
#include "setproj_impl.h"

#define U DBL_EPSILON

static int in_rows(cup_setproj *sp, const double *y) {
  return sp->m == 0 || polyset_slack(sp->S->K, sp->g, y, sp->sm, sp->gm) >= 0;
}

/* ||a - b||_P from above (and below, lo may be NULL); scratch: work + 2n. */
static double dist_hi(cup_setproj *sp, const double *a, const double *b, double *lo) {
  return polyset_metric_dist_hi(sp->S->K, a, b, lo, sp->work + 2 * (size_t)sp->n);
}

static int in_ball(cup_setproj *sp, const double *y) { return dist_hi(sp, y, sp->c, NULL) <= sp->r; }

/* y pushed along the polyset's interior direction d (C d > 0) just far
 * enough that every row holds beyond its rounding, as lcp/step_solve.c's eta
 * certificate does, into out (may alias y): 1 when that point is certainly
 * in the rows. A point on a face (the polyset's answer for a point of that
 * face) is not certainly in them; this one is, a rounding away. */
static int push_inside(cup_setproj *sp, const double *y, double *out) {
  const cup_polyset *K = sp->S->K;
  if (!K->rdir || sp->m == 0) return 0;
  polyset_slack(K, sp->g, y, sp->sm, sp->gm);
  double t = 0;
  for (int i = 0; i < sp->m; i++)
    if (sp->sm[i] - sp->gm[i] < 0) {
      if (!(K->Crdir[i] > 0)) return 0;
      t = fmax(t, (3 * sp->gm[i] - sp->sm[i]) / K->Crdir[i]);
    }
  for (int j = 0; j < sp->n; j++) out[j] = y[j] + t * K->rdir[j];
  return in_rows(sp, out);
}

/* Project y onto K to absolute targets (and rounding-level relative ones). */
static int onto_rows(cup_setproj *sp, const double *y, double *out, double eps, double eta,
                     cup_proj_info *pi) {
  cup_projector_set_tolerances(sp->proj, eps, 1e-15, eta, 1e-13);
  return cup_project(sp->proj, y, out, pi);
}

/* The projection of c onto K as the anchor; 1 if it is certainly in S, 0
 * if not (K and B only touch, to rounding), or CUP_ERR_EMPTY_SET. */
static int anchor(cup_setproj *sp, double eta) {
  if (sp->anchor_ok >= 0) return sp->anchor_ok;
  cup_proj_info pi;
  int st = onto_rows(sp, sp->c, sp->anchor, 0, eta, &pi);
  if (st == CUP_ERR_EMPTY_SET)
    return setproj_fail(sp, st, "the polyset is empty: Farkas certificate y >= 0 with g^T y = %.3g, "
                        "||C^T y||_{P^-1} = %.3g", pi.farkas_gap, pi.farkas_residual);
  if (st < 0) return setproj_fail(sp, st, "projecting the centre onto the polyset failed: %s", cup_status_string(st));
  if (!in_rows(sp, sp->anchor)) {
    const double *v = cup_projector_feasible(sp->proj);
    if (v) la_copy(sp->anchor, v, sp->n);
    else push_inside(sp, sp->anchor, sp->anchor);   /* the centre's projection on a face */
  }
  sp->anchor_ok = in_rows(sp, sp->anchor) && in_ball(sp, sp->anchor);
  double dlow = sqrt(fmax(pi.dual_value, 0)) * (1 - 1e-12);
  if (!sp->anchor_ok && dlow > sp->r)
    return setproj_fail(sp, CUP_ERR_EMPTY_SET,
                        "the polyset and the ball do not meet: the centre is at least %.6g from "
                        "the polyset, the radius is %.6g", dlow, sp->r);
  return sp->anchor_ok;
}

/* A point certainly in S near y (y's polyset answer came with pfeas, an
 * exactly feasible point of K, or NULL) into sp->v; 0 if none was found. */
static int feasible_near(cup_setproj *sp, const double *y, const double *pfeas, double eta) {
  int n = sp->n;
  const double *base = in_rows(sp, y) ? y : pfeas && in_rows(sp, pfeas) ? pfeas
                    : push_inside(sp, y, sp->v) ? sp->v : NULL;   /* y on a face */
  if (!base) return 0;
  if (in_ball(sp, base)) { la_copy(sp->v, base, n); return 1; }
  if (anchor(sp, eta) != 1) return 0;
  /* a + t (base - a) on the sphere: alpha t^2 + 2 beta t + gamma = 0, gamma < 0 */
  double *d = sp->work + 3 * (size_t)n, *ac = sp->v;
  for (int j = 0; j < n; j++) { d[j] = base[j] - sp->anchor[j]; ac[j] = sp->anchor[j] - sp->c[j]; }
  double dn = cup_polyset_norm(sp->S->K, d), an = cup_polyset_norm(sp->S->K, ac);
  double beta = 0;
  double *pd = sp->work + 2 * (size_t)n;
  polyset_metric_apply(sp->S->K, d, pd);
  for (int j = 0; j < n; j++) beta += ac[j] * pd[j];
  double alpha = dn * dn, gamma = an * an - sp->r * sp->r;
  double t = alpha > 0 ? (-beta + sqrt(fmax(beta * beta - alpha * gamma, 0))) / alpha : 0;
  t = fmin(t, 1);
  for (int tries = 0; tries < 6; tries++, t *= 1 - 1e-9 * (1 << (2 * tries))) {
    for (int j = 0; j < n; j++) sp->v[j] = sp->anchor[j] + t * d[j];
    if (in_rows(sp, sp->v) && in_ball(sp, sp->v)) return 1;
  }
  la_copy(sp->v, sp->anchor, n);
  return 1;
}

/* Certify the feasible point sp->v against the lower bound lb on d_S(x)^2;
 * keep it in `best` if its eps is the smallest yet. Returns 1 when certified. */
static int judge(cup_setproj *sp, const double *x, double lb, double *best, double *best_eps,
                 cup_proj_info *info) {
  double e = dist_hi(sp, x, sp->v, NULL);
  e = fmax(0, e * e - fmax(lb, 0));
  if (e < *best_eps) {
    *best_eps = e;
    la_copy(best, sp->v, sp->n);
    info->dual_value = fmax(lb, 0);
  }
  return e <= info->eps_target;
}

/* The best certified point into z; without one, an error (z untouched:
 * never an uncertified point passed on as an answer). */
static int finish(cup_setproj *sp, double *z, const double *best, double best_eps, cup_proj_info *info) {
  if (!(best_eps < INFINITY))
    return info->status = setproj_fail(sp, CUP_ERR_UNCERTIFIED, "the intersection of the polyset and the "
                                       "ball: no point certainly in both was found (eta = inf)");
  la_copy(z, best, sp->n);
  info->eps_cert = best_eps;
  info->eta_cert = 0;
  info->status = best_eps <= info->eps_target ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
  return info->status;
}

static int project(cup_setproj *sp, const double *x, double *z, cup_proj_info *info) {
  const cup_polyset *K = sp->S->K;
  int n = sp->n;
  double *xs = sp->work, *best = sp->work + n;
  setproj_targets(sp, fmax(cup_polyset_norm(K, x), cup_polyset_norm(K, sp->c) + sp->r), info);
  double et = info->eps_target, ht = info->eta_target, best_eps = INFINITY;
  la_copy(sp->xs, x, n);                          /* z may alias x */
  x = sp->xs;
  cup_proj_info pi;
  /* mu = 0: the ball may not be active */
  int st = onto_rows(sp, x, sp->zk, 0.25 * et, 0.25 * ht, &pi);
  if (st == CUP_ERR_EMPTY_SET)
    return setproj_fail(sp, info->status = st, "the polyset is empty: Farkas certificate y >= 0 with "
                        "g^T y = %.3g, ||C^T y||_{P^-1} = %.3g", pi.farkas_gap, pi.farkas_residual);
  if (st < 0) return setproj_fail(sp, info->status = st, "polyset projection failed: %s", cup_status_string(st));
  info->iterations = pi.iterations;
  double xc_lo, xc = dist_hi(sp, x, sp->c, &xc_lo);
  (void)xc;
  double phi_lo = dist_hi(sp, sp->zk, sp->c, NULL) - sp->r;
  if (phi_lo <= 0) {
    info->skipped = pi.skipped;
    if (feasible_near(sp, sp->zk, cup_projector_feasible(sp->proj), ht))
      judge(sp, x, pi.dual_value, best, &best_eps, info);
    else if (anchor(sp, ht) < 0)
      return info->status = CUP_ERR_EMPTY_SET;
    return finish(sp, z, best, best_eps, info);
  }
  /* the ball is active: the bracket's other end is the centre's projection */
  int a = anchor(sp, ht);
  if (a < 0) return info->status = a;
  if (a == 0) return finish(sp, z, best, best_eps, info);   /* K and B only touch */
  double phi_hi = dist_hi(sp, sp->anchor, sp->c, NULL) - sp->r;
  double s_lo = 0, s_hi = 1;
  int side = 0;
  info->active = 1;
  for (int it = 0; it < 100 && s_hi - s_lo > 4 * U; it++) {
    double s = s_hi - phi_hi * (s_hi - s_lo) / (phi_hi - phi_lo);
    if (!(s > s_lo && s < s_hi)) s = 0.5 * (s_lo + s_hi);
    double one_mu = 1 / (1 - s);                     /* 1 + mu */
    for (int j = 0; j < n; j++) xs[j] = (1 - s) * x[j] + s * sp->c[j];
    st = onto_rows(sp, xs, sp->zk, 0.25 * et / one_mu, 0.25 * ht, &pi);
    if (st < 0) return setproj_fail(sp, info->status = st, "polyset projection failed: %s", cup_status_string(st));
    info->iterations += pi.iterations;
    double lb = pi.dual_value * one_mu + s * xc_lo * xc_lo - s * one_mu * sp->r * sp->r;
    if (feasible_near(sp, sp->zk, cup_projector_feasible(sp->proj), ht) &&
        judge(sp, x, lb, best, &best_eps, info))
      break;
    double phi = dist_hi(sp, sp->zk, sp->c, NULL) - sp->r;
    if (phi > 0) {
      s_lo = s; phi_lo = phi;
      if (side == 1) phi_hi *= 0.5;                  /* Illinois: the stale end counts half */
      side = 1;
    } else {
      s_hi = s; phi_hi = phi;
      if (side == -1) phi_lo *= 0.5;
      side = -1;
    }
  }
  return finish(sp, z, best, best_eps, info);
}

/* The projector onto the rows; its tolerances are set at each trial (onto_rows). */
static int create(cup_setproj *sp, char *errmsg) {
  return cup_projector_create(&sp->proj, sp->S->K, &sp->opt, errmsg);
}

const setproj_kind setproj_intersection = {.create = create, .place = setproj_place_affine, .project = project,
                                           .own_tolerances = 1};

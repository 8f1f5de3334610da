/* certify — what every projection method returns through: the primal point
 * of a dual iterate, the certificates of a candidate (paper, Sec. 2: eps by
 * weak duality, eta by a certainly feasible point nearby) and the Farkas
 * test of an empty K. Below the methods (firstorder.c, activeset.c,
 * newton.c) and the dispatcher (projector.c), which all call it. */
#include <float.h>
#include <math.h>
#include <string.h>
#include "catchup.h"
#include "certify.h"

#define U DBL_EPSILON

/* ---- linear algebra on the projector's workspace ------------------------------ */

void certify_metric_solve(cup_projector *p, double *v) {
  const cup_polyset *K = p->K;
  if (K->pkind == CUP_METRIC_SPARSE) la_simplicial_solve(K->LP, v, p->wn2);
  else polyset_metric_solve_diag(K, v);
}

void certify_eval_primal(cup_projector *p, const double *x, const double *g, const double *lam,
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
  } else if (K->pkind == CUP_METRIC_DIAGONAL) {   /* one pass: u = P^-1 C^T lam, y = x + u */
    la_sparse_gatxy(&K->C, lam, p->u);
    const double *di = K->pdinv;
    for (int j = 0; j < n; j++) {
      p->u[j] *= di[j];
      y[j] = x[j] + p->u[j];
    }
    polyset_slack(K, g, y, s, gam);
    return;
  } else {
    la_sparse_gatxy(&K->C, lam, p->u);     /* C^T lam by column gathers */
    certify_metric_solve(p, p->u);
  }
  for (int j = 0; j < n; j++) y[j] = x[j] + p->u[j];
  polyset_slack(K, g, y, s, gam);
}

/* ---- certificates ------------------------------------------------------------- */

/* Check a trial point: slack and rounding bound into sv/gamv; 1 if certainly
 * feasible. */
static int verify_feasible(cup_projector *p, const double *w) {
  return polyset_slack(p->K, p->g, w, p->sv, p->gamv) >= 0;
}

/* Is a stored anchor (user point or last feasible point) valid for the
 * current offset? Checks lazily after the offset changed. */
static int anchor_valid(cup_projector *p, const double *w, double *sw, int *state) {
  if (*state == -1) {
    double *gw = p->gamv;
    *state = polyset_slack(p->K, p->g, w, sw, gw) >= 0 ? 1 : 0;
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

/* z with the coordinates that are rounding next to its largest (|z_j| <=
 * 64 u max |z|) set to 0. A set without interior pins coordinates to 0
 * exactly (a current between two diodes' rows i >= 0 and -i >= 0): no
 * point of a segment to an anchor is certainly in it but the anchor
 * itself, so segment_to walks the whole way (the full bridge's first theta
 * step from v(C1) = -50 V: 0.0725 for a z whose i(L1) = -1.6e-15 is
 * 5e-17 from K), while z snapped onto those zeros may be certainly in K
 * (slack exactly 0, its rounding bound 0). A bound, whatever the snap:
 * d_K(z) <= ||z - w||_P for the w verify_feasible finds in K, and the
 * distance is polyset_metric_dist_hi's upper bound. INFINITY if none. */
static double snap_zeros(cup_projector *p, const double *z) {
  double big = 0;
  for (int j = 0; j < p->n; j++) big = fmax(big, fabs(z[j]));
  double tiny = 64 * U * big;
  int moved = 0;
  for (int j = 0; j < p->n; j++) {
    p->wn[j] = fabs(z[j]) <= tiny ? 0 : z[j];
    moved |= p->wn[j] != z[j];
  }
  if (!moved || !verify_feasible(p, p->wn)) return INFINITY;
  return polyset_metric_dist_hi(p->K, z, p->wn, NULL, p->wn2);
}

/* Keep the trial point in p->wn (slack in p->sv) if it is the nearest yet. */
static void keep_candidate(cup_projector *p, double dist, double *best) {
  if (dist < *best) {
    *best = dist;
    la_copy(p->v, p->wn, p->n);
    la_copy(p->s_v, p->sv, p->m);
    p->has_v = 1;
  }
}

/* Weak duality holds for lam+ = max(lam, 0) only. With z = y(lam) and
 * dl = lam+ - lam, ||x - z||_P^2 - 2 q(lam+) = 2 lam+^T s(z) + dl^T M dl,
 * and dl^T M dl = ||C^T dl||_{P^-1}^2 <= (sum_i dl_i ||c_i||_{P^-1})^2: a
 * finishing solve leaves rounding-sized negative multipliers on the
 * degenerate rows of a jam, and clipping them would move z. Recomputes
 * eps's and q's sums (eps from e0) at lam+; returns that sum of dl_i
 * ||c_i||, rounded up for the row norms' and its own rounding. */
static double positive_part(const cup_projector *p, const double *lam, double e0,
                            double *eps_z, double *dq) {
  double e = e0, q = 0, clip = 0;
  for (int i = 0; i < p->m; i++) {
    double lp = la_max(lam[i], 0);
    e += 2 * lp * (p->s[i] + p->gam[i]);
    q -= 2 * lp * p->b[i];
    clip += (lp - lam[i]) * p->K->rownorm[i];
  }
  *eps_z = e;
  *dq = q;
  return clip * (1 + 64 * U * p->K->solve_amp + 2 * p->m * U);
}

int certify_candidate(cup_projector *p, const double *x, const double *lam,
                      const double *z, cup_proj_info *info) {
  const cup_polyset *K = p->K;
  int n = p->n, m = p->m;
  /* z = fl(x + u): the exact y(lam) = x + P^-1 C^T lam differs from z by e,
   * bounded elementwise by a few ulps of |x| + |u| (times P's condition for
   * a sparse metric, whose solve is backward stable). */
  double un = z != x ? certify_step_norm(p, z, x) : 0;   /* ||z - x||_P = ||u||_P */
  double ebound = certify_z_rounding(K, info->scale, un);
  double eps_z = ebound * ebound, viol = 0, worst = INFINITY, dq = 0, lmin = 0;
  for (int i = 0; i < m; i++) {
    eps_z += 2 * lam[i] * (p->s[i] + p->gam[i]);
    viol = la_max(viol, -p->s[i]);
    double sl = p->s[i] - p->gam[i];
    if (isnan(sl) || sl < worst) worst = sl;   /* a NaN row stays the minimum */
    dq -= 2 * lam[i] * p->b[i];
    lmin = la_min(lmin, lam[i]);
  }
  double clip = lmin < 0 ? positive_part(p, lam, ebound * ebound, &eps_z, &dq) : 0;
  eps_z += clip * clip;
  info->violation = viol;
  info->eps_cert = isnan(eps_z) ? NAN : la_max(eps_z, 0);
  /* 2 q(lam+) = -||u(lam+)||_P^2 - 2 lam+^T b with ||u(lam+)||_P <= un + clip
   * (= ||u||_P for lam >= 0), reported as a lower bound on d^2. */
  info->dual_value = dq - (un + clip) * (un + clip);

  p->has_v = 0;
  double eta = INFINITY;
  /* d_K(z) >= max_i violation_i / ||c_i||_{P^-1} (each halfspace contains K):
   * when that already exceeds the target, no anchor can help */
  double dlow = 0;
  for (int i = 0; i < m; i++)
    if (p->s[i] < 0 && K->rownorm[i] > 0) dlow = la_max(dlow, -p->s[i] / K->rownorm[i]);
  if (worst >= 0) {
    eta = 0;
  } else if (dlow > info->eta_target) {
    eta = INFINITY;
  } else {
    double best = INFINITY;
    keep_candidate(p, push_along_direction(p, z), &best);
    /* the origin, when g > 0 puts it inside K: free, unlike the inward
     * anchor below (a second solve; ladders of diodes: a sixth of the work) */
    if (!(best <= info->eta_target) && p->origin_ok)
      keep_candidate(p, segment_to(p, z, p->origin, p->g), &best);
    if (!(best <= info->eta_target) && p->make_inward && !p->has_inward) {
      int it = p->iters;
      p->make_inward(p, p->inward_ws);   /* certification work, not dual iterations */
      p->iters = it;
    }
    if (!(best <= info->eta_target) && p->has_inward &&
        polyset_slack(K, p->g, p->inward, p->s_inward, p->gamv) >= 0)
      keep_candidate(p, segment_to(p, z, p->inward, p->s_inward), &best);
    if (!(best <= info->eta_target) && p->user_pt &&
        anchor_valid(p, p->user_pt, p->s_user, &p->user_ok))
      keep_candidate(p, segment_to(p, z, p->user_pt, p->s_user), &best);
    if (!(best <= info->eta_target) &&
        anchor_valid(p, p->anchor, p->s_anchor, &p->anchor_ok))
      keep_candidate(p, segment_to(p, z, p->anchor, p->s_anchor), &best);
    if (!(best <= info->eta_target)) keep_candidate(p, snap_zeros(p, z), &best);
    eta = best;
  }
  info->eta_cert = eta;
  if (p->opt.return_feasible && p->has_v) {
    /* eps for v: 2 lam+^T s(v) + ||v - y(lam+)||_P^2, no cancellation;
     * s(v) is at most s_v plus its rounding bound */
    verify_feasible(p, p->v);
    double ev = 0;
    for (int i = 0; i < m; i++) ev += 2 * la_max(lam[i], 0) * (p->sv[i] + p->gamv[i]);
    double dv = eta + ebound + clip;
    info->eps_cert = fmax(ev + dv * dv, 0);
    info->eta_cert = 0;
  }
  /* Remember a certainly feasible point as the next anchor. */
  if (worst >= 0 || p->has_v) {
    la_copy(p->anchor, worst >= 0 ? z : p->v, n);
    la_copy(p->s_anchor, worst >= 0 ? p->s : p->s_v, m);
    p->anchor_ok = 1;
  }
  return info->eps_cert <= info->eps_target && info->eta_cert <= info->eta_target;
}

int certify_farkas_test(cup_projector *p, const double *dlam, cup_proj_info *info) {
  const cup_polyset *K = p->K;
  double sum = 0, gy = 0;
  for (int i = 0; i < p->m; i++) {
    if (dlam[i] < 0) return 0;
    sum += dlam[i];
    gy += p->g[i] * dlam[i];
  }
  if (!(sum > 0) || !(gy < 0)) return 0;
  la_sparse_gatxy(&K->C, dlam, p->wn);          /* r = C^T y */
  memcpy(p->u, p->wn, sizeof(double) * (size_t)p->n);
  certify_metric_solve(p, p->u);                     /* ||r||_{P^-1}^2 = r^T P^-1 r */
  double rr = sqrt(fmax(la_dot(p->wn, p->u, p->n), 0));
  double radius = rr > 0 ? -gy / rr : INFINITY;
  if (!(radius > 1e6 * fmax(info->scale, DBL_MIN))) return 0;
  for (int i = 0; i < p->m; i++) p->farkas[i] = dlam[i] / sum;
  info->farkas_gap = gy / sum;
  info->farkas_residual = rr / sum;
  return 1;
}


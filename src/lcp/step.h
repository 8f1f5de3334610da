/* step — the LCP of one step onto a polyset K = {x : C x + g >= 0}:
 *     z = x_free + H lambda,  H = h W B,  B = P^-1 C^T,
 *     0 <= lambda  _|_  w = C z + g >= 0,   an LCP with M = C H.
 * With W = I and h = 1, z is the P-projection of x_free onto K and lambda
 * the projector's multipliers (its exact path for small dense sets); the
 * theta scheme (Moreau-Jean time stepping, as in Siconos's EulerMoreauOSI)
 * takes W = (I - h theta A)^-1 from its free step, theta = 0 being the
 * explicit catching-up step (M symmetric: the P-projection) and theta = 1/2
 * second order where the solution is smooth. The LCP is
 * solved exactly (lcp.h), warm-started from the previous active set, aiming
 * the rows a few ulps inside K so that the answer is certainly feasible;
 * dense, for sets with K->dense (m <= 64 rows and n <= 256). */
#ifndef CUP_LCP_STEP_H
#define CUP_LCP_STEP_H

#include <float.h>
#include <math.h>
#include "catchup/projection.h"
#include "catchup/status.h"
#include "util/lanes.h"
#include "util/linalg.h"
#include "util/ckpt.h"
#include "set/polyset_impl.h"
#include "lcp.h"
#include "block.h"
#include "mode.h"

/* Up to this many states and rows, without D, a step is first tried by code
 * unrolled for its sizes (the circuits' common case: a few ns instead of a
 * loop over sparse rows and a general pivoting solver); it does the same
 * arithmetic in the same order, so z, lambda and the certificates are those
 * of the general path, which takes over for anything unusual (a singular
 * block, NaN, the exact mode eps_target < 0). */
#define CUP_STEP_SMALL_N 4
#define CUP_STEP_SMALL_M 2
typedef struct lcp_step {
  int n, m;
  double h;
  const cup_polyset *K;
  double *H;        /* n x m, column-major */
  double *M;        /* m x m, column-major */
  lcp_solver lcp;      /* lambda of the last step in lcp.lam */
  double *s, *gam, *v, *tau, *qs, *sv, *gamv;
  double lq;        /* lambda^T q of the last step (q: the free point's slack) */
  /* D != 0 (lcp_step_init_bd): w = C z + D lambda + g */
  double *D;        /* m x m, column-major, or NULL */
  double *geff;     /* g + D lambda: the offset the step's z must satisfy */
  double theta;
  double *WB;       /* n x m: W B, of which H is made by the weights below */
  double *Hprev;    /* n x m: h (1 - theta) W B (the trapezoid's old half; 0 where D's column is) */
  double *carry;    /* m: Pi zeta_k, the part of the last zeta that is a function of the state */
  double *xpred;    /* xf + Hprev carry */
  double *q0;       /* m: the free point's slack C xpred + g, kept for the step's re-solves */
  unsigned char *dcol0; /* D's column j is zero: zeta_j is never fixed by w, an impulse wherever it acts */
  unsigned long long mode; /* the support J of zeta (a bit per row) the weights were set for */
  int nker;         /* dim ker D_JJ, less the columns of dcol0 (weighted so already) */
  int *kcol;        /* its free columns t: the kernel vector z_t has z_t[t] = 1, 0 on the other t */
  double *Z;        /* m x nker: the kernel vectors z_t, column-major */
  double *work;     /* m x m + 2 m doubles and 3 m ints (kwork): the kernel's elimination */
  int *kwork;
  double *Ms;       /* m x m: M with rows scaled by rsc, which the LCP solves */
  double *rsc;      /* m: 1 / (largest entry of M's row); then q and q - tau so scaled */
  int warm;         /* 1: the step with D tries warm_d first (m <= LCP_BLOCKS_MAX_M; tests set 0) */
  int lam_sparse;   /* 1 (warm, and M and D finite: build_hm): a zero entry of lambda adds an exact zero */
  lcp_blocks blocks;   /* the warm step's active sets, emptied by build_hm */
  lcp_modes modes;     /* warm: the kernels and matrices of the modes met (set_mode) */
  double *wscr;     /* 5 m: the warm step's scaled q, aims, lambda and a solve */
  /* small sets (see CUP_STEP_SMALL_N): C's rows dense for the unrolled step */
  int small;        /* 1: lcp_step_solve tries the unrolled step first */
  v2d Ccol[CUP_STEP_SMALL_N];      /* C's columns, the rows in lanes, zeros included */
  v2d rowgam;                      /* K->rowgam, the rows in lanes */
  v2d Hcol[CUP_STEP_SMALL_M][2];   /* H's columns, the states in lanes (two pairs) */
  double det;                          /* M's determinant for m = 2, as the pivoting forms it */
} lcp_step;

/* W (n x n, column-major; NULL: the identity) and h give H and M. Returns
 * CUP_OK, CUP_ERR_UNSUPPORTED (K is not dense) or CUP_ERR_NOMEM; callers
 * write the message, in their own name. */
int lcp_step_init(lcp_step *ls, const cup_polyset *K, const double *W, double h);
/* The same for an LCS with D != 0 (Siconos's EulerMoreauOSI): B (n x m,
 * column-major) replaces P^-1 C^T in H = h W B Wt, M = C H + D (D m x m,
 * column-major); z satisfies C z + D lambda + g >= 0 and the certificates
 * below use g + D lambda; an M that is not a P-matrix (a monotone LCP) is
 * solved by Lemke's method. B NULL: P^-1 C^T; D NULL: lcp_step_init.
 * The weights Wt follow the step's mode, the support J of zeta: on J,
 * 0 = C_J x + D_JJ zeta_J + g_J fixes zeta_J up to ker D_JJ. The part of
 * zeta in ker D_JJ is not a function of the state but a multiplier of a
 * constraint on it (a diode with D = 0, or a loop of diodes, capacitors and
 * sources with no resistance: a bridge's skew coupling), a measure that
 * carries the state's jumps: it is taken whole at t_{k+1}, h W B, as
 * Moreau-Jean does. The rest, Pi zeta, is a function of the state, and the
 * trapezoid's weights keep theta = 1/2 second order on it: h theta W B in
 * H, and h (1 - theta) W B Pi zeta_k added to the free point. So every
 * impulse is taken once, whichever rows D couples. The kernel's free
 * columns carry the full weight (Pi is the projection along ker D_JJ onto
 * the other columns); a step whose solution has another support than the
 * weights were set for is solved again with that support's weights. */
int lcp_step_init_bd(lcp_step *ls, const cup_polyset *K, const double *W, double h,
                     const double *B, const double *D, double theta);
/* Before a run from x0 with offset g: zeta_0 from the LCP
 * 0 <= zeta _|_ C x0 + D zeta + g >= 0 (by Lemke's method), its support's
 * weights and the trapezoid's carry Pi zeta_0. Returns 1 when x0 is
 * consistent (that LCP has a solution; with D = 0: C x0 + g >= 0), 0 when
 * it is not (the state jumps at t = 0, in the first step). */
int lcp_step_start(lcp_step *ls, const double *x0, const double *g);
void lcp_step_free(lcp_step *ls);
/* What a step carries to the next (lambda, its warm start, lambda^T q), to
 * or from a checkpoint (util/ckpt.h). */
void lcp_step_checkpoint(lcp_step *ls, ckpt *c);
/* z from the free point xf for the offset g (scale: cup_polyset_norm of xf,
 * reported in info->scale); eps_target < 0 asks for the exact solution:
 * certified when the gap is below max(1e-12 scale^2, floor), the floor
 * being the gap of slacks at the rounding bound of forming z = xf + H lambda
 * and its slack, i.e. when the active rows' slacks are zero to rounding (a
 * relative target alone fails whenever lambda is large: stiff steps, jumps);
 * certificates in info:
 * eps_cert = 2 mu^T (s + gam) with the impulse mu = h lambda (the
 * complementarity gap, z = xf + W P^-1 C^T mu; for theta = 0 exactly the
 * projector's weak-duality certificate), eta_cert a certified distance of z
 * to K(t). Returns CUP_OK, CUP_WARN_NOT_CERTIFIED, CUP_ERR_LINALG (a
 * singular principal block: M not a P-matrix) or CUP_ERR_NONFINITE. */
int lcp_step_solve(lcp_step *ls, const double *g, const double *xf, double *z,
                   double scale, double eps_target, double eta_target, cup_proj_info *info);
/* A certified distance of z to K for the offset g, from the slack of z in
 * ls->s with rounding bounds ls->gam: 0 when z is certainly in K, else a
 * push along the polyset's direction into K, verified; INFINITY when
 * neither works. */
double lcp_step_eta(lcp_step *ls, const double *g, const double *z);
/* step.c's, for step_solve.c (with D): the weights and H, M for the
 * support J (1 when they changed, 0 when those in force were J's), and the
 * carry Pi zeta of the last zeta (aimed: solved with the aims tau). */
int set_mode(lcp_step *ls, unsigned long long J);
void carry_of(lcp_step *ls, int aimed);

/* ---- lcp_step_solve unrolled for a small set (CUP_STEP_SMALL_N
 * states, CUP_STEP_SMALL_M rows, no D), as always-inline
 * functions of compile-time sizes: step.c dispatches to them, and the
 * integrator's fused step (integrator/faststep.c) inlines them behind its
 * free step. They do the general path's arithmetic in the same order (a
 * zero entry of the dense rows adds an exact zero to finite sums), so z,
 * lambda and the certificates are the general path's; where that path would
 * meet anything unusual they decline, having changed only scratch. States
 * x_0..x_3 are the lanes of two v2d, (x_0, x_1) and (x_2, x_3); rows
 * the lanes of one; unused lanes hold zeros and are never read. */
#define CUP_ALWAYS_INLINE static inline __attribute__((always_inline))

/* What the unrolled step carries from one step to the next: lcp.lam, lq and
 * lcp.prev (as a bit mask), in registers while the fused steps run. */
typedef struct lcp_small_carry {
  v2d lam;
  double lq;
  unsigned act;
} lcp_small_carry;

/* A step's outcome: cup_proj_info's fields of the same names. */
typedef struct lcp_small_out {
  int status, skipped, iterations, active;
  double eps_cert, eta_cert, violation;
} lcp_small_out;

CUP_ALWAYS_INLINE lcp_small_carry lcp_small_load(const lcp_step *ls, const int m) {
  lcp_small_carry c = {.lam = {ls->lcp.lam[0], m > 1 ? ls->lcp.lam[1] : 0}, .lq = ls->lq};
  for (int i = 0; i < m; i++) c.act |= (unsigned)(ls->lcp.prev[i] != 0) << i;
  return c;
}

CUP_ALWAYS_INLINE void lcp_small_store(lcp_step *ls, const lcp_small_carry *c, const int m) {
  for (int i = 0; i < m; i++) {
    ls->lcp.lam[i] = c->lam[i];
    ls->lcp.prev[i] = (c->act >> i) & 1;
  }
  ls->lq = c->lq;
}

CUP_ALWAYS_INLINE void lcp_small_info(cup_proj_info *info, const lcp_small_out *o, double scale,
                                      double eps_target, double eta_target) {
  *info = (cup_proj_info){.status = o->status, .method = CUP_PROJ_ACTIVESET, .iterations = o->iterations,
                          .skipped = o->skipped, .active = o->active, .scale = scale, .eps_target = eps_target,
                          .eta_target = eta_target, .eps_cert = o->eps_cert, .eta_cert = o->eta_cert,
                          .violation = o->violation};
}

/* polyset_slack of the rows (lanes) at x, term by term in the same order (a
 * zero entry adds an exact zero to finite sums). */
CUP_ALWAYS_INLINE void lcp_small_slack(const lcp_step *ls, v2d g, const v2d *x, v2d *s,
                                       v2d *gam, const int n) {
  v2d acc = g, mag = v2_abs(g);
  for (int j = 0; j < n; j++) {
    v2d t = ls->Ccol[j] * v2_lane(x, j);
    acc += t;
    mag += v2_abs(t);
  }
  *s = acc;
  *gam = ls->rowgam * mag;
}

/* lcp_step_eta for the slack s, gam of z: its common case, z certainly
 * in K, without a call. */
CUP_ALWAYS_INLINE double lcp_small_eta(lcp_step *ls, v2d g, const v2d *z, v2d s, v2d gam,
                                       const int n, const int m) {
  v2d d = s - gam;
  double worst = d[0];                            /* the general path's min from INFINITY */
  if (m > 1) worst = la_min(worst, d[1]);
  if (worst >= 0) return 0;
  double gm[CUP_STEP_SMALL_M], zm[CUP_STEP_SMALL_N];
  for (int i = 0; i < m; i++) {
    ls->s[i] = s[i];
    ls->gam[i] = gam[i];
    gm[i] = g[i];
  }
  for (int j = 0; j < n; j++) zm[j] = v2_lane(z, j);
  return lcp_step_eta(ls, gm, zm);
}

/* One pass of lcp.c's Murty pivoting for m <= 2 rows at the active set act
 * (a bit mask; each block solved by the same closed forms, the same
 * tolerances, the same least index): the block's solution in *l0, *l1 and
 * -1 when no index flips, else the index to flip, or -2 at a singular
 * block. Scalars, not arrays indexed by the active set, so that nothing
 * goes through memory; det = M[0] M[3] - M[2] M[1], formed once. */
CUP_ALWAYS_INLINE int lcp_small_pass(unsigned act, const double *M, double det, double q0, double q1,
                                     double tol_w, double *l0p, double *l1p, const int m) {
  double l0 = 0, l1 = 0;
  if (act == 3) {
    if (!(det != 0)) return -2;
    l0 = (-q0 * M[3] + q1 * M[2]) / det;
    l1 = (-q1 * M[0] + q0 * M[1]) / det;
  } else if (act == 1) {
    if (!(M[0] != 0)) return -2;
    l0 = -q0 / M[0];
  } else if (act == 2) {                          /* m = 2 */
    if (!(M[3] != 0)) return -2;
    l1 = -q1 / M[3];
  }
  double w0 = q0, w1 = q1;                        /* w = q + M lam on the active columns */
  if (act & 1) w0 += M[0] * l0;
  if (act & 2) w0 += M[m] * l1;
  if (m > 1 && (act & 1)) w1 += M[1] * l0;
  if (m > 1 && (act & 2)) w1 += M[1 + m] * l1;
  double lmax = fabs(l0);                         /* la_max from 0 */
  if (m > 1) lmax = la_max(lmax, fabs(l1));
  double tol_l = 64 * DBL_EPSILON * lmax;
  *l0p = l0;
  *l1p = l1;
  if ((act & 1) ? l0 < -tol_l : w0 < -tol_w) return 0;
  if (m > 1 && ((act & 2) ? l1 < -tol_l : w1 < -tol_w)) return 1;
  return -1;
}

/* lcp.c's Murty pivoting from the warm start *act, pass after pass
 * (step.c): 0 with lam and *act written; 1, leaving them, where lcp.c would
 * meet a singular block or cycle (and then retry cold): the general path
 * takes the step over. */
int lcp_small_murty_loop(unsigned *actp, const double *M, double det, double q0, double q1, double tol_w,
                         v2d *lam, int *pivots, int m);

/* lcp_small_murty_loop, its first pass inlined: the warm start is right at
 * almost every step, and the loop, kept out of line, holds no registers
 * there (GCC spilled the fused steps' states around it). */
CUP_ALWAYS_INLINE int lcp_small_murty(unsigned *actp, const double *M, double det, v2d q, v2d *lam,
                                      int *pivots, const int m) {
  const double q0 = q[0], q1 = q[1];
  double scale = fabs(q0);                        /* la_max from 0 */
  if (m > 1) scale = la_max(scale, fabs(q1));
  double tol_w = 64 * DBL_EPSILON * scale, l0, l1;
  int flip = lcp_small_pass(*actp, M, det, q0, q1, tol_w, &l0, &l1, m);
  if (flip == -1) {
    *lam = (v2d){l0, l1};
    return 0;
  }
  if (flip == -2) return 1;
  return lcp_small_murty_loop(actp, M, det, q0, q1, tol_w, lam, pivots, m);
}

/* lcp_step_solve for n states and m rows known at compile time, eps_target
 * >= 0 and no D, from the free point xf for the offset g (lanes), carrying
 * c from the last step: 1 when it took the step (z, *c and *o written), 0
 * when the general path must (NaN or Inf in xf or g, a singular block),
 * having changed nothing but scratch. */
CUP_ALWAYS_INLINE int lcp_small_core(lcp_step *ls, lcp_small_carry *c, v2d g,
                                     const v2d *restrict xf, v2d *restrict z, double eps_target,
                                     double eta_target, lcp_small_out *o, const int n, const int m) {
  const int halves = (n + 1) / 2;
  v2d q, gam;
  lcp_small_slack(ls, g, xf, &q, &gam, n);        /* q = C x_free + g */
  /* NaN or Inf in xf or g makes q so (every row takes every state, zeros
   * included, and 0 Inf is NaN); so does an overflow of q, declined too */
  v2d probe = 0 * q;
  if (isnan(probe[0] + probe[1])) return 0;
  double qmin = q[0];                             /* the general path's min from INFINITY */
  if (m > 1) qmin = la_min(qmin, q[1]);
  if (qmin >= 0) {                                /* the free point is in K: lambda = 0 */
    for (int r = 0; r < halves; r++) z[r] = xf[r];
    c->lam = (v2d){0, 0};
    c->lq = 0;
    *o = (lcp_small_out){.skipped = 1, .eta_cert = lcp_small_eta(ls, g, z, q, gam, n, m)};
    o->status = o->eta_cert <= eta_target ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
    return 1;
  }
  v2d qs = q - (16 * gam + DBL_MIN), lam;     /* aimed a few ulps inside K, as step.c */
  int pivots = 0;
  if (lcp_small_murty(&c->act, ls->M, ls->det, qs, &lam, &pivots, m)) return 0;
  double l0 = la_max(lam[0], 0), l1 = m > 1 ? la_max(lam[1], 0) : 0, lq = 0;
  lq += l0 * q[0];
  if (m > 1) lq += l1 * q[1];
  c->lam = lam = (v2d){l0, l1};
  c->lq = lq;
  for (int r = 0; r < halves; r++) z[r] = xf[r];
  for (int r = 0; r < halves && l0 != 0; r++) z[r] += ls->Hcol[0][r] * l0;
  for (int r = 0; r < halves && m > 1 && l1 != 0; r++) z[r] += ls->Hcol[1][r] * l1;
  v2d s, sg;
  __asm__("" : "+r"(ls));   /* read C's columns again rather than keep them live across the step (spilled) */
  lcp_small_slack(ls, g, z, &s, &sg, n);
  v2d gapi = 2 * ls->h * lam * (s + sg);      /* impulse mu = h lambda */
  double gap = 0, viol = 0;
  int active = 0;
  for (int i = 0; i < m; i++) {
    gap += gapi[i];
    viol = la_max(viol, -s[i]);
    active += lam[i] > 0;
  }
  *o = (lcp_small_out){.iterations = pivots + 1, .active = active, .violation = viol,
                       .eps_cert = isnan(gap) ? NAN : la_max(gap, 0),
                       .eta_cert = lcp_small_eta(ls, g, z, s, sg, n, m)};
  o->status = o->eps_cert <= eps_target && o->eta_cert <= eta_target ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
  return 1;
}

/* lcp_small_core from and to step.c's arrays: 1 when it took the step
 * (info->status set), 0 when the general path must. */
CUP_ALWAYS_INLINE int lcp_small_step(lcp_step *ls, const double *g, const double *restrict xf,
                                     double *restrict z, double scale, double eps_target, double eta_target,
                                     cup_proj_info *info, const int n, const int m) {
  v2d xv[2] = {{0, 0}, {0, 0}}, zv[2];
  for (int j = 0; j < n; j++) xv[j >> 1][j & 1] = xf[j];
  v2d gv = {g[0], m > 1 ? g[1] : 0};
  lcp_small_carry c = lcp_small_load(ls, m);
  lcp_small_out o;
  if (!lcp_small_core(ls, &c, gv, xv, zv, eps_target, eta_target, &o, n, m)) return 0;
  lcp_small_store(ls, &c, m);
  for (int j = 0; j < n; j++) z[j] = v2_lane(zv, j);
  lcp_small_info(info, &o, scale, eps_target, eta_target);
  return 1;
}

#endif

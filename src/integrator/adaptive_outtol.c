/* adaptive_outtol — output tol (CUP_OUTPUT_TOL, docs/run-output.md): the
 * points inside a step's piece of exact flow that the straight lines
 * between consecutive reported points need to stay within
 *     output_tol s_i + tol_abs' ,  s_i = max |x_i| over the points so far,
 * of x_i(t) in each component (tol_abs' = output_tol times the scheme's own
 * error target, tol_abs + tol_rel max_j s_j: a floor, so that a state at
 * rounding level never asks for points). Each piece [a, b] is halved until
 * the line's error, estimated from x and x' = X M y at its ends, is below
 * that: for the cubic with those ends (Hermite's) the line is off by at most
 * (b - a) / 4 max(|x'(a) - c|, |x'(b) - c|) (c the chord's slope), exactly
 * that for a parabola. The first two halvings also ask the middle's value
 * itself (a piece whose ends' slopes equal its chord's, a bump between,
 * passes the slopes' test). Each point checked is a point kept: one flow
 * value and two products by X a point, by the step's Taylor series
 * (adaptive_series.c). Allocates nothing. */
#include <float.h>
#include <math.h>
#include "catchup.h"
#include "adaptive_impl.h"
#include "tally.h"
#include "model/signal_map.h"

/* A point of the flow: t, then x (n), x' (n) and y (na). */
typedef struct {
  double *t, *x, *d, *y;
} tol_pt;

static tol_pt slot_at(const adaptive_ws *A, double *base) {
  int n = A->n;
  return (tol_pt){.t = base, .x = base + 1, .d = base + 1 + n, .y = base + 1 + 2 * n};
}

/* P at t0 + tau: y by the piece's series (S, from ya over h; ya itself at
 * 0), x = X y, x' = X M y. */
static void flow_point(adaptive_ws *A, ad_mode *md, const double *ya, double h, double t0, double tau, tol_pt P) {
  *P.t = tau == h ? t0 + h : t0 + tau;
  if (tau == 0) la_copy(P.y, ya, A->na);
  else ad_series_at(A, &A->sy, md, h, ya, tau, P.y);
  ad_state(A, md, P.y, P.x);
  ad_mode_mv(A, md, P.y, A->fb);                 /* (fb: the series' scratch is fa) */
  ad_state(A, md, A->fb, P.d);
}

/* (no libm fmax a component: its NaN rules cost a call; a NaN state is refused at its offer) */
static inline double max2(double a, double b) { return a > b ? a : b; }

static void peak_of(adaptive_ws *A, const double *x) {
  for (int i = 0; i < A->n; i++) A->opeak[i] = max2(A->opeak[i], fabs(x[i]));
}

/* Is the line from L to R within tol? mid: the middle's x, or NULL. */
static int line_ok(const adaptive_ws *A, tol_pt L, tol_pt R, const double *mid) {
  int n = A->n;
  double w = *R.t - *L.t, smax = 0;
  for (int i = 0; i < n; i++) smax = max2(smax, A->opeak[i]);
  double floor = A->o.tol_abs + A->o.tol_rel * smax, tol = A->o.output_tol, rnd = 64 * DBL_EPSILON * smax;
  for (int i = 0; i < n; i++) {
    double c = (R.x[i] - L.x[i]) / w, thr = tol * max2(A->opeak[i], floor) + rnd;
    double err = 0.25 * w * max2(fabs(L.d[i] - c), fabs(R.d[i] - c));
    if (mid) err = max2(err, fabs(mid[i] - 0.5 * (L.x[i] + R.x[i])));
    if (!(err <= thr)) return 0;
  }
  return 1;
}

static void pt_copy(const adaptive_ws *A, tol_pt to, tol_pt from) {
  *to.t = *from.t;
  la_copy(to.x, from.x, A->n);
  la_copy(to.d, from.d, A->n);
  la_copy(to.y, from.y, A->na);
}

/* Where the points go: the sink one at a time, or with integrator_set_put's
 * put a batch at a time (A->bt, bx, bs: AD_BATCH of them, their signals by
 * re's rows over y, as adaptive_sample.c's dense_batch makes them). */
typedef struct {
  const struct ad_rec *re;                       /* NULL: the sink */
  int ns, c;                                     /* signals; points in the batch */
  double tr;                                     /* a refused point's time */
} tol_out;

/* The batch to put: 1 if a point was refused (its time in O->tr). The
 * samples counted as the sink's: those offered, the refused one too. */
static int flush(adaptive_ws *A, ad_run *R, long k, tol_out *O) {
  int c = O->c, took = c ? A->put(R->sink_ctx, k, c, A->bt, A->bx, A->bs, AD_BATCH) : 0;
  O->c = 0;
  if (took < 0) took = 0;
  if (took > c) took = c;
  R->info->samples += took < c ? took + 1 : c;
  if (took == c) return 0;
  O->tr = A->bt[took];
  return 1;
}

/* P offered (step k), as dense_samples offers a sample (the sink's record
 * reads its y: adaptive_zeta, adaptive_record): 1 if refused (its time in
 * O->tr; with put, this point's or an earlier one's of the batch). */
static int offer(adaptive_ws *A, ad_run *R, ad_mode *md, tol_pt P, long k, tol_out *O) {
  int n = A->n;
  if (tally_state_beyond(P.x, n)) {              /* (as a dense sample: never a state out of range) */
    if (O->re && flush(A, R, k, O)) return 1;    /* (the points before it first) */
    int w = tally_state_worst(P.x, n);
    return ad_fail(R, CUP_ERR_DIVERGED, "the state left its range ||x||_1 <= %g at t = %.17g (x[%d] = %.3g): "
                   "the scheme diverged", CUP_STATE_MAX, *P.t, w, P.x[w]);
  }
  if (O->re) {
    int c = O->c++;
    A->bt[c] = *P.t;
    la_copy(A->bx + (size_t)c * n, P.x, n);
    ad_rec_rows(O->re, O->ns, P.y, A->bs + c, AD_BATCH);
    return O->c == AD_BATCH ? flush(A, R, k, O) : 0;
  }
  R->info->samples++;
  la_copy(A->zy, P.y, A->na);
  A->zt = *P.t;
  A->zmd = md;
  A->zy_ready = 1;
  A->rows_ready = 0;
  int refused = R->sink(k, *P.t, P.x, R->sink_ctx) != 0;
  A->zmd = NULL;
  A->zy_ready = 0;
  O->tr = *P.t;
  return refused;
}

/* A refusal at time tr: the piece kept for the resumed run (ad_dense_resume). */
static int keep_piece(adaptive_ws *A, ad_mode *md, const double *ya, double t0, double t1, long k, int with_t0,
                      double tr, const double *peak0) {
  struct ad_pend *p = &A->pend;
  p->active = 1;
  p->seg2 = 0;
  p->md = (int)(md - A->modes);
  p->k = k;
  p->t_end = t1;
  p->ta = t0;
  p->tr = tr;
  p->with_t0 = with_t0;
  if (p->zy != ya) la_copy(p->zy, ya, A->na);   /* (a resumed piece's are these already) */
  if (p->opk != peak0) la_copy(p->opk, peak0, A->n);
  return 1;
}

/* The piece's points by halving (the file's comment): a stack of right
 * ends (slots of A->ostk) above the left end L, each check of [L, top]
 * either keeping it (top is the next point) or pushing its middle. */
static int cut(adaptive_ws *A, ad_run *R, ad_mode *md, const double *ya, double t0, double t1, long k,
               int with_t0, double skip, tol_out *O) {
  int n = A->n, na = A->na, slot = 1 + 2 * n + na, sp = 1;
  double h = t1 - t0;
  tol_pt L = slot_at(A, A->oleft), top = slot_at(A, A->ostk);
  flow_point(A, md, ya, h, t0, 0, L);
  flow_point(A, md, ya, h, t0, h, top);
  *top.t = t1;
  peak_of(A, L.x);
  peak_of(A, top.x);
  if (with_t0 && t0 >= skip) {
    int st = offer(A, R, md, L, k, O);
    if (st) return st;
  }
  while (sp > 0) {
    tol_pt Rt = slot_at(A, A->ostk + (size_t)(sp - 1) * slot), M = slot_at(A, A->ostk + (size_t)sp * slot);
    double tm = *L.t + 0.5 * (*Rt.t - *L.t);
    int ok = sp > AD_TOL_DEPTH || !(tm > *L.t && tm < *Rt.t);
    if (!ok && sp > 2) ok = line_ok(A, L, Rt, NULL);
    if (!ok) {
      flow_point(A, md, ya, h, t0, tm - t0, M);
      peak_of(A, M.x);
      ok = sp <= 2 && line_ok(A, L, Rt, M.x);
    }
    if (!ok) {                                   /* halved: the middle is the new right end */
      sp++;
      continue;
    }
    pt_copy(A, L, Rt);                           /* [L, R] kept: R is the next point */
    sp--;
    if (sp > 0 && *L.t >= skip) {
      int st = offer(A, R, md, L, k, O);
      if (st) return st;
    }
  }
  return O->re ? flush(A, R, k, O) : 0;
}

int ad_emit_tol(adaptive_ws *A, ad_run *R, ad_mode *md, const double *ya, double t0, double t1, long k,
                int with_t0, double skip) {
  if (!R->sink || !(t1 - t0 > 0)) return CUP_OK;
  const ad_mode *smd = A->sy.md;                 /* the step's series, if another's: made again after */
  const double *sy0 = A->sy.y0;
  double sh = A->sy.h;
  la_copy(A->pend.opk, A->opeak, A->n);          /* (the scales at the piece's start: a refusal's) */
  const signal_map *S = A->put ? nl_signal_map(A->put_nl) : NULL;
  const struct ad_rec *re = S && S->ns == A->put_ns ? ad_rec_of(A, md, S) : NULL;
  tol_out O = {.re = re && !re->nu ? re : NULL, .ns = S ? S->ns : 0};
  int st = cut(A, R, md, ya, t0, t1, k, with_t0, skip, &O);
  if (st > 0) st = keep_piece(A, md, ya, t0, t1, k, with_t0, O.tr, A->pend.opk);
  if (A->sy.md != smd || A->sy.y0 != sy0 || A->sy.h != sh) A->sy.md = NULL;
  return st;
}

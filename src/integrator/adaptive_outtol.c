/* adaptive_outtol — output tol (CUP_OUTPUT_TOL, docs/run-output.md): the
 * points inside a step's piece of exact flow that the straight lines
 * between consecutive reported points need to stay within
 *     output_tol max(s_i, tol_abs + tol_rel max_j s_j) + 64 eps max_j s_j
 * of x_i(t) in each component, s_i = max |x_i| over the points so far (the
 * scheme's own error target a floor, and rounding: a state at rounding
 * level never asks for points). Each piece [a, b] is halved until
 * the line's error, estimated from x and x' = X M y at its ends, is below
 * that: for the cubic with those ends (Hermite's) the line is off by at most
 * (b - a) / 4 max(|x'(a) - c|, |x'(b) - c|) (c the chord's slope), exactly
 * that for a parabola. The first two halvings also ask the middle's value
 * itself (a piece whose ends' slopes equal its chord's, a bump between,
 * passes the slopes' test). Each point checked is a point kept: one flow
 * value and one pass of X and X M over it a point; the flow value is
 * exp(2^-j h M) times the point before it for na <= AD_TOL_LEVELS_NA (a
 * matrix a halving level: level), else the step's Taylor series
 * (adaptive_series.c); a step's piece ends on the run's own y there (no
 * level 0), and a piece new to the levels checks its first middle by its
 * own Taylor series (flow_taylor: most such pieces keep no point inside,
 * and need no level). Allocates nothing. */
#include <float.h>
#include <math.h>
#include "catchup.h"
#include "adaptive_impl.h"
#include "tally.h"
#include "model/signal_map.h"

/* A point of the flow: t, then x (n), x' (n) and y (na); slot s of A->ostk. */
typedef struct {
  double *t, *x, *d, *y;
} tol_pt;

static inline tol_pt slot_at(const adaptive_ws *A, int s) {
  int n = A->n;
  double *base = A->ostk + (size_t)s * (1 + 2 * (size_t)n + (size_t)A->na);
  return (tol_pt){.t = base, .x = base + 1, .d = base + 1 + n, .y = base + 1 + 2 * n};
}

/* (no libm fmax a component: its NaN rules cost a call; a NaN state is refused at its offer) */
static inline double max2(double a, double b) { return a > b ? a : b; }

/* A->oxm = X M (n x na, row-major: x' = X M y), once a piece. */
static void xm_of(adaptive_ws *A, const ad_mode *md) {
  int n = A->n, na = A->na;
  for (int i = 0; i < n; i++)
    for (int j = 0; j < na; j++) {
      double acc = 0;
      for (int k = 0; k < na; k++) acc += md->X[(size_t)i * na + k] * md->M[k + (size_t)j * na];
      A->oxm[(size_t)i * na + j] = acc;
    }
}

/* x = X y and x' = (X M) y of P, in one pass. */
static void x_and_d(const adaptive_ws *A, const ad_mode *md, tol_pt P) {
  int n = A->n, na = A->na;
  const double *X = md->X, *XM = A->oxm, *y = P.y;
  for (int i = 0; i < n; i++, X += na, XM += na) {
    double a = 0, b = 0;
    for (int j = 0; j < na; j++) {
      a += X[j] * y[j];
      b += XM[j] * y[j];
    }
    P.x[i] = a;
    P.d[i] = b;
  }
}

/* P at t0 + tau by the piece's series (from ya over h; ya itself at 0). */
static void flow_point(adaptive_ws *A, ad_mode *md, const double *ya, double h, double t0, double tau, tol_pt P) {
  *P.t = t0 + tau;
  if (tau == 0) la_copy(P.y, ya, A->na);
  else ad_series_at(A, &A->sy, md, h, ya, tau, P.y);
  x_and_d(A, md, P);
}

/* C = A B (na x na, column-major; na a constant in each case). */
static inline __attribute__((always_inline)) void mat_mul_n(int na, const double *a, const double *b, double *c) {
  for (int j = 0; j < na; j++)
    for (int i = 0; i < na; i++) {
      double acc = 0;
      for (int k = 0; k < na; k++) acc += a[i + k * na] * b[k + j * na];
      c[i + j * na] = acc;
    }
}

static void mat_mul(int na, const double *a, const double *b, double *c) {
  switch (na) {
    case 1: mat_mul_n(1, a, b, c); return;
    case 2: mat_mul_n(2, a, b, c); return;
    case 3: mat_mul_n(3, a, b, c); return;
    default: mat_mul_n(4, a, b, c); return;     /* (na <= AD_TOL_LEVELS_NA) */
  }
}

/* A Taylor series' next term, f tmp, into term and added to sum (len
 * entries): 1 when it is below a quarter ulp of the sum's largest entry
 * (the series ends there). */
static inline int taylor_add(int len, const double *tmp, double f, double *term, double *sum) {
  double big = 0, smax = 0;
  for (int q = 0; q < len; q++) {
    term[q] = tmp[q] * f;
    sum[q] += term[q];
    big = max2(big, fabs(term[q]));
    smax = max2(smax, fabs(sum[q]));
  }
  return big <= 0.25 * DBL_EPSILON * smax;
}

/* exp(tau M) into E by its Taylor series, tau snorm <= 1/2: to the first
 * term below a quarter ulp of the sum's largest entry (at most 30). The
 * first term's I M is M itself (the same sums: 0 + m + 0 ... is m, but
 * for a -0 entry +0, and a zero's sign never reaches a sum that starts at
 * +0; M is finite where the levels are made: snorm bounds it). */
static void expm_taylor(adaptive_ws *A, const ad_mode *md, double tau, double *E) {
  int na = A->na, NA = na * na;
  double *term = A->olev + (size_t)(AD_TOL_DEPTH + 2) * NA;
  for (int q = 0; q < NA; q++) E[q] = 0;
  for (int q = 0; q < NA; q += na + 1) E[q] = 1;   /* (no q % (na + 1) an entry: a division each) */
  if (taylor_add(NA, md->M, tau, term, E)) return;
  double *tmp = term + NA;
  for (int k = 2; k <= 30; k++) {
    mat_mul(na, term, md->M, tmp);
    if (taylor_add(NA, tmp, tau / k, term, E)) break;
  }
}

/* exp(2^-j h M), made when first asked for this mode and h (consecutive
 * pieces of the same length on the same mode share them: steps at hmax, a
 * sine's eighths). Level j0 + 5 by its Taylor series (j0 the first whose
 * tau snorm <= 1/2: the input's coupling block of M is nilpotent, the
 * terms fall as the diagonal blocks', snorm, as adaptive_series.c's), the
 * coarser ones by squaring it (exp(2 tau M) = exp(tau M)^2: na^3 each; the
 * rounding grows as eps / (tau snorm), 64 eps at most), a deeper one by its
 * own series. Each level is the same function of (M, h, j) whatever asked
 * first: a resumed run's points are the same bits. */
static __attribute__((noinline)) const double *level(adaptive_ws *A, const ad_mode *md, double h, int j) {
  int NA = A->na * A->na;
  double *E = A->olev + (size_t)j * NA;
  if (A->olev_ok >> j & 1) return E;
  if (j < A->olev_base) {
    const double *F = level(A, md, h, j + 1);
    mat_mul(A->na, F, F, E);
  } else {
    expm_taylor(A, md, h / (double)((uint64_t)1 << j), E);
  }
  A->olev_ok |= (uint64_t)1 << j;
  return E;
}

/* out = exp(tau M) y, na <= 4, by its Taylor series in 2^s substeps
 * (tau 2^-s snorm <= 1/2), each to the first term below a quarter ulp of
 * the sum's largest component (at most 30): one point without the levels
 * (na^2 a term, where a level is na^3). */
static void flow_taylor(const adaptive_ws *A, const ad_mode *md, double tau, int s, const double *y, double *out) {
  int na = A->na;
  double term[4], tmp[4], dt = ldexp(tau, -s);
  la_copy(out, y, na);
  for (long q = 0; q < 1L << s; q++) {
    la_copy(term, out, na);
    for (int k = 1; k <= 30; k++) {
      ad_mode_mv_few(na, md->M, term, tmp);
      if (taylor_add(na, tmp, dt / k, term, out)) break;
    }
  }
}

/* y = E y_L, x = X y, x' = (X M) y, na a constant (n <= na rows). */
static inline __attribute__((always_inline)) void times_n(int na, int n, const double *restrict E,
                                                          const double *restrict yl, const double *restrict X,
                                                          const double *restrict XM, double *restrict y,
                                                          double *restrict x, double *restrict d) {
  double v[4];
  for (int i = 0; i < na; i++) {
    double acc = 0;
    for (int k = 0; k < na; k++) acc += E[i + k * na] * yl[k];
    v[i] = y[i] = acc;
  }
  for (int i = 0; i < n; i++, X += na, XM += na) {
    double a = 0, b = 0;
    for (int j = 0; j < na; j++) {
      a += X[j] * v[j];
      b += XM[j] * v[j];
    }
    x[i] = a;
    d[i] = b;
  }
}

/* P = the point 2^-j h after L: exp(2^-j h M) y_L, or the series. */
static void flow_after(adaptive_ws *A, ad_mode *md, const double *ya, double h, double t0, tol_pt L, int j,
                       double tm, tol_pt P) {
  if (!A->olev || A->olev_base > AD_TOL_DEPTH) {   /* (no levels, or too stiff a piece for them) */
    flow_point(A, md, ya, h, t0, tm - t0, P);
    *P.t = tm;                                   /* (t1 itself at the end: not t0 + h) */
    return;
  }
  const double *E = A->olev_ok >> j & 1 ? A->olev + (size_t)j * A->na * A->na : level(A, md, h, j);
  *P.t = tm;
  switch (A->na) {
    case 1: times_n(1, A->n, E, L.y, md->X, A->oxm, P.y, P.x, P.d); return;
    case 2: times_n(2, A->n, E, L.y, md->X, A->oxm, P.y, P.x, P.d); return;
    case 3: times_n(3, A->n, E, L.y, md->X, A->oxm, P.y, P.x, P.d); return;
    default: times_n(4, A->n, E, L.y, md->X, A->oxm, P.y, P.x, P.d); return;   /* (na <= AD_TOL_LEVELS_NA) */
  }
}

/* Each state's tolerance (A->othr) from the scales A->opeak. */
static void thresholds(adaptive_ws *A) {
  int n = A->n;
  double smax = 0;
  for (int i = 0; i < n; i++) smax = max2(smax, A->opeak[i]);
  double floor = A->o.tol_abs + A->o.tol_rel * smax, tol = A->o.output_tol, rnd = 64 * DBL_EPSILON * smax;
  for (int i = 0; i < n; i++) A->othr[i] = tol * max2(A->opeak[i], floor) + rnd;
}

/* The scales with x; the tolerances again if one moved. */
static void peak_of(adaptive_ws *A, const double *x) {
  int moved = 0;
  for (int i = 0; i < A->n; i++)
    if (fabs(x[i]) > A->opeak[i]) {
      A->opeak[i] = fabs(x[i]);
      moved = 1;
    }
  if (moved) thresholds(A);
}

/* Is the line from L to R within tol (thr: A->othr)? l, r: their slots
 * (t, x, x'); mid: the middle's x, or NULL. Plain pointers, read into
 * registers: A's fields were read again after each store to a slot. */
static inline int line_ok(int n, const double *thr, const double *l, const double *r, const double *mid) {
  double w = r[0] - l[0], iw = 1 / w, q = 0.25 * w;
  const double *lx = l + 1, *rx = r + 1, *ld = l + 1 + n, *rd = r + 1 + n;
  for (int i = 0; i < n; i++) {
    double c = (rx[i] - lx[i]) * iw;
    double err = q * max2(fabs(ld[i] - c), fabs(rd[i] - c));
    if (mid) err = max2(err, fabs(mid[i] - 0.5 * (lx[i] + rx[i])));
    if (!(err <= thr[i])) return 0;
  }
  return 1;
}

/* Where the points go: the sink one at a time, or with integrator_set_put's
 * put a batch at a time (A->bt, bx, bs: AD_BATCH of them, their signals by
 * re's rows over y, as adaptive_sample.c's dense_batch makes them). */
typedef struct {
  const struct ad_rec *re;                       /* NULL: the sink */
  int ns, c;                                     /* signals; points in the batch */
  int dense;                                     /* na <= 4: the batch's y kept (A->by), its signals made at
                                                    its put by ad_batch_signals (ad_signal_rows' rows) */
  double tr;                                     /* a refused point's time */
} tol_out;

/* The batch to put: 1 if a point was refused (its time in O->tr). The
 * samples counted as the sink's: those offered, the refused one too. */
static int flush(adaptive_ws *A, ad_run *R, long k, tol_out *O) {
  int c = O->c;
  if (O->dense) switch (A->na) {
      case 1: ad_batch_signals(1, A->bk, A->bkc, A->by, A->bs, O->ns, c); break;
      case 2: ad_batch_signals(2, A->bk, A->bkc, A->by, A->bs, O->ns, c); break;
      case 3: ad_batch_signals(3, A->bk, A->bkc, A->by, A->bs, O->ns, c); break;
      default: ad_batch_signals(4, A->bk, A->bkc, A->by, A->bs, O->ns, c); break;
    }
  int took = ad_put_batch(A, R, k, c);
  O->c = 0;
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
    if (O->dense) la_copy(A->by + (size_t)c * A->na, P.y, A->na);
    else ad_rec_rows(O->re, O->ns, P.y, A->bs + c, AD_BATCH);
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
static int keep_piece(adaptive_ws *A, ad_mode *md, const double *ya, const double *yb, double t0, double t1,
                      long k, int with_t0, double tr, const double *peak0) {
  struct ad_pend *p = ad_pend_start(A, md, k, t1);
  p->ta = t0;
  p->tr = tr;
  p->with_t0 = with_t0;
  if (p->zy != ya) la_copy(p->zy, ya, A->na);   /* (a resumed piece's are these already) */
  p->with_yb = yb != NULL;
  p->taylor = A->otaylor;
  if (yb && p->y2 != yb) la_copy(p->y2, yb, A->na);   /* (a step's piece: no second piece in y2) */
  if (p->opk != peak0) la_copy(p->opk, peak0, A->n);
  return 1;
}

/* peak_of with n held: 1 if a scale moved (the tolerances made again). */
static inline int peak_n(adaptive_ws *A, int n, const double *x) {
  double *pk = A->opeak;
  int moved = 0;
  for (int i = 0; i < n; i++)
    if (fabs(x[i]) > pk[i]) {
      pk[i] = fabs(x[i]);
      moved = 1;
    }
  if (moved) thresholds(A);
  return moved;
}

/* The point 2^-j h after l into p (slots: t, x, x', y), na a constant
 * NA with the levels (times_n: X, XM and the levels olev as halve holds
 * them, *ok its copy of A->olev_ok), else flow_after (NA 0). */
static inline __attribute__((always_inline)) void point_after(const int NA, adaptive_ws *A, ad_mode *md,
                                                              const double *ya, double h, double t0, int n,
                                                              const double *X, const double *XM,
                                                              const double *olev, uint64_t *ok, double *l,
                                                              int j, double tm, double *p) {
  if (NA) {
    const double *E = olev + (size_t)j * NA * NA;
    if (!(*ok >> j & 1)) {
      E = level(A, md, h, j);
      *ok = A->olev_ok;
    }
    p[0] = tm;
    times_n(NA, n, E, l + 1 + 2 * n, X, XM, p + 1 + 2 * n, p + 1, p + 1 + n);
  } else {
    tol_pt L = {.t = l, .x = l + 1, .d = l + 1 + n, .y = l + 1 + 2 * n};
    tol_pt P = {.t = p, .x = p + 1, .d = p + 1 + n, .y = p + 1 + 2 * n};
    flow_after(A, md, ya, h, t0, L, j, tm, P);
  }
}

/* The halving loop of cut (its comment), na a constant NA with the
 * levels, else 0: a stack of right ends above the left end l, each check
 * of [left, top] either keeping it (top is the next point) or pushing its
 * middle. A middle made at depth c (c halvings) sits in slot c + 1 (the
 * piece's ends in 0 and 1): the live points (the stack's and the left
 * end) were made at distinct depths, none deeper than the top's check d,
 * so the new middle's slot d + 2 is free (no free list). The slots by
 * pointer, the sizes held: each of A's fields was read again after a
 * store to a slot. */
static inline __attribute__((always_inline)) int halve(const int NA, adaptive_ws *A, ad_run *R, ad_mode *md,
                                                       const double *ya, double t0, double h, long k, double skip,
                                                       tol_out *O) {
  enum { SLOTS = AD_TOL_DEPTH + 3 };
  double *stk[SLOTS];
  int dep[SLOTS], sp = 1;
  const int n = A->n, na = NA ? NA : A->na;
  const size_t stride = 1 + 2 * (size_t)n + (size_t)na;
  double *const ostk = A->ostk, *l = ostk;
  const double *thr = A->othr, *X = md->X, *XM = A->oxm, *olev = A->olev;
  uint64_t lev_ok = A->olev_ok;                  /* (A's, read again only after level made one) */
  stk[0] = ostk + stride;
  dep[0] = 0;                                    /* (the halvings of [left, stk[i]] when it is the top) */
  while (sp > 0) {
    double *r = stk[sp - 1];
    int d = dep[sp - 1];
    double tl = l[0], tr = r[0], tm = tl + 0.5 * (tr - tl);
    int ok = d >= AD_TOL_DEPTH || !(tm > tl && tm < tr);
    if (!ok && d >= 2) ok = line_ok(n, thr, l, r, NULL);
    if (!ok) {
      double *p = ostk + (size_t)(d + 2) * stride;
      if (NA && d == 0 && A->otaylor && line_ok(n, thr, l, r, NULL)) {
        p[0] = tm;                               /* (the slopes pass: likely no point inside, no level made) */
        flow_taylor(A, md, tm - t0, A->olev_base > 5 ? A->olev_base - 6 : 0, ya, p + 1 + 2 * n);
        tol_pt P = {.t = p, .x = p + 1, .d = p + 1 + n, .y = p + 1 + 2 * n};
        x_and_d(A, md, P);
      } else {
        point_after(NA, A, md, ya, h, t0, n, X, XM, olev, &lev_ok, l, d + 1, tm, p);
      }
      peak_n(A, n, p + 1);
      if (!(d < 2 && line_ok(n, thr, l, r, p + 1))) {   /* halved: the middle is the new right end */
        dep[sp - 1] = dep[sp] = d + 1;
        stk[sp++] = p;
        continue;
      }
    }
    sp--;                                        /* [left, top] kept: top is the next point */
    l = r;
    if (sp > 0 && tr >= skip) {
      if (O->dense && !tally_state_beyond(r + 1, n)) {   /* (a batch's point: offer's, inline) */
        int c = O->c++;
        A->bt[c] = tr;
        la_copy(A->bx + (size_t)c * n, r + 1, n);
        la_copy(A->by + (size_t)c * na, r + 1 + 2 * n, na);
        if (O->c == AD_BATCH && flush(A, R, k, O)) return 1;
        continue;
      }
      tol_pt P = {.t = r, .x = r + 1, .d = r + 1 + n, .y = r + 1 + 2 * n};
      int st = offer(A, R, md, P, k, O);
      if (st) return st;
    }
  }
  return O->re ? flush(A, R, k, O) : 0;
}

/* The piece's points by halving (the file's comment): its ends, then
 * halve's loop. */
static int cut(adaptive_ws *A, ad_run *R, ad_mode *md, const double *ya, const double *yb, double t0, double t1,
               long k, int with_t0, double skip, int taylor, tol_out *O) {
  double h = t1 - t0;
  int hit = md == A->olev_md && md->mask == A->olev_mask && h == A->olev_h;
  if (!hit) {                                    /* (level's matrices and X M kept) */
    A->olev_md = md;
    A->olev_mask = md->mask;
    A->olev_h = h;
    A->olev_ok = 0;
    int j0 = 0;                                  /* (the series' pieces beyond 2^25 of tau snorm <= 1/2) */
    while (j0 <= AD_TOL_DEPTH - 5 && !(h / (double)((uint64_t)1 << j0) * md->snorm <= 0.5)) j0++;
    A->olev_base = j0 + 5;
    xm_of(A, md);
  }
  /* The root's middle by flow_taylor when its slopes pass (then likely
   * the piece's only check): on a piece whose mode and length the last
   * one had not, j0 <= 1 (h snorm <= 1: one series of na^2 a term, where
   * the levels ask for 13 products of na^3); else the levels, made for the
   * last piece. The choice a
   * refused piece made is kept (keep_piece), so that its resumed run's
   * points are the same bits whatever the levels made so far. */
  A->otaylor = taylor >= 0 ? taylor : !hit && A->olev && A->olev_base <= 6;
  tol_pt L = slot_at(A, 0), top = slot_at(A, 1);
  flow_point(A, md, ya, h, t0, 0, L);
  if (yb) {                                      /* (the run's own end: no level 0) */
    *top.t = t1;
    la_copy(top.y, yb, A->na);
    x_and_d(A, md, top);
  } else {
    flow_after(A, md, ya, h, t0, L, 0, t1, top);
  }
  thresholds(A);
  peak_of(A, L.x);
  peak_of(A, top.x);
  if (with_t0 && t0 >= skip) {
    int st = offer(A, R, md, L, k, O);
    if (st) return st;
  }
  if (!A->olev || A->olev_base > AD_TOL_DEPTH) return halve(0, A, R, md, ya, t0, h, k, skip, O);
  switch (A->na) {
    case 1: return halve(1, A, R, md, ya, t0, h, k, skip, O);
    case 2: return halve(2, A, R, md, ya, t0, h, k, skip, O);
    case 3: return halve(3, A, R, md, ya, t0, h, k, skip, O);
    default: return halve(4, A, R, md, ya, t0, h, k, skip, O);   /* (na <= AD_TOL_LEVELS_NA) */
  }
}

int ad_emit_tol(adaptive_ws *A, ad_run *R, ad_mode *md, const double *ya, const double *yb, double t0, double t1,
                long k, int with_t0, double skip, int taylor) {
  if (!R->sink || !(t1 - t0 > 0)) return CUP_OK;
  const ad_mode *smd = A->sy.md;                 /* the step's series, if another's: made again after */
  const double *sy0 = A->sy.y0;
  double sh = A->sy.h;
  la_copy(A->pend.opk, A->opeak, A->n);          /* (the scales at the piece's start: a refusal's) */
  const signal_map *S = A->put && !A->put_off ? ad_put_map(A) : NULL;
  const struct ad_rec *re = S && S->ns == A->put_ns ? ad_rec_of(A, md, S) : NULL;
  tol_out O = {.re = re && !re->nu ? re : NULL, .ns = S ? S->ns : 0};
  O.dense = O.re && A->na <= 4;
  if (O.dense) ad_signal_rows(A, O.re, O.ns);
  int st = cut(A, R, md, ya, yb, t0, t1, k, with_t0, skip, taylor, &O);
  if (st > 0) st = keep_piece(A, md, ya, yb, t0, t1, k, with_t0, O.tr, A->pend.opk);
  if (A->sy.md != smd || A->sy.y0 != sy0 || A->sy.h != sh) A->sy.md = NULL;
  return st;
}

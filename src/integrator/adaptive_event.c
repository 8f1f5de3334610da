/* adaptive_event — event functions of an active set, their sign changes on
 * a step and the location of the earliest one (adaptive_impl.h). */
#include <float.h>
#include <math.h>
#include <string.h>
#include "catchup.h"
#include "adaptive_impl.h"

/* The state's scale: v = x + K U w. */
static inline double state_scale(const adaptive_ws *A, const double *y) {
  switch (A->n) {                          /* (a converter's few states: unrolled) */
    case 1: return la_norm_inf(y, 1);
    case 2: return la_norm_inf(y, 2);
    case 3: return la_norm_inf(y, 3);
    case 4: return la_norm_inf(y, 4);
    default: return la_norm_inf(y, A->n);
  }
}

void ad_events_eval(const adaptive_ws *A, const ad_mode *md, const double *y, double *g, double *thr) {
  int m = A->m;
  double vmax = state_scale(A, y);
  for (int i = 0; i < m; i++) {            /* over L's and Lm's nonzeros (mode_sparse): the dense sums */
    double acc = md->Lc[i], mag = fabs(md->Lc[i]);
    for (int k = md->lp[i]; k < md->lp[i + 1]; k++) {
      double yj = y[md->li[k]];
      acc += md->lx[k] * yj;
      mag += md->lmx[k] * fabs(yj);
    }
    g[i] = acc;
    thr[i] = ad_row_rounding(A, md, i, mag, vmax);
  }
}

void ad_events_deriv(adaptive_ws *A, const ad_mode *md, const double *y, double *d) {
  double *My = A->My;
  ad_mode_mv(A, md, y, My);
  for (int i = 0; i < A->m; i++) {
    double acc = 0;
    for (int k = md->lp[i]; k < md->lp[i + 1]; k++) acc += md->lx[k] * My[md->li[k]];
    d[i] = acc;
  }
}

/* Row i's rounding threshold at y, as ad_events_eval makes it. */
static double threshold(const adaptive_ws *A, const ad_mode *md, int i, const double *y, double vmax) {
  double mag = fabs(md->Lc[i]);
  for (int k = md->lp[i]; k < md->lp[i + 1]; k++) mag += md->lmx[k] * fabs(y[md->li[k]]);
  return ad_row_rounding(A, md, i, mag, vmax);
}

/* The rows of ad_events_both. few: na <= 4, a constant here: (M y)_j only
 * where a row reads it, as ad_mode_mv_dense sums it (from +0, over the
 * columns in order), y's entries in registers (a full bridge's 4 rows read
 * 2 or 3 of M y's 3 components, and the product and its stores were a
 * quarter of the call); else M y from A->My, made whole. */
static inline __attribute__((always_inline)) void both_rows(int few, int na, const adaptive_ws *A, const ad_mode *md,
                                                            const double *y, double *g, double *thr, double *d) {
  double yv[4];
  const double *M = md->M, *My = A->My;
  for (int c = 0; few && c < na; c++) yv[c] = y[c];
  double vmax = state_scale(A, y);
  int m = A->m;
  const int *lp = md->lp, *li = md->li;
  const double *lx = md->lx, *Lc = md->Lc;
  for (int i = 0; i < m; i++) {
    double acc = Lc[i], dacc = 0;
    for (int k = lp[i]; k < lp[i + 1]; k++) {
      int j = li[k];
      double l = lx[k], myj = 0;
      if (few)
        for (int c = 0; c < na; c++) myj += M[j + c * na] * yv[c];
      else
        myj = My[j];
      acc += l * (few ? yv[j] : y[j]);
      dacc += l * myj;
    }
    g[i] = acc;
    d[i] = dacc;
    thr[i] = acc >= 0 ? 0 : threshold(A, md, i, y, vmax);
  }
  if (!(vmax <= DBL_MAX)) ad_events_thresholds(A, md, y, thr);   /* (an infinite state: c1 = 0 makes a NaN) */
}

/* (One pass over L's nonzeros for both: each sum as in its own function.)
 * A row's threshold counts only where its value is below zero: crossed()
 * and any_negative() ask g < -thr (never true for g >= 0, thr >= 0) and g
 * >= -thr (always). It is left out (0) where g >= 0 and the state is
 * finite, where it cannot be NaN either: it takes the magnitudes' sum and
 * a product by the state's scale, 12 of the 60 instructions a row of a
 * full bridge's (every row's: ad_events_thresholds). */
void ad_events_both(adaptive_ws *A, const ad_mode *md, const double *y, double *g, double *thr, double *d) {
  switch (A->na) {
    case 1: both_rows(1, 1, A, md, y, g, thr, d); return;
    case 2: both_rows(1, 2, A, md, y, g, thr, d); return;
    case 3: both_rows(1, 3, A, md, y, g, thr, d); return;
    case 4: both_rows(1, 4, A, md, y, g, thr, d); return;
  }
  ad_mode_mv(A, md, y, A->My);
  both_rows(0, A->na, A, md, y, g, thr, d);
}

void ad_events_thresholds(const adaptive_ws *A, const ad_mode *md, const double *y, double *thr) {
  double vmax = state_scale(A, y);
  for (int i = 0; i < A->m; i++) thr[i] = threshold(A, md, i, y, vmax);
}

/* Values, slopes and thresholds at tau into (g, d, thr); the state in A->yt. */
static void probe(adaptive_ws *A, ad_mode *md, double tau, double *g, double *d, double *thr,
                  ad_event *ev) {
  ad_series_at(A, &A->sy, md, ev->h, A->ya, tau, A->yt);
  ad_events_both(A, md, A->yt, g, thr, d);
  ev->evals++;
}

/* A probe at the bracket's new right end: its state (A->yt) kept for the
 * event, which flows there (the same function of the same arguments). */
static void hold_hi(adaptive_ws *A, ad_event *ev) {
  la_copy(A->yhi, A->yt, A->na);
  ev->hi_ok = 1;
}

static int crossed(double glo, double tlo, double ghi, double thi) { return glo >= -tlo && ghi < -thi; }

/* Any row crossing between the bracket's start (ga, ta) and (g, thr)? */
static int any_crossed(const adaptive_ws *A, const double *g, const double *thr) {
  const double *ga = A->ga, *ta = A->ta;
  for (int i = 0; i < A->m; i++)                 /* (g < -thr needs g < 0: the test first) */
    if (g[i] < 0 && crossed(ga[i], ta[i], g[i], thr[i])) return 1;
  return 0;
}

static void keep(adaptive_ws *A, double *g, double *d, double *t, const double *gs, const double *ds,
                 const double *ts) {
  int m = A->m;
  memcpy(g, gs, sizeof(double) * (size_t)m);
  memcpy(d, ds, sizeof(double) * (size_t)m);
  memcpy(t, ts, sizeof(double) * (size_t)m);
}

/* The lowest point of the cubic Hermite interpolant of (g0, d0) at 0 and
 * (g1, d1) at h, over [0, h]. */
static double hermite_min(double g0, double d0, double g1, double d1, double h, double *at) {
  /* p(s) = g0 + d0 s + c2 s^2 + c3 s^3 */
  double c2 = (3 * (g1 - g0) / h - 2 * d0 - d1) / h;
  double c3 = (d0 + d1 - 2 * (g1 - g0) / h) / (h * h);
  double best = fmin(g0, g1);
  *at = g0 <= g1 ? 0 : h;
  /* p'(s) = d0 + 2 c2 s + 3 c3 s^2 */
  double a = 3 * c3, b = 2 * c2, c = d0, r[2];
  int nr = 0;
  if (fabs(a) < 1e-300) {
    if (b != 0) r[nr++] = -c / b;
  } else {
    double disc = b * b - 4 * a * c;
    if (disc >= 0) {
      double q = -0.5 * (b + copysign(sqrt(disc), b));
      if (q != 0) r[nr++] = c / q;
      r[nr++] = q / a;
    }
  }
  for (int k = 0; k < nr; k++)
    if (r[k] > 0 && r[k] < h) {
      double s = r[k], v = g0 + s * (d0 + s * (c2 + s * c3));
      if (v < best) { best = v; *at = s; }
    }
  return best;
}

/* A dip of row i inside the step (slope down at the start, up at the end):
 * find the lowest point of the true function by safeguarded secant steps on
 * its slope; 1 with the bracket end in ev if it goes below zero there (or
 * any row crossed at a probe). */
static int find_dip(adaptive_ws *A, ad_mode *md, int i, double h, ad_event *ev) {
  double lo = 0, hi = h, dlo = A->da[i], dhi = A->db[i];
  for (int it = 0; it < 40 && hi - lo > 1e-3 * h; it++) {
    double s = lo + (hi - lo) * dlo / (dlo - dhi);
    if (!(s > lo + 0.05 * (hi - lo) && s < hi - 0.05 * (hi - lo))) s = 0.5 * (lo + hi);
    probe(A, md, s, A->gt, A->dt, A->tt, ev);
    if (any_crossed(A, A->gt, A->tt)) {
      keep(A, A->gb, A->db, A->tb, A->gt, A->dt, A->tt);
      ev->tau_lo = 0;
      ev->tau_sw = s;
      hold_hi(A, ev);
      return 1;
    }
    if (A->dt[i] < 0) { lo = s; dlo = A->dt[i]; } else { hi = s; dhi = A->dt[i]; }
  }
  return 0;
}

/* (Past its first test: ad_detect_may, inline in take_step.) */
int ad_detect(adaptive_ws *A, ad_mode *md, double h, ad_event *ev) {
  int m = A->m;
  ev->tau_lo = 0;
  ev->tau_sw = h;
  ev->hi_ok = 0;
  if (any_crossed(A, A->gb, A->tb)) return 1;
  for (int i = 0; i < m; i++) {
    if (!(A->da[i] < 0 && A->db[i] > 0)) continue;
    double at, low = hermite_min(A->ga[i], A->da[i], A->gb[i], A->db[i], h, &at);
    /* the interpolant is only a guide: look closer when it comes down to a
     * quarter of the end values */
    if (low < 0.25 * fmin(A->ga[i], A->gb[i]) && find_dip(A, md, i, h, ev)) return 1;
  }
  return 0;
}

/* The row crossing first: of those crossed at the bracket's end, the one
 * whose secant root comes earliest. */
static int leading(const adaptive_ws *A) {
  int best = -1;
  double tbest = INFINITY;
  for (int i = 0; i < A->m; i++) {
    if (!crossed(A->ga[i], A->ta[i], A->gb[i], A->tb[i])) continue;
    double frac = A->ga[i] / (A->ga[i] - A->gb[i]);
    if (frac < tbest) { tbest = frac; best = i; }
  }
  return best;
}

/* The root of row k from the bracket: a Newton step from the end nearer
 * the secant root when it stays inside, the secant root otherwise. */
static double root_estimate(const adaptive_ws *A, int k, double lo, double hi) {
  double gl = A->ga[k], gh = A->gb[k];
  double sec = lo + (hi - lo) * gl / (gl - gh);
  double nl = A->da[k] < 0 ? lo - gl / A->da[k] : NAN;
  double nh = A->db[k] < 0 ? hi - gh / A->db[k] : NAN;
  double nt = sec - lo < hi - sec ? nl : nh;
  return nt > lo && nt < hi ? nt : sec;
}

void ad_locate(adaptive_ws *A, ad_mode *md, double tolw, ad_event *ev) {
  double lo = ev->tau_lo, hi = ev->tau_sw;
  double floor_ = 16 * DBL_EPSILON * (fabs(ev->t0) + hi);
  /* An event whose delay costs nothing (c = 0: A B_k parallel to B_k) is
   * still switched at its root, not at the step's end: another row may
   * cross later in the step, and its event must come at its own time
   * (issue 27: with long steps two rows' events took the first's time,
   * and a row that crossed and came back was lost). */
  double free_delay = ldexp(hi - lo, -20);
  int k = leading(A), stalls = 0;
  double est = hi;
  for (int it = 0; it < 200 && k >= 0; it++) {
    est = root_estimate(A, k, lo, hi);
    /* The effect of switching a time delta late is (c / 2) delta^2 in x:
     * c = |zeta_k'| ||B_k|| when row k turns off, |s_k'| ||A B_k|| / S_kk
     * when it turns on (docs/adaptive.md). */
    double slope = fmax(fabs(A->db[k]), (A->ga[k] - A->gb[k]) / (hi - lo));
    double c = fmax(ev->cfac * slope * (md->is_zeta[k] ? A->cz[k] : A->cs[k]), ev->cmin);
    double need = c > 0 ? sqrt(2 * AD_EVENT_SHARE * tolw / c) : free_delay;
    need = fmax(need, floor_);
    if (hi - lo <= need) break;
    /* close the bracket around the estimate: from the right first (the
     * switch is at hi), then from the left (which proves the estimate) */
    double s = hi - est > 0.5 * need ? est + 0.5 * need : est - 0.5 * need;
    if (stalls >= 2 || !(s > lo && s < hi)) s = 0.5 * (lo + hi), stalls = 0;
    probe(A, md, s, A->gt, A->dt, A->tt, ev);
    double before = hi - lo;
    if (any_crossed(A, A->gt, A->tt)) {
      hi = s;
      keep(A, A->gb, A->db, A->tb, A->gt, A->dt, A->tt);
      hold_hi(A, ev);
      k = leading(A);
    } else {
      lo = s;
      keep(A, A->ga, A->da, A->ta, A->gt, A->dt, A->tt);
      if (!crossed(A->ga[k], A->ta[k], A->gb[k], A->tb[k])) k = leading(A);
    }
    stalls = hi - lo > 0.5 * before ? stalls + 1 : 0;
  }
  ev->tau_lo = lo;
  ev->tau_sw = hi;
  ev->row = k;
  ev->tau_est = k >= 0 ? est : hi;
}

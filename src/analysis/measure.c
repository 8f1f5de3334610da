/* measure — measurements of one period of a uniformly sampled signal
 * (catchup/pss.h): SPICE's .meas (average, RMS, extremes) and .four
 * (harmonics, THD), by the periodic trapezoid rule and the DFT of the
 * same samples; a signal that jumps at the period's known jump times (a
 * switching, an event: pss_jumps) by the exact figures of its
 * piecewise-linear interpolant with each jump at its own time, its sides
 * extrapolated from the samples on each side (docs/steady-state.md). */
#define _POSIX_C_SOURCE 200809L
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <gsl/gsl_math.h>
#include "catchup.h"
#include "catchup/pss.h"
#include "pss_run.h"
#include "util/fail.h"


int cup_measure_period(const double *v, long N, int order, cup_measure *m, double *amp, double *phase,
                       char *errmsg) {
  if (!v || !m) return fail_fmt(errmsg, CUP_ERR_ARG, "measure: NULL argument");
  if (N < 3) return fail_fmt(errmsg, CUP_ERR_ARG, "measure: %ld samples, at least 3 needed", N);
  long M = N - 1;                                /* v[M] closes the period: v[0 .. M-1] are its samples */
  if (order < 0 || 2L * order >= M)
    return fail_fmt(errmsg, CUP_ERR_ARG, "measure: harmonic order %d needs more than %d samples a period (%ld)",
                    order, 2 * order + 1, N);
  double s = 0, s2 = 0, lo = INFINITY, hi = -INFINITY;
  for (long j = 0; j < N; j++) {
    if (!isfinite(v[j])) return fail_fmt(errmsg, CUP_ERR_NONFINITE, "measure: sample %ld is %g", j, v[j]);
    lo = fmin(lo, v[j]);
    hi = fmax(hi, v[j]);
    if (j < M) { s += v[j]; s2 += v[j] * v[j]; }
  }
  m->avg = s / (double)M;
  m->rms = sqrt(s2 / (double)M);
  m->min = lo;
  m->max = hi;
  m->pp = hi - lo;
  m->thd = NAN;
  double c1 = 0, ch2 = 0;
  for (int k = 0; k <= order; k++) {
    double re = 0, im = 0, w = 2 * M_PI / (double)M;
    for (long j = 0; j < M; j++) {               /* the angle from j k mod M: exact phases for long records */
      double a = w * (double)((j * (long)k) % M);
      re += v[j] * cos(a);
      im -= v[j] * sin(a);
    }
    re /= (double)M;
    im /= (double)M;
    double mag = hypot(re, im);
    if (amp) amp[k] = k ? 2 * mag : re;
    if (phase) phase[k] = k ? atan2(im, re) : 0;
    if (k == 1) c1 = mag;
    if (k >= 2) ch2 += mag * mag;
  }
  if (order >= 1 && c1 > 1e-9 * m->rms) m->thd = sqrt(ch2) / c1;   /* no fundamental (a DC output): NaN */
  return CUP_OK;
}


/* ---- signals that jump: the piecewise-linear interpolant with its jumps ---- */

/* Of a period's samples v[0 .. M] (h = 1) and its jump times, the
 * interpolant: at a jump on sample j (at[j]; listed in jat) the left and
 * right values lv[j], rv[j] (the sample one of them, a one-sided
 * extrapolation the other; elsewhere both are v[j]); in an interval
 * [j, j + 1] holding one (inner[j]; listed in jin) its position th[j] and
 * the values a[j] (its left) and b[j] (its right), real[j] 1 where v jumps
 * there (0: a kink or nothing, the sides only split the integrals). */
typedef struct jump_shape {
  long M, nat, nin;
  long *jat, *jin;
  char *at, *inner, *real;     /* M + 1 each */
  double *lv, *rv, *th, *a, *b;
  double *cs, *sn;             /* M each: cos and -sin of 2 pi m / M (the harmonics' phases), or unset */
} jump_shape;

/* The values on each side of sample j. */
static double left_of(const jump_shape *s, const double *v, long j) { return s->at[j] ? s->lv[j] : v[j]; }
static double right_of(const jump_shape *s, const double *v, long j) { return s->at[j] ? s->rv[j] : v[j]; }

/* Interval [i, i + 1] holds no jump, inside or at its ends: its line
 * extrapolates. */
static int clean(const jump_shape *s, long i) {
  return i >= 0 && i < s->M && !s->inner[i] && !s->at[i] && !s->at[i + 1];
}

/* The jump times (positions p in sample units, sorted) onto the samples
 * and intervals: one within 1e-9 of a sample is on it (at 0 and M, the
 * period's ends, the samples there are each side's already, unless ends:
 * then one there is a jump on sample M, v[M] either side); of several
 * inside one interval the first counts (the piece between them is not
 * sampled: the right side's line stands for it). */
static void place(jump_shape *s, const double *pos, int nj, int ends) {
  for (int q = 0; q < nj; q++) {
    double p = pos[q], r = nearbyint(p);
    if (fabs(p - r) <= 1e-9) {
      long j = (long)r;
      if (ends && (j == 0 || j == s->M)) {
        if (!s->at[s->M]) s->at[s->M] = 1, s->jat[s->nat++] = s->M;
        continue;
      }
      if (j > 0 && j < s->M && !s->at[j]) s->at[j] = 1, s->jat[s->nat++] = j;
      continue;
    }
    long j = (long)floor(p);
    if (j < 0 || j >= s->M || s->inner[j]) continue;
    s->inner[j] = 1;
    s->jin[s->nin++] = j;
    s->th[j] = p - (double)j;
  }
}

/* |v[i + 1] - v[i]|, 0 outside the period: the change over a sample beside
 * a jump time, which an extrapolation's error of a continuous signal stays
 * below (a jump of v smaller than it costs O(h^2) measured as none). */
static double slope(const double *v, long M, long i) { return i >= 0 && i < M ? fabs(v[i + 1] - v[i]) : 0; }

/* Each side's value at each jump time (one on a sample where v does not
 * jump: the sample; one inside an interval: the lines on each side, and
 * real whether v jumps there); 1 if v jumps at one of them or at the
 * period's ends (by more than the change over a sample beside it and 1e-6
 * of scale, v's largest magnitude). */
static int shape(jump_shape *s, const double *v, double scale) {
  long M = s->M;
  double floor_ = 1e-6 * scale;
  int jumps = fabs(v[0] - v[M]) > fabs(v[1] - v[0]) + fabs(v[M] - v[M - 1]) + floor_;   /* at t0 = t0 + T */
  for (long q = 0; q < s->nat; q++) {
    long j = s->jat[q];
    int cl = clean(s, j - 2) && !s->inner[j - 1], cr = clean(s, j + 1) && !s->inner[j];
    double eL = cl ? 2 * v[j - 1] - v[j - 2] : v[j - 1];
    double eR = j == M ? v[0] : cr ? 2 * v[j + 1] - v[j + 2] : v[j + 1];   /* at T: the next period's start */
    s->lv[j] = s->rv[j] = v[j];
    if (fabs(v[j] - eL) <= fabs(v[j] - eR)) s->rv[j] = eR;   /* the sample is the side it continues */
    else s->lv[j] = eL;
    if (fabs(s->rv[j] - s->lv[j]) > slope(v, M, j - 2) + slope(v, M, j == M ? 0 : j + 1) + floor_) jumps = 1;
    else s->lv[j] = s->rv[j] = v[j];            /* no jump of v there (a kink, or nothing) */
  }
  for (long q = 0; q < s->nin; q++) {
    long j = s->jin[q];
    double t = s->th[j];
    s->a[j] = clean(s, j - 1) ? v[j] + t * (v[j] - v[j - 1]) : right_of(s, v, j);
    s->b[j] = clean(s, j + 1) ? v[j + 1] - (1 - t) * (v[j + 2] - v[j + 1]) : left_of(s, v, j + 1);
    s->real[j] = fabs(s->b[j] - s->a[j]) > slope(v, M, j - 1) + slope(v, M, j + 1) + floor_;
    jumps |= s->real[j];
  }
  return jumps;
}

/* The integral over [0, L] (sample units) of the line from y0 to y1 times
 * E(s) = exp(-i (x0 + w s)), w = 2 pi k / M > 0, into (re, im), from E0 =
 * E(0) = c0 + i s0, E1 = E(L) and e^{-i w L} - 1 = dr + i di: by parts,
 * (i / w) (y1 E1 - y0 E0) + (y1 - y0) / (L w^2) (E1 - E0), E1 - E0 taken
 * as E0 (e^{-i w L} - 1) (dr = -2 sin^2(w L / 2): no cancellation). */
static void line_fourier(double c0, double s0, double c1, double s1, double dr, double di, double w, double L,
                         double y0, double y1, double *re, double *im) {
  double er = c0 * dr - s0 * di, ei = c0 * di + s0 * dr;                             /* E1 - E0 */
  double pr = y1 * c1 - y0 * c0, pi = y1 * s1 - y0 * s0, g = (y1 - y0) / (L * w * w);
  *re += -pi / w + g * er;
  *im += pr / w + g * ei;
}

/* e^{-i w L} - 1 into (dr, di). */
static void step_phase(double w, double L, double *dr, double *di) {
  double sh = sin(w * L / 2);
  *dr = -2 * sh * sh;
  *di = -sin(w * L);
}

/* The Fourier coefficient k >= 1 of the interpolant s of v, times M, into
 * (re, im): each sample's phase from the table, a jump's from its time. */
static void shape_fourier(const jump_shape *s, const double *v, int k, double *re, double *im) {
  long M = s->M;
  double w = 2 * M_PI * (double)k / (double)M, dr1, di1;
  step_phase(w, 1, &dr1, &di1);
  *re = *im = 0;
  for (long j = 0; j < M; j++) {
    long m0 = (j * (long)k) % M, m1 = ((j + 1) * (long)k) % M;   /* exact phases for long records */
    double c0 = s->cs[m0], s0 = s->sn[m0], c1 = s->cs[m1], s1 = s->sn[m1];
    double y0 = right_of(s, v, j), y1 = left_of(s, v, j + 1);
    if (!s->inner[j]) {
      line_fourier(c0, s0, c1, s1, dr1, di1, w, 1, y0, y1, re, im);
      continue;
    }
    double t = s->th[j], x = 2 * M_PI * (double)m0 / (double)M + w * t, cx = cos(x), sx = -sin(x), dr, di;
    step_phase(w, t, &dr, &di);
    line_fourier(c0, s0, cx, sx, dr, di, w, t, y0, s->a[j], re, im);
    step_phase(w, 1 - t, &dr, &di);
    line_fourier(cx, sx, c1, s1, dr, di, w, 1 - t, s->b[j], y1, re, im);
  }
}

/* The figures of the interpolant s of v: the exact average, RMS,
 * extremes (m's, the samples', with both sides of each jump) and (order
 * >= 1) Fourier coefficients of the piecewise-linear function with its
 * jumps. */
static void shape_figures(const jump_shape *s, const double *v, int order, cup_measure *m, double *amp,
                          double *phase) {
  long M = s->M;
  double s1 = 0, s2 = 0, lo = m->min, hi = m->max;
  for (long j = 0; j < M; j++) {
    double y0 = right_of(s, v, j), y1 = left_of(s, v, j + 1);
    if (!s->inner[j]) {
      s1 += (y0 + y1) / 2;
      s2 += (y0 * y0 + y0 * y1 + y1 * y1) / 3;
      continue;
    }
    double t = s->th[j], a = s->a[j], b = s->b[j];
    s1 += t * (y0 + a) / 2 + (1 - t) * (b + y1) / 2;
    s2 += t * (y0 * y0 + y0 * a + a * a) / 3 + (1 - t) * (b * b + b * y1 + y1 * y1) / 3;
  }
  for (long q = 0; q < s->nat; q++) {            /* the other side of a jump on a sample */
    long j = s->jat[q];
    lo = fmin(lo, fmin(s->lv[j], s->rv[j]));
    hi = fmax(hi, fmax(s->lv[j], s->rv[j]));
  }
  for (long q = 0; q < s->nin; q++) {            /* both sides of one inside an interval (a kink's: lines) */
    long j = s->jin[q];
    if (!s->real[j]) continue;
    lo = fmin(lo, fmin(s->a[j], s->b[j]));
    hi = fmax(hi, fmax(s->a[j], s->b[j]));
  }
  m->avg = s1 / (double)M;
  m->rms = sqrt(fmax(s2, 0) / (double)M);
  m->min = lo;
  m->max = hi;
  m->pp = hi - lo;
  m->thd = NAN;
  double c1 = 0, ch2 = 0;
  for (int k = 1; k <= order; k++) {
    double re, im;
    shape_fourier(s, v, k, &re, &im);
    re /= (double)M;
    im /= (double)M;
    double mag = hypot(re, im);
    if (amp) amp[k] = 2 * mag;
    if (phase) phase[k] = atan2(im, re);
    if (k == 1) c1 = mag;
    if (k >= 2) ch2 += mag * mag;
  }
  if (amp && order >= 0) amp[0] = m->avg;
  if (phase && order >= 0) phase[0] = 0;
  if (order >= 1 && c1 > 1e-9 * m->rms) m->thd = sqrt(ch2) / c1;
}

static void shape_free(jump_shape *s) {
  if (!s) return;
  free(s->at); free(s->inner); free(s->real); free(s->lv); free(s->jat);
  free(s);
}

/* A jump_shape for N samples and the jumps at times jt[0 .. nj) of a period
 * [t0, t0 + T] (sorted), its phase table for the harmonics if asked; NULL
 * with no jumps (or no memory: *st says). */
static jump_shape *shape_new(long N, const double *jt, int nj, double t0, double T, int harmonics, int ends,
                             int *st) {
  *st = CUP_OK;
  if (nj <= 0 || !jt || !(T > 0) || N < 3) return NULL;
  jump_shape *s = calloc(1, sizeof *s);
  double *pos = malloc(sizeof(double) * (size_t)nj);
  if (s) {
    s->M = N - 1;
    s->at = calloc((size_t)N, 1);
    s->inner = calloc((size_t)N, 1);
    s->real = calloc((size_t)N, 1);
    s->lv = malloc(sizeof(double) * (harmonics > 0 ? 7 : 5) * (size_t)N);
    s->jat = malloc(sizeof(long) * 2 * (size_t)nj);
  }
  if (!s || !pos || !s->at || !s->inner || !s->real || !s->lv || !s->jat) {
    shape_free(s);
    free(pos);
    *st = CUP_ERR_NOMEM;
    return NULL;
  }
  s->jin = s->jat + nj;
  s->rv = s->lv + N; s->th = s->lv + 2 * N; s->a = s->lv + 3 * N; s->b = s->lv + 4 * N;
  if (harmonics > 0) {
    s->cs = s->lv + 5 * N; s->sn = s->lv + 6 * N;
    for (long m = 0; m < s->M; m++) {
      double x = 2 * M_PI * (double)m / (double)s->M;
      s->cs[m] = cos(x);
      s->sn[m] = -sin(x);
    }
  }
  for (int q = 0; q < nj; q++) pos[q] = (jt[q] - t0) / T * (double)s->M;
  place(s, pos, nj, ends);
  free(pos);
  return s;
}

/* cup_measure_period of w, then, if w jumps at s's jumps, the figures of its
 * interpolant with the jumps instead (a signal that does not jump keeps
 * the periodic trapezoid rule and the DFT, bit for bit). */
static int measure_one(const double *w, long N, int order, jump_shape *s, cup_measure *m, double *amp,
                       double *phase, char *errmsg) {
  int st = cup_measure_period(w, N, order, m, amp, phase, errmsg);
  if (!st && s && shape(s, w, fmax(fabs(m->min), fabs(m->max)))) shape_figures(s, w, order, m, amp, phase);
  return st;
}

int cup_measure_period_jumps(const double *v, long N, const double *jump_t, long nj, double t0, double T, int order,
                             cup_measure *m, double *amp, double *phase, char *errmsg) {
  if (nj < 0 || nj > INT_MAX || (nj > 0 && !jump_t))
    return fail_fmt(errmsg, CUP_ERR_ARG, "measure: %ld jump times%s", nj, nj > 0 ? " and none given (NULL)" : "");
  if (!(T > 0) || !isfinite(T) || !isfinite(t0))
    return fail_fmt(errmsg, CUP_ERR_ARG, "measure: the period [%g, %g + %g] must be finite with T > 0", t0, t0, T);
  for (long q = 0; q < nj; q++) {
    if (!(jump_t[q] >= t0 && jump_t[q] <= t0 + T))
      return fail_fmt(errmsg, CUP_ERR_ARG, "measure: jump time %ld (%.17g) outside the period [%.17g, %.17g]", q,
                      jump_t[q], t0, t0 + T);
    if (q > 0 && jump_t[q] < jump_t[q - 1])
      return fail_fmt(errmsg, CUP_ERR_ARG, "measure: jump time %ld (%.17g) before jump time %ld (%.17g): they must "
                      "be sorted", q, jump_t[q], q - 1, jump_t[q - 1]);
  }
  int st;
  jump_shape *s = shape_new(N, jump_t, (int)nj, t0, T, order, 1, &st);   /* NULL: no jumps, or N < 3 */
  if (st) return fail_fmt(errmsg, st, "measure: out of memory");
  st = measure_one(v, N, order, s, m, amp, phase, errmsg);
  shape_free(s);
  return st;
}

/* The average power over the period of signals v and i (their product
 * into w, measured as measure_one measures a signal). */
static int power_of(const double *sig, long N, int ns, int v, int i, double *w, jump_shape *s, double *avg,
                    char *errmsg) {
  if (!sig || !w || !avg || v < 0 || i < 0 || v >= ns || i >= ns)
    return fail_fmt(errmsg, CUP_ERR_ARG, "measure power: NULL argument or signal outside [0, %d)", ns);
  for (long k = 0; k < N; k++) w[k] = sig[k * ns + v] * sig[k * ns + i];
  cup_measure m;
  int st = measure_one(w, N, 0, s, &m, NULL, NULL, errmsg);
  *avg = m.avg;
  return st;
}

int pss_measure(const double *sig, long N, int ns, pss_figures *f, double *w, char *errmsg) {
  int st = CUP_OK, H = f->harmonics;
  jump_shape *s = shape_new(N, f->jt, f->nj, 0, f->T, H, f->ends, &st);
  if (st) return fail_fmt(errmsg, st, "measure: out of memory");
  for (int j = 0; !st && j < f->nm; j++) {
    int c = f->idx ? f->idx[j] : j;
    for (long k = 0; k < N; k++) w[k] = sig[k * ns + c];
    size_t row = (size_t)j * (size_t)(H + 1);
    st = measure_one(w, N, H, s, &f->me[j], f->amp ? f->amp + row : NULL, f->phase ? f->phase + row : NULL, errmsg);
  }
  for (int j = 0; !st && j < f->np; j++) st = power_of(sig, N, ns, f->pv[j], f->pc[j], w, s, &f->power[j], errmsg);
  if (!st && f->eff_out >= 0) f->efficiency = f->power[f->eff_out] / -f->power[f->eff_in];
  shape_free(s);
  return st;
}

int pss_jumps_init(pss_jumps *J, double T, long samples) {
  memset(J, 0, sizeof *J);
  J->T = T;
  J->cap = 4 * samples + 64;
  J->t = malloc(sizeof(double) * (size_t)J->cap);
  return J->t ? CUP_OK : CUP_ERR_NOMEM;
}

void pss_jumps_free(pss_jumps *J) {
  free(J->t);
  J->t = NULL;
  J->n = J->cap = 0;
}

void pss_jumps_add(pss_jumps *J, double t) {
  if (!(t > 0 && t < J->T)) return;              /* the period's ends: its first and last samples */
  if (J->n > 0 && J->t[J->n - 1] == t) return;
  if (J->n < J->cap) J->t[J->n++] = t;
  else J->overflow = 1;
}

void pss_jumps_breaks(pss_jumps *J, const cup_input *u) {
  double t = cup_input_next_break(u, 0);
  for (; t < J->T && !J->overflow; t = cup_input_next_break(u, t)) pss_jumps_add(J, t);
  J->at_ends = fabs(t - J->T) <= 1e-12 * J->T;
}

int pss_jumps_event(double t, int row, int on, void *ctx) {
  pss_jumps *J = ctx;
  pss_jumps_add(J, t);
  return J->on_event ? J->on_event(t, row, on, J->event_ctx) : 0;
}

static int by_time(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

void pss_jumps_finish(pss_jumps *J, pss_figures *f) {
  f->jt = NULL;
  f->nj = 0;
  f->T = J->T;
  f->ends = 0;
  if (J->overflow) return;                       /* more than the samples can resolve: as cup_measure_period */
  qsort(J->t, (size_t)J->n, sizeof(double), by_time);
  long k = 0;                                    /* each time once: an event at a break's time (a */
  for (long q = 0; q < J->n; q++)                /* diode turning on at a PULSE edge) was noted twice */
    if (k == 0 || J->t[q] != J->t[k - 1]) J->t[k++] = J->t[q];
  J->n = k;
  if (J->at_ends && J->n < J->cap) {             /* a break at T is one at 0 too */
    memmove(J->t + 1, J->t, sizeof(double) * (size_t)J->n);
    J->t[0] = 0;
    J->n++;
    f->ends = 1;
  }
  f->jt = J->t;
  f->nj = (int)J->n;
}

int pss_probe_power(cup_netlist *nl, const char *element, int *v, int *i, char *errmsg) {
  const char *a, *b;
  char sv[300], si[300];
  int st = cup_netlist_element_nodes(nl, element, &a, &b, errmsg);
  if (st) return st;
  snprintf(sv, sizeof sv, "v(%.120s,%.120s)", a, b);
  snprintf(si, sizeof si, "i(%.200s)", element);
  if ((*v = cup_netlist_probe(nl, sv, errmsg)) < 0) return *v;
  if ((*i = cup_netlist_probe(nl, si, errmsg)) < 0) return *i;
  return CUP_OK;
}

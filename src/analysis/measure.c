/* measure — measurements of one period of a uniformly sampled signal
 * (catchup/pss.h): SPICE's .meas (average, RMS, extremes) and .four
 * (harmonics, THD), by the periodic trapezoid rule and the DFT of the
 * same samples. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
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

int measure_power(const double *sig, long N, int ns, int v, int i, double *w, double *avg, char *errmsg) {
  if (!sig || !w || !avg || v < 0 || i < 0 || v >= ns || i >= ns)
    return fail_fmt(errmsg, CUP_ERR_ARG, "measure power: NULL argument or signal outside [0, %d)", ns);
  for (long k = 0; k < N; k++) w[k] = sig[k * ns + v] * sig[k * ns + i];
  cup_measure m;
  int st = cup_measure_period(w, N, 0, &m, NULL, NULL, errmsg);
  *avg = m.avg;
  return st;
}

int pss_measure(const double *sig, long N, int ns, pss_figures *f, double *w, char *errmsg) {
  int st = CUP_OK, H = f->harmonics;
  for (int j = 0; !st && j < f->nm; j++) {
    int c = f->idx ? f->idx[j] : j;
    for (long k = 0; k < N; k++) w[k] = sig[k * ns + c];
    size_t row = (size_t)j * (size_t)(H + 1);
    st = cup_measure_period(w, N, H, &f->me[j], f->amp ? f->amp + row : NULL, f->phase ? f->phase + row : NULL,
                            errmsg);
  }
  for (int j = 0; !st && j < f->np; j++) st = measure_power(sig, N, ns, f->pv[j], f->pc[j], w, &f->power[j], errmsg);
  if (!st && f->eff_out >= 0) f->efficiency = f->power[f->eff_out] / -f->power[f->eff_in];
  return st;
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

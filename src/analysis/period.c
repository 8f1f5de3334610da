/* period — the common period of an input's waveforms (catchup/pss.h): the
 * least multiple of every periodic term's period, or the reason there is
 * none, naming the term. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "catchup.h"
#include "catchup/pss.h"
#include "model/input_impl.h"
#include "util/fail.h"

/* T over Tu a whole number, within 1e-9 of it. */
static int whole_multiple(double T, double Tu) {
  double k = nearbyint(T / Tu);
  return k >= 1 && fabs(T / Tu - k) <= 1e-9 * k;
}

/* Periods in a ratio of integers up to this are commensurate. */
#define PERIOD_MAX_MULTIPLE 1000
/* ... to this relative accuracy (50 Hz and 150 Hz: 3 x 1/150 is 1/50 to 1 ulp). */
#define PERIOD_REL 1e-12

/* A term's period (0: constant, any period will do), or < 0 with errmsg.
 * strict: the term must repeat from t = 0; else its period once it repeats
 * (a PWL or a single pulse, constant after their last corner: 0; a delayed
 * PULSE or SIN: their period; cup_input_steady_phase says from when). */
static double term_period(const input_term *t, int k, int strict, char *errmsg) {
  switch (t->kind) {
    case CUP_WAVE_CONSTANT: return 0;
    case CUP_WAVE_SINE:
    case CUP_WAVE_SQUARE: return t->omega > 0 && t->amp != 0 ? 2 * M_PI / t->omega : 0;
    case CUP_WAVE_PWL:
      for (int j = 1; strict && j < t->np; j++)
        if (t->v[j] != t->v[0])
          return fail_fmt(errmsg, CUP_ERR_ARG, "input component %d, term %d (pwl): a PWL source is not periodic "
                          "(it stays at its last value after t = %g); give the steady state a periodic source",
                          t->comp, k, t->t[t->np - 1]), -1;
      return 0;
    case CUP_WAVE_PULSE: {
      if (t->value2 == t->value) return 0;
      if (!(t->period > 0) && !strict) return 0;
      if (!(t->period > 0))
        return fail_fmt(errmsg, CUP_ERR_ARG, "input component %d, term %d (pulse): PULSE with no period (a "
                        "single pulse) is not periodic", t->comp, k), -1;
      /* before its delay the source holds its initial value: [0, T) is a
       * period like the later ones only if the pulse of the period before
       * would have ended by t = 0 */
      if (strict && t->delay + t->rise + t->width + t->fall > t->period * (1 + 1e-12))
        return fail_fmt(errmsg, CUP_ERR_ARG, "input component %d, term %d (pulse): its delay %g makes [0, %g) "
                        "unlike later periods (delay + rise + width + fall = %g > period); shift the pulse by "
                        "a whole period less, or take its period from t0 = %g on (cup_input_steady_phase)",
                        t->comp, k, t->delay, t->period, t->delay + t->rise + t->width + t->fall,
                        fmin(t->delay, t->delay + t->rise + t->width + t->fall - t->period)), -1;
      return t->period;
    }
    case CUP_WAVE_DAMPED_SINE:
      if (t->damping != 0)
        return fail_fmt(errmsg, CUP_ERR_ARG, "input component %d, term %d (SIN): it decays (damping %g): no "
                        "periodic steady state", t->comp, k, t->damping), -1;
      if (strict && t->delay != 0 && t->amp != 0 && t->omega > 0)
        return fail_fmt(errmsg, CUP_ERR_ARG, "input component %d, term %d (SIN): its delay %g makes [0, T) "
                        "unlike later periods; give the steady state an undelayed SIN, or take its period "
                        "from t0 = %g on (cup_input_steady_phase)", t->comp, k, t->delay, t->delay), -1;
      return t->omega > 0 && t->amp != 0 ? 2 * M_PI / t->omega : 0;
  }
  return fail_fmt(errmsg, CUP_ERR_ARG, "input component %d, term %d: unknown waveform", t->comp, k), -1;
}

/* The time from which term t repeats with its period (term_period's, not
 * strict): the end of a PWL's last ramp or of a single pulse (constant
 * after), a SIN's delay, and for a PULSE whose last pulse before its delay
 * would not have ended by then (delay + rise + width + fall > period) the
 * end of that pulse, delay + rise + width + fall - period (within 1e-12 of
 * the period: 0, so that a pulse ending on its period's end keeps t0 = 0). */
static double term_phase(const input_term *t) {
  double rwf = t->rise + t->width + t->fall;
  switch (t->kind) {
    case CUP_WAVE_PWL:
      for (int j = 1; j < t->np; j++)
        if (t->v[j] != t->v[0]) return fmax(0, t->t[t->np - 1]);
      return 0;
    case CUP_WAVE_PULSE:
      if (t->value2 == t->value) return 0;
      if (!(t->period > 0)) return t->delay + rwf;
      if (t->delay + rwf <= t->period * (1 + 1e-12)) return 0;
      return fmin(t->delay, t->delay + rwf - t->period);
    case CUP_WAVE_DAMPED_SINE: return t->amp != 0 && t->omega > 0 ? t->delay : 0;
    default: return 0;
  }
}

/* The least common multiple of the terms' periods in *T: 0, or 1 when the
 * input tells none (a callback, or constant: any period), -1 naming the
 * term that does not repeat, -2 naming two periods with no common one. */
static int common_period(const cup_input *u, int strict, double *T, char *errmsg) {
  *T = 0;
  if (u->fn) return 1;
  double per = 0;
  int first = -1;
  for (int k = 0; k < u->nterms; k++) {
    double p = term_period(&u->terms[k], k, strict, errmsg);
    if (p < 0) return -1;
    if (p == 0) continue;
    if (per == 0) { per = p; first = k; continue; }
    int a = 1;
    for (; a <= PERIOD_MAX_MULTIPLE; a++) {      /* the least a with a per = b p */
      double r = a * per / p, b = nearbyint(r);
      if (b >= 1 && fabs(r - b) <= PERIOD_REL * r) break;
    }
    if (a > PERIOD_MAX_MULTIPLE)
      return fail_fmt(errmsg, CUP_ERR_ARG, "the sources have no common period: input component %d, term %d "
                      "(period %.17g) and term %d (period %.17g) are not in a ratio of integers up to %d",
                      u->terms[k].comp, k, p, first, per, PERIOD_MAX_MULTIPLE), -2;
    per *= a;
  }
  *T = per;
  return per == 0;
}

int cup_input_period(const cup_input *u, double *T, char *errmsg) {
  if (!u || !T) return fail_fmt(errmsg, CUP_ERR_ARG, "input period: NULL argument");
  int c = common_period(u, 1, T, errmsg);
  if (c == -2 && errmsg) {
    size_t n = strlen(errmsg);
    snprintf(errmsg + n, CUP_ERRMSG_LEN - n, "; give the period");
  }
  if (c < 0) return CUP_ERR_ARG;
  if (c > 0 && u->fn)
    return fail_fmt(errmsg, CUP_ERR_ARG, "the input is a callback, which cannot tell its period: give the period");
  if (c > 0)
    return fail_fmt(errmsg, CUP_ERR_ARG, "the input is constant: no period to find a steady state over; give the "
                    "period");
  return CUP_OK;
}

/* A given period must be one over which every source repeats: a whole
 * number of their common period. A source that does not repeat from t = 0
 * (a PWL that changes, a single or delayed pulse, a damped or delayed
 * SIN), or two with no common period, make every T wrong: the run over
 * [0, T) is then no period map, and a fixed point of it no steady state
 * (a full bridge's delayed gates failed at t = 0 with CUP_ERR_LINALG). */
int cup_input_period_fits(const cup_input *u, double T, char *errmsg) {
  double Tu;
  char why[CUP_ERRMSG_LEN];
  if (!u || !(T > 0)) return CUP_OK;
  int c = common_period(u, 1, &Tu, why);
  if (c > 0) return CUP_OK;                      /* a callback or a constant: any period */
  if (c < 0)
    return fail_fmt(errmsg, CUP_ERR_ARG, "the period %.17g: the sources do not repeat over it: %s", T, why);
  if (whole_multiple(T, Tu)) return CUP_OK;
  return fail_fmt(errmsg, CUP_ERR_ARG, "the period %.17g is not a whole number of the sources' common period "
                  "%.17g (%.6g of them): over it the sources do not repeat", T, Tu, T / Tu);
}

int cup_input_steady_phase(const cup_input *u, double period, double *T, double *t0, char *errmsg) {
  if (!T || !t0) return fail_fmt(errmsg, CUP_ERR_ARG, "steady phase: NULL argument");
  *T = period;
  *t0 = 0;
  if (!(*T >= 0) || !isfinite(*T))
    return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: the period %g must be finite and > 0 (or 0: the sources')",
                    *T);
  if (!u) {
    if (*T > 0) return CUP_OK;
    return fail_fmt(errmsg, CUP_ERR_ARG, "steady state: the circuit has no input to take the period from: give the "
                    "period");
  }
  double Tu;
  int c = common_period(u, 0, &Tu, errmsg);
  if (c == -2 && errmsg && !(*T > 0)) {
    size_t n = strlen(errmsg);
    snprintf(errmsg + n, CUP_ERRMSG_LEN - n, "; give the period");
  }
  if (c < 0) return CUP_ERR_ARG;
  if (c > 0 && !(*T > 0))
    return fail_fmt(errmsg, CUP_ERR_ARG, u->fn ? "the input is a callback, which cannot tell its period: give the "
                    "period" : "the input is constant: no period to find a steady state over; give the period");
  if (c == 0 && *T > 0 && !whole_multiple(*T, Tu))
    return fail_fmt(errmsg, CUP_ERR_ARG, "the period %.17g is not a whole number of the sources' common period "
                    "%.17g (%.6g of them): over it the sources do not repeat", *T, Tu, *T / Tu);
  if (!(*T > 0)) *T = Tu;
  for (int k = 0; !u->fn && k < u->nterms; k++) *t0 = fmax(*t0, term_phase(&u->terms[k]));
  return CUP_OK;
}

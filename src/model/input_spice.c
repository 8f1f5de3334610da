/* input_spice — the SPICE source functions as input terms: PULSE (a
 * periodic trapezoid) and SIN with a delay and a damping, with exact values,
 * exact integrals and their breakpoints. */
#include <float.h>
#include <math.h>
#include "catchup.h"
#include "input_impl.h"
#include "util/linalg.h"

#define TWO_PI 6.283185307179586476925286766559

int spice_term_init(input_term *t, const cup_wave *w, char *errmsg) {
  if (w->kind == CUP_WAVE_DAMPED_SINE) {
    if (!isfinite(w->amplitude) || !isfinite(w->frequency) || !isfinite(w->phase) || !isfinite(w->delay) ||
        !isfinite(w->damping))
      return fail_fmt(errmsg, CUP_ERR_NONFINITE, "input: damped sine amplitude %g, frequency %g, phase %g, "
                      "delay %g, damping %g must be finite", w->amplitude, w->frequency, w->phase, w->delay,
                      w->damping);
    if (w->frequency < 0 || w->delay < 0)
      return fail_fmt(errmsg, CUP_ERR_ARG, "input: damped sine frequency %g and delay %g must be >= 0",
                      w->frequency, w->delay);
    if (!isfinite(TWO_PI * w->frequency))
      return fail_fmt(errmsg, CUP_ERR_NONFINITE, "input: frequency %g overflows", w->frequency);
    t->amp = w->amplitude;
    t->omega = TWO_PI * w->frequency;
    t->phase = w->phase;
    t->delay = w->delay;
    t->damping = w->damping;
    return CUP_OK;
  }
  const double v[7] = {w->value, w->value2, w->delay, w->rise, w->fall, w->width, w->period};
  for (int k = 0; k < 7; k++)
    if (!isfinite(v[k]))
      return fail_fmt(errmsg, CUP_ERR_NONFINITE, "input: pulse value %g, value2 %g, delay %g, rise %g, fall %g, "
                      "width %g, period %g must be finite", v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
  for (int k = 2; k < 7; k++)
    if (v[k] < 0)
      return fail_fmt(errmsg, CUP_ERR_ARG, "input: pulse delay %g, rise %g, fall %g, width %g and period %g "
                      "must be >= 0", v[2], v[3], v[4], v[5], v[6]);
  if (w->period > 0 && !(w->period >= w->rise + w->width + w->fall))
    return fail_fmt(errmsg, CUP_ERR_ARG, "input: pulse period %g is shorter than rise + width + fall = %g",
                    w->period, w->rise + w->width + w->fall);
  t->value = w->value;
  t->value2 = w->value2;
  t->delay = w->delay;
  t->rise = w->rise;
  t->fall = w->fall;
  t->width = w->width;
  t->period = w->period;
  return CUP_OK;
}

/* ---- PULSE: one period, shape(s) for s in [0, period) ------------------------ */

/* Value at s >= 0 after the delay; right-continuous at a jump (rise or fall 0). */
static double shape(const input_term *t, double s) {
  if (s < t->rise) return t->value + (t->value2 - t->value) * (s / t->rise);
  s -= t->rise;
  if (s < t->width) return t->value2;
  s -= t->width;
  if (s < t->fall) return t->value2 + (t->value - t->value2) * (s / t->fall);
  return t->value;
}

/* int_a^b shape, 0 <= a <= b (within one period when periodic): trapezoids
 * of the ramps, rectangles of the flat parts. */
static double shape_integral(const input_term *t, double a, double b) {
  const double knot[4] = {0, t->rise, t->rise + t->width, t->rise + t->width + t->fall};
  double sum = 0;
  for (int k = 0; k < 4; k++) {
    double lo = fmax(a, knot[k]), hi = k < 3 ? fmin(b, knot[k + 1]) : b;
    if (!(hi > lo)) continue;
    /* linear on [knot k, knot k+1]: the trapezoid of its end values (at
     * hi, the limit from the left) */
    double vlo = shape(t, lo), vhi;
    if (k == 0) vhi = t->value + (t->value2 - t->value) * (hi / t->rise);
    else if (k == 1 || k == 3) vhi = vlo;
    else vhi = t->value2 + (t->value - t->value2) * ((hi - knot[2]) / t->fall);
    sum += 0.5 * (vlo + vhi) * (hi - lo);
  }
  return sum;
}

/* The corners of a PULSE are delay + P j + c_k, c = {0, rise, rise + width,
 * rise + width + fall}, summed in that order (pulse_break returns them so,
 * and a switching time found from the value lands on one): the value
 * changes piece exactly at those numbers. The period j holding tt >= delay:
 * floor's, moved by one where the quotient rounds across its start (a
 * value an ulp before its own corner: the buck's switchings fell an ulp
 * off the breakpoints, each window paying a piece of length 0). */
static double pulse_period(const input_term *t, double tt) {
  double j = floor((tt - t->delay) / t->period);
  if (t->delay + t->period * j > tt) return j - 1;
  if (t->delay + t->period * (j + 1) <= tt) return j + 1;
  return j;
}

/* The period of tt >= delay: pulse_period's, 0 without a period. */
static double period_of(const input_term *t, double tt) { return t->period > 0 ? pulse_period(t, tt) : 0; }

static double pulse_value(const input_term *t, double tt) {
  double s = tt - t->delay;
  if (s < 0) return t->value;
  double j = period_of(t, tt), base = t->delay + t->period * j;
  if (t->period > 0) s -= t->period * j;
  /* a ramp's fraction clamped to [0, 1] (s rounds apart from tt - base);
   * a ramp shorter than its corner's ulp starts there all the same (the
   * value at the corner is the ramp's start, the jump just after it) */
  double c2 = base + (t->rise + t->width);
  if (tt < base + t->rise || (tt == base && t->rise > 0))
    return t->value + (t->value2 - t->value) * fmin(fmax(s / t->rise, 0), 1);
  if (tt < c2) return t->value2;
  if (tt < base + (t->rise + t->width + t->fall) || (tt == c2 && t->fall > 0))
    return t->value2 + (t->value - t->value2) * fmin(fmax((s - t->rise - t->width) / t->fall, 0), 1);
  return t->value;
}

/* A PULSE with jump edges (rise = fall = 0) at tt, as pulse_value gives
 * it (its branches reduced: value2 on [base, base + width), value
 * elsewhere), and in *hi the end of the piece tt is in: the sums
 * pulse_value compares against (the top's end base + (rise + width) and,
 * through pulse_period, the next period's start), so every time in
 * [tt, *hi) has the value returned, bit for bit. */
double spice_jump_pulse(const input_term *t, double tt, double *hi) {
  double j;
  return spice_jump_pulse_j(t, tt, &j, hi);
}

double spice_jump_pulse_j(const input_term *t, double tt, double *j, double *hi) {
  if (tt - t->delay < 0) {
    *j = -1;
    *hi = t->delay;
    return t->value;
  }
  *j = period_of(t, tt);
  return spice_jump_piece(t, tt, *j, hi);
}


static double pulse_integral(const input_term *t, double a, double b) {
  double sum = 0;
  if (a < t->delay) {
    double e = fmin(b, t->delay);
    sum += t->value * (e - a);
    a = e;
  }
  if (!(b > a)) return sum;
  double sa = a - t->delay, sb = b - t->delay;
  if (!(t->period > 0)) return sum + shape_integral(t, sa, sb);
  double P = t->period, ka = floor(sa / P), kb = floor(sb / P);
  double ra = sa - ka * P, rb = sb - kb * P;
  if (ka == kb) return sum + shape_integral(t, ra, rb);
  return sum + shape_integral(t, ra, P) + (kb - ka - 1) * shape_integral(t, 0, P) + shape_integral(t, 0, rb);
}

/* The next corner after tt (pulse_value's): the least of those of the
 * periods around tt's (the last corner of one and the first of the next
 * may round either way when rise + width + fall = P). The parameters are
 * >= 0 (spice_term_init), so a period's corners do not decrease with k nor
 * its base with j: a period whose last corner is not past tt has none past
 * it, the first corner of each past tt is its least, and a period whose
 * base is not below the least found has none below it (the least of all 12
 * corners, 5 or 6 of them computed: a switched run asks at each window's
 * start and in each search for its next switching time). */
static double pulse_break(const input_term *t, double tt) {
  if (tt < t->delay) return t->delay;
  const double c[4] = {0, t->rise, t->rise + t->width, t->rise + t->width + t->fall};
  double P = t->period, next = INFINITY;
  double j0 = P > 0 ? fmax(pulse_period(t, tt) - 1, 0) : 0;
  for (int j = 0; j < (P > 0 ? 3 : 1); j++) {
    double base = t->delay + P * (j0 + j);
    if (!(base < next)) break;
    if (!(base + c[3] > tt)) continue;             /* (the period before tt's, as a rule) */
    for (int k = 0; k < 4; k++) {
      double b = base + c[k];
      if (b > tt) {
        if (b < next) next = b;
        break;
      }
    }
  }
  return next;
}

/* pulse_break of a PULSE with jump edges in period pp of tt >= delay
 * (pulse_period's): its corners delay + P j and that + (rise + width),
 * pulse_break's sums; past tt and least among periods pp - 1 to pp + 1 only
 * the top's end of pp - 1 (when it rounds past tt), of pp, and the start of
 * pp + 1 can be (the others are below tt or past that start). */
static double jump_break(const input_term *t, double tt, double pp) {
  double P = t->period, w = t->rise + t->width;
  if (!(P > 0)) {
    double c2 = (t->delay + P * 0) + w;
    return c2 > tt ? c2 : INFINITY;
  }
  double next = t->delay + P * (pp + 1), c2 = (t->delay + P * pp) + w;
  if (c2 > tt && c2 < next) next = c2;
  if (pp >= 1) {
    double c1 = (t->delay + P * (pp - 1)) + w;
    if (c1 > tt && c1 < next) next = c1;
  }
  return next;
}

/* (At the break tt from a time in period j: spice_period_after, as spice_jump_pulse_next.) */
double spice_jump_break(const input_term *t, double tt, double *per) {
  if (tt < t->delay) {
    *per = 1;
    return t->delay;
  }
  double j = *per >= 2 ? spice_period_after(t, tt, *per - 2) : period_of(t, tt);
  *per = j + 2;
  return jump_break(t, tt, j);
}

void spice_pulse_line(const input_term *t, double mid, double *t0, double *v0, double *slope) {
  /* the piece holding mid: after its corner (pulse_break's), up to the
   * next; a rise or fall below the corner's ulp leaves two corners equal,
   * and the piece is the later one's (the step is then a jump) */
  const double c[4] = {0, t->rise, t->rise + t->width, t->rise + t->width + t->fall};
  const double from[4] = {t->value, t->value2, t->value2, t->value};
  const double to[4] = {t->value2, t->value2, t->value, t->value};
  *t0 = mid;
  *v0 = t->value;
  *slope = 0;
  if (mid < t->delay) return;
  double P = t->period, base = t->delay + (P > 0 ? P * pulse_period(t, mid) : 0);
  int k = 3;
  while (k > 0 && !(base + c[k] <= mid)) k--;
  double start = base + c[k], end = k < 3 ? base + c[k + 1] : INFINITY;
  *t0 = start;
  *v0 = from[k];
  *slope = to[k] != from[k] && end > start ? (to[k] - from[k]) / (end - start) : 0;
}

/* ---- SIN with delay and damping ------------------------------------------------ */

static double damped_value(const input_term *t, double tt) {
  double s = tt - t->delay;
  if (s < 0) return t->amp * sin(t->phase);
  return t->amp * exp(-t->damping * s) * sin(t->omega * s + t->phase);
}

/* int_s0^s1 e^{-d s} sin(w s + p) ds = Im[e^{i p} e^{z s0} (e^{z h} - 1)/z],
 * z = -d + i w, h = s1 - s0, with e^{z h} - 1 from expm1 and half-angle
 * sines so that a short interval loses no digits. */
static double damped_integral_after(const input_term *t, double s0, double s1) {
  double d = t->damping, w = t->omega, h = s1 - s0;
  if (d == 0 && w == 0) return sin(t->phase) * h;
  double e0 = exp(-d * s0), c0 = cos(w * s0 + t->phase), n0 = sin(w * s0 + t->phase);
  double sh = sin(0.5 * w * h);
  double dr = expm1(-d * h) * cos(w * h) - 2 * sh * sh, di = exp(-d * h) * sin(w * h);
  double nr = c0 * dr - n0 * di, ni = c0 * di + n0 * dr;
  return e0 * (-w * nr - d * ni) / (d * d + w * w);
}

static double damped_integral(const input_term *t, double a, double b) {
  double sum = 0;
  if (a < t->delay) {
    double e = fmin(b, t->delay);
    sum += t->amp * sin(t->phase) * (e - a);
    a = e;
  }
  if (b > a) sum += t->amp * damped_integral_after(t, a - t->delay, b - t->delay);
  return sum;
}

/* ---- dispatch ---------------------------------------------------------------------- */

double spice_term_value(const input_term *t, double tt) {
  return t->kind == CUP_WAVE_PULSE ? pulse_value(t, tt) : damped_value(t, tt);
}

double spice_term_integral(const input_term *t, double a, double b) {
  return t->kind == CUP_WAVE_PULSE ? pulse_integral(t, a, b) : damped_integral(t, a, b);
}

double spice_term_break(const input_term *t, double tt) {
  if (t->kind == CUP_WAVE_PULSE) return t->value2 == t->value ? INFINITY : pulse_break(t, tt);
  return tt < t->delay && t->amp != 0 ? t->delay : INFINITY;
}

int spice_term_constant(const input_term *t) {
  if (t->kind == CUP_WAVE_PULSE) return t->value2 == t->value;
  return t->amp == 0 || (t->omega == 0 && t->damping == 0);
}

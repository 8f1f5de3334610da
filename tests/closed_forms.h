/* Closed-form solutions of small sweeping processes and LCS (derived in the
 * comments and in docs/closed-forms.md), shared by the fixed-step tests
 * (test_integrator.c) and the adaptive scheme's (test_adaptive.c). Event
 * times by bracketing and bisection in long double. Include after cmocka.h
 * and testutil.h. */
#ifndef CUP_CLOSED_FORMS_H
#define CUP_CLOSED_FORMS_H

#include <math.h>

/* (a) An interval of half-width r = 1/2 moving with sin t:
 *     x' in -N_[sin t - r, sin t + r](x), x(0) = 0  (the play operator).
 *   x = 0 until sin t - r reaches it at pi/6; then pushed: sin t - r up to
 *   pi/2; rests at r until the upper edge sin t + r comes down at pi; pushed
 *   down: sin t + r until 3 pi/2; rests at -r until 2 pi; and so on. */
static inline double interval_exact(double t, int i, const void *par) {
  (void)i; (void)par;
  double r = 0.5;
  if (t <= M_PI / 6) return 0;
  if (t <= M_PI / 2) return sin(t) - r;
  double tau = fmod(t - M_PI / 2, 2 * M_PI);
  if (tau <= M_PI / 2) return r;
  if (tau <= M_PI) return sin(t) + r;
  if (tau <= 1.5 * M_PI) return -r;
  return sin(t) - r;
}

/* (a') The same interval with relaxation, x' in -N(x) - x, x(0) = 0. Phases:
 *   free:  x = x_d e^{-(t - t_d)}, until it meets an edge sin t -/+ r;
 *   lower: x = sin t - r while the edge outruns the drift, cos t > -(sin t - r);
 *   upper: x = sin t + r while cos t < -(sin t + r).
 * Event times by bracketing and bisection in long double. */
#define RELAX_MAX 64
typedef struct { int nev; long double t[RELAX_MAX], xd[RELAX_MAX]; int phase[RELAX_MAX]; } relax_par;

static inline long double relax_free(long double xd, long double td, long double t) { return xd * expl(-(t - td)); }

static inline long double relax_event(int phase, long double xd, long double td, long double t) {
  switch (phase) {
    case 0: {                                     /* free: distance to the nearer edge */
      long double x = relax_free(xd, td, t);
      return fminl(x - (sinl(t) - 0.5L), (sinl(t) + 0.5L) - x);
    }
    case 1: return cosl(t) + sinl(t) - 0.5L;      /* lower: detach when < 0 */
    default: return -(cosl(t) + sinl(t) + 0.5L);  /* upper: detach when < 0 */
  }
}

static inline void relax_setup(relax_par *q, double T) {
  q->nev = 1;
  q->t[0] = 0; q->xd[0] = 0; q->phase[0] = 0;
  long double t = 0;
  while (q->nev < RELAX_MAX) {
    int k = q->nev - 1, ph = q->phase[k];
    long double td = q->t[k], xd = q->xd[k], a = t, dt = 1e-3L, b = a + dt;
    while (b < T + 1 && relax_event(ph, xd, td, b) > 0) { a = b; b += dt; }
    if (b >= T + 1) break;
    for (int it = 0; it < 200; it++) {
      long double mid = 0.5L * (a + b);
      if (relax_event(ph, xd, td, mid) > 0) a = mid; else b = mid;
    }
    t = 0.5L * (a + b);
    long double x = ph == 0 ? relax_free(xd, td, t) : ph == 1 ? sinl(t) - 0.5L : sinl(t) + 0.5L;
    int next = ph != 0 ? 0 : (fabsl(x - (sinl(t) - 0.5L)) < fabsl(x - (sinl(t) + 0.5L)) ? 1 : 2);
    q->t[q->nev] = t; q->xd[q->nev] = x; q->phase[q->nev] = next;
    q->nev++;
    t += 1e-9L;
  }
}

static inline double relax_exact(double t, int i, const void *vp) {
  (void)i;
  const relax_par *q = vp;
  int k = 0;
  while (k + 1 < q->nev && q->t[k + 1] <= t) k++;
  switch (q->phase[k]) {
    case 0: return (double)relax_free(q->xd[k], q->t[k], t);
    case 1: return sin(t) - 0.5;
    default: return sin(t) + 0.5;
  }
}

/* (b) The quadrant cone with f = -x + c, c = (1, -1), x(0) = (0, 1):
 *   x1 = 1 - e^-t (inside); x2 = 2 e^-t - 1 until it reaches 0 at ln 2, then
 *   held at 0 since the free drift -1 points out. */
static inline double cone_exact(double t, int i, const void *par) {
  (void)par;
  if (i == 0) return 1 - exp(-t);
  return t <= log(2) ? 2 * exp(-t) - 1 : 0;
}

/* (c) RL half-wave rectifier: L i' = -R i + V sin(w t) + zeta,
 *   0 <= zeta _|_ i >= 0 (zeta = -v_diode); as an LCS A = -R/L, B = 1/L,
 *   C = 1, E = V/L, P = L (P B = C^T). From i(0) = 0 it conducts:
 *     i(t) = V/Z (sin(w t - phi) + sin(phi) e^{-t R/L}),
 *   Z = sqrt(R^2 + w^2 L^2), phi = atan(w L / R), until i returns to 0 at
 *   t_off in (pi/w, 2 pi/w) (found by bisection in long double); then
 *   i = 0 until the source turns positive at 2 pi/w, and the period repeats. */
typedef struct { double R, L, V, w; long double toff; } rect_par;

static inline long double rect_cond(const rect_par *q, long double t) {
  long double Z = sqrtl((long double)q->R * q->R + (long double)q->w * q->w * q->L * q->L);
  long double phi = atanl((long double)q->w * q->L / q->R);
  return q->V / Z * (sinl(q->w * t - phi) + sinl(phi) * expl(-t * q->R / q->L));
}

static inline void rect_setup(rect_par *q) {
  long double lo = M_PIl / q->w, hi = 2 * M_PIl / q->w;
  for (int k = 0; k < 200; k++) {
    long double mid = 0.5L * (lo + hi);
    if (rect_cond(q, mid) > 0) lo = mid; else hi = mid;
  }
  q->toff = 0.5L * (lo + hi);
}

static inline double rect_exact(double t, int i, const void *vp) {
  (void)i;
  const rect_par *q = vp;
  double period = 2 * M_PI / q->w;
  double tau = fmod(t, period);
  if (t > 0 && tau == 0) tau = 0;
  return tau <= q->toff ? (double)rect_cond(q, tau) : 0;
}

/* (d) The quadrant with its corner active: x' = diag(-1, -2) x + (-1, -1),
 *   x(0) = (1, 1), metric P = diag(2, 3) (axis-aligned rows: the same
 *   normals). x1 = 2 e^-t - 1 until ln 2; x2 = 1.5 e^-2t - 0.5 until
 *   ln(3)/2; each then held at 0, both after ln 2. */
static inline double corner_exact(double t, int i, const void *par) {
  (void)par;
  if (i == 0) return t <= log(2) ? 2 * exp(-t) - 1 : 0;
  return t <= 0.5 * log(3) ? 1.5 * exp(-2 * t) - 0.5 : 0;
}

/* (e) A set that jumps: x' = -x, K(t) = {x >= s(t)}, s = sign(sin 2 pi t),
 *   x(0) = 1. On (0, 1/2) s = 1 holds x at 1; on (1/2, 1) s = -1 frees it:
 *   x = e^{-(t - 1/2)}; at t = 1 s(1) = 0 keeps it; just after, s = 1 throws
 *   x up to 1 (a jump), held until 3/2, then free again. The error is
 *   bounded by C h on the grid (n a multiple of 4 puts the jumps on it). */
static inline double jump_exact(double t, int i, const void *par) {
  (void)i; (void)par;
  double tau = fmod(t, 1.0);
  if (t == 0) return 1;
  if (tau == 0) return exp(-0.5);              /* t = 1: K(1) = {x >= 0} */
  return tau <= 0.5 ? 1 : exp(-(tau - 0.5));
}

#endif

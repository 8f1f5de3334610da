/* An independent exact reference for small switched circuits: the circuit's
 * modes written by hand from its physics (which diodes conduct), each an
 * affine ODE in the state x, the input u and its derivative u', with guards
 * (affine functions that stay >= 0 while the mode holds). The input is,
 * piece by piece, u = a sin(w t) + b cos(w t) + d + e (t - ts), so the
 * state and the input's generator (sin, cos, 1, t - ts) obey one linear system per mode
 * and piece, flowed by a matrix exponential in long double; a guard's sign
 * change is found on substeps and located by bisection; the next mode is
 * the first whose guards are nonnegative there (to first order where they
 * are zero). None of this calls the library. */
#ifndef CUP_CIRCUIT_REF_H
#define CUP_CIRCUIT_REF_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define CR_N 4                  /* states at most */
#define CR_K (CR_N + 3)         /* a row over (x_0 .. x_{n-1}, u, u', 1) */
#define CR_Y (CR_N + 4)         /* the flow's state: (x, sin w t, cos w t, 1, t - ts) */
#define CR_G 6                  /* guards per mode at most */

typedef struct { double f[CR_N][CR_K]; int ng; double g[CR_G][CR_K]; } cr_mode;
typedef struct { double a, b, d, e, ts; } cr_piece;   /* u = a sin + b cos + d + e (t - ts) */

typedef struct cr_circuit {
  int n, nmodes;
  cr_mode mode[8];
  double w;                     /* the sine's angular frequency */
  /* u's piece at t (its coefficients) and where it ends */
  void (*piece)(const struct cr_circuit *c, double t, cr_piece *p, double *tend);
  double par[8];                /* the waveform's parameters, for piece */
  double hsub;                  /* the substeps on which guards are checked */
} cr_circuit;

typedef struct { double t0, t1; int mode; cr_piece pc; double y0[CR_Y]; } cr_seg;
typedef struct { const cr_circuit *c; int nseg, cap; cr_seg *seg; } cr_traj;

/* A row over (x, u, u', 1) as a row over y for the piece pc. */
static inline void cr_row_y(const cr_circuit *c, const double *r, const cr_piece *pc, double *out) {
  int n = c->n;
  for (int j = 0; j < n; j++) out[j] = r[j];
  double ru = r[n], rd = r[n + 1];
  out[n] = ru * pc->a - rd * pc->b * c->w;
  out[n + 1] = ru * pc->b + rd * pc->a * c->w;
  out[n + 2] = ru * pc->d + rd * pc->e + r[n + 2];
  out[n + 3] = ru * pc->e;
}

/* The generator of mode k on the piece pc: (n + 4) x (n + 4), row-major. */
static inline void cr_generator(const cr_circuit *c, int k, const cr_piece *pc, double *M) {
  int n = c->n, ny = n + 4;
  memset(M, 0, sizeof(double) * (size_t)ny * ny);
  for (int i = 0; i < n; i++) cr_row_y(c, c->mode[k].f[i], pc, M + (size_t)i * ny);
  M[(size_t)n * ny + n + 1] = c->w;          /* (sin)' = w cos */
  M[(size_t)(n + 1) * ny + n] = -c->w;       /* (cos)' = -w sin */
  M[(size_t)(n + 3) * ny + n + 2] = 1;       /* t' = 1 */
}

/* y(tau) = exp(tau M) y0, by scaling and squaring of a Taylor series in
 * long double (GSL's exponential_ss was off by 2.5e-12 relative on the
 * resonant converter's generator over 10 us, and a reference must be
 * better than what it checks). */
static inline void cr_flow(int ny, const double *M, const double *y0, double tau, double *y) {
  long double X[CR_Y * CR_Y], T[CR_Y * CR_Y], P[CR_Y * CR_Y], W[CR_Y * CR_Y], norm = 0;
  for (int i = 0; i < ny; i++) {
    long double r = 0;
    for (int j = 0; j < ny; j++) r += fabsl((long double)tau * M[i * ny + j]);
    norm = r > norm ? r : norm;
  }
  int sq = 0;
  while (norm > 0.25L) { norm *= 0.5L; sq++; }
  long double sc = ldexpl(1.0L, -sq);
  for (int i = 0; i < ny * ny; i++) { X[i] = (long double)tau * M[i] * sc; P[i] = X[i]; T[i] = X[i]; }
  for (int k = 2; k <= 30; k++) {                /* T = exp(X) - I = X + X^2/2 + ... */
    long double big = 0;
    for (int i = 0; i < ny; i++)
      for (int j = 0; j < ny; j++) {
        long double acc = 0;
        for (int l = 0; l < ny; l++) acc += P[i * ny + l] * X[l * ny + j];
        W[i * ny + j] = acc / k;
      }
    for (int i = 0; i < ny * ny; i++) { P[i] = W[i]; T[i] += P[i]; big = fabsl(P[i]) > big ? fabsl(P[i]) : big; }
    if (big < 1e-24L) break;
  }
  for (int q = 0; q < sq; q++) {                 /* (I + T)^2 = I + (2 T + T^2) */
    for (int i = 0; i < ny; i++)
      for (int j = 0; j < ny; j++) {
        long double acc = 2 * T[i * ny + j];
        for (int l = 0; l < ny; l++) acc += T[i * ny + l] * T[l * ny + j];
        W[i * ny + j] = acc;
      }
    memcpy(T, W, sizeof(long double) * (size_t)(ny * ny));
  }
  for (int i = 0; i < ny; i++) {
    long double acc = y0[i];
    for (int j = 0; j < ny; j++) acc += T[i * ny + j] * y0[j];
    y[i] = (double)acc;
  }
}

static inline double cr_dot(int ny, const double *r, const double *y) {
  double acc = 0;
  for (int j = 0; j < ny; j++) acc += r[j] * y[j];
  return acc;
}

/* Mode k's guards at y into g. */
static inline void cr_guards(const cr_circuit *c, int k, const cr_piece *pc, const double *y, double *g) {
  int ny = c->n + 4;
  double r[CR_Y];
  for (int q = 0; q < c->mode[k].ng; q++) {
    cr_row_y(c, c->mode[k].g[q], pc, r);
    g[q] = cr_dot(ny, r, y);
  }
}

/* Has a guard of mode k crossed at y? Below zero by more than rounding, or
 * below where it started (g0) when it started a rounding below zero. */
static inline int cr_crossed(const cr_circuit *c, int k, const cr_piece *pc, const double *y, const double *g0) {
  int ny = c->n + 4;
  double g[CR_G], scale = 1;
  for (int j = 0; j < ny; j++) scale = fmax(scale, fabs(y[j]));
  cr_guards(c, k, pc, y, g);
  for (int q = 0; q < c->mode[k].ng; q++)
    if (g[q] < fmin(0, g0[q]) - 2e-14 * scale) return 1;
  return 0;
}

/* Mode k continues from y: each guard positive, or zero with a slope >= 0
 * on mode k's own flow. */
static inline int cr_admissible(const cr_circuit *c, int k, const cr_piece *pc, const double *y) {
  int ny = c->n + 4;
  double M[CR_Y * CR_Y], My[CR_Y], r[CR_Y], scale = 1, dscale = 1;
  cr_generator(c, k, pc, M);
  for (int i = 0; i < ny; i++) {
    My[i] = cr_dot(ny, M + (size_t)i * ny, y);
    scale = fmax(scale, fabs(y[i]));
    dscale = fmax(dscale, fabs(My[i]));
  }
  for (int q = 0; q < c->mode[k].ng; q++) {
    cr_row_y(c, c->mode[k].g[q], pc, r);
    double g = cr_dot(ny, r, y), d = cr_dot(ny, r, My);
    if (g < -1e-9 * scale) return 0;
    if (g <= 1e-9 * scale && d < -1e-9 * dscale) return 0;
  }
  return 1;
}

static inline int cr_choose(const cr_circuit *c, const cr_piece *pc, const double *y) {
  for (int k = 0; k < c->nmodes; k++)
    if (cr_admissible(c, k, pc, y)) return k;
  return -1;
}

static inline void cr_push(cr_traj *tr, double t0, double t1, int mode, const cr_piece *pc, const double *y0) {
  if (tr->nseg == tr->cap) {
    tr->cap = tr->cap ? 2 * tr->cap : 256;
    tr->seg = realloc(tr->seg, sizeof(cr_seg) * (size_t)tr->cap);
  }
  cr_seg *s = &tr->seg[tr->nseg++];
  s->t0 = t0; s->t1 = t1; s->mode = mode; s->pc = *pc;
  memcpy(s->y0, y0, sizeof s->y0);
}

/* The trajectory from x0 over [0, T]; 0, or -1 if no mode continues. */
static inline int cr_solve(const cr_circuit *c, const double *x0, double T, cr_traj *tr) {
  int n = c->n, ny = n + 4;
  double y[CR_Y], ya[CR_Y], yb[CR_Y], ym[CR_Y], M[CR_Y * CR_Y], t = 0;
  memset(tr, 0, sizeof *tr);
  tr->c = c;
  memcpy(y, x0, sizeof(double) * (size_t)n);
  y[n] = 0; y[n + 1] = 1; y[n + 2] = 1; y[n + 3] = 0;
  int mode = -1;
  while (t < T) {
    cr_piece pc;
    double tend;
    c->piece(c, t, &pc, &tend);
    tend = fmin(tend, T);
    y[n + 3] = t - pc.ts;
    if (mode < 0 || !cr_admissible(c, mode, &pc, y)) mode = cr_choose(c, &pc, y);
    if (mode < 0) return -1;
    cr_generator(c, mode, &pc, M);
    double ta = t, t_event = -1, g0[CR_G];
    cr_guards(c, mode, &pc, y, g0);
    memcpy(ya, y, sizeof ya);
    while (ta < tend) {                       /* each flow from the segment's start: no drift */
      double tb = fmin(tend, ta + c->hsub);
      cr_flow(ny, M, y, tb - t, yb);
      if (cr_crossed(c, mode, &pc, yb, g0)) {
        double lo = ta, hi = tb;              /* the crossing, by bisection */
        for (int it = 0; it < 200 && hi - lo > 4e-16 * fabs(hi); it++) {
          double mid = 0.5 * (lo + hi);
          cr_flow(ny, M, y, mid - t, ym);
          if (cr_crossed(c, mode, &pc, ym, g0)) hi = mid; else lo = mid;
        }
        cr_flow(ny, M, y, hi - t, yb);
        t_event = hi;
        break;
      }
      ta = tb;
      memcpy(ya, yb, sizeof ya);
    }
    double t1 = t_event >= 0 ? t_event : tend;
    cr_push(tr, t, t1, mode, &pc, y);
    memcpy(y, t_event >= 0 ? yb : ya, sizeof y);
    t = t1;
    if (t_event >= 0) mode = -1;
  }
  return 0;
}

/* x(t) on the trajectory. */
static inline void cr_eval(const cr_traj *tr, double t, double *x) {
  const cr_circuit *c = tr->c;
  int k = 0, ny = c->n + 4;
  while (k + 1 < tr->nseg && tr->seg[k].t1 < t) k++;
  const cr_seg *s = &tr->seg[k];
  double M[CR_Y * CR_Y], y[CR_Y];
  cr_generator(c, s->mode, &s->pc, M);
  cr_flow(ny, M, s->y0, t - s->t0, y);
  memcpy(x, y, sizeof(double) * (size_t)c->n);
}

static inline void cr_free(cr_traj *tr) { free(tr->seg); tr->seg = NULL; tr->nseg = tr->cap = 0; }

/* ---- inputs ---- */

/* par: amplitude, phase offset d; one piece. */
static inline void cr_sine(const cr_circuit *c, double t, cr_piece *p, double *tend) {
  (void)t;
  *p = (cr_piece){c->par[0], 0, c->par[1], 0, 0};
  *tend = INFINITY;
}

/* |amplitude sin w t|: pieces between the zeros. */
static inline void cr_abs_sine(const cr_circuit *c, double t, cr_piece *p, double *tend) {
  double half = M_PI / c->w, k = floor(t / half * (1 + 1e-15));
  *tend = (k + 1) * half;
  *p = (cr_piece){fmod(k, 2) == 0 ? c->par[0] : -c->par[0], 0, 0, 0, 0};
}

/* SPICE's PULSE(V1 V2 TD TR TF PW PER): par[0..6]. */
static inline void cr_pulse(const cr_circuit *c, double t, cr_piece *p, double *tend) {
  const double *q = c->par;
  double v1 = q[0], v2 = q[1], td = q[2], tr = q[3], tf = q[4], pw = q[5], per = q[6];
  if (t < td) { *p = (cr_piece){0, 0, v1, 0, 0}; *tend = td; return; }
  double k = floor((t - td) / per), s = td + k * per, tt = t - s;
  double e1 = tr, e2 = tr + pw, e3 = tr + pw + tf;
  /* pieces by the time within the period; a time a rounding short of a
   * corner belongs to the next piece */
  double eps = 1e-15 * fmax(1, fabs(t));
  if (tt < e1 - eps) { *p = (cr_piece){0, 0, v1, (v2 - v1) / tr, s}; *tend = s + e1; }
  else if (tt < e2 - eps) { *p = (cr_piece){0, 0, v2, 0, s + e1}; *tend = s + e2; }
  else if (tt < e3 - eps) { *p = (cr_piece){0, 0, v2, (v1 - v2) / tf, s + e2}; *tend = s + e3; }
  else { *p = (cr_piece){0, 0, v1, 0, s + e3}; *tend = s + per; }
}

#endif

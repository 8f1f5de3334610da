/* An independent exact reference for ideal switched linear circuits: the
 * converters and rectifiers of examples/circuits. Nothing here calls the
 * library; each circuit's topologies are written by hand from its physics
 * (tests/pwl_circuits.h), not from the netlist formulation.
 *
 * The state is y = (x, w): the circuit's states x and the sources'
 * exosystem w (1 for DC; sin w t, cos w t for sines). A topology (mode) is
 * y' = M y with guards g y >= 0 that hold while it does (a conducting
 * diode's current, a blocking one's reverse voltage), and, where entering
 * it constrains the state (an inductor's only path opened), the jump
 * y <- J y, the projection in the energy metric onto its constraints.
 * Gates are ideal PULSE(0 1 TD jump jump PW PER) signals, a mode belongs to
 * one gate configuration (the bit mask of the gates high) or to all.
 *
 * Between switching times and events the flow is exp(tau M) (long double
 * Taylor series with scaling and squaring, from the segment's start: no
 * drift); gate edges are known times; a guard's sign change is found on
 * substeps of hsub and located by bisection to 1e-14 relative (then a few
 * ulps); the next mode is the first one, in the circuit's order, of the
 * gate configuration in force that is admissible after its jump: each
 * guard positive, or zero with a slope >= 0 on the mode's own flow. */
#ifndef CUP_PWL_REF_H
#define CUP_PWL_REF_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PR_Y 10                 /* (x, w) at most */
#define PR_G 8                  /* guards per mode at most */
#define PR_M 32                 /* modes at most */
#define PR_GATES 4

typedef struct {
  int gate;                     /* the gate configuration it belongs to; -1: every one */
  double M[PR_Y][PR_Y];         /* y' = M y */
  int ng;
  double g[PR_G][PR_Y];         /* g y >= 0 while the mode holds */
  int jump;
  double J[PR_Y][PR_Y];         /* y <- J y on entering (a projection: J J = J) */
} pr_mode;

typedef struct {
  int n, ny, nmodes, ngates;
  pr_mode mode[PR_M];
  double td[PR_GATES], pw[PR_GATES], per[PR_GATES];
  double hsub;                  /* the substeps on which guards are checked */
} pr_circuit;

typedef struct { double t0, t1; int mode; double y0[PR_Y]; } pr_seg;
typedef struct { const pr_circuit *c; int nseg, cap, events, jumps; pr_seg *seg; } pr_traj;

/* Gate i at t: high on [TD + k PER, TD + k PER + PW); the next edge after t.
 * A time a rounding short of an edge belongs to the piece after it. */
static inline double pr_gate(const pr_circuit *c, int i, double t, int *high) {
  double td = c->td[i], pw = c->pw[i], per = c->per[i], eps = 1e-15 * fmax(fabs(t), per);
  if (t < td - eps) { *high = 0; return td; }
  double k = floor((t - td + eps) / per), s = td + k * per;
  if (t < s + pw - eps) { *high = 1; return s + pw; }
  *high = 0;
  return td + (k + 1) * per;
}

static inline int pr_gates(const pr_circuit *c, double t, double *tnext) {
  int mask = 0;
  *tnext = INFINITY;
  for (int i = 0; i < c->ngates; i++) {
    int h;
    *tnext = fmin(*tnext, pr_gate(c, i, t, &h));
    mask |= h << i;
  }
  return mask;
}

/* y = exp(tau M) y0. */
static inline void pr_flow(int ny, const double M[PR_Y][PR_Y], const double *y0, double tau, double *y) {
  long double X[PR_Y][PR_Y], T[PR_Y][PR_Y], P[PR_Y][PR_Y], W[PR_Y][PR_Y], norm = 0;
  for (int i = 0; i < ny; i++) {
    long double r = 0;
    for (int j = 0; j < ny; j++) r += fabsl((long double)tau * M[i][j]);
    norm = r > norm ? r : norm;
  }
  int sq = 0;
  while (norm > 0.25L) { norm *= 0.5L; sq++; }
  long double sc = ldexpl(1.0L, -sq);
  for (int i = 0; i < ny; i++)
    for (int j = 0; j < ny; j++) X[i][j] = P[i][j] = T[i][j] = (long double)tau * M[i][j] * sc;
  for (int k = 2; k <= 30; k++) {                /* T = exp(X) - I */
    long double big = 0;
    for (int i = 0; i < ny; i++)
      for (int j = 0; j < ny; j++) {
        long double acc = 0;
        for (int l = 0; l < ny; l++) acc += P[i][l] * X[l][j];
        W[i][j] = acc / k;
      }
    for (int i = 0; i < ny; i++)
      for (int j = 0; j < ny; j++) { P[i][j] = W[i][j]; T[i][j] += P[i][j]; big = fmaxl(big, fabsl(P[i][j])); }
    if (big < 1e-24L) break;
  }
  for (int q = 0; q < sq; q++) {                 /* (I + T)^2 = I + (2 T + T^2) */
    for (int i = 0; i < ny; i++)
      for (int j = 0; j < ny; j++) {
        long double acc = 2 * T[i][j];
        for (int l = 0; l < ny; l++) acc += T[i][l] * T[l][j];
        W[i][j] = acc;
      }
    memcpy(T, W, sizeof T);
  }
  for (int i = 0; i < ny; i++) {
    long double acc = y0[i];
    for (int j = 0; j < ny; j++) acc += T[i][j] * y0[j];
    y[i] = (double)acc;
  }
}

static inline double pr_dot(int ny, const double *r, const double *y) {
  long double acc = 0;
  for (int j = 0; j < ny; j++) acc += (long double)r[j] * y[j];
  return (double)acc;
}

static inline double pr_scale(int ny, const double *y) {
  double s = 1;
  for (int j = 0; j < ny; j++) s = fmax(s, fabs(y[j]));
  return s;
}

/* Has a guard of mode k crossed at y? Below zero by more than rounding, or
 * below where it started (g0) when it started a rounding below zero. */
static inline int pr_crossed(const pr_circuit *c, int k, const double *y, const double *g0) {
  double scale = pr_scale(c->ny, y);
  for (int q = 0; q < c->mode[k].ng; q++)
    if (pr_dot(c->ny, c->mode[k].g[q], y) < fmin(0, g0[q]) - 2e-14 * scale) return 1;
  return 0;
}

/* Mode k continues from y: each guard positive, or zero with a slope >= 0. */
static inline int pr_admissible(const pr_circuit *c, int k, const double *y) {
  int ny = c->ny;
  const pr_mode *m = &c->mode[k];
  double My[PR_Y], scale = pr_scale(ny, y), dscale = 1;
  for (int i = 0; i < ny; i++) { My[i] = pr_dot(ny, m->M[i], y); dscale = fmax(dscale, fabs(My[i])); }
  for (int q = 0; q < m->ng; q++) {
    double g = pr_dot(ny, m->g[q], y), d = pr_dot(ny, m->g[q], My);
    if (g < -1e-9 * scale) return 0;
    if (g <= 1e-9 * scale && d < -1e-9 * dscale) return 0;
  }
  return 1;
}

static inline void pr_apply_jump(const pr_circuit *c, int k, const double *y, double *out) {
  if (!c->mode[k].jump) { memcpy(out, y, sizeof(double) * PR_Y); return; }
  for (int i = 0; i < c->ny; i++) out[i] = pr_dot(c->ny, c->mode[k].J[i], y);
}

/* The first admissible mode of gate configuration gc at y (after its jump,
 * into y), or -1. */
static inline int pr_choose(const pr_circuit *c, int gc, double *y) {
  double yj[PR_Y];
  for (int k = 0; k < c->nmodes; k++) {
    if (c->mode[k].gate >= 0 && c->mode[k].gate != gc) continue;
    pr_apply_jump(c, k, y, yj);
    if (pr_admissible(c, k, yj)) { memcpy(y, yj, sizeof yj); return k; }
  }
  return -1;
}

static inline void pr_push(pr_traj *tr, double t0, double t1, int mode, const double *y0) {
  if (tr->nseg == tr->cap) {
    tr->cap = tr->cap ? 2 * tr->cap : 1024;
    tr->seg = realloc(tr->seg, sizeof(pr_seg) * (size_t)tr->cap);
  }
  pr_seg *s = &tr->seg[tr->nseg++];
  s->t0 = t0; s->t1 = t1; s->mode = mode;
  memcpy(s->y0, y0, sizeof s->y0);
}

/* The trajectory from y0 = (x0, w0) over [0, T]; 0, or -1 if no mode
 * continues (a topology the circuit's list lacks), -2 if out of memory. */
static inline int pr_solve(const pr_circuit *c, const double *y0, double T, pr_traj *tr) {
  int ny = c->ny;
  double y[PR_Y] = {0}, ya[PR_Y], yb[PR_Y], ym[PR_Y], t = 0;
  memset(tr, 0, sizeof *tr);
  tr->c = c;
  memcpy(y, y0, sizeof(double) * (size_t)ny);
  int mode = -1;
  while (t < T) {
    double tend;
    int gc = pr_gates(c, t, &tend);
    tend = fmin(tend, T);
    if (mode < 0 || (c->mode[mode].gate >= 0 && c->mode[mode].gate != gc) || !pr_admissible(c, mode, y)) {
      double before[PR_Y];
      memcpy(before, y, sizeof before);
      mode = pr_choose(c, gc, y);
      if (mode < 0) return -1;
      double scale = pr_scale(c->n, before);      /* a jump moves a state beyond its rounding */
      for (int i = 0; i < c->n; i++)
        if (fabs(y[i] - before[i]) > 1e-9 * scale) { tr->jumps++; break; }
    }
    double g0[PR_G], t_event = -1, ta = t;
    for (int q = 0; q < c->mode[mode].ng; q++) g0[q] = pr_dot(ny, c->mode[mode].g[q], y);
    memcpy(ya, y, sizeof ya);
    while (ta < tend) {
      double tb = fmin(tend, ta + c->hsub);
      pr_flow(ny, c->mode[mode].M, y, tb - t, yb);
      if (pr_crossed(c, mode, yb, g0)) {
        double lo = ta, hi = tb;               /* bracketed: bisect to 1e-14 relative, then to ulps */
        for (int it = 0; it < 200 && hi - lo > 4e-16 * fabs(hi); it++) {
          double mid = 0.5 * (lo + hi);
          pr_flow(ny, c->mode[mode].M, y, mid - t, ym);
          if (pr_crossed(c, mode, ym, g0)) hi = mid; else lo = mid;
        }
        pr_flow(ny, c->mode[mode].M, y, hi - t, yb);
        t_event = hi;
        break;
      }
      ta = tb;
      memcpy(ya, yb, sizeof ya);
    }
    double t1 = t_event >= 0 ? t_event : tend;
    pr_push(tr, t, t1, mode, y);
    if (!tr->seg) return -2;
    memcpy(y, t_event >= 0 ? yb : ya, sizeof y);
    t = t1;
    if (t_event >= 0) { mode = -1; tr->events++; }
  }
  return 0;
}

/* y(t) on the trajectory (the value after a jump at a segment's start). */
static inline void pr_eval_y(const pr_traj *tr, double t, double *y) {
  int lo = 0, hi = tr->nseg - 1;
  while (lo < hi) {                              /* the last segment with t0 <= t */
    int mid = (lo + hi + 1) / 2;
    if (tr->seg[mid].t0 <= t) lo = mid; else hi = mid - 1;
  }
  const pr_seg *s = &tr->seg[lo];
  pr_flow(tr->c->ny, tr->c->mode[s->mode].M, s->y0, t - s->t0, y);
}

/* The value before a jump at t (the first segment with t1 >= t). */
static inline void pr_eval_left(const pr_traj *tr, double t, double *x) {
  int lo = 0, hi = tr->nseg - 1;
  while (lo < hi) {
    int mid = (lo + hi) / 2;
    if (tr->seg[mid].t1 >= t) hi = mid; else lo = mid + 1;
  }
  const pr_seg *s = &tr->seg[lo];
  double y[PR_Y];
  pr_flow(tr->c->ny, tr->c->mode[s->mode].M, s->y0, t - s->t0, y);
  memcpy(x, y, sizeof(double) * (size_t)tr->c->n);
}

static inline void pr_eval(const pr_traj *tr, double t, double *x) {
  double y[PR_Y];
  pr_eval_y(tr, t, y);
  memcpy(x, y, sizeof(double) * (size_t)tr->c->n);
}

/* The mean of the row r y over [a, b], exactly: on each piece the integral
 * is one more state of the flow, q' = r y (needs ny < PR_Y). */
static inline double pr_mean(const pr_traj *tr, const double *r, double a, double b) {
  int ny = tr->c->ny;
  long double acc = 0;
  for (int k = 0; k < tr->nseg; k++) {
    const pr_seg *s = &tr->seg[k];
    double t0 = fmax(a, s->t0), t1 = fmin(b, s->t1), M[PR_Y][PR_Y] = {{0}}, z0[PR_Y] = {0}, z[PR_Y];
    if (t1 <= t0) continue;
    for (int i = 0; i < ny; i++) memcpy(M[i], tr->c->mode[s->mode].M[i], sizeof(double) * (size_t)ny);
    memcpy(M[ny], r, sizeof(double) * (size_t)ny);
    pr_flow(ny, tr->c->mode[s->mode].M, s->y0, t0 - s->t0, z0);
    pr_flow(ny + 1, M, z0, t1 - t0, z);
    acc += z[ny];
  }
  return (double)(acc / (b - a));
}

static inline void pr_free(pr_traj *tr) { free(tr->seg); tr->seg = NULL; tr->nseg = tr->cap = 0; }

#endif

/* Helpers shared by the stress tests (tests/test_stress_*.c): a small LCS
 * from dense matrices, sinks that keep a whole trajectory, and a constant
 * or sine input. Include after cmocka.h and testutil.h. */
#ifndef CUP_STRESS_UTIL_H
#define CUP_STRESS_UTIL_H

#include <stdio.h>
#include "testutil.h"

/* An LCS from dense row-major matrices (absent ones: NULL). P: NULL for the
 * identity, Pdiag for a diagonal metric, or Pfull (n x n row-major, SPD). */
typedef struct { tcsc A, B, C, E, G, P; cup_lcs *L; } lcs_built;

static inline int build_lcs(lcs_built *b, int n, int m, int p, const double *A, const double *B,
                            const double *C, const double *E, const double *F, const double *G,
                            const double *Pdiag, const double *Pfull, char *msg) {
  memset(b, 0, sizeof *b);
  cup_lcs_desc d;
  memset(&d, 0, sizeof d);
  d.n = n; d.m = m; d.p = p;
  if (A) { tcsc_from_dense(&b->A, A, n, n); d.A = b->A.view; }
  if (B) { tcsc_from_dense(&b->B, B, n, m); d.B = b->B.view; }
  tcsc_from_dense(&b->C, C, m, n); d.C = b->C.view;
  if (E) { tcsc_from_dense(&b->E, E, n, p); d.E = b->E.view; }
  if (G) { tcsc_from_dense(&b->G, G, m, p); d.G = b->G.view; }
  d.F = F;
  if (Pdiag) d.P = (cup_metric){CUP_METRIC_DIAGONAL, Pdiag, {0}, 0};
  if (Pfull) {
    tcsc_from_dense(&b->P, Pfull, n, n);
    d.P = (cup_metric){CUP_METRIC_SPARSE, NULL, b->P.view, 0};
  }
  return cup_lcs_create(&b->L, &d, msg);
}

static inline void unbuild_lcs(lcs_built *b) {
  cup_lcs_free(&b->L);
  if (b->A.p) tcsc_free(&b->A);
  if (b->B.p) tcsc_free(&b->B);
  if (b->C.p) tcsc_free(&b->C);
  if (b->E.p) tcsc_free(&b->E);
  if (b->G.p) tcsc_free(&b->G);
  if (b->P.p) tcsc_free(&b->P);
}

/* A whole trajectory: rows k = 0..n of dim entries, and the times. */
typedef struct { int dim; long rows, cap; double *t, *X; } traj;

static inline void traj_init(traj *tr, int dim, long cap) {
  tr->dim = dim; tr->rows = 0; tr->cap = cap;
  tr->t = malloc(sizeof(double) * (size_t)cap);
  tr->X = malloc(sizeof(double) * (size_t)cap * (size_t)dim);
}
static inline void traj_free(traj *tr) { free(tr->t); free(tr->X); tr->t = tr->X = NULL; }

static inline int traj_sink(long k, double t, const double *x, void *ctx) {
  traj *tr = ctx;
  (void)k;
  if (tr->rows >= tr->cap) return 1;
  tr->t[tr->rows] = t;
  memcpy(tr->X + (size_t)tr->rows * (size_t)tr->dim, x, sizeof(double) * (size_t)tr->dim);
  tr->rows++;
  return 0;
}

static inline cup_input *input_terms(int nterm, const cup_wave *w) {
  cup_input *u = NULL;
  if (cup_input_create(&u, 1, NULL)) return NULL;
  for (int k = 0; k < nterm; k++)
    if (cup_input_add(u, 0, &w[k], NULL)) { cup_input_free(&u); return NULL; }
  return u;
}

/* The adaptive scheme's options over [0, T] at tol_abs, tol_rel, with
 * `samples` output times (the rest the defaults). */
static inline void adaptive_options(cup_integrator_options *o, double T, double tol_abs, double tol_rel,
                                    long samples) {
  cup_integrator_options_default(o);
  o->scheme = CUP_SCHEME_ADAPTIVE;
  o->T = T;
  o->tol_abs = tol_abs;
  o->tol_rel = tol_rel;
  o->output = CUP_OUTPUT_SAMPLES;
  o->output_samples = samples;
}

/* Events that accumulate at t = 1/2: u = (zigzag, -1), the zigzag's 200
 * teeth of widths 0.05 0.9^k (summing to 1/2) rising from 0 over the share
 * `rise` of each width to `height` times it, falling back to 0 over the
 * rest, then 0. Its rows: x' = zeta - 1 pushed up by the teeth. */
static inline cup_input *zigzag_input(double rise, double height) {
  enum { TEETH = 200 };
  double tt[2 * TEETH + 1], vv[2 * TEETH + 1], t = 0, d = 0.05;
  for (int k = 0; k < TEETH; k++, d *= 0.9) {       /* sum of d = 1/2 */
    tt[2 * k] = t;
    vv[2 * k] = 0;
    tt[2 * k + 1] = t + rise * d;
    vv[2 * k + 1] = height * d;
    t += d;
  }
  tt[2 * TEETH] = t;
  vv[2 * TEETH] = 0;
  cup_input *u = NULL;
  assert_int_equal(cup_input_create(&u, 2, NULL), CUP_OK);
  cup_wave zig = {.kind = CUP_WAVE_PWL, .npoints = 2 * TEETH + 1, .t = tt, .v = vv};
  cup_wave down = {.kind = CUP_WAVE_CONSTANT, .value = -1};
  assert_int_equal(cup_input_add(u, 0, &zig, NULL), CUP_OK);
  assert_int_equal(cup_input_add(u, 1, &down, NULL), CUP_OK);
  return u;
}

#endif

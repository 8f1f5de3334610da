/* estimate — see estimate.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "estimate.h"

int estimate_init(estimate_ws *E, long n, int dim) {
  memset(E, 0, sizeof *E);
  long half = n / 2;
  E->n = n;
  E->stride = (half + CUP_ESTIMATE_POINTS - 1) / CUP_ESTIMATE_POINTS;
  E->dim = dim;
  E->X = malloc(sizeof(double) * (size_t)dim * (size_t)(half / E->stride + 2));
  return E->X ? CUP_OK : CUP_ERR_NOMEM;
}

void estimate_free(estimate_ws *E) {
  free(E->X);
  free(E->hist);
  memset(E, 0, sizeof *E);
}

/* Coarse step k goes to row k / s, the last one (k = n/2) to the row after. */
int estimate_keep(long k, double t, const double *x, void *ctx) {
  (void)t;
  estimate_ws *E = ctx;
  long half = E->n / 2, row = k % E->stride == 0 ? k / E->stride : half / E->stride + 1;
  memcpy(E->X + (size_t)row * (size_t)E->dim, x, sizeof(double) * (size_t)E->dim);
  return 0;
}

void estimate_start(estimate_ws *E, int ok) {
  E->ok = ok;
  E->err = 0;
  E->held = 0;
}

int estimate_samples(estimate_ws *E, const cup_integrator_options *o) {
  E->interp = 0;
  if (o->output != CUP_OUTPUT_SAMPLES || o->output_samples < 2 || o->n < 1) return CUP_OK;
  E->h = o->T / (double)o->n;
  E->t0 = o->output_t0;
  E->ds = (o->T - o->output_t0) / (double)(o->output_samples - 1);
  E->jmax = (double)(o->output_samples - 1);
  if (!E->hist && !(E->hist = malloc(sizeof(double) * 2 * (size_t)E->dim))) return CUP_ERR_NOMEM;
  E->interp = 1;
  E->held = 0;
  return CUP_OK;
}

/* Step k (t_{k-1}, t_k] has a sample inside it, off its ends (by more than
 * 1e-9 h: a sample on a grid time to rounding is that time's state). */
static int inside(const estimate_ws *E, long k) {
  double ta = (double)(k - 1) * E->h, tb = (double)k * E->h, m = 1e-9 * E->h;
  double j = floor((ta + m - E->t0) / E->ds) + 1;
  if (j < 0) j = 0;
  return j <= E->jmax && E->t0 + j * E->ds < tb - m;
}

/* Step last_k's samples inside it: their interpolation's error from its
 * backward difference (D_k, ok_back) and forward one (D_{k+1}, ok_fwd).
 * For an event a fraction f into the step, D_k = h (1 - f) |s| and
 * D_{k+1} = h f |s| (s: the jump in x'), and the interpolation's error is
 * h f (1 - f) |s| = D_k D_{k+1} / (D_k + D_{k+1}); on a smooth stretch that
 * is h^2 |x''| / 2, four times the error. With one difference only (the
 * run's first or last step, or at a jump) that one, an upper bound. */
static void interp_close(estimate_ws *E, int ok_fwd, double fwd) {
  if (!E->inside_last) return;
  double e;
  if (E->back_ok && ok_fwd) e = E->back + fwd > 0 ? E->back * fwd / (E->back + fwd) : 0;
  else if (E->back_ok) e = E->back;
  else if (ok_fwd) e = fwd;
  else return;
  E->err = fmax(E->err, e);
}

void estimate_anchor(estimate_ws *E, long k, const double *x) {
  if (!E->interp) return;
  if (E->held && E->last_k == k && !memcmp(E->hist, x, sizeof(double) * (size_t)E->dim)) return;   /* no jump */
  if (E->held && E->last_k == k) interp_close(E, 0, 0);
  memcpy(E->hist, x, sizeof(double) * (size_t)E->dim);
  E->last_k = k;
  E->held = 1;
  E->inside_last = 0;
  E->back_ok = 0;
}

static void interp_step(estimate_ws *E, long k, const double *x) {
  double *x1 = E->hist, *x2 = E->hist + E->dim;
  if (E->held && E->last_k != k - 1) {             /* (a gap: the differences start again) */
    interp_close(E, 0, 0);
    E->held = 0;
  }
  int ok = E->held == 2;
  double d = 0;
  if (ok)
    for (int i = 0; i < E->dim; i++) d = fmax(d, fabs(x[i] - 2 * x1[i] + x2[i]));
  if (E->held) interp_close(E, ok, d);             /* step k - 1: D_{k-1} and D_k */
  memcpy(x2, x1, sizeof(double) * (size_t)E->dim);
  memcpy(x1, x, sizeof(double) * (size_t)E->dim);
  E->held = E->held < 2 ? E->held + 1 : 2;
  E->last_k = k;
  E->inside_last = inside(E, k);
  E->back = d;
  E->back_ok = ok;
  if (k == E->n) interp_close(E, 0, 0);            /* the last step: D_n alone */
}

void estimate_compare(estimate_ws *E, long k, const double *x) {
  if (E->interp) interp_step(E, k, x);
  long half = E->n / 2;
  const double *c;
  if (k == E->n) c = E->X + (size_t)(half / E->stride + (half % E->stride != 0)) * (size_t)E->dim;
  else if (k % (2 * E->stride) == 0) c = E->X + (size_t)(k / (2 * E->stride)) * (size_t)E->dim;
  else return;
  for (int i = 0; i < E->dim; i++) E->err = fmax(E->err, fabs(x[i] - c[i]));
}

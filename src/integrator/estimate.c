/* estimate — see estimate.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "estimate.h"
#include "util/linalg.h"

int cup_estimate_init(cup_estimate *E, const cup_lcs *L, const cup_input *u,
                      const cup_integrator_options *o, char *errmsg) {
  memset(E, 0, sizeof *E);
  cup_integrator_options h = *o;
  h.n = o->n / 2;
  h.estimate = 0;
  h.output = CUP_OUTPUT_EVERY;
  h.on_step = NULL;
  h.on_event = NULL;
  E->n = o->n;
  E->stride = (h.n + CUP_ESTIMATE_POINTS - 1) / CUP_ESTIMATE_POINTS;
  h.output_every = E->stride;
  E->dim = cup_lcs_dim(L);
  E->X = malloc(sizeof(double) * (size_t)E->dim * (size_t)(h.n / E->stride + 2));
  if (!E->X) return cup_fail(errmsg, CUP_ERR_NOMEM, "error estimate: out of memory");
  int st = cup_integrator_create(&E->half, L, u, &h, errmsg);
  if (st) { free(E->X); E->X = NULL; }
  return st;
}

void cup_estimate_free(cup_estimate *E) {
  cup_integrator_free(&E->half);
  free(E->X);
  memset(E, 0, sizeof *E);
}

/* Coarse step k goes to row k / s, the last one (k = n/2) to the row after. */
static int keep(long k, double t, const double *x, void *ctx) {
  (void)t;
  cup_estimate *E = ctx;
  long half = E->n / 2, row = k % E->stride == 0 ? k / E->stride : half / E->stride + 1;
  memcpy(E->X + (size_t)row * (size_t)E->dim, x, sizeof(double) * (size_t)E->dim);
  return 0;
}

void cup_estimate_prepare(cup_estimate *E, const double *x0) {
  cup_run_info info;
  E->err = 0;
  E->ok = cup_integrator_run(E->half, x0, keep, E, &info) >= 0;
}

void cup_estimate_compare(cup_estimate *E, long k, const double *x) {
  long half = E->n / 2;
  const double *c;
  if (k == E->n) c = E->X + (size_t)(half / E->stride + (half % E->stride != 0)) * (size_t)E->dim;
  else if (k % (2 * E->stride) == 0) c = E->X + (size_t)(k / (2 * E->stride)) * (size_t)E->dim;
  else return;
  for (int i = 0; i < E->dim; i++) E->err = fmax(E->err, fabs(x[i] - c[i]));
}

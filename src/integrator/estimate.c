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
}

void estimate_compare(estimate_ws *E, long k, const double *x) {
  long half = E->n / 2;
  const double *c;
  if (k == E->n) c = E->X + (size_t)(half / E->stride + (half % E->stride != 0)) * (size_t)E->dim;
  else if (k % (2 * E->stride) == 0) c = E->X + (size_t)(k / (2 * E->stride)) * (size_t)E->dim;
  else return;
  for (int i = 0; i < E->dim; i++) E->err = fmax(E->err, fabs(x[i] - c[i]));
}

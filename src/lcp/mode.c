/* mode — see mode.h. */
#include <stdlib.h>
#include <string.h>
#include "mode.h"

int lcp_modes_init(lcp_modes *c, int n, int m) {
  memset(c, 0, sizeof *c);
  c->n = n, c->m = m;
  size_t N = (size_t)n, M = (size_t)m, per = 3 * M * M + N * M + M;
  c->mem = calloc(LCP_MODES * per + 1, sizeof(double));
  c->imem = calloc(LCP_MODES * M + 1, sizeof(int));
  if (!c->mem || !c->imem) return 1;
  for (int e = 0; e < LCP_MODES; e++) {
    lcp_mode *E = &c->md[e];
    double *d = c->mem + (size_t)e * per;
    E->Z = d, E->M = d + M * M, E->Ms = d + 2 * M * M, E->H = d + 3 * M * M, E->rsc = E->H + N * M;
    E->kc = c->imem + (size_t)e * M;
    E->n = n, E->m = m;
  }
  return 0;
}

void lcp_modes_free(lcp_modes *c) {
  free(c->mem);
  free(c->imem);
  memset(c, 0, sizeof *c);
}

lcp_mode *lcp_modes_get(lcp_modes *c, unsigned long long J) {
  for (int e = 0; e < LCP_MODES; e++)
    if (c->md[e].state && c->md[e].J == J) return &c->md[e];
  lcp_mode *E = &c->md[c->next];
  c->next = (c->next + 1) % LCP_MODES;
  E->J = J;
  E->state = 0;
  return E;
}

void lcp_mode_copy(lcp_mode *E, double *H, double *M, double *Ms, double *rsc, int *lam_sparse, int to) {
  size_t n = (size_t)E->n, m = (size_t)E->m;
  double *ours[4] = {E->H, E->M, E->Ms, E->rsc}, *theirs[4] = {H, M, Ms, rsc};
  size_t len[4] = {n * m, m * m, m * m, m};
  for (int a = 0; a < 4; a++)
    memcpy(to ? ours[a] : theirs[a], to ? theirs[a] : ours[a], sizeof(double) * len[a]);
  if (to) E->lam_sparse = *lam_sparse;
  else *lam_sparse = E->lam_sparse;
}

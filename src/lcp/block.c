/* block — see block.h. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "block.h"

int lcp_blocks_init(lcp_blocks *c, int m) {
  memset(c, 0, sizeof *c);
  c->m = m;
  size_t M = (size_t)m;
  c->mem = calloc(LCP_BLOCKS * 5 * M * M + 1, sizeof(double));
  c->imem = calloc(LCP_BLOCKS * 2 * M + 1, sizeof(int));
  if (!c->mem || !c->imem) return 1;
  for (int b = 0; b < LCP_BLOCKS; b++) {
    lcp_block *B = &c->blk[b];
    double *d = c->mem + (size_t)b * 5 * M * M;
    B->lu = d, B->Ws = d + M * M, B->Ma = d + 2 * M * M, B->Dg = d + 3 * M * M, B->Da = d + 4 * M * M;
    B->idx = c->imem + (size_t)b * 2 * M;
    B->piv = B->idx + M;
  }
  return 0;
}

void lcp_blocks_free(lcp_blocks *c) {
  free(c->mem);
  free(c->imem);
  memset(c, 0, sizeof *c);
}

/* The block of the active set act, as lcp.c's solve_on would form its
 * parts at each solve (the same entries, the same closed forms, la_dense_lu
 * of the same matrix: the same bits). */
static void build(lcp_block *B, int m, unsigned long long act, const double *Ms, const double *M,
                  const double *D) {
  int k = 0, o;
  for (int i = 0; i < m; i++)
    if (act >> i & 1) B->idx[k++] = i;
  o = k;
  for (int i = 0; i < m; i++)
    if (!(act >> i & 1)) B->idx[o++] = i;
  const int *idx = B->idx;
  B->act = act;
  B->k = k;
  B->state = 1;
  if (k == 1) {
    B->d[0] = Ms[idx[0] + (size_t)idx[0] * m];
    if (!(B->d[0] != 0)) B->state = 2;
  } else if (k == 2) {
    int a = idx[0], b = idx[1];
    double maa = Ms[a + (size_t)a * m], mab = Ms[a + (size_t)b * m];
    double mba = Ms[b + (size_t)a * m], mbb = Ms[b + (size_t)b * m];
    B->d[0] = maa, B->d[1] = mab, B->d[2] = mba, B->d[3] = mbb;
    B->d[4] = maa * mbb - mab * mba;
    if (!(B->d[4] != 0)) B->state = 2;
  } else if (k) {
    for (int b = 0; b < k; b++)
      for (int a = 0; a < k; a++) B->lu[a + (size_t)b * k] = Ms[idx[a] + (size_t)idx[b] * m];
    if (la_dense_lu(B->lu, k, B->piv)) B->state = 2;
  }
  for (int b = 0; b < k; b++)
    for (int i = 0; i < m; i++) {
      size_t f = (size_t)idx[b] * m + i, t = (size_t)b * m + i;
      B->Ws[t] = Ms[f];
      B->Ma[t] = fabs(M[f]);
      B->Dg[t] = D[f];
      B->Da[t] = fabs(D[f]);
    }
}

const lcp_block *lcp_blocks_get(lcp_blocks *c, unsigned long long act, const double *Ms, const double *M,
                                const double *D) {
  for (int b = 0; b < LCP_BLOCKS; b++)
    if (c->blk[b].state && c->blk[b].act == act) return &c->blk[b];
  lcp_block *B = &c->blk[c->next];
  c->next = (c->next + 1) % LCP_BLOCKS;
  build(B, c->m, act, Ms, M, D);
  return B;
}

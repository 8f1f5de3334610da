/* crowd_order — the crowd's internal numbering of its agents, along a
 * Hilbert curve over the cells of the cell list (crowd_impl.h). The state
 * polyset projects in it (rowbuf_order): neighbours in the room are
 * then mostly neighbours in C's columns, in its rows and in the dual matrix,
 * where the user's numbering (random in space when the agents are placed
 * at random) made every row's columns a cache miss at 10^5 agents
 * (BENCHMARKS.md, "Crowds"). The user never sees it: the state, the exit
 * times and the messages keep the user's index. */
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "util/linalg.h"
#include "crowd_impl.h"

/* The place of cell (x, y) along the Hilbert curve of the n x n grid (n a
 * power of two); the classic quadrant-by-quadrant walk. */
static long hilbert_d(int n, int x, int y) {
  long d = 0;
  for (int s = n / 2; s > 0; s /= 2) {
    int rx = (x & s) > 0, ry = (y & s) > 0;
    d += (long)s * s * ((3 * rx) ^ ry);
    if (!ry) {                                 /* rotate the quadrant */
      if (rx) { x = n - 1 - x; y = n - 1 - y; }
      int t = x; x = y; y = t;
    }
  }
  return d;
}

typedef struct cell_key { long d; int k; } cell_key;

static int cmp_key(const void *a, const void *b) {
  long x = ((const cell_key *)a)->d, y = ((const cell_key *)b)->d;
  return (x > y) - (x < y);
}

int crowd_order_init(cup_crowd *c, const double *q, char *errmsg) {
  c->order_gen = 0;
  int ncell = c->gx * c->gy, n = 1;
  while (n < c->gx || n < c->gy) n *= 2;
  c->ord = malloc(sizeof(int) * (size_t)c->N);
  c->rank = malloc(sizeof(int) * (size_t)c->N);
  c->colmap = malloc(sizeof(int) * 2 * (size_t)c->N);
  c->hpos = malloc(sizeof(int) * (size_t)ncell);
  cell_key *key = malloc(sizeof(cell_key) * (size_t)ncell);
  if (!c->ord || !c->rank || !c->colmap || !c->hpos || !key) {
    free(key);
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "crowd: out of memory");
  }
  for (int k = 0; k < ncell; k++) key[k] = (cell_key){hilbert_d(n, k % c->gx, k / c->gx), k};
  qsort(key, (size_t)ncell, sizeof *key, cmp_key);
  for (int h = 0; h < ncell; h++) c->hpos[key[h].k] = h;
  free(key);
  crowd_renumber(c, q);
  return CUP_OK;
}

void crowd_order_free(cup_crowd *c) {
  free(c->ord); free(c->rank); free(c->colmap); free(c->hpos);
  c->ord = c->rank = c->colmap = c->hpos = NULL;
}

/* Agent i before agent j within a cell: by x, then y, then the user's index
 * (two agents at one point: only evacuated ones, which have no rows). */
static int before(const double *q, int i, int j) {
  if (q[2 * i] != q[2 * j]) return q[2 * i] < q[2 * j];
  if (q[2 * i + 1] != q[2 * j + 1]) return q[2 * i + 1] < q[2 * j + 1];
  return i < j;
}

void crowd_renumber(cup_crowd *c, const double *q) {
  int ncell = c->gx * c->gy, *start = c->cell_ptr, *cursor = c->head, *h = c->kcell;
  /* a counting sort by the cell's place on the curve (cell_ptr, head and
     kcell are bin_agents' and free until it runs) */
  memset(start, 0, sizeof(int) * ((size_t)ncell + 1));
  for (int i = 0; i < c->N; i++) start[(h[i] = c->hpos[crowd_cell_of(c, q[2 * i], q[2 * i + 1])]) + 1]++;
  for (int k = 0; k < ncell; k++) start[k + 1] += start[k];
  memcpy(cursor, start, sizeof(int) * (size_t)ncell);
  for (int i = 0; i < c->N; i++) c->ord[cursor[h[i]]++] = i;
  for (int k = 0; k < ncell; k++)             /* by position within a cell: a few agents */
    for (int a = start[k] + 1; a < start[k + 1]; a++) {
      int i = c->ord[a], b = a;
      for (; b > start[k] && before(q, i, c->ord[b - 1]); b--) c->ord[b] = c->ord[b - 1];
      c->ord[b] = i;
    }
  int same = c->order_gen > 0;               /* the numbering it had (rank is still the old one) */
  for (int k = 0; k < c->N && same; k++) same = c->rank[c->ord[k]] == k;
  c->far_base = -1;
  if (same) return;                           /* no new generation: the pool stays as it is */
  for (int k = 0; k < c->N; k++) {
    c->rank[c->ord[k]] = k;
    c->colmap[2 * k] = 2 * c->ord[k];
    c->colmap[2 * k + 1] = 2 * c->ord[k] + 1;
  }
  c->order_gen++;
}

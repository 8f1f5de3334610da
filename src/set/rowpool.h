/* rowpool — the rows of a state-dependent polyset, step after step.
 *
 * The user's callback appends the rows of C(t, x_k) to a cup_rowbuf. The
 * pool keeps one slot per row pattern (its sorted column list) seen
 * recently, so that a contact that persists, vanishes or comes back finds
 * its slot again: the pool's polyset keeps one sparsity pattern (slots not
 * in use this step are zero rows with offset 1, never active), and the
 * symbolic analysis of its dual matrix C P^-1 C^T is reused while every row
 * finds a slot. A pattern not in the pool rebuilds it (the one place that
 * allocates once the buffers have grown): the slots in use, the new rows,
 * the slots used within the last CUP_POOL_KEEP steps, and the patterns the
 * callback expects soon (cup_rowbuf_expect), which then need no rebuild
 * when they arrive. */
#ifndef CUP_ROWPOOL_H
#define CUP_ROWPOOL_H

#include "catchup/set.h"

/* Slots unused for more than this many steps are dropped at a rebuild. */
#define CUP_POOL_KEEP 32

struct cup_rowbuf {
  int n;                 /* columns */
  int m, cap;            /* rows and capacity */
  int nnz, nzcap;        /* entries and capacity */
  int *ptr;              /* cap + 1 row starts */
  int *col;              /* nzcap */
  double *val;           /* nzcap */
  double *off;           /* cap: offsets */
  int me, ecap, enz, enzcap;   /* expected patterns (cup_rowbuf_expect): count, capacities */
  int *eptr, *ecol;
  int status;            /* first failed cup_rowbuf_add since the clear (CUP_OK if none) */
  char message[256];     /* what was wrong with it (bounded: numbers), whole inside a set's message */
  /* the callback's own numbering of the state (rowbuf_order) */
  const int *perm;       /* n: column k of the rows is x[perm[k]]; NULL: the state's order */
  long perm_gen;         /* changes whenever perm does */
};

int rowbuf_init(cup_rowbuf *rb, int n, int rows, int nnz);
void rowbuf_free(cup_rowbuf *rb);
void rowbuf_clear(cup_rowbuf *rb);
/* The rows' columns are in the callback's numbering: column k is x[perm[k]]
 * (perm, n entries, a permutation, must stay unchanged and alive until the
 * next call with another generation). The state polyset then projects in
 * that numbering (a crowd numbered along a space-filling curve keeps C, M
 * and the factor nearly banded) and gives its answers in the state's. A
 * new generation renumbers the pool's patterns. Internal: the crowd's. */
void rowbuf_order(cup_rowbuf *rb, const int *perm, long generation);

typedef struct row_pool {
  int n;
  int m, cap;            /* slots, capacity */
  int nnz, nzcap;        /* pattern entries, capacity */
  int *ptr, *col;        /* slot patterns, CSR (cap + 1, nzcap) */
  unsigned *hash;        /* per slot */
  int *next;             /* hash chains */
  int *head;             /* hsize heads */
  int hsize;             /* a power of two >= 2 cap */
  long *used;            /* per slot: last step it held a row */
  int *row_of;           /* per slot: the buffer row it holds this step, or -1 */
  int *slot_of;          /* per buffer row (rcap): its slot, or -1 */
  int rcap;
  int *old_of;           /* after a rebuild: per new slot, the old slot or -1 */
  int unique;            /* no pattern holds two slots (then a slot found is the slot) */
} row_pool;

int rowpool_init(row_pool *P, int n);
void rowpool_free(row_pool *P);
/* Give each row of rb a slot of the same pattern (at most one row a slot);
 * returns the number of rows left without one (0: the pattern repeats), or
 * CUP_ERR_NOMEM. */
int rowpool_match(row_pool *P, const cup_rowbuf *rb, long step);
/* New slots: the rows of rb first (in order), then the slots used within
 * CUP_POOL_KEEP steps that hold no row now, then the expected patterns not
 * among them. Fills old_of and the matches. */
int rowpool_rebuild(row_pool *P, const cup_rowbuf *rb, long step);
/* The slots' patterns in a new numbering of the columns: column c becomes
 * map[c] (a permutation of 0..n-1); every slot and its hash follow. */
void rowpool_renumber(row_pool *P, const int *map);

#endif

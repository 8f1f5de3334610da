/* rowpool — see rowpool.h; and the kind state-polyset's part of the set
 * (its checks, its recheck, its table) at the end. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "util/linalg.h"
#include "rowpool.h"
#include "set_impl.h"

/* ---- the row buffer ------------------------------------------------------------ */

/* The next capacity >= need, doubling from cap. */
static int next_cap(int cap, int need) {
  int c = cap > 0 ? cap : 16;
  while (c < need) c = c > (1 << 29) ? need : 2 * c;
  return c;
}

static int grow_rows(cup_rowbuf *rb, int need) {
  if (need <= rb->cap) return CUP_OK;
  int c = next_cap(rb->cap, need);
  int *ptr = realloc(rb->ptr, sizeof(int) * ((size_t)c + 1));
  if (ptr) rb->ptr = ptr;
  double *off = realloc(rb->off, sizeof(double) * (size_t)c);
  if (off) rb->off = off;
  if (!ptr || !off) return CUP_ERR_NOMEM;
  rb->cap = c;
  return CUP_OK;
}

static int grow_entries(cup_rowbuf *rb, int need) {
  if (need <= rb->nzcap) return CUP_OK;
  int c = next_cap(rb->nzcap, need);
  int *col = realloc(rb->col, sizeof(int) * (size_t)c);
  if (col) rb->col = col;
  double *val = realloc(rb->val, sizeof(double) * (size_t)c);
  if (val) rb->val = val;
  if (!col || !val) return CUP_ERR_NOMEM;
  rb->nzcap = c;
  return CUP_OK;
}

int rowbuf_init(cup_rowbuf *rb, int n, int rows, int nnz) {
  memset(rb, 0, sizeof *rb);
  rb->n = n;
  int st = grow_rows(rb, rows > 0 ? rows : 16);
  if (!st) st = grow_entries(rb, nnz > 0 ? nnz : 64);
  if (!st) rb->ptr[0] = 0;
  return st;
}

void rowbuf_free(cup_rowbuf *rb) {
  free(rb->ptr); free(rb->off); free(rb->col); free(rb->val); free(rb->eptr); free(rb->ecol);
  memset(rb, 0, sizeof *rb);
}

void rowbuf_clear(cup_rowbuf *rb) {
  rb->m = rb->nnz = rb->me = rb->enz = 0;
  rb->ptr[0] = 0;
  rb->status = CUP_OK;
  rb->message[0] = '\0';
}

void rowbuf_order(cup_rowbuf *rb, const int *perm, long generation) {
  rb->perm = perm;
  rb->perm_gen = generation;
}

int cup_rowbuf_rows(const cup_rowbuf *rb) { return rb ? rb->m : 0; }

/* Remember the first bad row (the callback may not check every return). */
__attribute__((format(printf, 3, 4)))
static int reject(cup_rowbuf *rb, int status, const char *fmt, ...) {
  if (rb->status == CUP_OK) {
    rb->status = status;
    int len = snprintf(rb->message, sizeof rb->message, "row %d: ", rb->m);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(rb->message + len, sizeof rb->message - (size_t)len, fmt, ap);
    va_end(ap);
  }
  return status;
}

static int check_columns(cup_rowbuf *rb, int nnz, const int *cols) {
  if (nnz < 0 || (nnz > 0 && !cols)) return reject(rb, CUP_ERR_ARG, "%d entries without columns", nnz);
  for (int k = 0; k < nnz; k++) {
    if (cols[k] < 0 || cols[k] >= rb->n)
      return reject(rb, CUP_ERR_ARG, "column %d is outside 0..%d", cols[k], rb->n - 1);
    if (k > 0 && cols[k] <= cols[k - 1])
      return reject(rb, CUP_ERR_ARG, "column %d after column %d (columns must increase)", cols[k], cols[k - 1]);
  }
  return CUP_OK;
}

int cup_rowbuf_add(cup_rowbuf *rb, int nnz, const int *cols, const double *vals, double offset) {
  if (!rb) return CUP_ERR_ARG;
  int st = check_columns(rb, nnz, cols);
  if (st) return st;
  if (nnz > 0 && !vals) return reject(rb, CUP_ERR_ARG, "%d entries without values", nnz);
  if (!isfinite(offset)) return reject(rb, CUP_ERR_NONFINITE, "the offset is %g", offset);
  for (int k = 0; k < nnz; k++)
    if (!isfinite(vals[k]))
      return reject(rb, CUP_ERR_NONFINITE, "the value in column %d is %g", cols[k], vals[k]);
  if (grow_rows(rb, rb->m + 1) || grow_entries(rb, rb->nnz + nnz))
    return reject(rb, CUP_ERR_NOMEM, "out of memory");
  if (nnz) {
    memcpy(rb->col + rb->nnz, cols, sizeof(int) * (size_t)nnz);
    memcpy(rb->val + rb->nnz, vals, sizeof(double) * (size_t)nnz);
  }
  rb->off[rb->m] = offset;
  rb->nnz += nnz;
  rb->ptr[++rb->m] = rb->nnz;
  return CUP_OK;
}

int cup_rowbuf_expect(cup_rowbuf *rb, int nnz, const int *cols) {
  if (!rb) return CUP_ERR_ARG;
  int st = check_columns(rb, nnz, cols);
  if (st) return st;
  if (rb->me + 2 > rb->ecap) {
    int c = next_cap(rb->ecap, rb->me + 2);
    int *p = realloc(rb->eptr, sizeof(int) * (size_t)c);
    if (!p) return reject(rb, CUP_ERR_NOMEM, "out of memory");
    rb->eptr = p;
    rb->ecap = c;
  }
  if (rb->enz + nnz > rb->enzcap) {
    int c = next_cap(rb->enzcap, rb->enz + nnz);
    int *p = realloc(rb->ecol, sizeof(int) * (size_t)c);
    if (!p) return reject(rb, CUP_ERR_NOMEM, "out of memory");
    rb->ecol = p;
    rb->enzcap = c;
  }
  if (rb->me == 0) rb->eptr[0] = 0;
  if (nnz) memcpy(rb->ecol + rb->enz, cols, sizeof(int) * (size_t)nnz);
  rb->enz += nnz;
  rb->eptr[++rb->me] = rb->enz;
  return CUP_OK;
}

/* ---- the pool of slots ---------------------------------------------------------- */

static unsigned pattern_hash(const int *col, int len) {
  unsigned h = 2166136261u ^ (unsigned)len;          /* FNV-1a over the columns */
  for (int k = 0; k < len; k++) {
    unsigned c = (unsigned)col[k];
    for (int b = 0; b < 4; b++) { h ^= (c >> (8 * b)) & 0xffu; h *= 16777619u; }
  }
  return h;
}

int rowpool_init(row_pool *P, int n) {
  memset(P, 0, sizeof *P);
  P->n = n;
  P->unique = 1;
  P->ptr = calloc(1, sizeof(int));
  return P->ptr ? CUP_OK : CUP_ERR_NOMEM;
}

void rowpool_free(row_pool *P) {
  free(P->ptr); free(P->col); free(P->hash); free(P->next); free(P->head); free(P->used);
  free(P->row_of); free(P->slot_of); free(P->old_of);
  memset(P, 0, sizeof *P);
}

/* A slot with this pattern (holding no row this step, if free_only), or -1. */
static int find_slot(const row_pool *P, const int *col, int len, int free_only) {
  if (!P->m) return -1;
  unsigned h = pattern_hash(col, len);
  for (int s = P->head[h & (unsigned)(P->hsize - 1)]; s >= 0; s = P->next[s])
    if (P->hash[s] == h && (!free_only || P->row_of[s] < 0) && P->ptr[s + 1] - P->ptr[s] == len &&
        !memcmp(P->col + P->ptr[s], col, sizeof(int) * (size_t)len))
      return s;
  return -1;
}

/* Does slot s hold this pattern? */
static int same_pattern(const row_pool *P, int s, const int *col, int len) {
  return s >= 0 && s < P->m && P->ptr[s + 1] - P->ptr[s] == len &&
         !memcmp(P->col + P->ptr[s], col, sizeof(int) * (size_t)len);
}

/* The slot find_slot would give, tried first at `guess` (the slot after the
 * previous row's: the rows of a step mostly come in the order of the last
 * rebuild's, and the guess reads the pool in order where a hash lookup
 * reads it at random). When no pattern is in the pool twice, a slot with
 * the pattern is the only one, so the guess gives the same slot. */
static int slot_for(const row_pool *P, const int *col, int len, int free_only, int guess) {
  if (P->unique && same_pattern(P, guess, col, len) && (!free_only || P->row_of[guess] < 0)) return guess;
  return find_slot(P, col, len, free_only);
}

int rowpool_match(row_pool *P, const cup_rowbuf *rb, long step) {
  if (rb->m > P->rcap) {
    int *q = realloc(P->slot_of, sizeof(int) * ((size_t)rb->m + 1));
    if (!q) return CUP_ERR_NOMEM;
    P->slot_of = q;
    P->rcap = rb->m;
  }
  for (int s = 0; s < P->m; s++) P->row_of[s] = -1;
  int missing = 0, guess = 0;
  for (int r = 0; r < rb->m; r++) {
    int s = slot_for(P, rb->col + rb->ptr[r], rb->ptr[r + 1] - rb->ptr[r], 1, guess);
    P->slot_of[r] = s;
    if (s >= 0) { P->row_of[s] = r; P->used[s] = step; guess = s + 1; }
    else missing++;
  }
  for (int e = 0; e < rb->me; e++) {        /* an expected pattern keeps its slot alive */
    int s = slot_for(P, rb->ecol + rb->eptr[e], rb->eptr[e + 1] - rb->eptr[e], 0, guess);
    if (s >= 0) { P->used[s] = step; guess = s + 1; }
  }
  return missing;
}

/* Room for m slots of nnz entries in total. */
static int reserve(row_pool *P, int m, int nnz) {
  if (m > P->cap) {
    int c = P->cap > 0 ? P->cap : 16;
    while (c < m) c *= 2;
    int *ptr = realloc(P->ptr, sizeof(int) * ((size_t)c + 1));
    if (ptr) P->ptr = ptr;
    unsigned *hash = realloc(P->hash, sizeof(unsigned) * (size_t)c);
    if (hash) P->hash = hash;
    int *next = realloc(P->next, sizeof(int) * (size_t)c), *row_of = realloc(P->row_of, sizeof(int) * (size_t)c);
    if (next) P->next = next;
    if (row_of) P->row_of = row_of;
    long *used = realloc(P->used, sizeof(long) * (size_t)c);
    if (used) P->used = used;
    int *old_of = realloc(P->old_of, sizeof(int) * (size_t)c);
    if (old_of) P->old_of = old_of;
    if (!ptr || !hash || !next || !row_of || !used || !old_of) return CUP_ERR_NOMEM;
    int hs = 2;
    while (hs < 2 * c) hs *= 2;
    int *head = realloc(P->head, sizeof(int) * (size_t)hs);
    if (!head) return CUP_ERR_NOMEM;
    P->head = head;
    P->hsize = hs;
    P->cap = c;
  }
  if (nnz > P->nzcap) {
    int c = P->nzcap > 0 ? P->nzcap : 64;
    while (c < nnz) c *= 2;
    int *col = realloc(P->col, sizeof(int) * (size_t)c);
    if (!col) return CUP_ERR_NOMEM;
    P->col = col;
    P->nzcap = c;
  }
  return CUP_OK;
}

/* Append a slot of this pattern (room reserved) and hash it. */
static void append_slot(row_pool *P, const int *col, int len, long used, int old) {
  int s = P->m++;
  memcpy(P->col + P->nnz, col, sizeof(int) * (size_t)len);
  P->nnz += len;
  P->ptr[s + 1] = P->nnz;
  unsigned h = pattern_hash(col, len);
  P->hash[s] = h;
  P->next[s] = P->head[h & (unsigned)(P->hsize - 1)];
  P->head[h & (unsigned)(P->hsize - 1)] = s;
  P->row_of[s] = -1;
  P->used[s] = used;
  P->old_of[s] = old;
}

/* The chains of the hash table over slots 0..m-1. */
static void rehash(row_pool *P) {
  for (int k = 0; k < P->hsize; k++) P->head[k] = -1;
  for (int s = 0; s < P->m; s++) {
    unsigned h = P->hash[s] = pattern_hash(P->col + P->ptr[s], P->ptr[s + 1] - P->ptr[s]);
    P->next[s] = P->head[h & (unsigned)(P->hsize - 1)];
    P->head[h & (unsigned)(P->hsize - 1)] = s;
  }
}

void rowpool_renumber(row_pool *P, const int *map) {
  for (int s = 0; s < P->m; s++) {
    int *col = P->col + P->ptr[s], len = P->ptr[s + 1] - P->ptr[s];
    for (int k = 0; k < len; k++) {          /* insertion sort: a pattern has a few columns */
      int c = map[col[k]], q = k;
      for (; q > 0 && col[q - 1] > c; q--) col[q] = col[q - 1];
      col[q] = c;
    }
  }
  if (P->m) rehash(P);
}

int rowpool_rebuild(row_pool *P, const cup_rowbuf *rb, long step) {
  /* the old slots to keep, and their patterns, before they are overwritten */
  int keep = 0, keep_nnz = 0;
  for (int s = 0; s < P->m; s++)
    if (P->row_of[s] < 0 && step - P->used[s] <= CUP_POOL_KEEP) { keep++; keep_nnz += P->ptr[s + 1] - P->ptr[s]; }
  int m = rb->m + keep + rb->me, nnz = rb->nnz + keep_nnz + rb->enz;
  int *kptr = malloc(sizeof(int) * ((size_t)keep + 1)), *kcol = malloc(sizeof(int) * ((size_t)keep_nnz + 1));
  int *kold = malloc(sizeof(int) * ((size_t)keep + 1)), *rold = malloc(sizeof(int) * ((size_t)rb->m + 1));
  long *kused = malloc(sizeof(long) * ((size_t)keep + 1));
  int st = kptr && kcol && kold && rold && kused ? CUP_OK : CUP_ERR_NOMEM;
  if (!st) {
    int q = 0, z = 0;
    kptr[0] = 0;
    for (int s = 0; s < P->m; s++) {
      if (!(P->row_of[s] < 0 && step - P->used[s] <= CUP_POOL_KEEP)) continue;
      int len = P->ptr[s + 1] - P->ptr[s];
      memcpy(kcol + z, P->col + P->ptr[s], sizeof(int) * (size_t)len);
      z += len;
      kold[q] = s;
      kused[q] = P->used[s];
      kptr[++q] = z;
    }
    for (int r = 0; r < rb->m; r++) rold[r] = P->slot_of[r];
    st = reserve(P, m, nnz);
  }
  if (!st) {
    P->m = P->nnz = 0;
    P->ptr[0] = 0;
    for (int k = 0; k < P->hsize; k++) P->head[k] = -1;
    P->unique = 1;
    for (int r = 0; r < rb->m; r++) {
      const int *col = rb->col + rb->ptr[r];
      int len = rb->ptr[r + 1] - rb->ptr[r];
      if (find_slot(P, col, len, 0) >= 0) P->unique = 0;
      append_slot(P, col, len, step, rold[r]);
      P->row_of[r] = r;
      P->slot_of[r] = r;
    }
    for (int q = 0; q < keep; q++) {
      if (find_slot(P, kcol + kptr[q], kptr[q + 1] - kptr[q], 0) >= 0) P->unique = 0;
      append_slot(P, kcol + kptr[q], kptr[q + 1] - kptr[q], kused[q], kold[q]);
    }
    for (int e = 0; e < rb->me; e++) {
      const int *col = rb->ecol + rb->eptr[e];
      int len = rb->eptr[e + 1] - rb->eptr[e];
      if (find_slot(P, col, len, 0) < 0) append_slot(P, col, len, step, -1);
    }
  }
  free(kptr); free(kcol); free(kold); free(rold); free(kused);
  return st;
}

/* ---- the kind state-polyset ---------------------------------------------------- */

static int state_check(const cup_set_desc *d, char *errmsg) {
  if (!d->rows) return fail_fmt(errmsg, CUP_ERR_ARG, "set state-polyset: the rows callback is NULL");
  if (d->P.kind == CUP_METRIC_SPARSE)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED,
                    "set state-polyset: the metric must be the identity or diagonal (the rows' "
                    "dual matrix C P^-1 C^T is refactored in place at every step)");
  return CUP_OK;
}

int set_on_recheck(cup_set *S, int (*recheck)(double t, const double *x, const double *z, void *ctx)) {
  if (!S || S->kind != CUP_SET_STATE_POLYSET) return CUP_ERR_ARG;
  S->recheck = recheck;
  return CUP_OK;
}

const set_kind set_kind_state_polyset = {.check = state_check};

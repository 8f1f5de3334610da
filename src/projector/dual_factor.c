/* dual_factor — see dual_factor.h. */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "dual_factor.h"

struct cup_dfact {
  const cup_polyset *K;
  int kkt;                    /* 1: KKT form (sparse P); 0: M form (diagonal P) */
  int n, m, N;                /* N: order of the factored matrix (n + m or m) */
  int updates;                /* M form: row updates allowed */
  cholmod_common cm;
  cholmod_sparse *Ku;         /* permuted upper matrix (KKT form: values rewritten; M form: M) */
  cholmod_sparse *Mp;         /* M form: permuted full M, for rowadd columns */
  cholmod_sparse *R;          /* M form: one column for rowadd, one row pattern for rowdel */
  cholmod_factor *L;          /* simplicial LDL^T; M form: room for the factor of all of M */
  int *pperm, *iperm;         /* permuted <-> natural (KKT order for the KKT form) */
  int *cpos, *dpos;           /* KKT form: positions of C's entries and of row diagonals */
  double *work;               /* 2 N */
  unsigned char *fact_act;    /* rows free in the current factor (natural order) */
  double fact_delta, delta_min;
  int has_fact;
  /* M form, the factorization restricted to the free rows (restricted_ldl) */
  unsigned char *pact;        /* free flags in the permuted order */
  int *par, *flag, *stack;    /* etree of the factor being built, marks, reach */
  double *yrow;               /* the row being built, scattered (zero between rows) */
  int *etree;                 /* elimination tree of all of M: bounds rows of any factor */
  unsigned stamp;             /* marks in flag for row patterns (rowdel) */
  double refactor_ops;        /* work of the last refactorization; 0: none yet */
  int *lp0, *next0, *prev0;   /* L's first layout: each column with room for all of M */
};

double cup_dfact_delta_min(const cup_dfact *f) { return f->delta_min; }

/* ---- permutation and upper storage (shared) ---------------------------------- */

/* From a symmetric matrix given by its lower triangle (natural order; each
 * entry tagged), build the permuted upper triangle with a map from every
 * original entry to its position. */
static int permuted_upper(cup_dfact *f, int N, const int *Ap, const int *Ai, const double *Ax,
                          int *map, char *errmsg) {
  int nnz = Ap[N];
  cholmod_sparse A = {0};
  A.nrow = A.ncol = (size_t)N; A.nzmax = (size_t)nnz;
  A.p = (void *)Ap; A.i = (void *)Ai; A.x = (void *)Ax; A.stype = -1;
  A.itype = CHOLMOD_INT; A.xtype = CHOLMOD_REAL; A.dtype = CHOLMOD_DOUBLE;
  A.sorted = 1; A.packed = 1;
  f->cm.supernodal = CHOLMOD_SIMPLICIAL;
  f->cm.final_ll = 0;
  /* AMD alone: the factors are of the free rows only (restricted_ldl), whose
   * fill an ordering of all of M hardly changes; METIS and nested dissection
   * saved 3-5% of the room for all of M on crowds of 10^5 disks and took 15
   * times AMD's time (8.5 s against 0.25 s); a set whose rows change with
   * the state is analysed again when they do */
  f->cm.nmethods = 1;
  f->cm.method[0].ordering = CHOLMOD_AMD;
  cholmod_factor *L0 = cholmod_analyze(&A, &f->cm);   /* fill-reducing order */
  if (!L0) return cup_fail(errmsg, CUP_ERR_LINALG, "dual factor: CHOLMOD analysis failed (%d)", f->cm.status);
  f->pperm = malloc(sizeof(int) * (size_t)N);
  f->iperm = malloc(sizeof(int) * (size_t)N);
  int *rowcnt = calloc((size_t)N + 1, sizeof(int)), *colcnt = calloc((size_t)N + 1, sizeof(int));
  int *order = malloc(sizeof(int) * ((size_t)nnz + 1)), *colof = malloc(sizeof(int) * ((size_t)nnz + 1));
  f->Ku = cholmod_allocate_sparse((size_t)N, (size_t)N, (size_t)nnz, 1, 1, 1, CHOLMOD_REAL, &f->cm);
  int st = CUP_OK;
  if (!f->pperm || !f->iperm || !rowcnt || !colcnt || !order || !colof || !f->Ku) {
    st = cup_fail(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
    goto done;
  }
  for (int k = 0; k < N; k++) {
    int orig = L0->Perm ? ((int *)L0->Perm)[k] : k;
    f->pperm[k] = orig;
    f->iperm[orig] = k;
  }
  for (int c = 0; c < N; c++)
    for (int e = Ap[c]; e < Ap[c + 1]; e++) {
      int pr = f->iperm[Ai[e]], pc = f->iperm[c];
      rowcnt[(pr < pc ? pr : pc) + 1]++;
      colcnt[(pr < pc ? pc : pr) + 1]++;
      colof[e] = c;
    }
  for (int k = 0; k < N; k++) { rowcnt[k + 1] += rowcnt[k]; colcnt[k + 1] += colcnt[k]; }
  int *Kp = f->Ku->p, *Ki = f->Ku->i;
  double *Kx = f->Ku->x;
  memcpy(Kp, colcnt, sizeof(int) * ((size_t)N + 1));
  for (int e = 0; e < nnz; e++) {                    /* bucket by row, then append by column */
    int pr = f->iperm[Ai[e]], pc = f->iperm[colof[e]];
    order[rowcnt[pr < pc ? pr : pc]++] = e;
  }
  for (int t = 0; t < nnz; t++) {
    int e = order[t];
    int pr = f->iperm[Ai[e]], pc = f->iperm[colof[e]];
    int row = pr < pc ? pr : pc, col = pr < pc ? pc : pr;
    int pos = colcnt[col]++;
    Ki[pos] = row;
    Kx[pos] = Ax[e];
    map[e] = pos;
  }
done:
  cholmod_free_factor(&L0, &f->cm);
  free(rowcnt); free(colcnt); free(order); free(colof);
  return st;
}

/* Symbolic analysis in the stored (natural) order, unpacked so that row
 * updates find room, and a first numeric factorization so that later ones
 * reuse L's memory. */
static int symbolic(cup_dfact *f, char *errmsg) {
  f->cm.nmethods = 1;
  f->cm.method[0].ordering = CHOLMOD_NATURAL;
  f->cm.postorder = 0;
  f->cm.final_pack = 0;
  f->L = cholmod_analyze(f->Ku, &f->cm);
  if (!f->L) return cup_fail(errmsg, CUP_ERR_LINALG, "dual factor: CHOLMOD analysis failed (%d)", f->cm.status);
  cholmod_factorize(f->Ku, f->L, &f->cm);
  if (f->cm.status < 0) return cup_fail(errmsg, CUP_ERR_LINALG, "dual factor: factorization failed (%d)", f->cm.status);
  f->has_fact = 1;
  f->fact_delta = -1;                      /* no delta yet: the first real factor is full */
  return CUP_OK;
}

/* ---- the KKT form (sparse P) ---------------------------------------------------- */

static int kkt_create(cup_dfact *f, char *errmsg) {
  const cup_polyset *K = f->K;
  int n = f->n, m = f->m, N = f->N = n + m;
  int nnzP = 0;
  for (int j = 0; j < n; j++)
    for (int k = K->Pfull.p[j]; k < K->Pfull.p[j + 1]; k++) nnzP += K->Pfull.i[k] >= j;
  int nnz = nnzP + K->C.nnz + m;
  int *Ap = malloc(sizeof(int) * ((size_t)N + 1)), *Ai = malloc(sizeof(int) * (size_t)nnz);
  int *tag = malloc(sizeof(int) * (size_t)nnz), *map = malloc(sizeof(int) * (size_t)nnz);
  double *Ax = malloc(sizeof(double) * (size_t)nnz);
  f->cpos = malloc(sizeof(int) * ((size_t)K->C.nnz + 1));
  f->dpos = malloc(sizeof(int) * ((size_t)m + 1));
  int st = CUP_OK;
  if (!Ap || !Ai || !tag || !map || !Ax || !f->cpos || !f->dpos) {
    st = cup_fail(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
    goto done;
  }
  /* lower triangle: P's lower part and C_j's entries below in each column
   * j < n; the constraint diagonals after. Tags: >= 0 an entry of C, -1-i
   * the diagonal of row i, -1-m a P entry. */
  int q = 0;
  Ap[0] = 0;
  for (int j = 0; j < n; j++) {
    for (int k = K->Pfull.p[j]; k < K->Pfull.p[j + 1]; k++)
      if (K->Pfull.i[k] >= j) { Ai[q] = K->Pfull.i[k]; Ax[q] = K->Pfull.x[k]; tag[q++] = -1 - m; }
    for (int k = K->C.p[j]; k < K->C.p[j + 1]; k++) { Ai[q] = n + K->C.i[k]; Ax[q] = 0; tag[q++] = k; }
    Ap[j + 1] = q;
  }
  for (int i = 0; i < m; i++) { Ai[q] = n + i; Ax[q] = -1; tag[q++] = -1 - i; Ap[n + i + 1] = q; }
  st = permuted_upper(f, N, Ap, Ai, Ax, map, errmsg);
  for (int e = 0; !st && e < nnz; e++) {
    if (tag[e] >= 0) f->cpos[tag[e]] = map[e];
    else if (tag[e] > -1 - m) f->dpos[-1 - tag[e]] = map[e];
  }
  if (!st) st = symbolic(f, errmsg);
done:
  free(Ap); free(Ai); free(tag); free(map); free(Ax);
  return st;
}

static int kkt_factor(cup_dfact *f, const unsigned char *act, double delta) {
  const cup_sparse *C = &f->K->C;
  double *Kx = f->Ku->x;
  for (int j = 0; j < C->ncol; j++)
    for (int k = C->p[j]; k < C->p[j + 1]; k++) Kx[f->cpos[k]] = act[C->i[k]] ? C->x[k] : 0;
  for (int i = 0; i < f->m; i++) Kx[f->dpos[i]] = act[i] ? -delta : -1;
  cholmod_factorize(f->Ku, f->L, &f->cm);
  return f->cm.status < 0 || f->cm.status == CHOLMOD_NOT_POSDEF ? CUP_ERR_LINALG : CUP_OK;
}

/* [P C_F^T; C_F -delta][u; w] = [0; v]  gives  w = -(M_FF + delta)^-1 v. */
static void kkt_solve(cup_dfact *f, double *v) {
  int n = f->n, m = f->m, N = f->N;
  double *t = f->work, *scratch = f->work + N;
  for (int k = 0; k < N; k++) {
    int o = f->pperm[k];
    t[k] = o < n ? 0 : v[o - n];
  }
  cup_simplicial_solve(f->L, t, scratch);
  for (int k = 0; k < N; k++) {
    int o = f->pperm[k];
    if (o >= n) v[o - n] = -t[k];
  }
  (void)m;
}

/* ---- the M form (diagonal P) ------------------------------------------------------ */

/* The elimination tree of all of M (Liu's algorithm with path compression):
 * every factor of a principal submatrix in this order has its pattern
 * inside the factor of M, so a row of the full factor, found from this tree,
 * bounds the row of any factor (what rowdel needs). */
static void full_etree(cup_dfact *f) {
  const int *Kp = f->Ku->p, *Ki = f->Ku->i;
  int *anc = f->flag;
  for (int k = 0; k < f->m; k++) {
    f->etree[k] = -1;
    anc[k] = -1;
    for (int e = Kp[k]; e < Kp[k + 1]; e++)
      for (int i = Ki[e], next; i != -1 && i < k; i = next) {
        next = anc[i];
        anc[i] = k;
        if (next == -1) f->etree[i] = k;
      }
  }
  memset(f->flag, 0, sizeof(int) * (size_t)f->m);
}

static int mform_create(cup_dfact *f, char *errmsg) {
  const cup_polyset *K = f->K;
  int m = f->m, N = f->N = m;
  /* S = C D^-1/2 (m x n), M = S S^T */
  cholmod_sparse *S = cholmod_allocate_sparse((size_t)m, (size_t)f->n, (size_t)K->C.nnz, 1, 1, 0,
                                              CHOLMOD_REAL, &f->cm);
  if (!S) return cup_fail(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
  memcpy(S->p, K->C.p, sizeof(int) * ((size_t)f->n + 1));
  memcpy(S->i, K->C.i, sizeof(int) * (size_t)K->C.nnz);
  for (int j = 0; j < f->n; j++)
    for (int k = K->C.p[j]; k < K->C.p[j + 1]; k++)
      ((double *)S->x)[k] = K->C.x[k] * sqrt(K->pdinv[j]);
  cholmod_sparse *M = cholmod_aat(S, NULL, 0, 1, &f->cm);
  cholmod_free_sparse(&S, &f->cm);
  if (!M || !cholmod_sort(M, &f->cm)) {
    cholmod_free_sparse(&M, &f->cm);
    return cup_fail(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory forming C P^-1 C^T");
  }
  /* rows of C that are zero give an empty column in M: give every row a diagonal */
  cholmod_sparse *I = cholmod_speye((size_t)m, (size_t)m, CHOLMOD_REAL, &f->cm);
  double zero[2] = {0, 0}, one[2] = {1, 0};
  cholmod_sparse *Mz = I ? cholmod_add(M, I, one, zero, 1, 1, &f->cm) : NULL;
  cholmod_free_sparse(&I, &f->cm);
  cholmod_free_sparse(&M, &f->cm);
  if (!Mz) return cup_fail(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
  cholmod_sort(Mz, &f->cm);
  /* lower triangle for the ordering */
  const int *Mp = Mz->p, *Mi = Mz->i;
  const double *Mx = Mz->x;
  int nnzl = 0;
  for (int j = 0; j < m; j++)
    for (int k = Mp[j]; k < Mp[j + 1]; k++) nnzl += Mi[k] >= j;
  int *Ap = malloc(sizeof(int) * ((size_t)m + 1)), *Ai = malloc(sizeof(int) * ((size_t)nnzl + 1));
  int *map = malloc(sizeof(int) * ((size_t)nnzl + 1));
  double *Ax = malloc(sizeof(double) * ((size_t)nnzl + 1));
  int st = CUP_OK;
  if (!Ap || !Ai || !map || !Ax) { st = cup_fail(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory"); goto done; }
  int q = 0;
  Ap[0] = 0;
  for (int j = 0; j < m; j++) {
    for (int k = Mp[j]; k < Mp[j + 1]; k++)
      if (Mi[k] >= j) { Ai[q] = Mi[k]; Ax[q++] = Mx[k]; }
    Ap[j + 1] = q;
  }
  st = permuted_upper(f, N, Ap, Ai, Ax, map, errmsg);
  if (st) goto done;
  f->Mp = cholmod_submatrix(Mz, f->pperm, m, f->pperm, m, 1, 1, &f->cm);   /* permuted, full */
  f->R = cholmod_allocate_sparse((size_t)m, 1, (size_t)m, 1, 1, 0, CHOLMOD_REAL, &f->cm);
  size_t M1 = (size_t)m + 1;
  f->pact = calloc(M1, 1);
  f->par = malloc(sizeof(int) * M1);
  f->flag = malloc(sizeof(int) * M1);
  f->stack = malloc(sizeof(int) * M1);
  f->etree = malloc(sizeof(int) * M1);
  f->yrow = calloc(M1, sizeof(double));
  if (!f->Mp || !f->R || !f->pact || !f->par || !f->flag || !f->stack || !f->etree || !f->yrow) {
    st = cup_fail(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
    goto done;
  }
  full_etree(f);
  /* Room for the factor of all of M, held as L = I until the first
   * factorization: no numeric work here, and none of a size of all of M later */
  f->cm.nmethods = 1;
  f->cm.method[0].ordering = CHOLMOD_NATURAL;
  f->cm.postorder = 0;
  /* each column's room is its count in the factor of all of M and no more
   * (CHOLMOD's default adds a fifth and 5 entries a column): restricted_ldl
   * fills no more, and a column CHOLMOD's row updates move is moved back */
  f->cm.grow1 = 1;
  f->cm.grow2 = 0;
  f->L = cholmod_analyze(f->Ku, &f->cm);
  if (!f->L || !cholmod_change_factor(CHOLMOD_REAL, 0, 0, 0, 1, f->L, &f->cm)) {
    st = cup_fail(errmsg, f->cm.status == CHOLMOD_OUT_OF_MEMORY ? CUP_ERR_NOMEM : CUP_ERR_LINALG,
                  "dual factor: CHOLMOD analysis failed (%d)", f->cm.status);
    goto done;
  }
  /* CHOLMOD's row updates may move a column whose room looks short to them;
   * restricted_ldl goes back to this layout, every column's room its count in
   * the factor of all of M, which holds any factor of free rows */
  f->lp0 = malloc(sizeof(int) * M1);
  f->next0 = malloc(sizeof(int) * (M1 + 1));
  f->prev0 = malloc(sizeof(int) * (M1 + 1));
  if (!f->lp0 || !f->next0 || !f->prev0) {
    st = cup_fail(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
    goto done;
  }
  memcpy(f->lp0, f->L->p, sizeof(int) * M1);
  memcpy(f->next0, f->L->next, sizeof(int) * (M1 + 1));
  memcpy(f->prev0, f->L->prev, sizeof(int) * (M1 + 1));
  /* rowadd/rowdel need 2m of CHOLMOD workspace: take it now, not in a projection */
  if (!cholmod_allocate_work((size_t)m, 2 * (size_t)m, 2 * (size_t)m, &f->cm))
    st = cup_fail(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory for CHOLMOD workspace");
done:
  cholmod_free_sparse(&Mz, &f->cm);
  free(Ap); free(Ai); free(map); free(Ax);
  return st;
}

/* LDL^T of M~ = M_FF + delta I on the free rows F, identity elsewhere, by
 * rows (up-looking, Davis' LDL): row k of L solves with the rows above it on
 * the reach of M(F, k) in the elimination tree, which is built on the way
 * (a row's parent is the first later row that reaches it). The work is that
 * of the factor of M_FF alone, whatever the size of M: a crowd with a tenth
 * of its contacts active, or half a ladder, costs a fraction of M's factor.
 * Written into CHOLMOD's simplicial factor (diagonal first in each column),
 * whose room for all of M holds any such factor, so that row updates and
 * solves work on it as on CHOLMOD's own. */
static int restricted_ldl(cup_dfact *f, const unsigned char *act, double delta) {
  int m = f->m;
  const int *Kp = f->Ku->p, *Ki = f->Ku->i;
  const double *Kx = f->Ku->x;
  int *Lp = f->L->p, *Li = f->L->i, *Lnz = f->L->nz;
  double *Lx = f->L->x, *y = f->yrow;
  int *par = f->par, *flag = f->flag, *stack = f->stack;
  unsigned char *pact = f->pact;
  double ops = 0;
  if (!f->L->is_monotonic) {         /* columns moved by row updates: the first layout again */
    memcpy(Lp, f->lp0, sizeof(int) * ((size_t)m + 1));
    memcpy(f->L->next, f->next0, sizeof(int) * ((size_t)m + 2));
    memcpy(f->L->prev, f->prev0, sizeof(int) * ((size_t)m + 2));
    f->L->is_monotonic = 1;
  }
  for (int k = 0; k < m; k++) pact[k] = act[f->pperm[k]];
  for (int k = 0; k < m; k++) {
    int p0 = Lp[k];
    Li[p0] = k;
    Lnz[k] = 1;
    if (!pact[k]) { Lx[p0] = 1; continue; }
    par[k] = -1;
    flag[k] = k;                     /* rows above k carry flags < k: no reset needed */
    int top = m;
    for (int e = Kp[k]; e < Kp[k + 1]; e++) {
      int i = Ki[e];
      if (i == k) { y[k] += Kx[e] + delta; continue; }
      if (!pact[i]) continue;
      y[i] += Kx[e];
      int len = 0;
      for (; flag[i] != k; i = par[i]) {
        if (par[i] < 0) par[i] = k;
        stack[len++] = i;
        flag[i] = k;
      }
      while (len > 0) stack[--top] = stack[--len];
    }
    double d = y[k];
    y[k] = 0;
    ops += Kp[k + 1] - Kp[k] + m - top;
    for (; top < m; top++) {
      int i = stack[top], q0 = Lp[i], q1 = q0 + Lnz[i];
      double yi = y[i], lki = yi / Lx[q0];
      y[i] = 0;
      for (int q = q0 + 1; q < q1; q++) y[Li[q]] -= Lx[q] * yi;
      d -= lki * yi;
      Li[q1] = k;
      Lx[q1] = lki;
      Lnz[i]++;
      ops += q1 - q0;
    }
    if (!(d > 0)) {                  /* not positive definite: leave a valid factor (I) */
      for (int i = 0; i < m; i++) { y[i] = 0; Lnz[i] = 1; Li[Lp[i]] = i; Lx[Lp[i]] = 1; }
      memset(f->fact_act, 0, (size_t)m);
      memset(pact, 0, (size_t)m);
      f->refactor_ops = 0;
      return CUP_ERR_LINALG;
    }
    Lx[p0] = d;
  }
  f->refactor_ops = ops;
  return CUP_OK;
}

/* A row update's work, estimated by the path it walks up the current
 * factor's tree: from row k if it is free, else from each free neighbour. */
static double update_cost(const cup_dfact *f, int k) {
  const int *Lp = f->L->p, *Li = f->L->i, *Lnz = f->L->nz;
  const int *Mp = f->Mp->p, *Mi = f->Mp->i;
  double cost = 0;
  for (int e = Mp[k]; e < Mp[k + 1]; e++) {
    int i = Mi[e];
    if (i != k && !f->fact_act[f->pperm[i]]) continue;
    for (int j = i; j >= 0; j = Lnz[j] > 1 ? Li[Lp[j] + 1] : -1) cost += Lnz[j];
  }
  return cost;
}

/* Free row i (natural) joins: its column of M~ against the rows free now. */
static int mform_rowadd(cup_dfact *f, int i, double delta) {
  int k = f->iperm[i];
  const int *Mp = f->Mp->p, *Mi = f->Mp->i;
  const double *Mx = f->Mp->x;
  int *Rp = f->R->p, *Ri = f->R->i;
  double *Rx = f->R->x;
  int nz = 0;
  for (int e = Mp[k]; e < Mp[k + 1]; e++) {
    int r = Mi[e];
    if (r == k) { Ri[nz] = r; Rx[nz++] = Mx[e] + delta; }
    else if (f->fact_act[f->pperm[r]]) { Ri[nz] = r; Rx[nz++] = Mx[e]; }
  }
  Rp[0] = 0;
  Rp[1] = nz;
  if (!cholmod_rowadd((size_t)k, f->R, f->L, &f->cm)) return CUP_ERR_LINALG;
  f->fact_act[i] = 1;
  f->pact[k] = 1;
  return CUP_OK;
}

/* Free row i (natural) leaves. CHOLMOD finds row k of L by searching every
 * column before k unless told where it can be: the row of the full factor
 * (the reach of M(:, k) in the full tree) bounds it. */
static int mform_rowdel(cup_dfact *f, int i) {
  int k = f->iperm[i];
  const int *Kp = f->Ku->p, *Ki = f->Ku->i;
  int *Ri = f->R->i, *flag = f->flag, nz = 0;
  if (++f->stamp == 0 || f->stamp > (unsigned)INT_MAX) {
    memset(flag, 0, sizeof(int) * (size_t)f->m);
    f->stamp = 1;
  }
  int mark = -(int)f->stamp;         /* negative: never a row index of restricted_ldl */
  for (int e = Kp[k]; e < Kp[k + 1]; e++)
    for (int j = Ki[e]; j >= 0 && j < k && flag[j] != mark; j = f->etree[j]) {
      flag[j] = mark;
      Ri[nz++] = j;
    }
  ((int *)f->R->p)[0] = 0;
  ((int *)f->R->p)[1] = nz;
  if (!cholmod_rowdel((size_t)k, f->R, f->L, &f->cm)) return CUP_ERR_LINALG;
  f->fact_act[i] = 0;
  f->pact[k] = 0;
  return CUP_OK;
}

/* L D L^T t = t on the free rows only, in the permuted order (the other
 * rows are identity and come back unchanged); D folded into the backward
 * sweep. */
static void mform_solve(cup_dfact *f, double *v) {
  int m = f->m, nf = 0;
  const int *Lp = f->L->p, *Li = f->L->i, *Lnz = f->L->nz, *pp = f->pperm;
  const double *Lx = f->L->x;
  const unsigned char *pact = f->pact;
  int *cols = f->stack;
  double *t = f->work;
  for (int k = 0; k < m; k++)
    if (pact[k]) { cols[nf++] = k; t[k] = v[pp[k]]; }
  for (int c = 0; c < nf; c++) {
    int j = cols[c], p0 = Lp[j], p1 = p0 + Lnz[j];
    double tj = t[j];
    for (int p = p0 + 1; p < p1; p++) t[Li[p]] -= Lx[p] * tj;
  }
  for (int c = nf - 1; c >= 0; c--) {
    int j = cols[c], p0 = Lp[j], p1 = p0 + Lnz[j];
    double tj = t[j] / Lx[p0];
    for (int p = p0 + 1; p < p1; p++) tj -= Lx[p] * t[Li[p]];
    t[j] = tj;
    v[pp[j]] = tj;
  }
}

/* Row updates when their estimated work stays below a refactorization's
 * (CHOLMOD's updates cost a few times more per entry than restricted_ldl).
 * Rows leave first, so that each joining row sees the final free set. */
static int mform_update(cup_dfact *f, const unsigned char *act, double delta, long *changes) {
  int m = f->m;
  double budget = f->refactor_ops / 4, cost = 0;
  for (int i = 0; i < m && cost <= budget; i++)
    if (act[i] != f->fact_act[i]) cost += update_cost(f, f->iperm[i]);
  if (!(cost <= budget)) return 1;
  int st = CUP_OK;
  for (int i = 0; i < m && !st; i++)
    if (f->fact_act[i] && !act[i]) { st = mform_rowdel(f, i); ++*changes; }
  for (int i = 0; i < m && !st; i++)
    if (!f->fact_act[i] && act[i]) { st = mform_rowadd(f, i, delta); ++*changes; }
  return st;
}

/* ---- the interface ------------------------------------------------------------------- */

int cup_dfact_create(cup_dfact **out, const cup_polyset *K, int updates, char *errmsg) {
  *out = NULL;
  cup_dfact *f = calloc(1, sizeof *f);
  if (!f) return cup_fail(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
  f->K = K;
  f->n = K->n;
  f->m = K->m;
  f->kkt = K->pkind == CUP_METRIC_SPARSE;
  f->updates = updates && !f->kkt;
  int st = cup_cholmod_start(&f->cm) ? cup_fail(errmsg, CUP_ERR_LINALG, "CHOLMOD start failed") : CUP_OK;
  if (!st) st = f->kkt ? kkt_create(f, errmsg) : mform_create(f, errmsg);
  if (!st) {
    f->work = calloc(2 * (size_t)f->N, sizeof(double));   /* M form: rows outside F stay finite */
    f->fact_act = calloc((size_t)f->m + 1, 1);
    if (!f->work || !f->fact_act) st = cup_fail(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
  }
  double mmax = 0;
  for (int i = 0; i < f->m; i++) mmax = fmax(mmax, K->rownorm[i] * K->rownorm[i]);
  f->delta_min = 1e-10 * (mmax > 0 ? mmax : 1);
  if (st) { cup_dfact_free(&f); return st; }
  *out = f;
  return CUP_OK;
}

void cup_dfact_free(cup_dfact **fp) {
  if (!fp || !*fp) return;
  cup_dfact *f = *fp;
  if (f->L) cholmod_free_factor(&f->L, &f->cm);
  if (f->Ku) cholmod_free_sparse(&f->Ku, &f->cm);
  if (f->Mp) cholmod_free_sparse(&f->Mp, &f->cm);
  if (f->R) cholmod_free_sparse(&f->R, &f->cm);
  cholmod_finish(&f->cm);
  free(f->pperm); free(f->iperm); free(f->cpos); free(f->dpos);
  free(f->work); free(f->fact_act);
  free(f->pact); free(f->par); free(f->flag); free(f->stack); free(f->etree); free(f->yrow);
  free(f->lp0); free(f->next0); free(f->prev0);
  free(f);
  *fp = NULL;
}

int cup_dfact_factor(cup_dfact *f, const unsigned char *act, double delta,
                     int *refactorizations, int *row_updates) {
  int m = f->m;
  int same = f->has_fact && f->fact_delta == delta;
  if (same && memcmp(act, f->fact_act, (size_t)m) == 0) return CUP_OK;
  int st;
  if (!f->kkt && f->updates && same && f->refactor_ops > 0) {
    long changes = 0;
    st = mform_update(f, act, delta, &changes);
    *row_updates += (int)changes;
    if (st <= 0) {                     /* 1: refactoring is cheaper */
      if (st) f->has_fact = 0;
      return st;
    }
  }
  st = f->kkt ? kkt_factor(f, act, delta) : restricted_ldl(f, act, delta);
  (*refactorizations)++;
  if (st) { f->has_fact = 0; return st; }
  memcpy(f->fact_act, act, (size_t)m);
  f->fact_delta = delta;
  f->has_fact = 1;
  return CUP_OK;
}

void cup_dfact_revalue(cup_dfact *f) {
  const cup_polyset *K = f->K;
  int m = f->m;
  const int *Mp = f->Mp->p, *Mi = f->Mp->i, *Kp = f->Ku->p;
  double *Mx = f->Mp->x, *Kx = f->Ku->x, *wv = f->work, mmax = 0;
  for (int i = 0; i < m; i++) wv[i] = 0;
  for (int c = 0; c < m; c++) {
    int i = f->pperm[c];
    /* column i of M = C P^-1 c_i, scattered by natural row */
    for (int a = K->Ct.p[i]; a < K->Ct.p[i + 1]; a++) {
      int j = K->Ct.i[a];
      double cij = K->Ct.x[a] * K->pdinv[j];
      for (int b = K->C.p[j]; b < K->C.p[j + 1]; b++) wv[K->C.i[b]] += K->C.x[b] * cij;
    }
    /* Mp's column c (sorted), whose upper part is Ku's column c in order */
    int q = Kp[c];
    for (int e = Mp[c]; e < Mp[c + 1]; e++) {
      int r = Mi[e];
      double v = wv[f->pperm[r]];
      Mx[e] = v;
      if (r <= c) Kx[q++] = v;
      if (r == c) mmax = fmax(mmax, v);
    }
    for (int a = K->Ct.p[i]; a < K->Ct.p[i + 1]; a++) {
      int j = K->Ct.i[a];
      for (int b = K->C.p[j]; b < K->C.p[j + 1]; b++) wv[K->C.i[b]] = 0;
    }
  }
  f->delta_min = 1e-10 * (mmax > 0 ? mmax : 1);
  f->has_fact = 0;                         /* the next factor is a full numeric one */
}

void cup_dfact_solve(cup_dfact *f, double *v) {
  if (f->kkt) kkt_solve(f, v);
  else mform_solve(f, v);
}

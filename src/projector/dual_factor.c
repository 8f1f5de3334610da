/* dual_factor — see dual_factor.h. */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "dual_factor.h"
#include "dual_cg.h"

struct dfact {
  const cup_polyset *K;
  int kkt;                    /* 1: KKT form (sparse P); 0: M form (diagonal P) */
  int n, m, N;                /* N: order of the factored matrix (n + m or m) */
  int updates;                /* M form: row updates allowed */
  cholmod_common cm;
  cholmod_sparse *Ku;         /* KKT form: permuted upper matrix, values rewritten */
  cholmod_sparse *Mp;         /* M form: permuted upper triangle of M, sorted */
  cholmod_sparse R;           /* M form: one column for rowadd, one row pattern for rowdel */
  int Rp[2];
  cholmod_factor *L;          /* simplicial LDL^T; M form: in `room` entries, laid out by new_layout */
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
  unsigned stamp;             /* marks in flag for row patterns (row updates, their cost) */
  double refactor_ops;        /* work of the last refactorization; 0: none yet */
  /* M form: the factor of the free rows alone, laid out for a set of rows
   * that holds them (row updates inside it); when no layout fits the room,
   * solves by conjugate gradients on M~ instead (dual_cg.c) */
  size_t room;                /* entries of L */
  int *lp0;                   /* the layout: each column's room its count in the factor of
                               * lay_act's rows, and a spare entry for those rows */
  unsigned char *lay_act;     /* the rows the layout was made for (permuted order) */
  int lay_ok;
  int all_fit;                /* 0: a layout for every row of nonzero norm did not fit */
  int lp_stale;               /* L->p is not the layout */
  int by_cg;
  double *cg_z, *cg_p, *cg_q, *cg_u;   /* m, m, m, n */
};

double dfact_delta_min(const dfact *f) { return f->delta_min; }
int dfact_by_cg(const dfact *f) { return f->by_cg; }

/* ---- permutation and upper storage (shared) ---------------------------------- */

/* AMD order of a symmetric matrix (CHOLMOD reads the triangle its stype
 * names) into pperm/iperm; the analysis' workspace is let go at once. With
 * full, the entries of the factor of all of it in that order (the analysis
 * counts them anyway). */
static int amd_order(dfact *f, cholmod_sparse *A, long *full, char *errmsg) {
  int N = (int)A->nrow;
  f->cm.supernodal = CHOLMOD_SIMPLICIAL;
  f->cm.final_ll = 0;
  /* AMD alone: the factors are of the free rows only (restricted_ldl), whose
   * fill an ordering of all of M hardly changes; METIS and nested dissection
   * saved 3-5% of the room for all of M on crowds of 10^5 disks and took 15
   * times AMD's time (8.5 s against 0.25 s); a set whose rows change with
   * the state is analysed again when they do */
  f->cm.nmethods = 1;
  f->cm.method[0].ordering = CHOLMOD_AMD;
  cholmod_factor *L0 = cholmod_analyze(A, &f->cm);
  if (!L0) return fail_fmt(errmsg, CUP_ERR_LINALG, "dual factor: CHOLMOD analysis failed (%d)", f->cm.status);
  f->pperm = malloc(sizeof(int) * (size_t)N);
  f->iperm = malloc(sizeof(int) * (size_t)N);
  if (f->pperm && f->iperm)
    for (int k = 0; k < N; k++) {
      int orig = L0->Perm ? ((int *)L0->Perm)[k] : k;
      f->pperm[k] = orig;
      f->iperm[orig] = k;
    }
  if (full) {
    *full = 0;
    for (int k = 0; k < N; k++) *full += ((int *)L0->ColCount)[k];
  }
  cholmod_free_factor(&L0, &f->cm);
  cholmod_free_work(&f->cm);
  if (!f->pperm || !f->iperm) return fail_fmt(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
  return CUP_OK;
}

/* From a symmetric matrix given by its lower triangle (natural order; each
 * entry tagged), build the permuted upper triangle with a map from every
 * original entry to its position. */
static int permuted_upper(dfact *f, int N, const int *Ap, const int *Ai, const double *Ax,
                          int *map, char *errmsg) {
  int nnz = Ap[N];
  cholmod_sparse A = {0};
  A.nrow = A.ncol = (size_t)N; A.nzmax = (size_t)nnz;
  A.p = (void *)Ap; A.i = (void *)Ai; A.x = (void *)Ax; A.stype = -1;
  A.itype = CHOLMOD_INT; A.xtype = CHOLMOD_REAL; A.dtype = CHOLMOD_DOUBLE;
  A.sorted = 1; A.packed = 1;
  int st = amd_order(f, &A, NULL, errmsg);
  if (st) return st;
  int *rowcnt = calloc((size_t)N + 1, sizeof(int)), *colcnt = calloc((size_t)N + 1, sizeof(int));
  int *order = malloc(sizeof(int) * ((size_t)nnz + 1)), *colof = malloc(sizeof(int) * ((size_t)nnz + 1));
  f->Ku = cholmod_allocate_sparse((size_t)N, (size_t)N, (size_t)nnz, 1, 1, 1, CHOLMOD_REAL, &f->cm);
  if (!rowcnt || !colcnt || !order || !colof || !f->Ku) {
    st = fail_fmt(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
    goto done;
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
  free(rowcnt); free(colcnt); free(order); free(colof);
  return st;
}

/* Symbolic analysis in the stored (natural) order, unpacked so that row
 * updates find room, and a first numeric factorization so that later ones
 * reuse L's memory. */
static int symbolic(dfact *f, char *errmsg) {
  f->cm.nmethods = 1;
  f->cm.method[0].ordering = CHOLMOD_NATURAL;
  f->cm.postorder = 0;
  f->cm.final_pack = 0;
  f->L = cholmod_analyze(f->Ku, &f->cm);
  if (!f->L) return fail_fmt(errmsg, CUP_ERR_LINALG, "dual factor: CHOLMOD analysis failed (%d)", f->cm.status);
  cholmod_factorize(f->Ku, f->L, &f->cm);
  if (f->cm.status < 0) return fail_fmt(errmsg, CUP_ERR_LINALG, "dual factor: factorization failed (%d)", f->cm.status);
  f->has_fact = 1;
  f->fact_delta = -1;                      /* no delta yet: the first real factor is full */
  return CUP_OK;
}

/* ---- the KKT form (sparse P) ---------------------------------------------------- */

static int kkt_create(dfact *f, char *errmsg) {
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
    st = fail_fmt(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
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

static int kkt_factor(dfact *f, const unsigned char *act, double delta) {
  const la_sparse *C = &f->K->C;
  double *Kx = f->Ku->x;
  for (int j = 0; j < C->ncol; j++)
    for (int k = C->p[j]; k < C->p[j + 1]; k++) Kx[f->cpos[k]] = act[C->i[k]] ? C->x[k] : 0;
  for (int i = 0; i < f->m; i++) Kx[f->dpos[i]] = act[i] ? -delta : -1;
  cholmod_factorize(f->Ku, f->L, &f->cm);
  return f->cm.status < 0 || f->cm.status == CHOLMOD_NOT_POSDEF ? CUP_ERR_LINALG : CUP_OK;
}

/* [P C_F^T; C_F -delta][u; w] = [0; v]  gives  w = -(M_FF + delta)^-1 v. */
static void kkt_solve(dfact *f, double *v) {
  int n = f->n, m = f->m, N = f->N;
  double *t = f->work, *scratch = f->work + N;
  for (int k = 0; k < N; k++) {
    int o = f->pperm[k];
    t[k] = o < n ? 0 : v[o - n];
  }
  la_simplicial_solve(f->L, t, scratch);
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
static void full_etree(dfact *f) {
  const int *Mp = f->Mp->p, *Mi = f->Mp->i;
  int *anc = f->flag;
  for (int k = 0; k < f->m; k++) {
    f->etree[k] = -1;
    anc[k] = -1;
    for (int e = Mp[k]; e < Mp[k + 1]; e++)
      for (int i = Mi[e], next; i != -1 && i < k; i = next) {
        next = anc[i];
        anc[i] = k;
        if (next == -1) f->etree[i] = k;
      }
  }
  memset(f->flag, 0, sizeof(int) * (size_t)f->m);
}

static int cmp_int(const void *a, const void *b) {
  int x = *(const int *)a, y = *(const int *)b;
  return (x > y) - (x < y);
}

/* A column's rows in order: by insertion when they are a few (a crowd's
 * columns of M hold about five), where qsort's calls cost more than the
 * sort. */
static void sort_rows(int *a, int len) {
  if (len > 32) {
    qsort(a, (size_t)len, sizeof(int), cmp_int);
    return;
  }
  for (int t = 1; t < len; t++) {
    int v = a[t], u = t;
    for (; u > 0 && a[u - 1] > v; u--) a[u] = a[u - 1];
    a[u] = v;
  }
}

/* M = C P^-1 C^T in the permuted order, sorted, every diagonal present (a
 * zero row of C has M_ii = 0): its upper triangle. Column by
 * column from the rows of C, M_ri = sum_j c_rj c_ij / p_j, so that no
 * copy of M is made on the way (CHOLMOD's product, sum and sort made four);
 * a first pass counts the entries (the pattern alone), the second sums. */
static cholmod_sparse *build_m(dfact *f) {
  const la_sparse *C = &f->K->C, *Ct = &f->K->Ct;
  const double *pdinv = f->K->pdinv;
  int m = f->m;
  int *mark = malloc(sizeof(int) * ((size_t)m + 1)), *list = malloc(sizeof(int) * ((size_t)m + 1));
  double *val = calloc((size_t)m + 1, sizeof(double));
  cholmod_sparse *M = NULL;
  if (!mark || !list || !val) goto done;
  for (int pass = 0; pass < 2; pass++) {
    size_t nnz = 0;
    for (int k = 0; k < m; k++) mark[k] = -1;
    for (int k = 0; k < m; k++) {
      int i = f->pperm[k], len = 0;
      mark[k] = k;
      list[len++] = k;
      for (int a = Ct->p[i]; a < Ct->p[i + 1]; a++) {
        int j = Ct->i[a];
        double cij = Ct->x[a] * pdinv[j];
        for (int b = C->p[j]; b < C->p[j + 1]; b++) {
          int r = f->iperm[C->i[b]];
          if (r > k) continue;
          if (mark[r] != k) { mark[r] = k; list[len++] = r; }
          if (pass == 1) val[r] += C->x[b] * cij;
        }
      }
      if (pass == 1) {
        int *Mp = M->p, *Mi = M->i;
        double *Mx = M->x;
        sort_rows(list, len);
        for (int t = 0; t < len; t++) {
          Mi[Mp[k] + t] = list[t];
          Mx[Mp[k] + t] = val[list[t]];
          val[list[t]] = 0;
        }
        Mp[k + 1] = Mp[k] + len;
      }
      nnz += (size_t)len;
    }
    if (pass == 0) {
      M = cholmod_allocate_sparse((size_t)m, (size_t)m, nnz, 1, 1, 0, CHOLMOD_REAL, &f->cm);
      if (!M) goto done;
      ((int *)M->p)[0] = 0;
    }
  }
done:
  free(mark); free(list); free(val);
  return M;
}

/* The column counts of the factor of M_FF, F = pact (permuted order; the
 * reach of each row, as restricted_ldl walks it) laid out packed in p;
 * returns the entries. */
static long packed_layout(dfact *f, const unsigned char *pact, int *p) {
  int m = f->m;
  const int *Mp = f->Mp->p, *Mi = f->Mp->i;
  int *par = f->par, *flag = f->flag;
  for (int k = 0; k < m; k++) p[k + 1] = 1 + pact[k];   /* a free row's column: one spare entry */
  for (int k = 0; k < m; k++) {
    if (!pact[k]) continue;
    par[k] = -1;
    flag[k] = k;
    for (int e = Mp[k]; e < Mp[k + 1]; e++)
      for (int i = Mi[e]; i < k && pact[i] && flag[i] != k; i = par[i]) {
        if (par[i] < 0) par[i] = k;
        flag[i] = k;
        p[i + 1]++;
      }
  }
  for (int k = 0; k < m; k++) flag[k] = k;   /* below any row that looks at k */
  p[0] = 0;
  for (int k = 0; k < m; k++) p[k + 1] += p[k];
  return p[m];
}

/* A layout holds the factor of any subset of the rows it was made for (the
 * filled graph of a principal submatrix, eliminated in the same order, is a
 * subgraph): a new delta, or rows leaving, keep it. */
static int fits_layout(const dfact *f) {
  if (!f->lay_ok) return 0;
  for (int k = 0; k < f->m; k++)
    if (f->pact[k] > f->lay_act[k]) return 0;
  return 1;
}

/* A layout for every row of nonzero norm if that fits the room (then every
 * free set fits it); else for the free set and the last layout's rows (the
 * free set of a jam wanders among the same rows); else for the free set. */
static int new_layout(dfact *f) {
  f->lp_stale = 1;
  if (f->all_fit) {
    for (int k = 0; k < f->m; k++) f->lay_act[k] = f->K->rownorm[f->pperm[k]] > 0;
    if (packed_layout(f, f->lay_act, f->lp0) <= (long)f->room) return f->lay_ok = 1;
    f->all_fit = 0;
    f->lay_ok = 0;
  }
  if (f->lay_ok) {
    for (int k = 0; k < f->m; k++) f->lay_act[k] |= f->pact[k];
    if (packed_layout(f, f->lay_act, f->lp0) <= (long)f->room) return 1;
  }
  f->lay_ok = packed_layout(f, f->pact, f->lp0) <= (long)f->room;
  if (f->lay_ok) memcpy(f->lay_act, f->pact, (size_t)f->m);
  return f->lay_ok;
}

/* The room of the factor: all of M's factor with a spare entry a column,
 * unless that is more than twice M itself: then twice M. The free rows of a
 * crowd are a few in a hundred of its contacts, and the factor of all of M
 * 3-6 times M (10^3-10^5 disks), most of the projector's memory; a chain (a
 * ladder) fills less than M. The free rows of a jam (1000 disks, 600 steps)
 * never outgrew twice M; a free set that does is solved by CG. */
static long auto_room(long full, long nnz_m, int m) {
  return full > 2 * nnz_m ? 2 * nnz_m : full + m;
}

/* L's columns in order, linked as CHOLMOD links a monotonic simplicial
 * factor (head m + 1, tail m). */
static void columns_in_order(cholmod_factor *L, int m) {
  int *next = L->next, *prev = L->prev;
  for (int j = 0; j < m; j++) {
    next[j] = j + 1;
    prev[j] = j - 1;
  }
  prev[0] = m + 1;
  next[m] = -1;
  prev[m] = m - 1;
  next[m + 1] = 0;
  prev[m + 1] = -1;
  L->is_monotonic = 1;
}

/* L = I in room for `room` entries (at least the diagonal), a CHOLMOD factor
 * object so that CHOLMOD's row updates work on it; restricted_ldl lays each
 * factor out in it (new_layout). What row updates need (CHOLMOD's
 * workspace, a column, the tree of all of M) is taken now, not in a
 * projection. */
static int factor_room(dfact *f, long room, char *errmsg) {
  size_t M1 = (size_t)f->m + 1;
  f->room = (size_t)(room > f->m ? room : f->m);
  f->L = cholmod_allocate_factor((size_t)f->m, &f->cm);
  if (!f->L || !cholmod_change_factor(CHOLMOD_REAL, 0, 0, 1, 1, f->L, &f->cm) ||
      !cholmod_reallocate_factor(f->room, f->L, &f->cm))
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory for the factor");
  f->lp0 = malloc(sizeof(int) * M1);
  f->lay_act = calloc(M1, 1);
  f->cg_z = malloc(sizeof(double) * M1);
  f->cg_p = malloc(sizeof(double) * M1);
  f->cg_q = malloc(sizeof(double) * M1);
  f->cg_u = calloc((size_t)f->n + 1, sizeof(double));
  if (!f->lp0 || !f->lay_act || !f->cg_z || !f->cg_p || !f->cg_q || !f->cg_u)
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
  f->all_fit = f->lp_stale = 1;
  new_layout(f);
  /* row updates in every layout: rows inside it join and leave by updates,
   * rows outside it make a new layout and a refactorization. Where the
   * layout holds every row of nonzero norm (a ladder, the jam of 1000
   * disks) every free set fits; where it holds the free set and the last
   * layout's rows (crowds of 10^4 disks and more) a jam's free set wanders
   * among them: 10^4 disks jammed at a door of 1.2 m, half the
   * refactorizations and a third of the time, for a workspace of 5 m ints
   * and 2 m doubles (+5-6 % of the projector's memory at 10^4 and 10^5) */
  if (!f->updates) return CUP_OK;
  f->etree = malloc(sizeof(int) * M1);
  if (!f->etree) return fail_fmt(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
  full_etree(f);
  /* rowadd/rowdel need 2m of CHOLMOD workspace */
  if (!cholmod_allocate_work((size_t)f->m, 2 * (size_t)f->m, 2 * (size_t)f->m, &f->cm))
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory for CHOLMOD workspace");
  return CUP_OK;
}

/* room < 0: automatic (auto_room); else the room, in entries. */
static int mform_create(dfact *f, long room, char *errmsg) {
  const la_sparse *C = &f->K->C;
  int m = f->m;
  f->N = m;
  /* AMD of M = C P^-1 C^T from C's pattern (CHOLMOD orders C C^T), and the
   * size of the factor of all of M in that order: C C^T has M's pattern
   * (build_m keeps every product, and every row of the pool has entries) */
  cholmod_sparse Cv = {0};
  Cv.nrow = (size_t)m; Cv.ncol = (size_t)f->n; Cv.nzmax = (size_t)C->nnz;
  Cv.p = C->p; Cv.i = C->i; Cv.x = C->x; Cv.stype = 0;
  Cv.itype = CHOLMOD_INT; Cv.xtype = CHOLMOD_REAL; Cv.dtype = CHOLMOD_DOUBLE;
  Cv.sorted = 1; Cv.packed = 1;
  long full = 0;
  int st = amd_order(f, &Cv, &full, errmsg);
  if (st) return st;
  size_t M1 = (size_t)m + 1;
  f->Mp = build_m(f);
  f->pact = calloc(M1, 1);
  f->par = malloc(sizeof(int) * M1);
  f->flag = calloc(M1, sizeof(int));
  f->stack = malloc(sizeof(int) * M1);
  f->yrow = calloc(M1, sizeof(double));
  if (!f->Mp || !f->pact || !f->par || !f->flag || !f->stack || !f->yrow)
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory forming C P^-1 C^T");
  long nnz_m = 2L * ((int *)f->Mp->p)[m] - m;
  /* a column CHOLMOD's row updates would move (none should: new_layout
   * leaves a spare entry in each) gets no more room than it needs */
  f->cm.grow1 = 1;
  f->cm.grow2 = 0;
  return factor_room(f, room < 0 ? auto_room(full, nnz_m, m) : room, errmsg);
}

/* LDL^T of M~ = M_FF + delta I on the free rows F, identity elsewhere, by
 * rows (up-looking, Davis' LDL): row k of L solves with the rows above it on
 * the reach of M(F, k) in the elimination tree, which is built on the way
 * (a row's parent is the first later row that reaches it). The work is that
 * of the factor of M_FF alone, whatever the size of M: a crowd with a tenth
 * of its contacts active, or half a ladder, costs a fraction of M's factor.
 * Written into CHOLMOD's simplicial factor (diagonal first in each column),
 * in a layout for a set of rows that holds F (made first if the last one
 * does not), so that row updates and solves work on it as on CHOLMOD's own;
 * by_cg when no layout for F fits the room. */
static int restricted_ldl(dfact *f, const unsigned char *act, double delta) {
  int m = f->m;
  const int *Kp = f->Mp->p, *Ki = f->Mp->i, *Kend = Kp + 1;
  const double *Kx = f->Mp->x;
  int *Lp = f->L->p, *Li = f->L->i, *Lnz = f->L->nz;
  double *Lx = f->L->x, *y = f->yrow;
  int *par = f->par, *flag = f->flag, *stack = f->stack;
  unsigned char *pact = f->pact;
  double ops = 0;
  if (!f->L->is_monotonic) {                 /* columns moved by row updates */
    columns_in_order(f->L, m);
    f->lp_stale = 1;
  }
  for (int k = 0; k < m; k++) pact[k] = act[f->pperm[k]];
  if (!fits_layout(f)) f->by_cg = !new_layout(f);
  if (f->by_cg) {
    for (int k = 0; k < m; k++) { Lp[k + 1] = k + 1; Lnz[k] = 1; Li[k] = k; Lx[k] = 1; }
    f->refactor_ops = 0;
    return CUP_OK;
  }
  if (f->lp_stale) memcpy(Lp, f->lp0, sizeof(int) * ((size_t)m + 1));
  f->lp_stale = 0;
  for (int k = 0; k < m; k++) {
    int p0 = Lp[k];
    Li[p0] = k;
    Lnz[k] = 1;
    if (!pact[k]) { Lx[p0] = 1; continue; }
    par[k] = -1;
    flag[k] = k;                     /* rows above k carry flags < k: no reset needed */
    int top = m;
    for (int e = Kp[k]; e < Kend[k]; e++) {
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
    ops += Kend[k] - Kp[k] + m - top;
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

/* A fresh mark for flag: negative, never a row index of restricted_ldl. */
static int new_mark(dfact *f) {
  if (++f->stamp == 0 || f->stamp > (unsigned)INT_MAX) {
    memset(f->flag, 0, sizeof(int) * (size_t)f->m);
    f->stamp = 1;
  }
  return -(int)f->stamp;
}

/* A row update's work, estimated by the columns on the paths up the current
 * factor's tree from row i and from its free neighbours, each column once
 * (CHOLMOD's solve for a joining row, and the update of the rows below it
 * along the path from its new column's first entry, which starts at a
 * neighbour or on the path of one). */
static double update_cost(dfact *f, int i) {
  const la_sparse *C = &f->K->C, *Ct = &f->K->Ct;
  const int *Lp = f->L->p, *Li = f->L->i, *Lnz = f->L->nz;
  int mark = new_mark(f);
  double cost = 0;
  for (int a = Ct->p[i]; a < Ct->p[i + 1]; a++)
    for (int b = C->p[Ct->i[a]]; b < C->p[Ct->i[a] + 1]; b++) {
      int r = C->i[b];
      if (r != i && !f->fact_act[r]) continue;
      for (int j = f->iperm[r]; j >= 0 && f->flag[j] != mark; j = Lnz[j] > 1 ? Li[Lp[j] + 1] : -1) {
        f->flag[j] = mark;
        cost += Lnz[j];
      }
    }
  return cost;
}

/* The column (rowadd) or row pattern (rowdel) handed to CHOLMOD, held in
 * scratch that is free during row updates: the reach stack and the solves'
 * work. */
static cholmod_sparse *update_vector(dfact *f, int nz) {
  cholmod_sparse *R = &f->R;
  memset(R, 0, sizeof *R);
  R->nrow = R->nzmax = (size_t)f->m;
  R->ncol = 1;
  f->Rp[0] = 0;
  f->Rp[1] = nz;
  R->p = f->Rp; R->i = f->stack; R->x = f->work;
  R->packed = 1;
  R->itype = CHOLMOD_INT; R->xtype = CHOLMOD_REAL; R->dtype = CHOLMOD_DOUBLE;
  return R;
}

/* Free row i (natural) joins: its column of M~ against the rows free now,
 * M(:, i) = C P^-1 c_i summed as build_m does (the packed form keeps only
 * M's upper part). */
static int mform_rowadd(dfact *f, int i, double delta) {
  const la_sparse *C = &f->K->C, *Ct = &f->K->Ct;
  int k = f->iperm[i], mark = new_mark(f), nz = 0;
  int *Ri = f->stack, *flag = f->flag;
  double *Rx = f->work, *y = f->yrow;
  for (int a = Ct->p[i]; a < Ct->p[i + 1]; a++) {
    int j = Ct->i[a];
    double cij = Ct->x[a] * f->K->pdinv[j];
    for (int b = C->p[j]; b < C->p[j + 1]; b++) {
      int r = C->i[b], pr = f->iperm[r];
      if (r != i && !f->fact_act[r]) continue;
      if (flag[pr] != mark) { flag[pr] = mark; Ri[nz++] = pr; }
      y[pr] += C->x[b] * cij;
    }
  }
  for (int t = 0; t < nz; t++) {
    Rx[t] = y[Ri[t]] + (Ri[t] == k ? delta : 0);
    y[Ri[t]] = 0;
  }
  if (!cholmod_rowadd((size_t)k, update_vector(f, nz), f->L, &f->cm)) return CUP_ERR_LINALG;
  f->fact_act[i] = 1;
  f->pact[k] = 1;
  return CUP_OK;
}

/* Free row i (natural) leaves. CHOLMOD finds row k of L by searching every
 * column before k unless told where it can be: the row of the full factor
 * (the reach of M(:, k) in the full tree) bounds it. */
static int mform_rowdel(dfact *f, int i) {
  int k = f->iperm[i];
  const int *Kp = f->Mp->p, *Ki = f->Mp->i;
  int *Ri = f->stack, *flag = f->flag, nz = 0, mark = new_mark(f);
  for (int e = Kp[k]; e < Kp[k + 1]; e++)
    for (int j = Ki[e]; j >= 0 && j < k && flag[j] != mark; j = f->etree[j]) {
      flag[j] = mark;
      Ri[nz++] = j;
    }
  if (!cholmod_rowdel((size_t)k, update_vector(f, nz), f->L, &f->cm)) return CUP_ERR_LINALG;
  f->fact_act[i] = 0;
  f->pact[k] = 0;
  return CUP_OK;
}

/* L D L^T t = t on the free rows only, in the permuted order (the other
 * rows are identity and come back unchanged); D folded into the backward
 * sweep. */
static void mform_solve(dfact *f, double *v) {
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
 * (CHOLMOD's updates cost a few times more per entry than restricted_ldl),
 * for rows inside the layout only: there no column outgrows its room (the
 * factors of subsets of the layout's rows, and the explicit zeros CHOLMOD
 * leaves behind, keep to that of the whole set), and the spare entry of each
 * keeps CHOLMOD from moving a full one before it looks; CHOLMOD would
 * otherwise reallocate L. Rows leave first, so that each joining row sees
 * the final free set. */
static int mform_update(dfact *f, const unsigned char *act, double delta, long *changes) {
  int m = f->m;
  double budget = f->refactor_ops / 4, cost = 0;
  for (int i = 0; i < m && cost <= budget; i++) {
    if (act[i] == f->fact_act[i]) continue;
    if (act[i] && !f->lay_act[f->iperm[i]]) return 1;     /* outside the layout */
    cost += update_cost(f, i);
  }
  if (!(cost <= budget)) return 1;
  int st = CUP_OK;
  for (int i = 0; i < m && !st; i++)
    if (f->fact_act[i] && !act[i]) { st = mform_rowdel(f, i); ++*changes; }
  for (int i = 0; i < m && !st; i++)
    if (!f->fact_act[i] && act[i]) { st = mform_rowadd(f, i, delta); ++*changes; }
  return st;
}

/* ---- the interface ------------------------------------------------------------------- */

int dfact_create(dfact **out, const cup_polyset *K, int updates, long room, char *errmsg) {
  *out = NULL;
  dfact *f = calloc(1, sizeof *f);
  if (!f) return fail_fmt(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
  f->K = K;
  f->n = K->n;
  f->m = K->m;
  f->kkt = K->pkind == CUP_METRIC_SPARSE;
  f->updates = updates && !f->kkt;
  int st = la_cholmod_start(&f->cm) ? fail_fmt(errmsg, CUP_ERR_LINALG, "CHOLMOD start failed") : CUP_OK;
  if (!st) st = f->kkt ? kkt_create(f, errmsg) : mform_create(f, room, errmsg);
  if (!st) {
    f->work = calloc(2 * (size_t)f->N, sizeof(double));   /* M form: rows outside F stay finite */
    f->fact_act = calloc((size_t)f->m + 1, 1);
    if (!f->work || !f->fact_act) st = fail_fmt(errmsg, CUP_ERR_NOMEM, "dual factor: out of memory");
  }
  double mmax = 0;
  for (int i = 0; i < f->m; i++) mmax = la_max(K->rownorm[i] * K->rownorm[i], mmax);
  f->delta_min = 1e-10 * (mmax > 0 ? mmax : 1);
  if (st) { dfact_free(&f); return st; }
  *out = f;
  return CUP_OK;
}

void dfact_free(dfact **fp) {
  if (!fp || !*fp) return;
  dfact *f = *fp;
  if (f->L) cholmod_free_factor(&f->L, &f->cm);
  if (f->Ku) cholmod_free_sparse(&f->Ku, &f->cm);
  if (f->Mp) cholmod_free_sparse(&f->Mp, &f->cm);
  cholmod_finish(&f->cm);
  free(f->pperm); free(f->iperm); free(f->cpos); free(f->dpos);
  free(f->work); free(f->fact_act);
  free(f->pact); free(f->par); free(f->flag); free(f->stack); free(f->etree); free(f->yrow);
  free(f->lp0);
  free(f->cg_z); free(f->cg_p); free(f->cg_q); free(f->cg_u); free(f->lay_act);
  free(f);
  *fp = NULL;
}

int dfact_factor(dfact *f, const unsigned char *act, double delta,
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

void dfact_revalue(dfact *f) {
  const cup_polyset *K = f->K;
  int m = f->m;
  const int *Mp = f->Mp->p, *Mi = f->Mp->i;
  double *Mx = f->Mp->x, *wv = f->work, mmax = 0;
  for (int i = 0; i < m; i++) wv[i] = 0;
  for (int c = 0; c < m; c++) {
    int i = f->pperm[c];
    /* column i of M = C P^-1 c_i, scattered by natural row */
    for (int a = K->Ct.p[i]; a < K->Ct.p[i + 1]; a++) {
      int j = K->Ct.i[a];
      double cij = K->Ct.x[a] * K->pdinv[j];
      for (int b = K->C.p[j]; b < K->C.p[j + 1]; b++) wv[K->C.i[b]] += K->C.x[b] * cij;
    }
    for (int e = Mp[c]; e < Mp[c + 1]; e++) {
      int r = Mi[e];
      double v = wv[f->pperm[r]];
      Mx[e] = v;
      if (r == c) mmax = la_max(v, mmax);   /* NaN passed over, as by fmax */
    }
    for (int a = K->Ct.p[i]; a < K->Ct.p[i + 1]; a++) {
      int j = K->Ct.i[a];
      for (int b = K->C.p[j]; b < K->C.p[j + 1]; b++) wv[K->C.i[b]] = 0;
    }
  }
  f->delta_min = 1e-10 * (mmax > 0 ? mmax : 1);
  f->has_fact = 0;                         /* the next factor is a full numeric one */
}

void dfact_solve(dfact *f, double *v) {
  if (f->kkt) kkt_solve(f, v);
  else if (f->by_cg) {
    double *w[5] = {f->work, f->work + f->m, f->cg_z, f->cg_p, f->cg_q};
    dual_cg(f->K, f->fact_act, f->fact_delta, v, w, f->cg_u);
  }
  else mform_solve(f, v);
}

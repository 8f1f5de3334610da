/* netlist_hybrid — the hybrid matrix H of the resistive network seen from
 * the ports (netlist_impl.h): H = J X^T X + N with X = L^-1 Pi K from the
 * Cholesky factor of the supernodes' Laplacian, J = diag(1 on voltage
 * ports, -1 on current ports) and N the tree-path terms. Entries that
 * cancel to rounding are dropped by a bound computed alongside (the same
 * sums in absolute values), and the rows of fixed diodes among the voltage
 * ports are zero by structure (their current cannot depend on port voltages
 * when every current port is open: they are tree edges between parts that
 * nothing else joins), so D = 0 and P B = C^T hold exactly where they
 * should. */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "netlist_impl.h"

/* The four arrays in one allocation, x's start (a configuration formed in
 * a switched run fills some 8 of these: 4 reallocs each and 4 frees, some
 * 10 % of the formulation, were one malloc and one free). From 16 entries
 * up: 256 were 6 KB a list for a handful of entries, and the full bridge's
 * configurations, formed in its run, spent 60 us of wall time (some 40
 * page faults) more in their formulation with them. */
int nl_coo_add(nl_coo *t, int i, int j, double x, double mag) {
  if (t->n == t->cap) {
    int cap = t->cap ? 2 * t->cap : 16;
    double *nx = malloc((2 * sizeof(double) + 2 * sizeof(int)) * (size_t)cap);
    if (!nx) return CUP_ERR_NOMEM;
    double *nm = nx + cap;
    int *ni = (int *)(nm + cap), *nj = ni + cap;
    if (t->n) {
      memcpy(nx, t->x, sizeof(double) * (size_t)t->n);
      memcpy(nm, t->mag, sizeof(double) * (size_t)t->n);
      memcpy(ni, t->i, sizeof(int) * (size_t)t->n);
      memcpy(nj, t->j, sizeof(int) * (size_t)t->n);
    }
    free(t->x);
    t->x = nx; t->mag = nm; t->i = ni; t->j = nj;
    t->cap = cap;
  }
  t->i[t->n] = i; t->j[t->n] = j; t->x[t->n] = x; t->mag[t->n++] = mag;
  return CUP_OK;
}

void nl_coo_free(nl_coo *t) { free(t->x); memset(t, 0, sizeof *t); }

int nl_coo_to_csc(const nl_coo *t, int nrow, int ncol, la_sparse *out) {
  /* the scratch in one allocation (a switched run formulates each
   * configuration inside its run, some 60 of these a bridge): acc, amag,
   * then cnt (zeroed), order, mark, rows */
  size_t R = (size_t)nrow + 1, C = (size_t)ncol + 1, N = (size_t)t->n + 1;
  size_t need = sizeof(double) * 2 * R + sizeof(int) * (C + N + 2 * R);
  /* a small one on the stack (a converter's all are: a malloc and a free each, ~200 instructions) */
  double small[512], *acc = scratch_take(small, sizeof small, need, 0), *amag = acc ? acc + R : NULL;
  int *cnt = acc ? (int *)(amag + R) : NULL, *order = cnt ? cnt + C : NULL;
  int *mark = order ? order + N : NULL, *rows = mark ? mark + R : NULL;
  int st = acc ? CUP_OK : CUP_ERR_NOMEM;
  if (!st) {
    memset(cnt, 0, sizeof(int) * C);
    for (int k = 0; k < t->n; k++) cnt[t->j[k] + 1]++;
    for (int c = 0; c < ncol; c++) cnt[c + 1] += cnt[c];
    for (int k = 0; k < t->n; k++) order[cnt[t->j[k]]++] = k;   /* by column */
    for (int c = ncol; c > 0; c--) cnt[c] = cnt[c - 1];
    cnt[0] = 0;
    st = la_sparse_alloc(out, nrow, ncol, t->n);
  }
  for (int r = 0; !st && r < nrow; r++) mark[r] = -1;
  int nz = 0;
  for (int c = 0; !st && c < ncol; c++) {
    int nr = 0;
    out->p[c] = nz;
    for (int q = cnt[c]; q < cnt[c + 1]; q++) {
      int k = order[q], r = t->i[k];
      if (mark[r] != c) { mark[r] = c; acc[r] = 0; amag[r] = 0; rows[nr++] = r; }
      acc[r] += t->x[k];
      amag[r] += t->mag[k];
    }
    for (int a = 1; a < nr; a++)                  /* insertion sort: columns are short */
      for (int b = a; b > 0 && rows[b - 1] > rows[b]; b--) { int s = rows[b]; rows[b] = rows[b - 1]; rows[b - 1] = s; }
    for (int a = 0; a < nr; a++) {
      int r = rows[a];
      if (!(fabs(acc[r]) > 256 * DBL_EPSILON * amag[r])) continue;
      out->i[nz] = r;
      out->x[nz++] = acc[r];
    }
  }
  if (!st) { out->p[ncol] = nz; out->nnz = nz; }
  scratch_free(acc, small);
  return st;
}

/* ---- the network's matrices ---------------------------------------------------- */

typedef struct hy {
  cup_netlist *nl;
  const nl_circuit *c;
  int np;
  int *pp;            /* path scratch */
  double *pc;
  nl_coo lap, k, h;      /* Lap (upper), K, and H's N part */
} hy;

static int port_nodes(const hy *y, int q, int *a, int *b) {
  const nl_elem *el = &y->c->elem[y->nl->port[q].elem];
  *a = el->a;
  *b = el->b;
  return 0;
}

/* Resistor e: Lap, Z_V = A_R G T_R^T into K, and -T_R G T_R^T into H. */
static int add_resistor(hy *y, const nl_elem *el) {
  cup_netlist *nl = y->nl;
  double g = 1 / el->value;
  int sa = nl->snode[el->a], sb = nl->snode[el->b], st = CUP_OK;
  int len = nl_path(nl, el->a, el->b, y->pp, y->pc);
  if (sa != sb) {
    if (sa >= 0) st = nl_coo_add(&y->lap, sa, sa, g, g);
    if (!st && sb >= 0) st = nl_coo_add(&y->lap, sb, sb, g, g);
    if (!st && sa >= 0 && sb >= 0) st = nl_coo_add(&y->lap, sa < sb ? sa : sb, sa < sb ? sb : sa, -g, g);
    for (int k = 0; k < len && !st; k++) {
      if (sa >= 0) st = nl_coo_add(&y->k, sa, y->pp[k], g * y->pc[k], 0);
      if (!st && sb >= 0) st = nl_coo_add(&y->k, sb, y->pp[k], -g * y->pc[k], 0);
    }
  }
  for (int k1 = 0; k1 < len && !st; k1++)
    for (int k2 = 0; k2 < len && !st; k2++)
      st = nl_coo_add(&y->h, y->pp[k1], y->pp[k2], -g * y->pc[k1] * y->pc[k2], g);
  return st;
}

/* Current port q: A_I into K, -T_I and T_I^T into H. */
static int add_current_port(hy *y, int q) {
  cup_netlist *nl = y->nl;
  int a, b;
  port_nodes(y, q, &a, &b);
  int sa = nl->snode[a], sb = nl->snode[b], st = CUP_OK;
  if (sa != sb) {
    if (sa >= 0) st = nl_coo_add(&y->k, sa, q, 1, 0);
    if (!st && sb >= 0) st = nl_coo_add(&y->k, sb, q, -1, 0);
  }
  int len = nl_path(nl, a, b, y->pp, y->pc);
  for (int k = 0; k < len && !st; k++) {
    st = nl_coo_add(&y->h, y->pp[k], q, -y->pc[k], 1);
    if (!st) st = nl_coo_add(&y->h, q, y->pp[k], y->pc[k], 1);
  }
  return st;
}

static cholmod_sparse *to_cholmod(cup_netlist *nl, const nl_coo *t, int nrow, int ncol, int stype) {
  cholmod_triplet *T = cholmod_allocate_triplet((size_t)nrow, (size_t)ncol, (size_t)t->n + 1, stype,
                                                CHOLMOD_REAL, nl->cm);
  if (!T) return NULL;
  if (t->n) {                                     /* no triplets: t's arrays are NULL */
    memcpy(T->i, t->i, sizeof(int) * (size_t)t->n);
    memcpy(T->j, t->j, sizeof(int) * (size_t)t->n);
    memcpy(T->x, t->x, sizeof(double) * (size_t)t->n);
  }
  T->nnz = (size_t)t->n;
  cholmod_sparse *A = cholmod_triplet_to_sparse(T, (size_t)t->n + 1, nl->cm);
  cholmod_free_triplet(&T, nl->cm);
  return A;
}

static cholmod_sparse *abs_copy(cup_netlist *nl, cholmod_sparse *A) {
  cholmod_sparse *B = cholmod_copy_sparse(A, nl->cm);
  if (!B) return NULL;
  double *x = B->x;
  const int *p = B->p;
  for (int k = 0; k < p[B->ncol]; k++) x[k] = fabs(x[k]);
  return B;
}

/* X^T X (and |X|^T |X|) with J's signs, into the triplets of H. */
static int add_xtx(hy *y) {
  cup_netlist *nl = y->nl;
  cholmod_common *cm = nl->cm;
  cholmod_sparse *Lap = to_cholmod(nl, &y->lap, nl->ns, nl->ns, 1);
  nl->K = Lap ? to_cholmod(nl, &y->k, nl->ns, y->np, 0) : NULL;
  if (!Lap || !nl->K) { cholmod_free_sparse(&Lap, cm); return CUP_ERR_NOMEM; }
  cm->final_ll = 1;
  nl->Lf = cholmod_analyze(Lap, cm);
  int ok = nl->Lf && cholmod_factorize(Lap, nl->Lf, cm) && cm->status == CHOLMOD_OK;
  cholmod_free_sparse(&Lap, cm);
  if (!ok) return cm->status == CHOLMOD_OUT_OF_MEMORY ? CUP_ERR_NOMEM : CUP_ERR_LINALG;
  cholmod_sparse *Y = cholmod_spsolve(CHOLMOD_P, nl->Lf, nl->K, cm);
  cholmod_sparse *X = Y ? cholmod_spsolve(CHOLMOD_L, nl->Lf, Y, cm) : NULL;
  cholmod_sparse *Xa = X ? abs_copy(nl, X) : NULL;
  cholmod_sparse *Xt = Xa ? cholmod_transpose(X, 1, cm) : NULL, *Xat = Xt ? cholmod_transpose(Xa, 1, cm) : NULL;
  cholmod_sparse *XtX = Xat ? cholmod_ssmult(Xt, X, 0, 1, 1, cm) : NULL;
  cholmod_sparse *XatXa = XtX ? cholmod_ssmult(Xat, Xa, 0, 1, 1, cm) : NULL;
  int st = XatXa ? CUP_OK : cm->status == CHOLMOD_OUT_OF_MEMORY ? CUP_ERR_NOMEM : CUP_ERR_LINALG;
  for (int j = 0; !st && j < y->np; j++) {
    const int *p = XtX->p, *i = XtX->i, *pa = XatXa->p, *ia = XatXa->i;
    const double *x = XtX->x, *xa = XatXa->x;
    /* same pattern (|X| has X's), so the magnitude is read alongside */
    for (int k = p[j], ka = pa[j]; k < p[j + 1] && !st; k++) {
      while (ka < pa[j + 1] && ia[ka] < i[k]) ka++;
      double mag = ka < pa[j + 1] && ia[ka] == i[k] ? xa[ka] : fabs(x[k]);
      st = nl_coo_add(&y->h, i[k], j, i[k] < nl->nv ? x[k] : -x[k], mag);
    }
  }
  cholmod_free_sparse(&Y, cm); cholmod_free_sparse(&X, cm); cholmod_free_sparse(&Xa, cm);
  cholmod_free_sparse(&Xt, cm); cholmod_free_sparse(&Xat, cm);
  cholmod_free_sparse(&XtX, cm); cholmod_free_sparse(&XatXa, cm);
  return st;
}

int nl_hybrid(cup_netlist *nl, const nl_circuit *c, char *errmsg) {
  hy y = {nl, c, nl->nv + nl->ni, NULL, NULL, {0}, {0}, {0}};
  int maxd = 0;
  for (int v = 0; v < c->nnodes; v++) maxd = nl->depth[v] > maxd ? nl->depth[v] : maxd;
  /* the path scratch, pc then pp, in one block: on the stack for a shallow forest */
  double small[128];
  size_t np = 2 * (size_t)maxd + 2;
  y.pc = scratch_take(small, sizeof small, (sizeof(double) + sizeof(int)) * np, 0);
  y.pp = y.pc ? (int *)(y.pc + np) : NULL;
  int st = y.pc ? CUP_OK : CUP_ERR_NOMEM;
  if (!st && nl->ns > 0) {                      /* (the supernodes' Laplacian alone needs CHOLMOD: add_xtx) */
    if (!(nl->cm = malloc(sizeof *nl->cm))) st = CUP_ERR_NOMEM;
    else if (la_cholmod_start(nl->cm) != CUP_OK) { free(nl->cm); nl->cm = NULL; st = CUP_ERR_LINALG; }
  }
  for (int e = 0; e < c->nelem && !st; e++)
    if (c->elem[e].kind == NL_R && c->elem[e].a != c->elem[e].b) st = add_resistor(&y, &c->elem[e]);
  for (int q = nl->nv; q < y.np && !st; q++) st = add_current_port(&y, q);
  if (!st && nl->ns > 0) st = add_xtx(&y);
  if (!st) {                                     /* fixed diodes: no voltage-port rows or columns */
    int w = 0;
    for (int k = 0; k < y.h.n; k++) {
      int i = y.h.i[k], j = y.h.j[k];
      int zero = i < nl->nv && j < nl->nv &&
                 ((nl->port[i].var == NL_VAR_Z) || (nl->port[j].var == NL_VAR_Z));
      if (zero) continue;
      y.h.i[w] = i; y.h.j[w] = j; y.h.x[w] = y.h.x[k]; y.h.mag[w++] = y.h.mag[k];
    }
    y.h.n = w;
    st = nl_coo_to_csc(&y.h, y.np, y.np, &nl->H);
  }
  scratch_free(y.pc, small);
  nl_coo_free(&y.lap); nl_coo_free(&y.k); nl_coo_free(&y.h);
  if (st == CUP_ERR_NOMEM) return nl_fail(c, -1, errmsg, st, "out of memory while formulating the circuit");
  if (st) return nl_fail(c, -1, errmsg, st, "the resistor network could not be factored (CHOLMOD status %d)",
                         nl->cm ? nl->cm->status : CHOLMOD_INVALID);
  return CUP_OK;
}

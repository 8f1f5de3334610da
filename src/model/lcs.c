#define _POSIX_C_SOURCE 200809L
/* lcs — linear complementarity systems x' = A x + B zeta + E u,
 * 0 <= zeta _|_ C x + G u + F >= 0 (paper, Sec. 7), as a sweeping process
 * in the P-metric: P B = C^T makes B zeta a P-normal to K(t). */
#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include "catchup.h"
#include "lcs_impl.h"
#include "set/polyset_impl.h"
#include "util/block.h"

static int present(const cup_csc *c) { return c->ncol > 0 && c->colptr; }

static int copy_opt(la_sparse *dst, int *has, const cup_csc *src, const char *name,
                    int nrow, int ncol, char *errmsg) {
  *has = present(src);
  if (!*has) { memset(dst, 0, sizeof *dst); return CUP_OK; }
  return la_sparse_copy(dst, src, name, nrow, ncol, errmsg);
}

/* P B = C^T, compared column by column of B: (P b_j) against row j of C,
 * on the entries either can have (a netlist's LCS has 10^4 columns: a
 * dense sweep per column would be quadratic). The message names the
 * largest mismatch (the first, by column then row, among equal ones). */
static int check_pb(const cup_polyset *K, const la_sparse *B, double tol, char *errmsg) {
  int n = K->n, m = K->m;
  /* pb, ct, rows and seen in one zeroed block, on the stack for a small
   * LCS (a switched run makes one a configuration: four callocs and frees were) */
  size_t N = (size_t)n + 1, need = (N * (2 * sizeof(double) + sizeof(int) + 1) + sizeof(double) - 1) / sizeof(double);
  double small[128], *pb = scratch_take(small, sizeof small, sizeof(double) * need, 1);
  if (!pb) return fail_fmt(errmsg, CUP_ERR_NOMEM, "LCS: out of memory");
  double *ct = pb + N;
  int *rows = (int *)(ct + N);
  unsigned char *seen = (unsigned char *)(rows + N);
  double worst = 0, scale = 0, pbv = 0, ctv = 0;
  int wi = -1, wj = -1;
  for (int j = 0; j < m; j++) {
    int nr = 0;
#define TOUCH(r) do { if (!seen[r]) { seen[r] = 1; rows[nr++] = (r); } } while (0)
    for (int k = B->p[j]; k < B->p[j + 1]; k++) {          /* P b_j */
      int i = B->i[k];
      if (K->pkind == CUP_METRIC_SPARSE) {
        for (int q = K->Pfull.p[i]; q < K->Pfull.p[i + 1]; q++) {
          TOUCH(K->Pfull.i[q]);
          pb[K->Pfull.i[q]] += K->Pfull.x[q] * B->x[k];
        }
      } else {
        TOUCH(i);
        pb[i] += (K->pkind == CUP_METRIC_DIAGONAL ? K->pd[i] : 1) * B->x[k];
      }
    }
    for (int k = K->Ct.p[j]; k < K->Ct.p[j + 1]; k++) {
      TOUCH(K->Ct.i[k]);
      ct[K->Ct.i[k]] = K->Ct.x[k];
    }
#undef TOUCH
    for (int a = 1; a < nr; a++)                             /* rows in order: short lists */
      for (int b = a; b > 0 && rows[b - 1] > rows[b]; b--) { int t = rows[b]; rows[b] = rows[b - 1]; rows[b - 1] = t; }
    for (int a = 0; a < nr; a++) {
      int i = rows[a];
      scale = fmax(scale, fmax(fabs(pb[i]), fabs(ct[i])));
      double d = fabs(pb[i] - ct[i]);
      if (d > worst || isnan(d)) { worst = d; wi = i; wj = j; pbv = pb[i]; ctv = ct[i]; }
      pb[i] = ct[i] = 0;
      seen[i] = 0;
    }
  }
  scratch_free(pb, small);
  if (wi >= 0 && !(worst <= tol * scale))
    return fail_fmt(errmsg, CUP_ERR_PB_CT,
                    "P B differs from C^T: largest mismatch at (%d,%d): (P B) = %.17g but C^T = %.17g "
                    "(relative %.3g > tolerance %.3g)", wi, wj, pbv, ctv, worst / (scale > 0 ? scale : 1), tol);
  return CUP_OK;
}

static int has_nonzero(const cup_csc *c) {
  if (!present(c)) return 0;
  for (int k = 0; k < c->colptr[c->ncol]; k++)
    if (c->values && c->values[k] != 0) return 1;
  return 0;
}

/* All principal minors positive (m small: 2^m determinants by LU). */
static int p_matrix(const double *D, int m, double *work, int *piv) {
  for (unsigned mask = 1; mask < (1u << m); mask++) {
    int k = 0, idx[16];
    for (int i = 0; i < m; i++) if (mask >> i & 1u) idx[k++] = i;
    for (int a = 0; a < k; a++)
      for (int b = 0; b < k; b++) work[a + b * k] = D[idx[a] + idx[b] * m];
    if (la_dense_lu(work, k, piv)) return 0;
    double det = 1;
    unsigned char seen[16] = {0};
    for (int a = 0; a < k; a++) {
      det *= work[a + a * k];
      int len = 0;                                 /* the row permutation's sign: its cycles */
      for (int b = a; !seen[b]; b = piv[b]) { seen[b] = 1; len++; }
      if (len && len % 2 == 0) det = -det;
    }
    if (!(det > 0)) return 0;
  }
  return 1;
}

/* D must make each step's LCP solvable with a unique answer: positive
 * semidefinite (x^T D x >= 0, checked on (D + D^T)/2 by its eigenvalues,
 * to rounding) or, for a few rows, a P-matrix. */
static int check_D(const la_sparse *Ds, char *errmsg) {
  int m = Ds->nrow;
  if (m > 1024) return CUP_OK;               /* too big to check densely: the LCP solver will tell */
  /* D, S, the eigenvalues and their workspace in one zeroed block (on the stack for a small D) */
  size_t need = 2 * (size_t)m * m + 3 * (size_t)m + 1;
  double small[256], *D = scratch_take(small, sizeof small, sizeof(double) * need, 1);
  double *S = D ? D + (size_t)m * m : NULL;
  double *ev = S ? S + (size_t)m * m : NULL;
  int st = D ? CUP_OK : fail_fmt(errmsg, CUP_ERR_NOMEM, "LCS: out of memory");
  double lmin = 0, norm = 0;
  if (!st) {
    for (int j = 0; j < m; j++)
      for (int k = Ds->p[j]; k < Ds->p[j + 1]; k++) D[Ds->i[k] + (size_t)j * m] = Ds->x[k];
    for (int j = 0; j < m; j++)
      for (int i = 0; i < m; i++) {
        S[i + (size_t)j * m] = 0.5 * (D[i + (size_t)j * m] + D[j + (size_t)i * m]);
        norm = la_max(norm, fabs(D[i + (size_t)j * m]));
      }
    if (la_dense_symm_eig(S, m, ev, ev + m)) st = fail_fmt(errmsg, CUP_ERR_LINALG, "LCS: eigenvalues of D failed");
    for (int i = 0; !st && i < m; i++) lmin = la_min(lmin, ev[i]);
  }
  if (!st && lmin < -1e-12 * m * norm) {
    double *work = malloc(sizeof(double) * 16 * 16);
    int piv[16];
    int ok = m <= 12 && work && p_matrix(D, m, work, piv);
    free(work);
    if (!ok)
      st = fail_fmt(errmsg, CUP_ERR_ARG, "D is not positive semidefinite ((D + D^T)/2 has the eigenvalue %.3g) "
                    "and not a P-matrix: the LCP of a step may have no or several solutions", lmin);
  }
  scratch_free(D, small);                        /* (S and ev in its block) */
  return st;
}

static int copy_names(cup_lcs *L, const char *const *names, int lend, char *errmsg) {
  if (!names) return CUP_OK;
  L->row_names = (char **)(L->F + L->m + 1);       /* (in L's block: create) */
  for (int i = 0; lend && i < L->m; i++) lend = names[i] != NULL;   /* (a missing one: "?", copied) */
  L->names_lent = lend;
  for (int i = 0; i < L->m; i++)
    if (!(L->row_names[i] = lend ? (char *)names[i] : strdup(names[i] ? names[i] : "?")))
      return fail_fmt(errmsg, CUP_ERR_NOMEM, "LCS: out of memory");
  return CUP_OK;
}

void lcs_rows_text(const cup_lcs *L, const int *rows, int k, char *buf, unsigned long size) {
  size_t len = (size_t)snprintf(buf, size, "%s", k == 1 ? "row" : "rows");
  for (int a = 0; a < k && len < size; a++) {
    if (len > size / 2) { snprintf(buf + len, size - len, ", ..."); return; }
    if (L->row_names)
      len += (size_t)snprintf(buf + len, size - len, "%s%s", a ? ", " : " ", L->row_names[rows[a]]);
    else
      len += (size_t)snprintf(buf + len, size - len, "%s%d", a ? ", " : " ", rows[a]);
  }
}

int lcs_needs_reciprocal(const char *scheme, const char *why, char *errmsg) {
  return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED, "the %s scheme needs P B = C^T (a reciprocal network: %s, and B "
                  "is not P^-1 C^T here: controlled sources drive the diodes' rows): use the theta scheme",
                  scheme, why);
}

static int create(cup_lcs **out, const cup_lcs_desc *d, int lend, char *errmsg);

int cup_lcs_create(cup_lcs **out, const cup_lcs_desc *d, char *errmsg) { return create(out, d, 0, errmsg); }
int lcs_create_lent(cup_lcs **out, const cup_lcs_desc *d, char *errmsg) { return create(out, d, 1, errmsg); }

static int create(cup_lcs **out, const cup_lcs_desc *d, int lend, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "LCS: output pointer is NULL");
  *out = NULL;
  if (!d) return fail_fmt(errmsg, CUP_ERR_ARG, "LCS: description is NULL");
  if (d->n < 1 || d->m < 0 || d->p < 0)
    return fail_fmt(errmsg, CUP_ERR_DIM, "LCS: n = %d, m = %d, p = %d; need n >= 1, m >= 0, p >= 0",
                    d->n, d->m, d->p);
  if (!(d->pb_tol >= 0)) return fail_fmt(errmsg, CUP_ERR_ARG, "LCS: pb_tol = %g must be >= 0", d->pb_tol);
  /* F and the row names' array in L's block (a switched run makes an LCS a
   * configuration: two callocs and two frees less) */
  cup_lcs *L = calloc(1, sizeof *L + ((size_t)d->m + 1) * (sizeof(double) + sizeof(char *)));
  if (!L) return fail_fmt(errmsg, CUP_ERR_NOMEM, "LCS: out of memory");
  L->F = (double *)(L + 1);
  L->n = d->n; L->m = d->m; L->p = d->p;
  int st = CUP_OK;
  if (d->C.nrow != d->m || d->C.ncol != d->n)
    st = fail_fmt(errmsg, CUP_ERR_DIM, "C is %d x %d, expected m x n = %d x %d", d->C.nrow, d->C.ncol, d->m, d->n);
  if (!st) st = copy_opt(&L->A, &L->has_A, &d->A, "A", d->n, d->n, errmsg);
  if (!st) st = copy_opt(&L->E, &L->has_E, &d->E, "E", d->n, d->p, errmsg);
  if (!st) st = copy_opt(&L->G, &L->has_G, &d->G, "G", d->m, d->p, errmsg);
  if (!st && (L->has_E || L->has_G) && d->p == 0)
    st = fail_fmt(errmsg, CUP_ERR_DIM, "E or G given but the input dimension p is 0");
  if (!st) {
    for (int i = 0; !st && d->F && i < d->m; i++) {
      if (!isfinite(d->F[i])) st = fail_fmt(errmsg, CUP_ERR_NONFINITE, "F[%d] is %g", i, d->F[i]);
      L->F[i] = d->F[i];
    }
  }
  if (!st) st = cup_polyset_create(&L->K, &d->C, L->F, &d->P, errmsg);
  if (!st) st = copy_names(L, d->row_names, lend, errmsg);
  L->has_D = !st && has_nonzero(&d->D);
  L->keep_B = !st && d->keep_B && d->m > 0;
  if (L->keep_B && !L->has_D) {              /* D = 0, B as given: stored as a zero D */
    L->has_D = 1;
    if (!present(&d->B)) st = fail_fmt(errmsg, CUP_ERR_ARG, "keep_B needs B");
    if (!st) st = la_sparse_copy(&L->B, &d->B, "B", d->n, d->m, errmsg);
    if (!st) st = la_sparse_alloc(&L->D, d->m, d->m, 0) ? fail_fmt(errmsg, CUP_ERR_NOMEM, "LCS: out of memory")
                                                          : CUP_OK;
  } else if (L->has_D) {                     /* not a sweeping process: keep B and D as given */
    if (!present(&d->B)) st = fail_fmt(errmsg, CUP_ERR_ARG, "D != 0 needs B (it is not P^-1 C^T then)");
    if (!st) st = la_sparse_copy(&L->B, &d->B, "B", d->n, d->m, errmsg);
    if (!st) st = la_sparse_copy(&L->D, &d->D, "D", d->m, d->m, errmsg);
    if (!st && !L->keep_B) st = check_D(&L->D, errmsg);   /* keep_B: an active network, see lcs.h */
  } else if (!st && present(&d->B)) {
    la_sparse B;
    st = la_sparse_copy(&B, &d->B, "B", d->n, d->m, errmsg);
    if (!st) {
      st = check_pb(L->K, &B, d->pb_tol > 0 ? d->pb_tol : 1e-12, errmsg);
      la_sparse_free(&B);
    }
  }
  if (st) { cup_lcs_free(&L); return st; }
  L->fixed = 1;
  for (int k = 0; L->has_G && k < L->G.nnz; k++)
    if (L->G.x[k] != 0) L->fixed = 0;
  *out = L;
  return CUP_OK;
}

void cup_lcs_free(cup_lcs **Lp) {
  if (!Lp || !*Lp) return;
  cup_lcs *L = *Lp;
  la_sparse_free(&L->A);
  la_sparse_free(&L->E);
  la_sparse_free(&L->G);
  cup_polyset_free(&L->K);
  la_sparse_free(&L->B);
  la_sparse_free(&L->D);
  for (int i = 0; L->row_names && !L->names_lent && i < L->m; i++) free(L->row_names[i]);
  free(L);                                   /* (F and row_names in its block) */
  *Lp = NULL;
}

int cup_lcs_dim(const cup_lcs *L) { return L ? L->n : 0; }
int cup_lcs_rows(const cup_lcs *L) { return L ? L->m : 0; }
int cup_lcs_inputs(const cup_lcs *L) { return L ? L->p : 0; }
const cup_polyset *cup_lcs_polyset(const cup_lcs *L) { return L ? L->K : NULL; }
int cup_lcs_fixed_set(const cup_lcs *L) { return L ? L->fixed : 1; }
int cup_lcs_has_D(const cup_lcs *L) { return L ? L->has_D : 0; }

/* A dense row-major r x c matrix as a CSC view into caller storage. */
static cup_csc dense_view(int r, int c, const double *a, int *cp, int *ri, double *vx) {
  int q = 0;
  cp[0] = 0;
  for (int j = 0; j < c; j++) {
    for (int i = 0; i < r; i++)
      if (a[i * c + j] != 0) { ri[q] = i; vx[q++] = a[i * c + j]; }
    cp[j + 1] = q;
  }
  return (cup_csc){r, c, cp, ri, vx};
}

int cup_lcs_circuit(cup_lcs **out, const cup_circuit *c, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "circuit: output pointer is NULL");
  *out = NULL;
  if (!c) return fail_fmt(errmsg, CUP_ERR_ARG, "circuit: parameters are NULL");
  const double v[6] = {c->R1, c->R2, c->R3, c->L2, c->L3, c->C4};
  const char *names[6] = {"R1", "R2", "R3", "L2", "L3", "C4"};
  for (int k = 0; k < 6; k++) {
    if (!isfinite(v[k])) return fail_fmt(errmsg, CUP_ERR_NONFINITE, "circuit: %s = %g", names[k], v[k]);
    if (k < 3 && v[k] < 0) return fail_fmt(errmsg, CUP_ERR_ARG, "circuit: %s = %g must be >= 0", names[k], v[k]);
    if (k >= 3 && !(v[k] > 0)) return fail_fmt(errmsg, CUP_ERR_ARG, "circuit: %s = %g must be > 0", names[k], v[k]);
  }
  if (!isfinite(c->G[0]) || !isfinite(c->G[1]))
    return fail_fmt(errmsg, CUP_ERR_NONFINITE, "circuit: G = (%g, %g)", c->G[0], c->G[1]);
  double R1 = c->R1, R2 = c->R2, R3 = c->R3, L2 = c->L2, L3 = c->L3, C4 = c->C4;
  /* the paper's matrices (Sec. 7, example) */
  const double A[9] = {0, 1, 0,
                       -1 / (L3 * C4), -(R1 + R3) / L3, R1 / L3,
                       0, R1 / L2, -(R1 + R2) / L2};
  const double B[6] = {0, 0, 1 / L3, 1 / L3, -1 / L2, 0};
  const double C[6] = {0, 1, -1, 0, 1, 0};
  const double E[3] = {0, 1 / L3, 1 / L2};
  const double G[2] = {c->G[0], c->G[1]};
  const double P[3] = {1, L3, L2};
  int pa[4], ia[9], pb[3], ib[6], pc[4], ic[6], pe[2], ie[3], pg[2], ig[2];
  double xa[9], xb[6], xc[6], xe[3], xg[2];
  cup_lcs_desc d = {0};
  d.n = 3; d.m = 2; d.p = 1;
  d.A = dense_view(3, 3, A, pa, ia, xa);
  d.B = dense_view(3, 2, B, pb, ib, xb);
  d.C = dense_view(2, 3, C, pc, ic, xc);
  d.E = dense_view(3, 1, E, pe, ie, xe);
  d.G = dense_view(2, 1, G, pg, ig, xg);
  d.P = (cup_metric){CUP_METRIC_DIAGONAL, P, {0}, 0};
  return cup_lcs_create(out, &d, errmsg);
}

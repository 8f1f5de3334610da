/* netlist_reduce — a switch configuration's netlist reduced (netlist_switch.c
 * forms it): the diode rows first, in the written order; the constraint
 * rows a switch makes (a loop of capacitors closed, a cut of inductors
 * left open) eliminated by the P-orthogonal projector
 *     Pi = I - P^-1 C_Q^T (C_Q P^-1 C_Q^T)^-1 C_Q,
 * which is also the jump into the configuration, their multipliers
 * recovered from the state, and the LCS formed over the rest. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "catchup/netlist.h"
#include "lcs_impl.h"
#include "netlist_impl.h"

int nl_switch_nomem(const nl_circuit *c, char *errmsg) {
  return nl_fail(c, -1, errmsg, CUP_ERR_NOMEM, "out of memory while forming a switch configuration");
}

/* Dense m x n (column-major) into CSC without its zeros: entries at or
 * below 256 eps times their magnitude bound mag (same layout; NULL: exact
 * zeros only) cancelled to rounding. */
static int to_csc(const double *a, const double *mag, int m, int n, la_sparse *out) {
  int nnz = 0;
  for (size_t k = 0; k < (size_t)m * (size_t)n; k++) nnz += fabs(a[k]) > (mag ? 256 * 2.2e-16 * mag[k] : 0);
  if (la_sparse_alloc(out, m, n, nnz)) return CUP_ERR_NOMEM;
  int q = 0;
  for (int j = 0; j < n; j++) {
    out->p[j] = q;
    for (int i = 0; i < m; i++) {
      double v = a[i + (size_t)j * m];
      if (fabs(v) > (mag ? 256 * 2.2e-16 * mag[i + (size_t)j * m] : 0)) { out->i[q] = i; out->x[q++] = v; }
    }
  }
  out->p[n] = q;
  out->nnz = q;
  return CUP_OK;
}

/* out (m x n) = a (m x k) b (k x n), and |a| |b| into mag if not NULL. */
static void mul(const double *a, const double *b, int m, int k, int n, double *out, double *mag) {
  for (int j = 0; j < n; j++)
    for (int i = 0; i < m; i++) {
      double s = 0, t = 0;
      for (int l = 0; l < k; l++) {
        double v = a[i + (size_t)l * m] * b[l + (size_t)j * k];
        s += v; t += fabs(v);
      }
      out[i + (size_t)j * m] = s;
      if (mag) mag[i + (size_t)j * m] = t;
    }
}

/* Columns (or rows) `pick` of a dense matrix: out = a(:, pick) or a(pick, :). */
static void cols(const double *a, int nrow, const int *pick, int k, double *out) {
  for (int j = 0; j < k; j++) memcpy(out + (size_t)j * nrow, a + (size_t)pick[j] * nrow, sizeof(double) * (size_t)nrow);
}
static void rows(const double *a, int nrow, int ncol, const int *pick, int k, double *out) {
  for (int j = 0; j < ncol; j++)
    for (int i = 0; i < k; i++) out[i + (size_t)j * k] = a[pick[i] + (size_t)j * nrow];
}

typedef struct red {
  int n, p, m, mq, nq;
  int *dr, *qr;            /* the diode rows (by diode index), the constraint rows */
  double *Pinv, *Cq, *T, *Pi, *Pim;   /* n x n, nq x n, n x nq, n x n, |Pi| */
  double *S;               /* nq x nq: C_Q P^-1 C_Q^T, factored */
  int *piv;
  double *w;
} red;

static void red_free(red *r) {
  free(r->dr); free(r->Pinv); free(r->Cq); free(r->T); free(r->Pi); free(r->Pim);   /* (qr in dr's block) */
  free(r->S); free(r->piv); free(r->w);
}

/* Which derived row is which: diode rows in the written order, constraint
 * rows after; the constraints checked (no source, no diode in them). */
static int classify(cup_netlist *sub, const nl_circuit *c, const nl_circuit *d, red *r, char *errmsg) {
  const nl_raw *R = sub->raw;
  r->n = sub->n; r->p = sub->p; r->mq = sub->m;
  r->dr = malloc(sizeof(int) * 2 * ((size_t)r->mq + 1));   /* qr in its block */
  r->qr = r->dr ? r->dr + r->mq + 1 : NULL;
  sub->zrow = malloc(sizeof(int) * ((size_t)r->mq + 1));
  if (!r->dr || !sub->zrow) return nl_switch_nomem(c, errmsg);
  for (int e = 0, k = 0; e < d->nelem; e++) {
    if (d->elem[e].kind != NL_D) continue;
    int row = sub->evar[e];
    if (d->elem[e].eq == NL_EQ_NONE) { sub->zrow[row] = k; r->dr[k++] = row; r->m = k; }
    else { sub->zrow[row] = -1 - r->nq; r->qr[r->nq++] = row; }
  }
  for (int q = 0; q < r->nq; q++) {
    int row = r->qr[q], e = -1;
    for (int f = 0; f < d->nelem && e < 0; f++)
      if (d->elem[f].kind == NL_D && sub->evar[f] == row) e = f;
    int src = 0, dio = 0;
    for (int j = 0; j < r->p; j++) src |= R->G[row + (size_t)j * r->mq] != 0;
    for (int j = 0; j < r->mq; j++) dio |= R->D[row + (size_t)j * r->mq] != 0 || R->D[j + (size_t)row * r->mq] != 0;
    if (src || dio)
      return nl_fail(d, e, errmsg, CUP_ERR_UNSUPPORTED, "%s %s: a jump through %s is not supported; put a "
                     "resistor %s", d->elem[e].eq == NL_EQ_LOOP ? "closed, the switch puts capacitors in a loop with"
                                                               : "open, the switch leaves inductors in a cutset with",
                     src ? "a source" : "a diode", src ? "it" : "it",
                     d->elem[e].eq == NL_EQ_LOOP ? "in series with the switch" : "across the switch");
  }
  return CUP_OK;
}

/* Pi = I - P^-1 C_Q^T S^-1 C_Q and T = P^-1 C_Q^T S^-1. */
static int projector(cup_netlist *sub, const nl_circuit *d, red *r, char *errmsg) {
  const nl_raw *R = sub->raw;
  int n = r->n, nq = r->nq;
  r->Pinv = malloc(sizeof(double) * (size_t)n * n);
  r->Cq = malloc(sizeof(double) * (size_t)nq * n);
  r->T = malloc(sizeof(double) * (size_t)n * nq);
  r->Pi = malloc(sizeof(double) * (size_t)n * n);
  r->Pim = malloc(sizeof(double) * (size_t)n * n);
  r->S = malloc(sizeof(double) * (size_t)nq * nq);
  r->piv = malloc(sizeof(int) * ((size_t)n + 1));
  r->w = malloc(sizeof(double) * ((size_t)n + nq + 1) * 2);
  double *lu = malloc(sizeof(double) * (size_t)n * n);
  if (!r->Pinv || !r->Cq || !r->T || !r->Pi || !r->Pim || !r->S || !r->piv || !r->w || !lu) {
    free(lu);
    return nl_switch_nomem(d, errmsg);
  }
  memcpy(lu, R->P, sizeof(double) * (size_t)n * n);
  int st = la_dense_lu(lu, n, r->piv);
  for (int j = 0; !st && j < n; j++) {
    double *col = r->Pinv + (size_t)j * n;
    la_zero(col, n);
    col[j] = 1;
    la_dense_lu_solve(lu, n, r->piv, col, r->w);
  }
  free(lu);
  if (st) return nl_fail(d, -1, errmsg, CUP_ERR_LINALG, "the energy metric is singular");
  rows(R->C, r->mq, n, r->qr, nq, r->Cq);
  double *PCt = r->Pim;                            /* scratch: P^-1 C_Q^T, n x nq */
  for (int j = 0; j < nq; j++)
    for (int i = 0; i < n; i++) {
      double s = 0;
      for (int l = 0; l < n; l++) s += r->Pinv[i + (size_t)l * n] * r->Cq[j + (size_t)l * nq];
      PCt[i + (size_t)j * n] = s;
    }
  mul(r->Cq, PCt, nq, n, nq, r->S, NULL);
  if (la_dense_lu(r->S, nq, r->piv)) {
    int e = -1;
    for (int f = 0; f < d->nelem && e < 0; f++)
      if (d->elem[f].kind == NL_D && d->elem[f].eq != NL_EQ_NONE) e = f;
    return nl_fail(d, e, errmsg, CUP_ERR_UNSUPPORTED, "the switches' constraints on the state are redundant "
                   "(two switches close the same loop of capacitors, or open the same cut of inductors)");
  }
  for (int i = 0; i < n; i++) {                    /* T's rows: S^-T (P^-1 C_Q^T)^T's columns; S symmetric */
    for (int j = 0; j < nq; j++) r->w[j] = PCt[i + (size_t)j * n];
    la_dense_lu_solve(r->S, nq, r->piv, r->w, r->w + nq);
    for (int j = 0; j < nq; j++) r->T[i + (size_t)j * n] = r->w[j];
  }
  mul(r->T, r->Cq, n, nq, n, r->Pi, r->Pim);
  for (size_t k = 0; k < (size_t)n * n; k++) r->Pi[k] = -r->Pi[k];
  for (int j = 0; j < n; j++) { r->Pi[j + (size_t)j * n] += 1; r->Pim[j + (size_t)j * n] += 1; }
  return CUP_OK;
}

/* The multipliers Lam (x, u, zeta) = -S^-1 C_Q (A x + E u + B zeta), what
 * holds C_Q x' = 0 (signals: a loop's current, a cut's voltage). */
static int multipliers(cup_netlist *sub, red *r) {
  const nl_raw *R = sub->raw;
  int n = r->n, p = r->p, m = r->m, nq = r->nq, nv = n + p + m;
  sub->Lam = calloc((size_t)nq * nv + 1, sizeof(double));
  if (!sub->Lam) return CUP_ERR_NOMEM;
  for (int v = 0; v < nv; v++) {
    const double *col = v < n ? R->A + (size_t)v * n : v < n + p ? R->E + (size_t)(v - n) * n
                                                              : R->B + (size_t)r->dr[v - n - p] * n;
    for (int q = 0; q < nq; q++) {
      double s = 0;
      for (int l = 0; l < n; l++) s += r->Cq[q + (size_t)l * nq] * col[l];
      r->w[q] = -s;
    }
    la_dense_lu_solve(r->S, nq, r->piv, r->w, r->w + nq);
    for (int q = 0; q < nq; q++) sub->Lam[(size_t)q * nv + v] = r->w[q];
  }
  return CUP_OK;
}

static cup_csc view(const la_sparse *s) {
  return s->nnz || s->ncol ? (cup_csc){s->nrow, s->ncol, s->p, s->i, s->x} : (cup_csc){0, 0, NULL, NULL, NULL};
}

/* The configuration's LCS from its parts s (A, E, B, C, G, D over its
 * diode rows), F's room (m, zeroed), P sparse (Ps) or diagonal (pd): F = 1
 * on a diode that is inert in it. */
static int lcs_of(cup_netlist *sub, const la_sparse *const s[6], double *F, const la_sparse *Ps, const double *pd,
                  const nl_circuit *d, char *errmsg) {
  const nl_raw *R = sub->raw;
  int n = sub->n, p = sub->p, m = s[3]->nrow;
  int inert = 0, hasD = s[5]->nnz > 0;
  for (int i = 0; i < m; i++) {                  /* a row that nothing reaches: never conducts */
    int used = 0;
    for (int k = 0; k < s[3]->nnz && !used; k++) used = s[3]->i[k] == i;
    for (int k = 0; k < s[4]->nnz && !used; k++) used = s[4]->i[k] == i;
    for (int k = 0; k < s[5]->nnz && !used; k++) used = s[5]->i[k] == i;
    if (!used) { F[i] = 1; inert = 1; }
  }
  char lib[CUP_ERRMSG_LEN];                        /* (not cleared whole: 12 KB a configuration) */
  lib[0] = '\0';
  cup_lcs_desc q = {0};
  q.n = n; q.m = m; q.p = p;
  q.A = view(s[0]); q.E = view(s[1]); q.B = view(s[2]); q.C = view(s[3]); q.G = view(s[4]);
  if (hasD) q.D = view(s[5]);
  q.F = inert ? F : NULL;
  q.P = Ps ? (cup_metric){CUP_METRIC_SPARSE, NULL, view(Ps), 0} : (cup_metric){CUP_METRIC_DIAGONAL, pd, {0}, 0};
  q.row_names = (const char *const *)sub->row_name;
  q.keep_B = R->keep_B && !hasD;
  /* the row names: its elements' (the switched netlist's circuit's, or its own), freed after L: lent */
  int st = lcs_create_lent(&sub->L, &q, lib);
  if (st && R->keep_B) { q.keep_B = 1; st = lcs_create_lent(&sub->L, &q, lib); }
  if (st == CUP_ERR_NOMEM) return nl_switch_nomem(d, errmsg);
  return st ? nl_fail(d, -1, errmsg, st, "%s", lib) : CUP_OK;
}

/* No constraint row: the formulation's parts are the LCS (its diode rows
 * in the written order, P as formed), as the dense path below would give
 * them back (their CSC holds no zero, and that path drops exact zeros
 * alone), without the round trip through dense matrices. */
static int sparse_lcs(cup_netlist *sub, const nl_circuit *d, char *errmsg) {
  const nl_raw *R = sub->raw;
  int n = sub->n, dia = 1;
  const la_sparse *Pc = R->Pc.p ? &R->Pc : NULL;
  double small[256], *pd = scratch_take(small, sizeof small, sizeof(double) * ((size_t)n + 1 + (size_t)sub->m + 1), 0);
  double *F = pd ? pd + n + 1 : NULL;
  if (!pd) return nl_switch_nomem(d, errmsg);
  la_zero(F, sub->m + 1);
  for (int j = 0; j < n; j++) pd[j] = Pc ? 0 : R->pdiag[j];
  for (int j = 0; Pc && j < n; j++)                /* (its entries: no zero stored) */
    for (int k = Pc->p[j]; k < Pc->p[j + 1]; k++) {
      if (Pc->i[k] == j) pd[j] = Pc->x[k];
      else dia = 0;
    }
  const la_sparse *const six[6] = {&R->part[0], &R->part[4], &R->part[1], &R->part[2], &R->part[5], &R->part[3]};
  int st = lcs_of(sub, six, F, dia ? NULL : Pc, pd, d, errmsg);
  scratch_free(pd, small);
  return st;
}

/* The configuration's LCS: Pi A, Pi E, Pi B, C Pi on the diode rows (the
 * formulation's own matrices where there is no constraint), F = 1 on a
 * diode that is inert in it. */
static int reduced_lcs(cup_netlist *sub, const nl_circuit *d, red *r, char *errmsg) {
  const nl_raw *R = sub->raw;
  if (R->sparse) return sparse_lcs(sub, d, errmsg);
  int n = r->n, p = r->p, m = r->m, mq = r->mq, nq = r->nq;
  size_t big = (size_t)(n > m ? n : m) * (size_t)(n > p ? (n > m ? n : m) : (p > m ? p : m)) + 1;
  /* X, Y, M, |a| (with constraints) and F in one block, F zeroed */
  double *X = malloc(sizeof(double) * ((nq ? 4 : 3) * big + (size_t)m + 1));
  double *Y = X ? X + big : NULL, *M = X ? Y + big : NULL, *Mb = X && nq ? M + big : NULL;
  double *F = X ? (nq ? Mb : M) + big : NULL;
  if (F) la_zero(F, m + 1);
  la_sparse s[6] = {{0}};
  int st = X ? CUP_OK : CUP_ERR_NOMEM;
  /* A, E, B: Pi times the formulation's; C: its diode rows times Pi; D, G: its diode rows and columns */
  const double *src[3] = {R->A, R->E, NULL};
  int ncol[3] = {n, p, m};
  for (int t = 0; t < 3 && !st; t++) {
    const double *a = src[t];
    if (t == 2) { cols(R->B, n, r->dr, m, Y); a = Y; }
    if (nq) {
      mul(r->Pi, a, n, n, ncol[t], X, M);
      for (size_t k = 0; k < (size_t)n * ncol[t]; k++) Mb[k] = fabs(a[k]);
      mul(r->Pim, Mb, n, n, ncol[t], M, NULL);
      st = to_csc(X, M, n, ncol[t], &s[t]);
    } else {
      st = to_csc(a, NULL, n, ncol[t], &s[t]);
    }
  }
  if (!st) {
    rows(R->C, mq, n, r->dr, m, Y);
    if (nq) {
      mul(Y, r->Pi, m, n, n, X, NULL);
      for (size_t k = 0; k < (size_t)m * n; k++) Y[k] = fabs(Y[k]);
      mul(Y, r->Pim, m, n, n, M, NULL);
      st = to_csc(X, M, m, n, &s[3]);
    } else {
      st = to_csc(Y, NULL, m, n, &s[3]);
    }
  }
  if (!st) {
    rows(R->G, mq, p, r->dr, m, Y);
    st = to_csc(Y, NULL, m, p, &s[4]);
  }
  if (!st) {
    for (int j = 0; j < m; j++)
      for (int i = 0; i < m; i++) Y[i + (size_t)j * m] = R->D[r->dr[i] + (size_t)r->dr[j] * mq];
    st = to_csc(Y, NULL, m, m, &s[5]);
  }
  la_sparse Ps = {0};
  int dia = 1;
  for (int j = 0; j < n; j++)
    for (int i = 0; i < n; i++) dia &= i == j || R->P[i + (size_t)j * n] == 0;
  double *pd = !st ? malloc(sizeof(double) * ((size_t)n + 1)) : NULL;
  if (!st && !pd) st = CUP_ERR_NOMEM;
  for (int j = 0; !st && j < n; j++) pd[j] = R->P[j + (size_t)j * n];
  if (!st && !dia) st = to_csc(R->P, NULL, n, n, &Ps);
  const la_sparse *const six[6] = {&s[0], &s[1], &s[2], &s[3], &s[4], &s[5]};
  if (!st) st = lcs_of(sub, six, F, dia ? NULL : &Ps, pd, d, errmsg);
  else st = nl_switch_nomem(d, errmsg);
  free(pd);
  la_sparse_free(&Ps);
  free(X);                                         /* (Y, M, Mb and F in its block) */
  for (int t = 0; t < 6; t++) la_sparse_free(&s[t]);
  return st;
}

/* The rows renamed: the diodes' first, in the written order (the public
 * accessors see mr of them), the constraints' after. */
static int rename_rows(cup_netlist *sub, const red *r) {
  /* in place, through a copy (on the stack for a small circuit: two mallocs
   * and two frees less a switch configuration) */
  size_t mq = (size_t)r->mq;
  char *nsmall[64], **nm = scratch_take(nsmall, sizeof nsmall, sizeof(char *) * mq, 0);
  int fsmall[64], *fx = scratch_take(fsmall, sizeof fsmall, sizeof(int) * mq, 0);
  if (!nm || !fx) {
    scratch_free(nm, nsmall);
    scratch_free(fx, fsmall);
    return CUP_ERR_NOMEM;
  }
  for (int k = 0; k < r->m; k++) { nm[k] = sub->row_name[r->dr[k]]; fx[k] = sub->row_fixed[r->dr[k]]; }
  for (int k = 0; k < r->nq; k++) { nm[r->m + k] = sub->row_name[r->qr[k]]; fx[r->m + k] = sub->row_fixed[r->qr[k]]; }
  if (mq) {
    memcpy(sub->row_name, nm, sizeof(char *) * mq);
    memcpy(sub->row_fixed, fx, sizeof(int) * mq);
  }
  scratch_free(nm, nsmall);
  scratch_free(fx, fsmall);
  sub->mr = r->m;
  sub->nq = r->nq;
  return CUP_OK;
}

/* Reduced (netlist_impl.h): the steps above in turn. */
int nl_switch_reduce(cup_netlist *sub, const nl_circuit *c, const nl_circuit *d, double **Pi, char *errmsg) {
  red r = {0};
  int st = classify(sub, c, d, &r, errmsg);
  if (!st && r.nq) st = projector(sub, d, &r, errmsg);
  if (!st && r.nq && multipliers(sub, &r)) st = nl_switch_nomem(c, errmsg);
  if (!st) st = rename_rows(sub, &r) ? nl_switch_nomem(c, errmsg) : CUP_OK;
  if (!st) st = reduced_lcs(sub, d, &r, errmsg);
  if (!st && !r.nq) { free(sub->zrow); sub->zrow = NULL; }   /* diode rows as formulated */
  if (!st && r.nq) { *Pi = r.Pi; r.Pi = NULL; }
  red_free(&r);
  nl_raw_free(sub);                                /* (read by the steps above alone) */
  return st;
}

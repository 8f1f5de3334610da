/* netlist_ctl — what makes a circuit's network more than resistors:
 *
 * Controlled sources (E, F, G, H). Each is a port whose value (E, H: a
 * voltage; F, G: a current) is gain times a controlling quantity (E, G: a
 * node voltage difference; F, H: an element's current). The hybrid matrix
 * H is first formed with them as independent ports (netlist_hybrid.c);
 * every controlling quantity is then a row y = M_s s + M_z z over the other
 * ports' values s and the controlled ones z, so z = g y gives
 *     (I - g M_z) z = g M_s s,   z = Z s,
 * and H's columns of z are replaced by H_z Z. A singular I - g M_z is a
 * loop of controlled sources with loop gain 1: their outputs are not
 * determined, and the error names them. The network is no longer
 * reciprocal: H's cross blocks are not minus each other's transposes, so
 * P B = C^T may fail (docs/netlist.md).
 *
 * Coupled inductors (K). L1, L2 with M = k sqrt(L1 L2) make P's inductor
 * block the inductance matrix; each group of inductors joined by K is one
 * dense block, checked positive definite by its Cholesky factor and
 * inverted for A = P^-1 H_x. */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "netlist_impl.h"

/* ---- controlled sources ------------------------------------------------------- */

/* The controlling quantities' rows, M (nc x np, row-major). */
static int control_rows(cup_netlist *nl, double *M) {
  int np = nl->nv + nl->ni, st = CUP_OK;
  for (int k = 0; k < nl->nctl && !st; k++) {
    const nl_elem *el = &nl->elem[nl->ctl_elem[k]];
    double *row = M + (size_t)k * np;
    if (el->kind == NL_E || el->kind == NL_G) {
      st = nl_prow_node(nl, el->ca, 1, row);
      if (!st) st = nl_prow_node(nl, el->cb, -1, row);
    } else {
      st = nl_prow_current(nl, el->ctrl, row);
    }
  }
  return st;
}

/* Sources reachable from s along A's off-diagonal entries (i depends on j:
 * an edge j -> i), forward or (back) backward. */
static void reach(const double *A, int nc, int s, int back, unsigned char *seen, int *stack) {
  int top = 0;
  seen[s] = 1;
  stack[top++] = s;
  while (top) {
    int v = stack[--top];
    for (int w = 0; w < nc; w++)
      if (w != v && !seen[w] && (back ? A[v * nc + w] : A[w * nc + v]) != 0) { seen[w] = 1; stack[top++] = w; }
  }
}

/* "E1, E2 and F1": the loop through source s, the sources that both depend
 * on it and it depends on (A's strongly connected component). */
static int loop_names(const cup_netlist *nl, const double *A, int s, char *buf, size_t size) {
  int nc = nl->nctl, n = 0, *stack = malloc(sizeof(int) * (size_t)nc);
  unsigned char *fw = calloc((size_t)nc, 1), *bw = calloc((size_t)nc, 1);
  if (!stack || !fw || !bw) { free(stack); free(fw); free(bw); return CUP_ERR_NOMEM; }
  reach(A, nc, s, 0, fw, stack);
  reach(A, nc, s, 1, bw, stack);
  for (int k = 0; k < nc; k++) n += fw[k] && bw[k];
  size_t len = 0;
  buf[0] = '\0';
  for (int k = 0, j = 0; k < nc && len + 1 < size; k++) {
    if (!fw[k] || !bw[k]) continue;
    if (len > 120) { snprintf(buf + len, size - len, ", ..."); break; }
    len += (size_t)snprintf(buf + len, size - len, "%s%s", j == 0 ? "" : j + 1 < n ? ", " : " and ",
                            nl->elem[nl->ctl_elem[k]].name);
    j++;
  }
  free(stack); free(fw); free(bw);
  return n;
}

/* Solve A Z = R (A nc x nc, R nc x np, both row-major, overwritten; Z into
 * R) by Gaussian elimination with complete pivoting. Returns 0, or the
 * number of sources left unpivoted (their indices in rest) when A is
 * singular. */
static int solve_complete(double *A, double *R, int nc, int np, int *rest) {
  int *rp = malloc(sizeof(int) * (size_t)nc), *cp = malloc(sizeof(int) * (size_t)nc);
  if (!rp || !cp) { free(rp); free(cp); return -1; }
  double big = 0;
  for (int i = 0; i < nc * nc; i++) big = fmax(big, fabs(A[i]));
  for (int i = 0; i < nc; i++) rp[i] = cp[i] = i;
  int bad = 0;
  for (int k = 0; k < nc && !bad; k++) {
    int pi = k, pj = k;
    for (int i = k; i < nc; i++)
      for (int j = k; j < nc; j++)
        if (fabs(A[rp[i] * nc + cp[j]]) > fabs(A[rp[pi] * nc + cp[pj]])) { pi = i; pj = j; }
    int t = rp[k]; rp[k] = rp[pi]; rp[pi] = t;
    t = cp[k]; cp[k] = cp[pj]; cp[pj] = t;
    double piv = A[rp[k] * nc + cp[k]];
    if (!(fabs(piv) > 1e-12 * fmax(1, big))) {
      for (int i = k; i < nc; i++) rest[bad++] = cp[i];
      break;
    }
    for (int i = k + 1; i < nc; i++) {
      double f = A[rp[i] * nc + cp[k]] / piv;
      if (f == 0) continue;
      for (int j = k; j < nc; j++) A[rp[i] * nc + cp[j]] -= f * A[rp[k] * nc + cp[j]];
      for (int j = 0; j < np; j++) R[(size_t)rp[i] * np + j] -= f * R[(size_t)rp[k] * np + j];
    }
  }
  if (!bad) {                                     /* back substitution: unknown cp[k] from row rp[k] */
    double *Z = calloc((size_t)nc * np + 1, sizeof(double));
    if (!Z) { free(rp); free(cp); return -1; }
    for (int k = nc - 1; k >= 0; k--)
      for (int j = 0; j < np; j++) {
        double acc = R[(size_t)rp[k] * np + j];
        for (int l = k + 1; l < nc; l++) acc -= A[rp[k] * nc + cp[l]] * Z[(size_t)cp[l] * np + j];
        Z[(size_t)cp[k] * np + j] = acc / A[rp[k] * nc + cp[k]];
      }
    memcpy(R, Z, sizeof(double) * (size_t)nc * np);
    free(Z);
  }
  free(rp); free(cp);
  return bad;
}

/* H's columns of controlled ports replaced by H_z Z (magnitudes summed
 * alongside, so that products that cancel to rounding are dropped). */
static int substitute(cup_netlist *nl) {
  int np = nl->nv + nl->ni, st = CUP_OK;
  nl_coo t = {0};
  for (int j = 0; j < np && !st; j++)
    for (int k = nl->H.p[j]; k < nl->H.p[j + 1] && !st; k++) {
      int i = nl->H.i[k];
      double h = nl->H.x[k];
      if (nl->port[j].var != NL_VAR_CTL) { st = nl_coo_add(&t, i, j, h, fabs(h)); continue; }
      const double *z = nl->zmap + (size_t)nl->port[j].index * np;
      for (int q = 0; q < np && !st; q++)
        if (z[q] != 0) st = nl_coo_add(&t, i, q, h * z[q], fabs(h * z[q]));
    }
  la_sparse H = {0};
  if (!st) st = nl_coo_to_csc(&t, np, np, &H);
  nl_coo_free(&t);
  if (st) return st;
  la_sparse_free(&nl->H);
  nl->H = H;
  return CUP_OK;
}

int nl_controlled(cup_netlist *nl, const nl_circuit *c, char *errmsg) {
  int nc = nl->nctl, np = nl->nv + nl->ni;
  if (!nc) return CUP_OK;
  double *M = calloc((size_t)nc * np + 1, sizeof(double)), *A = malloc(sizeof(double) * (size_t)nc * nc);
  int *rest = malloc(sizeof(int) * (size_t)nc);
  nl->zmap = calloc((size_t)nc * np + 1, sizeof(double));
  int st = M && A && rest && nl->zmap ? control_rows(nl, M) : CUP_ERR_NOMEM;
  for (int i = 0; !st && i < nc; i++) {          /* A = I - g M_z, R = g M_s */
    double g = nl->elem[nl->ctl_elem[i]].value;
    for (int j = 0; j < nc; j++) A[i * nc + j] = (i == j) - g * M[(size_t)i * np + nl->eport[nl->ctl_elem[j]]];
    for (int q = 0; q < np; q++)
      nl->zmap[(size_t)i * np + q] = nl->port[q].var == NL_VAR_CTL ? 0 : g * M[(size_t)i * np + q];
  }
  double *A0 = st ? NULL : malloc(sizeof(double) * (size_t)nc * nc);
  if (!st && !A0) st = CUP_ERR_NOMEM;
  if (!st) memcpy(A0, A, sizeof(double) * (size_t)nc * nc);
  int bad = st ? 0 : solve_complete(A, nl->zmap, nc, np, rest);
  if (bad < 0) st = CUP_ERR_NOMEM;
  if (!st && bad > 0) {
    char names[200];
    int first = nc, n = loop_names(nl, A0, rest[0], names, sizeof names);
    for (int k = 0; k < nc && n > 0; k++)       /* named at the first of them in the netlist */
      if (k < first && strstr(names, nl->elem[nl->ctl_elem[k]].name)) first = k;
    st = n < 0 ? CUP_ERR_NOMEM
               : nl_fail(c, nl->ctl_elem[first < nc ? first : rest[0]], errmsg, CUP_ERR_PARSE, "a loop of "
                         "controlled sources (%s) makes the circuit singular: its loop gain is 1, so %s not "
                         "determined by the rest of the circuit; change a gain or break the loop", names,
                         n == 1 ? "the output is" : "their outputs are");
  }
  free(A0);
  if (!st && (st = substitute(nl))) st = CUP_ERR_NOMEM;
  free(M); free(A); free(rest);
  if (st == CUP_ERR_NOMEM) return nl_fail(c, -1, errmsg, st, "out of memory while formulating the circuit");
  return st;
}

/* ---- coupled inductors ---------------------------------------------------------- */

static int find(int *uf, int v) {
  while (uf[v] != v) v = uf[v] = uf[uf[v]];
  return v;
}

/* Group g's inductance matrix (dense, size k, states in idx) from the
 * inductors' values and the K cards within it. */
static void group_matrix(const cup_netlist *nl, const nl_circuit *c, const int *idx, int k, const int *state_elem,
                         double *Lm) {
  memset(Lm, 0, sizeof(double) * (size_t)k * k);
  for (int a = 0; a < k; a++) Lm[a * k + a] = c->elem[state_elem[idx[a]]].value;
  for (int q = 0; q < c->ncoup; q++) {
    int i = nl->evar[c->coup[q].l1], j = nl->evar[c->coup[q].l2], a = -1, b = -1;
    for (int s = 0; s < k; s++) { if (idx[s] == i) a = s; if (idx[s] == j) b = s; }
    if (a < 0 || b < 0) continue;
    double m = c->coup[q].k * sqrt(Lm[a * k + a] * Lm[b * k + b]);
    Lm[a * k + b] += m;
    Lm[b * k + a] += m;
  }
}

/* In-place Cholesky then inverse of a k x k SPD matrix; 0 if not SPD. */
static int spd_inverse(double *Lm, int k, double *inv) {
  for (int j = 0; j < k; j++) {
    double d = Lm[j * k + j];
    for (int l = 0; l < j; l++) d -= Lm[j * k + l] * Lm[j * k + l];
    if (!(d > 1e-12 * Lm[j * k + j])) return 0;   /* relative: k = 1 - 1e-13 is not an inductance */
    Lm[j * k + j] = sqrt(d);
    for (int i = j + 1; i < k; i++) {
      double s = Lm[i * k + j];
      for (int l = 0; l < j; l++) s -= Lm[i * k + l] * Lm[j * k + l];
      Lm[i * k + j] = s / Lm[j * k + j];
    }
  }
  for (int col = 0; col < k; col++) {             /* solve L L^T x = e_col */
    double *x = inv + (size_t)col * k;
    for (int i = 0; i < k; i++) {
      double s = i == col;
      for (int l = 0; l < i; l++) s -= Lm[i * k + l] * x[l];
      x[i] = s / Lm[i * k + i];
    }
    for (int i = k - 1; i >= 0; i--) {
      double s = x[i];
      for (int l = i + 1; l < k; l++) s -= Lm[l * k + i] * x[l];
      x[i] = s / Lm[i * k + i];
    }
  }
  return 1;
}

int nl_coupling_metric(cup_netlist *nl, const nl_circuit *c, la_sparse *P, char *errmsg) {
  int n = nl->n, nL = nl->nL;
  if (!c->ncoup) return CUP_OK;
  int *uf = malloc(sizeof(int) * ((size_t)nL + 1)), *state_elem = malloc(sizeof(int) * ((size_t)nL + 1));
  int *idx = malloc(sizeof(int) * ((size_t)nL + 1)), *lastk = malloc(sizeof(int) * ((size_t)nL + 1));
  double *Lm = malloc(sizeof(double) * ((size_t)nL * nL + 1)), *inv = malloc(sizeof(double) * ((size_t)nL * nL + 1));
  nl->coupled = calloc((size_t)n + 1, sizeof(int));
  nl_coo tp = {0}, ti = {0};
  int st = uf && state_elem && idx && lastk && Lm && inv && nl->coupled ? CUP_OK : CUP_ERR_NOMEM;
  for (int e = 0; !st && e < c->nelem; e++)
    if (c->elem[e].kind == NL_L) state_elem[nl->evar[e]] = e;
  for (int s = 0; !st && s < nL; s++) { uf[s] = s; lastk[s] = -1; }
  for (int q = 0; !st && q < c->ncoup; q++) {
    int a = find(uf, nl->evar[c->coup[q].l1]), b = find(uf, nl->evar[c->coup[q].l2]);
    if (a != b) uf[a] = b;
  }
  for (int q = 0; !st && q < c->ncoup; q++) lastk[find(uf, nl->evar[c->coup[q].l1])] = q;
  for (int s = 0; !st && s < nL; s++) {
    if (find(uf, s) != s || lastk[s] < 0) continue;   /* one pass per coupled group, at its root */
    int k = 0;
    for (int t = 0; t < nL; t++) if (find(uf, t) == s) idx[k++] = t;
    group_matrix(nl, c, idx, k, state_elem, Lm);
    for (int a = 0; a < k && !st; a++)
      for (int b = 0; b <= a && !st; b++) {
        st = nl_coo_add(&tp, idx[a], idx[b], Lm[a * k + b], 0);
        if (!st && a != b) st = nl_coo_add(&tp, idx[b], idx[a], Lm[a * k + b], 0);
      }
    if (st) break;
    if (!spd_inverse(Lm, k, inv)) {
      char names[200] = "";
      size_t len = 0;
      for (int a = 0; a < k && len < 150; a++)
        len += (size_t)snprintf(names + len, sizeof names - len, "%s%s", a == 0 ? "" : a + 1 < k ? ", " : " and ",
                                c->elem[state_elem[idx[a]]].name);
      const nl_coupling *K = &c->coup[lastk[s]];
      const char *file = c->files && K->file < c->nfiles ? c->files[K->file] : c->file;
      st = fail_fmt(errmsg, CUP_ERR_PARSE, "%s:%d:%d: %s: the inductance matrix of %s is not positive definite "
                    "(their coupling coefficients are inconsistent: the energy 1/2 i^T L i can vanish or turn "
                    "negative); lower the coupling coefficients", file, K->line, K->col, K->name, names);
      break;
    }
    for (int a = 0; a < k && !st; a++) {
      nl->coupled[idx[a]] = 1;
      for (int b = 0; b < k && !st; b++) st = nl_coo_add(&ti, idx[a], idx[b], inv[(size_t)b * k + a], 0);
    }
  }
  for (int e = 0; !st && e < c->nelem; e++)      /* the rest of P: the uncoupled inductors, the capacitors */
    if ((c->elem[e].kind == NL_L && !nl->coupled[nl->evar[e]]) || c->elem[e].kind == NL_C)
      st = nl_coo_add(&tp, nl->evar[e], nl->evar[e], c->elem[e].value, 0);
  if (st == CUP_ERR_NOMEM || (!st && (nl_coo_to_csc(&tp, n, n, P) || nl_coo_to_csc(&ti, n, n, &nl->Pinv))))
    st = nl_fail(c, -1, errmsg, CUP_ERR_NOMEM, "out of memory while formulating the circuit");
  nl_coo_free(&tp); nl_coo_free(&ti);
  free(uf); free(state_elem); free(idx); free(lastk); free(Lm); free(inv);
  return st;
}

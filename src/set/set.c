/* set — the moving sets of a general sweeping process (catchup/set.h):
 * the registry of the kinds, validation, copies, and the parameters c(t),
 * r(t), g(t) at u(t). A kind's own checks, set-up and closed-form
 * projection sit in its file (set_impl.h's set_kind); this file names no
 * kind but in the registry. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "set_impl.h"

#define NAME4_(e, v, name, doc) [v] = name,
static const char *const kinds[CUP_SET_COUNT] = {CUP_SET_LIST(NAME4_)};
#undef NAME4_

const char *cup_set_kind_name(int kind) {
  return kind >= 0 && kind < CUP_SET_COUNT ? kinds[kind] : "unknown";
}

int cup_set_kind_parse(const char *name) {
  for (int k = 0; name && k < CUP_SET_COUNT; k++)
    if (!strcmp(name, kinds[k])) return k;
  return -1;
}

/* The registry: one line a kind. The kinds with nothing of their own
 * beyond rows and a ball are here; the others sit with their closed form. */
static const set_kind set_kind_polyset = {.rows = -1};
static const set_kind set_kind_intersection = {.rows = -1, .ball = 1};
static const set_kind *const registry[CUP_SET_COUNT] = {
  [CUP_SET_POLYSET] = &set_kind_polyset,
  [CUP_SET_BALL] = &set_kind_ball,
  [CUP_SET_ELLIPSOID] = &set_kind_ellipsoid,
  [CUP_SET_HALFSPACE] = &set_kind_halfspace,
  [CUP_SET_INTERSECTION] = &set_kind_intersection,
  [CUP_SET_ORACLE] = &set_kind_oracle,
  [CUP_SET_STATE_POLYSET] = &set_kind_state_polyset,
};

int cup_set_dim(const cup_set *S) { return S ? S->n : 0; }
int cup_set_params(const cup_set *S) { return S ? S->p : 0; }
int cup_set_kind_of(const cup_set *S) { return S ? S->kind : -1; }

void cup_set_free(cup_set **Sp) {
  if (!Sp || !*Sp) return;
  cup_set *S = *Sp;
  if (S->owns_K) cup_polyset_free(&S->K);
  if (S->owns_G) la_sparse_free(&S->G);
  la_sparse_free(&S->Gc);
  free(S->center); free(S->gr); free(S->Qd); free(S->V); free(S->VtP); free(S->lam); free(S->pa);
  free(S);
  *Sp = NULL;
}

int set_wrap_polyset(cup_set **out, const cup_polyset *K, const la_sparse *G, int p,
                     char *errmsg) {
  *out = NULL;
  cup_set *S = calloc(1, sizeof *S);
  if (!S) return fail_fmt(errmsg, CUP_ERR_NOMEM, "set: out of memory");
  S->kind = CUP_SET_POLYSET;
  S->type = registry[CUP_SET_POLYSET];
  S->n = K->n;
  S->p = p;
  S->K = (cup_polyset *)K;           /* borrowed: never freed or written through S */
  if (G) { S->G = *G; S->has_G = 1; }
  *out = S;
  return CUP_OK;
}

/* ---- validation and copies ---------------------------------------------------- */

static int finite_vector(const double *v, int len, const char *name, char *errmsg) {
  for (int k = 0; v && k < len; k++)
    if (!isfinite(v[k])) return fail_fmt(errmsg, CUP_ERR_NONFINITE, "set: %s[%d] is %g", name, k, v[k]);
  return CUP_OK;
}

static int copy_vector(double **dst, const double *src, int len, const char *name, char *errmsg) {
  int st = finite_vector(src, len, name, errmsg);
  if (st) return st;
  *dst = calloc((size_t)len + 1, sizeof(double));
  if (!*dst) return fail_fmt(errmsg, CUP_ERR_NOMEM, "set: out of memory");
  if (src) memcpy(*dst, src, sizeof(double) * (size_t)len);
  return CUP_OK;
}

static int check_kind_fields(const cup_set_desc *d, char *errmsg) {
  if ((int)d->kind < 0 || (int)d->kind >= (int)CUP_SET_COUNT)
    return fail_fmt(errmsg, CUP_ERR_ARG, "set: unknown kind %d", (int)d->kind);
  const set_kind *k = registry[d->kind];
  const char *name = cup_set_kind_name(d->kind);
  if (d->n < 1 || d->p < 0)
    return fail_fmt(errmsg, CUP_ERR_DIM, "set %s: n = %d, p = %d; need n >= 1 and p >= 0", name, d->n, d->p);
  if (k->rows && !set_present(&d->C))
    return fail_fmt(errmsg, CUP_ERR_ARG, "set %s: C is missing", name);
  if (k->rows && (d->C.ncol != d->n || (k->rows > 0 && d->C.nrow != k->rows))) {
    char rows[16] = "m";
    if (k->rows > 0) snprintf(rows, sizeof rows, "%d", k->rows);
    return fail_fmt(errmsg, CUP_ERR_DIM, "set %s: C is %d x %d, expected %s x %d", name, d->C.nrow,
                    d->C.ncol, rows, d->n);
  }
  int st = k->check ? k->check(d, errmsg) : CUP_OK;
  if (st) return st;
  if (k->ball && !isfinite(d->radius))
    return fail_fmt(errmsg, CUP_ERR_NONFINITE, "set %s: radius is %g", name, d->radius);
  if (k->ball && !d->gr && !set_present(&d->Gc) && d->radius < 0)
    return fail_fmt(errmsg, CUP_ERR_EMPTY_SET, "set %s: radius = %g < 0: the set is empty", name, d->radius);
  return CUP_OK;
}

/* The rows (or none) and the metric, as a polyset. */
static int make_polyset(cup_set *S, const cup_set_desc *d, char *errmsg) {
  int zero = 0;
  int *cp = calloc((size_t)d->n + 1, sizeof(int));
  if (!cp) return fail_fmt(errmsg, CUP_ERR_NOMEM, "set: out of memory");
  cup_csc none = {0, d->n, cp, &zero, NULL};
  int rows = S->type->rows != 0;
  int st = cup_polyset_create(&S->K, rows ? &d->C : &none, rows ? d->F : NULL, &d->P, errmsg);
  free(cp);
  S->owns_K = 1;
  return st;
}

static int copy_motion(cup_set *S, const cup_set_desc *d, char *errmsg) {
  int st = CUP_OK, m = S->K->m;
  if (S->type->rows && set_present(&d->G)) {
    if (d->p == 0) return fail_fmt(errmsg, CUP_ERR_DIM, "set: G is given but p = 0");
    st = la_sparse_copy(&S->G, &d->G, "G", m, d->p, errmsg);
    S->has_G = S->owns_G = !st;
  }
  if (st || !S->type->ball) return st;
  st = copy_vector(&S->center, d->center, d->n, "center", errmsg);
  if (!st && set_present(&d->Gc)) {
    if (d->p == 0) return fail_fmt(errmsg, CUP_ERR_DIM, "set: Gc is given but p = 0");
    st = la_sparse_copy(&S->Gc, &d->Gc, "Gc", d->n, d->p, errmsg);
    S->has_Gc = !st;
  }
  S->radius = d->radius;
  if (!st && d->gr && d->p > 0) st = copy_vector(&S->gr, d->gr, d->p, "gr", errmsg);
  return st;
}

int cup_set_create(cup_set **out, const cup_set_desc *d, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "set: output pointer is NULL");
  *out = NULL;
  if (!d) return fail_fmt(errmsg, CUP_ERR_ARG, "set: description is NULL");
  int st = check_kind_fields(d, errmsg);
  if (st) return st;
  cup_set *S = calloc(1, sizeof *S);
  if (!S) return fail_fmt(errmsg, CUP_ERR_NOMEM, "set: out of memory");
  S->kind = d->kind;
  S->type = registry[d->kind];
  S->n = d->n;
  S->p = d->p;
  S->oracle = d->oracle;
  S->oracle_ctx = d->oracle_ctx;
  S->rows = d->rows;
  S->rows_ctx = d->rows_ctx;
  st = make_polyset(S, d, errmsg);
  if (!st) st = copy_motion(S, d, errmsg);
  if (!st && S->type->setup) st = S->type->setup(S, d, errmsg);
  if (st) { cup_set_free(&S); return st; }
  *out = S;
  return CUP_OK;
}

void set_place(const cup_set *S, const double *u, double *g, double *c, double *r) {
  int use_u = S->p > 0 && u;
  if (g && S->K->m) {
    la_copy(g, S->K->g0, S->K->m);
    if (S->has_G && use_u) la_sparse_gaxpy(&S->G, u, g);
  }
  if (c && S->center) {
    la_copy(c, S->center, S->n);
    if (S->has_Gc && use_u) la_sparse_gaxpy(&S->Gc, u, c);
  }
  if (r) {
    double rr = S->radius;
    if (S->gr && use_u)
      for (int k = 0; k < S->p; k++) rr += S->gr[k] * u[k];
    *r = rr;
  }
}

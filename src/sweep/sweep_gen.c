/* sweep_gen — generated variants (sweep_gen.h). One entry of variants: with
 *   grid:   {KEY: [v, ...], ...}        the cartesian product, the last key fastest
 *   zip:    {KEY: [v, ...], ...}        lists of one length, taken together
 *   sample: {count: N, seed: S, ranges: {KEY: [lo, hi] or {log: [lo, hi]}}}
 * makes prod(grid) x len(zip) x N variants, in that order (the sample's
 * points fastest). The Latin hypercube puts one point in each of the N
 * strata of every range (a seeded permutation per key, a uniform offset in
 * the stratum), from splitmix64: the file alone fixes the variants. */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include "sweep_gen.h"

enum { GEN_KEYS = 32 };

typedef struct {
  int ng, nz, nr;                         /* grid keys, zip keys, sampled ranges */
  const st_node *gk[GEN_KEYS], *gv[GEN_KEYS], *zk[GEN_KEYS], *zv[GEN_KEYS], *rk[GEN_KEYS];
  long glen[GEN_KEYS], zlen, count;       /* zlen, count: 1 when absent */
  double lo[GEN_KEYS], hi[GEN_KEYS];
  int logr[GEN_KEYS];
  unsigned long long seed;
} gen;

/* A value as SPICE writes it: 4.7k, 10u, 1meg, 2.2e-6 (the netlist's own suffixes). */
static int spice_value(const char *s, double *v) {
  static const struct { const char *suf; double mul; } sfx[] = {
      {"meg", 1e6}, {"t", 1e12}, {"g", 1e9}, {"k", 1e3}, {"m", 1e-3}, {"u", 1e-6}, {"n", 1e-9}, {"p", 1e-12},
      {"f", 1e-15}};
  char *end;
  *v = strtod(s, &end);
  if (end == s) return -1;
  if (!*end) return isfinite(*v) ? 0 : -1;
  for (size_t k = 0; k < sizeof sfx / sizeof sfx[0]; k++) {
    size_t n = strlen(sfx[k].suf);
    if (strlen(end) == n && !strncasecmp(end, sfx[k].suf, n)) {
      *v *= sfx[k].mul;
      return isfinite(*v) ? 0 : -1;
    }
  }
  return -1;
}

static int number_value(rd *p, const st_node *nd, const char *key, double *v) {
  char b[64];
  if (nd->kind != ST_SCALAR || st_is_null(nd) || spice_value(nd->text, v))
    return fail(p, CUP_ERR_PARSE, nd, key, "expected a number such as 4.7k, 10u or 2.2e-6 (got %s)",
                st_looks(nd, b, sizeof b));
  return CUP_OK;
}

/* A list of scalar values (a scalar: one); its length into *len. */
static int value_list(rd *p, const st_node *nd, const char *key, long *len) {
  char k2[KEY_LEN], b[64];
  if (nd->kind == ST_MAP) return fail(p, CUP_ERR_PARSE, nd, key, "expected a value or a list of values (got a mapping)");
  if (nd->kind == ST_SEQ && nd->len == 0) return fail(p, CUP_ERR_PARSE, nd, key, "empty list: give at least one value");
  if (nd->kind == ST_SCALAR && st_is_null(nd)) return fail(p, CUP_ERR_PARSE, nd, key, "expected a value (got null)");
  *len = nd->kind == ST_SEQ ? nd->len : 1;
  for (int j = 0; nd->kind == ST_SEQ && j < nd->len; j++)
    if (nd->item[j]->kind != ST_SCALAR || st_is_null(nd->item[j]))
      return fail(p, CUP_ERR_PARSE, nd->item[j], joini(k2, key, j), "expected a value (got %s)",
                  st_looks(nd->item[j], b, sizeof b));
  return CUP_OK;
}

static int read_grid(rd *p, const st_node *g, const char *key, gen *G) {
  char k2[KEY_LEN];
  int st = need_map(p, g, key, "a mapping of scene keys to lists of values, e.g. {netlist.L: [10u, 22u]}");
  if (!st && g->len > GEN_KEYS) st = fail(p, CUP_ERR_PARSE, g, key, "at most %d keys (got %d)", GEN_KEYS, g->len);
  for (int j = 0; !st && j < g->len; j++) {
    G->gk[j] = g->key[j], G->gv[j] = g->item[j];
    st = value_list(p, g->item[j], join(k2, key, g->key[j]->text), &G->glen[j]);
  }
  if (!st) G->ng = g->len;
  return st;
}

static int read_zip(rd *p, const st_node *z, const char *key, gen *G) {
  char k2[KEY_LEN];
  int st = need_map(p, z, key, "a mapping of scene keys to lists of one length, e.g. {netlist.C: [1u, 2u], "
                    "netlist.R: [5, 10]}");
  if (!st && z->len > GEN_KEYS) st = fail(p, CUP_ERR_PARSE, z, key, "at most %d keys (got %d)", GEN_KEYS, z->len);
  for (int j = 0; !st && j < z->len; j++) {
    long len;
    G->zk[j] = z->key[j], G->zv[j] = z->item[j];
    st = value_list(p, z->item[j], join(k2, key, z->key[j]->text), &len);
    if (!st && j == 0) G->zlen = len;
    if (!st && len != G->zlen)
      st = fail(p, CUP_ERR_PARSE, z->item[j], k2, "zipped lists need one length: %s has %ld values, %s has %ld",
                z->key[0]->text, G->zlen, z->key[j]->text, len);
  }
  if (!st) G->nz = z->len;
  return st;
}

static int read_range(rd *p, const st_node *nd, const char *key, gen *G, int j) {
  char k2[KEY_LEN];
  const st_node *r = nd;
  int st = CUP_OK;
  G->logr[j] = 0;
  if (nd->kind == ST_MAP) {
    static const char *const known[] = {"log", NULL};
    if ((st = check_keys(p, nd, key, known))) return st;
    if (!(r = opt(nd, "log"))) return fail(p, CUP_ERR_PARSE, nd, key, "expected [lo, hi] or {log: [lo, hi]}");
    G->logr[j] = 1;
    key = join(k2, key, "log");
  }
  if (r->kind != ST_SEQ || r->len != 2) return fail(p, CUP_ERR_PARSE, r, key, "expected [lo, hi] or {log: [lo, hi]}");
  char k3[KEY_LEN];
  if ((st = number_value(p, r->item[0], joini(k3, key, 0), &G->lo[j]))) return st;
  if ((st = number_value(p, r->item[1], joini(k3, key, 1), &G->hi[j]))) return st;
  if (!(G->lo[j] < G->hi[j])) return fail(p, CUP_ERR_PARSE, r, key, "needs lo < hi (got %g, %g)", G->lo[j], G->hi[j]);
  if (G->logr[j] && !(G->lo[j] > 0))
    return fail(p, CUP_ERR_PARSE, r, key, "a log range needs lo > 0 (got %g)", G->lo[j]);
  return CUP_OK;
}

static int read_sample(rd *p, const st_node *sm, const char *key, gen *G) {
  static const char *const known[] = {"count", "seed", "ranges", NULL};
  char k2[KEY_LEN], k3[KEY_LEN];
  const st_node *x, *rg;
  long v = 0;
  int st = need_map(p, sm, key, "a mapping with count, seed and ranges");
  if (!st) st = check_keys(p, sm, key, known);
  if (st) return st;
  if (!(x = opt(sm, "count"))) return fail(p, CUP_ERR_PARSE, sm, join(k2, key, "count"), "missing (required)");
  if ((st = integer(p, x, join(k2, key, "count"), 1, SW_GEN_MAX, &G->count))) return st;
  G->seed = 1;
  if ((x = opt(sm, "seed"))) {
    if ((st = integer(p, x, join(k2, key, "seed"), 0, 9007199254740991L, &v))) return st;
    G->seed = (unsigned long long)v;
  }
  if (!(rg = opt(sm, "ranges"))) return fail(p, CUP_ERR_PARSE, sm, join(k2, key, "ranges"), "missing (required)");
  join(k2, key, "ranges");
  if ((st = need_map(p, rg, k2, "a mapping of scene keys to [lo, hi] or {log: [lo, hi]}"))) return st;
  if (rg->len > GEN_KEYS) return fail(p, CUP_ERR_PARSE, rg, k2, "at most %d keys (got %d)", GEN_KEYS, rg->len);
  for (int j = 0; !st && j < rg->len; j++) {
    G->rk[j] = rg->key[j];
    st = read_range(p, rg->item[j], join(k3, k2, rg->key[j]->text), G, j);
  }
  if (!st) G->nr = rg->len;
  return st;
}

static int read_gen(rd *p, const st_node *nd, const char *key, gen *G) {
  char k2[KEY_LEN];
  const st_node *x;
  int st = CUP_OK;
  memset(G, 0, sizeof *G);
  G->zlen = G->count = 1;
  if ((x = opt(nd, "grid"))) st = read_grid(p, x, join(k2, key, "grid"), G);
  if (!st && (x = opt(nd, "zip"))) st = read_zip(p, x, join(k2, key, "zip"), G);
  if (!st && (x = opt(nd, "sample"))) st = read_sample(p, x, join(k2, key, "sample"), G);
  return st;
}

static long total(const gen *G) {
  double n = (double)G->zlen * (double)G->count;
  for (int j = 0; j < G->ng; j++) n *= (double)G->glen[j];
  return n > (double)SW_GEN_MAX ? -1 : (long)n;
}

int sw_gen_count(rd *p, const st_node *nd, const char *key, long *count) {
  gen G;
  int st = read_gen(p, nd, key, &G);
  if (st) return st;
  if ((*count = total(&G)) < 0)
    return fail(p, CUP_ERR_PARSE, nd, key, "generates more than %ld variants", SW_GEN_MAX);
  return CUP_OK;
}

/* ---- expansion ---- */

static unsigned long long splitmix64(unsigned long long *x) {
  unsigned long long z = (*x += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

static double uniform01(unsigned long long *x) { return (double)(splitmix64(x) >> 11) * 0x1.0p-53; }

/* The Latin hypercube: N x nr values, row i the i-th point. */
static double *hypercube(const gen *G) {
  long N = G->count;
  double *v = malloc(sizeof(double) * (size_t)(N * G->nr + 1));
  long *perm = malloc(sizeof(long) * (size_t)N);
  unsigned long long x = G->seed;
  for (int j = 0; v && perm && j < G->nr; j++) {
    for (long i = 0; i < N; i++) perm[i] = i;
    for (long i = N - 1; i > 0; i--) {          /* Fisher-Yates */
      long k = (long)(splitmix64(&x) % (unsigned long long)(i + 1)), w = perm[i];
      perm[i] = perm[k], perm[k] = w;
    }
    for (long i = 0; i < N; i++) {
      double u = ((double)perm[i] + uniform01(&x)) / (double)N;
      v[i * G->nr + j] = G->logr[j] ? exp(log(G->lo[j]) + u * (log(G->hi[j]) - log(G->lo[j])))
                                    : G->lo[j] + u * (G->hi[j] - G->lo[j]);
    }
  }
  free(perm);
  if (!perm) { free(v); return NULL; }
  return v;
}

/* "key=value": a scalar as written (a quoted one in single quotes). */
static char *scalar_override(const char *key, const st_node *v) {
  size_t n = strlen(v->text), len = strlen(key) + 2 * n + 4;
  char *s = malloc(len), *w = s;
  if (!s) return NULL;
  w += sprintf(w, "%s=", key);
  if (v->quoted) *w++ = '\'';
  for (size_t i = 0; i < n; i++) {
    if (v->quoted && v->text[i] == '\'') *w++ = '\'';
    *w++ = v->text[i];
  }
  if (v->quoted) *w++ = '\'';
  *w = '\0';
  return s;
}

static const st_node *item(const st_node *list, long j) { return list->kind == ST_SEQ ? list->item[j] : list; }

static int fill(const gen *G, const char *name, char *const *set, int n_set, sw_gen_variant *v, long J,
                const double *cube) {
  int n = n_set + G->ng + G->nz + G->nr;
  char buf[160];
  if (!(v->set = calloc((size_t)n + 1, sizeof *v->set))) return CUP_ERR_NOMEM;
  for (int j = 0; j < n_set; j++)
    if (!(v->set[v->n_set++] = strdup(set[j]))) return CUP_ERR_NOMEM;
  long sidx = J % G->count, rest = J / G->count, zidx = rest % G->zlen, gidx[GEN_KEYS];
  rest /= G->zlen;
  for (int j = G->ng - 1; j >= 0; j--) gidx[j] = rest % G->glen[j], rest /= G->glen[j];
  for (int j = 0; j < G->ng; j++)
    if (!(v->set[v->n_set++] = scalar_override(G->gk[j]->text, item(G->gv[j], gidx[j])))) return CUP_ERR_NOMEM;
  for (int j = 0; j < G->nz; j++)
    if (!(v->set[v->n_set++] = scalar_override(G->zk[j]->text, item(G->zv[j], zidx)))) return CUP_ERR_NOMEM;
  for (int j = 0; j < G->nr; j++) {
    size_t len = strlen(G->rk[j]->text) + 32;
    char *s = malloc(len);
    if (!s) return CUP_ERR_NOMEM;
    snprintf(s, len, "%s=%.17g", G->rk[j]->text, cube[sidx * G->nr + j]);
    v->set[v->n_set++] = s;
  }
  snprintf(buf, sizeof buf, "%.120s.%ld", name, J);
  return (v->name = strdup(buf)) ? CUP_OK : CUP_ERR_NOMEM;
}

int sw_gen_expand(rd *p, const st_node *nd, const char *key, const char *name, size_t name_len, char *const *set,
                  int n_set, sw_gen_variant *out, long count) {
  gen G;
  int st = read_gen(p, nd, key, &G);
  if (st) return st;
  char k2[KEY_LEN], digits[32];
  if (strlen(name) + (size_t)snprintf(digits, sizeof digits, ".%ld", count - 1) >= name_len)
    return fail(p, CUP_ERR_PARSE, opt(nd, "name"), join(k2, key, "name"), "with the generated suffix (%s) longer "
                "than %zu characters", digits, name_len - 1);
  double *cube = G.nr ? hypercube(&G) : NULL;
  if (G.nr && !cube) return CUP_ERR_NOMEM;
  for (long J = 0; J < count && !st; J++) st = fill(&G, name, set, n_set, &out[J], J, cube);
  free(cube);
  return st;
}

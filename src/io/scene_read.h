/* scene_read — what every reader of a scene file needs: messages that name
 * FILE:LINE:COL and the dotted key (scene_tree.c), required and optional
 * keys, numbers, matrices (inline or Matrix Market), vectors, the metric P,
 * and the type of scene.c's reader of an input component. Static inline, so that the readers
 * of each key (scene.c, scene_set.c) share them without the library
 * exporting generic names. Internal to the library. */
#ifndef CUP_SCENE_READ_H
#define CUP_SCENE_READ_H

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "mtx.h"
#include "read_text.h"
#include "scene_tree.h"
#include "util/path.h"

/* What every reader needs: names for messages, the directory of the file,
 * the list of the files read (read_text.h: every file a key names is
 * read through read_text with it). */
typedef struct rd {
  st_src src;
  const char *dir;
  char *errmsg;
  file_list *files;
} rd;

#define KEY_LEN 128              /* dotted keys ("input.1.0.amplitude") */


static inline int fail(rd *r, int status, const st_node *at, const char *key, const char *fmt, ...)
  __attribute__((format(printf, 5, 6)));
static inline int fail(rd *r, int status, const st_node *at, const char *key, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  st_verror(r->errmsg, status, &r->src, at, key, fmt, ap);
  va_end(ap);
  return status;
}

/* Dotted keys; a key too long for the buffer ends in "..." */
static inline const char *join(char *buf, const char *parent, const char *k) {
  if (snprintf(buf, KEY_LEN, "%s%s%s", parent, *parent ? "." : "", k) >= KEY_LEN)
    strcpy(buf + KEY_LEN - 4, "...");
  return buf;
}

static inline const char *joini(char *buf, const char *parent, int i) {
  if (snprintf(buf, KEY_LEN, "%s.%d", parent, i) >= KEY_LEN) strcpy(buf + KEY_LEN - 4, "...");
  return buf;
}

/* ---- keys ---------------------------------------------------------------- */

static inline int check_keys(rd *r, const st_node *map, const char *mkey, const char *const *known) {
  const st_node *bad = st_unknown_key(map, known);
  if (!bad) return CUP_OK;
  char key[KEY_LEN], hint[ST_HINT_LEN];
  return fail(r, CUP_ERR_PARSE, bad, join(key, mkey, bad->text), "unknown key (%s)",
              st_suggest(hint, sizeof hint, bad->text, known));
}

/* The value of an optional key (NULL if absent or null). */
static inline const st_node *opt(const st_node *map, const char *k) {
  const st_node *v = st_get(map, k, NULL);
  return st_is_null(v) ? NULL : v;
}

/* The value of a required key, or an error at the mapping. */
static inline int need(rd *r, const st_node *map, const char *mkey, const char *k, const st_node **out) {
  char key[KEY_LEN];
  *out = opt(map, k);
  if (*out) return CUP_OK;
  return fail(r, CUP_ERR_PARSE, map, join(key, mkey, k), "missing (required)");
}

static inline int need_map(rd *r, const st_node *nd, const char *key, const char *what) {
  char b[64];
  if (nd->kind == ST_MAP) return CUP_OK;
  return fail(r, CUP_ERR_PARSE, nd, key, "expected %s (got %s)", what, st_looks(nd, b, sizeof b));
}

static inline int string(rd *r, const st_node *nd, const char *key, const char **out) {
  char b[64];
  if (nd->kind != ST_SCALAR || st_is_null(nd))
    return fail(r, CUP_ERR_PARSE, nd, key, "expected a word or a string (got %s)", st_looks(nd, b, sizeof b));
  *out = nd->text;
  return CUP_OK;
}

/* ---- numbers ------------------------------------------------------------- */

static inline int number(rd *r, const st_node *nd, const char *key, double *out) {
  char b[64];
  if (nd->kind == ST_SCALAR && nd->quoted && st_number(nd->text, out))
    return fail(r, CUP_ERR_PARSE, nd, key, "expected a number (got the string \"%.40s\": write numbers without quotes)",
                nd->text);
  if (nd->kind != ST_SCALAR || nd->quoted || st_is_null(nd) || !st_number(nd->text, out))
    return fail(r, CUP_ERR_PARSE, nd, key, "expected a number (got %s)", st_looks(nd, b, sizeof b));
  if (!isfinite(*out)) return fail(r, CUP_ERR_NONFINITE, nd, key, "must be finite (got %g)", *out);
  return CUP_OK;
}

/* A number >= lo (strict: > lo). */
static inline int number_min(rd *r, const st_node *nd, const char *key, double lo, int strict, double *out) {
  int st = number(r, nd, key, out);
  if (st) return st;
  if (strict ? *out > lo : *out >= lo) return CUP_OK;
  return fail(r, CUP_ERR_PARSE, nd, key, "must be %s %g (got %g)", strict ? ">" : ">=", lo, *out);
}

/* An integer in [lo, hi]; 1e6 is accepted (an exact integer in a float). */
static inline int integer(rd *r, const st_node *nd, const char *key, long lo, long hi, long *out) {
  double v;
  int st = number(r, nd, key, &v);
  if (st) return st;
  if (v != floor(v)) return fail(r, CUP_ERR_PARSE, nd, key, "must be an integer (got %g)", v);
  if (v < (double)lo) return fail(r, CUP_ERR_PARSE, nd, key, "must be >= %ld (got %g)", lo, v);
  if (v > (double)hi) return fail(r, CUP_ERR_PARSE, nd, key, "must be <= %ld (got %g)", hi, v);
  *out = (long)v;
  return CUP_OK;
}

/* true or false (YAML 1.2's core schema spellings). */
static inline int boolean(rd *r, const st_node *nd, const char *key, int *out) {
  static const char *const yes[] = {"true", "True", "TRUE", NULL}, *const no[] = {"false", "False", "FALSE", NULL};
  char b[64];
  for (int k = 0; nd->kind == ST_SCALAR && !nd->quoted && yes[k]; k++) {
    if (!strcmp(nd->text, yes[k])) { *out = 1; return CUP_OK; }
    if (!strcmp(nd->text, no[k])) { *out = 0; return CUP_OK; }
  }
  return fail(r, CUP_ERR_PARSE, nd, key, "expected true or false (got %s)", st_looks(nd, b, sizeof b));
}

/* ---- matrices ------------------------------------------------------------ */

/* An owned CSC matrix (inline or from a Matrix Market file, mtx.c) and
 * where it was written. */
typedef struct mat {
  mtx_csc a;
  const st_node *at;
} mat;

static inline void mat_free(mat *M) {
  mtx_free(&M->a);
  M->at = NULL;
}

static inline cup_csc mat_view(const mat *M) {
  cup_csc v = {0};
  if (M->a.p) v = (cup_csc){M->a.nrow, M->a.ncol, M->a.p, M->a.i, M->a.x};
  return v;
}

#define MATRIX_FORMS "a list of rows like [[1, 0], [0, 1]], or {file: name.mtx}"

static inline int matrix_inline(rd *r, const st_node *nd, const char *key, mat *M) {
  char k1[KEY_LEN], k2[KEY_LEN], b[64];
  if (nd->len == 0 || nd->item[0]->kind != ST_SEQ)
    return fail(r, CUP_ERR_PARSE, nd, key, "expected a matrix: " MATRIX_FORMS " (got %s)",
                nd->len ? "a list of numbers" : "an empty list");
  int nr = nd->len, nc = nd->item[0]->len;
  if (nc == 0) return fail(r, CUP_ERR_PARSE, nd->item[0], joini(k1, key, 0), "a row needs at least one entry");
  for (int i = 0; i < nr; i++) {
    const st_node *row = nd->item[i];
    if (row->kind != ST_SEQ)
      return fail(r, CUP_ERR_PARSE, row, joini(k1, key, i), "expected a row: a list of numbers (got %s)",
                  st_looks(row, b, sizeof b));
    if (row->len != nc)
      return fail(r, CUP_ERR_DIM, row, joini(k1, key, i), "row %d has %d entries but row 0 has %d", i,
                  row->len, nc);
  }
  double *a = malloc(sizeof(double) * (size_t)nr * (size_t)nc);
  if (!a) return CUP_ERR_NOMEM;
  int st = CUP_OK;
  for (int i = 0; i < nr && !st; i++)
    for (int j = 0; j < nc && !st; j++)
      st = number(r, nd->item[i]->item[j], joini(k2, joini(k1, key, i), j), &a[(size_t)i * nc + j]);
  if (!st) st = mtx_from_dense(&M->a, nr, nc, a, (size_t)nc, 1);
  free(a);
  return st;
}

static inline int matrix_file(rd *r, const st_node *nd, const char *key, mat *M);

static inline int matrix(rd *r, const st_node *nd, const char *key, mat *M) {
  char b[64];
  M->at = nd;
  if (nd->kind == ST_MAP && st_get(nd, "file", NULL)) return matrix_file(r, nd, key, M);
  if (nd->kind == ST_SEQ) return matrix_inline(r, nd, key, M);
  return fail(r, CUP_ERR_PARSE, nd, key, "expected a matrix: " MATRIX_FORMS " (got %s)", st_looks(nd, b, sizeof b));
}

static inline int matrix_dims(rd *r, const mat *M, const char *key, int nr, int nc, const char *why) {
  if (M->a.nrow == nr && M->a.ncol == nc) return CUP_OK;
  return fail(r, CUP_ERR_DIM, M->at, key, "must be %d x %d (%s), got %d x %d", nr, nc, why, M->a.nrow,
              M->a.ncol);
}

static inline int matrix_file(rd *r, const st_node *nd, const char *key, mat *M) {
  static const char *const known[] = {"file", NULL};
  char k1[KEY_LEN];
  const st_node *fn = NULL;
  const char *name = "";
  int st = check_keys(r, nd, key, known);
  if (!st) st = need(r, nd, key, "file", &fn);
  if (!st) st = string(r, fn, join(k1, key, "file"), &name);
  if (st) return st;
  char *full = path_join(r->dir, name), *text = NULL;
  if (!full) return CUP_ERR_NOMEM;
  size_t len = 0;
  st = read_text(full, &text, &len, r->files, NULL);   /* the bytes hashed are the bytes parsed */
  if (st == CUP_ERR_IO) st = fail(r, CUP_ERR_IO, fn, k1, "cannot open '%s': %s", full, strerror(errno));
  FILE *f = st ? NULL : len ? fmemopen(text, len, "r") : fopen("/dev/null", "r");   /* no empty fmemopen */
  if (!st && !f) st = CUP_ERR_NOMEM;
  char msg[CUP_ERRMSG_LEN];
  if (!st) st = mtx_read(f, name, &M->a, msg);
  if (f) fclose(f);
  free(text);
  free(full);
  return st == CUP_ERR_PARSE ? fail(r, st, fn, k1, "%s", msg) : st;
}

/* ---- vectors ------------------------------------------------------------- */

/* `want` numbers: an inline list or a single-column Matrix Market file.
 * `why` says where want comes from ("n = 3"). */
static inline int vector(rd *r, const st_node *nd, const char *key, int want, const char *why, double **out) {
  char k1[KEY_LEN], b[64];
  *out = NULL;
  if (nd->kind == ST_MAP && st_get(nd, "file", NULL)) {
    mat M = {0};
    int st = matrix(r, nd, key, &M);
    if (!st && (M.a.ncol != 1 || M.a.nrow != want))
      st = fail(r, CUP_ERR_DIM, nd, key, "expected a %d x 1 matrix (%s), got %d x %d", want, why, M.a.nrow,
                M.a.ncol);
    if (!st && !(*out = calloc((size_t)want, sizeof(double)))) st = CUP_ERR_NOMEM;
    for (int k = 0; !st && k < M.a.p[1]; k++) (*out)[M.a.i[k]] = M.a.x[k];
    mat_free(&M);
    return st;
  }
  if (nd->kind != ST_SEQ)
    return fail(r, CUP_ERR_PARSE, nd, key, "expected a list of %d numbers or {file: name.mtx} (got %s)", want,
                st_looks(nd, b, sizeof b));
  if (nd->len != want)
    return fail(r, CUP_ERR_DIM, nd, key, "expected %d numbers (%s), got %d", want, why, nd->len);
  double *v = calloc((size_t)want + 1, sizeof(double));
  if (!v) return CUP_ERR_NOMEM;
  for (int k = 0; k < want; k++) {
    int st = number(r, nd->item[k], joini(k1, key, k), &v[k]);
    if (st) { free(v); return st; }
  }
  *out = v;
  return CUP_OK;
}

/* ---- the metric ---------------------------------------------------------- */

/* A metric P at key: identity (absent or the word), a list of n positive
 * numbers (the diagonal, into *diag), or an n x n SPD matrix (inline or a
 * file; symmetric files are expanded; into *Pm). why says where n comes from. */
static inline int read_metric(rd *r, const st_node *nd, const char *key, int n, const char *why, mat *Pm,
                              double **diag, cup_metric *P) {
  char k1[KEY_LEN];
  *P = (cup_metric){CUP_METRIC_IDENTITY, NULL, {0}, 0};
  if (!nd) return CUP_OK;
  if (nd->kind == ST_SCALAR) {
    if (!nd->quoted && !strcmp(nd->text, "identity")) return CUP_OK;
    return fail(r, CUP_ERR_PARSE, nd, key, "expected identity, a list of %d positive numbers (the diagonal) "
                "or a %d x %d SPD matrix (got '%.40s')", n, n, n, nd->text);
  }
  if (nd->kind == ST_SEQ && nd->len && nd->item[0]->kind == ST_SCALAR) {
    int st = vector(r, nd, key, n, why, diag);
    for (int k = 0; !st && k < n; k++)
      if (!((*diag)[k] > 0))
        st = fail(r, CUP_ERR_NOT_SPD, nd->item[k], joini(k1, key, k), "must be > 0 (got %g)", (*diag)[k]);
    if (!st) *P = (cup_metric){CUP_METRIC_DIAGONAL, *diag, {0}, 0};
    return st;
  }
  int st = matrix(r, nd, key, Pm);
  if (!st) st = matrix_dims(r, Pm, key, n, n, why);
  if (!st) *P = (cup_metric){CUP_METRIC_SPARSE, NULL, mat_view(Pm), 0};
  return st;
}

/* ---- an input component ----------------------------------------------------- */

/* Reads component j of u: a term (a number, or a mapping with a type:
 * constant, sine, square, pwl), or a list of terms (their sum), added to u.
 * scene.c's reader of input:, handed to the readers of other keys. */
typedef int (*scene_component_fn)(rd *r, const st_node *nd, const char *key, cup_input *u, int j);

#endif

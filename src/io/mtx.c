/* mtx — see mtx.h. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include "catchup.h"
#include "util/linalg.h"
#include "mtx.h"

void mtx_free(mtx_csc *M) {
  free(M->p); free(M->i); free(M->x);
  memset(M, 0, sizeof *M);
}

/* CSC of a dense matrix with entry (i, j) at a[i*rs + j*cs]; zeros dropped. */
int mtx_from_dense(mtx_csc *M, int nr, int nc, const double *a, size_t rs, size_t cs) {
  size_t nnz = 0;
  for (int j = 0; j < nc; j++)
    for (int i = 0; i < nr; i++) nnz += a[i * rs + j * cs] != 0;
  M->nrow = nr; M->ncol = nc;
  M->p = malloc(sizeof(int) * ((size_t)nc + 1));
  M->i = malloc(sizeof(int) * (nnz + 1));
  M->x = malloc(sizeof(double) * (nnz + 1));
  if (!M->p || !M->i || !M->x) return CUP_ERR_NOMEM;
  int q = 0;
  M->p[0] = 0;
  for (int j = 0; j < nc; j++) {
    for (int i = 0; i < nr; i++) {
      double v = a[i * rs + j * cs];
      if (v != 0) { M->i[q] = i; M->x[q++] = v; }
    }
    M->p[j + 1] = q;
  }
  return CUP_OK;
}

typedef struct mm_head {
  int array, symmetric;
  long nrow, ncol, nnz;
} mm_head;

typedef struct mm_ctx {
  const char *name;
  long line;
  char *msg;
} mm_ctx;

static int mm_fail(const mm_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int mm_fail(const mm_ctx *c, const char *fmt, ...) {
  int w = c->line > 0 ? snprintf(c->msg, CUP_ERRMSG_LEN, "%s:%ld: ", c->name, c->line)
                      : snprintf(c->msg, CUP_ERRMSG_LEN, "%s: ", c->name);
  va_list ap;
  va_start(ap, fmt);
  if (w >= 0 && w < CUP_ERRMSG_LEN) vsnprintf(c->msg + w, CUP_ERRMSG_LEN - (size_t)w, fmt, ap);
  va_end(ap);
  return CUP_ERR_PARSE;
}

static int mm_banner(mm_ctx *c, const char *line, mm_head *h) {
  char obj[16], fmt[16], field[16], sym[16];
  /* the banner is case-sensitive (the format's spec; CHOLMOD's reader fails
   * on "%%matrixmarket" and leaks a block), the keywords are not */
  if (strncmp(line, "%%MatrixMarket", 14) != 0 ||
      sscanf(line + 14, "%15s %15s %15s %15s", obj, fmt, field, sym) != 4)
    return mm_fail(c, "not a Matrix Market file (the first line must be "
                      "'%%%%MatrixMarket matrix coordinate real general' or similar)");
  if (strcasecmp(obj, "matrix") != 0) return mm_fail(c, "object '%s' is not 'matrix'", obj);
  if (strcasecmp(fmt, "coordinate") && strcasecmp(fmt, "array"))
    return mm_fail(c, "format '%s': expected coordinate or array", fmt);
  if (strcasecmp(field, "real") && strcasecmp(field, "integer"))
    return mm_fail(c, "field '%s': only real or integer matrices are supported", field);
  if (strcasecmp(sym, "general") && strcasecmp(sym, "symmetric"))
    return mm_fail(c, "symmetry '%s': only general or symmetric matrices are supported", sym);
  h->array = strcasecmp(fmt, "array") == 0;
  h->symmetric = strcasecmp(sym, "symmetric") == 0;
  return CUP_OK;
}

/* Whitespace-separated tokens of a line (at most max). */
static int tokens(char *line, char **tok, int max) {
  int n = 0;
  char *save = NULL;
  for (char *s = strtok_r(line, " \t\r\n", &save); s; s = strtok_r(NULL, " \t\r\n", &save)) {
    if (n < max) tok[n] = s;
    n++;
  }
  return n;
}

static int mm_long(const char *s, long *v) {
  char *end;
  errno = 0;
  *v = strtol(s, &end, 10);
  return !errno && end != s && !*end;
}

static int mm_size(mm_ctx *c, char *line, mm_head *h) {
  char *t[3];
  int want = h->array ? 2 : 3, n = tokens(line, t, 3);
  if (n != want || !mm_long(t[0], &h->nrow) || !mm_long(t[1], &h->ncol) || (!h->array && !mm_long(t[2], &h->nnz)))
    return mm_fail(c, "expected the size line '%s'", h->array ? "ROWS COLS" : "ROWS COLS ENTRIES");
  if (h->nrow < 1 || h->ncol < 1 || h->nrow > INT_MAX / 2 || h->ncol > INT_MAX / 2 || (!h->array && h->nnz < 0))
    return mm_fail(c, "size %ld x %ld is out of range", h->nrow, h->ncol);
  if (h->symmetric && h->nrow != h->ncol)
    return mm_fail(c, "a symmetric matrix must be square (got %ld x %ld)", h->nrow, h->ncol);
  if (h->array) h->nnz = h->symmetric ? h->nrow * (h->nrow + 1) / 2 : h->nrow * h->ncol;
  return CUP_OK;
}

/* (i, j), 1-based, of the k-th value of an array file (column-major; the
 * lower triangle only when symmetric). */
static void mm_array_pos(const mm_head *h, long k, long *i, long *j) {
  long col = 0, len = h->nrow;
  while (h->symmetric && k >= len) { k -= len; col++; len--; }
  if (h->symmetric) { *i = col + k + 1; *j = col + 1; return; }
  *i = k % h->nrow + 1;
  *j = k / h->nrow + 1;
}

static int mm_value(mm_ctx *c, const char *tok, long i, long j) {
  char *end;
  double v = strtod(tok, &end);
  if (end == tok || *end) return mm_fail(c, "entry (%ld,%ld): '%.30s' is not a number", i, j, tok);
  if (!isfinite(v)) {
    c->line = 0;                               /* the spec's "file.mtx: entry (i,j) is nan" */
    return mm_fail(c, "entry (%ld,%ld) is %s", i, j, isnan(v) ? "nan" : v > 0 ? "inf" : "-inf");
  }
  return CUP_OK;
}

static int mm_entry(mm_ctx *c, char *line, const mm_head *h, long *count) {
  char *t[3];
  int n = tokens(line, t, 3);
  long i, j;
  if (h->array) {
    if (n != 1) return mm_fail(c, "expected one value per line");
    if (*count >= h->nnz) return mm_fail(c, "more values than the %ld the size line declares", h->nnz);
    mm_array_pos(h, (*count)++, &i, &j);
    return mm_value(c, t[0], i, j);
  }
  if (n != 3 || !mm_long(t[0], &i) || !mm_long(t[1], &j))
    return mm_fail(c, "expected an entry 'ROW COL VALUE'");
  if (i < 1 || i > h->nrow || j < 1 || j > h->ncol)
    return mm_fail(c, "entry (%ld,%ld) is outside the %ld x %ld matrix", i, j, h->nrow, h->ncol);
  if (++*count > h->nnz) return mm_fail(c, "more entries than the %ld the size line declares", h->nnz);
  return mm_value(c, t[2], i, j);
}

static int mm_check(mm_ctx *c, FILE *f, mm_head *h) {
  char *line = NULL;
  size_t cap = 0;
  long count = 0;
  int st = CUP_OK, have_size = 0;
  c->line = 0;
  while (!st && getline(&line, &cap, f) >= 0) {
    c->line++;
    if (c->line == 1) { st = mm_banner(c, line, h); continue; }
    const char *s = line + strspn(line, " \t\r\n");
    if (!*s || *s == '%') continue;
    if (!have_size) { st = mm_size(c, line, h); have_size = 1; continue; }
    st = mm_entry(c, line, h, &count);
  }
  free(line);
  if (st) return st;
  if (c->line == 0) return mm_fail(c, "empty file, not a Matrix Market file");
  c->line = 0;
  if (!have_size) return mm_fail(c, "no size line");
  if (count != h->nnz) return mm_fail(c, "the size line declares %ld entries but the file has %ld", h->nnz, count);
  return CUP_OK;
}

static int from_cholmod(mtx_csc *M, cholmod_sparse *A) {
  size_t nc = A->ncol, nnz = (size_t)((int *)A->p)[nc];
  M->nrow = (int)A->nrow; M->ncol = (int)nc;
  M->p = malloc(sizeof(int) * (nc + 1));
  M->i = malloc(sizeof(int) * (nnz + 1));
  M->x = malloc(sizeof(double) * (nnz + 1));
  if (!M->p || !M->i || !M->x) return CUP_ERR_NOMEM;
  memcpy(M->p, A->p, sizeof(int) * (nc + 1));
  memcpy(M->i, A->i, sizeof(int) * nnz);
  memcpy(M->x, A->x, sizeof(double) * nnz);
  return CUP_OK;
}

/* CHOLMOD reads the checked file: sparse with both triangles, or dense. */
static int mm_read(mm_ctx *c, FILE *f, mtx_csc *M) {
  cholmod_common cm;
  if (la_cholmod_start(&cm)) return mm_fail(c, "CHOLMOD start failed");
  int mtype = -1, st = CUP_OK;
  void *X = cholmod_read_matrix(f, 1, &mtype, &cm);
  if (X && mtype == CHOLMOD_SPARSE) {
    cholmod_sparse *A = X;
    if (!A->sorted) cholmod_sort(A, &cm);
    st = A->packed && A->stype == 0 && A->xtype == CHOLMOD_REAL ? from_cholmod(M, A)
                                                                 : mm_fail(c, "unexpected CHOLMOD matrix layout");
    cholmod_free_sparse(&A, &cm);
  } else if (X && mtype == CHOLMOD_DENSE) {
    cholmod_dense *D = X;
    st = mtx_from_dense(M, (int)D->nrow, (int)D->ncol, D->x, 1, D->d);
    cholmod_free_dense(&D, &cm);
  } else {
    if (X && mtype == CHOLMOD_TRIPLET) cholmod_free_triplet((cholmod_triplet **)&X, &cm);
    st = mm_fail(c, "CHOLMOD could not read it (status %d)", cm.status);
  }
  cholmod_finish(&cm);
  return st;
}

int mtx_read(FILE *f, const char *name, mtx_csc *M, char *msg) {
  mm_ctx c = {name, 0, msg};
  mm_head h = {0};
  int st = mm_check(&c, f, &h);
  if (!st) {
    rewind(f);
    st = mm_read(&c, f, M);
  }
  return st;
}

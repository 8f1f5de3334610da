/* read_text — see read_text.h. */
#define _XOPEN_SOURCE 700             /* realpath */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include "catchup.h"
#include "util/linalg.h"
#include "read_text.h"
#include "sha256.h"
#include "util/path.h"

void file_list_free(file_list *l) {
  if (!l) return;
  for (int k = 0; k < l->n; k++) free(l->e[k].path);
  free(l->e);
  memset(l, 0, sizeof *l);
}

static int holds(const file_list *l, const file_entry *f) {
  for (int k = 0; k < l->n; k++)
    if (!strcmp(l->e[k].path, f->path) && !strcmp(l->e[k].sha256, f->sha256)) return 1;
  return 0;
}

static int add(file_list *l, const file_entry *f) {
  if (holds(l, f)) return CUP_OK;
  char *path = strdup(f->path);
  if (!path || la_grow(&l->e, &l->cap, l->n, sizeof *l->e, 4)) { free(path); return CUP_ERR_NOMEM; }
  l->e[l->n] = *f;
  l->e[l->n++].path = path;
  return CUP_OK;
}

int file_list_merge(file_list *l, const file_list *src) {
  int st = CUP_OK;
  for (int k = 0; src && k < src->n && !st; k++) st = add(l, &src->e[k]);
  return st;
}

/* realpath(path), or realpath of its folder joined with its last name when
 * path does not exist (yet); NULL if neither resolves. */
static char *canonical(const char *path) {
  char *full = realpath(path, NULL);
  if (full) return full;
  const char *base = path_base(path);
  char *dir = NULL, *d = path_dir(path, &dir) ? NULL : realpath(dir ? dir : ".", NULL);
  free(dir);
  if (!d) return NULL;
  size_t n = strlen(d) + strlen(base) + 2;
  full = malloc(n);
  if (full) snprintf(full, n, "%s%s%s", d, strcmp(d, "/") ? "/" : "", base);
  free(d);
  return full;
}

int file_list_check_output(const file_list *l, const char *out, char *errmsg) {
  struct stat so, si;
  int out_exists = stat(out, &so) == 0;
  char *co = canonical(out);
  int st = CUP_OK;
  for (int k = 0; l && k < l->n && !st; k++) {
    const file_entry *e = &l->e[k];
    const char *why = NULL;
    char *ci = co ? canonical(e->path) : NULL;
    if (ci && !strcmp(co, ci)) why = "the same path";
    else if (out_exists && stat(e->path, &si) == 0 && si.st_dev == so.st_dev && si.st_ino == so.st_ino)
      why = "the same file";
    else if (out_exists && (e->dev || e->ino) && e->dev == (unsigned long long)so.st_dev &&
             e->ino == (unsigned long long)so.st_ino)
      why = "the file it was when read";
    free(ci);
    if (why)
      st = fail_fmt(errmsg, CUP_ERR_ARG, "the output %s is %s, which the run reads (%s): writing there would "
                    "destroy an input; nothing was written", out, e->path, why);
  }
  free(co);
  return st;
}

char *file_list_text(const file_list *l) {
  size_t len = 1;
  for (int k = 0; l && k < l->n; k++) len += 64 + 3 + 2 * strlen(l->e[k].path);
  char *s = malloc(len), *w = s;
  for (int k = 0; s && l && k < l->n; k++) {
    w += sprintf(w, "%s  ", l->e[k].sha256);
    for (const char *p = l->e[k].path; *p; p++) {
      if (*p == '\n' || *p == '\\') *w++ = '\\';
      *w++ = *p == '\n' ? 'n' : *p;
    }
    *w++ = '\n';
  }
  if (s) *w = '\0';
  return s;
}

int file_list_compare(const file_list *l, const char *stored, const char *what, char *errmsg,
                      size_t size) {
  const char *line = stored;
  int k = 0;
  for (; line && *line && k < l->n; k++) {
    const file_entry *e = &l->e[k];
    if (strncmp(line, e->sha256, 64) != 0) {
      snprintf(errmsg, size, "%s changed since %s was made (SHA-256 %.12s... then, %.12s... now)", e->path, what,
               line, e->sha256);
      return CUP_ERR_ARG;
    }
    line = strchr(line, '\n');
    if (line) line++;
  }
  if (k < l->n) {
    snprintf(errmsg, size, "%s is read now but was not when %s was made (a scene or netlist names other files)",
             l->e[k].path, what);
    return CUP_ERR_ARG;
  }
  if (line && *line) {
    const char *end = strchr(line, '\n');
    int n = end ? (int)(end - line) : (int)strlen(line);
    snprintf(errmsg, size, "%.*s was read when %s was made and is not now (a scene or netlist names other files)",
             n > 66 ? n - 66 : 0, n > 66 ? line + 66 : "", what);
    return CUP_ERR_ARG;
  }
  return CUP_OK;
}

int read_text(const char *path, char **text, size_t *len, file_list *files, char *errmsg) {
  FILE *f = fopen(path, "rb");
  if (!f) return fail_fmt(errmsg, CUP_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
  struct stat sb;
  int have_id = fstat(fileno(f), &sb) == 0;
  size_t cap = 4096, n = 0, got;
  char *buf = malloc(cap);
  while (buf && (got = fread(buf + n, 1, cap - n, f)) > 0) {
    n += got;
    if (n == cap) {
      char *nb = realloc(buf, cap *= 2);
      if (!nb) { free(buf); buf = NULL; }
      buf = nb;
    }
  }
  int err = ferror(f);
  fclose(f);
  if (!buf) return fail_fmt(errmsg, CUP_ERR_NOMEM, "%s: out of memory", path);
  if (err) { free(buf); return fail_fmt(errmsg, CUP_ERR_IO, "%s: read error", path); }
  if (files) {
    file_entry e = {(char *)path, "", have_id ? (unsigned long long)sb.st_dev : 0,
                        have_id ? (unsigned long long)sb.st_ino : 0};
    sha256_hex(buf, n, e.sha256);
    if (add(files, &e)) { free(buf); return fail_fmt(errmsg, CUP_ERR_NOMEM, "%s: out of memory", path); }
  }
  *text = buf;
  *len = n;
  return CUP_OK;
}

int load_args(const char *what, const char *item, int has_out, const void *src,
              const char *const *list, int n, char *errmsg) {
  if (errmsg) errmsg[0] = '\0';
  if (!has_out) return fail_fmt(errmsg, CUP_ERR_ARG, "%s: output pointer is NULL", what);
  if (!src) return fail_fmt(errmsg, CUP_ERR_ARG, "%s: path or text is NULL", what);
  if (n < 0 || (n > 0 && !list)) return fail_fmt(errmsg, CUP_ERR_ARG, "%s: %d %ss but no list", what, n, item);
  for (int k = 0; k < n; k++)
    if (!list[k]) return fail_fmt(errmsg, CUP_ERR_ARG, "%s: %s %d is NULL", what, item, k);
  return CUP_OK;
}

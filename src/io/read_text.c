/* read_text — see read_text.h. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include "catchup.h"
#include "util/linalg.h"
#include "read_text.h"
#include "sha256.h"

void cup_file_list_free(cup_file_list *l) {
  if (!l) return;
  for (int k = 0; k < l->n; k++) free(l->e[k].path);
  free(l->e);
  memset(l, 0, sizeof *l);
}

static int holds(const cup_file_list *l, const cup_file_entry *f) {
  for (int k = 0; k < l->n; k++)
    if (!strcmp(l->e[k].path, f->path) && !strcmp(l->e[k].sha256, f->sha256)) return 1;
  return 0;
}

static int add(cup_file_list *l, const cup_file_entry *f) {
  if (holds(l, f)) return CUP_OK;
  char *path = strdup(f->path);
  if (!path || cup_grow(&l->e, &l->cap, l->n, sizeof *l->e, 4)) { free(path); return CUP_ERR_NOMEM; }
  l->e[l->n] = *f;
  l->e[l->n++].path = path;
  return CUP_OK;
}

int cup_file_list_merge(cup_file_list *l, const cup_file_list *src) {
  int st = CUP_OK;
  for (int k = 0; src && k < src->n && !st; k++) st = add(l, &src->e[k]);
  return st;
}

int cup_read_text(const char *path, char **text, size_t *len, cup_file_list *files, char *errmsg) {
  FILE *f = fopen(path, "rb");
  if (!f) return cup_fail(errmsg, CUP_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
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
  if (!buf) return cup_fail(errmsg, CUP_ERR_NOMEM, "%s: out of memory", path);
  if (err) { free(buf); return cup_fail(errmsg, CUP_ERR_IO, "%s: read error", path); }
  if (files) {
    cup_file_entry e = {(char *)path, "", have_id ? (unsigned long long)sb.st_dev : 0,
                        have_id ? (unsigned long long)sb.st_ino : 0};
    cup_sha256_hex(buf, n, e.sha256);
    if (add(files, &e)) { free(buf); return cup_fail(errmsg, CUP_ERR_NOMEM, "%s: out of memory", path); }
  }
  *text = buf;
  *len = n;
  return CUP_OK;
}

int cup_load_args(const char *what, const char *item, int has_out, const void *src,
                  const char *const *list, int n, char *errmsg) {
  if (errmsg) errmsg[0] = '\0';
  if (!has_out) return cup_fail(errmsg, CUP_ERR_ARG, "%s: output pointer is NULL", what);
  if (!src) return cup_fail(errmsg, CUP_ERR_ARG, "%s: path or text is NULL", what);
  if (n < 0 || (n > 0 && !list)) return cup_fail(errmsg, CUP_ERR_ARG, "%s: %d %ss but no list", what, n, item);
  for (int k = 0; k < n; k++)
    if (!list[k]) return cup_fail(errmsg, CUP_ERR_ARG, "%s: %s %d is NULL", what, item, k);
  return CUP_OK;
}

/* read_text — see read_text.h. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "util/linalg.h"
#include "read_text.h"

int cup_read_text(const char *path, char **text, size_t *len, char *errmsg) {
  FILE *f = fopen(path, "rb");
  if (!f) return cup_fail(errmsg, CUP_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
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

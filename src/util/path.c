/* path — see path.h. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup/status.h"
#include "path.h"

char *path_join(const char *dir, const char *name) {
  if (name[0] == '/' || !dir || !dir[0]) return strdup(name);
  size_t len = strlen(dir) + strlen(name) + 2;
  char *s = malloc(len);
  if (s) snprintf(s, len, "%s/%s", dir, name);
  return s;
}

int path_dir(const char *path, char **dir) {
  const char *slash = strrchr(path, '/');
  *dir = slash ? strndup(path, slash == path ? 1 : (size_t)(slash - path)) : NULL;
  return slash && !*dir ? CUP_ERR_NOMEM : CUP_OK;
}

const char *path_base(const char *path) {
  const char *slash = strrchr(path, '/');
  return slash ? slash + 1 : path;
}

char *path_stem(const char *path) {
  const char *base = path_base(path), *dot = strrchr(base, '.');
  return strndup(base, dot && dot != base ? (size_t)(dot - base) : strlen(base));
}

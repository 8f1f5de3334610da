/* read_text — a whole file into memory, and the argument checks the readers
 * of scene files and netlists share. Internal to the library. */
#ifndef CUP_READ_TEXT_H
#define CUP_READ_TEXT_H

#include <stddef.h>

/* The bytes of path into *text (malloc'd; not NUL-terminated beyond len)
 * and *len. CUP_ERR_IO ("PATH: cannot open: reason") or CUP_ERR_NOMEM with
 * the message in errmsg (CUP_ERRMSG_LEN bytes, may be NULL). */
int cup_read_text(const char *path, char **text, size_t *len, char *errmsg);

/* The arguments common to the loaders (what: "scene" or "netlist"; item:
 * what the list holds, "override" or "set"): CUP_ERR_ARG with a message when
 * the output pointer is absent (has_out 0), src (a path or text) is NULL, or
 * the list of n items is inconsistent or holds a NULL. Clears errmsg. */
int cup_load_args(const char *what, const char *item, int has_out, const void *src,
                  const char *const *list, int n, char *errmsg);

#endif

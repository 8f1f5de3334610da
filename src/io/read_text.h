/* read_text — a whole file into memory, for the readers of scene files and
 * netlists. Internal to the library. */
#ifndef CUP_READ_TEXT_H
#define CUP_READ_TEXT_H

#include <stddef.h>

/* The bytes of path into *text (malloc'd; not NUL-terminated beyond len)
 * and *len. CUP_ERR_IO ("PATH: cannot open: reason") or CUP_ERR_NOMEM with
 * the message in errmsg (CUP_ERRMSG_LEN bytes, may be NULL). */
int cup_read_text(const char *path, char **text, size_t *len, char *errmsg);

#endif

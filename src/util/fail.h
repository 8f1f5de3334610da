/* fail — the library's error messages: a status and one line of text in
 * the caller's errmsg buffer (CUP_ERRMSG_LEN bytes), the library's only
 * way of saying what went wrong (it never prints). Internal. */
#ifndef CUP_FAIL_H
#define CUP_FAIL_H

#include <stdarg.h>

/* Format an error message into buf (may be NULL); returns status. */
int fail_fmt(char *buf, int status, const char *fmt, ...)
  __attribute__((format(printf, 3, 4)));

/* The rest of a message after a prefix of w characters already in buf
 * (CUP_ERRMSG_LEN bytes; w as snprintf returned it), with newlines turned to
 * spaces so that the whole message is one line; returns status. */
int fail_vfmt_at(char *buf, int w, int status, const char *fmt, va_list ap)
  __attribute__((format(printf, 4, 0)));

#endif

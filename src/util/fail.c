/* fail — see fail.h. */
#include <stdarg.h>
#include <stdio.h>
#include "catchup/sparse.h"   /* CUP_ERRMSG_LEN */
#include "fail.h"

int fail_fmt(char *buf, int status, const char *fmt, ...) {
  if (buf) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, CUP_ERRMSG_LEN, fmt, ap);
    va_end(ap);
  }
  return status;
}

int fail_vfmt_at(char *buf, int w, int status, const char *fmt, va_list ap) {
  if (!buf) return status;
  size_t cap = CUP_ERRMSG_LEN;
  if (w >= 0 && (size_t)w < cap) vsnprintf(buf + w, cap - (size_t)w, fmt, ap);
  for (char *p = buf; *p; p++)                  /* one line, always */
    if (*p == '\n' || *p == '\r') *p = ' ';
  return status;
}

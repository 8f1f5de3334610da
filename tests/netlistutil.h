/* What the netlist tests share (test_netlist.c, test_netlist_ext.c): a
 * netlist from text that must load, or must fail with a one-line message;
 * a message's content; an entry of a CSC matrix. Needs cmocka.h before it. */
#ifndef CUP_NETLISTUTIL_H
#define CUP_NETLISTUTIL_H

#include <string.h>
#include "catchup.h"
#include "util/linalg.h"   /* la_sparse */

static inline cup_netlist *text_ok(const char *text, const char *const *sets, int nsets) {
  char err[CUP_ERRMSG_LEN] = "";
  cup_netlist *nl = NULL;
  int st = cup_netlist_load_string(&nl, text, "t.cir", sets, nsets, err);
  if (st) fail_msg("loading failed (%d): %s\n%s", st, err, text);
  return nl;
}

/* The message, which names no line break; the netlist left NULL. */
static inline const char *text_bad(const char *text, const char *const *sets, int nsets) {
  static char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = (cup_netlist *)&err;
  int st = cup_netlist_load_string(&nl, text, "t.cir", sets, nsets, err);
  if (st == CUP_OK) fail_msg("loaded but should not have:\n%s", text);
  assert_null(nl);
  assert_null(strchr(err, '\n'));
  return err;
}

static inline void assert_contains(const char *msg, const char *want) {
  if (!strstr(msg, want)) fail_msg("message\n  %s\ndoes not contain\n  %s", msg, want);
}

/* Entry (r, c) of an owned CSC (0 when absent). */
static inline double at(const la_sparse *S, int r, int c) {
  if (!S->p || c >= S->ncol) return 0;
  for (int k = S->p[c]; k < S->p[c + 1]; k++)
    if (S->i[k] == r) return S->x[k];
  return 0;
}

#endif

/* Internal layout of cup_lcs. */
#ifndef CUP_LCS_IMPL_H
#define CUP_LCS_IMPL_H

#include "catchup/lcs.h"
#include "util/linalg.h"

/* "rows D1, D3" (or "rows 0, 2" without names) for messages, into buf. */
void lcs_rows_text(const struct cup_lcs *L, const int *rows, int k, char *buf, unsigned long size);
/* CUP_ERR_UNSUPPORTED for the scheme named, which needs P B = C^T, on an
 * LCS that keeps its B (keep_B: controlled sources drive the diodes' rows);
 * why: what of the scheme needs it. The schemes' one wording of it. */
int lcs_needs_reciprocal(const char *scheme, const char *why, char *errmsg);

struct cup_lcs {
  int n, m, p;
  int has_A, has_E, has_G;
  la_sparse A, E, G;   /* present when has_*: n x n, n x p, m x p */
  double *F;            /* m (in L's block) */
  cup_polyset *K;       /* {x : C x + F >= 0}, metric P */
  int fixed;            /* G absent or zero */
  /* D != 0: the LCS is not a sweeping process; the theta and adaptive schemes run it */
  int has_D;            /* D given with a nonzero entry, or keep_B: B and D as given */
  int keep_B;           /* B kept as given (P B != C^T allowed): the reason when D = 0 */
  la_sparse B, D;      /* has_D: n x m and m x m as given (D may be all zero) */
  char **row_names;     /* m names for messages, or NULL (the array in L's block) */
  int names_lent;       /* row_names' strings are the caller's (lcs_create_lent), not freed */
};

/* cup_lcs_create, with the row names' strings not copied (the array is):
 * the caller's, which must outlive the LCS (a switch configuration's, its
 * elements' names: a strdup and a free less a row). */
int lcs_create_lent(struct cup_lcs **out, const cup_lcs_desc *d, char *errmsg);

#endif

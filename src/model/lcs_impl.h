/* Internal layout of cup_lcs. */
#ifndef CUP_LCS_IMPL_H
#define CUP_LCS_IMPL_H

#include "catchup/lcs.h"
#include "util/linalg.h"

struct cup_lcs {
  int n, m, p;
  int has_A, has_E, has_G;
  cup_sparse A, E, G;   /* present when has_*: n x n, n x p, m x p */
  double *F;            /* m */
  cup_polyset *K;       /* {x : C x + F >= 0}, metric P */
  int fixed;            /* G absent or zero */
};

#endif

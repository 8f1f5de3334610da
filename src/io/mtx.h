/* mtx — Matrix Market files for the scene loader. CHOLMOD's reader takes
 * "1 1 abc" as a pattern entry of value 1 and stops quietly after the
 * declared count, so each file is checked line by line first: the banner,
 * the size line, every entry's indices and value, and the count. Then
 * CHOLMOD builds the matrix (symmetric files expanded to both triangles,
 * duplicates summed). Internal to the library. */
#ifndef CUP_MTX_H
#define CUP_MTX_H

#include <stddef.h>
#include <stdio.h>

/* An owned CSC matrix, 0-based, rows increasing in each column. */
typedef struct mtx_csc {
  int nrow, ncol;
  int *p, *i;
  double *x;
} mtx_csc;

void mtx_free(mtx_csc *M);
/* CSC of a dense matrix with entry (i, j) at a[i*rs + j*cs]; zeros dropped.
 * CUP_OK or CUP_ERR_NOMEM (then mtx_free releases what M holds). */
int mtx_from_dense(mtx_csc *M, int nr, int nc, const double *a, size_t rs, size_t cs);
/* Check the open file f, then read it. name is the file as the scene names
 * it. A malformed file gives CUP_ERR_PARSE with "NAME:LINE: problem" (or
 * "NAME: problem") in msg (CUP_ERRMSG_LEN bytes), out of memory
 * CUP_ERR_NOMEM; M holds what was allocated either way. */
int mtx_read(FILE *f, const char *name, mtx_csc *M, char *msg);

#endif

/* catchup/sparse.h — sparse matrix views passed into the library. */
#ifndef CATCHUP_SPARSE_H
#define CATCHUP_SPARSE_H

#ifdef __cplusplus
extern "C" {
#endif

/** Length of the error-message buffers that create functions fill. */
#define CUP_ERRMSG_LEN 256

/** A compressed-sparse-column matrix, 0-based (CHOLMOD's layout), as a view:
 *  the library copies what it needs at creation and never keeps the pointers.
 *  Row indices must be strictly increasing within each column. */
typedef struct cup_csc {
  int nrow;              /**< number of rows */
  int ncol;              /**< number of columns */
  const int *colptr;     /**< ncol+1 column starts; colptr[0] = 0 */
  const int *rowind;     /**< colptr[ncol] row indices, 0-based */
  const double *values;  /**< colptr[ncol] values */
} cup_csc;

#ifdef __cplusplus
}
#endif
#endif

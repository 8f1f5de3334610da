/* catchup/sparse.h — sparse matrix views passed into the library. */
#ifndef CATCHUP_SPARSE_H
#define CATCHUP_SPARSE_H

#ifdef __cplusplus
extern "C" {
#endif

/** Length of the error-message buffers that create and load functions fill:
 *  room for two paths of PATH_MAX (a file and a file it names) and the rest
 *  of the message, so that no message is cut, however deep the folders.
 *  (It was 256: an ABI change; rebuild what calls the library.) */
#define CUP_ERRMSG_LEN 12288
/** Length of cup_run_info.message (integrator.h). A run's messages name a
 *  step, a time, rows and values, never a path: this holds the longest of
 *  them whole. (The field had 256 bytes: an ABI change.) */
#define CUP_RUN_MSG_LEN 1024

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

/* catchup/polyset.h — sparse polyhedral sets K = {x : C x + g >= 0} with a
 * metric P (diagonal or sparse SPD). A polyset is read-only after creation
 * and may be shared between projectors, threads and ranks. */
#ifndef CATCHUP_POLYSET_H
#define CATCHUP_POLYSET_H

#include "catchup/export.h"
#include "catchup/sparse.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cup_polyset cup_polyset;

typedef enum cup_metric_kind {
  CUP_METRIC_IDENTITY = 0,  /**< P = I */
  CUP_METRIC_DIAGONAL = 1,  /**< P = diag(d), d > 0 */
  CUP_METRIC_SPARSE = 2     /**< P sparse SPD, factored once by CHOLMOD */
} cup_metric_kind;

/** The metric P of the projection (the paper's P with P B = C^T). */
typedef struct cup_metric {
  cup_metric_kind kind;  /**< which of the fields below is used */
  const double *diag;    /**< DIAGONAL: dim positive entries */
  cup_csc matrix;        /**< SPARSE: dim x dim, both triangles or lower only */
  int lower_only;        /**< SPARSE: 1 if only the lower triangle is stored */
} cup_metric;

/** Create K = {x in R^dim : C x + g >= 0}. C is m x dim (copied); g has m
 *  entries (copied; NULL means 0) and is the default offset that projectors
 *  start from; P may be NULL (identity). Validates sizes, finiteness, symmetry
 *  and positive definiteness of P. On failure *K is NULL, nothing is leaked
 *  and errmsg (CUP_ERRMSG_LEN bytes, may be NULL) names the problem. */
CUP_API int cup_polyset_create(cup_polyset **K, const cup_csc *C, const double *g,
                               const cup_metric *P, char *errmsg);

/** Free and set *K to NULL (a NULL *K is fine). */
CUP_API void cup_polyset_free(cup_polyset **K);

CUP_API int cup_polyset_dim(const cup_polyset *K);   /**< number of variables */
CUP_API int cup_polyset_rows(const cup_polyset *K);  /**< number of constraints m */

/** Guaranteed upper bound L >= lambda_max(C P^-1 C^T) used as 1/step by the
 *  projected-gradient methods (Collatz-Wielandt bound on |C| P^-1 |C|^T,
 *  tightened by a dense eigenvalue bound for small sets). */
CUP_API double cup_polyset_lipschitz(const cup_polyset *K);

/** The P-norm sqrt(v^T P v) of a vector of dim entries. */
CUP_API double cup_polyset_norm(const cup_polyset *K, const double *v);

/** 1 if x is certainly in {C x + g >= 0} (each row checked with a bound on
 *  its rounding error), 0 otherwise. g NULL means the default offset. */
CUP_API int cup_polyset_contains(const cup_polyset *K, const double *g, const double *x);

/** A direction d with C d > 0 (so x + t d enters K for t large), if one was
 *  found at creation; NULL otherwise. Used to certify distances. */
CUP_API const double *cup_polyset_interior_direction(const cup_polyset *K);

#ifdef __cplusplus
}
#endif
#endif

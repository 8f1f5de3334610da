/* catchup/projector.h — certified (eps, eta)-approximate projections onto a
 * polyset in the P-metric (paper, Sec. 2 definition and Sec. 7 method).
 *
 * z is an (eps, eta)-approximate projection of x onto K when
 *     ||x - z||_P^2 < d_K(x)^2 + eps   and   d_K(z) <= eta
 * (z may lie outside K). Every return carries certified bounds: eps_cert from
 * weak duality (a dual point lambda >= 0 gives d_K(x)^2 >= 2 q(lambda)), and
 * eta_cert from an exactly feasible point v found on a segment from z or by a
 * push along a direction into K; eta_cert bounds the true distance d_K(z), not
 * the raw constraint violation.
 *
 * The one public way to project onto a polyset; cup_setproj (catchup/set.h)
 * onto a set of kind CUP_SET_POLYSET is a thin wrapper over this one. */
#ifndef CATCHUP_PROJECTOR_H
#define CATCHUP_PROJECTOR_H

#include "catchup/export.h"
#include "catchup/polyset.h"
#include "catchup/projection.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cup_projector cup_projector;

/** Options; fill with cup_projector_options_default() and change fields. */
typedef struct cup_projector_options {
  cup_proj_method method; /**< CUP_PROJ_AUTO */
  double eps_abs;         /**< target eps = eps_abs + eps_rel * S^2 (S: scale) */
  double eps_rel;         /**< default 1e-10 */
  double eta_abs;         /**< target eta = eta_abs + eta_rel * S */
  double eta_rel;         /**< default 1e-10 */
  int max_iter;           /**< dual iterations (first-order) per call; 100000 */
  int warm_start;         /**< start from the previous lambda; 1 */
  int return_feasible;    /**< return the exactly feasible point v instead of z; 0 */
  double lipschitz;       /**< step 1/L uses this L if > 0 (must bound lambda_max(C P^-1 C^T)); 0 = guaranteed bound */
  const double *feasible_point; /**< a known point of K for the default offset (copied), or NULL */
  int factor_updates;     /**< sparse exact path with a diagonal P: update the factorization
                               row by row when few rows change (1, default), or always
                               refactor (0: strictly allocation-free; with 1, CHOLMOD's row
                               update may allocate a temporary on factors of ~10^4+ rows).
                               Only where the factor of all of C P^-1 C^T is at most twice
                               that matrix (chains, small sets); otherwise (crowds) the
                               factor of the free rows is packed in that much room and
                               always refactored */
} cup_projector_options;

CUP_API void cup_projector_options_default(cup_projector_options *opt);

/** Create a projector onto K; allocates all workspace (cup_project does not
 *  allocate). The projector keeps a pointer to K, which must outlive it. */
CUP_API int cup_projector_create(cup_projector **p, const cup_polyset *K,
                                 const cup_projector_options *opt, char *errmsg);
CUP_API void cup_projector_free(cup_projector **p);

/** Replace the offset g (m entries, copied) for the following projections:
 *  K(t) = {x : C x + g(t) >= 0} with g(t) = G u(t) + F. */
CUP_API int cup_projector_set_offset(cup_projector *p, const double *g);
/** Change the absolute/relative tolerances for the following projections. */
CUP_API int cup_projector_set_tolerances(cup_projector *p, double eps_abs, double eps_rel,
                                         double eta_abs, double eta_rel);
/** Offer a point believed to be in K(current offset); it is checked (with a
 *  rounding bound) and used as an anchor for eta certificates if feasible.
 *  Returns 1 if accepted. */
CUP_API int cup_projector_offer_feasible(cup_projector *p, const double *w);
/** Forget the warm start. */
CUP_API void cup_projector_reset(cup_projector *p);

/** Project x onto K in the P-metric: z (dim entries; may alias x) and info
 *  (may be NULL). Returns CUP_OK when (eps_target, eta_target) are certified,
 *  CUP_WARN_NOT_CERTIFIED with the bounds reached otherwise,
 *  CUP_ERR_EMPTY_SET with a Farkas certificate (cup_projector_farkas),
 *  CUP_ERR_NONFINITE for a NaN/Inf in x, CUP_ERR_DIVERGED if an iterate
 *  became non-finite. On an error z is left unchanged. */
CUP_API int cup_project(cup_projector *p, const double *x, double *z, cup_proj_info *info);

/** Multipliers lambda (m entries) of the last projection (0 after a skip). */
CUP_API const double *cup_projector_lambda(const cup_projector *p);
/** An exactly feasible point v of K found while certifying the last
 *  projection (eta_cert = ||z - v||_P), or NULL if none was needed/found. */
CUP_API const double *cup_projector_feasible(const cup_projector *p);
/** After CUP_ERR_EMPTY_SET: y >= 0 (m entries) with C^T y ~ 0 and g^T y < 0. */
CUP_API const double *cup_projector_farkas(const cup_projector *p);

/** The name of a method in CUP_PROJ_METHOD_LIST ("auto", ...); "unknown" otherwise. */
CUP_API const char *cup_proj_method_name(int method);
/** A name of CUP_PROJ_METHOD_LIST -> its value; -1 if unknown. */
CUP_API int cup_proj_method_parse(const char *name);

#ifdef __cplusplus
}
#endif
#endif

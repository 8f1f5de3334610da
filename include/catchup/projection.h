/* catchup/projection.h — what one projection reports: the methods that may
 * make it and what it certifies (cup_proj_info). Below the projector
 * (catchup/projector.h): the sets' closed forms and oracles and the exact
 * LCP step fill it too. */
#ifndef CATCHUP_PROJECTION_H
#define CATCHUP_PROJECTION_H

#ifdef __cplusplus
extern "C" {
#endif

/* One list of the projector methods: X(enumerator, value, name, what it is).
 * The enum, cup_proj_method_name/parse, --help texts, the scene reader's
 * messages, the Fortran constants and the docs tables are all made from it.
 * Values are part of the ABI: append, never renumber. */
#define CUP_PROJ_METHOD_LIST(X)                                                         \
  X(CUP_PROJ_AUTO, 0, "auto",                                                           \
    "fastest method that certifies the tolerances: on small dense sets (m <= 64, "     \
    "dim <= 256) the dual LCP by principal pivoting (closed form for 1 or 2 active "   \
    "rows), falling back to the active set; on sparse sets the active-set Newton method") \
  X(CUP_PROJ_PG, 1, "pg", "the paper's dual projected gradient, step 1/L")              \
  X(CUP_PROJ_FISTA, 2, "fista", "accelerated dual gradient with adaptive restart")      \
  X(CUP_PROJ_ACTIVESET, 3, "activeset", "exact: active-set Newton on the dual (dense or CHOLMOD)")

typedef enum cup_proj_method {
#define CUP_PROJ_ENUM_(e, v, name, doc) e = v,
  CUP_PROJ_METHOD_LIST(CUP_PROJ_ENUM_)
#undef CUP_PROJ_ENUM_
} cup_proj_method;
#define CUP_PROJ_ONE_(e, v, name, doc) +1
/** The number of methods: values 0 .. CUP_PROJ_METHOD_COUNT - 1. */
enum { CUP_PROJ_METHOD_COUNT = 0 CUP_PROJ_METHOD_LIST(CUP_PROJ_ONE_) };
#undef CUP_PROJ_ONE_

/** What one projection did and what it certifies. */
typedef struct cup_proj_info {
  int status;             /**< as returned */
  int method;             /**< method that produced the answer (cup_proj_method) */
  int iterations;         /**< dual iterations (first-order steps + Newton solves) */
  int factorizations;     /**< sparse numeric factorizations */
  int skipped;            /**< 1 if x was already in K: z = x exactly */
  int active;             /**< constraints with lambda_i > 0 */
  double scale;           /**< S = max(||x||_P, max_i |g_i| / ||c_i||_{P^-1}) */
  double eps_target;      /**< eps requested (absolute) */
  double eta_target;      /**< eta requested (absolute) */
  double eps_cert;        /**< certified: ||x - z||_P^2 - d_K(x)^2 <= eps_cert */
  double eta_cert;        /**< certified: d_K(z) <= eta_cert (INFINITY if unknown) */
  double violation;       /**< raw max_i (-(C z + g)_i)_+ for comparison with eta_cert */
  double dual_value;      /**< 2 q(lambda): a certified lower bound on d_K(x)^2 */
  double farkas_gap;      /**< empty K: g^T y (< 0) for the certificate y >= 0 */
  double farkas_residual; /**< empty K: ||C^T y||_{P^-1}; K has no point within
                               radius -farkas_gap / farkas_residual of 0 */
  int row_updates;        /**< rows added to or removed from the sparse factor */
} cup_proj_info;

#ifdef __cplusplus
}
#endif
#endif

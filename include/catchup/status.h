/* catchup/status.h — status codes: 0 ok, negative errors, positive warnings. */
#ifndef CATCHUP_STATUS_H
#define CATCHUP_STATUS_H

#include "catchup/export.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One list gives both the enum and the messages (cup_status_string).
 * Numbers are part of the ABI and of the HDF5 output: append, never renumber. */
#define CUP_STATUS_LIST(X)                                                    \
  X(CUP_OK,                  0, "ok")                                         \
  X(CUP_ERR_NOMEM,          -1, "out of memory")                              \
  X(CUP_ERR_ARG,            -2, "invalid argument")                           \
  X(CUP_ERR_DIM,            -3, "dimension mismatch")                         \
  X(CUP_ERR_NONFINITE,      -4, "NaN or Inf in the input")                    \
  X(CUP_ERR_NOT_SPD,        -5, "metric P is not symmetric positive definite") \
  X(CUP_ERR_EMPTY_SET,      -6, "the set is empty (Farkas certificate in info)") \
  X(CUP_ERR_PB_CT,          -7, "P B differs from C^T")                       \
  X(CUP_ERR_CALLBACK,       -8, "a user callback failed or returned NaN/Inf") \
  X(CUP_ERR_DIVERGED,       -9, "an iterate or the state became NaN or Inf, or left its range (CUP_STATE_MAX)") \
  X(CUP_ERR_IO,            -10, "file input/output failed")                   \
  X(CUP_ERR_PARSE,         -11, "syntax or schema error in an input file")    \
  X(CUP_ERR_LINALG,        -12, "sparse factorization failed")                \
  X(CUP_ERR_TIME_LIMIT,    -13, "time limit reached")                         \
  X(CUP_ERR_INTERRUPTED,   -14, "interrupted by the caller")                  \
  X(CUP_ERR_UNSUPPORTED,   -15, "not supported for this configuration")      \
  X(CUP_WARN_NOT_CERTIFIED,  1, "requested (eps, eta) not certified within the iteration limit; bounds reached are in info") \
  X(CUP_WARN_STIFF,          2, "explicit scheme with h*rho(A) > 2: the free step is unstable") \
  X(CUP_WARN_QUADRATURE,     3, "input quadrature did not reach its tolerance") \
  X(CUP_WARN_X0_OUTSIDE,     4, "x0 is not consistent (outside K(0); with D != 0, no zeta >= 0 makes C x0 + D zeta + g >= 0): the first step jumps, by the size in the message") \
  X(CUP_WARN_SPLITTING,      5, "implicit/exponential scheme: the projection along B loses what the free step moved (h above the time constant of a constraint direction, or a source driving a blocked state fast within a step); the message says where and how much") \
  X(CUP_ERR_STEP_SIZE,     -16, "adaptive scheme: the step size underflowed (the input or the solution is not smooth enough for tol there)") \
  X(CUP_WARN_ZENO,           6, "adaptive scheme: events accumulate (Zeno behaviour or chattering) beyond the event rate cap; catching-up steps took over there") \
  X(CUP_WARN_TOL_FLOOR,      7, "adaptive scheme: tol is below what double precision can deliver at the state's scale") \
  X(CUP_ERR_UNCERTIFIED,   -17, "no method found a point within a certified distance of the set (eta = inf)") \
  X(CUP_ERR_NO_STEADY_STATE, -18, "steady state: Newton's method on the period map found no periodic orbit (a Floquet multiplier at 1, or the iteration did not converge: the message says which)") \
  X(CUP_WARN_UNSTABLE_ORBIT,  8, "steady state: the periodic orbit has a Floquet multiplier of modulus >= 1: it is not asymptotically stable, a transient does not settle on it") \
  X(CUP_WARN_COARSE_MEASURE,  9, "steady state: more switchings and events in the period than 4 a sample + 64: the measurements place none of them (O(h) where a signal jumps); raise steady_state.samples")

typedef enum cup_status {
#define CUP_STATUS_ENUM_(name, value, text) name = value,
  CUP_STATUS_LIST(CUP_STATUS_ENUM_)
#undef CUP_STATUS_ENUM_
} cup_status;

/** Message for a status code; "unknown status" for a value not in the list. */
CUP_API const char *cup_status_string(int status);

/** Symbolic name ("CUP_ERR_EMPTY_SET"); "CUP_UNKNOWN" for a value not in the list. */
CUP_API const char *cup_status_name(int status);

/** Most severe of two statuses: any error beats any warning beats ok; among
 *  errors (or warnings) the first one is kept. */
CUP_API int cup_status_merge(int first, int second);

#ifdef __cplusplus
}
#endif
#endif

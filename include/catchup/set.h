/* catchup/set.h — the moving sets C(t) of a general sweeping process
 *     x'(t) in -N(C(t); x(t)) + f(t, x(t))        (paper, Sec. 3)
 * and their certified (eps, eta)-approximate projections in a metric P.
 *
 * A set moves through p parameters u(t) (an input, catchup/input.h) that
 * enter affinely: the offset g = F + G u of a polyset, the centre
 * c = center + Gc u and the radius r = radius + gr^T u of a ball or an
 * ellipsoid. A user oracle gets the time itself; a state-dependent polyset
 * gets the time and the state x_k, and the step projects onto C(t_{k+1}, x_k)
 * (Kunze and Monteiro Marques). */
#ifndef CATCHUP_SET_H
#define CATCHUP_SET_H

#include "catchup/export.h"
#include "catchup/sparse.h"
#include "catchup/polyset.h"
#include "catchup/projector.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cup_set cup_set;

/* One list of the set kinds: X(enumerator, value, name (the scene's key),
 * what it is and how it is projected). Values are part of the ABI: append,
 * never renumber. */
#define CUP_SET_LIST(X)                                                                 \
  X(CUP_SET_POLYSET, 0, "polyset",                                                      \
    "{x : C x + F + G u(t) >= 0}: the dual projector (as for an LCS)")                  \
  X(CUP_SET_BALL, 1, "ball",                                                            \
    "{x : dist_P(x, c(t)) <= r(t)}: closed form")                                        \
  X(CUP_SET_ELLIPSOID, 2, "ellipsoid",                                                  \
    "{x : (x - c(t))^T Q (x - c(t)) <= r(t)^2}: 1-D root find in the eigenbasis of (Q, P)") \
  X(CUP_SET_HALFSPACE, 3, "halfspace",                                                  \
    "{x : a^T x + b(t) >= 0}: closed form")                                             \
  X(CUP_SET_INTERSECTION, 4, "intersection",                                            \
    "a polyset and a ball: 1-D root find on the ball's multiplier, one polyset "        \
    "projection per trial")                                                             \
  X(CUP_SET_ORACLE, 5, "oracle",                                                        \
    "the user's (eps, eta)-projection callback, checked at every step")                 \
  X(CUP_SET_STATE_POLYSET, 6, "state-polyset",                                          \
    "{y : C(t, x_k) y + g(t, x_k) >= 0}: rows rebuilt from x_k at every step by a callback; " \
    "the sparse factorization is reused while the row patterns repeat")

typedef enum cup_set_kind {
#define CUP_SET_ENUM_(e, v, name, doc) e = v,
  CUP_SET_LIST(CUP_SET_ENUM_)
#undef CUP_SET_ENUM_
} cup_set_kind;
#define CUP_SET_ONE_(e, v, name, doc) +1
/** The number of set kinds: values 0 .. CUP_SET_COUNT - 1. */
enum { CUP_SET_COUNT = 0 CUP_SET_LIST(CUP_SET_ONE_) };
#undef CUP_SET_ONE_

/** A user projection oracle (paper, Sec. 2): write into z (n entries) an
 *  (eps, eta)-approximate projection of x onto C(t),
 *      ||x - z||_P^2 < d_C(t)(x)^2 + eps   and   d_C(t)(z) <= eta,
 *  and what it certifies: *eps_cert >= ||x - z||_P^2 - d(x)^2, *eta_cert >=
 *  d(z). eps and eta are the schedules (eps_n, eta_n) or the projector's
 *  targets. Return 0, or nonzero to stop the run with CUP_ERR_CALLBACK.
 *  Callable from Fortran (bind(C)). */
typedef int (*cup_oracle_fn)(double t, const double *x, double eps, double eta, double *z,
                             double *eps_cert, double *eta_cert, void *ctx);

/** Rows of a state-dependent polyset, filled by the callback below. */
typedef struct cup_rowbuf cup_rowbuf;

/** Append one row c^T y + offset >= 0: nnz entries, columns 0-based and
 *  strictly increasing, values finite. Grows the buffer when it is full
 *  (the only allocation, until the largest row count has been seen).
 *  Returns CUP_OK, CUP_ERR_ARG (a column out of range or not increasing:
 *  the row is not added), CUP_ERR_NONFINITE or CUP_ERR_NOMEM. */
CUP_API int cup_rowbuf_add(cup_rowbuf *rows, int nnz, const int *cols, const double *vals, double offset);
/** Announce a row pattern that may become a row soon (a contact just beyond
 *  the margin): no constraint now. Such patterns join the factorization's
 *  pool whenever a new row forces a new analysis anyway, so that the rows
 *  they announce need none when they come. Columns as for cup_rowbuf_add. */
CUP_API int cup_rowbuf_expect(cup_rowbuf *rows, int nnz, const int *cols);
/** Rows appended so far. */
CUP_API int cup_rowbuf_rows(const cup_rowbuf *rows);

/** The rows of C(t, x): append them with cup_rowbuf_add (the buffer is
 *  empty on entry). Return 0, or nonzero to stop with CUP_ERR_CALLBACK.
 *  A row whose column pattern was seen in the last steps reuses that row's
 *  slot of the sparse factor (no allocation, no new symbolic analysis); a
 *  new pattern costs a new analysis. Rows for contacts about to form (a
 *  margin) and cup_rowbuf_expect for those a little farther keep the
 *  patterns repeating. Callable from Fortran (bind(C)). */
typedef int (*cup_rows_fn)(double t, const double *x, cup_rowbuf *rows, void *ctx);

/** What a set is. A matrix with ncol = 0 is absent. Everything is copied,
 *  except the callbacks' contexts. */
typedef struct cup_set_desc {
  cup_set_kind kind;      /**< which set; each field says which kinds read it */
  int n;                  /**< dimension of x */
  int p;                  /**< parameters u in R^p that move the set (0: it is fixed) */
  cup_metric P;           /**< the metric of the projection (kind IDENTITY: P = I); the
                               ellipsoid needs n <= 256, the state polyset a diagonal P */
  cup_csc C;              /**< POLYSET, INTERSECTION: m x n; HALFSPACE: 1 x n (a^T) */
  const double *F;        /**< POLYSET, INTERSECTION: m entries; HALFSPACE: b (1 entry); NULL: 0 */
  cup_csc G;              /**< POLYSET, HALFSPACE, INTERSECTION: m x p, the offset's motion */
  const double *center;   /**< BALL, ELLIPSOID, INTERSECTION: n entries at u = 0; NULL: 0 */
  cup_csc Gc;             /**< BALL, ELLIPSOID, INTERSECTION: n x p, the centre's motion */
  double radius;          /**< BALL, ELLIPSOID, INTERSECTION: r at u = 0 */
  const double *gr;       /**< BALL, ELLIPSOID, INTERSECTION: p entries, r = radius + gr^T u; NULL: fixed */
  cup_csc Q;              /**< ELLIPSOID: n x n symmetric positive definite shape */
  cup_oracle_fn oracle;   /**< ORACLE: the projection */
  void *oracle_ctx;       /**< ORACLE: passed to oracle */
  cup_rows_fn rows;       /**< STATE_POLYSET: the rows at (t, x_k) */
  void *rows_ctx;         /**< STATE_POLYSET: passed to rows */
} cup_set_desc;

/** Validate and copy. On failure *S is NULL and errmsg (CUP_ERRMSG_LEN
 *  bytes, may be NULL) names the field and the problem. A set is read-only
 *  after creation (its callbacks aside) and may be shared. */
CUP_API int cup_set_create(cup_set **S, const cup_set_desc *d, char *errmsg);
CUP_API void cup_set_free(cup_set **S);
CUP_API int cup_set_dim(const cup_set *S);       /**< n */
CUP_API int cup_set_params(const cup_set *S);    /**< p */
CUP_API int cup_set_kind_of(const cup_set *S);   /**< its cup_set_kind */
/** The name of a kind in CUP_SET_LIST ("ball", ...); "unknown" otherwise. */
CUP_API const char *cup_set_kind_name(int kind);
/** A name of CUP_SET_LIST -> its value; -1 if unknown. */
CUP_API int cup_set_kind_parse(const char *name);

/* ---- projections onto a set, one at a time ------------------------------------ *
 * Onto any set. On a polyset (CUP_SET_POLYSET) the one public way is
 * cup_projector (catchup/projector.h), with its offsets, multipliers and
 * certificates; a cup_setproj onto a polyset is a thin wrapper over it
 * (the projector made at create, g = F + G u placed at each place, the
 * projection by cup_project, the same z and info), kept so that one loop
 * serves every kind. */

typedef struct cup_setproj cup_setproj;

/** A projector onto S (which must outlive it); allocates its workspace.
 *  opt (NULL: defaults) gives the tolerances, targets eps_abs + eps_rel S^2
 *  and eta_abs + eta_rel S with S the scale of the problem, and the method
 *  of the polyset projections. */
CUP_API int cup_setproj_create(cup_setproj **sp, const cup_set *S, const cup_projector_options *opt,
                               char *errmsg);
CUP_API void cup_setproj_free(cup_setproj **sp);
/** Place the set: time t, parameters u (p entries; NULL when p = 0) and, for
 *  a state-dependent set, the state x (n entries; rows are rebuilt here).
 *  Returns CUP_OK or an error whose words go into errmsg (CUP_ERRMSG_LEN
 *  bytes, may be NULL), the one way errors travel (README, "Errors: one way"). */
CUP_API int cup_setproj_place(cup_setproj *sp, double t, const double *u, const double *x, char *errmsg);
/** Project x onto the set as last placed: z (n entries; may alias x) with
 *  the certified (eps, eta) in info (may be NULL): CUP_OK when the targets
 *  are certified, CUP_WARN_NOT_CERTIFIED with what was reached otherwise,
 *  CUP_ERR_EMPTY_SET (a negative radius, a polyset and a ball that do not
 *  meet), CUP_ERR_CALLBACK (an oracle that failed, returned NaN or a point
 *  farther from x than its claims allow), CUP_ERR_NONFINITE. On an error z
 *  is unchanged and errmsg (as above) says what happened; errmsg is
 *  written only on an error. */
CUP_API int cup_setproj_solve(cup_setproj *sp, const double *x, double *z, cup_proj_info *info, char *errmsg);
/** Change the absolute/relative tolerances for the following projections. */
CUP_API int cup_setproj_set_tolerances(cup_setproj *sp, double eps_abs, double eps_rel, double eta_abs,
                                       double eta_rel);

/* The older forms, kept for their users (C and Fortran), each a thin
 * wrapper with the same behaviour: cup_setproj_move is cup_setproj_place
 * and cup_setproj_project is cup_setproj_solve, without errmsg; their words
 * are read afterwards with cup_setproj_message (the last failing call's,
 * "" after a success), the text errmsg would have received. */
CUP_API int cup_setproj_move(cup_setproj *sp, double t, const double *u, const double *x);
CUP_API int cup_setproj_project(cup_setproj *sp, const double *x, double *z, cup_proj_info *info);
CUP_API const char *cup_setproj_message(const cup_setproj *sp);
/** State polyset: rows of the set as last placed; 0 for other kinds. */
CUP_API int cup_setproj_rows(const cup_setproj *sp);
/** State polyset: how many times a new row pattern forced a new symbolic
 *  analysis (and the allocations that go with it) since creation. */
CUP_API long cup_setproj_rebuilds(const cup_setproj *sp);

#ifdef __cplusplus
}
#endif
#endif

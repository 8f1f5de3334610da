/* Internal layout of cup_set and the closed-form projections that sit with
 * their sets (ball, ellipsoid, half-space). */
#ifndef CUP_SET_IMPL_H
#define CUP_SET_IMPL_H

#include "catchup/set.h"
#include "catchup/projection.h"
#include "polyset_impl.h"

struct cup_set {
  int kind, n, p;
  cup_polyset *K;        /* the rows {C x + F >= 0} and the metric P; a set without rows
                            keeps a polyset of 0 rows for its metric */
  int owns_K;            /* 0: borrowed (an LCS's polyset) */
  cup_sparse G;          /* m x p: g = F + G u */
  int has_G, owns_G;
  double *center;        /* n: c = center + Gc u */
  cup_sparse Gc;
  int has_Gc;
  double radius;         /* r = radius + gr^T u */
  double *gr;            /* p, or NULL */
  /* ellipsoid: V^T P V = I and V^T Q V = diag(lam), so that x - c = V y with
   * ||x - c||_P = ||y|| and (x - c)^T Q (x - c) = sum lam_i y_i^2 */
  double *Qd;            /* n x n, column-major */
  double *V, *VtP;       /* n x n: V and V^T P (y = V^T P (x - c)) */
  double *lam;           /* n */
  double pmin;           /* a lower bound on lambda_min(P) */
  double *pa;            /* half-space: P^-1 a */
  cup_oracle_fn oracle;
  void *oracle_ctx;
  cup_rows_fn rows;
  void *rows_ctx;
  /* STATE_POLYSET, internal (a crowd's): given the answer z of the step
   * from x at t, > 0 when the rows missed a constraint that z violates (the
   * rows callback, called again at the same (t, x), then adds it), 0 when
   * they missed none, < 0 on failure. Called with rows_ctx. */
  int (*recheck)(double t, const double *x, const double *z, void *ctx);
};

/* Give a STATE_POLYSET its recheck (the field above): the one way a module
 * above set/ (a crowd) sets it. CUP_ERR_ARG for another kind of set. */
int set_on_recheck(cup_set *S, int (*recheck)(double t, const double *x, const double *z, void *ctx));

/* A set over a polyset that is not copied (an LCS's): g = F + G u with the
 * polyset's default offset as F and G (may be NULL) borrowed too. */
int cup_set_wrap_polyset(cup_set **S, const cup_polyset *K, const cup_sparse *G, int p,
                         char *errmsg);

/* The parameters at u (p entries; ignored when p = 0): the offset g (m
 * entries) for sets with rows, the centre c (n) and the radius *r for
 * balls and ellipsoids. Any output may be NULL. */
void cup_set_place(const cup_set *S, const double *u, double *g, double *c, double *r);

/* Scratch the closed forms need: 4 n doubles. */
#define CUP_CLOSED_WORK(n) (4 * (size_t)(n) + 4)

/* Certified closed-form projections of x onto the placed set; the targets
 * and the scale are in info (eps_target, eta_target, scale) on entry, the
 * certificates on return, as cup_project fills them. z may alias x.
 * Return CUP_OK, CUP_WARN_NOT_CERTIFIED or CUP_ERR_EMPTY_SET (r < 0, or a
 * half-space 0 >= -b > 0). */
int cup_ball_project(const cup_set *S, const double *c, double r, const double *x, double *z,
                     double *work, cup_proj_info *info);
int cup_ellipsoid_project(const cup_set *S, const double *c, double r, const double *x, double *z,
                          double *work, cup_proj_info *info);
int cup_halfspace_project(const cup_set *S, const double *g, const double *x, double *z,
                          double *work, cup_proj_info *info);

/* The user's oracle at t, checked (set/oracle.c): z only on success; msg
 * (size bytes) says what was wrong on CUP_ERR_CALLBACK. work: 3 n. */
int cup_oracle_project(const cup_set *S, double t, const double *x, double *z, double *work,
                       cup_proj_info *info, char *msg, size_t size);

/* Bounds on ||v||_P for a computed v: *lo <= ||v||_P <= *hi, allowing for the
 * rounding of the sum (and of forming v from one subtraction). Returns the
 * computed value. */
double cup_metric_norm_bounds(const cup_polyset *K, const double *v, double *lo, double *hi);
/* An upper bound on ||a - b||_P (and a lower one into *lo, may be NULL);
 * scratch w: n entries. */
double cup_metric_dist_hi(const cup_polyset *K, const double *a, const double *b, double *lo, double *w);

#endif

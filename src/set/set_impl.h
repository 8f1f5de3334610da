/* Internal layout of cup_set, its kinds' table and the closed-form
 * projections that sit with their sets (ball, ellipsoid, half-space). */
#ifndef CUP_SET_IMPL_H
#define CUP_SET_IMPL_H

#include "catchup/set.h"
#include "catchup/projection.h"
#include "polyset_impl.h"

/* A set kind's part of the set itself, as GSL's step types: what its
 * description carries, the kind's own checks and its set-up. One static
 * table a kind, in the kind's file (ball.c: ball, halfspace; ellipsoid.c;
 * oracle.c; rowpool.c: state-polyset; set.c: polyset, intersection), and
 * one line in set.c's registry. The kind's projection is the projector's
 * (projector/setproj_impl.h, setproj_kind). */
typedef struct set_kind {
  int rows;      /* rows C x + F >= 0 in the description: 0 none, -1 any number, k > 0 exactly k */
  int ball;      /* a centre and a radius (the motion Gc, gr) */
  /* the kind's own fields, checked after n, p and the rows, before the
   * radius; NULL: none */
  int (*check)(const cup_set_desc *d, char *errmsg);
  /* after the rows (or none) and the motion are copied; NULL: nothing more */
  int (*setup)(cup_set *S, const cup_set_desc *d, char *errmsg);
} set_kind;

extern const set_kind set_kind_ball, set_kind_halfspace, set_kind_ellipsoid, set_kind_oracle,
    set_kind_state_polyset;

/* The description holds the matrix c (a view: columns and pointers). */
static inline int set_present(const cup_csc *c) { return c->ncol > 0 && c->colptr; }

struct cup_set {
  int kind, n, p;
  const set_kind *type;  /* the registry's entry of kind */
  cup_polyset *K;        /* the rows {C x + F >= 0} and the metric P; a set without rows
                            keeps a polyset of 0 rows for its metric */
  int owns_K;            /* 0: borrowed (an LCS's polyset) */
  la_sparse G;          /* m x p: g = F + G u */
  int has_G, owns_G;
  double *center;        /* n: c = center + Gc u */
  la_sparse Gc;
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
int set_wrap_polyset(cup_set **S, const cup_polyset *K, const la_sparse *G, int p,
                     char *errmsg);

/* The parameters at u (p entries; ignored when p = 0): the offset g (m
 * entries) for sets with rows, the centre c (n) and the radius *r for
 * balls and ellipsoids. Any output may be NULL. */
void set_place(const cup_set *S, const double *u, double *g, double *c, double *r);

/* Scratch the closed forms need: 4 n doubles. */
#define CUP_CLOSED_WORK(n) (4 * (size_t)(n) + 4)

/* Certified closed-form projections of x onto the placed set; the targets
 * and the scale are in info (eps_target, eta_target, scale) on entry, the
 * certificates on return, as cup_project fills them. z may alias x.
 * Return CUP_OK, CUP_WARN_NOT_CERTIFIED or CUP_ERR_EMPTY_SET (r < 0, or a
 * half-space 0 >= -b > 0). */
int ball_project(const cup_set *S, const double *c, double r, const double *x, double *z,
                 double *work, cup_proj_info *info);
int ellipsoid_project(const cup_set *S, const double *c, double r, const double *x, double *z,
                      double *work, cup_proj_info *info);
int halfspace_project(const cup_set *S, const double *g, const double *x, double *z,
                      double *work, cup_proj_info *info);

/* The user's oracle at t, checked (set/oracle.c): z only on success; msg
 * (size bytes) says what was wrong on CUP_ERR_CALLBACK. work: 3 n. */
int oracle_project(const cup_set *S, double t, const double *x, double *z, double *work,
                   cup_proj_info *info, char *msg, size_t size);

#endif

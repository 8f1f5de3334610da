/* Internal layout of cup_setproj: the projection onto any cup_set, and the
 * table of a set kind's projection (setproj_kind), shared by the dispatcher
 * (setproj.c) and the kinds: setpoly.c (polyset, and the placing of a set
 * with rows or a ball that the others share), closedform.c (ball,
 * ellipsoid, halfspace), setoracle.c, polyball.c (intersection) and
 * statepoly.c (state-polyset). */
#ifndef CUP_SETPROJ_IMPL_H
#define CUP_SETPROJ_IMPL_H

#include <stdarg.h>
#include <stdio.h>
#include "catchup/set.h"
#include "projector.h"
#include "set/rowpool.h"
#include "set/set_impl.h"

/* A set's message goes whole into the integrator's cause (integrator.c's
 * WHAT_LEN) after a prefix of at most 80 characters. */
#define CUP_SETPROJ_MSG (CUP_RUN_MSG_LEN - 192)

/* A set kind's projection, as the projector's methods (proj_ws.h) and
 * GSL's step types: one static table a kind, in the kind's file, and one
 * line in setproj.c's registry; the dispatcher names no kind. The set's own
 * part of a kind (checks, set-up) is set/'s set_kind. */
typedef struct setproj_kind {
  /* the kind's own part of the set projector, after the common buffers;
   * NULL: none */
  int (*create)(cup_setproj *sp, char *errmsg);
  void (*free)(cup_setproj *sp);            /* what create took; NULL: none */
  /* the set at t, u(t) (u checked present when the set has parameters) and
   * the state x (may be NULL); NULL: the set does not move */
  int (*place)(cup_setproj *sp, double t, const double *u, const double *x);
  /* the certified projection of x (finite) onto the placed set; a failure
   * leaves its message (setproj_fail) */
  int (*project)(cup_setproj *sp, const double *x, double *z, cup_proj_info *info);
  /* rows the placing missed at the answer z (set_impl.h's recheck), as
   * setproj_recheck returns; NULL: it misses none */
  int (*recheck)(cup_setproj *sp, double t, const double *x, const double *z);
  int own_tolerances;   /* 1: it sets its projector's tolerances at each call (not the options') */
} setproj_kind;

extern const setproj_kind setproj_polyset, setproj_ball, setproj_ellipsoid, setproj_halfspace,
    setproj_intersection, setproj_oracle, setproj_state_polyset;

struct cup_setproj {
  const cup_set *S;
  const setproj_kind *type;    /* the registry's entry of S's kind */
  cup_projector_options opt;
  int kind, n, m;
  double t;                    /* time of the set as placed */
  double *g, *c, r;            /* offset (m), centre (n), radius */
  double *work;                /* CUP_CLOSED_WORK(n) */
  double *xs, *zk, *v;         /* n each: a copy of x, a polyset answer, a feasible point */
  cup_projector *proj;         /* POLYSET, INTERSECTION (onto the rows), STATE_POLYSET (the pool's) */
  /* INTERSECTION: a point certainly in both, for the segments that certify */
  double *anchor;
  int anchor_ok;               /* -1: not computed for the current placement */
  double *sm, *gm;             /* m: slack and its rounding bound at a trial point */
  /* STATE_POLYSET */
  cup_rowbuf rb;
  row_pool pool;
  cup_polyset *PK;             /* the pool's polyset (rows = slots) */
  int *cpos;                   /* per pool entry (CSR order): its position in PK->C */
  double *rework;              /* 2 m + n doubles for polyset_revalue */
  long step, rebuilds;
  int rows_now;
  /* the callback's numbering of the state (rowbuf_order) */
  int ordered;                 /* 1: the pool, PK and proj are in perm's numbering */
  int *perm, *pmap;            /* n: column k is x[perm[k]]; workspace of a renumbering */
  long perm_gen;
  char message[CUP_SETPROJ_MSG];
};

/* Targets eps_abs + eps_rel S^2, eta_abs + eta_rel S into info. */
static inline void setproj_targets(const cup_setproj *sp, double S, cup_proj_info *info) {
  const cup_projector_options *o = &sp->opt;
  info->scale = S;
  info->eps_target = o->eps_abs + (o->eps_rel > 0 ? o->eps_rel * S * S : 0);
  info->eta_target = o->eta_abs + (o->eta_rel > 0 ? o->eta_rel * S : 0);
}

/* The message of a failure; returns status. (Inline, like the targets: the
 * methods below the dispatcher must not call back into it.) */
__attribute__((format(printf, 3, 4)))
static inline int setproj_fail(cup_setproj *sp, int status, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(sp->message, sizeof sp->message, fmt, ap);
  va_end(ap);
  return status;
}

/* The placing of a set with rows or a ball (setpoly.c), every placed
 * kind's: g, c and r at u, checked finite (and r >= 0), the offset into
 * the rows' projector. */
int setproj_place_affine(cup_setproj *sp, double t, const double *u, const double *x);
/* The message of a polyset projection's outcome st (setpoly.c): the
 * Farkas certificate of an empty set, the status of another failure.
 * Returns st. */
int setproj_polyset_outcome(cup_setproj *sp, int st, const cup_proj_info *info);

#endif

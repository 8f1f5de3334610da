/* Internal layout of cup_setproj: the projection onto any cup_set, shared
 * by setproj.c (dispatch, closed forms, oracle), polyball.c (a polyset and a
 * ball) and statepoly.c (rows rebuilt from the state). */
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

struct cup_setproj {
  const cup_set *S;
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
  cup_rowpool pool;
  cup_polyset *PK;             /* the pool's polyset (rows = slots) */
  int *cpos;                   /* per pool entry (CSR order): its position in PK->C */
  double *rework;              /* 2 m + n doubles for cup_polyset_revalue */
  long step, rebuilds;
  int rows_now;
  /* the callback's numbering of the state (cup_rowbuf_order) */
  int ordered;                 /* 1: the pool, PK and proj are in perm's numbering */
  int *perm, *pmap;            /* n: column k is x[perm[k]]; workspace of a renumbering */
  long perm_gen;
  char message[CUP_SETPROJ_MSG];
};

/* Targets eps_abs + eps_rel S^2, eta_abs + eta_rel S into info. */
static inline void cup_setproj_targets(const cup_setproj *sp, double S, cup_proj_info *info) {
  const cup_projector_options *o = &sp->opt;
  info->scale = S;
  info->eps_target = o->eps_abs + (o->eps_rel > 0 ? o->eps_rel * S * S : 0);
  info->eta_target = o->eta_abs + (o->eta_rel > 0 ? o->eta_rel * S : 0);
}

/* The message of a failure; returns status. (Inline, like the targets: the
 * methods below the dispatcher must not call back into it.) */
__attribute__((format(printf, 3, 4)))
static inline int cup_setproj_fail(cup_setproj *sp, int status, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(sp->message, sizeof sp->message, fmt, ap);
  va_end(ap);
  return status;
}

int cup_polyball_project(cup_setproj *sp, const double *x, double *z, cup_proj_info *info);

int cup_statepoly_init(cup_setproj *sp, char *errmsg);
void cup_statepoly_free(cup_setproj *sp);
/* Rows at (t, x) from the callback, into the pool's polyset and projector. */
int cup_statepoly_move(cup_setproj *sp, double t, const double *x);
/* The projection, in the callback's numbering if it gave one. */
int cup_statepoly_project(cup_setproj *sp, const double *x, double *z, cup_proj_info *info);
/* The set's recheck of the answer z of the step from x at t (set_impl.h): 1
 * when it missed rows, which are then built again at (t, x) within the same
 * step; 0 when it missed none (or has no recheck); an error status. */
int cup_statepoly_recheck(cup_setproj *sp, double t, const double *x, const double *z);

#endif

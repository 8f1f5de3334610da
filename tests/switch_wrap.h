/* A cup_switching that passes each call on to another (a netlist's, from
 * cup_netlist_switching), for the tests that watch or perturb a few of its
 * calls (test_switch_quiet.c, test_switch_samples.c). The context is the
 * test's wrapper, whose first member is the cup_switching it wraps; the
 * test puts its own callbacks over the ones it watches. */
#ifndef CUP_SWITCH_WRAP_H
#define CUP_SWITCH_WRAP_H

#include "catchup.h"

/* (a pointer to a struct, converted, points to its first member) */
static inline const cup_switching *fwd_in(void *ctx) { return ctx; }

static inline int fwd_settle(void *c, int *topo, double t, const double *x, const double *z, char *e) {
  return fwd_in(c)->settle(fwd_in(c)->ctx, topo, t, x, z, e);
}
static inline int fwd_next(void *c, int topo, double t, double tmax, double *tnext) {
  return fwd_in(c)->next(fwd_in(c)->ctx, topo, t, tmax, tnext);
}
static inline const cup_lcs *fwd_lcs(void *c, int topo) { return fwd_in(c)->lcs(fwd_in(c)->ctx, topo); }
static inline void fwd_jump(void *c, int topo, double *x) { fwd_in(c)->jump(fwd_in(c)->ctx, topo, x); }
static inline int fwd_state_gated(void *c, int topo) { return fwd_in(c)->state_gated(fwd_in(c)->ctx, topo); }
static inline int fwd_crossed(void *c, int topo, double t, const double *x) {
  return fwd_in(c)->crossed(fwd_in(c)->ctx, topo, t, x);
}
static inline int fwd_moves(void *c, int topo) {   /* (a NULL moves: 1, as the run reads it) */
  return fwd_in(c)->moves ? fwd_in(c)->moves(fwd_in(c)->ctx, topo) : 1;
}

/* Every call of wrapper w's switching passed on; quiet NULL (no claims). */
static inline cup_switching fwd_switching(void *w) {
  return (cup_switching){w, fwd_settle, fwd_next, fwd_lcs, fwd_jump, fwd_state_gated, fwd_crossed, fwd_moves, NULL};
}

#endif

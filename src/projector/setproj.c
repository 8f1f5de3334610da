/* setproj — certified projections onto any cup_set: the dispatcher. The
 * registry below gives each kind its table (setproj_impl.h's
 * setproj_kind): the polyset through the dual projector (setpoly.c), the
 * closed forms of set/ (closedform.c), the user's oracle checked by
 * set/oracle.c (setoracle.c), the intersection of a polyset and a ball
 * (polyball.c) and the state-dependent polyset (statepoly.c). Below the
 * registry no kind is named. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "setproj_impl.h"

static const setproj_kind *const registry[CUP_SET_COUNT] = {
  [CUP_SET_POLYSET] = &setproj_polyset,
  [CUP_SET_BALL] = &setproj_ball,
  [CUP_SET_ELLIPSOID] = &setproj_ellipsoid,
  [CUP_SET_HALFSPACE] = &setproj_halfspace,
  [CUP_SET_INTERSECTION] = &setproj_intersection,
  [CUP_SET_ORACLE] = &setproj_oracle,
  [CUP_SET_STATE_POLYSET] = &setproj_state_polyset,
};

void cup_setproj_free(cup_setproj **spp) {
  if (!spp || !*spp) return;
  cup_setproj *sp = *spp;
  if (sp->type->free) sp->type->free(sp);
  cup_projector_free(&sp->proj);
  free(sp->g); free(sp->c); free(sp->work); free(sp->xs); free(sp->zk); free(sp->v); free(sp->anchor);
  free(sp->sm); free(sp->gm);
  free(sp);
  *spp = NULL;
}

int cup_setproj_create(cup_setproj **out, const cup_set *S, const cup_projector_options *opt,
                       char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "set projector: output pointer is NULL");
  *out = NULL;
  if (!S) return fail_fmt(errmsg, CUP_ERR_ARG, "set projector: set is NULL");
  cup_setproj *sp = calloc(1, sizeof *sp);
  if (!sp) return fail_fmt(errmsg, CUP_ERR_NOMEM, "set projector: out of memory");
  if (opt) sp->opt = *opt; else cup_projector_options_default(&sp->opt);
  sp->S = S;
  sp->kind = S->kind;
  sp->type = registry[S->kind];
  sp->n = S->n;
  sp->m = S->K->m;
  size_t N = (size_t)sp->n + 1;
  sp->g = calloc((size_t)sp->m + 1, sizeof(double));
  sp->c = calloc(N, sizeof(double));
  sp->work = calloc(CUP_CLOSED_WORK(sp->n), sizeof(double));
  sp->xs = calloc(N, sizeof(double));
  sp->zk = calloc(N, sizeof(double));
  sp->v = calloc(N, sizeof(double));
  sp->anchor = calloc(N, sizeof(double));
  sp->sm = calloc((size_t)sp->m + 1, sizeof(double));
  sp->gm = calloc((size_t)sp->m + 1, sizeof(double));
  int st = sp->g && sp->c && sp->work && sp->xs && sp->zk && sp->v && sp->anchor && sp->sm && sp->gm
               ? CUP_OK : fail_fmt(errmsg, CUP_ERR_NOMEM, "set projector: out of memory");
  if (!st && sp->type->create) st = sp->type->create(sp, errmsg);
  if (st) { cup_setproj_free(&sp); return st; }
  set_place(S, NULL, sp->g, sp->c, &sp->r);
  sp->anchor_ok = -1;
  *out = sp;
  return CUP_OK;
}

int cup_setproj_set_tolerances(cup_setproj *sp, double eps_abs, double eps_rel, double eta_abs,
                               double eta_rel) {
  if (!sp || !(eps_abs >= 0) || !(eps_rel >= 0) || !(eta_abs >= 0) || !(eta_rel >= 0)) return CUP_ERR_ARG;
  sp->opt.eps_abs = eps_abs; sp->opt.eps_rel = eps_rel;
  sp->opt.eta_abs = eta_abs; sp->opt.eta_rel = eta_rel;
  if (sp->proj && !sp->type->own_tolerances)
    return cup_projector_set_tolerances(sp->proj, eps_abs, eps_rel, eta_abs, eta_rel);
  return CUP_OK;
}

/* The older form of the words (set.h): read in place. */
const char *cup_setproj_message(const cup_setproj *sp) { return sp ? sp->message : ""; }
int cup_setproj_rows(const cup_setproj *sp) { return sp ? sp->rows_now : 0; }   /* 0 but for rows from x */
long cup_setproj_rebuilds(const cup_setproj *sp) { return sp ? sp->rebuilds : 0; }

/* The one way errors travel (README, "Errors: one way"): a failure's words, whole,
 * into the caller's errmsg; the set projector keeps them too, for the older
 * cup_setproj_message and for the integrator's message. */
static int told(int st, const char *words, char *errmsg) {
  if (st < 0 && errmsg) snprintf(errmsg, CUP_ERRMSG_LEN, "%s", words[0] ? words : cup_status_string(st));
  return st;
}

static inline int move_(cup_setproj *sp, double t, const double *u, const double *x) {
  if (!sp) return CUP_ERR_ARG;
  sp->message[0] = '\0';
  sp->t = t;
  sp->anchor_ok = -1;
  if (sp->S->p > 0 && !u)
    return setproj_fail(sp, CUP_ERR_ARG, "the set moves with %d parameters but u is NULL", sp->S->p);
  return sp->type->place ? sp->type->place(sp, t, u, x) : CUP_OK;
}

int cup_setproj_place(cup_setproj *sp, double t, const double *u, const double *x, char *errmsg) {
  int st = move_(sp, t, u, x);
  return told(st, sp ? sp->message : "set projector: sp is NULL", errmsg);
}

int cup_setproj_move(cup_setproj *sp, double t, const double *u, const double *x) {
  return move_(sp, t, u, x);     /* the older form: cup_setproj_place without errmsg */
}

int setproj_recheck(cup_setproj *sp, double t, const double *x, const double *z) {
  if (!sp || !sp->type->recheck || !x || !z) return 0;
  sp->message[0] = '\0';
  return sp->type->recheck(sp, t, x, z);
}

static inline int project_(cup_setproj *sp, const double *x, double *z, cup_proj_info *info_out) {
  cup_proj_info local;
  cup_proj_info *info = info_out ? info_out : &local;
  *info = (cup_proj_info){.eta_cert = INFINITY};
  if (!sp || !x || !z) return info->status = CUP_ERR_ARG;
  sp->message[0] = '\0';
  for (int j = 0; j < sp->n; j++)
    if (!isfinite(x[j])) {
      setproj_fail(sp, CUP_ERR_NONFINITE, "x[%d] is %g", j, x[j]);
      return info->status = CUP_ERR_NONFINITE;
    }
  return sp->type->project(sp, x, z, info);
}

int cup_setproj_solve(cup_setproj *sp, const double *x, double *z, cup_proj_info *info, char *errmsg) {
  int st = project_(sp, x, z, info);
  return told(st, sp && x && z ? sp->message : "set projector: sp, x or z is NULL", errmsg);
}

int cup_setproj_project(cup_setproj *sp, const double *x, double *z, cup_proj_info *info) {
  return project_(sp, x, z, info);   /* the older form: cup_setproj_solve without errmsg */
}

/* setproj — certified projections onto any cup_set: the polyset through
 * the dual projector, the closed forms of set/, the user's oracle checked by
 * set/oracle.c, the intersection of a polyset and a ball (polyball.c) and
 * the state-dependent polyset (statepoly.c). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "setproj_impl.h"

static int uses_rows_projector(int kind) {
  return kind == CUP_SET_POLYSET || kind == CUP_SET_INTERSECTION;
}

void cup_setproj_free(cup_setproj **spp) {
  if (!spp || !*spp) return;
  cup_setproj *sp = *spp;
  if (sp->kind == CUP_SET_STATE_POLYSET) cup_statepoly_free(sp);
  cup_projector_free(&sp->proj);
  free(sp->g); free(sp->c); free(sp->work); free(sp->xs); free(sp->zk); free(sp->v); free(sp->anchor);
  free(sp->sm); free(sp->gm);
  free(sp);
  *spp = NULL;
}

int cup_setproj_create(cup_setproj **out, const cup_set *S, const cup_projector_options *opt,
                       char *errmsg) {
  if (!out) return cup_fail(errmsg, CUP_ERR_ARG, "set projector: output pointer is NULL");
  *out = NULL;
  if (!S) return cup_fail(errmsg, CUP_ERR_ARG, "set projector: set is NULL");
  cup_setproj *sp = calloc(1, sizeof *sp);
  if (!sp) return cup_fail(errmsg, CUP_ERR_NOMEM, "set projector: out of memory");
  if (opt) sp->opt = *opt; else cup_projector_options_default(&sp->opt);
  sp->S = S;
  sp->kind = S->kind;
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
               ? CUP_OK : cup_fail(errmsg, CUP_ERR_NOMEM, "set projector: out of memory");
  if (!st && uses_rows_projector(sp->kind)) st = cup_projector_create(&sp->proj, S->K, &sp->opt, errmsg);
  if (!st && sp->kind == CUP_SET_STATE_POLYSET) st = cup_statepoly_init(sp, errmsg);
  if (st) { cup_setproj_free(&sp); return st; }
  cup_set_place(S, NULL, sp->g, sp->c, &sp->r);
  sp->anchor_ok = -1;
  *out = sp;
  return CUP_OK;
}

int cup_setproj_set_tolerances(cup_setproj *sp, double eps_abs, double eps_rel, double eta_abs,
                               double eta_rel) {
  if (!sp || !(eps_abs >= 0) || !(eps_rel >= 0) || !(eta_abs >= 0) || !(eta_rel >= 0)) return CUP_ERR_ARG;
  sp->opt.eps_abs = eps_abs; sp->opt.eps_rel = eps_rel;
  sp->opt.eta_abs = eta_abs; sp->opt.eta_rel = eta_rel;
  if (sp->proj && sp->kind != CUP_SET_INTERSECTION)
    return cup_projector_set_tolerances(sp->proj, eps_abs, eps_rel, eta_abs, eta_rel);
  return CUP_OK;
}

const char *cup_setproj_message(const cup_setproj *sp) { return sp ? sp->message : ""; }
int cup_setproj_rows(const cup_setproj *sp) {
  return sp && sp->kind == CUP_SET_STATE_POLYSET ? sp->rows_now : 0;
}
long cup_setproj_rebuilds(const cup_setproj *sp) { return sp ? sp->rebuilds : 0; }

/* The centre and radius just placed: finite, and a radius >= 0. */
static int check_ball(cup_setproj *sp) {
  for (int j = 0; j < sp->n; j++)
    if (!isfinite(sp->c[j])) return cup_setproj_fail(sp, CUP_ERR_NONFINITE, "the centre c[%d] is %g", j, sp->c[j]);
  if (!isfinite(sp->r)) return cup_setproj_fail(sp, CUP_ERR_NONFINITE, "the radius is %g", sp->r);
  if (sp->r < 0)
    return cup_setproj_fail(sp, CUP_ERR_EMPTY_SET, "the radius r(t) = %.17g < 0: the %s is empty", sp->r,
                            cup_set_kind_name(sp->kind));
  return CUP_OK;
}

int cup_setproj_move(cup_setproj *sp, double t, const double *u, const double *x) {
  if (!sp) return CUP_ERR_ARG;
  sp->message[0] = '\0';
  sp->t = t;
  sp->anchor_ok = -1;
  const cup_set *S = sp->S;
  if (S->p > 0 && !u) return cup_setproj_fail(sp, CUP_ERR_ARG, "the set moves with %d parameters but u is NULL", S->p);
  switch (sp->kind) {
    case CUP_SET_ORACLE:
      return CUP_OK;
    case CUP_SET_STATE_POLYSET:
      if (!x) return cup_setproj_fail(sp, CUP_ERR_ARG, "a state-dependent set needs the state x");
      return cup_statepoly_move(sp, t, x);
    default:
      break;
  }
  cup_set_place(S, u, sp->g, sp->c, &sp->r);
  for (int i = 0; i < sp->m; i++)
    if (!isfinite(sp->g[i])) return cup_setproj_fail(sp, CUP_ERR_NONFINITE, "the offset g[%d] is %g", i, sp->g[i]);
  if (sp->proj) cup_projector_set_offset(sp->proj, sp->g);
  if (sp->kind == CUP_SET_BALL || sp->kind == CUP_SET_ELLIPSOID || sp->kind == CUP_SET_INTERSECTION)
    return check_ball(sp);
  return CUP_OK;
}

/* The scale of a ball's placement: ||c||_P + r. */
static double ball_scale(const cup_setproj *sp) {
  return cup_polyset_norm(sp->S->K, sp->c) + fabs(sp->r);
}

static int closed_form(cup_setproj *sp, const double *x, double *z, cup_proj_info *info) {
  const cup_set *S = sp->S;
  double xn = cup_polyset_norm(S->K, x);
  int st;
  if (sp->kind == CUP_SET_HALFSPACE) {
    double a = S->K->rownorm[0];
    cup_setproj_targets(sp, fmax(xn, a > 0 ? fabs(sp->g[0]) / a : 0), info);
    st = cup_halfspace_project(S, sp->g, x, z, sp->work, info);
    if (st == CUP_ERR_EMPTY_SET)
      cup_setproj_fail(sp, st, "the half-space {0 >= -b} with b(t) = %.17g < 0 is empty", sp->g[0]);
    return st;
  }
  cup_setproj_targets(sp, fmax(xn, ball_scale(sp)), info);
  if (sp->kind == CUP_SET_BALL) return cup_ball_project(S, sp->c, sp->r, x, z, sp->work, info);
  return cup_ellipsoid_project(S, sp->c, sp->r, x, z, sp->work, info);
}

int cup_setproj_recheck(cup_setproj *sp, double t, const double *x, const double *z) {
  if (!sp || sp->kind != CUP_SET_STATE_POLYSET || !x || !z) return 0;
  sp->message[0] = '\0';
  return cup_statepoly_recheck(sp, t, x, z);
}

int cup_setproj_project(cup_setproj *sp, const double *x, double *z, cup_proj_info *info_out) {
  cup_proj_info local;
  cup_proj_info *info = info_out ? info_out : &local;
  *info = (cup_proj_info){.eta_cert = INFINITY};
  if (!sp || !x || !z) return info->status = CUP_ERR_ARG;
  sp->message[0] = '\0';
  for (int j = 0; j < sp->n; j++)
    if (!isfinite(x[j])) {
      cup_setproj_fail(sp, CUP_ERR_NONFINITE, "x[%d] is %g", j, x[j]);
      return info->status = CUP_ERR_NONFINITE;
    }
  int st;
  switch (sp->kind) {
    case CUP_SET_POLYSET:
    case CUP_SET_STATE_POLYSET:
      st = sp->kind == CUP_SET_STATE_POLYSET ? cup_statepoly_project(sp, x, z, info)
                                             : cup_project(sp->proj, x, z, info);
      if (st == CUP_ERR_EMPTY_SET)
        cup_setproj_fail(sp, st, "the polyset is empty: Farkas certificate y >= 0 with g^T y = %.3g, "
                         "||C^T y||_{P^-1} = %.3g", info->farkas_gap, info->farkas_residual);
      else if (st < 0 && !sp->message[0])
        cup_setproj_fail(sp, st, "polyset projection failed: %s", cup_status_string(st));
      return st;
    case CUP_SET_INTERSECTION:
      return cup_polyball_project(sp, x, z, info);
    case CUP_SET_ORACLE:
      cup_setproj_targets(sp, cup_polyset_norm(sp->S->K, x), info);
      return cup_oracle_project(sp->S, sp->t, x, z, sp->work, info, sp->message, sizeof sp->message);
    default:
      st = closed_form(sp, x, z, info);
      if (st < 0 && !sp->message[0]) cup_setproj_fail(sp, st, "%s", cup_status_string(st));
      return st;
  }
}

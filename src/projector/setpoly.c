/* setpoly — the kind polyset of a set projector: the rows' projector made
 * once, the offset g = F + G u placed at each step, the projection by the
 * dual projector. Its placing (g, and a ball's centre and radius, checked)
 * is every placed kind's: the closed forms and the intersection share it. */
#include <math.h>
#include "catchup.h"
#include "setproj_impl.h"

/* The centre and radius just placed: finite, and a radius >= 0. */
static int check_ball(cup_setproj *sp) {
  for (int j = 0; j < sp->n; j++)
    if (!isfinite(sp->c[j])) return setproj_fail(sp, CUP_ERR_NONFINITE, "the centre c[%d] is %g", j, sp->c[j]);
  if (!isfinite(sp->r)) return setproj_fail(sp, CUP_ERR_NONFINITE, "the radius is %g", sp->r);
  if (sp->r < 0)
    return setproj_fail(sp, CUP_ERR_EMPTY_SET, "the radius r(t) = %.17g < 0: the %s is empty", sp->r,
                        cup_set_kind_name(sp->kind));
  return CUP_OK;
}

int setproj_place_affine(cup_setproj *sp, double t, const double *u, const double *x) {
  (void)t; (void)x;
  set_place(sp->S, u, sp->g, sp->c, &sp->r);
  for (int i = 0; i < sp->m; i++)
    if (!isfinite(sp->g[i])) return setproj_fail(sp, CUP_ERR_NONFINITE, "the offset g[%d] is %g", i, sp->g[i]);
  if (sp->proj) cup_projector_set_offset(sp->proj, sp->g);
  return sp->S->type->ball ? check_ball(sp) : CUP_OK;
}

int setproj_polyset_outcome(cup_setproj *sp, int st, const cup_proj_info *info) {
  if (st == CUP_ERR_EMPTY_SET)
    setproj_fail(sp, st, "the polyset is empty: Farkas certificate y >= 0 with g^T y = %.3g, "
                 "||C^T y||_{P^-1} = %.3g", info->farkas_gap, info->farkas_residual);
  else if (st < 0 && !sp->message[0])
    setproj_fail(sp, st, "polyset projection failed: %s", cup_status_string(st));
  return st;
}

static int create(cup_setproj *sp, char *errmsg) {
  return cup_projector_create(&sp->proj, sp->S->K, &sp->opt, errmsg);
}

static int project(cup_setproj *sp, const double *x, double *z, cup_proj_info *info) {
  return setproj_polyset_outcome(sp, cup_project(sp->proj, x, z, info), info);
}

const setproj_kind setproj_polyset = {.create = create, .place = setproj_place_affine, .project = project};

/* closedform — the kinds ball, ellipsoid and halfspace of a set projector:
 * the certified closed forms of set/ (ball.c, ellipsoid.c) at the placed
 * centre, radius and offset, with the targets at the placement's scale. */
#include <math.h>
#include "catchup.h"
#include "setproj_impl.h"

/* The scale of a ball's placement: ||c||_P + r. */
static double ball_scale(const cup_setproj *sp) {
  return cup_polyset_norm(sp->S->K, sp->c) + fabs(sp->r);
}

/* A failure without a message of its own says its status. */
static int said(cup_setproj *sp, int st) {
  if (st < 0 && !sp->message[0]) setproj_fail(sp, st, "%s", cup_status_string(st));
  return st;
}

static int project_ball(cup_setproj *sp, const double *x, double *z, cup_proj_info *info) {
  setproj_targets(sp, fmax(cup_polyset_norm(sp->S->K, x), ball_scale(sp)), info);
  return said(sp, ball_project(sp->S, sp->c, sp->r, x, z, sp->work, info));
}

static int project_ellipsoid(cup_setproj *sp, const double *x, double *z, cup_proj_info *info) {
  setproj_targets(sp, fmax(cup_polyset_norm(sp->S->K, x), ball_scale(sp)), info);
  return said(sp, ellipsoid_project(sp->S, sp->c, sp->r, x, z, sp->work, info));
}

static int project_halfspace(cup_setproj *sp, const double *x, double *z, cup_proj_info *info) {
  const cup_set *S = sp->S;
  double a = S->K->rownorm[0];
  setproj_targets(sp, fmax(cup_polyset_norm(S->K, x), a > 0 ? fabs(sp->g[0]) / a : 0), info);
  int st = halfspace_project(S, sp->g, x, z, sp->work, info);
  if (st == CUP_ERR_EMPTY_SET)
    setproj_fail(sp, st, "the half-space {0 >= -b} with b(t) = %.17g < 0 is empty", sp->g[0]);
  return said(sp, st);
}

const setproj_kind setproj_ball = {.place = setproj_place_affine, .project = project_ball};
const setproj_kind setproj_ellipsoid = {.place = setproj_place_affine, .project = project_ellipsoid};
const setproj_kind setproj_halfspace = {.place = setproj_place_affine, .project = project_halfspace};

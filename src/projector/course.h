/* course — the course of one projection that every method shares
 * (course.c): its start (the checks, the scale, the targets, an empty
 * row), the skip test of a point already in K, the method's solve and the
 * end (the answer checked finite, the warm start kept). A method's
 * `project` hook runs it (proj_general for a method without one); a method
 * that answers most points itself (small.c) starts it, and runs the rest
 * for the points it leaves. Below the methods and the dispatcher. */
#ifndef CUP_COURSE_H
#define CUP_COURSE_H

#include <math.h>
#include <string.h>
#include "proj_ws.h"
#include "util/linalg.h"

/* The start: 1 to go on; 0 when it answered x itself (info->status: a NULL
 * argument, NaN or Inf in x, an overflowed scale, an empty row with its
 * Farkas certificate). Inline: a method's project pays for no call. */
static inline int proj_start(cup_projector *p, const double *x, const double *z, cup_proj_info *info) {
  *info = (cup_proj_info){.eta_cert = INFINITY};
  if (!x || !z) return info->status = CUP_ERR_ARG, 0;
  const cup_polyset *K = p->K;
  for (int j = 0; j < p->n; j++)
    if (!isfinite(x[j])) return info->status = CUP_ERR_NONFINITE, 0;
  p->has_v = 0;
  p->has_inward = 0;
  p->make_inward = NULL;
  p->iters = p->facts = p->updates = 0;
  double S = la_max(cup_polyset_norm(K, x), p->gscale);
  if (!isfinite(S)) return info->status = CUP_ERR_DIVERGED, 0;   /* ||x||_P overflowed */
  info->scale = S;
  info->eps_target = p->opt.eps_abs + (p->opt.eps_rel > 0 ? p->opt.eps_rel * S * S : 0);
  info->eta_target = p->opt.eta_abs + (p->opt.eta_rel > 0 ? p->opt.eta_rel * S : 0);
  info->method = p->opt.method;
  if (p->empty_row >= 0) {                 /* a row 0 >= -g_i with g_i < 0 */
    memset(p->farkas, 0, sizeof(double) * (size_t)p->m);
    p->farkas[p->empty_row] = 1;
    info->farkas_gap = p->g[p->empty_row];
    info->farkas_residual = 0;
    return info->status = CUP_ERR_EMPTY_SET, 0;
  }
  return 1;
}

/* After proj_start: x returned unchanged if it is in K, else the method
 * in slot s solves (NULL: none, which only a set without rows has, and
 * every x is in it); the status. */
int proj_course(cup_projector *p, const proj_slot *s, const double *x, double *z, cup_proj_info *info);

/* The whole projection by the method in slot s (info may be NULL): the
 * project hook of every method that has none of its own. */
int proj_general(cup_projector *p, const proj_slot *s, const double *x, double *z, cup_proj_info *info);

#endif

/* projector — certified (eps, eta)-approximate projections onto a polyset
 * (paper, Sec. 2 definition; Sec. 7 dual method). This file is the
 * dispatcher: the projector's life (create, offsets, revalue, reset,
 * checkpoint, free) and the calls through the tables of the methods chosen
 * once at creation (choose.c), which it never names. The methods are one
 * file each (small.c, activeset.c, newton.c, firstorder.c); the course of a
 * projection they share (course.c) and the certificates they return
 * through (certify.c) are below them. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "catchup/projector.h"
#include "certify.h"
#include "choose.h"
#include "course.h"
#include "projector.h"

void cup_projector_options_default(cup_projector_options *o) {
  if (!o) return;
  memset(o, 0, sizeof *o);
  o->method = CUP_PROJ_AUTO;
  o->eps_abs = 0;
  o->eps_rel = 1e-10;
  o->eta_abs = 0;
  o->eta_rel = 1e-10;
  o->max_iter = 100000;
  o->warm_start = 1;
  o->return_feasible = 0;
  o->lipschitz = 0;
  o->feasible_point = NULL;
  o->factor_updates = 1;
}

static void offset_changed(cup_projector *p) {
  const cup_polyset *K = p->K;
  p->gscale = 0;
  p->empty_row = -1;
  for (int i = 0; i < p->m; i++) {
    if (K->rownorm[i] > 0) {
      p->gscale = la_max(fabs(p->g[i]) / K->rownorm[i], p->gscale);   /* NaN passed over */
    } else if (p->g[i] < 0 && p->empty_row < 0) {
      p->empty_row = i;              /* 0 >= -g_i > 0 is impossible */
    }
  }
  p->origin_ok = p->m > 0;
  for (int i = 0; i < p->m; i++) p->origin_ok &= p->g[i] > 0;
  p->anchor_ok = -1;                 /* -1: to be rechecked against the new g */
  p->user_ok = p->user_pt ? -1 : 0;
}

/* The shared vectors, then each method's (proj_ws.h: the two passes). */
static void lay_out(cup_projector *p, proj_carve *a, int user_point) {
  size_t N = (size_t)p->n, M = (size_t)p->m, D = sizeof(double);
  p->g = proj_carve_piece(a, M, D);
  p->lam = proj_carve_piece(a, M, D);
  p->lam_warm = proj_carve_piece(a, M, D);
  p->b = proj_carve_piece(a, M, D);
  p->s = proj_carve_piece(a, M, D);
  p->gam = proj_carve_piece(a, M, D);
  p->sv = proj_carve_piece(a, M, D);
  p->gamv = proj_carve_piece(a, M, D);
  p->y = proj_carve_piece(a, N, D);
  p->u = proj_carve_piece(a, N, D);
  p->y2 = proj_carve_piece(a, N, D);
  p->s2 = proj_carve_piece(a, M, D);
  p->gam2 = proj_carve_piece(a, M, D);
  p->v = proj_carve_piece(a, N, D);
  p->s_v = proj_carve_piece(a, M, D);
  p->anchor = proj_carve_piece(a, N, D);
  p->s_anchor = proj_carve_piece(a, M, D);
  p->inward = proj_carve_piece(a, N, D);
  p->s_inward = proj_carve_piece(a, M, D);
  p->origin = proj_carve_piece(a, N, D);
  p->farkas = proj_carve_piece(a, M, D);
  p->wn = proj_carve_piece(a, N, D);
  p->wn2 = proj_carve_piece(a, N, D);
  p->act2 = proj_carve_piece(a, M, 1);
  if (user_point) {
    p->user_pt = proj_carve_piece(a, N, D);
    p->s_user = proj_carve_piece(a, M, D);
  }
  for (int k = 0; k < p->nslots; k++)
    if (p->slot[k].m->lay_out) p->slot[k].m->lay_out(p, a, &p->slot[k].ws);
}

/* Method m in a slot of its own (once), and what it falls back to. */
static int add_slot(cup_projector *p, const proj_method *m) {
  for (int k = 0; k < p->nslots; k++)
    if (p->slot[k].m == m) return k;
  int k = p->nslots++;
  p->slot[k] = (proj_slot){m, NULL, -1};
  if (m->fallback) p->slot[k].fallback = add_slot(p, *m->fallback);
  return k;
}

/* What cup_project runs: slot k's method (-1: none, a sparse set without
 * rows), through its project hook or the shared course. */
static void run_slot(cup_projector *p, int k) {
  p->run = k >= 0 ? &p->slot[k] : NULL;
  p->project = p->run && p->run->m->project ? p->run->m->project : proj_general;
}

/* The method the options choose for K (a sparse set without rows needs
 * none: every point is in it), and the one proj_exact runs: the
 * same when it is exact, else the exact method where that needs only
 * vectors (a dense set's), else the same again. */
static void set_methods(cup_projector *p, const cup_projector_options *o) {
  const proj_method *m = proj_choose(p->K, o);
  p->method = p->exact = m ? add_slot(p, m) : -1;
  if (!m || m->exact) return;
  cup_projector_options e = *o;
  e.method = CUP_PROJ_ACTIVESET;
  const proj_method *x = proj_choose(p->K, &e);
  if (x && x->standby) p->exact = add_slot(p, x);
}

int cup_projector_create(cup_projector **out, const cup_polyset *K,
                         const cup_projector_options *opt, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "projector: output pointer is NULL");
  *out = NULL;
  if (!K) return fail_fmt(errmsg, CUP_ERR_ARG, "projector: polyset is NULL");
  cup_projector_options o;
  if (opt) o = *opt; else cup_projector_options_default(&o);
  if (o.method < CUP_PROJ_AUTO || o.method > CUP_PROJ_ACTIVESET)
    return fail_fmt(errmsg, CUP_ERR_ARG, "projector: unknown method %d", (int)o.method);
  if (!(o.eps_abs >= 0) || !(o.eps_rel >= 0) || !(o.eta_abs >= 0) || !(o.eta_rel >= 0))
    return fail_fmt(errmsg, CUP_ERR_ARG,
                    "projector: tolerances must be >= 0 (eps_abs %g, eps_rel %g, eta_abs %g, eta_rel %g)",
                    o.eps_abs, o.eps_rel, o.eta_abs, o.eta_rel);
  if (o.max_iter < 1)
    return fail_fmt(errmsg, CUP_ERR_ARG, "projector: max_iter = %d, must be >= 1", o.max_iter);
  if (!(o.lipschitz >= 0) || isinf(o.lipschitz))
    return fail_fmt(errmsg, CUP_ERR_ARG, "projector: lipschitz = %g, must be finite and >= 0", o.lipschitz);
  cup_projector *p = calloc(1, sizeof *p);
  if (!p) return fail_fmt(errmsg, CUP_ERR_NOMEM, "projector: out of memory");
  p->K = K;
  p->opt = o;
  p->opt.feasible_point = NULL;
  int n = p->n = K->n, m = p->m = K->m;
  size_t N = (size_t)n, M = (size_t)m;
  set_methods(p, &o);
  proj_carve a = {NULL, 0};
  lay_out(p, &a, opt && opt->feasible_point);         /* sizes */
  a.base = p->block = calloc(1, a.used);
  p->block_bytes = a.used;
  a.used = 0;
  if (!p->block) {
    cup_projector_free(&p);
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "projector: out of memory");
  }
  lay_out(p, &a, opt && opt->feasible_point);         /* pieces */
  if (p->user_pt) memcpy(p->user_pt, opt->feasible_point, sizeof(double) * N);
  memcpy(p->g, K->g0, sizeof(double) * M);
  offset_changed(p);
  if (p->user_pt) {
    for (int j = 0; j < n; j++)
      if (!isfinite(p->user_pt[j])) {
        cup_projector_free(&p);
        return fail_fmt(errmsg, CUP_ERR_NONFINITE, "projector: feasible_point[%d] is not finite", j);
      }
  }
  for (int k = 0; k < p->nslots; k++) {
    const proj_method *pm = p->slot[k].m;
    int st = pm->create ? pm->create(p, &p->slot[k].ws, errmsg) : CUP_OK;
    if (st) { cup_projector_free(&p); return st; }
  }
  run_slot(p, p->method);
  *out = p;
  return CUP_OK;
}

void cup_projector_free(cup_projector **pp) {
  if (!pp || !*pp) return;
  cup_projector *p = *pp;
  for (int k = 0; k < p->nslots; k++)
    if (p->slot[k].m->free) p->slot[k].m->free(p, p->slot[k].ws);
#ifdef __SANITIZE_ADDRESS__
  if (p->block) ASAN_UNPOISON_MEMORY_REGION(p->block, p->block_bytes);
#endif
  free(p->block);
  free(p);
  *pp = NULL;
}

int cup_projector_set_offset(cup_projector *p, const double *g) {
  if (!p || (!g && p->m > 0)) return CUP_ERR_ARG;
  for (int i = 0; i < p->m; i++)
    if (!isfinite(g[i])) return CUP_ERR_NONFINITE;
  if (p->m) memcpy(p->g, g, sizeof(double) * (size_t)p->m);
  offset_changed(p);
  return CUP_OK;
}

int cup_projector_set_tolerances(cup_projector *p, double eps_abs, double eps_rel,
                                 double eta_abs, double eta_rel) {
  if (!p) return CUP_ERR_ARG;
  if (!(eps_abs >= 0) || !(eps_rel >= 0) || !(eta_abs >= 0) || !(eta_rel >= 0))
    return CUP_ERR_ARG;
  p->opt.eps_abs = eps_abs; p->opt.eps_rel = eps_rel;
  p->opt.eta_abs = eta_abs; p->opt.eta_rel = eta_rel;
  return CUP_OK;
}

int cup_projector_offer_feasible(cup_projector *p, const double *w) {
  if (!p || !w) return 0;
  for (int j = 0; j < p->n; j++)
    if (!isfinite(w[j])) return 0;
  if (polyset_slack(p->K, p->g, w, p->s_anchor, p->gamv) < 0) return 0;
  la_copy(p->anchor, w, p->n);
  p->anchor_ok = 1;
  return 1;
}

void cup_projector_reset(cup_projector *p) {
  if (!p) return;
  if (p->m) memset(p->lam_warm, 0, sizeof(double) * (size_t)p->m);
  for (int k = 0; k < p->nslots; k++)
    if (p->slot[k].m->reset) p->slot[k].m->reset(p, p->slot[k].ws);
}

void projector_checkpoint(cup_projector *p, ckpt *c) {
  size_t M = sizeof(double) * (size_t)p->m, N = sizeof(double) * (size_t)p->n;
  ckpt_io(c, p->g, M);
  CUP_CKPT_IO(c, p->gscale);
  CUP_CKPT_IO(c, p->empty_row);
  CUP_CKPT_IO(c, p->origin_ok);
  CUP_CKPT_IO(c, p->user_ok);
  ckpt_io(c, p->lam, M);
  ckpt_io(c, p->lam_warm, M);
  ckpt_io(c, p->anchor, N);
  ckpt_io(c, p->s_anchor, M);
  CUP_CKPT_IO(c, p->anchor_ok);
  for (int k = 0; k < p->nslots; k++)
    if (p->slot[k].m->checkpoint) p->slot[k].m->checkpoint(p, p->slot[k].ws, c);
}

void projector_revalue(cup_projector *p) {
  offset_changed(p);                      /* row norms changed: scale, empty rows, anchors */
  for (int i = 0; i < p->m; i++)
    if (!(p->K->rownorm[i] > 0)) p->lam_warm[i] = 0;   /* a row that is off holds nothing */
  for (int k = 0; k < p->nslots; k++)
    if (p->slot[k].m->revalue) p->slot[k].m->revalue(p, p->slot[k].ws);
}

const double *cup_projector_lambda(const cup_projector *p) { return p ? p->lam : NULL; }
const double *cup_projector_feasible(const cup_projector *p) {
  return p && p->has_v ? p->v : NULL;
}
const double *cup_projector_farkas(const cup_projector *p) { return p ? p->farkas : NULL; }

/* ---- the projection ----------------------------------------------------------- */

/* The exact method whatever the options ask: the configured method runs
 * as if it were activeset where the projector has an exact one. */
int proj_exact(cup_projector *p, const double *x, double *z, cup_proj_info *info) {
  if (!p) return CUP_ERR_ARG;
  int method = p->opt.method;
  if (p->exact >= 0 && p->slot[p->exact].m->exact) p->opt.method = CUP_PROJ_ACTIVESET;
  run_slot(p, p->exact);
  int st = cup_project(p, x, z, info);
  run_slot(p, p->method);
  p->opt.method = method;
  return st;
}

int cup_project(cup_projector *p, const double *x, double *z, cup_proj_info *info) {
  if (!p) {
    if (info) *info = (cup_proj_info){.status = CUP_ERR_ARG, .eta_cert = INFINITY};
    return CUP_ERR_ARG;
  }
  return p->project(p, p->run, x, z, info);
}

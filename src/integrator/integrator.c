/* integrator — the driver: the front doors that make an integrator from a
 * model (an LCS, a sweeping process; switched.c makes a switched LCS's),
 * and the calls of the public API through the scheme's table (scheme.h),
 * which schemes.c chooses by the options. It names no scheme: the
 * fixed-step schemes are fixed.c, the event-driven one adaptive_scheme.c;
 * each checks what it needs of the model. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "options.h"
#include "schemes.h"
#include "integrator_impl.h"
#include "record.h"
#include "model/lcs_impl.h"
#include "set/set_impl.h"
#include "util/fail.h"

/* Both front doors end here: the scheme the options name, made from the
 * model that I's fields hold (md: the same, with what only set-up reads). */
static int build(cup_integrator *I, const scheme_model *md, char *errmsg) {
  I->sch = scheme_choose(&I->o);
  return I->sch->create(I, md, &I->ws, errmsg);
}

int cup_integrator_create(cup_integrator **out, const cup_lcs *L, const cup_input *u,
                          const cup_integrator_options *opt, char *errmsg) {
  return integrator_create_shared(out, L, u, opt, NULL, errmsg);
}

int integrator_create_shared(cup_integrator **out, const cup_lcs *L, const cup_input *u,
                             const cup_integrator_options *opt, struct adaptive_scratch **scratch, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "integrator: output pointer is NULL");
  *out = NULL;
  if (!L) return fail_fmt(errmsg, CUP_ERR_ARG, "integrator: LCS is NULL");
  int st;
  cup_integrator *I = integrator_new(opt, errmsg, &st);
  if (!I) return st;
  I->u = u;
  I->L = L;
  I->n = L->n; I->m = L->m; I->p = L->p;
  I->K = L->K;
  I->G = L->has_G ? &L->G : NULL;
  I->fixed = L->fixed;
  freestep_drift D = {L->n, L->p, L->has_A, L->has_E, L->A, L->E, "LCS"};
  scheme_model md = {&D, L, NULL, I->K, I->G, u, &I->o, scratch};
  st = build(I, &md, errmsg);
  if (st) { cup_integrator_free(&I); return st; }
  *out = I;
  return CUP_OK;
}

static int present(const cup_csc *c) { return c->ncol > 0 && c->colptr; }

static int process_model(cup_integrator *I, const cup_process_desc *d, freestep_drift *D, char *errmsg) {
  const cup_set *S = d->C;
  if (!S) return fail_fmt(errmsg, CUP_ERR_ARG, "process: the set C is NULL");
  if (d->n != S->n)
    return fail_fmt(errmsg, CUP_ERR_DIM, "process: n = %d but the set has dimension %d", d->n, S->n);
  if (d->p < 0) return fail_fmt(errmsg, CUP_ERR_DIM, "process: p = %d must be >= 0", d->p);
  if (S->p > 0 && S->p != d->p)
    return fail_fmt(errmsg, CUP_ERR_DIM, "process: the set moves with %d parameters but p = %d", S->p, d->p);
  int st = CUP_OK;
  *D = (freestep_drift){d->n, d->p, present(&d->A), present(&d->E), {0}, {0}, "process"};
  if (D->has_A) st = la_sparse_copy(&I->A_own, &d->A, "A", d->n, d->n, errmsg);
  if (!st && D->has_E) {
    if (d->p == 0) return fail_fmt(errmsg, CUP_ERR_DIM, "process: E is given but p = 0");
    st = la_sparse_copy(&I->E_own, &d->E, "E", d->n, d->p, errmsg);
  }
  D->A = I->A_own;
  D->E = I->E_own;
  I->S = S;
  I->u = d->u;
  I->n = d->n;
  I->p = d->p;
  if (S->kind == CUP_SET_POLYSET) {
    I->K = S->K;
    I->m = S->K->m;
    I->G = S->has_G ? &S->G : NULL;
    I->fixed = 1;
    for (int k = 0; I->G && k < I->G->nnz; k++)
      if (I->G->x[k] != 0) I->fixed = 0;
  }
  return st;
}

int cup_integrator_create_process(cup_integrator **out, const cup_process_desc *d,
                                  const cup_integrator_options *opt, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "integrator: output pointer is NULL");
  *out = NULL;
  if (!d) return fail_fmt(errmsg, CUP_ERR_ARG, "integrator: process description is NULL");
  int st;
  cup_integrator *I = integrator_new(opt, errmsg, &st);
  if (!I) return st;
  freestep_drift D;
  st = process_model(I, d, &D, errmsg);
  scheme_model md = {&D, NULL, d, I->K, I->G, I->u, &I->o, NULL};
  if (!st) st = build(I, &md, errmsg);
  if (st) { cup_integrator_free(&I); return st; }
  *out = I;
  return CUP_OK;
}

void cup_integrator_free(cup_integrator **Ip) {
  if (!Ip || !*Ip) return;
  cup_integrator *I = *Ip;
  if (I->sch && I->ws) I->sch->free(I->ws);
  la_sparse_free(&I->A_own);
  la_sparse_free(&I->E_own);
  free(I->restored_info);
  free(I);
  *Ip = NULL;
}

int cup_integrator_run(cup_integrator *I, const double *x0, cup_sample_fn sink, void *sink_ctx,
                       cup_run_info *info_out) {
  cup_run_info local;
  cup_run_info *info = info_out ? info_out : &local;
  if (!I || !x0) {
    memset(info, 0, sizeof *info);
    info->err_est = NAN;
    return info->status = CUP_ERR_ARG;
  }
  I->restored = 0;
  return I->sch->run(I->ws, x0, sink, sink_ctx, info);
}

void integrator_wall_limit(cup_integrator *I, double seconds) {
  I->o.max_wall_seconds = seconds;
  if (I->sch->wall_limit) I->sch->wall_limit(I->ws, seconds);
}

/* A restored checkpoint (checkpoint.c): the saved run's statistics, then
 * the scheme goes on from its stop. */
int cup_integrator_resume(cup_integrator *I, cup_sample_fn sink, void *sink_ctx, cup_run_info *info_out) {
  cup_run_info local;
  cup_run_info *info = info_out ? info_out : &local;
  if (!I || !I->restored) {
    memset(info, 0, sizeof *info);
    info->err_est = NAN;
    return info->status = CUP_ERR_ARG;
  }
  *info = *I->restored_info;
  I->restored = 0;
  return I->sch->resume(I->ws, sink, sink_ctx, info);
}

const double *cup_integrator_state(const cup_integrator *I) { return I ? I->sch->state(I->ws) : NULL; }

int cup_integrator_zeta(const cup_integrator *I, double *zeta) {
  if (!I || !zeta) return CUP_ERR_ARG;
  return I->sch->zeta(I->ws, zeta);
}

int integrator_record(const cup_integrator *I, const signal_map *S, double *out) {
  return I && S && I->sch->record ? I->sch->record(I->ws, S, out) : 0;
}

int integrator_set_put(cup_integrator *I, cup_netlist *nl, record_put_fn put) {
  return I && I->sch->set_put ? I->sch->set_put(I->ws, nl, put) : 0;
}

int cup_integrator_rows(const cup_integrator *I) { return I ? I->m : 0; }

/* adaptive_scheme — the event-driven scheme as an entry of the scheme table
 * (scheme.h): its hooks over adaptive.h's entry points (set-up in
 * adaptive.c, the run and checkpoints in adaptive_run.c, zeta in
 * adaptive_sample.c). */
#include "catchup.h"
#include "adaptive.h"
#include "integrator_impl.h"
#include "model/lcs_impl.h"
#include "util/fail.h"

static int takes(const cup_integrator_options *o) { return o->scheme == CUP_SCHEME_ADAPTIVE; }

/* An LCS with a reciprocal network (any D), or a process that is an LCS
 * (a polyset, f = A x + E u). */
static int create(cup_integrator *I, const scheme_model *md, void **ws, char *errmsg) {
  (void)I;
  const cup_lcs *L = md->L;
  const cup_process_desc *d = md->pd;
  if (L && L->has_D && L->keep_B)
    return lcs_needs_reciprocal(cup_scheme_name(CUP_SCHEME_ADAPTIVE), "its state jumps are projections in the "
                                "energy metric P and its choice of the active set takes the network as passive",
                                errmsg);
  if (d && (!md->K || d->f || d->f_integral))
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED, "adaptive scheme: it steps an LCS, a polyset with f = A x + E u "
                    "(this process has %s); use the explicit, implicit or exponential scheme",
                    !md->K ? "another set" : d->f ? "a callback f" : "a term f_integral");
  adaptive_ws *A = NULL;
  int st = adaptive_create(&A, md->D, md->K, md->G, L && L->has_D ? &L->B : NULL, L && L->has_D ? &L->D : NULL,
                           md->u, md->o, md->scratch, errmsg);
  *ws = A;
  return st;
}

static void free_ws(void *ws) {
  adaptive_ws *A = ws;
  adaptive_free(&A);
}

static int run(void *ws, const double *x0, cup_sample_fn sink, void *sink_ctx, cup_run_info *info) {
  return adaptive_run(ws, x0, sink, sink_ctx, info);
}

static const double *state(const void *ws) { return adaptive_state(ws); }
static int zeta(void *ws, double *z) { return adaptive_zeta(ws, z); }
static int record(void *ws, const struct signal_map *S, double *out) { return adaptive_record(ws, S, out); }

static int set_put(void *ws, cup_netlist *nl, record_put_fn put) {
  return adaptive_set_put(ws, nl, put);
}

static int stopped(const void *ws, cup_run_info *info) {
  if (!adaptive_stopped(ws)) return 0;
  adaptive_unstop(ws, info);
  return 1;
}

static void checkpoint(void *ws, ckpt *c) { adaptive_checkpoint(ws, c); }

static int resume(void *ws, cup_sample_fn sink, void *sink_ctx, cup_run_info *info) {
  return adaptive_resume(ws, sink, sink_ctx, info);
}

static void wall_limit(void *ws, double seconds) { adaptive_wall_limit(ws, seconds); }

static const scheme_type adaptive_type = {
  .name = "adaptive", .takes = takes, .create = create, .free = free_ws, .run = run, .state = state,
  .zeta = zeta, .record = record, .set_put = set_put, .stopped = stopped, .checkpoint = checkpoint, .resume = resume, .wall_limit = wall_limit,
};
const scheme_type *const scheme_adaptive = &adaptive_type;

adaptive_ws *adaptive_of(const cup_integrator *I) { return I->sch == scheme_adaptive ? I->ws : NULL; }

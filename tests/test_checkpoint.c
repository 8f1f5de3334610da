/* checkpoint: a run stopped at several points — by its sink refusing a
 * sample, by the interrupt flag (polled every 1024 steps), by the step
 * callback — saved, restored into a fresh integrator of the same scene and
 * resumed, again and again until T, gives the samples of the run that was
 * never stopped bit for bit (memcmp of every t and x, and of zeta, the
 * signals' input, at each sample), the same events, and the same
 * statistics and status. For the explicit scheme's exact small-LCP path
 * (its fused steps included), its dense active-set projector and its
 * projected gradient, the theta and implicit schemes, the step-doubling
 * estimate and the adaptive scheme (sines, a square wave's breakpoints, an
 * accumulation of events). And the refusals: a blob into another
 * configuration, a blob cut short, a run that did not stop. */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include "testutil.h"

#define EX CUP_SOURCE_DIR "/examples"

/* ---- what a run gives ---- */

typedef struct {
  int n, m;
  long count, cap;
  double *t, *x, *zeta;     /* per sample: t; x (n); zeta (m) */
  long *k;
  long nev, capev;
  double *ev;               /* per event: t, row, on */
} trace;

typedef struct {
  trace *tr;
  cup_integrator *I;        /* for zeta */
  long refuse_at;           /* refuse the sample with this index in the trace (-1: none) */
  volatile int *flag;       /* set at sample flag_at (the run stops at the next poll) */
  long flag_at;
  long refused;
  int first;                /* set the flag at the first sample of each run or resume */
  long every;               /* refuse each sample whose index is a multiple of this (once) */
} sink_ctx;

static void trace_init(trace *tr, int n, int m) {
  memset(tr, 0, sizeof *tr);
  tr->n = n;
  tr->m = m;
}

static void trace_free(trace *tr) {
  free(tr->t); free(tr->x); free(tr->zeta); free(tr->k); free(tr->ev);
}

static int sink(long k, double t, const double *x, void *ctx) {
  sink_ctx *c = ctx;
  trace *tr = c->tr;
  if (tr->count == c->refuse_at && c->refused == 0) { c->refused = 1; return 1; }
  if (c->every && tr->count % c->every == 0 && c->refused != tr->count + 1) { c->refused = tr->count + 1; return 1; }
  if (c->flag && (tr->count == c->flag_at || c->first)) *c->flag = 1;
  c->first = 0;
  if (tr->count == tr->cap) {
    tr->cap = 2 * tr->cap + 64;
    tr->t = realloc(tr->t, sizeof(double) * (size_t)tr->cap);
    tr->k = realloc(tr->k, sizeof(long) * (size_t)tr->cap);
    tr->x = realloc(tr->x, sizeof(double) * (size_t)(tr->cap * tr->n));
    tr->zeta = realloc(tr->zeta, sizeof(double) * (size_t)(tr->cap * tr->m + 1));
  }
  tr->t[tr->count] = t;
  tr->k[tr->count] = k;
  memcpy(tr->x + tr->count * tr->n, x, sizeof(double) * (size_t)tr->n);
  if (tr->m) assert_int_equal(cup_integrator_zeta(c->I, tr->zeta + tr->count * tr->m), CUP_OK);
  tr->count++;
  return 0;
}

static int event(double t, int row, int on, void *ctx) {
  trace *tr = ctx;
  if (tr->nev == tr->capev) {
    tr->capev = 2 * tr->capev + 64;
    tr->ev = realloc(tr->ev, sizeof(double) * 3 * (size_t)tr->capev);
  }
  double *e = tr->ev + 3 * tr->nev++;
  e[0] = t; e[1] = row; e[2] = on;
  return 0;
}

typedef struct { long at; long seen; } step_stop;

static int on_step(long k, double t, const cup_proj_info *pi, void *ctx) {
  (void)t; (void)pi;
  step_stop *s = ctx;
  if (k == s->at && !s->seen) { s->seen = 1; return 1; }
  return 0;
}

/* ---- a case ---- */

typedef struct {
  const char *name, *scene;
  const char *ovr[6];       /* the scene's overrides (key=value), up to the first NULL */
} scene_case;

static cup_scene *load(const scene_case *sc) {
  char err[CUP_ERRMSG_LEN];
  cup_scene *s = NULL;
  int novr = 0;
  while (novr < 6 && sc->ovr[novr]) novr++;
  if (cup_scene_load(&s, sc->scene, sc->ovr, novr, err) != CUP_OK) fail_msg("%s: %s", sc->name, err);
  return s;
}

static cup_integrator *make(const cup_scene *s, trace *tr, volatile int *flag, step_stop *ss) {
  cup_integrator_options o = *cup_scene_options(s);
  o.on_event = event;
  o.event_ctx = tr;
  o.interrupt = (const volatile int *)flag;
  if (ss) { o.on_step = on_step; o.step_ctx = ss; }
  char err[CUP_ERRMSG_LEN];
  cup_integrator *I = NULL;
  if (cup_scene_integrator(s, &o, &I, err) != CUP_OK) fail_msg("%s", err);
  return I;
}

/* How a run is stopped: the sink refuses the sample with index `refuse`
 * (of the whole run), the flag is set at the sample with index `flag_at`
 * (or before each run and resume with poll = 1: a stop every 1024 steps;
 * with poll = 2 at each run's first sample: the estimate's coarse run, which
 * the flag stops too, is over by then), or the step callback stops after
 * step `step`; or the sink refuses every `every`-th sample. -1 (0 for
 * every): not that way. */
typedef struct { long refuse, flag_at; int poll; long step, every; } stopper;

/* Stopped as `how` says (the flag again after each resume when poll),
 * saved, restored into a new integrator and resumed until the end. */
static int run_stopped(const cup_scene *s, const stopper *how, trace *tr, cup_run_info *info, int *stops) {
  volatile int flag = how->poll == 1;
  step_stop ss = {how->step, 0};
  sink_ctx c = {tr, NULL, how->refuse, how->flag_at >= 0 || how->poll ? &flag : NULL, how->flag_at, 0,
                how->poll == 2, how->every};
  cup_integrator *I = make(s, tr, &flag, how->step >= 0 ? &ss : NULL);
  c.I = I;
  int st = cup_integrator_run(I, cup_scene_x0(s), sink, &c, info);
  *stops = 0;
  while ((st == CUP_ERR_INTERRUPTED || st == CUP_ERR_TIME_LIMIT) && *stops < 10000) {
    ++*stops;
    long size = cup_integrator_checkpoint_size(I);
    if (size <= 0) fail_msg("checkpoint size %ld after a stop at step %ld: %s", size, info->step, info->message);
    void *blob = malloc((size_t)size);
    assert_int_equal(cup_integrator_checkpoint_save(I, info, blob, (unsigned long)size), CUP_OK);
    cup_integrator_free(&I);
    flag = how->poll == 1;
    c.first = how->poll == 2;
    I = make(s, tr, &flag, how->step >= 0 ? &ss : NULL);
    c.I = I;
    char err[CUP_ERRMSG_LEN];
    if (cup_integrator_checkpoint_restore(I, blob, (unsigned long)size, err) != CUP_OK) fail_msg("restore: %s", err);
    free(blob);
    st = cup_integrator_resume(I, sink, &c, info);
  }
  cup_integrator_free(&I);
  return st;
}

static void same_bits(const char *what, const void *a, const void *b, size_t n, long at) {
  if (memcmp(a, b, n)) fail_msg("%s differs at sample %ld", what, at);
}

static void compare(const char *name, const trace *a, const cup_run_info *ia, const trace *b,
                    const cup_run_info *ib) {
  if (a->count != b->count) fail_msg("%s: %ld samples, %ld resumed", name, a->count, b->count);
  for (long j = 0; j < a->count; j++) {
    same_bits("t", a->t + j, b->t + j, sizeof(double), j);
    same_bits("k", a->k + j, b->k + j, sizeof(long), j);
    same_bits("x", a->x + j * a->n, b->x + j * b->n, sizeof(double) * (size_t)a->n, j);
    if (a->m) same_bits("zeta", a->zeta + j * a->m, b->zeta + j * b->m, sizeof(double) * (size_t)a->m, j);
  }
  if (a->nev != b->nev) fail_msg("%s: %ld events, %ld resumed", name, a->nev, b->nev);
  if (a->nev) same_bits("events", a->ev, b->ev, sizeof(double) * 3 * (size_t)a->nev, 0);
  assert_int_equal(ia->status, ib->status);
  assert_string_equal(ia->message, ib->message);
  assert_int_equal(ia->step, ib->step);
  assert_int_equal(ia->projected, ib->projected);
  assert_int_equal(ia->skipped, ib->skipped);
  assert_int_equal(ia->not_certified, ib->not_certified);
  assert_int_equal(ia->dual_iterations, ib->dual_iterations);
  assert_int_equal(ia->samples, ib->samples);
  assert_int_equal(ia->events, ib->events);
  assert_int_equal(ia->rejected, ib->rejected);
  same_bits("t_end", &ia->t, &ib->t, sizeof(double), -1);
  same_bits("max_eps_cert", &ia->max_eps_cert, &ib->max_eps_cert, sizeof(double), -1);
  same_bits("max_eta_cert", &ia->max_eta_cert, &ib->max_eta_cert, sizeof(double), -1);
  if (!(isnan(ia->err_est) && isnan(ib->err_est))) same_bits("err_est", &ia->err_est, &ib->err_est, sizeof(double), -1);
}

/* The case run whole, then stopped each way in turn. */
static void check_case(const scene_case *sc) {
  cup_scene *s = load(sc);
  int n = cup_scene_dim(s), m = cup_lcs_rows(cup_scene_lcs(s));
  trace whole;
  trace_init(&whole, n, m);
  cup_run_info iw;
  {
    volatile int never = 0;
    sink_ctx c = {&whole, NULL, -1, NULL, -1, 0, 0, 0};
    cup_integrator *I = make(s, &whole, &never, NULL);
    c.I = I;
    cup_integrator_run(I, cup_scene_x0(s), sink, &c, &iw);
    cup_integrator_free(&I);
  }
  assert_true(iw.status >= 0);
  long S = whole.count, K = iw.step;
  const stopper ways[] = {
    {0, -1, 0, -1, 0}, {1, -1, 0, -1, 0}, {S / 3, -1, 0, -1, 0}, {S - 1, -1, 0, -1, 0},   /* the sink refuses */
    {-1, -1, 0, -1, S / 40 + 1},                                   /* ... every 40th of the samples */
    {-1, S / 2, 0, -1, 0},                                         /* the flag, mid-run */
    {-1, -1, 1, -1, 0},                                            /* the flag at every poll */
    {-1, -1, 2, -1, 0},                                            /* the flag at each run's first sample */
    {-1, -1, 0, K / 3 + 1, 0},                                     /* the step callback */
  };
  for (size_t w = 0; w < sizeof ways / sizeof ways[0]; w++) {
    if (ways[w].poll == 1 && cup_scene_options(s)->estimate) continue;   /* it would stop in the coarse run forever */
    trace tr;
    trace_init(&tr, n, m);
    cup_run_info ir;
    int stops;
    int st = run_stopped(s, &ways[w], &tr, &ir, &stops);
    print_message("%s, way %zu: %d stop%s, %ld samples, %ld steps, %ld events: %s\n", sc->name, w, stops,
                  stops == 1 ? "" : "s", tr.count, ir.step, ir.events, cup_status_name(st));
    if (ways[w].poll == 1 && !cup_scene_options(s)->estimate && K >= 2048) assert_true(stops >= K / 1024 - 1);
    if ((ways[w].refuse >= 0 && ways[w].refuse < S) || ways[w].step >= 0) assert_true(stops >= 1);
    if (ways[w].every) assert_true(stops >= (S - 1) / ways[w].every);
    compare(sc->name, &whole, &iw, &tr, &ir);
    trace_free(&tr);
  }
  trace_free(&whole);
  cup_scene_free(&s);
}

#define FIG2 EX "/paper-fig2.yaml"
#define BRIDGE EX "/circuits/series-resonant.yaml"
static const scene_case cases[] = {
  {"implicit, sparse set (Newton on CHOLMOD factors)", EX "/sparse-mtx/scene.yaml",
   {"n=3000", "output={every: 3}"}},
  {"explicit, exact small LCP (fused steps)", FIG2, {"n=20000", "output={every: 7}"}},
  {"explicit, dense active-set projector", FIG2, {"n=20000", "output={samples: 101}", "projector.method=activeset"}},
  {"explicit, projected gradient", FIG2,
   {"n=3000", "output={every: 10}", "projector.method=pg", "eps=1e-10", "eta=1e-8"}},
  {"theta", FIG2, {"n=20000", "scheme=theta", "output={every: 13}"}},
  {"theta through a diode bridge (D != 0: the weights' mode and Pi zeta)", BRIDGE,
   {"n=40000", "scheme=theta", "output={every: 9}"}},
  {"implicit, output final", FIG2, {"n=9000", "scheme=implicit", "output=final"}},
  {"explicit with the step-doubling estimate", FIG2, {"n=6000", "estimate=true", "output={samples: 11}"}},
  {"adaptive, every step", FIG2, {"scheme=adaptive", "tol=1e-10", "output={every: 1}", "T=100"}},
  {"adaptive, samples", FIG2, {"scheme=adaptive", "tol=1e-8", "output={samples: 501}", "T=3"}},
  {"adaptive through a diode bridge (D != 0), samples inside steps and events", BRIDGE,
   {"scheme=adaptive", "tol=1e-8", "output={samples: 801}"}},
  {"adaptive through a diode into an RC load (D != 0), every step: a step's end carried to the next",
   EX "/circuits/halfwave-rc.yaml", {"scheme=adaptive", "tol=1e-8", "output={every: 1}", "hmax=1e-4"}},
  {"theta, samples between steps (interpolated)", FIG2, {"n=20000", "scheme=theta", "output={samples: 301}"}},
  {"explicit, square wave", EX "/paper-fig3.yaml", {"n=30000", "output={every: 11}"}},
  {"adaptive, square wave (breakpoints)", EX "/paper-fig3.yaml",
   {"scheme=adaptive", "tol=1e-9", "output={every: 2}", "T=4"}},
  {"adaptive, accumulating events (catching-up steps)", FIG2,
   {"scheme=adaptive", "max_event_rate=5", "output={every: 1}", "T=100"}},
};

static void test_resumed_is_bit_for_bit(void **state) { check_case(*state); }

/* A blob goes only into an integrator of its configuration, whole. */
static void test_refusals(void **state) {
  (void)state;
  scene_case sc = {"refusals", FIG2, {"n=20000", "output={every: 7}"}};   /* the fused steps' case */
  cup_scene *s = load(&sc);
  trace tr;
  trace_init(&tr, 3, 2);
  volatile int flag = 0;
  sink_ctx c = {&tr, NULL, 5, NULL, -1, 0, 0, 0};
  cup_integrator *I = make(s, &tr, &flag, NULL);
  c.I = I;
  cup_run_info info;
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_integrator_checkpoint_size(I), CUP_ERR_ARG);          /* no run yet */
  assert_int_equal(cup_integrator_resume(I, sink, &c, &info), CUP_ERR_ARG);  /* nothing restored */
  assert_int_equal(cup_integrator_run(I, cup_scene_x0(s), sink, &c, &info), CUP_ERR_INTERRUPTED);
  long size = cup_integrator_checkpoint_size(I);
  assert_true(size > 0);
  unsigned char *blob = malloc((size_t)size);
  assert_int_equal(cup_integrator_checkpoint_save(I, &info, blob, (unsigned long)size - 1), CUP_ERR_ARG);
  assert_int_equal(cup_integrator_checkpoint_save(I, &info, blob, (unsigned long)size), CUP_OK);
  /* another n, another scheme */
  cup_integrator_options o = *cup_scene_options(s);
  o.n = 20001;
  cup_integrator *J = NULL;
  assert_int_equal(cup_scene_integrator(s, &o, &J, err), CUP_OK);
  assert_int_equal(cup_integrator_checkpoint_restore(J, blob, (unsigned long)size, err), CUP_ERR_ARG);
  assert_string_equal(err, "the checkpoint is of another run: n = 20000 there, 20001 here");
  cup_integrator_free(&J);
  o.n = 20000;
  o.scheme = CUP_SCHEME_THETA;
  assert_int_equal(cup_scene_integrator(s, &o, &J, err), CUP_OK);
  assert_int_equal(cup_integrator_checkpoint_restore(J, blob, (unsigned long)size, err), CUP_ERR_ARG);
  assert_string_equal(err, "the checkpoint is of another run: scheme = 0 there, 3 here");
  cup_integrator_free(&J);
  /* cut short, longer, garbage */
  J = make(s, &tr, &flag, NULL);
  assert_int_equal(cup_integrator_checkpoint_restore(J, blob, (unsigned long)size - 8, err), CUP_ERR_ARG);
  assert_non_null(strstr(err, "cut short"));
  blob[0] ^= 1;
  assert_int_equal(cup_integrator_checkpoint_restore(J, blob, (unsigned long)size, err), CUP_ERR_ARG);
  assert_non_null(strstr(err, "not a catchup checkpoint"));
  cup_integrator_free(&J);
  free(blob);
  /* a run that ended, or failed, has nothing to resume */
  c.refuse_at = -1;
  assert_true(cup_integrator_run(I, cup_scene_x0(s), sink, &c, &info) >= 0);
  assert_int_equal(cup_integrator_checkpoint_size(I), CUP_ERR_ARG);
  cup_integrator_free(&I);
  trace_free(&tr);
  cup_scene_free(&s);
  /* a ball's process: not saved */
  scene_case disc = {"disc", EX "/rotating-disc.yaml", {NULL}};
  s = load(&disc);
  I = make(s, &tr, &flag, NULL);
  trace_init(&tr, cup_scene_dim(s), 0);
  c.tr = &tr;
  c.I = I;
  c.refuse_at = 3;
  c.refused = 0;
  assert_int_equal(cup_integrator_run(I, cup_scene_x0(s), sink, &c, &info), CUP_ERR_INTERRUPTED);
  assert_int_equal(cup_integrator_checkpoint_size(I), CUP_ERR_UNSUPPORTED);
  cup_integrator_free(&I);
  trace_free(&tr);
  cup_scene_free(&s);
}

int main(void) {
  struct CMUnitTest tests[sizeof cases / sizeof cases[0] + 1];
  size_t k = 0;
  for (; k < sizeof cases / sizeof cases[0]; k++)
    tests[k] = (struct CMUnitTest)cmocka_unit_test_prestate(test_resumed_is_bit_for_bit, (void *)&cases[k]);
  tests[k++] = (struct CMUnitTest)cmocka_unit_test(test_refusals);
  return cmocka_run_group_tests(tests, NULL, NULL);
}

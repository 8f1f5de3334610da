/* switch_samples: a switched run's samples at and around its switching
 * times against the closed form of a two-capacitor circuit (docs/netlist.md,
 * .tran; switched.c). V1 charges C1 through R1 (C1 starts at V1: at rest),
 * C2 starts empty, and S1 closes C1 onto C2 at ts: the state jumps to the
 * charge-conserving C1 V1 / (C1 + C2) on both (the projection in the energy
 * metric), then both charge towards V1 with tau2 = R1 (C1 + C2), S1
 * carrying C2's current. Left of ts: (V1, 0), no current through S1.
 *
 * 1. The sample on a switching time is held by the window that ends there
 *    and given by the next one after the jump (the right limit). Every way
 *    the next window can fail to start (its configuration not formed, the
 *    rule's callback failing, the input failing at its start, the user's
 *    interrupt at the held window's last step) still gives that sample:
 *    as the window left it (the left limit) where the next configuration
 *    did not start, else the right limit; and a sink that refuses a sample
 *    is not called again.
 * 2. Samples inside a fixed-step step that holds a switching time (split
 *    there) are on their side of the jump: the left limit's flow before
 *    it, the right limit's after, each interpolated between its own
 *    piece's ends, never across the jump. */
#include <float.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include "testutil.h"
#include "switch_wrap.h"

static const double V1 = 10, R1 = 1e3, C1 = 1e-6, C2 = 3e-6;

static const char circuit[] = "two capacitors, charged\n"
                              "V1 in 0 10\nR1 in a 1k\nC1 a 0 1u IC=10\nC2 b 0 3u\nS1 a b g 0 SMOD\n"
                              "Vg g 0 PULSE(0 1 %.17g jump jump %.17g 2)\n.model SMOD SW(VT=0.5 VH=0.1)\n";

/* The closed form at t for S1 closed on [ts, t2): right (1) or left (0)
 * limit at a switching time itself. x = (v(a), v(b)) and the current
 * through S1. Once it opens again C2 keeps its voltage and C1 charges
 * back towards V1 with tau1 = R1 C1. */
static void exact2(double t, double ts, double t2, int right, double *x, double *is) {
  if (t < ts || (t == ts && !right)) {
    x[0] = V1, x[1] = 0, *is = 0;
    return;
  }
  double v0 = C1 * V1 / (C1 + C2), tau = R1 * (C1 + C2), tc = t < t2 || (t == t2 && !right) ? t : t2;
  double e = exp(-(tc - ts) / tau);
  x[0] = x[1] = V1 - (V1 - v0) * e;
  *is = C2 * (V1 - v0) / tau * e;
  if (tc == t) return;
  x[0] = V1 - (V1 - x[1]) * exp(-(t - t2) / (R1 * C1));
  *is = 0;
}

static void exact(double t, double ts, int right, double *x, double *is) { exact2(t, ts, INFINITY, right, x, is); }

/* ---- the wrapped model: failures injected at the switching ---------------- */

enum fail { NONE, FORM, SETTLE, INPUT, INTERRUPT, REFUSE };

typedef struct {
  cup_switching sw;            /* the netlist's (first: switch_wrap.h) */
  const cup_input *u;          /* the netlist's input */
  enum fail fail;
  double ts;
  int armed;                   /* the switching settled: INPUT fails from now on */
  volatile int stop;           /* INTERRUPT: the run's interrupt flag */
} wrap;

static int w_settle(void *ctx, int *topo, double t, const double *x, const double *zeta, char *errmsg) {
  wrap *W = ctx;
  if (t >= W->ts) {
    W->armed = 1;
    if (W->fail == SETTLE) {
      snprintf(errmsg, CUP_ERRMSG_LEN, "injected: the rule fails at t = %g", t);
      return CUP_ERR_CALLBACK;
    }
  }
  return W->sw.settle(W->sw.ctx, topo, t, x, zeta, errmsg);
}

static const cup_lcs *w_lcs(void *ctx, int topo) {
  wrap *W = ctx;
  return W->fail == FORM && topo != 0 ? NULL : W->sw.lcs(W->sw.ctx, topo);
}

static int w_input(double t, double *u, void *ctx) {
  wrap *W = ctx;
  if (W->fail == INPUT && W->armed) return 1;
  return cup_input_eval(W->u, t, u);
}

/* ---- the run and its samples ---------------------------------------------- */

typedef struct {
  cup_netlist *nl;
  const cup_integrator *I;
  wrap *W;
  int sig;                     /* i(S1) */
  long count, cap, refuse_at;  /* refuse_at: the sample refused (-1: none) */
  long calls_after;            /* calls after the refusal */
  double t[8192], x[8192][2], s[8192];
} rec;

static int sink(long k, double t, const double *x, void *ctx) {
  (void)k;
  rec *r = ctx;
  if (r->refuse_at >= 0 && r->count >= r->refuse_at) {
    r->calls_after += r->count > r->refuse_at;
    r->count += r->count == r->refuse_at;        /* (counted once: the refused one) */
    return 1;
  }
  if (r->count == r->cap) return 1;
  double zeta[16] = {0}, out[16];
  cup_integrator_zeta(r->I, zeta);
  assert_int_equal(cup_netlist_signals(r->nl, t, x, zeta, out), CUP_OK);
  r->t[r->count] = t;
  r->x[r->count][0] = x[0];
  r->x[r->count][1] = x[1];
  r->s[r->count] = out[r->sig];
  r->count++;
  if (r->W->fail == INTERRUPT && t > 0.3 * r->W->ts) r->W->stop = 1;   /* seen at the next 1024th step */
  return 0;
}

/* The circuit, S1 closed from ts for width, under options o with failure
 * f (REFUSE: of sample refuse_at): the status, the samples in r. */
static int run_case2(double ts, double width, cup_integrator_options *o, enum fail f, long refuse_at, rec *r,
                     char *message) {
  char text[512], err[CUP_ERRMSG_LEN];
  snprintf(text, sizeof text, circuit, ts, width);
  cup_netlist *nl = NULL;
  if (cup_netlist_load_string(&nl, text, "t.cir", NULL, 0, err)) fail_msg("%s", err);
  wrap W = {.fail = f, .ts = ts};
  assert_int_equal(cup_netlist_switching(nl, &W.sw), 1);
  W.u = cup_netlist_input(nl);
  cup_switching sw = fwd_switching(&W);
  sw.settle = w_settle;
  sw.lcs = w_lcs;
  cup_input *u = NULL;
  assert_int_equal(cup_input_create(&u, cup_input_dim(W.u), err), CUP_OK);
  assert_int_equal(cup_input_set_callback(u, w_input, &W, 1e-12, 1e-12), CUP_OK);
  memset(r, 0, offsetof(rec, t));
  r->nl = nl;
  r->W = &W;
  r->cap = 8192;
  r->refuse_at = f == REFUSE ? refuse_at : -1;
  r->sig = cup_netlist_probe(nl, "i(S1)", err);
  if (r->sig < 0) fail_msg("%s", err);
  o->interrupt = f == INTERRUPT ? (const volatile int *)&W.stop : NULL;
  cup_integrator *I = NULL;
  if (cup_integrator_create_switched(&I, &sw, u, o, err)) fail_msg("create: %s", err);
  r->I = I;
  cup_run_info info;
  int st = cup_integrator_run(I, cup_netlist_x0(nl), sink, r, &info);
  snprintf(message, CUP_RUN_MSG_LEN, "%s", info.message);
  cup_integrator_free(&I);
  cup_input_free(&u);
  cup_netlist_free(&nl);
  r->nl = NULL;
  r->W = NULL;
  return st;
}

static int run_case(double ts, cup_integrator_options *o, enum fail f, rec *r, char *message) {
  return run_case2(ts, 1, o, f, -1, r, message);
}

static void options(cup_integrator_options *o, cup_scheme s, long n, long samples, double T) {
  cup_integrator_options_default(o);
  o->scheme = s;
  o->n = n;
  o->T = T;
  o->tol_abs = o->tol_rel = 1e-10;
  o->output = CUP_OUTPUT_SAMPLES;
  o->output_samples = samples;
}

/* The index of the sample at time t, or -1. */
static long sample_at(const rec *r, double t) {
  for (long j = 0; j < r->count; j++)
    if (r->t[j] == t) return j;
  return -1;
}

/* The sample at ts: present, on the side expected (right 1, left 0), and
 * every sample before it on the closed form. */
static void check_held(const rec *r, double ts, int right, const char *what) {
  long j = sample_at(r, ts);
  if (j < 0) fail_msg("%s: the sample at the switching time t = %g is missing (%ld samples)", what, ts, r->count);
  double worst = 0, x[2], is;
  for (long i = 0; i < j; i++) {
    exact(r->t[i], ts, 1, x, &is);
    worst = fmax(worst, fmax(fabs(r->x[i][0] - x[0]), fabs(r->x[i][1] - x[1])));
  }
  exact(ts, ts, right, x, &is);
  double at = fmax(fabs(r->x[j][0] - x[0]), fabs(r->x[j][1] - x[1])), sat = fabs(fabs(r->s[j]) - is);
  print_message("%-28s sample %ld at t = %g: %s limit, error %.2e V (i(S1) %.2e A), before it %.2e V\n", what, j,
                ts, right ? "right" : "left", at, sat, worst);
  assert_true(at <= 1e-9 * V1);
  assert_true(sat <= 1e-6 * is + 1e-12);
  assert_true(worst <= 1e-9 * V1);
}

static const struct { cup_scheme s; const char *name; } schemes[] = {
  {CUP_SCHEME_THETA, "theta"}, {CUP_SCHEME_ADAPTIVE, "adaptive"},
};

/* 1. The held sample reaches the sink whatever stops the run after it. */
static void test_held_sample_kept(void **state) {
  (void)state;
  const double T = 2e-3, ts = 1e-3;
  static rec r;
  char msg[CUP_RUN_MSG_LEN], what[96];
  for (int q = 0; q < 2; q++) {
    cup_integrator_options o;
    options(&o, schemes[q].s, 2048, 2049, T);
    /* no failure: the right limit, and the whole run */
    assert_int_equal(run_case(ts, &o, NONE, &r, msg), CUP_OK);
    assert_int_equal(r.count, 2049);
    snprintf(what, sizeof what, "%s, unbroken", schemes[q].name);
    check_held(&r, ts, 1, what);
    static const struct { enum fail f; const char *name; } fails[] = {
      {FORM, "not formed"}, {SETTLE, "rule fails"}, {INPUT, "input fails"}, {INTERRUPT, "interrupt"},
    };
    for (int c = 0; c < 4; c++) {
      if (fails[c].f == INTERRUPT && schemes[q].s == CUP_SCHEME_ADAPTIVE) continue;   /* (its 1024th step is far) */   /* (its 1024th step is far) */
      int st = run_case(ts, &o, fails[c].f, &r, msg);
      snprintf(what, sizeof what, "%s, %s", schemes[q].name, fails[c].name);
      print_message("%-28s %s: %s\n", what, cup_status_name(st), msg);
      assert_true(st < 0);
      assert_int_equal(r.count, 1025);
      /* the right limit where the next configuration started (the fixed-step schemes give it before a step) */
      int right = fails[c].f == INPUT && schemes[q].s != CUP_SCHEME_ADAPTIVE;
      check_held(&r, ts, right, what);
    }
    /* a sink that refuses the held sample is not called again; one that
     * refuses the next has the held one, the right limit */
    for (long at = 1024; at <= 1025; at++) {
      int st = run_case2(ts, 1, &o, REFUSE, at, &r, msg);
      snprintf(what, sizeof what, "%s, sample %ld refused", schemes[q].name, at);
      print_message("%-28s %s: %s\n", what, cup_status_name(st), msg);
      assert_int_equal(st, CUP_ERR_INTERRUPTED);
      assert_int_equal(r.calls_after, 0);
      assert_int_equal(r.count, at + 1);          /* (the refused one counted) */
      if (at == 1025) check_held(&r, ts, 1, what);
    }
  }
}

/* 2. Samples inside a split step: S1 closes at ts inside step k (h = 10
 * us) and, in the second case, opens again within the same step (three
 * pieces); samples every 1 us, one of them on a switching time in the
 * third case (that sample's time a rounding from the gate's edge: the
 * right limit). Each sample against the closed form on its side: inside
 * the split step within the pieces' linear interpolation (h^2 |v''| / 8 =
 * 6e-6 V), i(S1) 0 left of the closing and after the opening. They were
 * interpolated between the step's ends across the jump: up to 6.8 V off,
 * and i(S1) the closed switch's before it closed. */
static void test_split_step_samples(void **state) {
  (void)state;
  const double T = 2e-3, h = 1e-5;
  static const struct { double ts, width; } cases[] = {{1.0037e-3, 1}, {1.0032e-3, 4e-6}, {1.004e-3, 1}};
  static const cup_scheme fixed[] = {CUP_SCHEME_THETA, CUP_SCHEME_IMPLICIT, CUP_SCHEME_EXPONENTIAL,
                                     CUP_SCHEME_EXPLICIT};
  static rec r;
  char msg[CUP_RUN_MSG_LEN];
  for (int c = 0; c < 3; c++)
    for (int q = 0; q < 4; q++) {
      double ts = cases[c].ts, t2 = ts + cases[c].width, ta = floor(ts / h) * h, tb = ta + h;
      cup_integrator_options o;
      options(&o, fixed[q], 200, 2001, T);
      int st = run_case2(ts, cases[c].width, &o, NONE, -1, &r, msg);
      if (st != CUP_OK) fail_msg("%s: %s", cup_status_name(st), msg);
      assert_int_equal(r.count, 2001);
      double in = 0, out = 0, ileft = 0, iright = 0, x[2], is;
      long inside = 0, left = 0;
      for (long j = 0; j < r.count; j++) {
        double t = r.t[j];
        /* a sample time a rounding short of a switching time is that time's, the right limit */
        double tt = fabs(t - ts) <= 8 * DBL_EPSILON * ts ? ts : fabs(t - t2) <= 8 * DBL_EPSILON * t2 ? t2 : t;
        exact2(tt, ts, t2, 1, x, &is);
        double e = fmax(fabs(r.x[j][0] - x[0]), fabs(r.x[j][1] - x[1]));
        if (t > ta && t < tb) {
          in = fmax(in, e), inside++;
          if (is == 0) ileft = fmax(ileft, fabs(r.s[j])), left++;
          else iright = fmax(iright, fabs(fabs(r.s[j]) - is) / is);
        } else {
          out = fmax(out, e);
        }
      }
      print_message("%-11s S1 on [%.6g, %.6g) ms: %ld samples in the split step (%ld with S1 open): error %.2e V "
                    "there (i(S1) %.1e A open, %.1e relative closed), %.2e V elsewhere\n", cup_scheme_name(fixed[q]),
                    1e3 * ts, 1e3 * fmin(t2, T), inside, left, in, ileft, iright, out);
      assert_int_equal(inside, 9);
      assert_true(left >= 3);
      assert_true(in <= 1e-5 * V1);
      assert_true(ileft <= 1e-12);
      assert_true(iright <= 1e-2);
      assert_true(out <= (fixed[q] == CUP_SCHEME_THETA ? 1e-5 : 2e-3) * V1);
    }
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_held_sample_kept),
    cmocka_unit_test(test_split_step_samples),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

/* switch_quiet: cup_switching's quiet (a netlist's: nl_sw_quiet), which
 * lets a switched run's window skip asking the input for its next
 * breakpoint (switched.c, adaptive_window's jumped & 4). Each claim that
 * the input has no breakpoint in (t, tnext) is checked against the
 * input's own cup_input_next_break (every term, no memo) at that t, and
 * refused for an input other than the netlist's; a run with the claims
 * and one without (quiet NULL) record the same every-step output, bit for
 * bit. A circuit whose input breaks where no switch reads it (a PULSE on
 * the supply) gets no claim at all, though some of its windows hold such
 * a break. The full bridge's and the buck-boost's next switching times
 * (nl_sw_next, its walk piece after piece) are their gates' next corners,
 * computed in closed form; and in the run without claims, every third
 * one is asked again after the netlist's memos are emptied (its time
 * origin set again: the next search from scratch, each gate's piece from
 * its period's division), the same double. */
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>
#include "testutil.h"
#include "switch_wrap.h"

#define CIR CUP_EXAMPLES_DIR "/circuits/"

typedef struct {
  cup_switching in;        /* the netlist's (first: switch_wrap.h) */
  const cup_input *other;  /* an input that is not the netlist's */
  long asked, claims, clear, wrong;
  /* the gates' PULSEs (delay, period, width; jump edges, 0 to 1 against
   * VT = 0.5, each edge a different switch's), when known: each next
   * switching checked against their closed-form corners */
  const double (*gate)[3];
  int ngate;
  long nexts, next_wrong;
  cup_netlist *fresh;      /* the netlist, when its answers are asked again from scratch */
  long fresh_asked, fresh_wrong;
} wrap;

/* The first corner after t of the gates' PULSEs, d + P j and d + P j + w
 * (one within 1e-12 of t is t's own: the netlist's corners are its sums
 * of its parsed values, an ulp or a few from these). */
static double first_edge(const double (*gate)[3], int ngate, double t) {
  double best = INFINITY;
  for (int g = 0; g < ngate; g++) {
    double d = gate[g][0], P = gate[g][1], w = gate[g][2];
    for (double j = fmax(floor((t - d) / P) - 1, 0); j <= floor((t - d) / P) + 2; j++) {
      double e[2] = {d + P * j, d + P * j + w};
      for (int q = 0; q < 2; q++)
        if (e[q] > t + 1e-12 && e[q] < best) best = e[q];
    }
  }
  return best;
}

static int w_next(void *c, int topo, double t, double tmax, double *tnext) {
  wrap *W = c;
  int st = W->in.next(W->in.ctx, topo, t, tmax, tnext);
  if (!st && W->ngate) {
    double e = first_edge(W->gate, W->ngate, t), want = e < tmax ? e : tmax;
    W->nexts++;
    if (!(fabs(*tnext - want) <= 1e-12 * fmax(1, fabs(want)))) {   /* (the edge, within the ulps of its sums) */
      W->next_wrong++;
      print_message("next switching from t = %.17g: %.17g, the gates' next corner %.17g (tmax %.17g)\n", t, *tnext, e,
                    tmax);
    }
  }
  if (!st && W->fresh && W->nexts % 3 == 0) {      /* (the two calls between: a walk begun, then moved on) */
    char err[CUP_ERRMSG_LEN];
    double again = NAN;
    assert_int_equal(cup_netlist_set_time_origin(W->fresh, 0, err), CUP_OK);
    int st2 = W->in.next(W->in.ctx, topo, t, tmax, &again);
    W->fresh_asked++;
    if (st2 || memcmp(&again, tnext, sizeof again)) {
      W->fresh_wrong++;
      print_message("next switching from t = %.17g: %.17g, from scratch %.17g\n", t, *tnext, again);
    }
  }
  return st;
}
static int w_quiet(void *c, int topo, const cup_input *u, double t, double tnext) {
  wrap *W = c;
  int q = W->in.quiet(W->in.ctx, topo, u, t, tnext);
  double nb = cup_input_next_break(u, t);
  W->asked++;
  W->clear += nb >= tnext;
  if (q == 1) {
    W->claims++;
    if (!(nb >= tnext)) {
      W->wrong++;
      print_message("wrong claim: t = %.17g, tnext = %.17g, the input's next break %.17g\n", t, tnext, nb);
    }
    W->wrong += W->in.quiet(W->in.ctx, topo, W->other, t, tnext) != 0;
  }
  return q;
}

typedef struct { double *buf; long cap, n; int dim; } rec_buf;
static int rec_sink(long k, double t, const double *x, void *vp) {
  (void)k;
  rec_buf *r = vp;
  if (r->n + 1 + r->dim > r->cap) return 1;
  r->buf[r->n++] = t;
  for (int i = 0; i < r->dim; i++) r->buf[r->n++] = x[i];
  return 0;
}

/* One run of nl through the wrapper W (its claims when quiet), every step
 * recorded into r. */
static void one_run(cup_netlist *nl, const cup_integrator_options *o, int quiet, wrap *W, rec_buf *r,
                    cup_run_info *info) {
  char err[CUP_ERRMSG_LEN];
  assert_int_equal(cup_netlist_switching(nl, &W->in), 1);
  assert_non_null(W->in.quiet);
  cup_switching sw = fwd_switching(W);
  sw.next = w_next;
  sw.quiet = quiet ? w_quiet : NULL;
  cup_integrator *I = NULL;
  if (cup_integrator_create_switched(&I, &sw, cup_netlist_input(nl), o, err)) fail_msg("%s", err);
  if (cup_integrator_run(I, cup_netlist_x0(nl), rec_sink, r, info) < 0) fail_msg("%s", info->message);
  cup_integrator_free(&I);
}

/* The netlist (a file, or text when file is NULL) run with and without
 * the claims, the same records; the claims' counts into *W. */
static void run_both(const char *file, const char *text, wrap *W, const double (*gate)[3], int ngate) {
  char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = NULL;
  if (file ? cup_netlist_load(&nl, file, NULL, 0, err) : cup_netlist_load_string(&nl, text, "q.cir", NULL, 0, err))
    fail_msg("%s", err);
  double tstep, tstop;
  assert_int_equal(cup_netlist_tran(nl, &tstep, &tstop), 1);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.T = tstop;
  o.tol_abs = o.tol_rel = 1e-6;
  o.output = CUP_OUTPUT_EVERY;
  o.output_every = 1;
  int dim = cup_lcs_dim(cup_netlist_lcs(nl));
  enum { CAP = 400000 };
  static double a[CAP], b[CAP];
  rec_buf ra = {a, CAP, 0, dim}, rb = {b, CAP, 0, dim};
  cup_input *other = NULL;
  assert_int_equal(cup_input_create(&other, cup_input_dim(cup_netlist_input(nl)), err), CUP_OK);
  wrap none = {0};
  cup_run_info ia, ib;
  memset(W, 0, sizeof *W);
  W->other = other;
  W->gate = none.gate = gate;
  W->ngate = none.ngate = ngate;
  none.fresh = ngate ? nl : NULL;
  one_run(nl, &o, 1, W, &ra, &ia);
  one_run(nl, &o, 0, &none, &rb, &ib);
  assert_true(ra.n > 100 && ra.n < CAP);
  assert_int_equal(ra.n, rb.n);
  assert_memory_equal(a, b, sizeof(double) * (size_t)ra.n);
  assert_int_equal(ia.step, ib.step);
  assert_int_equal(ia.events, ib.events);
  assert_int_equal(ia.samples, ib.samples);
  assert_int_equal(W->wrong, 0);
  assert_int_equal(W->next_wrong + none.next_wrong, 0);
  assert_true(!ngate || (W->nexts > 100 && none.nexts > 100));
  assert_true(!ngate || none.fresh_asked > 30);
  assert_int_equal(none.fresh_wrong, 0);
  print_message("%-14s windows %ld, clear of the input's breaks %ld, quiet %ld\n", file ? strrchr(file, '/') + 1 : "q.cir",
                W->asked, W->clear, W->claims);
  cup_input_free(&other);
  cup_netlist_free(&nl);
}

/* The converters whose gates are PULSEs, their supplies DC: nearly every
 * window is claimed, each claim true. */
static void test_converters_quiet(void **state) {
  (void)state;
  const char *names[] = {"buckboost", "fullbridge", "buck-ccm", "buck-dcm", "boost", "flyback"};
  /* the gates of the first two, as their files give them: every corner a switching */
  static const double bb[][3] = {{0, 10e-6, 5e-6}};
  static const double fb[][3] = {{1e-6, 100e-6, 49e-6}, {51e-6, 100e-6, 49e-6}, {76e-6, 100e-6, 49e-6},
                                 {26e-6, 100e-6, 49e-6}};
  for (size_t q = 0; q < sizeof names / sizeof *names; q++) {
    char file[512];
    snprintf(file, sizeof file, CIR "%s.cir", names[q]);
    wrap W;
    run_both(file, NULL, &W, q == 0 ? bb : q == 1 ? fb : NULL, q == 0 ? 1 : q == 1 ? 4 : 0);
    assert_true(W.asked > 100);
    assert_true(W.claims >= W.asked * 9 / 10);     /* (the first window's search is not the walk's) */
  }
}

/* The supply a PULSE the switch does not read: its corners fall inside
 * windows (clear < asked), and no window is claimed. */
static void test_unread_pulse(void **state) {
  (void)state;
  static const char text[] = "buck-boost, pulsed supply\n"
                             "V1 in 0 PULSE(12 10 3.3u jump jump 7u 23u)\n"
                             "VG g 0 PULSE(0 1 0 jump jump 5u 10u)\n"
                             "S1 in sw g 0 SWI\nL1 sw 0 50u\nD1 out sw\nC1 out 0 20u\nRL out 0 10\n"
                             ".model SWI SW(VT=0.5 VH=0)\n.tran 100n 200u\n.end\n";
  wrap W;
  run_both(NULL, text, &W, NULL, 0);
  assert_true(W.asked > 20);
  assert_true(W.clear < W.asked);
  assert_int_equal(W.claims, 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_converters_quiet),
    cmocka_unit_test(test_unread_pulse),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

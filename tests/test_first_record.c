/* What the first record (t = 0) holds for the algebraic quantities: the
 * multipliers zeta (cup_integrator_zeta inside the sink) and the signals
 * that read them, against references computed another way.
 *
 * The adaptive scheme stores the right limit at t = 0+, the multipliers of
 * the active set the solution takes right after 0 (docs/netlist.md,
 * "Signals"): a capacitor charged through a diode by a sine from 0 carries
 * C u'(0) (clamp, doubler, ladder: closed forms); a full bridge whose
 * inductor carries i0 at t = 0 has the pair that returns it conducting i0
 * and the other pair at 0, and v(a, b) = L i'(0+) + v(C1) (the exact
 * piecewise-linear reference of tests/pwl_ref.h). θ stores the LCP at x0
 * that its first step starts from (with D != 0: the bridge's pair as
 * above); with D = 0 every fixed-step scheme stores zeta = 0 there.
 * Before, every scheme stored zeta = 0: the bridge's i(D1) = -i0 (a diode
 * current below zero), the clamp's i(D1) = 0. */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <cmocka.h>
#include "catchup.h"
#include "netlist_integrator.h"
#include "pwl_circuits.h"

enum { MAXSIG = 16 };

typedef struct {
  cup_netlist *nl;
  const cup_integrator *I;
  int nsig, rows, refuse_first;  /* refuse_first: the sink refuses its first call once */
  double t0, x0[8], sig0[MAXSIG];  /* the first record */
} first_ctx;

static int first_sink(long k, double t, const double *x, void *vp) {
  (void)k;
  first_ctx *c = vp;
  if (c->refuse_first) {
    c->refuse_first = 0;
    return 1;
  }
  if (c->rows++ == 0) {
    double zeta[64];
    assert_true(cup_integrator_rows(c->I) <= 64);
    assert_int_equal(cup_integrator_zeta(c->I, zeta), CUP_OK);
    assert_int_equal(cup_netlist_signals(c->nl, t, x, zeta, c->sig0), CUP_OK);
    c->t0 = t;
    for (int i = 0; i < cup_lcs_dim(cup_netlist_lcs(c->nl)) && i < 8; i++) c->x0[i] = x[i];
  }
  return 0;
}

static cup_netlist *load(const char *text, const char *const *probes, int np) {
  char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = NULL;
  if (cup_netlist_load_string(&nl, text, "first.cir", NULL, 0, err)) fail_msg("%s", err);
  for (int i = 0; i < np; i++)
    if (cup_netlist_probe(nl, probes[i], err) != i) fail_msg("%s: %s", probes[i], err);
  return nl;
}

static cup_integrator *make(cup_netlist *nl, int scheme, double T) {
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = scheme;
  o.T = T;
  o.n = 1000;
  o.tol_abs = o.tol_rel = 1e-9;
  o.output = CUP_OUTPUT_SAMPLES;
  o.output_samples = 11;
  return netlist_integrator(nl, &o);
}

/* The first record of a run of nl under scheme over [0, T]. */
static first_ctx first_record(cup_netlist *nl, int scheme, double T) {
  first_ctx c = {.nl = nl, .nsig = cup_netlist_signal_count(nl)};
  assert_true(c.nsig <= MAXSIG);
  cup_integrator *I = make(nl, scheme, T);
  c.I = I;
  cup_run_info info;
  int st = cup_integrator_run(I, cup_netlist_x0(nl), first_sink, &c, &info);
  if (st < 0) fail_msg("%s: %s", cup_status_name(st), info.message);
  assert_true(c.rows > 1);
  assert_true(c.t0 == 0);
  cup_integrator_free(&I);
  return c;
}

static const char *scheme_name(int s) {
  return s == CUP_SCHEME_ADAPTIVE ? "adaptive" : s == CUP_SCHEME_THETA ? "theta" : "explicit";
}

static void near(const char *what, double got, double want, double tol) {
  print_message("  %-34s %.17g (want %.17g)\n", what, got, want);
  if (!(fabs(got - want) <= tol)) fail_msg("%s: %.17g, want %.17g (tol %.3g)", what, got, want, tol);
}

/* ---- D = 0: a capacitor charged through a diode by a sine from 0 -------------- */

/* The clamp, the doubler and the ladder (examples/circuits) from rest, the
 * sine rising at 0: the conducting diodes carry the capacitors' C v'(0+),
 * v' = u'(0) = 2 pi f Vp on each capacitor the diodes tie to the source
 * (the doubler's two in series: C / 2; the ladder's 8 in parallel through
 * D1, 8 - k + 1 of them through Dk; want[0] the largest). The fixed-step
 * schemes store 0. */
static void check_rest(const char *text, const char *const *probes, int np, const double *want, double T) {
  cup_netlist *nl = load(text, probes, np);
  int schemes[] = {CUP_SCHEME_ADAPTIVE, CUP_SCHEME_THETA, CUP_SCHEME_EXPLICIT};
  for (int s = 0; s < 3; s++) {
    print_message("%s:\n", scheme_name(schemes[s]));
    first_ctx c = first_record(nl, schemes[s], T);
    for (int i = 0; i < np; i++)
      near(probes[i], c.sig0[i], schemes[s] == CUP_SCHEME_ADAPTIVE ? want[i] : 0, 1e-12 * want[0]);
  }
  cup_netlist_free(&nl);
}

static void test_clamp(void **state) {
  (void)state;
  const char *probes[] = {"i(D1)", "i(C1)"};
  double w = 1e-6 * 2 * M_PI * 1e3 * 5, want[] = {w, w};
  check_rest("clamp\nV1 in 0 SIN(0 5 1k)\nC1 in out 1u\nD1 out 0\nRL out 0 10k\n.tran 1u 5m\n.end\n", probes, 2,
             want, 1e-4);
}

static void test_doubler(void **state) {
  (void)state;
  const char *probes[] = {"i(D2)", "i(D1)"};
  double want[] = {0.5e-6 * 2 * M_PI * 1e3 * 5, 0};
  check_rest("doubler\nV1 in 0 SIN(0 5 1k)\nC1 in a 1u\nD1 0 a\nD2 a out\nC2 out 0 1u\nRL out 0 100k\n"
             ".tran 1u 10m\n.end\n", probes, 2, want, 1e-4);
}

static void test_ladder(void **state) {
  (void)state;
  char text[1024];
  int len = snprintf(text, sizeof text, "ladder\nV1 n0 0 SIN(0 10 50)\n");
  for (int k = 1; k <= 8; k++)
    len += snprintf(text + len, sizeof text - (size_t)len, "D%d n%d n%d\nC%d n%d 0 1u\nR%d n%d 0 1meg\n", k, k - 1,
                    k, k, k, k, k);
  snprintf(text + len, sizeof text - (size_t)len, ".tran 100u 20m\n.end\n");
  const char *probes[] = {"i(D1)", "i(D5)", "i(D8)"};
  double cu = 1e-6 * 2 * M_PI * 50 * 10, want[] = {8 * cu, 4 * cu, cu};
  check_rest(text, probes, 3, want, 1e-3);
}

/* ---- D != 0: a full bridge whose inductor carries i0 at t = 0 ------------------ */

/* examples/circuits/fullbridge.cir with L1's IC = i0, every gate low until
 * 1 us: i0 > 0 leaves a through the filter, D2 brings it to a (v(a) = 0)
 * and D3 returns it to dc (v(b) = 100); i0 < 0: D1 and D4 (v(a) = 100,
 * v(b) = 0). The pair carries |i0|, the other pair 0; v(a, b) is
 * L i'(0+) + v(C1) with i'(0+) from the reference's mode at 0 (pwl_ref.h,
 * written from the circuit's physics). Adaptive and θ (both D != 0). */
static void test_fullbridge_i0(void **state) {
  (void)state;
  const char *probes[] = {"i(D1)", "i(D2)", "i(D3)", "i(D4)", "v(a)", "v(b)", "v(a,b)"};
  static pr_circuit pc;
  for (int sgn = 1; sgn >= -1; sgn -= 2) {
    double i0 = sgn * 1e-3, y0[PR_Y], Tref, dy[PR_Y] = {0};
    char text[1024];
    snprintf(text, sizeof text, "full bridge, i0\nVDC dc 0 100\nVG1 g1 0 PULSE(0 1 1u jump jump 49u 100u)\n"
             "VG2 g2 0 PULSE(0 1 51u jump jump 49u 100u)\nVG3 g3 0 PULSE(0 1 76u jump jump 49u 100u)\n"
             "VG4 g4 0 PULSE(0 1 26u jump jump 49u 100u)\nS1 dc a g1 0 SWI\nS2 a 0 g2 0 SWI\nS3 dc b g3 0 SWI\n"
             "S4 b 0 g4 0 SWI\nD1 a dc\nD2 0 a\nD3 b dc\nD4 0 b\nL1 a o 1m IC=%.17g\nC1 o b 2.2u\nRL o b 20\n"
             ".model SWI SW(VT=0.5 VH=0)\n.tran 1u 10m\n.end\n", i0);
    assert_int_equal(pc_example("fullbridge", &pc, y0, &Tref), 0);
    y0[0] = i0;
    pr_traj tr;
    assert_int_equal(pr_solve(&pc, y0, 2e-6, &tr), 0);
    const pr_mode *md = &pc.mode[tr.seg[0].mode];
    for (int j = 0; j < pc.ny; j++) dy[0] += md->M[0][j] * tr.seg[0].y0[j];
    double vab = 1e-3 * dy[0] + y0[1];
    pr_free(&tr);
    double on = fabs(i0), want[] = {sgn < 0 ? on : 0, sgn > 0 ? on : 0, sgn > 0 ? on : 0, sgn < 0 ? on : 0,
                                    sgn > 0 ? 0 : 100, sgn > 0 ? 100 : 0, vab};
    near("reference v(a,b)(0+)", vab, -sgn * 100.0, 1e-12);
    cup_netlist *nl = load(text, probes, 7);
    int schemes[] = {CUP_SCHEME_ADAPTIVE, CUP_SCHEME_THETA};
    for (int s = 0; s < 2; s++) {
      print_message("i0 = %g, %s:\n", i0, scheme_name(schemes[s]));
      first_ctx c = first_record(nl, schemes[s], 2e-6);
      assert_true(c.x0[0] == i0 && c.x0[1] == 0);   /* x0 as given */
      for (int i = 0; i < 7; i++) near(probes[i], c.sig0[i], want[i], 1e-12 * (i < 4 ? on : 100));
      for (int i = 0; i < 4; i++) assert_true(c.sig0[i] >= 0);
    }
    cup_netlist_free(&nl);
  }
}

/* ---- a resumed run's first record --------------------------------------------- */

/* A run stopped by the sink at x0's sample, saved, restored into a new
 * integrator and resumed gives that sample again: x0 as given bit for bit
 * and signal 0 as the uninterrupted run's, want (a closed form). */
static void resume_first(const char *text, const char *probe, int scheme, double want) {
  cup_netlist *nl = load(text, &probe, 1);
  print_message("%s, %s:\n", probe, scheme_name(scheme));
  first_ctx whole = first_record(nl, scheme, 1e-4);
  cup_integrator *I = make(nl, scheme, 1e-4);
  first_ctx c = {.nl = nl, .nsig = 1, .refuse_first = 1, .I = I};
  cup_run_info info;
  assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), first_sink, &c, &info), CUP_ERR_INTERRUPTED);
  assert_int_equal(c.rows, 0);
  long size = cup_integrator_checkpoint_size(I);
  assert_true(size > 0);
  void *blob = malloc((size_t)size);
  assert_int_equal(cup_integrator_checkpoint_save(I, &info, blob, (unsigned long)size), CUP_OK);
  cup_integrator_free(&I);
  cup_integrator *J = make(nl, scheme, 1e-4);
  char err[CUP_ERRMSG_LEN];
  if (cup_integrator_checkpoint_restore(J, blob, (unsigned long)size, err)) fail_msg("%s", err);
  free(blob);
  c.I = J;
  int st = cup_integrator_resume(J, first_sink, &c, &info);
  if (st < 0) fail_msg("%s: %s", cup_status_name(st), info.message);
  assert_int_equal(c.rows, whole.rows);
  int n = cup_lcs_dim(cup_netlist_lcs(nl));
  assert_true(c.t0 == 0 && !memcmp(c.x0, cup_netlist_x0(nl), sizeof(double) * (size_t)n));
  near("resumed, at t = 0", c.sig0[0], want, 1e-12 * want);
  assert_memory_equal(c.sig0, whole.sig0, sizeof(double));
  cup_integrator_free(&J);
  cup_netlist_free(&nl);
}

/* The clamp (adaptive: C u'(0)); a bridge with no switches whose inductor
 * carries 1 mA (test_adaptive_circuits' pairs-off circuit; adaptive and
 * θ: D2 carries it). */
static void test_resume_first(void **state) {
  (void)state;
  const char *clamp = "clamp\nV1 in 0 SIN(0 5 1k)\nC1 in out 1u\nD1 out 0\nRL out 0 10k\n.tran 1u 5m\n.end\n";
  const char *pairs = "bridge pairs\nVDC dc 0 100\nD1 a dc\nD2 0 a\nD3 b dc\nD4 0 b\nL1 a o 1m IC=1m\nC1 o b 2.2u\n"
                      "RL o b 20\n.tran 1u 10u\n.end\n";
  resume_first(clamp, "i(D1)", CUP_SCHEME_ADAPTIVE, 1e-6 * 2 * M_PI * 1e3 * 5);
  resume_first(pairs, "i(D2)", CUP_SCHEME_ADAPTIVE, 1e-3);
  resume_first(pairs, "i(D2)", CUP_SCHEME_THETA, 1e-3);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_clamp),
    cmocka_unit_test(test_doubler),
    cmocka_unit_test(test_ladder),
    cmocka_unit_test(test_fullbridge_i0),
    cmocka_unit_test(test_resume_first),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

/* netlist: the reader and the formulation against matrices written out by
 * hand (the paper's circuit, Sec. 7, and small circuits solved on paper),
 * the paper's trajectory through the scene format, the RL half-wave
 * rectifier against its closed form (docs/closed-forms.md), signals against
 * Kirchhoff's laws, and the malformed corpus: every .cir file in
 * tests/netlists/bad names its expected error on its title line. The LCS
 * internals (src/lcs_impl.h) are read to compare matrices. */
#define _GNU_SOURCE
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <dirent.h>
#include <cmocka.h>
#include "testutil.h"
#include "badcorpus.h"
#include "lcs_impl.h"
#include "netlistutil.h"
#include "polyset_impl.h"

#define EX CUP_EXAMPLES_DIR
#define CIR CUP_EXAMPLES_DIR "/circuits"
#define BAD CUP_BAD_NETLISTS_DIR

static cup_netlist *load_ok(const char *path, const char *const *sets, int nsets) {
  char err[CUP_ERRMSG_LEN] = "";
  cup_netlist *nl = NULL;
  int st = cup_netlist_load(&nl, path, sets, nsets, err);
  if (st) fail_msg("loading %s failed (%d): %s", path, st, err);
  assert_non_null(nl);
  return nl;
}

/* ---- the paper's circuit ----------------------------------------------------- */

/* examples/circuits/paper-fig2.cir has x = (i(L3), i(L2), v(C4)), the paper
 * x = (q, i(L3), i(L2)) with q = C4 v (C4 = 1): paper index of ours. */
static const int perm[3] = {1, 2, 0};

static void test_paper_matrices(void **state) {
  (void)state;
  cup_netlist *nl = load_ok(CIR "/paper-fig2.cir", NULL, 0);
  const cup_lcs *L = cup_netlist_lcs(nl);
  cup_circuit pc = {1, 2, 1, 1, 2, 1, {0, 0}};
  cup_lcs *R = NULL;
  assert_int_equal(cup_lcs_circuit(&R, &pc, NULL), CUP_OK);
  assert_int_equal(L->n, 3);
  assert_int_equal(L->m, 2);
  assert_int_equal(L->p, 2);                      /* two sources carrying the same u */
  assert_false(L->has_D);
  for (int i = 0; i < 3; i++) {
    for (int j = 0; j < 3; j++)
      assert_close(at(&L->A, i, j), at(&R->A, perm[i], perm[j]), 1e-15);
    assert_close(at(&L->E, i, 0) + at(&L->E, i, 1), at(&R->E, perm[i], 0), 1e-15);
    assert_close(L->K->pd[i], R->K->pd[perm[i]], 0);          /* diag(L3, L2, C4) ~ diag(1, L3, L2) */
    for (int r = 0; r < 2; r++) {
      assert_close(at(&L->K->C, r, i), at(&R->K->C, r, perm[i]), 0);
      assert_close(L->K->Bt[(size_t)r * 3 + i], R->K->Bt[(size_t)r * 3 + perm[i]], 1e-15);
    }
  }
  assert_string_equal(cup_netlist_state_name(nl, 0), "i(L3)");
  assert_string_equal(cup_netlist_state_name(nl, 2), "v(C4)");
  assert_string_equal(cup_netlist_row_name(nl, 0), "D1");
  assert_string_equal(cup_netlist_input_name(nl, 1), "V2");
  assert_int_equal(cup_netlist_row_fixed(nl, 0), 1);
  assert_int_equal(cup_netlist_row_fixed(nl, 1), 1);
  double tstep = 0, tstop = 0;
  assert_int_equal(cup_netlist_tran(nl, &tstep, &tstop), 1);
  assert_close(tstep, 0.01, 0);
  assert_close(tstop, 1, 0);
  cup_lcs_free(&R);
  cup_netlist_free(&nl);
  assert_null(nl);
}

typedef struct traj { long n; int dim; double x[1001][3]; } traj;   /* dim <= 3 states */

static int keep(long k, double t, const double *x, void *ctx) {
  (void)t;
  traj *s = ctx;
  if (k == 0) s->n = 0;
  if (s->n > 1000) return 1;
  memcpy(s->x[s->n++], x, sizeof(double) * (size_t)s->dim);
  return 0;
}

/* The netlist and examples/paper-fig2.yaml give the same trajectory, to
 * rounding, under every scheme (n = 1000). */
static void test_paper_trajectory(void **state) {
  (void)state;
  static traj a = {.dim = 3}, b = {.dim = 3};
  char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = load_ok(CIR "/paper-fig2.cir", NULL, 0);
  cup_scene *sc = NULL;
  const char *ovr[] = {"n=1000"};
  assert_int_equal(cup_scene_load(&sc, EX "/paper-fig2.yaml", ovr, 1, err), CUP_OK);
  for (int scheme = 0; scheme < CUP_SCHEME_COUNT; scheme++) {
    cup_integrator_options o = *cup_scene_options(sc);
    o.scheme = (cup_scheme)scheme;
    if (scheme == CUP_SCHEME_ADAPTIVE) {           /* it chooses its steps: sample the grid */
      o.output = CUP_OUTPUT_SAMPLES;
      o.output_samples = 1001;
    }
    cup_integrator *I = NULL;
    cup_run_info info;
    assert_int_equal(cup_integrator_create(&I, cup_netlist_lcs(nl), cup_netlist_input(nl), &o, err), CUP_OK);
    assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), keep, &a, &info), CUP_OK);
    cup_integrator_free(&I);
    assert_int_equal(cup_integrator_create(&I, cup_scene_lcs(sc), cup_scene_input(sc), &o, err), CUP_OK);
    assert_int_equal(cup_integrator_run(I, cup_scene_x0(sc), keep, &b, &info), CUP_OK);
    cup_integrator_free(&I);
    assert_int_equal(a.n, 1001);
    double worst = 0;
    for (long k = 0; k < a.n; k++)
      for (int i = 0; i < 3; i++) worst = fmax(worst, fabs(a.x[k][i] - b.x[k][perm[i]]));
    print_message("paper circuit, %-11s: netlist vs scene max |dx| = %.2e\n", cup_scheme_name(scheme), worst);
    assert_true(worst <= 1e-13);
  }
  cup_scene_free(&sc);
  cup_netlist_free(&nl);
}

/* ---- small circuits solved by hand -------------------------------------------- */

/* Values: engineering suffixes, units after them, .param expressions. */
static void test_values(void **state) {
  (void)state;
  cup_netlist *nl = text_ok("values\n"
                            ".param r0=2.2k cval={10u*(1+1)} half=0.5\n"
                            "V1 in 0 DC 1\n"
                            "R1 in a {r0*half}\n"               /* 1.1 kohm */
                            "C1 a 0 {cval}\n"                   /* 20 uF */
                            "R2 a b 1MEGohm\n"                  /* 1e6, not milli */
                            "L1 b 0 10mH\n"                     /* 10 mH */
                            "+ IC=2m\n"
                            ".tran 1u 1m uic\n", NULL, 0);
  const cup_lcs *L = cup_netlist_lcs(nl);
  /* x = (i(L1), v(C1)): L i' = v - R2 i;  C v' = (1 - v)/R1 - i */
  double R1 = 1100, C1 = 20e-6, R2 = 1e6, L1 = 10e-3;
  assert_close(at(&L->A, 0, 0), -R2 / L1, 1e-9);
  assert_close(at(&L->A, 0, 1), 1 / L1, 1e-12);
  assert_close(at(&L->A, 1, 0), -1 / C1, 1e-9);
  assert_close(at(&L->A, 1, 1), -1 / (R1 * C1), 1e-10);
  assert_close(at(&L->E, 1, 0), 1 / (R1 * C1), 1e-10);
  assert_close(cup_netlist_x0(nl)[0], 2e-3, 1e-18);
  cup_netlist_free(&nl);
  /* a set replaces a .param before anything reads it, and an element's value */
  const char *sets[] = {"r0=4.4k", "C1=5u"};
  nl = text_ok("values\n.param r0=2.2k\nV1 in 0 1\nR1 in a {r0/2}\nC1 a 0 1u\n", sets, 2);
  assert_close(at(&cup_netlist_lcs(nl)->A, 0, 0), -1 / (2200 * 5e-6), 1e-9);
  cup_netlist_free(&nl);
  const char *bad[] = {"R9=1k"};
  assert_contains(text_bad("x\nV1 in 0 1\nR1 in a 1k\nC1 a 0 1u\n", bad, 1),
                  "t.cir: set 'R9=1k': no element or .param of that name");
  const char *neg[] = {"R1=-5"};
  assert_contains(text_bad("x\nV1 in 0 1\nR1 in a 1k\nC1 a 0 1u\n", neg, 1),
                  "t.cir: set 'R1=-5': R1: bad value: resistance must be > 0 (got -5)");
}

/* V1's value at t for the source specification spec (a netlist with
 * .tran 1u 2m and .param jump=2u when param). */
static double pulse_at(const char *spec, int param, double t) {
  char text[256];
  snprintf(text, sizeof text, "p\n%sV1 a 0 %s\nR1 a b 1\nC1 b 0 1\n.tran 1u 2m\n",
           param ? ".param jump=2u\n" : "", spec);
  cup_netlist *nl = text_ok(text, NULL, 0);
  double u = NAN;
  assert_int_equal(cup_input_eval(cup_netlist_input(nl), t, &u), CUP_OK);
  cup_netlist_free(&nl);
  return u;
}

/* PULSE's TR or TF of 0 (or omitted) is TSTEP, as SPICE3 and ngspice read
 * it (a ramp; PLECS's reader takes 0 as a jump); `jump` in their place is
 * an edge of no duration, right-continuous, unless a .param is named so. */
static void test_pulse_edges(void **state) {
  (void)state;
  assert_close(pulse_at("PULSE(0 10 1m 0 0 0.5m 1m)", 0, 1e-3 + 0.5e-6), 5, 1e-9);       /* TSTEP = 1u */
  assert_close(pulse_at("PULSE(0 10 1m 0 0 0.5m 1m)", 0, 1.5e-3 + 1e-6 + 0.25e-6), 7.5, 1e-9);
  assert_close(pulse_at("PULSE(0 10 1m jump jump 0.5m 1m)", 0, 1e-3), 10, 0);
  assert_close(pulse_at("PULSE(0 10 1m jump jump 0.5m 1m)", 0, 1e-3 * (1 - 1e-12)), 0, 0);
  assert_close(pulse_at("PULSE(0 10 1m jump jump 0.5m 1m)", 0, 1.5e-3), 0, 0);
  assert_close(pulse_at("PULSE(0 10 1m jump jump 0.5m 1m)", 0, 2.5e-3 - 1e-9), 10, 0);   /* the next period */
  assert_close(pulse_at("PULSE 0 10 1m JUMP 1u 0.5m 1m", 0, 1.5e-3 + 0.5e-6), 5, 1e-9);  /* no parentheses */
  assert_close(pulse_at("PULSE(0 10 1m jump 0 0.5m 1m)", 1, 1e-3 + 1e-6), 5, 1e-9);      /* .param jump=2u */
  assert_contains(text_bad("p\nV1 a 0 PULSE(jump 10 1m)\nR1 a b 1\nC1 b 0 1\n.tran 1u 2m\n", NULL, 0),
                  "t.cir:2:14: V1: PULSE: 'jump' stands only for PULSE's rise or fall time TR, TF");
  assert_contains(text_bad("p\nV1 a 0 SIN(0 10 jump)\nR1 a b 1\nC1 b 0 1\n.tran 1u 2m\n", NULL, 0),
                  "V1: SIN: 'jump' stands only for PULSE's rise or fall time");
  /* PW and PER omitted are TSTOP (2m): one pulse, as SPICE runs it (TR = TSTEP, then V2 to the end) */
  assert_close(pulse_at("PULSE(0 10 1m)", 0, 1e-3 + 0.5e-6), 5, 1e-9);
  assert_close(pulse_at("PULSE(0 10 1m)", 0, 1.5e-3), 10, 0);
  assert_close(pulse_at("PULSE(0 10 1m)", 0, 2e-3), 10, 0);
  assert_close(pulse_at("PULSE(0 10 0 jump 0 2m)", 0, 1.9e-3), 10, 0);             /* PER = TSTOP < 2.001m */
  assert_contains(text_bad("p\nV1 a 0 PULSE(0 10 0 1u 1u 1.5m 1m)\nR1 a b 1\nC1 b 0 1\n.tran 1u 2m\n", NULL, 0),
                  "pulse period 0.001 is shorter than rise + width + fall");                 /* PER given: refused */
  const char *set[] = {"V1=PULSE(0 10 1m jump jump 0.5m 1m)"};                        /* a set too */
  cup_netlist *nl = text_ok("p\nV1 a 0 1\nR1 a b 1\nC1 b 0 1\n.tran 1u 2m\n", set, 1);
  double u;
  assert_int_equal(cup_input_eval(cup_netlist_input(nl), 1e-3, &u), CUP_OK);
  assert_close(u, 10, 0);
  cup_netlist_free(&nl);
}

/* Half-wave rectifier with source resistance: the diode sees Rs, so zeta is
 * its current and D = Rs; C v' = zeta - v/RL, w = -(v_a - v) with v_a = V - Rs zeta. */
static void test_free_diode(void **state) {
  (void)state;
  cup_netlist *nl = load_ok(CIR "/halfwave-rc.cir", NULL, 0);
  const cup_lcs *L = cup_netlist_lcs(nl);
  double Rs = 1, C = 100e-6, RL = 1000;
  assert_true(L->has_D);
  assert_int_equal(cup_netlist_row_fixed(nl, 0), 0);
  assert_close(at(&L->D, 0, 0), Rs, 1e-15);
  assert_close(at(&L->B, 0, 0), 1 / C, 1e-9);
  assert_close(at(&L->A, 0, 0), -1 / (RL * C), 1e-12);
  assert_close(at(&L->K->C, 0, 0), 1, 1e-15);
  assert_close(at(&L->G, 0, 0), -1, 1e-15);
  /* the catching-up schemes refuse it, naming the diode (theta and the
   * adaptive scheme run it) */
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  cup_integrator *I = NULL;
  char err[CUP_ERRMSG_LEN];
  for (int scheme = CUP_SCHEME_EXPLICIT; scheme < CUP_SCHEME_COUNT; scheme++) {
    if (scheme == CUP_SCHEME_THETA || scheme == CUP_SCHEME_ADAPTIVE) continue;
    o.scheme = (cup_scheme)scheme;
    assert_int_equal(cup_integrator_create(&I, L, cup_netlist_input(nl), &o, err), CUP_ERR_UNSUPPORTED);
    assert_contains(err, "needs D = 0");
    assert_contains(err, "row D1 has D != 0");
    assert_contains(err, "use the theta or the adaptive scheme");
  }
  cup_netlist_free(&nl);
}

/* The bridge: D1 is fixed by the other diodes' currents (a cutset of
 * diodes), D2..D4 are free. By hand, with v = v(out), Rs = 1:
 *   i1 = -z2 + z3 + z4 (KCL around the source),  C v' = z3 + z4 - v/RL,
 *   w2 = -(v(in2) - v) = v - V - Rs z2 + ... as below. */
static void test_bridge(void **state) {
  (void)state;
  cup_netlist *nl = load_ok(CIR "/bridge.cir", NULL, 0);
  const cup_lcs *L = cup_netlist_lcs(nl);
  assert_int_equal(L->m, 4);
  int fixed[4] = {1, 0, 0, 0};
  for (int i = 0; i < 4; i++) assert_int_equal(cup_netlist_row_fixed(nl, i), fixed[i]);
  /* potentials (z1 = -v(D1) = v(out) - v(in1)):
   *   v(in1) = v + z1,  v(x) = v(in1) - V,  v(in2) = v(x) - Rs i(Rs), i(Rs) = z2 - z4 (into in2 from x... ) */
  const double D[4][4] = {{0, -1, 1, 1}, {1, 1, 0, -1}, {-1, 0, 0, 0}, {-1, -1, 0, 1}};
  const double Cx[4] = {0, 0, 1, 1}, Gu[4] = {0, 1, 0, -1}, B[4] = {0, 0, 1e4, 1e4};
  for (int i = 0; i < 4; i++) {
    for (int j = 0; j < 4; j++) assert_close(at(&L->D, i, j), D[i][j], 1e-15);
    assert_close(at(&L->K->C, i, 0), Cx[i], 1e-15);
    assert_close(at(&L->G, i, 0), Gu[i], 1e-15);
    assert_close(at(&L->B, 0, i), B[i], 1e-9);
  }
  cup_netlist_free(&nl);
}

/* Loops of capacitors, the source and diodes: D = 0, a sweeping process in
 * the capacitor voltages. Doubler: w1 = v(a) = V - v1, w2 = v1 + v2 - V. */
static void test_doubler(void **state) {
  (void)state;
  cup_netlist *nl = load_ok(CIR "/doubler.cir", NULL, 0);
  const cup_lcs *L = cup_netlist_lcs(nl);
  assert_false(L->has_D);
  const double C[2][2] = {{-1, 0}, {1, 1}}, G[2] = {1, -1};
  for (int i = 0; i < 2; i++) {
    for (int j = 0; j < 2; j++) assert_close(at(&L->K->C, i, j), C[i][j], 1e-15);
    assert_close(at(&L->G, i, 0), G[i], 1e-15);
  }
  assert_close(at(&L->A, 1, 1), -1 / (100e3 * 1e-6), 1e-9);
  assert_close(at(&L->A, 0, 0), 0, 0);
  cup_netlist_free(&nl);
}

/* Signals are Kirchhoff's laws at given (t, x, zeta): the half-wave RC. */
static void test_signals(void **state) {
  (void)state;
  cup_netlist *nl = load_ok(CIR "/halfwave-rc.cir", NULL, 0);
  char err[CUP_ERRMSG_LEN];
  const char *want[] = {"v(out)", "i(D1)", "v(in)"};
  assert_int_equal(cup_netlist_probe_default(nl, 100, err), CUP_OK);
  assert_int_equal(cup_netlist_signal_count(nl), 3);
  for (int k = 0; k < 3; k++) assert_string_equal(cup_netlist_signal_name(nl, k), want[k]);
  assert_int_equal(cup_netlist_probe(nl, "I(rs)", err), 3);
  assert_string_equal(cup_netlist_signal_name(nl, 3), "i(Rs)");
  assert_int_equal(cup_netlist_probe(nl, "v(A, out)", err), 4);
  assert_string_equal(cup_netlist_signal_name(nl, 4), "v(a,out)");
  assert_string_equal(cup_netlist_signal_unit(nl, 4), "V");         /* the units files carry */
  assert_string_equal(cup_netlist_signal_unit(nl, 3), "A");
  assert_null(cup_netlist_signal_unit(nl, 5));
  assert_int_equal(cup_netlist_probe(nl, "i(C1)", err), 5);
  assert_int_equal(cup_netlist_probe(nl, "i(RL)", err), 6);
  assert_int_equal(cup_netlist_probe(nl, "v(out)", err), 0);     /* again: the same index */
  assert_int_equal(cup_netlist_probe(nl, "v(nowhere)", err), CUP_ERR_ARG);
  assert_contains(err, "probe 'v(nowhere)': no node named 'nowhere'");
  assert_int_equal(cup_netlist_probe(nl, "p(out)", err), CUP_ERR_ARG);
  double t = 0.004, x = 3.5, z = 2.25, out[7];
  double V = 10 * sin(2 * M_PI * 50 * t);
  assert_int_equal(cup_netlist_signals(nl, t, &x, &z, out), CUP_OK);
  assert_close(out[0], x, 1e-15);
  assert_close(out[1], z, 1e-15);
  assert_close(out[2], V, 1e-14);
  assert_close(out[3], z, 1e-15);                 /* i(Rs) = i(D1) */
  assert_close(out[4], V - 1 * z - x, 1e-14);     /* the diode's voltage */
  assert_close(out[5], z - x / 1000, 1e-15);      /* KCL at out */
  assert_close(out[6], x / 1000, 1e-18);
  cup_netlist_free(&nl);
  /* the paper's circuit: v(d) = R1 i(D1) + v(D1) with D1 conducting: R1 (i3 - i2) */
  nl = load_ok(CIR "/paper-fig2.cir", NULL, 0);
  assert_int_equal(cup_netlist_probe_default(nl, 100, err), CUP_OK);
  assert_string_equal(cup_netlist_signal_name(nl, 0), "v(d)");
  double xs[3] = {0.7, 0.2, -1.5}, zs[2] = {0, 0}, o2[3];
  assert_int_equal(cup_netlist_signals(nl, 0.1, xs, zs, o2), CUP_OK);
  assert_close(o2[0], 1 * (xs[0] - xs[1]), 1e-15);
  assert_close(o2[1], xs[0] - xs[1], 1e-15);       /* i(D1) */
  assert_close(o2[2], xs[0], 1e-15);               /* i(D4) = i(L3) */
  zs[0] = 0.25;                                     /* D1 blocking: v(e) = -v(D1)... v(d) = R1 i + v(D1) */
  assert_int_equal(cup_netlist_signals(nl, 0.1, xs, zs, o2), CUP_OK);
  assert_close(o2[0], (xs[0] - xs[1]) - zs[0], 1e-15);
  cup_netlist_free(&nl);
}

/* ---- the RL half-wave rectifier and its closed form ---------------------------------- */

typedef struct rl { double V, w, R, L, Z, phi, tau, toff; } rl;

static double rl_on(const rl *q, double t) {
  return q->V / q->Z * (sin(q->w * t - q->phi) + sin(q->phi) * exp(-t / q->tau));
}

/* i on a period: the conducting solution until it returns to 0 at toff
 * (found by bisection on (pi/w, 2 pi/w)), then 0. */
static double rl_exact(const rl *q, double t) {
  double T = 2 * M_PI / q->w, s = fmod(t, T);
  return s <= q->toff ? rl_on(q, s) : 0;
}

/* examples/circuits/rl-halfwave.cir's values and its switch-off time. */
static rl rl_example(void) {
  rl q = {10, 2 * M_PI * 50, 10, 50e-3, 0, 0, 0, 0};
  q.Z = sqrt(q.R * q.R + q.w * q.w * q.L * q.L);
  q.phi = atan(q.w * q.L / q.R);
  q.tau = q.L / q.R;
  double lo = M_PI / q.w, hi = 2 * M_PI / q.w;
  assert_true(rl_on(&q, lo) > 0 && rl_on(&q, hi) < 0);
  for (int it = 0; it < 200; it++) {
    double mid = 0.5 * (lo + hi);
    if (rl_on(&q, mid) > 0) lo = mid; else hi = mid;
  }
  q.toff = lo;
  return q;
}

static void test_rl_closed_form(void **state) {
  (void)state;
  rl q = rl_example();
  print_message("RL rectifier: Z = %.6g ohm, phi = %.6g rad, t_off = %.9g s\n", q.Z, q.phi, q.toff);
  cup_netlist *nl = load_ok(CIR "/rl-halfwave.cir", NULL, 0);
  char err[CUP_ERRMSG_LEN];
  double prev = 0;
  for (long n = 2000; n <= 20000; n *= 10) {
    for (int scheme = CUP_SCHEME_EXPLICIT; scheme < CUP_SCHEME_COUNT; scheme++) {
      cup_integrator_options o;
      cup_integrator_options_default(&o);
      o.T = 0.04;
      o.n = n;
      o.scheme = (cup_scheme)scheme;
      o.eps = o.eta = (cup_schedule){0, 0};
      o.output = CUP_OUTPUT_SAMPLES;
      o.output_samples = 1001;
      cup_integrator *I = NULL;
      assert_int_equal(cup_integrator_create(&I, cup_netlist_lcs(nl), cup_netlist_input(nl), &o, err), CUP_OK);
      static traj a;
      a.dim = cup_lcs_dim(cup_netlist_lcs(nl));
      assert_true(a.dim <= 3);
      cup_run_info info;
      assert_true(cup_integrator_run(I, cup_netlist_x0(nl), keep, &a, &info) >= 0);
      cup_integrator_free(&I);
      double worst = 0;
      for (long k = 0; k < a.n; k++) worst = fmax(worst, fabs(a.x[k][0] - rl_exact(&q, 0.04 * k / 1000)));
      double h = 0.04 / n;
      print_message("RL rectifier %-11s n %6ld: max error %.3e A = %.3f h (A/s)\n", cup_scheme_name(scheme), n,
                    worst, worst / h);
      /* measured: explicit and implicit 34.5 h (first order); exponential
       * exact to rounding (the free flow is exact and the diode switches
       * off by a projection onto i >= 0 and on at a grid point);
       * theta second order, 2240 h^2 */
      if (scheme <= CUP_SCHEME_IMPLICIT) assert_true(worst >= 33 * h && worst <= 36 * h);
      if (scheme == CUP_SCHEME_EXPONENTIAL) assert_true(worst <= 1e-12);
      if (scheme == CUP_SCHEME_THETA) assert_true(worst <= 2300 * h * h);
      if (scheme == CUP_SCHEME_ADAPTIVE) assert_true(worst <= o.tol_abs);   /* measured 2.4e-15 */
      if (scheme == CUP_SCHEME_EXPLICIT && prev > 0) assert_true(worst / prev < 0.101);
      if (scheme == CUP_SCHEME_EXPLICIT) prev = worst;
    }
  }
  cup_netlist_free(&nl);
}

/* A gate with jump edges is read from the piece's value while the time
 * stays in the piece (netlist_signal.c, sig_input): v(g) equals the
 * input's own evaluation bit for bit at every time, the corners (its
 * breakpoints) and their neighbouring doubles included, right after a
 * time in the piece before, forwards and backwards, and the closed
 * form away from the corners; after a new time origin the sources move
 * (a value kept from before would read 1 at 2.5 us, in the top it was
 * found in: the pulse from 3 us on is 0 there). */
static void test_signal_jump_pulse(void **state) {
  (void)state;
  const char *text = "gate\nV1 in 0 12\nVG g 0 PULSE(0 1 1u jump jump 3u 10u)\nR1 in a 1k\nRG g a 1k\n"
                     "C1 a 0 1u\n.probe v(g) v(in)\n.end\n";
  char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = NULL;
  assert_int_equal(cup_netlist_load_string(&nl, text, "gate.cir", NULL, 0, err), CUP_OK);
  assert_int_equal(cup_netlist_probe_default(nl, 100, err), CUP_OK);
  assert_string_equal(cup_netlist_signal_name(nl, 0), "v(g)");
  double x = 0.5, out[2], u[2];
  long checked = 0;
  for (int pass = 0; pass < 2; pass++)
    for (int i = 0; i <= 4000; i++) {
      int j = pass ? 4000 - i : i;                  /* the second pass backwards */
      double t = 50e-6 * j / 4000, b = cup_input_next_break(cup_netlist_input(nl), t);
      double ts[4] = {t, nextafter(b, 0), b, nextafter(b, 1)};
      for (int q = 0; q < (j % 20 ? 1 : 4); q++) {   /* the next corner and its neighbouring doubles */
        assert_int_equal(cup_netlist_signals(nl, ts[q], &x, NULL, out), CUP_OK);
        assert_int_equal(cup_input_eval(cup_netlist_input(nl), ts[q], u), CUP_OK);
        assert_true(out[0] == u[1] && out[1] == 12);
        double r = fmod(ts[q] - 1e-6, 1e-5);
        if (ts[q] > 1e-6 && fabs(r) > 1e-12 && fabs(r - 3e-6) > 1e-12 && fabs(r - 1e-5) > 1e-12)
          assert_true(out[0] == (r > 0 && r < 3e-6 ? 1 : 0)), checked++;
      }
    }
  assert_true(checked > 7000);
  assert_int_equal(cup_netlist_signals(nl, 2e-6, &x, NULL, out), CUP_OK);
  assert_true(out[0] == 1);
  assert_int_equal(cup_netlist_set_time_origin(nl, 3e-6, err), CUP_OK);
  assert_int_equal(cup_netlist_signals(nl, 2.5e-6, &x, NULL, out), CUP_OK);
  assert_true(out[0] == 0);                         /* 5.5 us as written: after the top */
  assert_int_equal(cup_netlist_signals(nl, 8.5e-6, &x, NULL, out), CUP_OK);
  assert_true(out[0] == 1);                         /* 11.5 us: the second period's top */
  cup_netlist_free(&nl);
}

/* The adaptive scheme's zeta (cup_integrator_zeta in the sink) gives the
 * RL rectifier's diode voltage: v(in,a) = 0 while it conducts, the source
 * 10 sin(w t) while it blocks (i = 0, so v(a) = R i + L i' = 0); and v(a)
 * the other way round. Samples within 1e-6 s of a switch are left out. */
typedef struct sig_run { cup_netlist *nl; const cup_integrator *I; double t[1001], s[1001][2]; long n; } sig_run;

static int keep_signals(long k, double t, const double *x, void *ctx) {
  (void)k;
  sig_run *r = ctx;
  double z[4], out[2];
  if (r->n > 1000 || cup_integrator_zeta(r->I, z) || cup_netlist_signals(r->nl, t, x, z, out)) return 1;
  r->t[r->n] = t;
  memcpy(r->s[r->n++], out, sizeof out);
  return 0;
}

static void test_rl_adaptive_signals(void **state) {
  (void)state;
  rl q = rl_example();
  static sig_run r;
  char err[CUP_ERRMSG_LEN];
  r.nl = load_ok(CIR "/rl-halfwave.cir", NULL, 0);
  assert_int_equal(cup_netlist_probe(r.nl, "v(in,a)", err), 0);
  assert_int_equal(cup_netlist_probe(r.nl, "v(a)", err), 1);
  assert_int_equal(cup_lcs_rows(cup_netlist_lcs(r.nl)), 1);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.T = 0.04;
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.tol_abs = o.tol_rel = 1e-9;
  o.output = CUP_OUTPUT_SAMPLES;
  o.output_samples = 1001;
  cup_integrator *I = NULL;
  assert_int_equal(cup_integrator_create(&I, cup_netlist_lcs(r.nl), cup_netlist_input(r.nl), &o, err), CUP_OK);
  r.I = I;
  cup_run_info info;
  assert_int_equal(cup_integrator_run(I, cup_netlist_x0(r.nl), keep_signals, &r, &info), CUP_OK);
  assert_int_equal(r.n, 1001);
  double worst = 0, Tp = 2 * M_PI / q.w;
  long blocking = 0;
  for (long k = 1; k < r.n; k++) {
    double t = r.t[k], s = fmod(t, Tp), V = q.V * sin(q.w * t);
    if (fabs(s - q.toff) < 1e-6 || s < 1e-6 || Tp - s < 1e-6) continue;
    int on = s < q.toff;
    blocking += !on;
    worst = fmax(worst, fmax(fabs(r.s[k][0] - (on ? 0 : V)), fabs(r.s[k][1] - (on ? V : 0))));
  }
  print_message("RL rectifier, adaptive: v(in,a) and v(a) against the closed form: max error %.3g V "
                "(%ld blocking samples)\n", worst, blocking);
  assert_true(blocking > 100);
  assert_true(worst <= 1e-6);
  cup_integrator_free(&I);
  cup_netlist_free(&r.nl);
}

/* ---- D != 0: the rectifiers against an independent integration ------------------------ */

/* With ideal diodes and a source resistance the RC rectifiers are ODEs with
 * a Lipschitz right-hand side: the diode (or bridge) current is
 * max(0, (V - v)/Rs) with V the source (|V| for the bridge), so
 *     C v' = max(0, (V(t) - v)/Rs) - v/RL.
 * Classical RK4 at a step 100x below the scheme's is the reference (its
 * error is far below the scheme's at the kinks where the diode switches). */
typedef struct rc { double Vm, w, Rs, C, RL; int full; } rc;

static double rc_rhs(const rc *q, double t, double v) {
  double V = q->Vm * sin(q->w * t);
  if (q->full) V = fabs(V);
  return (fmax(0, (V - v) / q->Rs) - v / q->RL) / q->C;
}

static void rc_reference(const rc *q, double T, long n, double *out) {   /* out[0..n] at t = k T/n */
  long sub = 100;
  double h = T / (double)(n * sub), v = 0;
  out[0] = 0;
  for (long k = 0; k < n; k++) {
    for (long j = 0; j < sub; j++) {
      double t = (double)(k * sub + j) * h;
      double k1 = rc_rhs(q, t, v), k2 = rc_rhs(q, t + h / 2, v + h / 2 * k1);
      double k3 = rc_rhs(q, t + h / 2, v + h / 2 * k2), k4 = rc_rhs(q, t + h, v + h * k3);
      v += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    out[k + 1] = v;
  }
}

/* v(out) (state 0) by the theta scheme at n = 3000 and 30000 against the
 * reference at the 1001 samples; returns the two errors. The step-doubling
 * estimate (a run at n/2 with the same D) is within 10x of them. */
static void rc_errors(const char *file, const rc *q, double err[2]) {
  cup_netlist *nl = load_ok(file, NULL, 0);
  char msg[CUP_ERRMSG_LEN];
  double T = 0.06;
  double *ref = malloc(sizeof(double) * 1001);
  rc_reference(q, T, 1000, ref);
  for (int r = 0; r < 2; r++) {
    cup_integrator_options o;
    cup_integrator_options_default(&o);
    o.T = T;
    o.n = r ? 30000 : 3000;
    o.scheme = CUP_SCHEME_THETA;
    o.eps = o.eta = (cup_schedule){0, 0};
    o.output = CUP_OUTPUT_SAMPLES;
    o.output_samples = 1001;
    o.estimate = 1;
    cup_integrator *I = NULL;
    cup_run_info info;
    static traj a;
    a.dim = cup_lcs_dim(cup_netlist_lcs(nl));
    assert_true(a.dim <= 3);
    assert_int_equal(cup_integrator_create(&I, cup_netlist_lcs(nl), cup_netlist_input(nl), &o, msg), CUP_OK);
    assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), keep, &a, &info), CUP_OK);
    cup_integrator_free(&I);
    err[r] = 0;
    for (long k = 0; k < a.n; k++) err[r] = fmax(err[r], fabs(a.x[k][0] - ref[k]));
    print_message("%s theta n %5ld: max |v - v_ref| = %.3e V, step-doubling estimate %.3e V\n",
                  strrchr(file, '/') + 1, o.n, err[r], info.err_est);
    assert_true(info.err_est >= 0.1 * err[r] && info.err_est <= 10 * err[r]);
  }
  free(ref);
  cup_netlist_free(&nl);
}

static void test_rectifiers_with_D(void **state) {
  (void)state;
  double e[2];
  rc half = {10, 2 * M_PI * 50, 1, 100e-6, 1000, 0};
  rc_errors(CIR "/halfwave-rc.cir", &half, e);
  /* measured: 3.8e-4 and 3.8e-6 V (half-wave), 5.7e-4 and 3.8e-6 V (bridge):
   * second order, the trapezoid on the diode currents (with the current at
   * t_{k+1} alone it was first order, 1.1e-2 and 1.1e-3 V) */
  assert_true(e[0] < 1e-3 && e[1] < e[0] / 50);
  rc full = half;
  full.full = 1;
  rc_errors(CIR "/bridge.cir", &full, e);
  assert_true(e[0] < 1e-3 && e[1] < e[0] / 50);
}

/* ---- bad input ----------------------------------------------------------------------- */

static int load_netlist(const char *path, char err[CUP_ERRMSG_LEN], int *out_null) {
  cup_netlist *nl = (cup_netlist *)err;
  int st = cup_netlist_load(&nl, path, NULL, 0, err);
  *out_null = nl == NULL;
  if (st == CUP_OK && nl) cup_netlist_free(&nl);
  return st;
}

static void test_bad_corpus(void **state) {
  (void)state;
  int failures;
  int count = bad_corpus_check(BAD, ".cir", "* expect: ", load_netlist, &failures);
  print_message("%d malformed netlists checked\n", count);
  assert_int_equal(failures, 0);
  assert_true(count >= 40);
}

/* Loops of ideal diodes with no resistance (issue 27): each netlist of
 * tests/netlists/warn loads, with the warning its first line expects,
 * naming the loop's elements (behind a switch: the warning of the
 * configuration settled on at t = 0, not of the one written); the example
 * circuits (a bridge among them:
 * a loop of diodes in both directions, whose current is unique) have none. */
static void test_diode_loops(void **state) {
  (void)state;
  static const char *const warn[] = {"antiparallel", "parallel", "diode-ring", "switched-antiparallel"};
  for (int k = 0; k < 4; k++) {
    char path[1024];
    snprintf(path, sizeof path, "%s/../warn/%s.cir", BAD, warn[k]);
    char *want = bad_expected_error(path, "* expect-warning: ");
    assert_non_null(want);
    cup_netlist *nl = load_ok(path, NULL, 0);
    const char *got = cup_netlist_warning(nl);
    if (!got || !strstr(got, want)) fail_msg("%s: warning\n  %s\nexpected\n  %s", warn[k], got ? got : "(none)", want);
    free(want);
    cup_netlist_free(&nl);
  }
  static const char *const clean[] = {"bridge", "clamp", "doubler", "halfwave-rc", "ladder", "paper-fig2",
                                      "rl-halfwave"};
  for (int k = 0; k < 7; k++) {
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.cir", CIR, clean[k]);
    cup_netlist *nl = load_ok(path, NULL, 0);
    if (cup_netlist_warning(nl)) fail_msg("%s: unexpected warning %s", clean[k], cup_netlist_warning(nl));
    cup_netlist_free(&nl);
  }
}

static char *slurp_text(const char *path) {
  FILE *f = fopen(path, "rb");
  assert_non_null(f);
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *s = malloc((size_t)n + 1);
  assert_int_equal(fread(s, 1, (size_t)n, f), (size_t)n);
  s[n] = '\0';
  fclose(f);
  return s;
}

static void check_clean(const char *text, long *loaded) {
  char err[CUP_ERRMSG_LEN] = "";
  cup_netlist *nl = (cup_netlist *)&err;
  int st = cup_netlist_load_string(&nl, text, "mut.cir", NULL, 0, err);
  if (st == CUP_OK) { (*loaded)++; cup_netlist_free(&nl); return; }
  if (nl || strncmp(err, "mut.cir", 7) || strchr(err, '\n'))
    fail_msg("status %d, message '%s' for\n%s", st, err, text);
}

/* Every prefix of every example, and each with one byte replaced by a
 * character that matters to the reader, loads or fails cleanly: a one-line
 * message naming the file, *nl NULL (leaks: valgrind/ASan runs). */
static void test_mutations(void **state) {
  (void)state;
  const char *files[] = {"paper-fig2", "halfwave-rc", "bridge", "clamp", "doubler", "rl-halfwave"};
  const char subst[] = {'(', '{', '=', '+', '\n', '0'};
  long loaded = 0, total = 0;
  for (size_t f = 0; f < sizeof files / sizeof files[0]; f++) {
    char path[512];
    snprintf(path, sizeof path, "%s/%s.cir", CIR, files[f]);
    char *text = slurp_text(path);
    size_t n = strlen(text);
    char *buf = malloc(n + 1);
    for (size_t k = 0; k <= n; k++, total++) {
      memcpy(buf, text, k);
      buf[k] = '\0';
      check_clean(buf, &loaded);
    }
    for (size_t k = 0; k < n; k++)
      for (size_t c = 0; c < sizeof subst; c++, total++) {
        memcpy(buf, text, n + 1);
        buf[k] = subst[c];
        check_clean(buf, &loaded);
      }
    free(buf);
    free(text);
  }
  print_message("mutated netlists: %ld of %ld loaded, the rest failed cleanly\n", loaded, total);
}

/* A netlist means what SPICE means (docs/netlist.md): .tran TSTEP TSTOP
 * TSTART TMAX samples every TSTEP from TSTART and caps the step at TMAX;
 * .options sets the adaptive scheme's tol (RELTOL relative; the smallest
 * of ABSTOL for L's currents, VNTOL and CHGTOL / C for C's voltages). */
static int keep_times(long k, double t, const double *x, void *ctx) {
  (void)k; (void)x;
  traj *s = ctx;
  if (s->n < 1001) s->x[s->n++][0] = t;
  return 0;
}

static void test_spice_meaning(void **state) {
  (void)state;
  const char *text = "netlist: {name: rc.cir, text: \"rc\\nV1 a 0 SIN(0 10 50)\\nR1 a b 1k\\nC1 b 0 10u\\n"
                     "L1 b c 1m\\nR2 c 0 10\\nD1 c 0\\n.options reltol=1e-8 abstol=1e-11 vntol=1e-7 itl4=50 "
                     "chgtol=1e-15\\n.tran 0.1m 20m 5m 50u\\n\"}\n";
  char err[CUP_ERRMSG_LEN];
  cup_scene *sc = NULL;
  if (cup_scene_load_string(&sc, text, "spice.yaml", NULL, NULL, 0, err)) fail_msg("%s", err);
  const cup_integrator_options *o = cup_scene_options(sc);
  assert_int_equal(o->scheme, CUP_SCHEME_ADAPTIVE);
  assert_close(o->T, 20e-3, 1e-18);
  assert_close(o->hmax, 50e-6, 1e-20);
  assert_close(o->output_t0, 5e-3, 1e-18);
  assert_int_equal(o->output, CUP_OUTPUT_SAMPLES);
  assert_int_equal(o->output_samples, 151);      /* (20m - 5m) / 0.1m + 1 */
  assert_close(o->tol_rel, 1e-8, 1e-23);
  assert_close(o->tol_abs, 1e-11, 1e-26);        /* min(ABSTOL 1e-11, VNTOL 1e-7, CHGTOL / C = 1e-10) */
  cup_integrator *I = NULL;
  if (cup_scene_integrator(sc, o, &I, err)) fail_msg("%s", err);
  static traj tt = {.dim = 1};
  tt.n = 0;
  cup_run_info info;
  assert_int_equal(cup_integrator_run(I, cup_scene_x0(sc), keep_times, &tt, &info), CUP_OK);
  assert_int_equal(tt.n, 151);
  for (int k = 0; k < tt.n; k++) assert_close(tt.x[k][0], 5e-3 + 0.1e-3 * k, 1e-17);
  assert_true(info.step >= 400);                 /* TMAX caps the steps: T / TMAX = 400 */
  cup_integrator_free(&I);
  cup_scene_free(&sc);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_paper_matrices),
    cmocka_unit_test(test_paper_trajectory),
    cmocka_unit_test(test_values),
    cmocka_unit_test(test_pulse_edges),
    cmocka_unit_test(test_free_diode),
    cmocka_unit_test(test_bridge),
    cmocka_unit_test(test_doubler),
    cmocka_unit_test(test_signals),
    cmocka_unit_test(test_rl_closed_form),
    cmocka_unit_test(test_rl_adaptive_signals),
    cmocka_unit_test(test_rectifiers_with_D),
    cmocka_unit_test(test_bad_corpus),
    cmocka_unit_test(test_diode_loops),
    cmocka_unit_test(test_mutations),
    cmocka_unit_test(test_spice_meaning),
    cmocka_unit_test(test_signal_jump_pulse),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

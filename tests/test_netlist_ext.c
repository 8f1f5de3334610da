/* netlist_ext: controlled sources (E, F, G, H), coupled inductors (K),
 * subcircuits (X, .subckt), .include and .lib, each against a closed form
 * computed here: amplifier gains from Kirchhoff's laws, two coupled RL
 * loops by their 2 x 2 matrix exponential, the op-amp precision rectifier
 * against k max(0, -vin). The LCS internals (src/model/lcs_impl.h) are read
 * to compare matrices. */
#define _GNU_SOURCE
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <unistd.h>
#include <sys/stat.h>
#include <cmocka.h>
#include "testutil.h"
#include "lcs_impl.h"
#include "netlistutil.h"

static void assert_rel(double got, double want, double tol) {
  if (!(fabs(got - want) <= tol * fabs(want))) fail_msg("got %.17g, want %.17g (rel tol %g)", got, want, tol);
}

/* A signal's value at state x (u from the netlist's input at t). */
static double signal_at(cup_netlist *nl, const char *name, double t, const double *x, const double *zeta) {
  char err[CUP_ERRMSG_LEN];
  int k = cup_netlist_probe(nl, name, err);
  if (k < 0) fail_msg("probe %s: %s", name, err);
  double out[64];
  assert_true(cup_netlist_signal_count(nl) <= 64);
  assert_int_equal(cup_netlist_signals(nl, t, x, zeta, out), CUP_OK);
  return out[k];
}

/* ---- controlled sources ------------------------------------------------------ */

/* An inverting amplifier, E as the op-amp with open-loop gain A, into an RC
 * load: v(out) = -A R2 vin / (R1 + R2 + A R1) and v(C1)' = (v(out) - v)/(RL C). */
static void test_vcvs_amplifier(void **state) {
  (void)state;
  const double R1 = 1e3, R2 = 10e3, A = 1e5, RL = 1e3, C = 1e-6, vin = 0.7;
  cup_netlist *nl = text_ok("inverting amplifier\n"
                            "V1 in 0 0.7\n"
                            "R1 in inm 1k\n"
                            "R2 inm out 10k\n"
                            "E1 out 0 0 inm 1e5\n"
                            "RL out o2 1k\n"
                            "C1 o2 0 1u\n", NULL, 0);
  const cup_lcs *L = cup_netlist_lcs(nl);
  double k = A * R2 / (R1 + R2 + A * R1);
  assert_false(L->has_D);                         /* no diode: a sweeping process, every scheme */
  assert_rel(at(&L->A, 0, 0), -1 / (RL * C), 1e-14);
  assert_rel(at(&L->E, 0, 0), -k / (RL * C), 1e-12);
  double x = 0.25;
  assert_rel(signal_at(nl, "v(out)", 0, &x, NULL), -k * vin, 1e-12);
  assert_rel(signal_at(nl, "v(inm)", 0, &x, NULL), -k * vin / -A, 1e-9);   /* v(out) = -A v(inm) */
  assert_rel(signal_at(nl, "i(E1)", 0, &x, NULL),                         /* from out through E1 to 0 */
             -((-k * vin - x) / RL + (-k * vin - (-k * vin / -A)) / R2), 1e-9);
  print_message("VCVS amplifier: gain %.9f (ideal -10), A = 1e5\n", -k);
  cup_netlist_free(&nl);
}

/* G: gm v(in) into RL || C; F: a current mirror of V's branch current; H:
 * a transresistance. Each C v' = (source) - v / RL. */
static void test_vccs_cccs_ccvs(void **state) {
  (void)state;
  const double gm = 2e-3, RL = 5e3, C = 1e-6, beta = 3, rm = 2e3;
  cup_netlist *nl = text_ok("three controlled sources\n"
                            "V1 in 0 2\n"
                            "R0 in 0 1k\n"
                            "G1 0 og in 0 2m\n"          /* gm v(in) flows from 0 through G1 into og */
                            "RG og 0 5k\n"
                            "CG og 0 1u\n"
                            "I1 0 a 1m\n"                 /* 1 mA into a, through Vs to 0 */
                            "Vs a 0 0\n"
                            "F1 0 of Vs 3\n"
                            "RF of 0 5k\n"
                            "CF of 0 1u\n"
                            "H1 oh 0 Vs 2k\n"
                            "RH oh b 5k\n"
                            "CH b 0 1u\n", NULL, 0);
  const cup_lcs *L = cup_netlist_lcs(nl);
  for (int j = 0; j < 3; j++) assert_rel(at(&L->A, j, j), -1 / (RL * C), 1e-14);
  /* inputs in netlist order: V1, I1, Vs */
  assert_rel(at(&L->E, 0, 0), gm / C, 1e-14);                 /* v(og)' = gm V1 / C */
  assert_rel(at(&L->E, 1, 1), beta / C, 1e-14);               /* i(Vs) = I1 */
  assert_rel(at(&L->E, 2, 1), rm / (RL * C), 1e-14);          /* v(oh) = rm I1 */
  double x[3] = {0, 0, 0};
  assert_rel(signal_at(nl, "i(G1)", 0, x, NULL), gm * 2, 1e-14);
  assert_rel(signal_at(nl, "i(F1)", 0, x, NULL), beta * 1e-3, 1e-14);
  assert_rel(signal_at(nl, "v(oh)", 0, x, NULL), rm * 1e-3, 1e-14);
  cup_netlist_free(&nl);
}

/* A loop of controlled sources with loop gain 1 (E1 = v(a), a its own
 * output) is singular; gain 0.5 is not (v = 0.5 v + ...). */
static void test_controlled_loop(void **state) {
  (void)state;
  assert_contains(text_bad("loop\nV1 in 0 1\nR1 in a 1k\nE1 b 0 b 0 1\nR2 b a 1k\nC1 a 0 1u\n", NULL, 0),
                  "t.cir:4:1: E1: a loop of controlled sources (E1) makes the circuit singular");
  assert_contains(text_bad("loop2\nV1 in 0 1\nR1 in a 1k\nE1 b 0 c 0 2\nE2 c 0 b 0 0.5\nR2 b a 1k\nR3 c a 1k\n"
                           "C1 a 0 1u\n", NULL, 0), "a loop of controlled sources (E1 and E2)");
  cup_netlist *nl = text_ok("loop ok\nV1 in 0 1\nR1 in a 1k\nE1 b 0 c 0 2\nE2 c 0 b 0 0.25\nR2 b a 1k\n"
                            "R3 c a 1k\nC1 a 0 1u\n", NULL, 0);
  cup_netlist_free(&nl);
}

/* ---- the op-amp precision rectifier (the item 6) ---------------------- */

typedef struct rec { cup_netlist *nl; cup_integrator *I; int k; double worst, kgain; long n; } rec;

static int rec_sink(long k, double t, const double *x, void *ctx) {
  rec *r = ctx;
  double zeta[2] = {0, 0}, out[64];
  if (k > 0) assert_int_equal(cup_integrator_zeta(r->I, zeta), CUP_OK);   /* zeta(0) = 0: skip t = 0 */
  assert_int_equal(cup_netlist_signals(r->nl, t, x, zeta, out), CUP_OK);
  double want = r->kgain * fmax(0, -sin(2 * M_PI * 50 * t));
  if (k > 0) r->worst = fmax(r->worst, fabs(out[r->k] - want));
  r->n++;
  return 0;
}

/* Inverting half-wave precision rectifier: D1 clamps the op-amp's output
 * to its inverting input for vin > 0 (then v(inm) = 0 exactly and v(vo) =
 * 0), D2 passes v(vo) = -k vin for vin < 0, k = A R2 / (R1 + R2 + A R1);
 * the state is an RC across the source (Rs, Cs), so v(vo) = k max(0, -vin)
 * at every step. Only the theta scheme runs it: the op-amp drives the
 * diodes' rows, B is not P^-1 C^T. */
static void test_precision_rectifier(void **state) {
  (void)state;
  const double R1 = 1e3, R2 = 2e3, A = 1e5;
  cup_netlist *nl = text_ok("precision rectifier\n"
                            "V1 in 0 SIN(0 1 50)\n"
                            "Rs in x 1k\n"
                            "Cs x 0 1u\n"
                            "R1 in inm 1k\n"
                            "R2 inm vo 2k\n"
                            "E1 oa 0 0 inm 1e5\n"
                            "D1 inm oa\n"
                            "D2 oa vo\n"
                            "RL vo 0 10k\n"
                            ".tran 20u 40m\n", NULL, 0);
  const cup_lcs *L = cup_netlist_lcs(nl);
  assert_true(L->has_D);
  char err[CUP_ERRMSG_LEN];
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.T = 0.04;
  o.n = 2000;
  cup_integrator *I = NULL;
  for (int s = 0; s < CUP_SCHEME_COUNT; s++) {
    if (s == CUP_SCHEME_THETA || s == CUP_SCHEME_ADAPTIVE) continue;
    o.scheme = (cup_scheme)s;
    assert_int_not_equal(cup_integrator_create(&I, L, cup_netlist_input(nl), &o, err), CUP_OK);
    assert_contains(err, "use the theta or the adaptive scheme");
  }
  print_message("explicit refused: %s\n", err);
  o.scheme = CUP_SCHEME_THETA;
  if (cup_integrator_create(&I, L, cup_netlist_input(nl), &o, err)) fail_msg("%s", err);
  rec r = {nl, I, cup_netlist_probe(nl, "v(vo)", err), 0, A * R2 / (R1 + R2 + A * R1), 0};
  assert_true(r.k >= 0);
  cup_run_info info;
  /* these diodes' rows do not depend on the state and the gain makes their
   * block nearly singular: the theta step refines zeta on its support and
   * certifies every step (docs/netlist.md, Limits) */
  int st = cup_integrator_run(I, cup_netlist_x0(nl), rec_sink, &r, &info);
  if (st != CUP_OK) fail_msg("%s", info.message);
  assert_int_equal(info.not_certified, 0);
  print_message("precision rectifier, theta n = 2000: max |v(vo) - k max(0, -vin)| = %.3e V (k = %.9f)\n",
                r.worst, r.kgain);
  assert_true(r.worst < 1e-8);                   /* rounding times the loop gain A = 1e5 */
  cup_integrator_free(&I);
  /* the adaptive scheme: each conducting diode's multiplier is algebraic
   * (its row of D), the switch at each zero of the input */
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.tol_abs = o.tol_rel = 1e-9;
  o.output = CUP_OUTPUT_SAMPLES;
  o.output_samples = 2001;
  if (cup_integrator_create(&I, L, cup_netlist_input(nl), &o, err)) fail_msg("%s", err);
  r.I = I;
  r.worst = 0;
  st = cup_integrator_run(I, cup_netlist_x0(nl), rec_sink, &r, &info);
  if (st != CUP_OK) fail_msg("%s", info.message);
  print_message("precision rectifier, adaptive tol 1e-9: max |v(vo) - k max(0, -vin)| = %.3e V, %ld events\n",
                r.worst, info.events);
  assert_true(r.worst < 1e-8);
  cup_integrator_free(&I);
  cup_netlist_free(&nl);
}

/* ---- coupled inductors --------------------------------------------------------- */

/* Two RL loops coupled by K: Lm i' = -R i + (V, 0). The exact solution from
 * x(0) = 0 is (e^{At} - I) A^-1 g with A = Lm^-1 (-R), g = Lm^-1 (V, 0), and
 * e^{At} by its two real eigenvalues (Sylvester's formula). */
static void exact_rl(const double A[4], const double g[2], double t, double x[2]) {
  double tr = A[0] + A[3], det = A[0] * A[3] - A[1] * A[2], disc = sqrt(tr * tr / 4 - det);
  double l1 = tr / 2 + disc, l2 = tr / 2 - disc, e1 = exp(l1 * t), e2 = exp(l2 * t);
  double a = (l1 * e2 - l2 * e1) / (l1 - l2), b = (e1 - e2) / (l1 - l2);   /* e^{At} = a I + b A */
  double M[4] = {a + b * A[0] - 1, b * A[1], b * A[2], a + b * A[3] - 1};  /* row-major */
  double y[2] = {(A[3] * g[0] - A[1] * g[1]) / det, (-A[2] * g[0] + A[0] * g[1]) / det};   /* A^-1 g */
  x[0] = M[0] * y[0] + M[1] * y[1];
  x[1] = M[2] * y[0] + M[3] * y[1];
}

typedef struct rl2 { double A[4], g[2], worst, T; long n; } rl2;

static int rl2_sink(long k, double t, const double *x, void *ctx) {
  (void)k;
  rl2 *q = ctx;
  double e[2];
  exact_rl(q->A, q->g, t, e);
  q->worst = fmax(q->worst, fmax(fabs(x[0] - e[0]), fabs(x[1] - e[1])));
  return 0;
}

static void test_coupled_rl(void **state) {
  (void)state;
  const double L1 = 1e-3, L2 = 2e-3, kc = 0.6, R1 = 1, R2 = 2, V = 1;
  cup_netlist *nl = text_ok("coupled RL loops\n"
                            "V1 a 0 1\n"
                            "R1 a b 1\n"
                            "L1 b 0 1m\n"
                            "L2 c 0 2m\n"
                            "R2 c 0 2\n"
                            "K1 L1 L2 0.6\n", NULL, 0);
  const cup_lcs *L = cup_netlist_lcs(nl);
  double M = kc * sqrt(L1 * L2), det = L1 * L2 - M * M;
  double Li[4] = {L2 / det, -M / det, -M / det, L1 / det};
  rl2 q = {{-R1 * Li[0], -R2 * Li[1], -R1 * Li[2], -R2 * Li[3]}, {V * Li[0], V * Li[2]}, 0, 0, 0};
  for (int i = 0; i < 2; i++)
    for (int j = 0; j < 2; j++) assert_rel(at(&L->A, i, j), q.A[2 * i + j], 1e-13);
  assert_rel(at(&L->E, 0, 0), q.g[0], 1e-13);
  assert_rel(at(&L->E, 1, 0), q.g[1], 1e-13);
  char err[CUP_ERRMSG_LEN];
  double theta1000 = 0;
  for (int s = 0; s < 3; s++) {                   /* exponential, theta n = 1000, theta n = 2000 */
    cup_integrator_options o;
    cup_integrator_options_default(&o);
    o.scheme = s ? CUP_SCHEME_THETA : CUP_SCHEME_EXPONENTIAL;
    o.T = 5e-3;
    o.n = s == 2 ? 2000 : 1000;
    cup_integrator *I = NULL;
    cup_run_info info;
    q.worst = 0;
    assert_int_equal(cup_integrator_create(&I, L, cup_netlist_input(nl), &o, err), CUP_OK);
    assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), rl2_sink, &q, &info), CUP_OK);
    cup_integrator_free(&I);
    print_message("coupled RL, %-11s n = %ld: max error %.3e A\n", cup_scheme_name(o.scheme), o.n, q.worst);
    if (s == 0) assert_true(q.worst < 1e-13);     /* exact for a linear ODE with a constant input */
    if (s == 1) assert_true((theta1000 = q.worst) < 1e-5);
    if (s == 2) assert_true(q.worst < theta1000 / 3.5);   /* second order */
  }
  cup_netlist_free(&nl);
}

/* K with a diode in series with L2 (a flyback's secondary): the metric is
 * the inductance matrix and P B = C^T still holds, so every scheme runs it. */
static void test_coupled_diode(void **state) {
  (void)state;
  cup_netlist *nl = text_ok("coupled with a diode\nV1 a 0 SIN(0 1 1k)\nR1 a b 1\nL1 b 0 1m\nL2 c 0 2m\n"
                            "D1 c d\nR2 d 0 2\nK1 L1 L2 0.9\n", NULL, 0);
  const cup_lcs *L = cup_netlist_lcs(nl);
  assert_false(L->has_D);
  cup_netlist_free(&nl);
  assert_contains(text_bad("k=1\nV1 a 0 1\nR1 a b 1\nL1 b 0 1m\nL2 c 0 2m\nR2 c 0 2\nK1 L1 L2 1\n", NULL, 0),
                  "t.cir:7:10: K1: k = 1 is not supported: a perfect coupling (an ideal transformer)");
  assert_contains(text_bad("k>1\nV1 a 0 1\nR1 a b 1\nL1 b 0 1m\nL2 c 0 2m\nR2 c 0 2\nK1 L1 L2 -1.5\n", NULL, 0),
                  "K1: k = -1.5 is out of range");
  /* pairwise 0.9 with signs that cannot all hold: L not positive definite */
  assert_contains(text_bad("3k\nV1 a 0 1\nR1 a b 1\nL1 b 0 1m\nL2 c 0 1m\nR2 c 0 2\nL3 d 0 1m\nR3 d 0 1\n"
                           "K1 L1 L2 0.9\nK2 L2 L3 0.9\nK3 L1 L3 -0.9\n", NULL, 0),
                  "t.cir:11:1: K3: the inductance matrix of L1, L2 and L3 is not positive definite");
}

/* ---- subcircuits, .include, .lib ------------------------------------------------- */

/* One RC definition, instantiated twice with different parameters (and an
 * internal node), and once inside another definition. */
static void test_subckt(void **state) {
  (void)state;
  cup_netlist *nl = text_ok("subcircuits\n"
                            ".param cbase=1u\n"
                            ".subckt rc in out params: r=1k c={cbase}\n"
                            "R1 in mid {r/2}\n"
                            "R2 mid out {r/2}\n"
                            "C1 out 0 {c}\n"
                            ".ends rc\n"
                            ".subckt two in out\n"
                            "X1 in m rc r=500\n"
                            "X2 m out rc PARAMS: c={2*cbase}\n"
                            ".ends\n"
                            "V1 a 0 1\n"
                            "X1 a b rc r=2k\n"
                            "X2 a d rc params: c=3u\n"
                            "X3 a e two\n", NULL, 0);
  const cup_lcs *L = cup_netlist_lcs(nl);
  const char *names[5] = {"v(X1.C1)", "v(X2.C1)", "v(X3.X1.C1)", "v(X3.X2.C1)", NULL};
  for (int j = 0; j < 4; j++) assert_string_equal(cup_netlist_state_name(nl, j), names[j]);
  assert_rel(at(&L->A, 0, 0), -1 / (2e3 * 1e-6), 1e-14);
  assert_rel(at(&L->A, 1, 1), -1 / (1e3 * 3e-6), 1e-14);
  /* X3: 500 ohm into 1u (node m), then 1k into 2u; m's equation couples them */
  assert_rel(at(&L->A, 2, 2), -(1 / 500.0 + 1 / 1e3) / 1e-6, 1e-14);
  assert_rel(at(&L->A, 2, 3), 1 / 1e3 / 1e-6, 1e-14);
  assert_rel(at(&L->A, 3, 3), -1 / (1e3 * 2e-6), 1e-14);
  double x[4] = {0.5, 0, 0, 0};
  assert_rel(signal_at(nl, "v(X1.mid)", 0, x, NULL), 0.75, 1e-14);          /* halfway from 1 to 0.5 */
  assert_rel(signal_at(nl, "i(X1.R1)", 0, x, NULL), 0.5 / 2e3, 1e-14);
  assert_rel(signal_at(nl, "v(b)", 0, x, NULL), 0.5, 1e-14);                 /* the pin is the caller's node */
  assert_rel(signal_at(nl, "i(r.x1.r2)", 0, x, NULL), 0.5 / 2e3, 1e-14);     /* ngspice's device name */
  cup_netlist_free(&nl);
}

static void write_file(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

/* Diodes with series resistors (D != 0) past the dense limits (64 rows):
 * theta and the adaptive scheme, the two that take D != 0, are dense, so
 * every scheme refuses it, and each says that no scheme runs it instead of
 * sending the user to another scheme that refuses it too (on 61ac75c:
 * implicit "use the theta or the adaptive scheme", theta "use the explicit,
 * implicit or exponential scheme", adaptive "use a fixed-step scheme").
 * With 2 stages the advice is the dense schemes, which run it. */
static void test_d_beyond_dense(void **state) {
  (void)state;
  char dir[] = "/tmp/cup_dd_XXXXXX", path[256], err[CUP_ERRMSG_LEN];
  assert_non_null(mkdtemp(dir));
  snprintf(path, sizeof path, "%s/ladder.cir", dir);
  for (int stages = 2; stages <= 70; stages += 68) {
    char text[16384];
    int at = snprintf(text, sizeof text, "rd ladder\nV1 n0 0 SIN(0 10 50)\n");
    for (int k = 1; k <= stages; k++)
      at += snprintf(text + at, sizeof text - (size_t)at, "D%d n%d m%d\nR%d m%d n%d 10\nC%d n%d 0 1u\n",
                     k, k - 1, k, k, k, k, k, k);
    snprintf(text + at, sizeof text - (size_t)at, ".tran 10u 20m\n.end\n");
    write_file(path, text);
    cup_netlist *nl = NULL;
    if (cup_netlist_load(&nl, path, NULL, 0, err)) fail_msg("%s", err);
    static const cup_scheme schemes[3] = {CUP_SCHEME_IMPLICIT, CUP_SCHEME_THETA, CUP_SCHEME_ADAPTIVE};
    for (int q = 0; q < 3; q++) {
      cup_integrator_options o;
      cup_integrator_options_default(&o);
      o.scheme = schemes[q];
      o.T = 0.02;
      o.n = 1000;
      cup_integrator *I = NULL;
      int st = cup_integrator_create(&I, cup_netlist_lcs(nl), cup_netlist_input(nl), &o, err);
      if (stages == 2 && schemes[q] != CUP_SCHEME_IMPLICIT) {
        if (st) fail_msg("%d stages, %s: %s", stages, cup_scheme_name(schemes[q]), err);
        cup_integrator_free(&I);
        continue;
      }
      assert_int_equal(st, CUP_ERR_UNSUPPORTED);
      if (!strstr(err, stages == 2 ? "use the theta or the adaptive scheme" : "no scheme runs it"))
        fail_msg("%d stages, %s: %s", stages, cup_scheme_name(schemes[q]), err);
    }
    cup_netlist_free(&nl);
  }
  remove(path);
  rmdir(dir);
}

/* .include and .lib with paths relative to the including file, and errors
 * located in the file that holds them. */
static void test_include_lib(void **state) {
  (void)state;
  char dir[] = "/tmp/cup_inc_XXXXXX", p[4][256], err[CUP_ERRMSG_LEN];
  assert_non_null(mkdtemp(dir));
  snprintf(p[0], sizeof p[0], "%s/sub", dir);
  assert_int_equal(mkdir(p[0], 0700), 0);
  snprintf(p[0], sizeof p[0], "%s/main.cir", dir);
  snprintf(p[1], sizeof p[1], "%s/sub/parts.inc", dir);
  snprintf(p[2], sizeof p[2], "%s/sub/more.inc", dir);
  snprintf(p[3], sizeof p[3], "%s/sub/lib.lib", dir);
  write_file(p[0], "main\n.include sub/parts.inc\n.lib sub/lib.lib fast\nV1 a 0 1\nX1 a b rc\nX2 a c rcf\n");
  write_file(p[1], "* the first line of an included file is read\n.include more.inc\n"
                   ".subckt rc in out\nR1 in out 1k\nC1 out 0 {cpar}\n.ends\n");
  write_file(p[2], ".param cpar=2u\n");
  write_file(p[3], ".lib slow\n.subckt rcf in out\nR1 in out 1meg\nC1 out 0 1\n.ends\n.endl\n"
                   ".lib fast\n.subckt rcf in out\nR1 in out 1\nC1 out 0 1n\n.ends\n.endl slow\n");
  cup_netlist *nl = NULL;
  if (cup_netlist_load(&nl, p[0], NULL, 0, err)) fail_msg("%s", err);
  const cup_lcs *L = cup_netlist_lcs(nl);
  assert_rel(at(&L->A, 0, 0), -1 / (1e3 * 2e-6), 1e-14);
  assert_rel(at(&L->A, 1, 1), -1 / (1 * 1e-9), 1e-14);       /* the fast section, not the slow */
  assert_int_equal(cup_netlist_file_count(nl), 4);
  assert_string_equal(cup_netlist_file(nl, 0), p[0]);
  char want[300];
  snprintf(want, sizeof want, "%s/sub/more.inc", dir);
  assert_string_equal(cup_netlist_file(nl, 2), want);
  cup_netlist_free(&nl);
  /* an error in the included file names it, its line and where it was included */
  write_file(p[2], ".param cpar=2u\nR9 x y 1kk!\n");
  assert_int_not_equal(cup_netlist_load(&nl, p[0], NULL, 0, err), CUP_OK);
  snprintf(want, sizeof want, "%s/sub/more.inc:2:8: R9: bad value '1kk!'", dir);
  assert_contains(err, want);
  assert_contains(err, "(included from ");
  assert_contains(err, "parts.inc:2)");
  /* an error in a subcircuit's body names the body's file and the instance */
  write_file(p[2], ".param cpar=-2u\n");
  assert_int_not_equal(cup_netlist_load(&nl, p[0], NULL, 0, err), CUP_OK);
  snprintf(want, sizeof want, "%s/sub/parts.inc:5:", dir);
  assert_contains(err, want);
  assert_contains(err, "X1.C1: bad value: capacitance must be > 0 (got -2e-06) (in instance X1 at ");
  for (int k = 3; k >= 0; k--) unlink(p[k]);
  snprintf(p[0], sizeof p[0], "%s/sub", dir);
  rmdir(p[0]);
  rmdir(dir);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_vcvs_amplifier),
    cmocka_unit_test(test_vccs_cccs_ccvs),
    cmocka_unit_test(test_controlled_loop),
    cmocka_unit_test(test_precision_rectifier),
    cmocka_unit_test(test_coupled_rl),
    cmocka_unit_test(test_coupled_diode),
    cmocka_unit_test(test_subckt),
    cmocka_unit_test(test_include_lib),
    cmocka_unit_test(test_d_beyond_dense),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

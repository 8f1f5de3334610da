/* netlist_switch: ideal switches (S, W) against closed forms computed here:
 * the two-capacitor problem (charge conserved, C1 C2 / (C1 + C2) V0^2 / 2
 * lost), the flux share of two inductors left in series by an opening
 * switch, an RC discharge through a closed switch, the ideal CCM buck's
 * average output D Vin and its inductor ripple, the configurations formed
 * once each, a switch that closes another through its control (the jump
 * of the capacitor it shorts); and the reader's errors. */
#define _GNU_SOURCE
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include "testutil.h"

static cup_netlist *text_ok(const char *text) {
  char err[CUP_ERRMSG_LEN] = "";
  cup_netlist *nl = NULL;
  int st = cup_netlist_load_string(&nl, text, "t.cir", NULL, 0, err);
  if (st) fail_msg("loading failed (%d): %s\n%s", st, err, text);
  return nl;
}

static const char *text_bad(const char *text) {
  static char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = NULL;
  int st = cup_netlist_load_string(&nl, text, "t.cir", NULL, 0, err);
  if (st == CUP_OK) fail_msg("loaded but should not have:\n%s", text);
  assert_null(nl);
  assert_null(strchr(err, '\n'));
  return err;
}

static void assert_contains(const char *msg, const char *want) {
  if (!strstr(msg, want)) fail_msg("message\n  %s\ndoes not contain\n  %s", msg, want);
}

/* The samples of a run: times, states and one signal. */
typedef struct run_rec {
  cup_netlist *nl;
  int n, k, sig, status;
  long cap, count;
  double *t, *x, *s;
  const cup_integrator *I;
} run_rec;

static int record(long k, double t, const double *x, void *ctx) {
  (void)k;
  run_rec *r = ctx;
  if (r->count == r->cap) return 1;
  r->t[r->count] = t;
  memcpy(r->x + r->count * r->n, x, sizeof(double) * (size_t)r->n);
  if (r->sig >= 0) {
    double zeta[16] = {0}, out[16];
    cup_integrator_zeta(r->I, zeta);
    assert_int_equal(cup_netlist_signals(r->nl, t, x, zeta, out), CUP_OK);
    r->s[r->count] = out[r->sig];
  }
  r->count++;
  return 0;
}

/* Run nl under the options o into r, at most cap records; the status in
 * r->status, an error fails the test. */
static void run_opts(cup_netlist *nl, const cup_integrator_options *o, long cap, const char *probe, run_rec *r) {
  char err[CUP_ERRMSG_LEN];
  memset(r, 0, sizeof *r);
  r->nl = nl;
  r->n = cup_lcs_dim(cup_netlist_lcs(nl));
  r->sig = probe ? cup_netlist_probe(nl, probe, err) : -1;
  if (probe && r->sig < 0) fail_msg("probe %s: %s", probe, err);
  r->cap = cap;
  r->t = malloc(sizeof(double) * (size_t)cap);
  r->x = malloc(sizeof(double) * (size_t)cap * (size_t)r->n);
  r->s = malloc(sizeof(double) * (size_t)cap);
  cup_switching sw;
  assert_int_equal(cup_netlist_switching(nl, &sw), 1);
  cup_integrator *I = NULL;
  if (cup_integrator_create_switched(&I, &sw, cup_netlist_input(nl), o, err)) fail_msg("create: %s", err);
  r->I = I;
  cup_run_info info;
  int st = cup_integrator_run(I, cup_netlist_x0(nl), record, r, &info);
  if (st < 0) fail_msg("run: %s", info.message);
  r->status = st;
  cup_integrator_free(&I);
}

/* Run nl over [0, T] with N samples into r: the adaptive scheme at tol,
 * or (steps > 0) scheme on that many steps. */
static void run_with(cup_netlist *nl, double T, double tol, long N, const char *probe, run_rec *r, cup_scheme scheme,
                     long steps) {
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = steps > 0 ? scheme : CUP_SCHEME_ADAPTIVE;
  if (steps > 0) o.n = steps;
  o.T = T;
  o.tol_abs = o.tol_rel = tol;
  o.output = CUP_OUTPUT_SAMPLES;
  o.output_samples = N;
  run_opts(nl, &o, N, probe, r);
  assert_int_equal(r->count, N);
}

static void run(cup_netlist *nl, double T, double tol, long N, const char *probe, run_rec *r) {
  run_with(nl, T, tol, N, probe, r, CUP_SCHEME_ADAPTIVE, 0);
}

static void rec_free(run_rec *r) { free(r->t); free(r->x); free(r->s); }

/* C1 charged to V0, C2 empty; S1 closes at 1 ms (a jump edge of its gate):
 * both then hold C1 V0 / (C1 + C2), the charge is C1 V0 to rounding and
 * the energy lost is C1 C2 / (C1 + C2) V0^2 / 2. Without the switch's
 * constraint the formulation refuses the loop C1, S1, C2. */
static void test_two_capacitors(void **state) {
  (void)state;
  const double C1 = 1e-6, C2 = 3e-6, V0 = 10;
  cup_netlist *nl = text_ok("two capacitors\n"
                            "C1 a 0 1u IC=10\n"
                            "C2 b 0 3u\n"
                            "S1 a b g 0 SMOD\n"
                            "Vg g 0 PULSE(0 1 1m jump jump 1 2)\n"
                            ".model SMOD SW(VT=0.5 VH=0.1)\n");
  run_rec r;
  run(nl, 2e-3, 1e-10, 201, "i(S1)", &r);
  double vf = C1 * V0 / (C1 + C2), lost = 0.5 * C1 * C2 / (C1 + C2) * V0 * V0, worst = 0, wq = 0;
  for (long k = 0; k < r.count; k++) {
    const double *x = r.x + 2 * k;
    int after = r.t[k] >= 1e-3;                   /* the sample at 1 ms: the state after the jump */
    worst = fmax(worst, after ? fmax(fabs(x[0] - vf), fabs(x[1] - vf)) : fmax(fabs(x[0] - V0), fabs(x[1])));
    wq = fmax(wq, fabs(C1 * x[0] + C2 * x[1] - C1 * V0));
    assert_true(fabs(r.s[k]) <= 1e-12);           /* no current once equal (and none before) */
  }
  const double *xe = r.x + 2 * (r.count - 1);
  double e0 = 0.5 * C1 * V0 * V0, e1 = 0.5 * C1 * xe[0] * xe[0] + 0.5 * C2 * xe[1] * xe[1];
  printf("two capacitors: |v - closed form| <= %.2e V, |charge - C1 V0| <= %.2e C, energy lost %.10e J "
         "(closed form %.10e J)\n", worst, wq, e0 - e1, lost);
  assert_true(worst <= 1e-12 * V0);
  assert_true(wq <= 1e-15 * C1 * V0);
  assert_true(fabs((e0 - e1) - lost) <= 1e-12 * lost);
  assert_int_equal(cup_netlist_configurations_formed(nl), 2);
  rec_free(&r);
  cup_netlist_free(&nl);
}

/* The same jump with every step recorded (output every 1) under options
 * o: the switching time holds two records, the state before the jump
 * (V0, 0) and after it (vf, vf) with no current through S1, so that a line
 * through the records shows the jump (it had the one before only, and
 * ramped to vf across the next step). The number of records, or -1. */
static long two_capacitors_every(cup_integrator_options *o, const char *what) {
  const double C1 = 1e-6, C2 = 3e-6, V0 = 10, vf = C1 * V0 / (C1 + C2);
  cup_netlist *nl = text_ok("two capacitors\nC1 a 0 1u IC=10\nC2 b 0 3u\nS1 a b g 0 SMOD\n"
                            "Vg g 0 PULSE(0 1 1m jump jump 1 2)\n.model SMOD SW(VT=0.5 VH=0.1)\n");
  o->T = 2e-3;
  o->output = CUP_OUTPUT_EVERY;
  o->output_every = 1;
  run_rec r;
  run_opts(nl, o, 4096, "i(S1)", &r);
  assert_true(r.count < r.cap);
  long at[4], nat = 0;
  for (long k = 0; k < r.count; k++)
    if (fabs(r.t[k] - 1e-3) <= 1e-15 && nat < 4) at[nat++] = k;
  printf("two capacitors, every step (%s): %ld records, %ld at the switching time\n", what, r.count, nat);
  assert_int_equal(nat, 2);
  assert_int_equal(at[1], at[0] + 1);
  const double *x0 = r.x + 2 * at[0], *x1 = r.x + 2 * at[1], *xe = r.x + 2 * (r.count - 1);
  assert_true(fabs(x0[0] - V0) <= 1e-12 * V0 && fabs(x0[1]) <= 1e-12 * V0);
  assert_true(fabs(x1[0] - vf) <= 1e-12 * V0 && fabs(x1[1] - vf) <= 1e-12 * V0);
  assert_true(fabs(xe[0] - vf) <= 1e-12 * V0 && fabs(xe[1] - vf) <= 1e-12 * V0);
  assert_true(fabs(r.s[at[1]]) <= 1e-12);
  long count = r.count;
  rec_free(&r);
  cup_netlist_free(&nl);
  return count;
}

static void test_two_capacitors_every_step(void **state) {
  (void)state;
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.tol_abs = o.tol_rel = 1e-10;
  two_capacitors_every(&o, "adaptive");
}

/* The fixed-step path (theta, the switching on grid time t_100): the
 * steps' ends, and the jump's second record at t_100: n + 2 records. */
static void test_two_capacitors_every_step_theta(void **state) {
  (void)state;
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_THETA;
  o.n = 200;
  assert_int_equal(two_capacitors_every(&o, "theta, n = 200"), 202);
}

/* A sine charges C1 through R1; S1 closes onto C2 at 1 ms. Then C1 and C2
 * hold one voltage v, and by Kirchhoff's laws the switch's current (the
 * multiplier of that configuration's constraint) is C2 / (C1 + C2)
 * (vs(t) - v) / R1: it reads the input through the constraint alone, the
 * probe naming no source node, and the signals' evaluation must see that
 * (it evaluates u only for the signals that read it). */
static void test_constraint_reads_input(void **state) {
  (void)state;
  const double C1 = 1e-6, C2 = 3e-6, R1 = 100, A = 10, f = 1e3;
  cup_netlist *nl = text_ok("a sine through a closing switch\n"
                            "V1 s 0 SIN(0 10 1k)\n"
                            "R1 s a 100\n"
                            "C1 a 0 1u\n"
                            "C2 b 0 3u\n"
                            "S1 a b g 0 SMOD\n"
                            "Vg g 0 PULSE(0 1 1m jump jump 1 2)\n"
                            ".model SMOD SW(VT=0.5 VH=0.1)\n");
  run_rec r;
  run(nl, 2e-3, 1e-10, 201, "i(S1)", &r);
  double worst = 0, largest = 0;
  long after = 0;
  for (long k = 0; k < r.count; k++) {
    if (!(r.t[k] > 1e-3 + 1e-9)) continue;
    double v = r.x[2 * k], vs = A * sin(2 * M_PI * f * r.t[k]), want = C2 / (C1 + C2) * (vs - v) / R1;
    worst = fmax(worst, fabs(r.s[k] - want));
    largest = fmax(largest, fabs(want));
    after++;
  }
  printf("constraint reads the input: |i(S1) - C2/(C1+C2) (vs - v)/R1| <= %.2e A over %ld samples "
         "(largest %.3f A)\n", worst, after, largest);
  assert_true(after >= 99);
  assert_true(largest > 0.01);
  assert_true(worst <= 1e-12 * A / R1);
  rec_free(&r);
  cup_netlist_free(&nl);
}

/* L1 = 1 H carrying 2 A and L2 = 3 H carrying 0.5 A share node b with S1
 * and R1; S1 is off from t = 0 (its gate is 0), which leaves L1 and L2 in
 * series: the jump is the flux-conserving (L1 i1 + L2 i2) / (L1 + L2) =
 * 0.875 A, then the loop R0, L1, L2 decays with tau = (L1 + L2) / R0.
 * x0 is off the configuration's constraint: projected, with a warning. */
static void test_inductor_cut(void **state) {
  (void)state;
  cup_netlist *nl = text_ok("inductors left in series\n"
                            "R0 a 0 2\n"
                            "L1 a b 1 IC=2\n"
                            "L2 b 0 3 IC=0.5\n"
                            "S1 b c g 0 SMOD\n"
                            "R1 c 0 1\n"
                            "Vg g 0 0\n"
                            ".model SMOD SW(VT=0.5)\n");
  run_rec r;
  run(nl, 4, 1e-11, 41, NULL, &r);
  assert_int_equal(r.status, CUP_WARN_X0_OUTSIDE);
  double istar = (1 * 2 + 3 * 0.5) / 4.0, worst = 0;
  for (long k = 0; k < r.count; k++) {             /* x0 projected is the first sample */
    double want = istar * exp(-2 * r.t[k] / 4);
    worst = fmax(worst, fmax(fabs(r.x[2 * k] - want), fabs(r.x[2 * k + 1] - want)));
  }
  printf("inductor cut: i1 = i2 = 0.875 exp(-t/2) A to %.2e A\n", worst);
  assert_true(worst <= 1e-10);
  rec_free(&r);
  cup_netlist_free(&nl);
}

/* An RC discharge through a switch with RON, closing at 1 ms: v(t) =
 * V0 exp(-(t - 1m) / ((R1 + RON) C)) after it, V0 before; and through an
 * ideal one (RON omitted), R1 C. */
static void test_rc_through_switch(void **state) {
  (void)state;
  for (int ideal = 0; ideal < 2; ideal++) {
    cup_netlist *nl = text_ok(ideal ? "rc\nC1 a 0 1u IC=5\nS1 a b g 0 SM\nR1 b 0 1k\nVg g 0 PULSE(0 2 1m 1u 1u 1 2)\n"
                                      ".model SM SW(VT=1)\n"
                                    : "rc\nC1 a 0 1u IC=5\nS1 a b g 0 SM\nR1 b 0 1k\nVg g 0 PULSE(0 2 1m 1u 1u 1 2)\n"
                                      ".model SM SW(VT=1 RON=250 ROFF=1e12)\n");
    run_rec r;
    run(nl, 4e-3, 1e-11, 401, NULL, &r);
    double tau = (1e3 + (ideal ? 0 : 250)) * 1e-6, ts = 1e-3 + 0.5e-6, worst = 0, roff = ideal ? 0 : 1e12;
    for (long k = 0; k < r.count; k++) {
      double t = r.t[k];
      double want = t <= ts ? 5 * exp(-t / (roff ? roff * 1e-6 : INFINITY)) : 5 * exp(-ts / (roff ? roff * 1e-6 : INFINITY)) * exp(-(t - ts) / tau);
      worst = fmax(worst, fabs(r.x[k] - want));
    }
    printf("RC through a%s switch closing at the gate's crossing (1.0005 ms): max error %.2e V\n",
           ideal ? "n ideal" : " RON=250 ROFF=1e12", worst);
    assert_true(worst <= 1e-9);
    rec_free(&r);
    cup_netlist_free(&nl);
  }
}

/* The ideal buck in CCM: 12 V in, D = 0.25 at 50 kHz (PULSE jump edges),
 * L = 100 uH, C = 10 uF, R = 5 Ohm. In the periodic steady state the
 * inductor's volt-seconds balance: the output's average over a period is
 * D Vin = 3 V exactly (the switch node is Vin for D Ts and 0 after, the
 * diode conducting); the inductor's ripple is (Vin - Vout) D Ts / L to
 * the output's own ripple relative to Vin - Vout. The two configurations are formed once each. */
static void test_buck(void **state) {
  (void)state;
  cup_netlist *nl = text_ok("ideal buck\n"
                            "V1 in 0 12\n"
                            "S1 in sw g 0 SMOD\n"
                            "D1 0 sw\n"
                            "L1 sw out 100u\n"
                            "C1 out 0 10u\n"
                            "R1 out 0 5\n"
                            "Vg g 0 PULSE(0 1 0 jump jump 5u 20u)\n"
                            ".model SMOD SW(VT=0.5)\n");
  const double Ts = 20e-6, D = 0.25, Vin = 12, L = 100e-6;
  long per = 2000, periods = 200;
  run_rec r;
  run(nl, periods * Ts, 1e-10, periods * per + 1, NULL, &r);
  /* the last period: the output's mean by the trapezoid on 2000 samples, the inductor's extremes */
  long k0 = (periods - 1) * per;
  double mean = 0, imax = -INFINITY, imin = INFINITY;
  for (long k = k0; k < k0 + per; k++) mean += 0.5 * (r.x[2 * k + 1] + r.x[2 * k + 3]) / (double)per;
  for (long k = k0; k <= k0 + per; k++) { imax = fmax(imax, r.x[2 * k]); imin = fmin(imin, r.x[2 * k]); }
  double drift = fabs(r.x[2 * (k0 + per) + 1] - r.x[2 * k0 + 1]);
  double ripple = (Vin - mean) * D * Ts / L, vmax = -INFINITY, vmin = INFINITY;
  for (long k = k0; k <= k0 + per; k++) { vmax = fmax(vmax, r.x[2 * k + 1]); vmin = fmin(vmin, r.x[2 * k + 1]); }
  printf("buck: mean v(out) over the last period %.9f V (D Vin = %.9f), drift over it %.1e V; ripple %.6f A "
         "(closed form %.6f A)\n", mean, D * Vin, drift, imax - imin, ripple);
  assert_true(drift <= 1e-7);
  assert_true(fabs(mean - D * Vin) <= 1e-5);
  /* the closed form takes v(out) constant: its error is within the output's ripple over Vin - Vout */
  assert_true(fabs((imax - imin) - ripple) <= ripple * (vmax - vmin) / (Vin - mean));
  assert_true(imin > 0);                          /* CCM */
  assert_int_equal(cup_netlist_configurations_formed(nl), 2);
  rec_free(&r);
  cup_netlist_free(&nl);
}

/* v(g2) of a PULSE(0 1 5u jump jump 3u 10u) read from t0 on: 1 on
 * [5u + k 10u, 8u + k 10u) of t0 + t; *edge: how near t is to a corner. */
static double gate2_exact(double t0, double t, double *edge) {
  double s = t0 + t - 5e-6, ph = s < 0 ? s : fmod(s, 10e-6);
  *edge = fmin(fabs(ph), fmin(fabs(ph - 3e-6), fabs(ph - 10e-6)));
  return s >= 0 && ph < 3e-6 ? 1 : 0;
}

/* Two gates out of phase: the samples' configurations change each few
 * microseconds, and their signals' gate values come from one cache they
 * share (sig_ucache): each sample's v(g2) is the PULSE's own value, also
 * after the time origin moved (the cache then starts over). */
static void test_gates_across_configurations(void **state) {
  (void)state;
  cup_netlist *nl = text_ok("two gated branches\n"
                            "V1 in 0 10\n"
                            "S1 in a g1 0 SMOD\nR1 a c 1k\n"
                            "S2 in b g2 0 SMOD\nR2 b c 1k\n"
                            "C1 c 0 1n\n"
                            "Vg1 g1 0 PULSE(0 1 0 jump jump 3u 10u)\n"
                            "Vg2 g2 0 PULSE(0 1 5u jump jump 3u 10u)\n"
                            ".model SMOD SW(VT=0.5)\n");
  char err[CUP_ERRMSG_LEN];
  const double origins[] = {0, 2.5e-6};
  for (int o = 0; o < 2; o++) {
    assert_int_equal(cup_netlist_set_time_origin(nl, origins[o], err), CUP_OK);
    run_rec r;
    run(nl, 50e-6, 1e-9, 1001, "v(g2)", &r);
    long checked = 0;
    for (long k = 0; k < r.count; k++) {
      double edge, want = gate2_exact(origins[o], r.t[k], &edge);
      if (edge < 1e-12) continue;                  /* at a corner: either side is the PULSE's to rounding */
      if (r.s[k] != want) fail_msg("t0 = %g: v(g2) = %g at t = %.17g, the PULSE's %g", origins[o], r.s[k], r.t[k], want);
      checked++;
    }
    assert_true(checked > 900);
    rec_free(&r);
  }
  /* the same instant read again after the origin moved: no value of the sources before */
  const double again[] = {0, 5e-6, 0, 1e-6};
  int g2 = cup_netlist_probe(nl, "v(g2)", err);
  assert_true(g2 >= 0);
  for (int o = 0; o < 4; o++) {
    double zeta[16] = {0}, out[16], edge;
    assert_int_equal(cup_netlist_set_time_origin(nl, again[o], err), CUP_OK);
    assert_int_equal(cup_netlist_signals(nl, 6e-6, cup_netlist_x0(nl), zeta, out), CUP_OK);
    assert_true(out[g2] == gate2_exact(again[o], 6e-6, &edge));
  }
  assert_true(cup_netlist_configurations_formed(nl) >= 3);
  cup_netlist_free(&nl);
}

/* A relaxation oscillator gated by its own capacitor: C charges from 10 V
 * through R1 = 1k while S1 is off and discharges through RON = 250 (to
 * v_inf = 2 V, tau2 = R1 || RON C) while on; S1 turns on above VT + VH = 6 V
 * and off below VT - VH = 4 V. From v(0) = 0: on at tau1 ln(10/4), then
 * off after t2 = tau2 ln((6 - 2)/(4 - 2)), on after t1 = tau1 ln((10 - 4)/(10 - 6)),
 * a period of t1 + t2. The samples against that piecewise closed form. */
static double relax_exact(double t) {
  const double tau1 = 1e-3, tau2 = 0.2e-3, t1 = tau1 * log(6.0 / 4), t2 = tau2 * log(4.0 / 2);
  double ton = tau1 * log(10.0 / 4);
  if (t <= ton) return 10 * (1 - exp(-t / tau1));
  double s = fmod(t - ton, t1 + t2);
  return s <= t2 ? 2 + 4 * exp(-s / tau2) : 10 - 6 * exp(-(s - t2) / tau1);
}

static void test_relaxation(void **state) {
  (void)state;
  cup_netlist *nl = text_ok("hysteretic RC relaxation oscillator\n"
                            "V1 in 0 10\n"
                            "R1 in c 1k\n"
                            "C1 c 0 1u\n"
                            "S1 c 0 c 0 SMOD\n"
                            ".model SMOD SW(VT=5 VH=1 RON=250)\n");
  run_rec r;
  run(nl, 5e-3, 1e-12, 5001, "v(c)", &r);
  double worst = 0, tw = 0;
  for (long k = 0; k < r.count; k++) {
    double e = fabs(r.x[k] - relax_exact(r.t[k]));
    if (e > worst) { worst = e; tw = r.t[k]; }
  }
  const double period = 1e-3 * log(1.5) + 0.2e-3 * log(2.0);
  printf("relaxation oscillator (period 2 tau ln form: %.9e s, %.1f periods): max |v - closed form| = %.2e V "
         "(at t = %.6e)\n", period, (5e-3 - 1e-3 * log(2.5)) / period, worst, tw);
  assert_true(worst <= 1e-8);
  assert_int_equal(cup_netlist_configurations_formed(nl), 2);
  rec_free(&r);
  cup_netlist_free(&nl);
}

/* The fixed-step schemes switch at the end of the step that holds the
 * switching time: on a grid that holds it, the two capacitors are as
 * exact as under the adaptive scheme (the sample at the switching time the
 * state after the jump under all four), and the buck's mean output is D Vin
 * to the scheme's error (it was 3.41 V while the gate's edges and the grid
 * rounded apart and a step in seven periods was taken in the old
 * configuration); the relaxation oscillator, whose switching times fall
 * between grid points, converges at first order in h. */
static void test_fixed_step(void **state) {
  (void)state;
  static const cup_scheme schemes[] = {CUP_SCHEME_EXPLICIT, CUP_SCHEME_IMPLICIT, CUP_SCHEME_EXPONENTIAL,
                                       CUP_SCHEME_THETA};
  for (int q = 0; q < 4; q++) {
    cup_netlist *nl = text_ok("two capacitors\nC1 a 0 1u IC=10\nC2 b 0 3u\nS1 a b g 0 SMOD\n"
                              "Vg g 0 PULSE(0 1 1m jump jump 1 2)\n.model SMOD SW(VT=0.5 VH=0.1)\n");
    run_rec r;
    run_with(nl, 2e-3, 0, 201, NULL, &r, schemes[q], 200);
    double worst = 0;
    for (long k = 0; k < r.count; k++)
      worst = fmax(worst, r.t[k] < 1e-3 ? fmax(fabs(r.x[2 * k] - 10), fabs(r.x[2 * k + 1]))
                                        : fmax(fabs(r.x[2 * k] - 2.5), fabs(r.x[2 * k + 1] - 2.5)));
    printf("two capacitors, %-11s n = 200: max error %.2e V\n", cup_scheme_name(schemes[q]), worst);
    assert_true(worst <= 1e-13);
    rec_free(&r);
    cup_netlist_free(&nl);
  }
  cup_netlist *nl = text_ok("ideal buck\nV1 in 0 12\nS1 in sw g 0 SMOD\nD1 0 sw\nL1 sw out 100u\nC1 out 0 10u\n"
                            "R1 out 0 5\nVg g 0 PULSE(0 1 0 jump jump 5u 20u)\n.model SMOD SW(VT=0.5)\n");
  run_rec r;
  long per = 40, periods = 200;
  run_with(nl, periods * 20e-6, 0, periods * per + 1, NULL, &r, CUP_SCHEME_THETA, periods * per);
  double mean = 0;
  long k0 = (periods - 1) * per;
  for (long k = k0; k < k0 + per; k++) mean += 0.5 * (r.x[2 * k + 1] + r.x[2 * k + 3]) / (double)per;
  printf("buck, theta, 40 steps a period: mean v(out) over the 200th period %.6f V (D Vin = 3)\n", mean);
  assert_true(fabs(mean - 3) <= 2e-3);
  assert_int_equal(cup_netlist_configurations_formed(nl), 2);
  rec_free(&r);
  cup_netlist_free(&nl);
  double err[2];
  for (int h = 0; h < 2; h++) {
    nl = text_ok("relaxation\nV1 in 0 10\nR1 in c 1k\nC1 c 0 1u\nS1 c 0 c 0 SMOD\n.model SMOD SW(VT=5 VH=1 RON=250)\n");
    run_with(nl, 5e-3, 0, 501, NULL, &r, CUP_SCHEME_THETA, 10000L << h);
    err[h] = 0;
    for (long k = 0; k < r.count; k++) err[h] = fmax(err[h], fabs(r.x[k] - relax_exact(r.t[k])));
    rec_free(&r);
    cup_netlist_free(&nl);
  }
  printf("relaxation oscillator, theta: max error %.3e V (n = 10000), %.3e V (n = 20000): ratio %.2f\n", err[0],
         err[1], err[0] / err[1]);
  assert_true(err[1] <= 0.1 && err[0] / err[1] > 1.6);   /* each switching up to h late: first order */
}

/* A switch the circuit gates, under a fixed-step scheme: the switching is
 * taken at the end of the first step whose end state passes the threshold
 * (docs/netlist.md, "Gating"). C charges through 1 kOhm from 10 V; S1
 * closes above 6 V (VT 5, VH 1), at t* = tau ln 2.5, onto 1 kOhm to ground
 * and stays closed (v tends to 5 V > 4 V). Under theta on a grid of h =
 * 10 us, t* = 916.3 us falls inside a step: the run follows the closed form
 * switched at the grid time after t* (920 us) to theta's error, and is off
 * the one switched at t* by the step's delay. */
static double rc_gated(double t, double ts) {
  if (t <= ts) return 10 * (1 - exp(-t / 1e-3));
  return 5 + (10 * (1 - exp(-ts / 1e-3)) - 5) * exp(-(t - ts) / 0.5e-3);
}

static void test_circuit_gated_step_end(void **state) {
  (void)state;
  cup_netlist *nl = text_ok("rc gated\nV1 in 0 10\nR1 in c 1k\nC1 c 0 1u\nS1 c d c 0 SMOD\nR2 d 0 1k\n"
                            ".model SMOD SW(VT=5 VH=1)\n");
  run_rec r;
  const double h = 1e-5, tstar = 1e-3 * log(2.5), tgrid = ceil(tstar / h) * h;
  run_with(nl, 3e-3, 0, 301, NULL, &r, CUP_SCHEME_THETA, 300);
  assert_int_equal(r.count, 301);
  double e_grid = 0, e_star = 0;
  for (long k = 0; k < r.count; k++) {
    e_grid = fmax(e_grid, fabs(r.x[k] - rc_gated(r.t[k], tgrid)));
    e_star = fmax(e_star, fabs(r.x[k] - rc_gated(r.t[k], tstar)));
  }
  printf("rc gated at 6 V, theta, h = 10 us: t* = %.6e s, taken at %.6e s: max error %.2e V against the closed form "
         "switched there, %.2e V against the one switched at t*\n", tstar, tgrid, e_grid, e_star);
  assert_true(tgrid - tstar > 0.2 * h);            /* inside a step */
  assert_true(e_grid <= 1e-4);
  assert_true(e_star >= 5e-3);
  assert_int_equal(cup_netlist_configurations_formed(nl), 2);
  rec_free(&r);
  cup_netlist_free(&nl);
}

/* Signals probed with "all" are recorded in every configuration: v(out)
 * is the capacitor's state at every sample of the buck, in both
 * configurations (a configuration formed before the probe had none, and
 * its samples kept the signals of the last sample before it: v(out) of
 * the buck-ccm example flat over each off-time in catchup-run's output). */
static void test_probe_all(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN];
  cup_netlist *nl = text_ok("ideal buck\nV1 in 0 12\nS1 in sw g 0 SMOD\nD1 0 sw\nL1 sw out 100u\nC1 out 0 10u\n"
                            "R1 out 0 5\nVg g 0 PULSE(0 1 0 jump jump 5u 20u)\n.model SMOD SW(VT=0.5)\n");
  assert_int_equal(cup_netlist_probe(nl, "all", err), CUP_OK);
  run_rec r;
  run_with(nl, 100e-6, 1e-8, 1001, "v(out)", &r, CUP_SCHEME_ADAPTIVE, 0);
  assert_int_equal(r.sig, 3);                      /* v(in) v(g) v(sw) v(out): "all"'s */
  assert_int_equal(r.count, 1001);
  double worst = 0;
  for (long k = 0; k < r.count; k++) worst = fmax(worst, fabs(r.s[k] - r.x[2 * k + 1]));
  printf("buck, probe all: max |v(out) - x_C1| over %ld samples %.2e V\n", r.count, worst);
  assert_true(worst == 0);
  assert_int_equal(cup_netlist_configurations_formed(nl), 2);
  rec_free(&r);
  cup_netlist_free(&nl);
}

/* A controller from code (cup_netlist_set_controller) that writes the
 * buck's PWM every 5 us (on at instants 4k, off at the others) gives the
 * trajectory of the gate from PULSE: the same switching times, so the
 * same states (the two runs against each other, the PULSE run against
 * D Vin in test_buck). A controller failing stops the run at its time. */
static int pwm_gate(double t, const double *x, int nswitch, int *gate, void *ctx) {
  (void)x;
  long *calls = ctx;
  (*calls)++;
  assert_int_equal(nswitch, 1);
  long k = lround(t / 5e-6);
  gate[0] = k % 4 == 0;
  return 0;
}

static int failing_gate(double t, const double *x, int nswitch, int *gate, void *ctx) {
  (void)x; (void)nswitch; (void)ctx;
  gate[0] = 1;
  return t > 1e-4;
}

static void test_controller(void **state) {
  (void)state;
  const char *buck = "ideal buck\nV1 in 0 12\nS1 in sw g 0 SMOD\nD1 0 sw\nL1 sw out 100u\nC1 out 0 10u\n"
                     "R1 out 0 5\nVg g 0 PULSE(0 1 0 jump jump 5u 20u)\n.model SMOD SW(VT=0.5)\n";
  cup_netlist *ref = text_ok(buck), *nl = text_ok(buck);
  char err[CUP_ERRMSG_LEN];
  long calls = 0;
  assert_int_equal(cup_netlist_set_controller(nl, 5e-6, pwm_gate, &calls, err), CUP_OK);
  run_rec a, b;
  run(ref, 2e-3, 1e-10, 2001, NULL, &a);
  run(nl, 2e-3, 1e-10, 2001, NULL, &b);
  double worst = 0;
  for (long k = 0; k < a.count * 2; k++) worst = fmax(worst, fabs(a.x[k] - b.x[k]));
  printf("buck, PWM from a controller every 5 us (%ld calls) against PULSE: max |dx| = %.2e\n", calls, worst);
  assert_true(worst <= 1e-9);
  assert_int_equal(calls, 400);                   /* t = 0, 5u, ..., 1995u */
  rec_free(&a);
  rec_free(&b);
  assert_int_equal(cup_netlist_set_controller(nl, 5e-6, failing_gate, NULL, err), CUP_OK);
  cup_switching sw;
  assert_int_equal(cup_netlist_switching(nl, &sw), 1);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.T = 2e-3;
  o.output = CUP_OUTPUT_FINAL;
  cup_integrator *I = NULL;
  assert_int_equal(cup_integrator_create_switched(&I, &sw, cup_netlist_input(nl), &o, err), CUP_OK);
  cup_run_info info;
  assert_int_equal(cup_integrator_run(I, cup_netlist_x0(nl), NULL, NULL, &info), CUP_ERR_CALLBACK);
  assert_contains(info.message, "the controller callback failed");
  printf("failing controller: %s\n", info.message);
  cup_integrator_free(&I);
  assert_int_equal(cup_netlist_set_controller(nl, 0, pwm_gate, NULL, err), CUP_ERR_ARG);
  /* its instants k ts are on the sources' clock: no time origin with it, nor it after one */
  assert_int_equal(cup_netlist_set_time_origin(nl, 1e-6, err), CUP_ERR_UNSUPPORTED);
  assert_contains(err, "controller");
  assert_int_equal(cup_netlist_set_controller(nl, 5e-6, NULL, NULL, err), CUP_OK);
  assert_int_equal(cup_netlist_set_time_origin(nl, 1e-6, err), CUP_OK);
  assert_int_equal(cup_netlist_set_controller(nl, 5e-6, pwm_gate, NULL, err), CUP_ERR_UNSUPPORTED);
  assert_int_equal(cup_netlist_set_time_origin(nl, 0, err), CUP_OK);
  assert_int_equal(cup_netlist_set_controller(nl, 5e-6, pwm_gate, NULL, err), CUP_OK);
  cup_netlist_free(&nl);
  cup_netlist_free(&ref);
}

/* A switch that moves another's control: S2 reads v(c), which is V1 = 1
 * through S1 when S1 is closed and 0 (R1 to ground) when it is open, so
 * that the configurations differ in S2's control row. When S1's gate rises
 * (1 ms) the rule closes S1, then, read in that configuration, S2 too (the
 * settle takes the configurations in turn until the rule holds: one whose
 * controls are another's, those of t alone, is not read again, and these
 * two are not such). S2 closed shorts C1: the jump onto its constraints
 * takes v(C1) = 1 to 0; with S2 open it stays 1. */
static void test_settle_moves_another_control(void **state) {
  (void)state;
  cup_netlist *nl = text_ok("cascade\n"
                            "V1 a 0 1\nVG g 0 PULSE(0 1 1m jump jump 1 2)\nS1 a c g 0 SWA\nR1 c 0 1k\n"
                            "V2 b 0 1\nR2 b x 1k\nC1 x 0 1u\nS2 x 0 c 0 SWA\n"
                            ".model SWA SW(VT=0.5 VH=0)\n.tran 1u 2m\n.end\n");
  cup_switching sw;
  assert_int_equal(cup_netlist_switching(nl, &sw), 1);
  assert_int_equal(cup_lcs_dim(cup_netlist_lcs(nl)), 1);
  char err[CUP_ERRMSG_LEN];
  const double tset[2] = {0.5e-3, 1.5e-3}, want[2] = {1, 0};
  for (int k = 0; k < 2; k++) {
    int topo = 0;                                /* both open: the configuration at t = 0 */
    double x[1] = {1};
    assert_int_equal(sw.settle(sw.ctx, &topo, tset[k], x, NULL, err), CUP_OK);
    sw.jump(sw.ctx, topo, x);
    if (fabs(x[0] - want[k]) > 1e-12) fail_msg("t = %g: v(C1) = %.17g after the jump, want %g", tset[k], x[0], want[k]);
  }
  cup_netlist_free(&nl);
}

static void test_errors(void **state) {
  (void)state;
  assert_contains(text_bad("t\nC1 a 0 1u\nR1 a b 1\nS1 a b c 0 NOPE\nV1 c 0 1\n"),
                  "t.cir:4:12: S1: model 'NOPE' is not defined");
  assert_contains(text_bad("t\nC1 a 0 1u\nR1 a b 1\nS1 a b c c M\nV1 c 0 1\n.model M SW(VT=1)\n"),
                  "t.cir:4:10: S1: no control path: both control nodes are 'c'");
  assert_contains(text_bad("t\nC1 a 0 1u\nR1 a b 1\nS1 a b c 0 M\n.model M SW(VT=1)\n"),
                  "t.cir:4:1: S1: no control path: control node 'c' is not connected to any element");
  assert_contains(text_bad("t\nC1 a 0 1u\nR1 a b 1\nW1 a b VX M\nV1 c 0 1\nR2 c 0 1\n.model M CSW(IT=1)\n"),
                  "t.cir:4:8: W1: no control path: no element named 'VX'");
  assert_contains(text_bad("t\nC1 a 0 1u\nR1 a b 1\nS1 a b c 0 M\nV1 c 0 1\n.model M SW(VT=1 RON=0)\n"),
                  "t.cir:6:22: M: bad value: ron must be > 0 (got 0");
  assert_contains(text_bad("t\nC1 a 0 1u\nR1 a b 1\nS1 a b c 0 M\nV1 c 0 1\n.model M SW(VT=1 VON=2)\n"),
                  "t.cir:6:18: M: 'VON' is not a parameter of a SW model");
  assert_contains(text_bad("t\nC1 a 0 1u\nR1 a b 1\nS1 a b c 0 M\nV1 c 0 1\n.model M CSW(IT=1)\n"),
                  "t.cir:4:12: S1: model 'M' is not an SW model");
  assert_contains(text_bad("t\nC1 a 0 1u\nV1 b 0 1\nS1 a b c 0 M\nV2 c 0 1\n.model M SW(VT=0.5)\n"),
                  "t.cir:4:1: S1: closed, the switch puts capacitors in a loop with a source");
}

/* The full bridge's gates, PULSE(0 1 d jump jump 49u 100u) for d = 1u,
 * 51u, 76u, 26u (examples/circuits/fullbridge.cir), walked as a switched
 * run asks: from each switching time the next (sw.next), the rule there
 * (sw.settle). Every switching time is the first gate corner after the
 * last in closed form (SPICE's PULSE: d + P j and d + P j + (0 + width),
 * summed in that order), 798 in 100 periods, and the configuration after
 * each is one per pattern of gates high in the piece that follows (the
 * closed form at its middle). From a time origin t0 (the sources from t0
 * on: memos afresh) the switching times are the corners of the shifted
 * input in turn (cup_input_next_break), 200 of them (2.5 ms). */
static const double fb_delay[4] = {1 * 1e-6, 51 * 1e-6, 76 * 1e-6, 26 * 1e-6}, fb_width = 49 * 1e-6,
                    fb_period = 100 * 1e-6;   /* (as the reader scales "76u") */

static double fb_corner_after(double t) {
  double best = INFINITY;
  for (int g = 0; g < 4; g++)
    for (int j = 0; j < 120; j++) {
      double base = fb_delay[g] + fb_period * j, c[2] = {base, base + (0 + fb_width)};
      for (int k = 0; k < 2; k++)
        if (c[k] > t && c[k] < best) best = c[k];
    }
  return best;
}

static void test_gate_schedule(void **state) {
  (void)state;
  cup_netlist *nl = text_ok("full bridge\nVDC dc 0 100\n"
                            "VG1 g1 0 PULSE(0 1 1u jump jump 49u 100u)\nVG2 g2 0 PULSE(0 1 51u jump jump 49u 100u)\n"
                            "VG3 g3 0 PULSE(0 1 76u jump jump 49u 100u)\nVG4 g4 0 PULSE(0 1 26u jump jump 49u 100u)\n"
                            "S1 dc a g1 0 SWI\nS2 a 0 g2 0 SWI\nS3 dc b g3 0 SWI\nS4 b 0 g4 0 SWI\n"
                            "D1 a dc\nD2 0 a\nD3 b dc\nD4 0 b\nL1 a o 1m\nC1 o b 2.2u\nRL o b 20\n"
                            ".model SWI SW(VT=0.5 VH=0)\n.tran 1u 10m\n.end\n");
  cup_switching sw;
  assert_int_equal(cup_netlist_switching(nl, &sw), 1);
  char err[CUP_ERRMSG_LEN];
  const double T = 100 * fb_period;
  double x[2] = {0, 0}, t = 0;
  int topo = 0, of_pattern[16], count = 0;
  for (int k = 0; k < 16; k++) of_pattern[k] = -1;
  assert_int_equal(sw.settle(sw.ctx, &topo, 0, x, NULL, err), CUP_OK);
  while (t < T) {
    double tb, want = fb_corner_after(t);
    assert_int_equal(sw.next(sw.ctx, topo, t, T, &tb), CUP_OK);
    if (tb != (want < T ? want : T)) fail_msg("switching %d after %.17g: at %.17g, the closed form %.17g", count, t, tb, want);
    if (tb == T) break;
    assert_int_equal(sw.settle(sw.ctx, &topo, tb, x, NULL, err), CUP_OK);
    double mid = (tb + fb_corner_after(tb)) / 2;
    int pattern = 0;
    for (int g = 0; g < 4; g++) {
      double s = mid - fb_delay[g];
      if (s >= 0 && s - floor(s / fb_period) * fb_period < fb_width) pattern |= 1 << g;
    }
    if (of_pattern[pattern] < 0) {
      for (int k = 0; k < 16; k++)
        if (of_pattern[k] == topo) fail_msg("at %.17g: configuration %d for gates %x and %x", tb, topo, k, pattern);
      of_pattern[pattern] = topo;
    }
    if (of_pattern[pattern] != topo)
      fail_msg("at %.17g: gates %x in configuration %d, before in %d", tb, pattern, topo, of_pattern[pattern]);
    t = tb;
    count++;
  }
  assert_int_equal(count, 798);                   /* (g2's and g3's last falls at T and past it) */
  assert_int_equal(cup_netlist_configurations_formed(nl), 9);   /* all open at t = 0, 8 patterns after */
  /* from t0: the shifted sources' own corners, walked on from 1 ms, where
   * the memos last held the old ones */
  topo = 0;
  assert_int_equal(sw.settle(sw.ctx, &topo, 0, x, NULL, err), CUP_OK);
  for (t = 0; t < 1e-3;) {
    double tb;
    assert_int_equal(sw.next(sw.ctx, topo, t, T, &tb), CUP_OK);
    assert_int_equal(sw.settle(sw.ctx, &topo, tb, x, NULL, err), CUP_OK);
    t = tb;
  }
  const double t0 = 1234.5e-6;
  assert_int_equal(cup_netlist_set_time_origin(nl, t0, err), CUP_OK);
  const cup_input *v = cup_netlist_input(nl);
  assert_int_equal(sw.settle(sw.ctx, &topo, t, x, NULL, err), CUP_OK);   /* on from where the walk stopped */
  for (int k = 0; k < 200; k++) {
    double tb, want = cup_input_next_break(v, t);
    assert_int_equal(sw.next(sw.ctx, topo, t, T, &tb), CUP_OK);
    if (tb != want) fail_msg("from t0, switching %d after %.17g: at %.17g, the sources' corner %.17g", k, t, tb, want);
    double c = fb_corner_after(t0 + tb - 1e-12);   /* (t0 + tb rounds apart from the corner it stands for) */
    if (fabs(t0 + tb - c) > 1e-15) fail_msg("from t0: %.17g is no gate's corner (%.17g)", t0 + tb, c);
    assert_int_equal(sw.settle(sw.ctx, &topo, tb, x, NULL, err), CUP_OK);
    t = tb;
  }
  cup_netlist_free(&nl);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_two_capacitors), cmocka_unit_test(test_two_capacitors_every_step),
    cmocka_unit_test(test_two_capacitors_every_step_theta),
    cmocka_unit_test(test_inductor_cut),
    cmocka_unit_test(test_constraint_reads_input),
    cmocka_unit_test(test_rc_through_switch), cmocka_unit_test(test_buck), cmocka_unit_test(test_relaxation),
    cmocka_unit_test(test_gates_across_configurations),
    cmocka_unit_test(test_fixed_step), cmocka_unit_test(test_probe_all),
    cmocka_unit_test(test_circuit_gated_step_end), cmocka_unit_test(test_controller), cmocka_unit_test(test_errors),
    cmocka_unit_test(test_settle_moves_another_control), cmocka_unit_test(test_gate_schedule),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

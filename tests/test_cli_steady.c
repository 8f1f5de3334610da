/* catchup-run --steady-state end to end (docs/steady-state.md): the file
 * holds one period from the steady state (/t over [0, T], /x's first row
 * the solved x0 and its last row x0 again), the /steady_state group with
 * units and long names, the measurements against the samples of the file
 * itself (the RMS of v(out) against the resistor's power v^2 / R; the
 * balance of the absorbed powers, which the capacitor's zero average closes
 * only at the steady state), the summary lines; the six-pulse rectifier's
 * first row (its diodes' right limit at 0+); no steady state (the LC at
 * resonance): the transient instead with a warning, or an error with
 * fallback: false; bad input: a period that is no whole number of the
 * sources', a usage error. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <math.h>
#include <cmocka.h>
#include <hdf5.h>
#include "catchup.h"

#define CLI_TMPDIR_TEMPLATE "/tmp/cup_steady_XXXXXX"
#include "cliutil.h"
#include "testutil.h"

#define BRIDGE CUP_EXAMPLES_DIR "/circuits/bridge.cir"

static void expect_exit(const result *r, int code) {
  if (!r->exited || r->code != code) fail_msg("exit %d (signal %d), expected %d:\n%s", r->code, r->sig, code, r->err);
}

static void expect_in(const char *text, const char *what) {
  if (!strstr(text, what)) fail_msg("lacks '%s':\n%s", what, text);
}

static char *attr_at(hid_t f, const char *obj, const char *name) {
  hid_t a = H5Aopen_by_name(f, obj, name, H5P_DEFAULT, H5P_DEFAULT);
  if (a < 0) fail_msg("attribute %s of %s missing", name, obj);
  hid_t type = H5Aget_type(a);
  char *s = NULL;
  assert_true(H5Aread(a, type, &s) >= 0);
  char *copy = strdup(s);
  H5free_memory(s);
  H5Tclose(type);
  H5Aclose(a);
  return copy;
}

static void bridge_period(void **state) {
  (void)state;
  const char *out = tmp_path("bridge.h5");
  result r = run_cli((const char *const[]){BRIDGE, "-o", out, "--steady-state", "--set",
                                           "steady_state.efficiency=[RL, V1]", "--set", "steady_state.power=[Rs]",
                                           NULL}, 0, 0);
  expect_exit(&r, 0);
  expect_in(r.err, "steady state: period 0.02 s");
  expect_in(r.err, "efficiency");
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  double *t, *x, *x0, *res, *vout, *per, *pw, *eff, *rms, *mre;
  hsize_t N = read_rows(f, "t", 1, 1, &t);
  assert_int_equal(N, 2001);
  assert_true(read_rows(f, "x", 2, 1, &x) == N);
  assert_true(read_rows(f, "steady_state/x0", 1, 1, &x0) == 1);
  hsize_t nres = read_rows(f, "steady_state/residuals", 1, 1, &res);
  read_rows(f, "signals/v(out)", 1, 1, &vout);
  read_rows(f, "steady_state/period", 1, 1, &per);
  assert_true(read_rows(f, "steady_state/power/average", 1, 1, &pw) == 3);   /* Rs, RL, V1 */
  read_rows(f, "steady_state/efficiency", 1, 1, &eff);
  read_rows(f, "steady_state/measure/rms", 1, 1, &rms);
  assert_true(read_rows(f, "steady_state/multipliers_re", 1, 1, &mre) == 1);
  assert_close(per[0], 0.02, 1e-17);
  assert_close(t[0], 0, 0);
  assert_close(t[N - 1], 0.02, 1e-17);
  assert_true(x[0] == x0[0]);                    /* the period starts at the solved state */
  assert_close(x[N - 1], x0[0], 1e-9 * fabs(x0[0]));   /* and closes on it */
  assert_true(nres >= 2 && res[nres - 1] <= 1e-10 * (fabs(x0[0]) + 1e-9));
  assert_true(fabs(mre[0]) < 1);
  /* the resistor's power is v(out)^2 / RL: the RMS measured (first of the run's signals: v(out)) */
  assert_close(pw[1], rms[0] * rms[0] / 1000, 1e-12 * pw[1]);
  /* absorbed powers balance (the capacitor's average is 0 over a period): to the O(h) of the
   * diodes' current jumps at 2001 samples */
  print_message("  P(Rs) %.9g, P(RL) %.9g, P(V1) %.9g W: sum %.3g; efficiency %.9g\n", pw[0], pw[1], pw[2],
                pw[0] + pw[1] + pw[2], eff[0]);
  assert_close(pw[0] + pw[1] + pw[2], 0, 1e-4 * fabs(pw[2]));
  assert_close(eff[0], pw[1] / -pw[2], 1e-15);
  assert_true(eff[0] > 0.98 && eff[0] < 1);
  char *u = attr_at(f, "steady_state/residuals", "long_name");
  expect_in(u, "Newton residual");
  free(u);
  u = attr_at(f, "steady_state/power/average", "units");
  assert_string_equal(u, "W");
  free(u);
  assert_int_equal(attr_i64(f, "steady_state_status"), CUP_OK);
  assert_close(attr_f64(f, "T"), 0.02, 1e-17);    /* the run is the period */
  H5Fclose(f);
  free(t); free(x); free(x0); free(res); free(vout); free(per); free(pw); free(eff); free(rms); free(mre);
}

static const char *lc = "LC at resonance\nV1 in 0 SIN(0 1 5032.921210448704)\nL1 in a 1m\nC1 a 0 1u\n"
                        ".tran 1u 1m\n.end\n";

static void no_steady_state(void **state) {
  (void)state;
  const char *cir = tmp_text("lc.cir", lc);
  const char *out = tmp_path("lc.h5");
  result r = run_cli((const char *const[]){cir, "-o", out, "--steady-state", NULL}, 0, 0);
  expect_exit(&r, 0);
  expect_in(r.err, "warning");
  expect_in(r.err, "a Floquet multiplier is at 1");
  expect_in(r.err, "the transient instead");
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  double *t;
  hsize_t N = read_rows(f, "t", 1, 1, &t);
  assert_close(t[N - 1], 1e-3, 1e-18);           /* the transient's .tran TSTOP */
  assert_int_equal(attr_i64(f, "steady_state_status"), CUP_ERR_NO_STEADY_STATE);
  assert_int_equal(attr_i64(f, "steady_state_solved"), 0);
  H5Fclose(f);
  free(t);
  r = run_cli((const char *const[]){cir, "-o", out, "--steady-state", "--set", "steady_state.fallback=false", NULL},
              0, 0);
  expect_exit(&r, 1);
  assert_int_equal(r.lines, 1);
  expect_in(r.err, "CUP_ERR_NO_STEADY_STATE");
}

/* .options steadyperiod=40m asks for it from the netlist itself (two periods of 50 Hz). */
static void netlist_option(void **state) {
  (void)state;
  const char *cir = tmp_text("hw.cir",
      "Half-wave\nV1 in 0 SIN(0 10 50)\nRs in a 1\nD1 a out\nC1 out 0 100u\nRL out 0 1k\n"
      ".options reltol=1e-4 steadyperiod=40m\n.tran 20u 60m\n.end\n");
  const char *out = tmp_path("hw.h5");
  result r = run_cli((const char *const[]){cir, "-o", out, NULL}, 0, 0);
  expect_exit(&r, 0);
  expect_in(r.err, "steady state: period 0.04 s");
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  double *t;
  hsize_t N = read_rows(f, "t", 1, 1, &t);
  assert_close(t[N - 1], 0.04, 1e-17);
  H5Fclose(f);
  free(t);
  r = run_cli((const char *const[]){cir, "-o", out, "--set", "steady_state=false", NULL}, 0, 0);
  expect_exit(&r, 0);
  assert_null(strstr(r.err, "steady state"));    /* the scene's key overrides the netlist's */
}

/* A switched netlist's signals follow its configuration sample by sample:
 * on the ideal CCM buck's steady-state period (12 V, D = 0.5) the switch
 * and the diode share the inductor's current (i(S1) + i(D1) = i(L1) at every
 * sample, each zero while the other conducts) and v(sw) is 12 V or 0, its
 * mean D Vin = 6 V to the sampling's O(1/N) at the two edges. */
static void switched_signals(void **state) {
  (void)state;
  const char *out = tmp_path("buck.h5");
  result r = run_cli((const char *const[]){CUP_EXAMPLES_DIR "/circuits/buck-ccm.cir", "-o", out, "--steady-state",
                                           "--probe", "i(S1)", "--probe", "i(D1)", "--probe", "i(L1)", "--probe",
                                           "v(sw)", NULL}, 0, 0);
  expect_exit(&r, 0);
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  double *is, *id, *il, *vsw;
  hsize_t N = read_rows(f, "signals/i(S1)", 1, 1, &is);
  assert_true(N > 100);
  assert_true(read_rows(f, "signals/i(D1)", 1, 1, &id) == N);
  assert_true(read_rows(f, "signals/i(L1)", 1, 1, &il) == N);
  assert_true(read_rows(f, "signals/v(sw)", 1, 1, &vsw) == N);
  double mean = 0;
  long on = 0;
  for (hsize_t j = 0; j < N; j++) {
    assert_close(is[j] + id[j], il[j], 1e-12 * fabs(il[j]));
    assert_true(is[j] == 0 || id[j] == 0);
    assert_true(vsw[j] == 12 || vsw[j] == 0);
    on += vsw[j] == 12;
    mean += (j == 0 || j == N - 1 ? 0.5 : 1.0) * vsw[j] / (double)(N - 1);
  }
  assert_true(on > (long)N / 3 && on < 2 * (long)N / 3);
  assert_close(mean, 6, 12.0 * 2 / (double)(N - 1));
  H5Fclose(f);
  free(is); free(id); free(il); free(vsw);
}

/* The six-pulse rectifier's period from its steady state: at t = 0 (the
 * period's first row) va = 0 is the middle phase, vc = 100 sin 120 deg the
 * highest and vb = -vc the lowest, so D5 (c to p) and D6 (n to b) carry
 * the inductor's current into the filter, D1 and D4 (phase a) carry
 * nothing, v(p) = vc and v(n) = vb: the right limit at 0+ (netlist.md,
 * "Signals"), continuous with the next rows. Before, the first row took
 * zeta = 0 there: i(D1) = i(D4) = i(L1) = 16.7 A, v(p) = v(n) = 0. */
static void sixpulse_first_row(void **state) {
  (void)state;
  const char *out = tmp_path("sixpulse.h5");
  const char *probes[] = {"i(D1)", "i(D4)", "i(D5)", "i(D6)", "i(L1)", "v(p)", "v(n)"};
  result r = run_cli((const char *const[]){CUP_EXAMPLES_DIR "/circuits/sixpulse.cir", "-o", out, "--steady-state",
                                           "--probe", probes[0], "--probe", probes[1], "--probe", probes[2], "--probe",
                                           probes[3], "--probe", probes[4], "--probe", probes[5], "--probe",
                                           probes[6], NULL}, 0, 0);
  expect_exit(&r, 0);
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  double *s[7], vc = 100 * sin(2 * M_PI / 3);
  char name[32];
  for (int k = 0; k < 7; k++) {
    snprintf(name, sizeof name, "signals/%s", probes[k]);
    assert_true(read_rows(f, name, 1, 1, &s[k]) > 100);
  }
  double il = s[4][0];
  print_message("t = 0: i(D1) %g, i(D4) %g, i(D5) %.17g, i(D6) %.17g, i(L1) %.17g, v(p) %.17g, v(n) %.17g\n",
                s[0][0], s[1][0], s[2][0], s[3][0], il, s[5][0], s[6][0]);
  assert_true(il > 1);
  assert_true(s[0][0] == 0 && s[1][0] == 0);
  assert_close(s[2][0], il, 1e-12 * il);
  assert_close(s[3][0], il, 1e-12 * il);
  assert_close(s[5][0], vc, 1e-12 * vc);
  assert_close(s[6][0], -vc, 1e-12 * vc);
  H5Fclose(f);
  for (int k = 0; k < 7; k++) free(s[k]);
}

/* The same period with every signal ('--probe all'): each must follow the
 * configuration too. The capacitor's mean
 * current is 0 in a steady state, v(out)'s mean is D Vin = 6 V and its
 * ripple ΔI Ts / (8 C) = 0.3 A * 10 us / 80 uF = 37.5 mV (the inductor's
 * ripple current integrated over half a period, the load's share of it
 * 0.2 % here). Before the signals of 'all' reached every configuration,
 * the off-time rows repeated the last on-time sample: v(out)'s mean read
 * 5.994 V, its ripple 19.4 mV and i(C1)'s mean 0.076 A. */
static void switched_default_signals(void **state) {
  (void)state;
  const char *out = tmp_path("buck-all.h5");
  result r = run_cli((const char *const[]){CUP_EXAMPLES_DIR "/circuits/buck-ccm.cir", "-o", out, "--steady-state",
                                           "--probe", "all", NULL}, 0, 0);
  expect_exit(&r, 0);
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  double *vo, *ic;
  hsize_t N = read_rows(f, "signals/v(out)", 1, 1, &vo);
  assert_true(N > 100);
  assert_true(read_rows(f, "signals/i(C1)", 1, 1, &ic) == N);
  double mv = 0, mi = 0, lo = vo[0], hi = vo[0];
  for (hsize_t j = 0; j < N; j++) {
    double w = (j == 0 || j == N - 1 ? 0.5 : 1.0) / (double)(N - 1);
    mv += w * vo[j];
    mi += w * ic[j];
    lo = fmin(lo, vo[j]);
    hi = fmax(hi, vo[j]);
  }
  assert_close(mv, 6, 1e-4);
  assert_close(mi, 0, 0.3 * 2 / (double)(N - 1));
  assert_close(hi - lo, 0.0375, 0.0375 * 0.01);
  H5Fclose(f);
  free(vo); free(ic);
}

/* A switched netlist's own .probe line chooses its signals, as any
 * netlist's does (docs/run-output.md): buck-ccm.cir's `.probe v(out) i(L1)
 * v(sw)`, those three and no other. The switched netlist is its first
 * configuration's, whose derived circuit had no probes: every signal was
 * recorded (11 here), whatever the line said. */
static void switched_netlist_probes(void **state) {
  (void)state;
  const char *out = tmp_path("buck-probe.h5");
  result r = run_cli((const char *const[]){CUP_EXAMPLES_DIR "/circuits/buck-ccm.cir", "-o", out, NULL}, 0, 0);
  expect_exit(&r, 0);
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  hid_t g = H5Gopen2(f, "signals", H5P_DEFAULT);
  assert_true(g >= 0);
  H5G_info_t info;
  assert_true(H5Gget_info(g, &info) >= 0);
  print_message("  %llu signals\n", (unsigned long long)info.nlinks);
  assert_int_equal(info.nlinks, 3);
  const char *want[3] = {"v(out)", "i(L1)", "v(sw)"};
  for (int k = 0; k < 3; k++) assert_true(H5Lexists(g, want[k], H5P_DEFAULT) > 0);
  H5Gclose(g);
  H5Fclose(f);
}

/* The full bridge: its gate VG3 (delay 76 us, width 49 us, period 100 us)
 * repeats only from t0 = 25 us (the base build refused it, CUP_ERR_ARG,
 * and ran the transient). The period written is [t0, t0 + T] of the
 * sources as written: /t from t0, /steady_state/t0, the summary says so,
 * and each gate's signal at each /t is its PULSE as written there. */
static void fullbridge_phase(void **state) {
  (void)state;
  const char *out = tmp_path("fullbridge.h5");
  result r = run_cli((const char *const[]){CUP_EXAMPLES_DIR "/circuits/fullbridge.cir", "-o", out, "--steady-state",
                                           "--probe", "all", NULL}, 0, 0);
  expect_exit(&r, 0);
  expect_in(r.err, "steady state: period 0.0001 s from t0 = 2.5e-05 s");
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  double *t, *x, *x0, *t0, *g[4];
  hsize_t N = read_rows(f, "t", 1, 1, &t);
  assert_true(read_rows(f, "x", 2, 2, &x) == N);
  assert_true(read_rows(f, "steady_state/x0", 1, 1, &x0) == 2);
  assert_true(read_rows(f, "steady_state/t0", 1, 1, &t0) == 1);
  const char *gate[4] = {"signals/v(g1)", "signals/v(g2)", "signals/v(g3)", "signals/v(g4)"};
  const double delay[4] = {1e-6, 51e-6, 76e-6, 26e-6};
  for (int k = 0; k < 4; k++) assert_true(read_rows(f, gate[k], 1, 1, &g[k]) == N);
  assert_close(t0[0], 25e-6, 1e-18);
  assert_close(t[0], t0[0], 0);
  assert_close(t[N - 1], t0[0] + 100e-6, 1e-18);
  assert_true(x[0] == x0[0] && x[1] == x0[1]);
  assert_close(x[2 * (N - 1)], x0[0], 1e-9);
  long checked = 0;
  for (hsize_t j = 0; j < N; j++)
    for (int k = 0; k < 4; k++) {
      double s = fmod(t[j] - delay[k] + 200e-6, 100e-6);   /* the time into its period as written */
      if (fabs(s) < 1e-12 || fabs(s - 49e-6) < 1e-12 || fabs(s - 100e-6) < 1e-12) continue;   /* an edge */
      assert_close(g[k][j], s < 49e-6 ? 1 : 0, 0);
      checked++;
    }
  print_message("  t0 %.17g, /t [%.9g, %.9g], x0 (%.9g, %.9g), %ld gate samples as written\n", t0[0], t[0], t[N - 1],
                x0[0], x0[1], checked);
  free(t); free(x); free(x0); free(t0);
  for (int k = 0; k < 4; k++) free(g[k]);
  H5Fclose(f);
}

static void bad_input(void **state) {
  (void)state;
  const char *out = tmp_path("bad.h5");
  result r = run_cli((const char *const[]){BRIDGE, "-o", out, "--period", "0.03", "--set",
                                           "steady_state.fallback=false", NULL}, 0, 0);
  expect_exit(&r, 1);
  expect_in(r.err, "is not a whole number of the sources' common period");
  r = run_cli((const char *const[]){BRIDGE, "-o", out, "--period", "-1", NULL}, 0, 0);
  expect_exit(&r, 2);
  expect_in(r.err, "--period '-1': not a positive number");
  r = run_cli((const char *const[]){BRIDGE, "-o", out, "--steady-state", "--set", "steady_state.power=[R9]", NULL}, 0,
              0);
  expect_exit(&r, 1);
  expect_in(r.err, "no element named 'R9'");
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(bridge_period),
    cmocka_unit_test(no_steady_state),
    cmocka_unit_test(netlist_option),
    cmocka_unit_test(switched_signals),
    cmocka_unit_test(switched_default_signals),
    cmocka_unit_test(switched_netlist_probes),
    cmocka_unit_test(fullbridge_phase),
    cmocka_unit_test(sixpulse_first_row),
    cmocka_unit_test(bad_input),
  };
  return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}

/* The measurements of one period of signals that jump (issue 32,
 * deliverable 2; docs/steady-state.md, "Measurements of one period"):
 * catchup-run --steady-state on the ideal buck, its figures read back from
 * /steady_state, against what does not come from catchup:
 *   - closed forms: the CCM buck's average v(sw) = D Vin (the switch node is
 *     Vin while S1 conducts, 0 while D1 does) and the efficiency 1 of a
 *     lossless converter; the DCM buck's average v(sw) = the average v(out)
 *     (the inductor's volt-seconds balance; v(sw) = v(out) once D1 blocks);
 *     the small-ripple RMS sqrt(D (I^2 + dI^2 / 12)) of i(S1), within what
 *     the output's ripple moves it;
 *   - the exact flow from catchup's x0 (tests/pwl_ref.h: matrix
 *     exponentials, the diode's turn-off bisected to ulps), each signal
 *     written from its topology by hand and integrated by 8-point
 *     Gauss-Legendre on 64 pieces of each smooth segment: the average, RMS,
 *     maximum (both sides of each jump) and fundamental of i(S1), i(D1),
 *     v(sw), and the continuous v(out) and i(L1).
 * At D = 0.5 the switch's edge falls on a sample (the 1000th of 2001), at
 * D = 0.3137 between two; the DCM buck's diode blocks inside the period (an
 * event of the adaptive scheme). More jump times than 4 a sample (200
 * switchings at 21 samples): the samples' own trapezoid rule, with a
 * warning. Before the jumps were measured as jumps,
 * the periodic trapezoid rule and the DFT of the samples were O(h) off at
 * each jump (efficiency 0.999 of the lossless buck). */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <math.h>
#include <cmocka.h>
#include <hdf5.h>
#include "catchup.h"

#define CLI_TMPDIR_TEMPLATE "/tmp/cup_pssjump_XXXXXX"
#include "cliutil.h"
#include "testutil.h"
#include "pwl_circuits.h"

#define CIR CUP_EXAMPLES_DIR "/circuits/"

enum { VSW, IS1, ID1, VOUT, IL1, NSIG };
static const char *const names[NSIG] = {"v(sw)", "i(S1)", "i(D1)", "v(out)", "i(L1)"};

typedef struct {
  double avg, rms, max, a1;   /* a1: the fundamental's amplitude */
} figs;

/* The buck's signal k in mode m (0 S1 on, 1 D1 on, 2 both off) at y = (i, v, 1). */
static double sig_of(int k, int m, const double *y, double Vin) {
  switch (k) {
  case VSW: return m == 0 ? Vin : m == 1 ? 0 : y[1];
  case IS1: return m == 0 ? y[0] : 0;
  case ID1: return m == 1 ? y[0] : 0;
  case VOUT: return y[1];
  default: return y[0];
  }
}

/* The exact figures of signal k over [0, Ts] of tr: Gauss-Legendre on each
 * segment's pieces (the flow is smooth inside a segment), the extremes
 * from both ends of each segment and its nodes. */
static figs exact(const pr_traj *tr, int k, double Vin, double Ts) {
  static const double gx[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363},
                      gw[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
  long double s1 = 0, s2 = 0, c = 0, s = 0;
  double hi = -INFINITY;
  for (int q = 0; q < tr->nseg; q++) {
    const pr_seg *g = &tr->seg[q];
    double a = fmax(g->t0, 0), b = fmin(g->t1, Ts);
    if (!(b > a)) continue;
    int P = 64;
    for (int p = 0; p < P; p++) {
      double lo = a + (b - a) * p / P, half = (b - a) / P / 2, mid = lo + half;
      for (int i = 0; i < 8; i++) {
        double t = mid + (i < 4 ? -1 : 1) * half * gx[i % 4], w = half * gw[i % 4], y[PR_Y];
        pr_flow(tr->c->ny, tr->c->mode[g->mode].M, g->y0, t - g->t0, y);
        double v = sig_of(k, g->mode, y, Vin);
        s1 += w * v;
        s2 += w * v * v;
        c += w * v * cos(2 * M_PI * t / Ts);
        s += w * v * sin(2 * M_PI * t / Ts);
      }
      for (int e = 0; e < 2; e++) {              /* the piece's ends, each on its segment's side */
        double y[PR_Y];
        pr_flow(tr->c->ny, tr->c->mode[g->mode].M, g->y0, (e ? lo + 2 * half : lo) - g->t0, y);
        hi = fmax(hi, sig_of(k, g->mode, y, Vin));
      }
    }
  }
  return (figs){(double)(s1 / Ts), sqrt((double)(s2 / Ts)), hi, 2 * (double)sqrtl(c * c + s * s) / Ts};
}

typedef struct {
  double x0[2], avg[NSIG], rms[NSIG], max[NSIG], amp[NSIG][4], pw[2], eff;
} measured;

/* catchup-run --steady-state on cir: the figures it writes. */
static void run(const char *cir, measured *m) {
  const char *out = tmp_path("buck.h5");
  result r = run_cli((const char *const[]){cir, "-o", out, "--steady-state", "--set",
                                           "steady_state.measure=[v(sw), i(S1), i(D1), v(out), i(L1)]", "--set",
                                           "steady_state.efficiency=[RL, V1]", "--set", "steady_state.harmonics=3",
                                           NULL}, 0, 0);
  if (!r.exited || r.code != 0) fail_msg("%s: exit %d:\n%s", cir, r.code, r.err);
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  double *x0, *avg, *rms, *max, *amp, *pw, *eff;
  assert_true(read_rows(f, "steady_state/x0", 1, 1, &x0) == 2);
  assert_true(read_rows(f, "steady_state/measure/average", 1, 1, &avg) == NSIG);
  read_rows(f, "steady_state/measure/rms", 1, 1, &rms);
  read_rows(f, "steady_state/measure/max", 1, 1, &max);
  assert_true(read_rows(f, "steady_state/measure/amplitude", 2, 4, &amp) == NSIG);
  assert_true(read_rows(f, "steady_state/power/average", 1, 1, &pw) == 2);
  read_rows(f, "steady_state/efficiency", 1, 1, &eff);
  H5Fclose(f);
  memcpy(m->x0, x0, sizeof m->x0);
  for (int k = 0; k < NSIG; k++) {
    m->avg[k] = avg[k], m->rms[k] = rms[k], m->max[k] = max[k];
    for (int h = 0; h < 4; h++) m->amp[k][h] = amp[4 * k + h];
  }
  m->pw[0] = pw[0], m->pw[1] = pw[1], m->eff = eff[0];
  free(x0); free(avg); free(rms); free(max); free(amp); free(pw); free(eff);
}

/* The exact flow over the period from catchup's x0. */
static void flow(const pr_circuit *c, const measured *m, double Ts, pr_traj *tr) {
  double y[PR_Y] = {m->x0[0], m->x0[1], 1};
  assert_int_equal(pr_solve(c, y, Ts, tr), 0);
}

/* Each signal's figures against the exact flow's: within tol of the
 * signal's scale (its largest magnitude), and the fundamental too. */
static void against_exact(const char *what, const pr_traj *tr, const measured *m, double Vin, double Ts, double tol) {
  for (int k = 0; k < NSIG; k++) {
    figs e = exact(tr, k, Vin, Ts);
    /* a continuous signal is measured as before: the periodic trapezoid rule and
     * the DFT, O(h^2) at a kink (i(L1) at the switching), and its extremes are
     * its samples': O(h) below a kink between two (i(L1)'s peak at D = 0.3137) */
    int cont = k == VOUT || k == IL1;
    double tavg = cont ? fmax(tol, 1e-6) : tol, tmax = cont ? 1e-3 : tol;
    double scale = fabs(e.max) > 0 ? fabs(e.max) : 1;
    print_message("%-10s %-6s avg %.12g (exact %.12g: %.2g)  rms %.12g (%.2g)  max %.12g (%.2g)  A1 %.10g (%.2g)\n",
                  what, names[k], m->avg[k], e.avg, (m->avg[k] - e.avg) / scale, m->rms[k], (m->rms[k] - e.rms) / scale,
                  m->max[k], (m->max[k] - e.max) / scale, m->amp[k][1], (m->amp[k][1] - e.a1) / scale);
    assert_true(fabs(m->avg[k] - e.avg) <= tavg * scale);
    assert_true(fabs(m->rms[k] - e.rms) <= tavg * scale);
    assert_true(fabs(m->max[k] - e.max) <= tmax * scale);
    assert_true(fabs(m->amp[k][1] - e.a1) <= tavg * scale);
  }
}

/* The CCM buck of examples/circuits at duty D (its gate's width D Ts). */
static void ccm(double D, const char *cir) {
  const double Vin = 12, L = 100e-6, C = 10e-6, R = 5, Ts = 10e-6;
  measured m;
  run(cir, &m);
  pr_circuit c;
  pc_buck(&c, Vin, L, C, R, D, Ts);
  pr_traj tr;
  flow(&c, &m, Ts, &tr);
  char what[32];
  snprintf(what, sizeof what, "ccm D=%g", D);
  /* closed forms: D Vin; a lossless converter's efficiency 1 */
  print_message("%-10s avg v(sw) %.15g (D Vin %.15g); P(RL) %.12g, P(V1) %.12g W, efficiency 1 %+.3g\n", what,
                m.avg[VSW], D * Vin, m.pw[0], m.pw[1], m.eff - 1);
  assert_true(fabs(m.avg[VSW] - D * Vin) <= 1e-9 * Vin);
  assert_true(fabs(m.eff - 1) <= 1e-9);
  /* the small-ripple RMS of the switch's current: I the average inductor
   * current (v(out) / R), dI its ripple (Vin - Vout) D Ts / L; the output's
   * own ripple (0.6 % of it) moves the ramp's slope by as much */
  double I = m.avg[VOUT] / R, dI = (Vin - m.avg[VOUT]) * D * Ts / L, rms = sqrt(D * (I * I + dI * dI / 12));
  print_message("%-10s rms i(S1) %.12g against sqrt(D (I^2 + dI^2 / 12)) = %.12g (%.2g)\n", what, m.rms[IS1], rms,
                m.rms[IS1] / rms - 1);
  assert_true(fabs(m.rms[IS1] / rms - 1) <= 1e-4);
  against_exact(what, &tr, &m, Vin, Ts, 2e-8);
  /* the switch node's fundamental: a rectangle of height Vin and width D Ts */
  double a1 = 2 * Vin * sin(M_PI * D) / M_PI;
  print_message("%-10s v(sw)'s fundamental %.12g (2 Vin sin(pi D) / pi = %.12g)\n", what, m.amp[VSW][1], a1);
  assert_true(fabs(m.amp[VSW][1] - a1) <= 1e-9 * Vin);
  pr_free(&tr);
}

static void ccm_half(void **state) {
  (void)state;
  ccm(0.5, CIR "buck-ccm.cir");
}

/* D = 0.3137: the edge at 627.4 samples, between two */
static void ccm_between(void **state) {
  (void)state;
  const char *cir = tmp_text("buck-3137.cir",
      "Buck, D = 0.3137\nV1 in 0 12\nVG g 0 PULSE(0 1 0 jump jump 3.137u 10u)\nS1 in sw g 0 SWI\nD1 0 sw\n"
      "L1 sw out 100u\nC1 out 0 10u\nRL out 0 5\n.model SWI SW(VT=0.5 VH=0)\n.tran 100n 1m\n"
      ".probe v(out) i(L1) v(sw)\n.end\n");
  ccm(0.3137, cir);
}

/* The DCM buck: the diode blocks inside the period, v(sw) jumps from 0 to v(out) there. */
static void dcm(void **state) {
  (void)state;
  const double Vin = 12, L = 10e-6, C = 10e-6, R = 20, D = 0.3, Ts = 10e-6;
  measured m;
  run(CIR "buck-dcm.cir", &m);
  pr_circuit c;
  pc_buck(&c, Vin, L, C, R, D, Ts);
  pr_traj tr;
  flow(&c, &m, Ts, &tr);
  assert_true(tr.events >= 1);                   /* the diode's turn-off */
  print_message("dcm        avg v(sw) %.15g, avg v(out) %.15g (%.2g); efficiency 1 %+.3g\n", m.avg[VSW], m.avg[VOUT],
                m.avg[VSW] - m.avg[VOUT], m.eff - 1);
  assert_true(fabs(m.avg[VSW] - m.avg[VOUT]) <= 1e-8 * Vin);
  assert_true(fabs(m.eff - 1) <= 1e-7);
  /* i(D1)'s side after S1 opens, extrapolated from the samples after: O(h^2)
   * of the inductor current's curvature (the output's ripple over 10 uH) */
  against_exact("dcm", &tr, &m, Vin, Ts, 1e-6);
  pr_free(&tr);
}

/* 200 switchings in the 1 ms period of a 1 kHz load, 21 samples: more
 * jump times than 4 a sample, which the samples cannot place: the
 * measurements are the samples' own (the periodic trapezoid rule of the
 * file's /signals), with a warning and steady_state_measure_jumps = -1 in
 * the file; at 2001 samples the jumps are placed (and counted there). */
static void too_many_jumps(void **state) {
  (void)state;
  const char *cir = tmp_text("buck-1k.cir",
      "Buck, 1 kHz load\nV1 in 0 12\nVG g 0 PULSE(0 1 0 jump jump 5u 10u)\nS1 in sw g 0 SWI\nD1 0 sw\n"
      "L1 sw out 100u\nC1 out 0 10u\nRL out 0 5\nIL out 0 SIN(0 0.1 1k)\n.model SWI SW(VT=0.5 VH=0)\n"
      ".tran 100n 1m\n.probe v(sw)\n.end\n");
  const char *out = tmp_path("buck-1k.h5");
  for (int dense = 0; dense < 2; dense++) {
    result r = run_cli((const char *const[]){cir, "-o", out, "--steady-state", "--set", "steady_state.measure=[v(sw)]",
                                             "--set", dense ? "steady_state.samples=2001" : "steady_state.samples=21",
                                             "--set", "steady_state.harmonics=3", NULL}, 0, 0);
    if (!r.exited || r.code != 0) fail_msg("exit %d:\n%s", r.code, r.err);
    hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(f >= 0);
    double *v, *avg;
    hsize_t N = read_rows(f, "signals/v(sw)", 1, 1, &v);
    read_rows(f, "steady_state/measure/average", 1, 1, &avg);
    int64_t placed = attr_i64(f, "steady_state_measure_jumps");
    H5Fclose(f);
    double trap = 0;
    for (hsize_t k = 0; k + 1 < N; k++) trap += v[k] / (double)(N - 1);
    print_message("%ld samples: avg v(sw) %.12g, the samples' trapezoid rule %.12g, D Vin 6%s\n", (long)N, avg[0], trap,
                  strstr(r.err, "4 a sample") ? "; warned" : "");
    if (!dense) {
      assert_true(strstr(r.err, "warning") && strstr(r.err, "4 a sample"));
      assert_true(avg[0] == trap || fabs(avg[0] - trap) <= 1e-14 * 12);
      assert_int_equal(placed, -1);                /* the file says none was placed */
    } else {
      assert_null(strstr(r.err, "4 a sample"));
      assert_true(fabs(avg[0] - 6) <= 1e-9 * 12);
      assert_true(placed >= 200 && placed <= 4 * 2001 + 64);   /* the gate's 200 edges at least */
    }
    free(v); free(avg);
  }
}

/* A buck without a switch: the source is the PULSE, D1 both switch and
 * freewheeling path (V1 at 0 V closes the loop), so the sources' edges at
 * t0 and t0 + T are the switchings; the period's last sample reads the
 * next period's source (its edge at T), and the jump there must count:
 * it read avg v(sw) 3.7674 and efficiency 0.99934 (D Vin = 3.7644, 1), and
 * the gate of the switched examples avg 0.50025 for a duty of 1/2. */
static void source_edge_at_period_end(void **state) {
  (void)state;
  const double D = 0.3137, Vin = 12;
  const char *cir = tmp_text("buck-noswitch.cir",
      "Buck without a switch\nV1 a 0 PULSE(0 12 0 jump jump 3.137u 10u)\nD1 a sw\nL1 sw out 100u\n"
      "C1 out 0 10u\nRL out 0 5\n.tran 100n 1m\n.end\n");
  const char *out = tmp_path("buck-noswitch.h5");
  result r = run_cli((const char *const[]){cir, "-o", out, "--steady-state", "--set",
                                           "steady_state.measure=[v(sw), v(a)]", "--set",
                                           "steady_state.efficiency=[RL, V1]", NULL}, 0, 0);
  if (!r.exited || r.code != 0) fail_msg("exit %d:\n%s", r.code, r.err);
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  double *avg, *eff;
  assert_true(read_rows(f, "steady_state/measure/average", 1, 1, &avg) == 2);
  read_rows(f, "steady_state/efficiency", 1, 1, &eff);
  H5Fclose(f);
  print_message("no switch: avg v(sw) %.15g, avg v(a) %.15g (D Vin %.15g); efficiency 1 %+.3g\n", avg[0], avg[1],
                D * Vin, eff[0] - 1);
  assert_true(fabs(avg[0] - D * Vin) <= 1e-9 * Vin);
  assert_true(fabs(avg[1] - D * Vin) <= 1e-12 * Vin);
  assert_true(fabs(eff[0] - 1) <= 1e-9);
  free(avg); free(eff);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(ccm_half),
      cmocka_unit_test(ccm_between),
      cmocka_unit_test(dcm),
      cmocka_unit_test(too_many_jumps),
      cmocka_unit_test(source_edge_at_period_end),
  };
  return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}

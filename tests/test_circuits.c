/* circuits: the theta scheme on LCS with D != 0 against exact solutions
 * computed here. Diode bridges put skew +-1 entries with a zero diagonal
 * into D; where they carry a jump of the state, the jump's impulse must be
 * taken once (src/lcp/step.h), and where the solution is smooth theta = 1/2
 * must stay second order:
 *   - a 10 V step through an ideal bridge into 300 nF || 1 kohm: the
 *     capacitor jumps to 10 V and stays (19.97 V before the fix);
 *   - an ideal full-wave bridge with a capacitor filter fed by a sine: the
 *     capacitor follows |V| while the diodes conduct and decays through the
 *     load between; started at the sine's peak it jumps to 10 V at t = 0;
 *   - the RC rectifiers of examples/circuits (a source resistance): linear
 *     flows between diode events, by matrix exponentials of the flow
 *     augmented with the sine's rotation, events bracketed;
 *   - the step itself on a D whose kernel mixes columns of unlike scale;
 *   - a series-resonant converter whose bridge diode is fixed by the
 *     others' currents: every step certified. */
#define _GNU_SOURCE
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include <gsl/gsl_linalg.h>
#include "testutil.h"
#include "lcp/step.h"

#define CIR CUP_SOURCE_DIR "/examples/circuits"

/* ---- running a netlist --------------------------------------------------------------- */

/* state 0 and zeta at every `every`-th step: row k / every */
typedef struct run { long n, every; double *t, *v, *z; int nz; } run;

typedef struct sink_ctx { run *r; cup_integrator *I; } sink_ctx;

static int keep_all(long k, double t, const double *x, void *ctx) {
  sink_ctx *c = ctx;
  long row = k / c->r->every;
  c->r->t[row] = t;
  c->r->v[row] = x[0];
  if (c->r->nz) cup_integrator_zeta(c->I, c->r->z + (size_t)row * c->r->nz);
  return 0;
}

/* The theta scheme (exact projections) on a netlist's text at n steps,
 * kept every `every` steps (n a multiple of it); the run's info in *info. */
static run run_every(const char *text, const char *const *sets, int nsets, long n, long every, double theta,
                     cup_run_info *info) {
  char err[CUP_ERRMSG_LEN] = "";
  cup_netlist *nl = NULL;
  if (cup_netlist_load_string(&nl, text, "t.cir", sets, nsets, err)) fail_msg("%s", err);
  const cup_lcs *L = cup_netlist_lcs(nl);
  double tstep, tstop;
  assert_int_equal(cup_netlist_tran(nl, &tstep, &tstop), 1);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_THETA;
  o.theta = theta;
  o.T = tstop;
  o.n = n;
  o.eps = o.eta = (cup_schedule){0, 0};
  o.output_every = every;
  size_t rows = (size_t)(n / every) + 1;
  run r = {n, every, calloc(rows, sizeof(double)), calloc(rows, sizeof(double)), NULL, cup_lcs_rows(L)};
  r.z = calloc(rows * (size_t)r.nz, sizeof(double));
  cup_integrator *I = NULL;
  assert_int_equal(cup_integrator_create(&I, L, cup_netlist_input(nl), &o, err), CUP_OK);
  sink_ctx c = {&r, I};
  int st = cup_integrator_run(I, cup_netlist_x0(nl), keep_all, &c, info);
  assert_true(st >= 0);
  cup_integrator_free(&I);
  cup_netlist_free(&nl);
  return r;
}

static run run_text(const char *text, const char *const *sets, int nsets, long n, double theta, cup_run_info *info) {
  return run_every(text, sets, nsets, n, 1, theta, info);
}

static char *read_file(const char *path) {
  FILE *f = fopen(path, "rb");
  assert_non_null(f);
  static char buf[1 << 14];
  size_t len = fread(buf, 1, sizeof buf - 1, f);
  fclose(f);
  buf[len] = 0;
  return buf;
}

static void run_free(run *r) { free(r->t); free(r->v); free(r->z); }

/* ---- the bridge: a step through four ideal diodes -------------------------- */

static const char *bridge_step =
    "bridge step\n"
    "V1 p 0 PULSE(0 10 1m 1p 1p 10m 20m)\n"
    "D1 p a\nD2 0 a\nD3 b p\nD4 b 0\n"
    "C1 a b 300n\nR1 a b 1k\n"
    ".tran 1u 2m\n";

/* v(C1) = 0 until the edge at 1 ms, then 10 V exactly (the diodes hold the
 * capacitor at the source's value while it discharges into R1), at every n:
 * the scheme is exact here. Before the fix theta = 1/2 gave 19.97, 19.997,
 * 19.9997 V one step after the edge at n = 2e3, 2e4, 2e5. The holding
 * current, the diodes' zeta, is v/R1 = 10 mA to first order. */
static void test_bridge_step(void **state) {
  (void)state;
  for (long n = 2000; n <= 200000; n *= 10) {
    cup_run_info info;
    run r = run_text(bridge_step, NULL, 0, n, 0.5, &info);
    assert_int_equal(info.status, CUP_OK);             /* x0 = 0 is consistent: no jump reported */
    assert_int_equal(info.not_certified, 0);
    double err = 0;
    for (long k = 0; k <= n; k++) err = fmax(err, fabs(r.v[k] - (k > n / 2 ? 10 : 0)));
    long k1 = n / 2 + 2;                                   /* one step after the edge's step */
    double i4 = r.z[k1 * r.nz + 3];                        /* D4's current */
    print_message("bridge step n %6ld: max |v - exact| = %.3g V, i(D4) %.6g mA one step on\n", n, err, 1e3 * i4);
    assert_true(err <= 1e-12 * 10);
    assert_close(i4, 10e-3, 10e-3 * 2e-6 * (2e6 / (double)n));
    run_free(&r);
  }
}

/* ---- ideal full-wave bridge with a capacitor filter --------------------------------- */

typedef struct fw { double Vm, w, phase, C, R; } fw;

static double fw_src(const fw *q, double t) { return fabs(q->Vm * sin(q->w * t + q->phase)); }

/* C d|V|/dt + |V|/R: the diodes' current while v follows |V|. */
static double fw_current(const fw *q, double t) {
  double s = sin(q->w * t + q->phase), c = cos(q->w * t + q->phase);
  return q->C * q->Vm * q->w * c * (s >= 0 ? 1 : -1) + fw_src(q, t) / q->R;
}

static double bisect(double (*f)(const void *, double), const void *ctx, double lo, double hi) {
  for (int it = 0; it < 200 && hi - lo > 0; it++) {
    double mid = 0.5 * (lo + hi);
    if ((f(ctx, mid) > 0) == (f(ctx, lo) > 0)) lo = mid; else hi = mid;
  }
  return 0.5 * (lo + hi);
}

typedef struct fw_seg { double t0, t1, v0; } fw_seg;   /* v0 < 0: follow |V|; else decay from v0 */
typedef struct fw_ev { const fw *q; double t0, v0; } fw_ev;

static double ev_current(const void *c, double t) { return fw_current(((const fw_ev *)c)->q, t); }
static double ev_catch(const void *c, double t) {
  const fw_ev *e = c;
  return fw_src(e->q, t) - e->v0 * exp(-(t - e->t0) / (e->q->R * e->q->C));
}

/* The exact solution on [0, T] as segments: v follows |V| while the
 * current is positive (the capacitor starts at |V(0)|: a jump from 0 if the
 * sine starts off zero), then decays until |V| catches it up; events found
 * on a 1 us scan and bisected. */
static int fw_segments(const fw *q, double T, fw_seg *seg, int cap) {
  int k = 0;
  double t = 0, dt = 1e-6;
  while (t < T && k + 2 < cap) {
    double toff = t;                              /* follow: until the current turns negative */
    while (toff < T && fw_current(q, toff + dt) > 0) toff += dt;
    if (toff < T) {
      fw_ev e = {q, 0, 0};
      toff = bisect(ev_current, &e, toff, toff + dt);
    }
    seg[k++] = (fw_seg){t, fmin(toff, T), -1};
    if (toff >= T) break;
    fw_ev e = {q, toff, fw_src(q, toff)};
    double ton = toff + dt;                       /* decay: until |V| reaches v */
    while (ton < T && ev_catch(&e, ton) < 0) ton += dt;
    if (ton < T) ton = bisect(ev_catch, &e, ton - dt, ton);
    seg[k++] = (fw_seg){toff, fmin(ton, T), e.v0};
    t = ton;
  }
  return k;
}

static double fw_exact(const fw *q, const fw_seg *seg, int k, double t) {
  for (int s = 0; s < k; s++)
    if (t <= seg[s].t1 || s == k - 1)
      return seg[s].v0 < 0 ? fw_src(q, t) : seg[s].v0 * exp(-(t - seg[s].t0) / (q->R * q->C));
  return NAN;
}

/* 10 V, 50 Hz from an ideal source through four ideal diodes into 100 uF ||
 * 1 kohm, for 3 periods, starting at phase 0 (consistent) and at the peak
 * (the capacitor jumps to 10 V in the first step; before the fix theta =
 * 1/2 took it to 19.998 V). Between events the scheme is exact while the
 * diodes conduct (v = |V| at t_{k+1}) and second order while v decays; at a
 * turn-off the step that straddles it leaves v on |V| a fraction of a step
 * too long, an error below (1/2) max |V''| h^2 = (1/2) w^2 Vm h^2 that the
 * decay carries on. Asserted: the error stays below w^2 Vm h^2 at every n
 * (second order), and the jump is reported, with its size, at the peak only. */
static void test_fullwave_filter(void **state) {
  (void)state;
  for (int peak = 0; peak < 2; peak++) {
    fw q = {10, 2 * M_PI * 50, peak ? M_PI / 2 : 0, 100e-6, 1000};
    fw_seg seg[64];
    int ns = fw_segments(&q, 0.06, seg, 64);
    assert_true(ns >= 6);
    const char *sets[] = {peak ? "V1=SIN(0 10 50 0 0 90)" : "V1=SIN(0 10 50)"};
    for (long n = 3000; n <= 300000; n *= 10) {
      char text[512];
      snprintf(text, sizeof text, "fw\nV1 p 0 SIN(0 10 50)\nD1 p a\nD2 0 a\nD3 b p\nD4 b 0\n"
                                  "C1 a b 100u\nR1 a b 1k\n.tran 20u 60m\n");
      cup_run_info info;
      run r = run_text(text, sets, 1, n, 0.5, &info);
      double err = 0, h = 0.06 / (double)n;
      for (long k = 1; k <= n; k++) err = fmax(err, fabs(r.v[k] - fw_exact(&q, seg, ns, r.t[k])));
      print_message("full-wave filter, %s, n %6ld: max |v - exact| = %.3g V (bound %.3g)\n",
                    peak ? "from the peak" : "from 0", n, err, q.w * q.w * q.Vm * h * h);
      assert_true(err <= q.w * q.w * q.Vm * h * h);
      assert_int_equal(info.not_certified, 0);
      if (peak) {
        assert_int_equal(info.status, CUP_WARN_X0_OUTSIDE);
        assert_non_null(strstr(info.message, "not consistent"));
        assert_non_null(strstr(info.message, "a jump of 10 in x[0]"));
      } else {
        assert_int_equal(info.status, CUP_OK);
      }
      run_free(&r);
    }
  }
}

/* ---- RC rectifiers with a source resistance: flows by matrix exponentials ------------ */

/* C v' = s (Vm sin wt - s v)/Rs - v/RL while the diode (pair) conducts,
 * -v/RL while not; y = (v, sin wt, cos wt), y' = A y. */
typedef struct rect { double Vm, w, Rs, C, RL; int full; } rect;

static void rect_flow(const rect *q, int on, double s, double dt, const double y0[3], double y[3]) {
  gsl_matrix *A = gsl_matrix_calloc(3, 3), *E = gsl_matrix_alloc(3, 3);
  double a = on ? (1 / q->Rs + 1 / q->RL) / q->C : 1 / (q->RL * q->C);
  gsl_matrix_set(A, 0, 0, -a * dt);
  if (on) gsl_matrix_set(A, 0, 1, s * q->Vm / (q->Rs * q->C) * dt);
  gsl_matrix_set(A, 1, 2, q->w * dt);
  gsl_matrix_set(A, 2, 1, -q->w * dt);
  assert_int_equal(gsl_linalg_exponential_ss(A, E, GSL_PREC_DOUBLE), 0);
  for (int i = 0; i < 3; i++) {
    y[i] = 0;
    for (int j = 0; j < 3; j++) y[i] += gsl_matrix_get(E, i, j) * y0[j];
  }
  gsl_matrix_free(A);
  gsl_matrix_free(E);
}

typedef struct rect_seg { double t0; int on; double s, y0[3]; } rect_seg;
typedef struct rect_ev { const rect *q; const rect_seg *g; } rect_ev;

/* The source the diodes see (|V| for the bridge) less v: the event function. */
static double rect_gap(const rect *q, const double y[3]) {
  double V = q->Vm * y[1];
  return (q->full ? fabs(V) : V) - y[0];
}

static double ev_gap(const void *c, double t) {
  const rect_ev *e = c;
  double y[3];
  rect_flow(e->q, e->g->on, e->g->s, t - e->g->t0, e->g->y0, y);
  return rect_gap(e->q, y);
}

/* Segments of one mode each on [0, T]: a conducting one ends where the
 * source falls to v (the current reaches 0), a blocking one where it rises
 * past v; found on a 2 us scan and bisected. */
static int rect_segments(const rect *q, double T, rect_seg *seg, int cap) {
  int k = 0;
  seg[k++] = (rect_seg){0, 1, 1, {0, 0, 1}};      /* v = 0 and the source rising at t = 0 */
  double dt = 2e-6;
  while (k < cap) {
    rect_seg *g = &seg[k - 1];
    rect_ev e = {q, g};
    double t = g->t0;
    while (t < T && (ev_gap(&e, t + dt) > 0) == g->on) t += dt;
    if (t >= T) break;
    double te = bisect(ev_gap, &e, t, t + dt), y[3];
    rect_flow(q, g->on, g->s, te - g->t0, g->y0, y);
    seg[k] = (rect_seg){te, !g->on, y[1] >= 0 ? 1 : -1, {y[0], y[1], y[2]}};
    if (seg[k].on && !q->full) seg[k].s = 1;
    k++;
  }
  return k;
}

static double rect_exact(const rect *q, const rect_seg *seg, int k, double t) {
  int s = 0;
  while (s + 1 < k && seg[s + 1].t0 <= t) s++;
  double y[3];
  rect_flow(q, seg[s].on, seg[s].s, t - seg[s].t0, seg[s].y0, y);
  return y[0];
}

/* The netlist's v (state 0) at n = 3000 and 30000 against the exact
 * solution at every 30th and 300th step: second order (the errors fall
 * 100x; asserted 50x). */
static void rect_orders(const char *file, const rect *q) {
  rect_seg seg[128];
  int ns = rect_segments(q, 0.06, seg, 128);
  assert_true(ns >= 5 && ns < 128);
  char *text = strdup(read_file(file));
  double e[2];
  for (int r = 0; r < 2; r++) {
    long n = r ? 30000 : 3000;
    cup_run_info info;
    run x = run_text(text, NULL, 0, n, 0.5, &info);
    assert_int_equal(info.status, CUP_OK);
    assert_int_equal(info.not_certified, 0);
    e[r] = 0;
    for (long k = 0; k <= n; k += n / 1000) e[r] = fmax(e[r], fabs(x.v[k] - rect_exact(q, seg, ns, x.t[k])));
    print_message("%s n %5ld: max |v - exact| = %.3e V\n", strrchr(file, '/') + 1, n, e[r]);
    run_free(&x);
  }
  free(text);
  assert_true(e[0] < 1e-3 && e[1] < e[0] / 50);
}

static void test_rc_rectifiers(void **state) {
  (void)state;
  rect half = {10, 2 * M_PI * 50, 1, 100e-6, 1000, 0};
  rect_orders(CIR "/halfwave-rc.cir", &half);
  rect full = half;
  full.full = 1;
  rect_orders(CIR "/bridge.cir", &full);
}

/* ---- the step: a kernel of D_JJ mixing columns of unlike scale ------------------------- */

/* Two rows, two states, C = P = W = I, B = I, D = u u^T with u = (1, 1000)
 * (rank 1, positive semidefinite; its columns 1000x apart): with both rows
 * active zeta's part along ker D = (-1000, 1) is a multiplier and the rest
 * a function. Asserted from the step's output alone: the carry c = Pi zeta
 * satisfies D (zeta - c) = 0 with c = 0 on the kernel's free column, and
 * z = xpred + h (theta c + (zeta - c)), the kernel's part weighted whole. */
static void test_mixed_kernel(void **state) {
  (void)state;
  double Cd[4] = {1, 0, 0, 1}, g[2] = {0, 0}, pd[2] = {1, 1}, Bm[4] = {1, 0, 0, 1};
  double D[4] = {1, 1000, 1000, 1e6}, h = 0.1, theta = 0.5;
  tcsc Cc;
  cup_polyset *K = tpolyset_dense(&Cc, Cd, 2, 2, g, pd);
  lcp_step ls;
  assert_int_equal(lcp_step_init_bd(&ls, K, NULL, h, Bm, D, theta), CUP_OK);
  double x0[2] = {0, 0};
  assert_int_equal(lcp_step_start(&ls, x0, g), 1);
  int mixed = 0;
  for (int trial = 0; trial < 40; trial++) {
    /* free points below both rows with x1 / x0 in (952, 1000), where the
     * LCP with theta's weights has both rows active */
    double s = 0.1 + 0.05 * trial;
    double xf[2] = {-s, -(955 + trial) * s}, z[2], xp[2], carry_in[2];
    for (int i = 0; i < 2; i++) carry_in[i] = ls.carry[i];
    for (int i = 0; i < 2; i++) xp[i] = xf[i] + h * (1 - theta) * carry_in[i];
    cup_proj_info pi;
    int st = lcp_step_solve(&ls, g, xf, z, 1, -1, 1e-10, &pi);
    assert_true(st >= 0);
    const double *lam = ls.lcp.lam, *c = ls.carry;
    for (int i = 0; i < 2; i++) {                  /* z = xpred + h (theta c + (zeta - c)) */
      double want = xp[i] + h * (theta * c[i] + (lam[i] - c[i]));
      assert_close(z[i], want, 1e-12 * (1 + fabs(want)));
    }
    if (!(lam[0] > 0 && lam[1] > 0)) continue;
    mixed++;
    for (int i = 0; i < 2; i++) {                  /* D (zeta - c) = 0 */
      double r = D[i] * (lam[0] - c[0]) + D[i + 2] * (lam[1] - c[1]);
      assert_true(fabs(r) <= 1e-12 * (fabs(D[i]) * lam[0] + fabs(D[i + 2]) * lam[1]));
    }
    assert_true(c[0] == 0 || c[1] == 0);           /* the kernel's free column carries nothing */
  }
  print_message("mixed kernel: %d of 40 steps with both rows active\n", mixed);
  assert_true(mixed >= 20);
  lcp_step_free(&ls);
  cup_polyset_free(&K);
  tcsc_free(&Cc);
}

/* ---- consistent starts ------------------------------------------------------------------ */

/* A start is consistent when some zeta >= 0 makes C x0 + D zeta + g >= 0:
 * the converter with 1 A in its inductor at t = 0 is (the bridge carries
 * it), though C x0 + g alone is negative on the row of the diode that
 * blocks it; it used to warn "x0 is outside K(0)". Nothing jumps: i(L1)
 * moves by at most |V| h / L in the first step. */
static void test_consistent_start(void **state) {
  (void)state;
  char *text = strdup(read_file(CIR "/series-resonant.cir"));
  char *l1 = strstr(text, "L1 in m 100u");
  assert_non_null(l1);
  char fixed[4096];
  snprintf(fixed, sizeof fixed, "%.*sL1 in m 100u IC=1%s", (int)(l1 - text), text, l1 + strlen("L1 in m 100u"));
  cup_run_info info;
  run r = run_text(fixed, NULL, 0, 40000, 0.5, &info);
  print_message("series-resonant from i(L1) = 1 A: status %s, i(L1) %.6g A after one step\n",
                cup_status_name(info.status), r.v[1]);
  assert_int_equal(info.status, CUP_OK);
  assert_close(r.v[0], 1, 0);
  assert_true(fabs(r.v[1] - 1) <= 1.1 * 100 / 100e-6 * 1e-3 / 40000);   /* |V| / L h: a flow, no jump */
  run_free(&r);
  free(text);
}

/* ---- a series-resonant converter: every step certified --------------------------------- */

/* examples/circuits/series-resonant.cir: D1 is fixed by the other diodes'
 * currents (its row of C is zero) and the 10 kohm across the bridge makes
 * the others' rows unlike in scale. Before the theta step scaled its LCP's
 * rows and refined its aim, 3705 of 4e4 and 56750 of 4e5 steps ended with
 * eta = infinity; now none, and the runs converge: i(L1) at n = 4e4 and
 * 4e5 differs by at most 1 % of its range, and 10x less at 4e5 and 4e6
 * (measured: 6.8e-3 and 1.4e-4 A, of 4.4 A). */
static void test_series_resonant(void **state) {
  (void)state;
  char *text = strdup(read_file(CIR "/series-resonant.cir"));
  double vmax = 0, d[2] = {0, 0};
  run prev = {0};
  for (long n = 40000; n <= 4000000; n *= 10) {   /* kept on the grid of n = 4e4 */
    cup_run_info info;
    run r = run_every(text, NULL, 0, n, n / 40000, 0.5, &info);
    print_message("series-resonant n %7ld: %ld steps not certified, status %s\n", n, info.not_certified,
                  cup_status_name(info.status));
    assert_int_equal(info.not_certified, 0);
    assert_int_equal(info.status, CUP_OK);
    for (long k = 0; k <= 40000; k++) vmax = fmax(vmax, fabs(r.v[k]));
    if (prev.n) {
      double *dd = &d[n == 4000000];
      for (long k = 0; k <= 40000; k++) *dd = fmax(*dd, fabs(prev.v[k] - r.v[k]));
      print_message("  max |i_L(n/10) - i_L(n)| = %.3g A\n", *dd);
      run_free(&prev);
    }
    prev = r;
  }
  run_free(&prev);
  free(text);
  assert_true(d[0] < 0.01 * vmax && d[1] < d[0] / 10);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_bridge_step),     cmocka_unit_test(test_fullwave_filter),
      cmocka_unit_test(test_rc_rectifiers),   cmocka_unit_test(test_mixed_kernel),
      cmocka_unit_test(test_consistent_start), cmocka_unit_test(test_series_resonant),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

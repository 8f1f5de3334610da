/* Steady-state sweeps and generated variants (src/sweep/sweep_steady.c,
 * sweep_gen.c; docs/sweep-format.md): each task of a sweep over the buck of
 * examples/circuits/buck-design.cir solves its steady state and measures it,
 * checked against the closed forms of the ideal buck (RS set to 1 uOhm):
 * the CCM average D Vin, the inductor's ripple (Vin - Vout) D Ts / L, the
 * efficiency 1, the largest multiplier e^{-Ts / (2 R C)} (both topologies
 * share the L-C-R filter's A), the DCM conversion ratio 2 / (1 + sqrt(1 +
 * 8 L / (R D^2 Ts))) within the ripple; a grid and a zip make the variants
 * and overrides they say; the Latin hypercube puts one point in each
 * stratum of every range, the same on every parse. Small sizes: the 10^4
 * study is scripts/bench-design. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include "catchup.h"
#include "sweep_run.h"
#define CLI_TMPDIR_TEMPLATE "/tmp/cup_sweep_steady_XXXXXX"
#include "tmpdir.h"

#define EX CUP_EXAMPLES_DIR

static sw_sweep *parse(const char *text, int resolve) {
  sw_sweep *s = NULL;
  char err[SW_ERR_LEN] = "";
  int st = sw_parse(&s, text, strlen(text), EX "/circuits/inline-sweep.yaml", err);
  if (!st && resolve) st = sw_resolve_files(s, err);
  if (st) fail_msg("sweep did not load: %s", err);
  return s;
}

/* variants: D = 0.3, 0.5, 0.7 at L = 100u (CCM), then L = 10u, R = 20 at D = 0.3 (DCM) */
static const char *buck_sweep =
    "base: buck-design.yaml\n"
    "variants:\n"
    "  - name: ccm\n"
    "    set: {netlist.RS: 1u}\n"
    "    grid: {netlist.D: [0.3, 0.5, 0.7]}\n"
    "  - name: dcm\n"
    "    set: {netlist.RS: 1u, netlist.D: 0.3}\n"
    "    zip: {netlist.L: [10u], netlist.R: [20]}\n";

static void steady_buck(void **state) {
  (void)state;
  sw_sweep *s = parse(buck_sweep, 1);
  assert_int_equal(s->n_variants, 4);
  assert_int_equal(s->n_tasks, 4);
  assert_true(s->steady);
  assert_int_equal(s->out_samples, 0);
  assert_string_equal(s->var[1].name, "ccm.1");
  assert_string_equal(s->var[1].set[1], "netlist.D=0.5");
  assert_string_equal(s->var[3].set[2], "netlist.L=10u");
  assert_string_equal(s->var[3].set[3], "netlist.R=20");
  assert_string_equal(sw_signal_name(s, s->ss_sig[0]), "v(out)");
  assert_string_equal(sw_signal_name(s, s->ss_sig[1]), "i(L1)");
  const double Vin = 12, Ts = 10e-6, C = 10e-6, RS = 1e-6;
  const double D[4] = {0.3, 0.5, 0.7, 0.3}, L[4] = {100e-6, 100e-6, 100e-6, 10e-6}, R[4] = {5, 5, 5, 20};
  double *traj = malloc(sizeof(double) * (size_t)(sw_traj_len(s) + 1));
  for (int k = 0; k < 4; k++) {
    sw_result r;
    sw_run_job(s, k, NULL, &r, traj);                 /* the reference: nothing to compute */
    assert_int_equal(r.status, CUP_OK);
    sw_run_job(s, s->n_variants + k, NULL, &r, traj);
    const struct sw_steady_result *q = &r.steady;
    const double *v = q->fig[0], *i = q->fig[1];      /* average, rms, min, max, peak-to-peak */
    printf("# %-6s %s: %d Newton steps, %ld period runs, residual %.2g, |mu| %.9f, v(out) %.9f V (p-p %.4g), "
           "i(L1) p-p %.6f A, efficiency %.9f, %.3f ms\n", s->var[k].name, cup_status_name(r.status), q->iterations,
           (long)q->period_runs, q->residual, q->max_multiplier, v[0], v[4], i[4], q->efficiency, 1e3 * r.wall);
    assert_int_equal(r.status, CUP_OK);
    assert_true(q->solved);
    assert_true(q->iterations >= 1 && q->iterations <= 6);
    assert_true(fabs(q->period - Ts) <= 1e-18);
    if (k < 3) {                                      /* CCM */
      assert_true(fabs(v[0] - D[k] * Vin) <= 2 * D[k] * RS * i[3] + 1e-9);
      double closed = (Vin - v[0]) * D[k] * Ts / L[k];
      assert_true(fabs(i[4] - closed) <= D[k] * Ts / L[k] * v[4] + 1e-9);
      assert_true(fabs(i[0] - v[0] / R[k]) <= 1e-6 * i[0]);      /* the capacitor's charge balance */
      assert_true(fabs(q->max_multiplier - exp(-Ts / (2 * R[k] * C))) <= 1e-6);
    } else {                                          /* DCM: the current reaches 0 */
      assert_true(fabs(i[2]) <= 1e-9);
      double M = 2 / (1 + sqrt(1 + 8 * L[k] / (R[k] * D[k] * D[k] * Ts)));
      assert_true(fabs(v[0] / Vin - M) <= v[4] / Vin);
    }
    /* The circuit's own efficiency: RS's loss over the input's power, RS
     * <i^2> / (Vin <i>) <= RS i_max / Vin (the input's current is i(L1) or 0),
     * the rest lossless. The input's current jumps at the gate edges, measured
     * there with its jumps (docs/steady-state.md, "Signals that jump": O(h^2)
     * on the smooth pieces; the trapezoid rule of the samples was O(h), up
     * to 1e-3 off here) */
    double loss = RS * i[3] / Vin;
    printf("#        efficiency 1 - %.3g, RS's loss at most %.3g\n", 1 - q->efficiency, loss);
    assert_true(q->efficiency <= 1 + 1e-8 && q->efficiency >= 1 - loss - 1e-8);
  }
  free(traj);
  sw_free(&s);
}

/* The Latin hypercube: 50 points, one in each fiftieth of every range (of
 * the logarithm for a log range), the same overrides on a second parse and
 * others with another seed. */
static void latin_hypercube(void **state) {
  (void)state;
  const char *text =
      "base: buck-design.yaml\n"
      "variants:\n"
      "  - name: first\n"
      "  - name: lhs\n"
      "    sample: {count: 50, seed: 7, ranges: {netlist.D: [0.2, 0.8], netlist.L: {log: [1u, 100u]}}}\n";
  sw_sweep *a = parse(text, 0), *b = parse(text, 0);
  assert_int_equal(a->n_variants, 51);
  int hitD[50] = {0}, hitL[50] = {0};
  for (int k = 1; k <= 50; k++) {
    const sw_variant *v = &a->var[k];
    char name[16];
    snprintf(name, sizeof name, "lhs.%d", k - 1);
    assert_string_equal(v->name, name);
    assert_int_equal(v->n_set, 2);
    assert_string_equal(v->set[0], b->var[k].set[0]);
    assert_string_equal(v->set[1], b->var[k].set[1]);
    double d = atof(strchr(v->set[0], '=') + 1), l = atof(strchr(v->set[1], '=') + 1);
    assert_true(d >= 0.2 && d < 0.8 && l >= 1e-6 && l < 100e-6);
    hitD[(int)floor((d - 0.2) / 0.6 * 50)]++;
    hitL[(int)floor(log(l / 1e-6) / log(100.0) * 50)]++;
  }
  for (int j = 0; j < 50; j++) {
    assert_int_equal(hitD[j], 1);
    assert_int_equal(hitL[j], 1);
  }
  sw_free(&b);
  const char *other =
      "base: buck-design.yaml\n"
      "variants:\n"
      "  - name: first\n"
      "  - name: lhs\n"
      "    sample: {count: 50, seed: 8, ranges: {netlist.D: [0.2, 0.8], netlist.L: {log: [1u, 100u]}}}\n";
  b = parse(other, 0);
  assert_string_not_equal(a->var[1].set[0], b->var[1].set[0]);
  sw_free(&a);
  sw_free(&b);
}

/* Lazy variants: a generated variant beyond its entry's first is loaded
 * by its own task. Its result is bit for bit a written variant's with the
 * same overrides; a value its scene refuses fails that task alone, with
 * the scene's message; a generated key that changes what the entry's first
 * stood for (here max_steps) fails its task, naming it. */
static void lazy_variants(void **state) {
  (void)state;
  sw_sweep *s = parse("base: buck-design.yaml\n"
                      "variants:\n"
                      "  - name: g\n"
                      "    grid: {netlist.L: [100u, -1u, 47u]}\n"
                      "  - name: m\n"
                      "    grid: {max_steps: [1000000, 2000000]}\n", 1);
  sw_sweep *w = parse("base: buck-design.yaml\n"
                      "variants: [{name: written, set: {netlist.L: 47u}}]\n", 1);
  assert_int_equal(s->n_variants, 5);
  assert_non_null(s->var[0].scene);
  assert_null(s->var[1].scene);                     /* lazy: loaded by its task */
  assert_null(s->var[2].scene);
  assert_non_null(s->var[3].scene);                 /* m.0: its entry's first */
  assert_true(sw_variant_lazy(s, 4) && !sw_variant_lazy(s, 3));
  assert_non_null(strstr(s->var[2].scene_text, "L: \"47u\""));
  sw_scene_slot slot = {-1, NULL};
  sw_run_opts ro = {NULL, NULL, NULL, 0, 0, &slot};
  sw_result r, ref;
  double traj[1];
  sw_run_job(w, w->n_variants, NULL, &ref, traj);
  for (int pass = 0; pass < 2; pass++) {            /* loaded per job, then kept in a slot */
    const sw_run_opts *o = pass ? &ro : NULL;
    sw_run_job(s, s->n_variants + 0, o, &r, traj);
    assert_int_equal(r.status, CUP_OK);
    sw_run_job(s, s->n_variants + 1, o, &r, traj);
    printf("# g.1: %s: %s\n", cup_status_name(r.status), r.message);
    assert_true(r.status < 0);
    assert_non_null(strstr(r.message, "variants.1 (g.1): "));
    assert_non_null(strstr(r.message, "inductance must be > 0"));
    sw_run_job(s, s->n_variants + 2, o, &r, traj);
    assert_int_equal(r.status, CUP_OK);
    assert_int_equal(r.steady.iterations, ref.steady.iterations);
    assert_memory_equal(r.steady.fig, ref.steady.fig, sizeof r.steady.fig);
    assert_memory_equal(&r.steady.efficiency, &ref.steady.efficiency, sizeof(double));
    assert_int_equal(slot.variant, pass ? 2 : -1);
    sw_run_job(s, s->n_variants + 4, o, &r, traj);
    printf("# m.1: %s: %s\n", cup_status_name(r.status), r.message);
    assert_int_equal(r.status, CUP_ERR_PARSE);
    assert_non_null(strstr(r.message, "variants.4 (m.1): its max_steps differs from m.0's"));
  }
  sw_scene_slot_free(&slot);
  sw_free(&w);
  sw_free(&s);
}

/* 200 switchings in the 1 ms period of a 1 kHz load (test_pss_jumps.c's
 * too_many_jumps): at 21 samples, more than 4 a sample, the measurements
 * cannot place the jumps and the task says so (CUP_WARN_COARSE_MEASURE and
 * its message; before, CUP_OK and nothing); at 2001 samples they are placed
 * and the average of v(sw) is the ideal buck's D Vin = 6. */
static void coarse_measure_is_said(void **state) {
  (void)state;
  char cir[300], scene[300];
  snprintf(cir, sizeof cir, "%s/buck-1k.cir", tmpdir);
  snprintf(scene, sizeof scene, "%s/buck-1k.yaml", tmpdir);
  FILE *fp = fopen(cir, "w");
  assert_non_null(fp);
  fputs("Buck, 1 kHz load\nV1 in 0 12\nVG g 0 PULSE(0 1 0 jump jump 5u 10u)\nS1 in sw g 0 SWI\nD1 0 sw\n"
        "L1 sw out 100u\nC1 out 0 10u\nRL out 0 5\nIL out 0 SIN(0 0.1 1k)\n.model SWI SW(VT=0.5 VH=0)\n"
        ".tran 100n 1m\n.end\n", fp);
  fclose(fp);
  fp = fopen(scene, "w");
  assert_non_null(fp);
  fputs("netlist: buck-1k.cir\nsteady_state:\n  measure: [v(sw)]\n  harmonics: 3\n", fp);
  fclose(fp);
  char text[600];
  snprintf(text, sizeof text, "base: %s\nvariants:\n  - name: n\n    grid: {steady_state.samples: [21, 2001]}\n",
           scene);
  sw_sweep *s = parse(text, 1);
  double traj[1];
  for (int k = 0; k < 2; k++) {
    sw_result r;
    sw_run_job(s, s->n_variants + k, NULL, &r, traj);
    printf("# %s: %s, avg v(sw) %.12g: %s\n", s->var[k].name, cup_status_name(r.status), r.steady.fig[0][0],
           r.message);
    assert_true(r.steady.solved);
    if (k == 0) {
      assert_int_equal(r.status, CUP_WARN_COARSE_MEASURE);
      assert_non_null(strstr(r.message, "more than 148 switchings and events in the period, 4 a sample"));
      assert_non_null(strstr(r.message, "raise steady_state.samples"));
    } else {
      assert_int_equal(r.status, CUP_OK);
      assert_null(strstr(r.message, "4 a sample"));
      assert_true(fabs(r.steady.fig[0][0] - 6) <= 1e-9 * 12);
    }
  }
  sw_free(&s);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(steady_buck),
      cmocka_unit_test(latin_hypercube),
      cmocka_unit_test(lazy_variants),
      cmocka_unit_test(coarse_measure_is_said),
  };
  return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}

/* sweep (src/sweep/, io/sha256.c): the sweep file, task order, the
 * sampling of n that are not multiples of samples - 1 (against the
 * library's samples and a closed form), and the Richardson
 * reference against the reference limit (tests/data) of the paper's case 1.
 * tests/sweeps/bad names its expected error in a "# expect: ..." first line. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include <hdf5.h>
#include "catchup.h"
#include "io/sha256.h"
#include "sweep_file.h"
#include "sweep_h5.h"
#include "sweep_run.h"
#include "refdata.h"

#define EX CUP_EXAMPLES_DIR

static void test_sha256_vectors(void **state) {
  (void)state;
  char hex[65];
  sha256_hex("", 0, hex);
  assert_string_equal(hex, "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  sha256_hex("abc", 3, hex);
  assert_string_equal(hex, "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  const char *m = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";   /* 448 bits: two blocks */
  sha256_hex(m, strlen(m), hex);
  assert_string_equal(hex, "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  char *a = malloc(1000000);
  assert_non_null(a);
  memset(a, 'a', 1000000);
  sha256_hex(a, 1000000, hex);
  assert_string_equal(hex, "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  free(a);
}

static sw_sweep *load_text(const char *text) {
  sw_sweep *s = NULL;
  char err[SW_ERR_LEN] = "";
  int st = sw_parse(&s, text, strlen(text), EX "/inline-sweep.yaml", err);
  if (!st) st = sw_resolve_files(s, err);
  if (st) fail_msg("sweep did not load: %s", err);
  return s;
}

static sw_sweep *load_file(const char *path) {
  sw_sweep *s = NULL;
  char err[SW_ERR_LEN] = "";
  int st = sw_load(&s, path, err);
  if (!st) st = sw_resolve_files(s, err);
  if (st) fail_msg("%s did not load: %s", path, err);
  return s;
}

static void expect_task(const sw_sweep *s, long id, int variant, long n, const char *eps, const char *eta,
                        int scheme, int projector) {
  sw_task t;
  assert_int_equal(sw_task_get(s, id, &t), CUP_OK);
  if (t.variant != variant || t.n != n || strcmp(t.eps, eps) || strcmp(t.eta, eta) || t.scheme != scheme ||
      t.projector != projector)
    fail_msg("task %ld: variant %d n %ld eps %s eta %s scheme %d projector %d", id, t.variant, t.n, t.eps,
             t.eta, t.scheme, t.projector);
}

/* Variant-major, then n, eps, eta, scheme, projector (last fastest); the
 * zipped eps/eta count once. */
static void test_smoke_task_order(void **state) {
  (void)state;
  sw_sweep *s = load_file(EX "/sweep-smoke.yaml");
  assert_int_equal(s->n_variants, 2);
  assert_int_equal(s->per_variant, 3 * 2 * 2 * 2);
  assert_int_equal(s->n_tasks, 48);
  assert_int_equal(s->var[0].n_ref, 40000);
  assert_int_equal(s->samples, 101);
  assert_true(s->T == 1.0 && s->dim == 3);
  expect_task(s, 0, 0, 100, "n^-2.1", "n^-1.05", CUP_SCHEME_EXPLICIT, CUP_PROJ_AUTO);
  expect_task(s, 1, 0, 100, "n^-2.1", "n^-1.05", CUP_SCHEME_EXPLICIT, CUP_PROJ_PG);
  expect_task(s, 2, 0, 100, "n^-2.1", "n^-1.05", CUP_SCHEME_IMPLICIT, CUP_PROJ_AUTO);
  expect_task(s, 5, 0, 100, "0", "0", CUP_SCHEME_EXPLICIT, CUP_PROJ_PG);
  expect_task(s, 8, 0, 250, "n^-2.1", "n^-1.05", CUP_SCHEME_EXPLICIT, CUP_PROJ_AUTO);
  expect_task(s, 47, 1, 1000, "0", "0", CUP_SCHEME_IMPLICIT, CUP_PROJ_PG);
  sw_task t;
  assert_int_equal(sw_task_get(s, 48, &t), CUP_ERR_ARG);
  /* References first, then blocks of consecutive tasks whose costs (n + 100
   * here: both schemes and projectors count 1) stay within a factor 4:
   * per variant, n = 100 and 250 (ids 0-15, cost 200 and 350) and n = 1000
   * (ids 16-23, cost 1100); the blocks of cost 1100 go first. */
  long order[50], at = 2;
  sw_schedule(s, order);
  assert_true(order[0] < 2 && order[1] < 2 && order[0] != order[1]);
  const long blocks[][2] = {{16, 24}, {40, 48}, {0, 16}, {24, 40}};
  for (int b = 0; b < 4; b++)
    for (long id = blocks[b][0]; id < blocks[b][1]; id++) assert_int_equal(order[at++], 2 + id);
  sw_free(&s);
  assert_null(s);
}

/* Two zip groups; absent axes come from the scene; "auto" n_ref. */
static void test_zip_groups_and_defaults(void **state) {
  (void)state;
  sw_sweep *s = load_text("base: paper-fig2.yaml\n"
                          "grid:\n"
                          "  n: [10, 20]\n"
                          "  eps: [1e-8, 0]\n  eta: [1e-4, 0]\n"
                          "  scheme: [explicit, exponential]\n  projector: [pg, fista]\n"
                          "  zip: [[eps, eta], [scheme, projector]]\n"
                          "variants:\n  - name: a\n  - {name: b, set: {n: 7, circuit.R1: 2}}\n"
                          "reference: {samples: 11}\n");
  assert_int_equal(s->per_variant, 2 * 2 * 2);
  expect_task(s, 0, 0, 10, "1e-8", "1e-4", CUP_SCHEME_EXPLICIT, CUP_PROJ_PG);
  expect_task(s, 1, 0, 10, "1e-8", "1e-4", CUP_SCHEME_EXPONENTIAL, CUP_PROJ_FISTA);
  expect_task(s, 2, 0, 10, "0", "0", CUP_SCHEME_EXPLICIT, CUP_PROJ_PG);
  expect_task(s, 15, 1, 20, "0", "0", CUP_SCHEME_EXPONENTIAL, CUP_PROJ_FISTA);
  assert_int_equal(s->var[0].n_ref, 80);          /* smallest multiple of 10 >= 4 x 20 */
  assert_non_null(strstr(s->var[1].scene_text, "R1: 2"));
  sw_free(&s);
  s = load_text("base: paper-fig2.yaml\nvariants:\n  - name: a\n  - {name: b, set: {n: 7, eps: 1e-9}}\n"
                "reference: {samples: 6}\n");
  assert_int_equal(s->n_tasks, 2);
  expect_task(s, 0, 0, 100, "n^-2.1", "n^-1.05", CUP_SCHEME_EXPLICIT, CUP_PROJ_AUTO);   /* the scene's */
  expect_task(s, 1, 1, 7, "1e-9", "n^-1.05", CUP_SCHEME_EXPLICIT, CUP_PROJ_AUTO);
  assert_int_equal(s->var[0].n_ref, 400);
  assert_int_equal(s->var[1].n_ref, 30);
  sw_free(&s);
  /* set values of every shape: a mapping, a list, a quoted string */
  s = load_text("base: paper-fig2.yaml\nvariants:\n"
                "  - name: c\n"
                "    set:\n"
                "      circuit: {R1: 1, R2: 2, R3: 1, L2: 1, L3: 4, C4: 1}\n"
                "      x0: [0, 0.5, 0]\n"
                "      eps: \"n^-3\"\n");
  assert_non_null(strstr(s->var[0].scene_text, "L3: 4"));
  assert_true(cup_scene_x0(s->var[0].scene)[1] == 0.5);
  expect_task(s, 0, 0, 100, "n^-3", "n^-1.05", CUP_SCHEME_EXPLICIT, CUP_PROJ_AUTO);
  sw_free(&s);
}

/* The shipped study: both paper cases, three circuit variants, n up to 10^6. */
static void test_paper_sweep(void **state) {
  (void)state;
  sw_sweep *s = load_file(EX "/paper-sweep.yaml");
  assert_true(s->n_variants >= 5);
  assert_int_equal(s->var[0].n_ref % (s->samples - 1), 0);
  long nmax = 0;
  for (int k = 0; k < s->len[SW_AXIS_N]; k++) nmax = s->n[k] > nmax ? s->n[k] : nmax;
  assert_int_equal(nmax, 1000000);
  assert_int_equal(s->var[0].n_ref, 4000000);
  char *g = sw_grid_text(s);
  assert_non_null(strstr(g, "zip: [eps, eta]"));
  free(g);
  sw_free(&s);
}

static char *first_line_expect(const char *path) {
  static char buf[1024];
  FILE *f = fopen(path, "r");
  assert_non_null(f);
  assert_non_null(fgets(buf, sizeof buf, f));
  fclose(f);
  buf[strcspn(buf, "\n")] = '\0';
  assert_true(strncmp(buf, "# expect: ", 10) == 0);
  return buf + 10;
}

static void test_bad_corpus(void **state) {
  (void)state;
  DIR *d = opendir(CUP_BAD_SWEEPS_DIR);
  assert_non_null(d);
  struct dirent *e;
  int count = 0;
  while ((e = readdir(d))) {
    size_t len = strlen(e->d_name);
    if (len < 6 || strcmp(e->d_name + len - 5, ".yaml")) continue;
    char path[1024], err[SW_ERR_LEN] = "";
    snprintf(path, sizeof path, "%s/%s", CUP_BAD_SWEEPS_DIR, e->d_name);
    const char *want = first_line_expect(path);
    sw_sweep *s = NULL;
    int st = sw_load(&s, path, err);
    if (!st) st = sw_resolve_files(s, err);
    if (st == CUP_OK) fail_msg("%s loaded without error", e->d_name);
    if (!strstr(err, want)) fail_msg("%s:\n  got  %s\n  want %s", e->d_name, err, want);
    assert_null(strchr(err, '\n'));
    sw_free(&s);                                  /* parsed but not resolved */
    count++;
  }
  closedir(d);
  assert_true(count >= 10);
}

/* /summary's and /references/summary's strings are fixed-length: nothing
 * written to them is cut. What a user writes (a variant's name, a schedule,
 * a generated name with its suffix) is refused beyond its field
 * (tests/sweeps/bad: long-name, long-eps, gen-long-name); the library's
 * own words fit theirs, every one of them; a message has the room of a
 * run's whole message and its prefix. */
static void test_fixed_fields_fit(void **state) {
  (void)state;
  static const int codes[] = {
#define CODE_(e, v, msg) e,
      CUP_STATUS_LIST(CODE_)
#undef CODE_
  };
  for (size_t k = 0; k < sizeof codes / sizeof codes[0]; k++)
    if (strlen(cup_status_name(codes[k])) >= SW_STATUS_LEN) fail_msg("%s: longer than /summary's status_name",
                                                                     cup_status_name(codes[k]));
  for (int k = 0; k < CUP_SCHEME_COUNT; k++) assert_true(strlen(cup_scheme_name(k)) < SW_WORD_LEN);
  for (int k = 0; k < CUP_PROJ_METHOD_COUNT; k++) assert_true(strlen(cup_proj_method_name(k)) < SW_WORD_LEN);
  assert_true(sizeof ((sw_row *)0)->status_name == SW_STATUS_LEN);
  assert_true(sizeof ((sw_refrow *)0)->status_name == SW_STATUS_LEN);
  assert_true(sizeof ((sw_row *)0)->message == sizeof ((sw_result *)0)->message);
  assert_true(sizeof ((sw_refrow *)0)->message == sizeof ((sw_result *)0)->message);
  assert_true(sizeof ((sw_result *)0)->message >= CUP_RUN_MSG_LEN + 64);
}

typedef struct { double x[101 * 3], t[101]; long k[101]; int n; } store_t;
static int sink(long k, double t, const double *x, void *ctx) {
  store_t *st = ctx;
  if (st->n < 101) { st->k[st->n] = k; st->t[st->n] = t; memcpy(st->x + 3 * st->n, x, 3 * sizeof(double)); st->n++; }
  return 0;
}

typedef struct { double x[251][3]; int n; } traj_all;
static int sink_all(long k, double t, const double *x, void *ctx) {
  (void)t;
  traj_all *a = ctx;
  if (k < 251) { memcpy(a->x[k], x, 3 * sizeof(double)); a->n = (int)k + 1; }
  return 0;
}

/* n = 250 with 101 samples: the library's CUP_OUTPUT_SAMPLES gives
 * t_j = j/100 itself, the step's state where t_j is on the grid (even j)
 * and the linear interpolation of the two steps around it otherwise (odd
 * j: halfway between steps m and m + 1, against every step kept by an
 * independent run); the sweep's task keeps those samples, bit for bit. */
static void test_samples_between_steps(void **state) {
  (void)state;
  sw_sweep *s = load_file(EX "/sweep-smoke.yaml");
  long task = 8;                                  /* case1, n = 250, paper schedules, explicit, auto */
  double *traj = malloc(sizeof(double) * 101 * 3);
  sw_result r;
  sw_run_job(s, s->n_variants + task, NULL, &r, traj);
  assert_int_equal(r.status, CUP_OK);
  assert_int_equal(r.stopped_step, 250);
  cup_integrator_options o = *cup_scene_options(s->var[0].scene);
  o.n = 250;
  o.output = CUP_OUTPUT_EVERY;
  o.output_every = 1;
  o.output_samples = 101;
  static traj_all all = {.n = 0};
  for (int pass = 0; pass < 2; pass++) {
    cup_integrator *I = NULL;
    assert_int_equal(cup_integrator_create(&I, cup_scene_lcs(s->var[0].scene), cup_scene_input(s->var[0].scene),
                                           &o, NULL), CUP_OK);
    store_t st = {{0}, {0}, {0}, 0};
    cup_run_info info;
    assert_int_equal(cup_integrator_run(I, cup_scene_x0(s->var[0].scene), pass ? sink : sink_all,
                                        pass ? (void *)&st : (void *)&all, &info), CUP_OK);
    cup_integrator_free(&I);
    if (!pass) {                                  /* every step first */
      assert_int_equal(all.n, 251);
      o.output = CUP_OUTPUT_SAMPLES;
      continue;
    }
    assert_int_equal(st.n, 101);
    for (int j = 0; j < 101; j++) {
      long m = (long)floor(2.5 * j);
      assert_int_equal(st.k[j], j % 2 ? m + 1 : m);
      assert_true(st.t[j] == (j == 100 ? 1.0 : j % 2 ? (double)j / 100 : (double)m * (1.0 / 250)));
      for (int i = 0; i < 3; i++) {
        /* halfway, to rounding: the weight (t_j - t_m) / h is 1/2 to the
         * rounding of t_j and t_m (~0.5 eps) over h (0.004): a few 100 eps */
        if (traj[3 * j + i] != st.x[3 * j + i])
          fail_msg("sample %d component %d: the sweep's %.17g, the library's %.17g", j, i, traj[3 * j + i],
                   st.x[3 * j + i]);
        double want = j % 2 ? all.x[m][i] + 0.5 * (all.x[m + 1][i] - all.x[m][i]) : all.x[m][i];
        double tol = j % 2 ? 4 * DBL_EPSILON * (fabs(all.x[m][i]) + fabs(all.x[m + 1][i])) +
                             512 * DBL_EPSILON * fabs(all.x[m + 1][i] - all.x[m][i]) : 0;
        if (!(fabs(want - st.x[3 * j + i]) <= tol))
          fail_msg("sample %d component %d: %.17g, expected %.17g", j, i, st.x[3 * j + i], want);
      }
    }
  }
  free(traj);
  sw_free(&s);
}

/* A netlist's task sampled at the sweep's common times t_j = j T / 10,
 * against the closed form of an RC charge (tests/sweeps/rc-tstart.cir:
 * v = 1 - exp(-t / RC), RC = 1 ms, T = 2 ms) at t_j: theta at n = 1005
 * (t_j = 100.5 j steps: odd j between steps) and the adaptive scheme, the
 * state and the signals v(out) and i(R1) = (1 - v) / 1k. Before, the first
 * was sampled at the nearest step (off by up to v' h / 2: 8.1e-4 V), the
 * second from the netlist's TSTART (0.5 ms: 0.39 V off at t = 0). */
static void test_netlist_samples_closed_form(void **state) {
  (void)state;
  const char *text = "base: rc-tstart.yaml\ngrid: {scheme: [theta, adaptive], n: [1005], eps: 0, eta: 0}\n"
                     "variants: [{name: rc}]\nreference: {samples: 11, method: adaptive}\n";
  sw_sweep *s = NULL;
  char err[SW_ERR_LEN] = "";
  int st = sw_parse(&s, text, strlen(text), CUP_BAD_SWEEPS_DIR "/../inline.yaml", err);
  if (!st) st = sw_resolve_files(s, err);
  if (st) fail_msg("sweep did not load: %s", err);
  assert_int_equal(s->samples, 11);
  int out = -1, ir = -1;
  for (int k = 0; k < s->nsig; k++) {
    if (!strcmp(sw_signal_name(s, k), "v(out)")) out = k;
    if (!strcmp(sw_signal_name(s, k), "i(R1)")) ir = k;
  }
  assert_true(out >= 0 && ir >= 0);
  double *x = malloc(sizeof(double) * (size_t)sw_traj_len(s));
  for (long task = 0; task < 2; task++) {       /* theta, adaptive */
    sw_result r;
    sw_run_job(s, s->n_variants + task, NULL, &r, x);
    assert_int_equal(r.status, CUP_OK);
    double tol = task ? 1e-9 : 2e-6, worst = 0;   /* theta: its O(h^2) and the interpolation's, ~4e-7 */
    for (int j = 0; j < 11; j++) {
      double t = j * 2e-3 / 10, v = 1 - exp(-t / 1e-3);
      const double *sig = x + 11 + j * s->nsig;
      double e = fmax(fabs(x[j] - v), fmax(fabs(sig[out] - v), 1e3 * fabs(sig[ir] - (1 - v) / 1e3)));
      worst = fmax(worst, e);
      if (!(e <= tol)) fail_msg("task %ld, t = %g: v %.17g, v(out) %.17g, i(R1) %.17g; want %.17g", task, t, x[j],
                                sig[out], sig[ir], v);
    }
    printf("# RC charge, %s: max error at the 11 sample times %.3g V\n", task ? "adaptive" : "theta n = 1005",
           worst);
  }
  free(x);
  sw_free(&s);
}

/* The reference of the paper's case 1 (n_ref auto = 4 x 10^4 for n up to
 * 10^4) against the reference limit in tests/data on t = k/1000. */
static void test_reference_vs_data(void **state) {
  (void)state;
  sw_sweep *s = load_text("base: paper-fig2.yaml\ngrid: {n: [100, 10000]}\nvariants: [{name: case1}]\n");
  assert_int_equal(s->var[0].n_ref, 40000);
  double *x = malloc(sizeof(double) * 1001 * 3);
  sw_result r;
  sw_run_job(s, 0, NULL, &r, x);
  assert_int_equal(r.status, CUP_OK);
  static double data[1001 * 3];
  ref_load("ref_case1_limit_richardson.csv", data);
  double err = ref_diff(x, data);
  printf("# reference (Richardson, n_ref = 40000) vs tests/data case-1 reference: max |diff| = %.3g; "
         "correction removed %.3g\n", err, r.correction);
  assert_true(err < 1e-6);
  assert_true(r.correction > 1e-5 && r.correction < 1e-4);   /* ~1.9e-5: x(2 n_ref) alone is off by that */
  free(x);
  sw_free(&s);
}

/* The tol axis and the adaptive reference: tasks vary tol last; the
 * reference (the adaptive scheme at tol 1e-13) agrees with the Richardson
 * limit in tests/data to that file's accuracy (about 1e-10), and an adaptive
 * task at tol 1e-9 measured against it has an error below tol with its
 * estimate within 10x. */
static void test_tol_axis_adaptive_reference(void **state) {
  (void)state;
  sw_sweep *s = load_text("base: paper-fig2.yaml\ngrid: {scheme: [explicit, adaptive], tol: [1e-6, 1e-9]}\n"
                          "variants: [{name: case1}]\nreference: {method: adaptive}\n");
  assert_int_equal(s->n_tasks, 4);
  sw_task t;
  assert_int_equal(sw_task_get(s, 3, &t), CUP_OK);
  assert_int_equal(t.scheme, CUP_SCHEME_ADAPTIVE);
  assert_true(t.tol_abs == 1e-9 && t.tol_rel == 1e-9);
  assert_int_equal(sw_task_get(s, 0, &t), CUP_OK);
  assert_true(t.scheme == CUP_SCHEME_EXPLICIT && t.tol_abs == 1e-6);
  double *ref = malloc(sizeof(double) * 1001 * 3), *x = malloc(sizeof(double) * 1001 * 3);
  sw_result r;
  sw_run_job(s, 0, NULL, &r, ref);
  assert_int_equal(r.status, CUP_OK);
  static double data[1001 * 3];
  ref_load("ref_case1_limit_richardson.csv", data);
  double ref_est = r.correction, diff = ref_diff(ref, data);
  sw_run_job(s, s->n_variants + 3, NULL, &r, x);
  double err = sw_max_error(x, ref, 1001 * 3);
  printf("# adaptive reference vs Richardson limit: %.3g (estimate %.3g); adaptive task at tol 1e-9: "
         "error %.3g, estimate %.3g, %ld events\n", diff, ref_est, err, r.err_est, (long)r.events);
  assert_true(diff < 2e-10 && ref_est < 1e-12);
  assert_int_equal(r.status, CUP_OK);
  assert_true(err <= 1e-9 * 4 && r.err_est <= 10 * err && r.err_est >= 0.1 * err);
  assert_true(r.events >= 8);
  free(ref);
  free(x);
  sw_free(&s);
}

/* reference: {method: adaptive, check: richardson}: the reference is the
 * adaptive run's, bit for bit, and cross_check is max |adaptive - Richardson|
 * recomputed from the two methods' own reference jobs (n_ref 40000: about
 * 5e-9 apart, the Richardson limit's own error there). check without
 * method: adaptive is refused. */
static void test_checked_adaptive_reference(void **state) {
  (void)state;
  const char *common = "base: paper-fig2.yaml\nvariants: [{name: case1}]\n";
  char text[256];
  snprintf(text, sizeof text, "%sreference: {method: adaptive, check: richardson, n: 40000}\n", common);
  sw_sweep *s = load_text(text);
  snprintf(text, sizeof text, "%sreference: {method: adaptive}\n", common);
  sw_sweep *sa = load_text(text);
  snprintf(text, sizeof text, "%sreference: {n: 40000}\n", common);
  sw_sweep *sr = load_text(text);
  assert_int_equal(s->var[0].n_ref, 40000);
  long count = 1001 * 3;
  double *x = malloc(sizeof(double) * (size_t)count * 3), *xa = x + count, *xr = xa + count;
  sw_result r, ra, rr;
  sw_run_job(s, 0, NULL, &r, x);
  sw_run_job(sa, 0, NULL, &ra, xa);
  sw_run_job(sr, 0, NULL, &rr, xr);
  assert_int_equal(r.status, CUP_OK);
  assert_memory_equal(x, xa, sizeof(double) * (size_t)count);
  double d = sw_max_error(xa, xr, count);
  printf("# adaptive reference vs Richardson (n_ref 40000): cross_check %.3g, recomputed %.3g\n", r.cross_check, d);
  assert_true(r.cross_check == d && d > 1e-10 && d < 1e-8);
  assert_true(isnan(rr.cross_check) && isnan(ra.cross_check));
  sw_free(&s);
  sw_free(&sa);
  sw_free(&sr);
  free(x);
  sw_sweep *bad = NULL;
  char err[SW_ERR_LEN] = "";
  snprintf(text, sizeof text, "%sreference: {check: richardson}\n", common);
  assert_int_equal(sw_parse(&bad, text, strlen(text), EX "/inline-sweep.yaml", err), CUP_ERR_PARSE);
  assert_non_null(strstr(err, "reference.check"));
  assert_non_null(strstr(err, "needs method: adaptive"));
}

/* A netlist sweep (examples/circuits/rectifier-sweep.yaml): the variant
 * RL-250 sets the load of the half-wave rectifier, whose D != 0 puts its
 * reference on the theta scheme (second-order Richardson); that reference
 * against an independent RK4 of C v' = max(0, (V - v)/Rs) - v/RL. */
static double rect_rhs(double t, double v) {
  return (fmax(0, (10 * sin(100 * 3.14159265358979323846 * t) - v) / 1) - v / 250) / 100e-6;
}

static void test_netlist_variants(void **state) {
  (void)state;
  sw_sweep *s = load_file(EX "/circuits/rectifier-sweep.yaml");
  assert_int_equal(s->n_variants, 3);
  assert_true(cup_lcs_has_D(cup_scene_lcs(s->var[1].scene)));
  long S = s->samples;
  double *x = malloc(sizeof(double) * (size_t)sw_traj_len(s));
  sw_result r;
  sw_run_job(s, 1, NULL, &r, x);
  assert_int_equal(r.status, CUP_OK);
  /* the probes of halfwave-rc.yaml follow the states: v(out) is C1's voltage, the state */
  assert_int_equal(s->nsig, 2);
  assert_string_equal(sw_signal_name(s, 0), "v(out)");
  assert_string_equal(sw_signal_name(s, 1), "i(D1)");
  for (long j = 0; j < S; j++)
    if (x[S + 2 * j] != x[j]) fail_msg("sample %ld: reference v(out) %.17g, v(C1) %.17g", j, x[S + 2 * j], x[j]);
  double T = cup_scene_options(s->var[1].scene)->T, h = T / ((double)(S - 1) * 200), v = 0, err = 0;
  for (long j = 0; j + 1 < S; j++) {
    err = fmax(err, fabs(x[j] - v));
    for (int k = 0; k < 200; k++) {
      double t = ((double)j * 200 + k) * h;
      double k1 = rect_rhs(t, v), k2 = rect_rhs(t + h / 2, v + h / 2 * k1);
      double k3 = rect_rhs(t + h / 2, v + h / 2 * k2), k4 = rect_rhs(t + h, v + h * k3);
      v += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
  }
  err = fmax(err, fabs(x[S - 1] - v));
  printf("# netlist variant RL-250: theta reference (n_ref = %ld) vs RK4: max |diff| = %.3g V\n",
         s->var[1].n_ref, err);
  assert_true(err < 1e-5);
  free(x);
  sw_free(&s);
}

/* The example crowd sweep (examples/crowd-sweep.yaml): 48 variants named
 * doorW-vV-sS, each a crowd of 150 agents; the start depends on the seed
 * alone (the door and the speed leave the placement alone), so variants of
 * one seed start alike and those of two seeds do not. */
static void test_crowd_sweep_example(void **state) {
  (void)state;
  sw_sweep *s = load_file(EX "/crowd-sweep.yaml");
  assert_int_equal(s->n_variants, 48);
  assert_true(s->crowd);
  const double *q0_of_seed[7] = {NULL};
  for (int v = 0; v < s->n_variants; v++) {
    double w, speed;
    int seed;
    assert_int_equal(sscanf(s->var[v].name, "door%lf-v%lf-s%d", &w, &speed, &seed), 3);
    assert_true(seed >= 1 && seed <= 6);
    const cup_crowd *c = cup_scene_crowd(s->var[v].scene);
    assert_non_null(c);
    assert_int_equal(cup_crowd_agents(c), 150);
    const double *q0 = cup_crowd_q0(c);
    if (!q0_of_seed[seed])
      q0_of_seed[seed] = q0;
    else
      assert_memory_equal(q0, q0_of_seed[seed], sizeof(double) * 300);
  }
  for (int seed = 2; seed <= 6; seed++)
    assert_true(memcmp(q0_of_seed[1], q0_of_seed[seed], sizeof(double) * 300) != 0);
  /* a crowd task's cost counts its agents: a step of 150 agents takes about
   * 0.7 us each (BENCHMARKS.md, "Crowds"), 1000 times the circuit's 0.1 us
   * unit; counted as a circuit step, 180 of them made one 20 ms batch */
  for (long j = s->n_variants; j < s->n_variants + s->n_tasks; j++) {
    sw_task t;
    assert_int_equal(sw_task_get(s, j - s->n_variants, &t), CUP_OK);
    assert_true(sw_job_cost(s, j) >= 0.7 / 0.1 * 150 * (double)t.n);
  }
  sw_free(&s);
}

/* /summary columns read back through HDF5 (names as documented). */
typedef struct { int64_t task_id; int8_t done; int32_t status; double error; int64_t stopped_step; } row_view;

static void read_back(const char *path, row_view *rows, double *x) {
  hid_t file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(file >= 0);
  hid_t t = H5Tcreate(H5T_COMPOUND, sizeof(row_view));
  H5Tinsert(t, "task_id", HOFFSET(row_view, task_id), H5T_NATIVE_INT64);
  H5Tinsert(t, "done", HOFFSET(row_view, done), H5T_NATIVE_INT8);
  H5Tinsert(t, "status", HOFFSET(row_view, status), H5T_NATIVE_INT32);
  H5Tinsert(t, "error", HOFFSET(row_view, error), H5T_NATIVE_DOUBLE);
  H5Tinsert(t, "stopped_step", HOFFSET(row_view, stopped_step), H5T_NATIVE_INT64);
  hid_t d = H5Dopen2(file, "summary", H5P_DEFAULT), dx = H5Dopen2(file, "runs/x", H5P_DEFAULT);
  assert_true(H5Dread(d, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows) >= 0);
  assert_true(H5Dread(dx, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, x) >= 0);
  H5Dclose(dx);
  H5Dclose(d);
  H5Tclose(t);
  H5Fclose(file);
}

/* Tasks written in one call, in runs of consecutive ids (1-3, 7, 9-10), land
 * in their own rows of /summary and /runs/x and nowhere else; a reference
 * that comes later fills the errors of its variant's tasks written without
 * one: with x = 100 id + k and x_ref = k the error is 100 id, failures
 * keep NaN. */
static void test_batched_writes(void **state) {
  (void)state;
  sw_sweep *s = load_text("base: paper-fig2.yaml\ngrid: {n: [10, 20, 30, 40, 50, 60]}\n"
                          "variants: [{name: a}, {name: b, set: {circuit.R1: 2}}]\nreference: {samples: 3}\n");
  enum { N = 12, K = 9, W = 6 };                  /* tasks; samples x dim; tasks written */
  assert_int_equal(s->n_tasks, N);
  assert_int_equal(s->samples * s->dim, K);
  const char *path = CUP_TEST_OUT_DIR "/batched_writes.h5";
  char err[SW_ERR_LEN] = "";
  sw_file *f = NULL;
  sw_provenance p = {"test", "test", "test", "test"};
  assert_int_equal(sw_file_create(&f, path, s, &p, err), CUP_OK);
  const long task[W] = {1, 2, 3, 7, 9, 10};
  const int status[W] = {CUP_OK, CUP_OK, CUP_WARN_NOT_CERTIFIED, CUP_ERR_DIVERGED, CUP_OK, CUP_OK};
  sw_result r[W];
  double x[W][K];
  sw_task_out out[W];
  for (int j = 0; j < W; j++) {
    memset(&r[j], 0, sizeof r[j]);
    r[j].job = s->n_variants + task[j];
    r[j].status = status[j];
    r[j].stopped_step = 1000 + task[j];
    for (int k = 0; k < K; k++) x[j][k] = 100.0 * (double)task[j] + k;
    out[j] = (sw_task_out){task[j], &r[j], x[j], task[j] < 6 ? 0.5 * (double)task[j] : NAN};
  }
  sw_task_out swapped[2] = {out[1], out[0]};
  assert_int_equal(sw_file_write_tasks(f, swapped, 2), CUP_ERR_ARG);     /* not in order: nothing written */
  assert_non_null(strstr(sw_file_errmsg(f), "cannot write task 1 (after task 2)"));
  assert_int_equal(sw_file_write_tasks(f, out, W), CUP_OK);
  double xref[K];
  for (int k = 0; k < K; k++) xref[k] = k;
  sw_result rr;
  memset(&rr, 0, sizeof rr);
  rr.job = 1;
  assert_int_equal(sw_file_write_reference(f, 1, &rr, xref), CUP_OK);
  assert_int_equal(sw_file_fill_errors(f, 1), CUP_OK);
  assert_int_equal(sw_file_close(&f, err), CUP_OK);

  row_view rows[N];
  double back[N * K];
  read_back(path, rows, back);
  for (long t = 0, j = 0; t < N; t++) {
    int written = j < W && task[j] == t;
    assert_int_equal(rows[t].task_id, t);
    assert_int_equal(rows[t].done, written);
    assert_int_equal(rows[t].status, written ? status[j] : CUP_ERR_INTERRUPTED);
    assert_int_equal(rows[t].stopped_step, written ? 1000 + t : 0);
    double e = !written || status[j] < 0 ? NAN : t < 6 ? 0.5 * (double)t : 100.0 * (double)t;
    if (isnan(e) ? !isnan(rows[t].error) : rows[t].error != e)
      fail_msg("task %ld: error %g, expected %g", t, rows[t].error, e);
    for (int k = 0; k < K; k++)
      if (written ? back[t * K + k] != x[j][k] : !isnan(back[t * K + k]))
        fail_msg("task %ld: /runs/x entry %d is %g", t, k, back[t * K + k]);
    j += written;
  }
  remove(path);
  sw_free(&s);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_sha256_vectors),
    cmocka_unit_test(test_smoke_task_order),
    cmocka_unit_test(test_zip_groups_and_defaults),
    cmocka_unit_test(test_paper_sweep),
    cmocka_unit_test(test_bad_corpus),
    cmocka_unit_test(test_fixed_fields_fit),
    cmocka_unit_test(test_samples_between_steps),
    cmocka_unit_test(test_netlist_samples_closed_form),
    cmocka_unit_test(test_reference_vs_data),
    cmocka_unit_test(test_tol_axis_adaptive_reference),
    cmocka_unit_test(test_checked_adaptive_reference),
    cmocka_unit_test(test_netlist_variants),
    cmocka_unit_test(test_crowd_sweep_example),
    cmocka_unit_test(test_batched_writes),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

/* catchup-run end to end (the contract in docs/design.md): exit codes and one-line
 * messages; the file's datasets, grid and attributes read back through the
 * HDF5 API; the trajectory in original x coordinates against the paper's
 * reference limit; a clean stop on SIGINT and a readable file after kill -9. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <signal.h>
#include <time.h>
#include <unistd.h>
#include <fcntl.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <cmocka.h>
#include <hdf5.h>
#include "catchup.h"

#define CLI_TMPDIR_TEMPLATE "/tmp/cup_cli_XXXXXX"
#include "cliutil.h"
#include "refdata.h"

static const char *fig2 = CUP_EXAMPLES_DIR "/paper-fig2.yaml";

static void expect_exit(const result *r, int code, int lines) {
  if (!r->exited || r->code != code || r->lines != lines)
    fail_msg("exit %d (signal %d) with %d stderr lines, expected exit %d with %d:\n%s",
             r->code, r->sig, r->lines, code, lines, r->err);
}

static void expect_in_err(const result *r, const char *text) {
  if (!strstr(r->err, text)) fail_msg("stderr lacks '%s':\n%s", text, r->err);
}

/* catchup-run ARGS exits with code and says text in one line of stderr. */
static void expect_says(const char *const *args, int code, const char *text) {
  result r = run_cli(args, 0, 0);
  expect_exit(&r, code, 1);
  expect_in_err(&r, text);
}

/* ---- reading the file ---- */

static void expect_attr_str(hid_t f, const char *name, const char *expect) {
  char s[4096];
  attr_str(f, name, s, sizeof s);
  if (strcmp(s, expect) != 0) fail_msg("attribute %s = '%s', expected '%s'", name, s, expect);
}

static int has_attr(hid_t f, const char *name) { return H5Aexists(f, name) > 0; }

/* The run's file OUT, opened for reading (the test fails if it cannot be). */
static hid_t open_out(const char *out) {
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  return f;
}

/* max |x - ref| of file f's 1001 rows against tests/data/NAME, checking
 * that t holds the times k/1000 exactly: the grid k h of a fixed-step run,
 * or the output times j T / (N - 1) of an adaptive one. */
static double diff_to_data(hid_t f, const char *name) {
  static double ref[1001 * 3];
  double *t, *x;
  assert_int_equal(read_rows(f, "t", 1, 1, &t), 1001);
  assert_int_equal(read_rows(f, "x", 2, 3, &x), 1001);
  ref_load(name, ref);
  for (int k = 0; k <= 1000; k++) assert_true(t[k] == (double)k * (1.0 / 1000) || t[k] == (double)k / 1000);
  double err = ref_diff(x, ref);
  free(t);
  free(x);
  return err;
}

/* ---- tests ---- */

/* The paper's case 1 at n = 1000: the grid is t_k = k h exactly, the rows are
 * x (not z = R x: x2 would be off by sqrt(L3)), and the error against the
 * reference limit is the first-order error the paper's scheme has, ~1.52/n. */
static void test_paper_case1_file(void **state) {
  (void)state;
  const char *out = tmp_path("case1.h5");
  const char *args[] = {fig2, "-o", out, "--n", "1e3", "--quiet", NULL};
  result r = run_cli(args, 0, 0);
  expect_exit(&r, 0, 0);
  hid_t f = open_out(out);
  double err = diff_to_data(f, "ref_case1_limit_richardson.csv");
  if (!(err > 1.0e-3 && err < 2.0e-3)) fail_msg("max error %.3g, expected ~1.52e-3", err);
  assert_true(attr_i64(f, "n") == 1000);
  assert_true(attr_f64(f, "T") == 1.0);
  assert_true(attr_i64(f, "samples") == 1001);
  assert_true(attr_i64(f, "status") == 0);
  assert_true(attr_i64(f, "stopped_step") == 1000);
  assert_true(attr_i64(f, "projected") + attr_i64(f, "skipped") == 1000);
  assert_true(fabs(attr_f64(f, "eps_value") / pow(1000, -2.1) - 1) < 1e-12);
  assert_true(attr_f64(f, "wall_time_s") >= 0);
  expect_attr_str(f, "status_name", "CUP_OK");
  expect_attr_str(f, "message", "");
  expect_attr_str(f, "eps", "n^-2.1");
  expect_attr_str(f, "scheme", "explicit");
  expect_attr_str(f, "scene_file", fig2);
  expect_attr_str(f, "catchup_version", cup_version());
  const char *need[] = {"eta", "eta_value", "projector", "dependency_versions", "scene",
                        "not_certified", "dual_iterations", "factorizations", "max_eps_cert",
                        "max_eta_cert", "h_rho", "stopped_t"};
  for (size_t i = 0; i < sizeof need / sizeof need[0]; i++)
    if (!has_attr(f, need[i])) fail_msg("attribute %s missing", need[i]);
  H5Fclose(f);
}

/* The adaptive scheme through the command line: --tol, the summary line
 * with the estimate, /events with one row per change of the active set
 * (the attribute events), in time order, and the trajectory against the
 * adaptive reference within the estimate's 10x. */
static void test_adaptive_file(void **state) {
  (void)state;
  const char *out = tmp_path("adaptive.h5");
  const char *args[] = {fig2, "-o", out, "--scheme", "adaptive", "--tol", "1e-8", "--set",
                        "output={samples: 1001}", NULL};
  result r = run_cli(args, 0, 0);
  expect_exit(&r, 0, 1);
  expect_in_err(&r, "tol=1e-08/1e-08 adaptive");
  expect_in_err(&r, "error estimate");
  hid_t f = open_out(out);
  double err = diff_to_data(f, "ref_case1_adaptive.csv");
  double est = attr_f64(f, "err_est");
  print_message("catchup-run --scheme adaptive --tol 1e-8: error %.3e, err_est %.3e, %ld events\n", err, est,
                (long)attr_i64(f, "events"));
  assert_true(err <= 3e-8 && est <= 10 * err && est >= 0.1 * err);
  assert_true(attr_f64(f, "tol_abs") == 1e-8 && attr_f64(f, "tol_rel") == 1e-8);
  expect_attr_str(f, "scheme", "adaptive");
  /* /events: (t, row, on) */
  typedef struct { double t; int32_t row; int8_t on; } ev;
  hsize_t ne = 0;
  ev *e = read_events(f, sizeof(ev), HOFFSET(ev, t), HOFFSET(ev, row), HOFFSET(ev, on), &ne);
  assert_true((long)ne == attr_i64(f, "events") && ne >= 8);
  for (hsize_t k = 0; k < ne; k++) {
    assert_true(e[k].row >= 0 && e[k].row < 2 && (e[k].on == 0 || e[k].on == 1));
    if (k) assert_true(e[k].t >= e[k - 1].t);
  }
  /* case 1 starts with row 1 (x2 >= 0) pushed on at t = 0 */
  assert_true(e[0].t == 0 && e[0].row == 1 && e[0].on == 1);
  free(e);
  H5Fclose(f);
  const char *bad[] = {fig2, "-o", out, "--tol", "-1e-8", NULL};
  expect_says(bad, 2, "--tol '-1e-8': not a positive number");
}

static void test_summary_line_and_overrides(void **state) {
  (void)state;
  const char *out = tmp_path("summary.h5");
  char oarg[300];
  snprintf(oarg, sizeof oarg, "--output=%s", out);
  const char *args2[] = {fig2, oarg, "--n=50", "--eps", "1e-9", "--scheme", "implicit",
                         "--set", "output.every=10", NULL};
  result r = run_cli(args2, 0, 0);
  expect_exit(&r, 0, 1);
  expect_in_err(&r, "n=50 implicit, 6 samples");
  hid_t f = open_out(out);
  assert_true(attr_i64(f, "n") == 50);
  assert_true(attr_f64(f, "eps_value") == 1e-9);
  expect_attr_str(f, "scheme", "implicit");
  double *t;
  assert_int_equal(read_rows(f, "t", 1, 1, &t), 6);
  assert_true(t[5] == 50 * (1.0 / 50));
  free(t);
  H5Fclose(f);
}

/* --help and the flags' messages name every scheme and projector method of
 * the library's lists; --set output.samples=N replaces the scene's mode. */
static void test_help_lists_and_output_override(void **state) {
  (void)state;
  const char *help[] = {"--help", NULL};
  result r = run_cli(help, 0, 0);
  expect_exit(&r, 0, 0);
  char line[128];
  for (int k = 0; k < CUP_SCHEME_COUNT; k++) {
    snprintf(line, sizeof line, "%s%s", k == 0 ? "--scheme NAME        " : k + 1 < CUP_SCHEME_COUNT ? ", " : " or ",
             cup_scheme_name(k));
    if (!strstr(r.out, line)) fail_msg("--help lacks '%s':\n%s", line, r.out);
  }
  assert_non_null(strstr(r.out, "theta"));
  for (int k = 0; k < CUP_PROJ_METHOD_COUNT; k++)
    if (!strstr(r.out, cup_proj_method_name(k))) fail_msg("--help lacks method %s", cup_proj_method_name(k));
  const char *bad[] = {fig2, "-o", tmp_path("x.h5"), "--scheme", "thet", NULL};
  expect_says(bad, 2, "unknown scheme (explicit, implicit, exponential, theta or adaptive)");

  const char *out = tmp_path("samples.h5");
  const char *args[] = {fig2, "-o", out, "--set", "output.samples=2", "--quiet", NULL};
  r = run_cli(args, 0, 0);
  expect_exit(&r, 0, 0);
  hid_t f = open_out(out);
  double *t;
  assert_int_equal(read_rows(f, "t", 1, 1, &t), 2);
  assert_true(t[0] == 0 && t[1] == 1);
  free(t);
  H5Fclose(f);
}

/* Each failure: the exit code and exactly one stderr line naming the thing. */
static void test_errors_are_one_line(void **state) {
  (void)state;
  const char *out = tmp_path("err.h5");
  struct { const char *args[8]; int code; const char *says; } cases[] = {
    {{fig2, NULL}, 2, "-o OUT.h5"},
    {{"-o", out, NULL}, 2, "no scene"},
    {{fig2, "-o", out, "--n", "12x", NULL}, 2, "--n '12x'"},
    {{fig2, "-o", out, "--n", "2.5", NULL}, 2, "--n '2.5': not a positive integer"},
    {{fig2, "-o", out, "--eps", "banana", NULL}, 2, "banana"},
    {{fig2, "-o", out, "--scheme", "rk4", NULL}, 2, "rk4"},
    {{fig2, "-o", out, "--projector", "nope", NULL}, 2, "nope"},
    {{fig2, "-o", out, "--frob", NULL}, 2, "--frob"},
    {{fig2, "-o", out, "--set", "novalue", NULL}, 2, "novalue"},
    {{fig2, "-o", out, "--set", "bogus=1", NULL}, 1, "bogus"},
    {{fig2, "-o", out, "--set", "circuit.R1=-1", NULL}, 1, "circuit.R1"},
    {{"/no/such/scene.yaml", "-o", out, NULL}, 1, "/no/such/scene.yaml"},
    {{fig2, "-o", "/no/such/dir/out.h5", NULL}, 1, "/no/such/dir/out.h5"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    result r = run_cli(cases[i].args, 0, 0);
    expect_exit(&r, cases[i].code, 1);
    expect_in_err(&r, cases[i].says);
  }
}

/* A warning: one line, exit 0 (with --quiet, nothing else). */
static void test_warning_exits_zero(void **state) {
  (void)state;
  const char *out = tmp_path("warn.h5");
  const char *args[] = {fig2, "-o", out, "--n", "20", "--projector", "pg", "--eps", "1e-40",
                        "--eta", "1e-40", "--set", "output=final", "--quiet", NULL};
  result r = run_cli(args, 0, 0);
  expect_exit(&r, 0, 1);
  expect_in_err(&r, "warning");
  expect_in_err(&r, "CUP_WARN_NOT_CERTIFIED");
  hid_t f = open_out(out);
  assert_true(attr_i64(f, "status") == CUP_WARN_NOT_CERTIFIED);
  H5Fclose(f);
}

/* A crowd whose contact margin is next to nothing (crowd.margin = 1e-9):
 * a step's rows hold only the contacts already touching, so the first
 * answer of most steps has agents overlapping; the crowd finds the contacts
 * its rows missed, and the step is projected again with their rows
 * (/steps/added counts them). No state then overlaps beyond sqrt 2 eta of the
 * step that made it, every step is certified, and catchup-run prints no
 * overlap warning (it did, with overlaps of 0.4 m, before the steps were
 * rechecked). With the default margin the same crowd misses no contact. */
static void test_crowd_missed_contacts(void **state) {
  (void)state;
  const char *scene = tmp_text("jam.yaml",
      "crowd:\n"
      "  room: [[0, 0], [6, 0], [6, 4], [0, 4]]\n"
      "  doors: [[[6, 1.5], [6, 2.5]]]\n"
      "  agents: {count: 25, radius: 0.25, spread: 0.0, region: [0.5, 0.5, 4, 3.5], seed: 3}\n"
      "  speed: 1.5\n"
      "T: 4\nn: 80\noutput: {every: 10}\n");
  const char *out = tmp_path("jam.h5");
  for (int tiny = 0; tiny <= 1; tiny++) {
    const char *args[] = {scene, "-o", out, "--set", tiny ? "crowd.margin=1e-9" : "crowd.grid=0.1", NULL};
    result r = run_cli(args, 0, 0);
    expect_exit(&r, 0, 2);
    assert_null(strstr(r.err, "overlap"));
    hid_t f = open_out(out);
    double *gap, *eta, *added, total = 0;
    hsize_t n = read_rows(f, "steps/gap", 1, 1, &gap);
    assert_true(read_rows(f, "steps/eta_cert", 1, 1, &eta) == n && n == 81);
    assert_true(read_rows(f, "steps/added", 1, 1, &added) == n);
    for (hsize_t k = 1; k < n; k++) {
      if (-gap[k] - sqrt(2) * eta[k] > 1e-9 * 0.25)      /* the app's rounding allowance */
        fail_msg("margin %s, step %d: gap %.3g, eta %.3g", tiny ? "1e-9" : "default", (int)k, gap[k], eta[k]);
      assert_true(eta[k] <= 0.01);                       /* certified: eta_n = 80^-1.05 */
      total += added[k];
    }
    if (tiny) assert_true(total > 100);
    else assert_true(total == 0);
    free(gap);
    free(eta);
    free(added);
    H5Fclose(f);
  }
}

/* Rows k = 0, 1000, 2000, ... of a run too long to finish (but the last
 * when it is the stop's row, flagged by stop_row); *last = t of the last. */
static void check_prefix(hid_t f, hsize_t *rows, double *last) {
  double *t, *x;
  hsize_t nt = read_rows(f, "t", 1, 1, &t), nx = read_rows(f, "x", 2, 3, &x);
  *rows = nt < nx ? nt : nx;
  hsize_t samples = H5Aexists(f, "stop_row") > 0 ? *rows - 1 : *rows;
  for (hsize_t j = 0; j < samples; j++)
    if (t[j] != (double)(j * 1000) * (1.0 / 1000000000))
      fail_msg("t[%llu] = %.17g", (unsigned long long)j, t[j]);
  *last = *rows ? t[*rows - 1] : NAN;
  free(t);
  free(x);
}

/* A run of the paper's circuit long enough to be stopped, into out. */
static void long_run_args(const char *args[9], const char *out) {
  static const char *long_run[] = {NULL, "-o", NULL, "--n", "1000000000", "--set",
                                   "output.every=1000", "--quiet", NULL};
  memcpy(args, long_run, sizeof long_run);
  args[0] = fig2;
  args[2] = out;
}

static void test_sigint_stops_cleanly(void **state) {
  (void)state;
  const char *out = tmp_path("sigint.h5");
  const char *args[9];
  long_run_args(args, out);
  result r = run_cli(args, 1.5, SIGINT);
  if (r.sig != SIGINT || r.lines != 1) fail_msg("signal %d, %d lines:\n%s", r.sig, r.lines, r.err);
  expect_in_err(&r, "stopped by SIGINT");
  expect_in_err(&r, "as its last row (stop_row), the state there: continue with --resume");
  hid_t f = open_out(out);
  hsize_t rows;
  double last;
  check_prefix(f, &rows, &last);
  assert_true(rows > 1);
  assert_true(attr_i64(f, "status") == CUP_ERR_INTERRUPTED);
  assert_true(attr_i64(f, "samples") == (int64_t)rows);
  assert_true(attr_i64(f, "stop_row") == (int64_t)rows - 1);     /* the state where it stopped */
  assert_true(last == attr_f64(f, "stopped_t"));
  expect_attr_str(f, "status_name", "CUP_ERR_INTERRUPTED");
  H5Fclose(f);
}

/* kill -9: no chance to clean up; the file opens as is and says "running". */
static void test_kill9_file_readable(void **state) {
  (void)state;
  const char *out = tmp_path("kill9.h5");
  const char *args[9];
  long_run_args(args, out);
  result r = run_cli(args, 2.5, SIGKILL);
  assert_int_equal(r.sig, SIGKILL);
  hid_t f = open_out(out);
  hsize_t rows;
  double last;
  check_prefix(f, &rows, &last);
  assert_true(rows > 0);          /* at least the flush of the first second */
  expect_attr_str(f, "status_name", "running");
  assert_false(has_attr(f, "wall_time_s"));
  H5Fclose(f);
}

/* An output file another process holds open (HDF5 locks it) is not
 * truncated: one line says it is in use, and the file keeps its rows. */
static void test_output_in_use(void **state) {
  (void)state;
  const char *out = tmp_path("held.h5");
  const char *first[] = {fig2, "-o", out, "--quiet", NULL};
  result r = run_cli(first, 0, 0);
  expect_exit(&r, 0, 0);
  hid_t f = open_out(out);                                  /* this process now holds it */
  const char *again[] = {fig2, "-o", out, "--n", "10", NULL};
  r = run_cli(again, 0, 0);
  expect_exit(&r, 1, 1);
  expect_in_err(&r, "is in use by another process (HDF5 file locking)");
  expect_in_err(&r, out);
  double *t;
  assert_int_equal(read_rows(f, "t", 1, 1, &t), 101);        /* the first run's rows, intact */
  assert_true(t[100] == 1);
  free(t);
  H5Fclose(f);
}

/* A netlist runs directly: /signals/<name> in the probes' order (their
 * `names` attribute), each row Kirchhoff's laws on the state and the
 * source (v(out) the capacitor's voltage, v(in) the sine), the state's
 * names; --set changes an element, --probe on a scene without a netlist
 * and an unknown signal are one-line errors. */
static void test_netlist_signals(void **state) {
  (void)state;
  const char *cir = CUP_EXAMPLES_DIR "/circuits/halfwave-rc.cir", *out = tmp_path("netlist.h5");
  const char *args[] = {cir, "-o", out, "--probe", "v(out)", "--probe", "V(IN)", "--set", "netlist.RL=500", NULL};
  result r = run_cli(args, 0, 0);
  expect_exit(&r, 0, 1);
  /* SPICE's meaning: the adaptive scheme to the default .options (RELTOL
   * 1e-6; CHGTOL 1e-14 over C1's 100 uF), sampled every TSTEP = 20 us */
  expect_in_err(&r, "tol=1e-10/1e-06 adaptive");
  expect_in_err(&r, "3001 samples");
  hid_t f = open_out(out);
  expect_attr_str(f, "state_names", "v(C1)");
  double *t, *x, *vout, *vin;
  hsize_t n = read_rows(f, "t", 1, 1, &t);
  assert_int_equal(n, 3001);
  assert_int_equal(read_rows(f, "x", 2, 1, &x), n);
  assert_int_equal(read_rows(f, "signals/v(out)", 1, 1, &vout), n);
  assert_int_equal(read_rows(f, "signals/v(in)", 1, 1, &vin), n);
  for (hsize_t k = 0; k < n; k++) {
    assert_true(vout[k] == x[k]);
    assert_true(fabs(vin[k] - 10 * sin(100 * 3.14159265358979323846 * t[k])) <= 1e-12);
    assert_true(fabs(t[k] - 0.06 * (double)k / 3000) <= 1e-18);
  }
  hid_t g = H5Gopen2(f, "signals", H5P_DEFAULT), a = H5Aopen(g, "names", H5P_DEFAULT);
  hid_t type = H5Aget_type(a);
  char *names[2] = {NULL, NULL};
  assert_true(H5Aread(a, type, names) >= 0);
  assert_string_equal(names[0], "v(out)");
  assert_string_equal(names[1], "v(in)");
  H5free_memory(names[0]);
  H5free_memory(names[1]);
  H5Tclose(type); H5Aclose(a); H5Gclose(g);
  H5Fclose(f);
  free(t); free(x); free(vout); free(vin);
  const char *noprobe[] = {fig2, "-o", out, "--probe", "v(a)", NULL};
  expect_says(noprobe, 1, "--probe: the scene has no netlist");
  const char *unknown[] = {cir, "-o", out, "--probe", "i(R9)", NULL};
  expect_says(unknown, 1, "probe 'i(R9)': no element named 'R9'");
  const char *bad[] = {CUP_SOURCE_DIR "/tests/netlists/bad/inductor-cutset.cir", "-o", out, NULL};
  expect_says(bad, 1, "inductor-cutset.cir:4:1: L1: L1 and L2 form a cutset of inductors and current sources");
}

/* Samples sparser than the steps (a step with one sample or none: its
 * batch makes no next state, and exp(dt M) is not made) against the
 * closed form of the source, v(in) = 10 sin(100 pi t), and against the
 * same times of the .tran grid's 3001 samples, whose steps hold many:
 * the flow is exact between steps, so both are the solution to the
 * run's tolerance. (A batch of one sample once read exp(dt M) unmade.) */
static void test_netlist_sparse_samples(void **state) {
  (void)state;
  const char *cir = CUP_EXAMPLES_DIR "/circuits/halfwave-rc.cir", *out = tmp_path("sparse.h5"),
             *fine = tmp_path("fine.h5");
  const char *args[] = {cir, "-o", out, "--set", "output.samples=4", "--probe", "v(in)", NULL};
  expect_says(args, 0, "4 samples");
  const char *dense[] = {cir, "-o", fine, "--probe", "v(in)", NULL};
  expect_says(dense, 0, "3001 samples");
  hid_t f = open_out(out), g = open_out(fine);
  double *t, *x, *vin, *tf, *xf;
  assert_int_equal(read_rows(f, "t", 1, 1, &t), 4);
  assert_int_equal(read_rows(f, "x", 2, 1, &x), 4);
  assert_int_equal(read_rows(f, "signals/v(in)", 1, 1, &vin), 4);
  assert_int_equal(read_rows(g, "t", 1, 1, &tf), 3001);
  assert_int_equal(read_rows(g, "x", 2, 1, &xf), 3001);
  for (int k = 0; k < 4; k++) {
    assert_true(t[k] == tf[1000 * k]);
    assert_true(fabs(vin[k] - 10 * sin(100 * 3.14159265358979323846 * t[k])) <= 1e-12);
    assert_true(fabs(x[k] - xf[1000 * k]) <= 1e-9);
  }
  H5Fclose(f);
  H5Fclose(g);
  free(t); free(x); free(vin); free(tf); free(xf);
}

/* A fixed-step scheme is one flag away from a netlist, with its own n or h:
 * .tran's TSTEP is the output's spacing, not a step; n or h alone chooses
 * theta. */
static void test_netlist_fixed_step(void **state) {
  (void)state;
  const char *cir = CUP_EXAMPLES_DIR "/circuits/halfwave-rc.cir", *out = tmp_path("fixed.h5");
  const char *none[] = {cir, "-o", out, "--scheme", "theta", NULL};
  result r = run_cli(none, 0, 0);
  expect_exit(&r, 1, 1);
  expect_in_err(&r, "the theta scheme needs n or h: the netlist's .tran TSTEP is the output's spacing, not a step");
  const char *withn[] = {cir, "-o", out, "--scheme", "theta", "--n", "6000", NULL};
  expect_says(withn, 0, "n=6000 theta, 3001 samples");
  const char *withh[] = {cir, "-o", out, "--scheme", "theta", "--h", "1e-5", NULL};
  expect_says(withh, 0, "n=6000 theta, 3001 samples");
  const char *both[] = {cir, "-o", out, "--scheme", "theta", "--h", "1e-5", "--n", "3", NULL};
  expect_says(both, 1, "h: give n or h, not both");
  const char *nalone[] = {cir, "-o", out, "--n", "6000", NULL};
  expect_says(nalone, 0, "n=6000 theta, 3001 samples");
  const char *halone[] = {cir, "-o", out, "--h", "1e-5", NULL};
  expect_says(halone, 0, "n=6000 theta, 3001 samples");
}

/* A rectifier whose diode has D != 0 (behind the source's resistance) is
 * refused by the explicit scheme with one line naming the diode and the
 * schemes that run it. */

static void test_explicit_refuses_D(void **state) {
  (void)state;
  const char *scene = CUP_EXAMPLES_DIR "/circuits/halfwave-rc.yaml", *out = tmp_path("explicit-D.h5");
  const char *args[] = {scene, "-o", out, "--scheme", "explicit", "--n", "3000", NULL};
  result r = run_cli(args, 0, 0);
  expect_exit(&r, 1, 1);
  expect_in_err(&r, "halfwave-rc.yaml: the explicit scheme needs D = 0");
  expect_in_err(&r, "row D1 has D != 0");
  expect_in_err(&r, "use the theta or the adaptive scheme");
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_netlist_signals),
    cmocka_unit_test(test_netlist_sparse_samples),
    cmocka_unit_test(test_explicit_refuses_D),
    cmocka_unit_test(test_netlist_fixed_step),
    cmocka_unit_test(test_paper_case1_file),
    cmocka_unit_test(test_adaptive_file),
    cmocka_unit_test(test_summary_line_and_overrides),
    cmocka_unit_test(test_help_lists_and_output_override),
    cmocka_unit_test(test_errors_are_one_line),
    cmocka_unit_test(test_warning_exits_zero),
    cmocka_unit_test(test_sigint_stops_cleanly),
    cmocka_unit_test(test_kill9_file_readable),
    cmocka_unit_test(test_output_in_use),
    cmocka_unit_test(test_crowd_missed_contacts),
  };
  return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}

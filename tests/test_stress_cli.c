/* Stress through catchup-run: a run that stops on an error keeps everything
 * it computed. K(t) empty at a step (tests/scenes/stress/empty-at-step.yaml)
 * and a diverging stiff explicit run (stiff-clamp-rlc.yaml): exit 1, one
 * stderr line with the step, the time and the cause (Farkas certificate;
 * h*rho), and the HDF5 file, read back here through the HDF5 C API, holds
 * rows 0..k-1, equal to a run truncated before step k. NaN/Inf in a scene
 * and in an override: exit 1, one line with file:line:col and the key. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <fcntl.h>
#include <unistd.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <cmocka.h>
#include <hdf5.h>
#include "catchup.h"

#define SCENES CUP_SOURCE_DIR "/tests/scenes"

#define CLI_TMPDIR_TEMPLATE "/tmp/cup_stress_cli_XXXXXX"
#include "cliutil.h"

static void expect_in(const char *text, const char *want) {
  if (!strstr(text, want)) fail_msg("'%s' not in:\n%s", want, text);
}

typedef struct { hsize_t rows; double *t, *x; int64_t status, stopped_step; double stopped_t; char msg[512]; } h5file;

static void load(const char *path, int dim, h5file *o) {
  hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) fail_msg("cannot open %s", path);
  o->rows = read_rows(f, "t", 1, 1, &o->t);
  assert_true(read_rows(f, "x", 2, (hsize_t)dim, &o->x) == o->rows);
  o->status = attr_i64(f, "status");
  o->stopped_step = attr_i64(f, "stopped_step");
  o->stopped_t = attr_f64(f, "stopped_t");
  assert_true(attr_i64(f, "samples") == (int64_t)o->rows);
  attr_str(f, "message", o->msg, sizeof o->msg);
  H5Fclose(f);
}

static void unload(h5file *o) { free(o->t); free(o->x); }

/* K(t) empties at step 110 (t = 110/128): the run stops there; rows 0..109
 * are in the file and equal, bit for bit, those of the same scene run to
 * T = 109/128 with n = 109 (the same grid h = 1/128). */
static void test_empty_set_keeps_prefix(void **state) {
  (void)state;
  const char *scene = SCENES "/stress/empty-at-step.yaml";
  const char *out = tmp_path("empty.h5"), *ref = tmp_path("truncated.h5");
  const char *a1[] = {scene, "-o", out, NULL};
  result r = run_cli(a1, 0, 0);
  if (r.code != 1 || r.lines != 1) fail_msg("exit %d with %d lines:\n%s", r.code, r.lines, r.err);
  expect_in(r.err, scene);
  expect_in(r.err, "CUP_ERR_EMPTY_SET");
  expect_in(r.err, "step 110 (t = 0.859375)");
  expect_in(r.err, "Farkas certificate");
  expect_in(r.err, out);                       /* "the samples before it are in OUT" */
  h5file a, b;
  load(out, 2, &a);
  assert_int_equal(a.status, CUP_ERR_EMPTY_SET);
  assert_int_equal(a.stopped_step, 109);       /* steps 1..109 completed */
  assert_true(a.stopped_t == 109.0 / 128);
  assert_int_equal(a.rows, a.stopped_step + 1);
  expect_in(a.msg, "step 110");
  expect_in(a.msg, "Farkas");
  const char *a2[] = {scene, "-o", ref, "--set", "T=0.8515625", "--n", "109", "--quiet", NULL};
  r = run_cli(a2, 0, 0);
  if (r.code != 0) fail_msg("truncated run: exit %d:\n%s", r.code, r.err);
  load(ref, 2, &b);
  assert_int_equal(b.status, CUP_OK);
  assert_int_equal(b.rows, 110);
  for (hsize_t k = 0; k < 110; k++) {
    assert_true(a.t[k] == (double)k / 128 && b.t[k] == a.t[k]);
    if (a.x[2 * k] != b.x[2 * k] || a.x[2 * k + 1] != b.x[2 * k + 1])
      fail_msg("row %llu: (%.17g, %.17g) vs truncated run (%.17g, %.17g)", (unsigned long long)k,
               a.x[2 * k], a.x[2 * k + 1], b.x[2 * k], b.x[2 * k + 1]);
  }
  /* the rows are a real trajectory: pushed up by the moving bound x1 >= u1 */
  assert_true(a.x[2 * 109] >= -5 + 7 * (109.0 / 128) - 1e-12 && a.x[2 * 109] <= 1 + 1e-12);
  unload(&a);
  unload(&b);
}

/* The stiff explicit run overflows: exit 1 naming the step, the time and
 * h*rho; every row before it is finite and in the file. */
static void test_divergence_keeps_prefix(void **state) {
  (void)state;
  const char *scene = SCENES "/stress/stiff-clamp-rlc.yaml";
  const char *out = tmp_path("stiff.h5");
  const char *args[] = {scene, "-o", out, NULL};
  result r = run_cli(args, 0, 0);
  if (r.code != 1 || r.lines != 1) fail_msg("exit %d with %d lines:\n%s", r.code, r.lines, r.err);
  expect_in(r.err, "CUP_ERR_DIVERGED");
  expect_in(r.err, "h*rho(A) = 1e+04 > 2");
  h5file a;
  load(out, 2, &a);
  assert_int_equal(a.status, CUP_ERR_DIVERGED);
  assert_int_equal(a.rows, a.stopped_step + 1);
  char want[64];
  snprintf(want, sizeof want, "step %lld (t = ", (long long)a.stopped_step + 1);
  expect_in(r.err, want);
  for (hsize_t k = 0; k < a.rows; k++) {
    assert_true(a.t[k] == (double)k * (0.02 / 2000));
    assert_true(isfinite(a.x[2 * k]) && isfinite(a.x[2 * k + 1]));
  }
  print_message("stiff explicit through catchup-run: %s\n", a.msg);
  unload(&a);
  /* the implicit scheme runs it through */
  const char *args2[] = {scene, "-o", out, "--scheme", "implicit", "--quiet", NULL};
  r = run_cli(args2, 0, 0);
  if (r.code != 0 || r.lines != 0) fail_msg("implicit: exit %d:\n%s", r.code, r.err);
  load(out, 2, &a);
  assert_int_equal(a.rows, 2001);
  assert_int_equal(a.status, CUP_OK);
  unload(&a);
}

/* The paper's circuit with L2 = 1e-9 (diverging-paper.yaml) under the
 * explicit scheme: the fused steps of a small LCS, every state stored or
 * only the last, and the projector pg: each exits 1 with CUP_ERR_DIVERGED
 * at the same step, the first whose state has ||x||_1 > 1e150, the rows
 * before it in the file and within that range. */
static void test_divergence_every_stride(void **state) {
  (void)state;
  const char *scene = SCENES "/stress/diverging-paper.yaml";
  const char *out = tmp_path("diverging.h5");
  long named = -1;
  const char *extra[][4] = {{"--quiet", NULL}, {"--set", "output=final", "--quiet", NULL},
                            {"--set", "output.every=7", "--quiet", NULL}, {"--projector", "pg", "--quiet", NULL}};
  for (int v = 0; v < 4; v++) {
    const char *args[8] = {scene, "-o", out};
    for (int j = 0; extra[v][j]; j++) args[3 + j] = extra[v][j];
    result r = run_cli(args, 0, 0);
    if (r.code != 1 || r.lines != 1) fail_msg("variant %d: exit %d with %d lines:\n%s", v, r.code, r.lines, r.err);
    expect_in(r.err, "CUP_ERR_DIVERGED");
    expect_in(r.err, "the state left its range ||x||_1 <= 1e+150");
    expect_in(r.err, "h*rho(A) = 3e+07 > 2");
    h5file a;
    load(out, 3, &a);
    assert_int_equal(a.status, CUP_ERR_DIVERGED);
    if (v == 0) named = (long)a.stopped_step + 1;
    assert_int_equal(a.stopped_step + 1, named);
    char want[64];
    snprintf(want, sizeof want, "step %ld (t = ", named);
    expect_in(r.err, want);
    expect_in(a.msg, want);
    for (hsize_t k = 0; k < a.rows; k++) {
      double n1 = fabs(a.x[3 * k]) + fabs(a.x[3 * k + 1]) + fabs(a.x[3 * k + 2]);
      if (!(n1 <= 1e150)) fail_msg("variant %d: row %llu has ||x||_1 = %g", v, (unsigned long long)k, n1);
    }
    assert_int_equal(a.rows, v == 0 || v == 3 ? named : v == 1 ? 0 : (named - 1) / 7 + 1);
    unload(&a);
  }
  assert_int_equal(named, 71);
}

/* A polyset and a ball with x0 on a face of the polyset
 * (intersection-face.yaml): the drift presses the point into the face and
 * slides it up to the corner of the face and the circle; the closed form
 * x(t) = (0.5, min(0.5 + t, 1.5)) holds at every step, each certified
 * (eta 0). Main stored a stale point at step 100 (eta = inf). Without the
 * drift the point stays at x0, on the face (main stored (0, 0) at step 1). */
static void test_intersection_on_a_face(void **state) {
  (void)state;
  const char *scene = SCENES "/stress/intersection-face.yaml";
  const char *out = tmp_path("face.h5");
  for (int drift = 1; drift >= 0; drift--) {
    const char *args[] = {scene, "-o", out, "--quiet", drift ? NULL : "--set", "f.b=[0, 0]", NULL};
    result r = run_cli(args, 0, 0);
    if (r.code != 0 || r.lines != 0) fail_msg("drift %d: exit %d:\n%s", drift, r.code, r.err);
    h5file a;
    load(out, 2, &a);
    assert_int_equal(a.status, CUP_OK);
    assert_int_equal(a.rows, 201);
    for (hsize_t k = 0; k < a.rows; k++) {
      double y = drift ? fmin(0.5 + (double)k / 100, 1.5) : 0.5;
      if (fabs(a.x[2 * k] - 0.5) > 1e-12 || fabs(a.x[2 * k + 1] - y) > 1e-12)
        fail_msg("drift %d, row %llu: (%.17g, %.17g), expected (0.5, %.17g)", drift, (unsigned long long)k,
                 a.x[2 * k], a.x[2 * k + 1], y);
    }
    hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
    assert_true(attr_f64(f, "max_eta_cert") == 0);
    H5Fclose(f);
    unload(&a);
  }
}

/* What the model allows but warns of (issue 27): a loop of ideal diodes
 * (tests/netlists/warn) and a door no agent can pass: exit 0, the warning
 * on one stderr line before the run's, and in the attribute `warnings`. */
static void test_model_warnings(void **state) {
  (void)state;
  const char *out = tmp_path("warn.h5");
  const char *cir = CUP_SOURCE_DIR "/tests/netlists/warn/antiparallel.cir";
  const char *a1[] = {cir, "-o", out, "--quiet", NULL};
  result r = run_cli(a1, 0, 0);
  if (r.code != 0) fail_msg("diode loop: exit %d:\n%s", r.code, r.err);
  const char *want = "antiparallel.cir:7:1: D1: D1 and D2 are ideal diodes in anti-parallel between nodes 'a' and "
                     "'b', a loop with no resistance: a current around it is not unique; the run takes one";
  expect_in(r.err, "catchup-run: warning: ");
  expect_in(r.err, want);
  char text[512];
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  attr_str(f, "warnings", text, sizeof text);
  H5Fclose(f);
  expect_in(text, want);
  const char *room = SCENES "/crowd/narrow-door.yaml";
  const char *a2[] = {room, "-o", out, NULL};
  r = run_cli(a2, 0, 0);
  if (r.code != 0) fail_msg("narrow door: exit %d:\n%s", r.code, r.err);
  want = "door 0 (from (6, 1.8) to (6, 2.2)) is 0.4 wide, narrower than the smallest agent (agent 1, diameter "
         "0.5): no agent can pass it; it is the only door: no agent can leave";
  expect_in(r.err, want);
  assert_true(strstr(r.err, want) < strstr(r.err, "-> "));   /* before the run's summary */
  expect_in(r.err, "0 out");
  f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  attr_str(f, "warnings", text, sizeof text);
  H5Fclose(f);
  expect_in(text, want);
  const char *a3[] = {CUP_SOURCE_DIR "/examples/paper-fig2.yaml", "-o", out, "--quiet", NULL};
  r = run_cli(a3, 0, 0);                             /* no warning: the attribute is empty */
  if (r.code != 0 || r.lines != 0) fail_msg("paper-fig2: exit %d:\n%s", r.code, r.err);
  f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  attr_str(f, "warnings", text, sizeof text);
  H5Fclose(f);
  assert_string_equal(text, "");
}

/* NaN in a scene file and in an override: exit 1, one line, the place. */
static void test_nonfinite_scene_values(void **state) {
  (void)state;
  const char *out = tmp_path("nan.h5");
  const char *a1[] = {SCENES "/bad/x0-nan.yaml", "-o", out, NULL};
  result r = run_cli(a1, 0, 0);
  if (r.code != 1 || r.lines != 1) fail_msg("exit %d with %d lines:\n%s", r.code, r.lines, r.err);
  expect_in(r.err, "x0-nan.yaml:11:9: x0.1: must be finite (got nan)");
  const char *a2[] = {CUP_SOURCE_DIR "/examples/paper-fig2.yaml", "-o", out, "--set",
                      "input.0.amplitude=-.inf", NULL};
  r = run_cli(a2, 0, 0);
  if (r.code != 1 || r.lines != 1) fail_msg("exit %d with %d lines:\n%s", r.code, r.lines, r.err);
  expect_in(r.err, "override 'input.0.amplitude=-.inf': input.0.amplitude: must be finite (got -inf)");
  const char *a3[] = {SCENES "/bad/x0-mtx-inf.yaml", "-o", out, NULL};
  r = run_cli(a3, 0, 0);
  if (r.code != 1 || r.lines != 1) fail_msg("exit %d with %d lines:\n%s", r.code, r.lines, r.err);
  expect_in(r.err, "x0-mtx-inf.yaml:8:12: x0.file: inf.mtx: entry (2,1) is -inf");
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_empty_set_keeps_prefix),
    cmocka_unit_test(test_divergence_keeps_prefix),
    cmocka_unit_test(test_divergence_every_stride),
    cmocka_unit_test(test_model_warnings),
    cmocka_unit_test(test_intersection_on_a_face),
    cmocka_unit_test(test_nonfinite_scene_values),
  };
  return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}

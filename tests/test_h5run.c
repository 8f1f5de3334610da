/* HDF5 run writer: every file is read back through the HDF5 API directly
 * (not through the writer) and compared bit for bit with values regenerated
 * from a seed; attributes are checked for their HDF5 types and through
 * h5dump; a writer killed mid-run must leave a file that opens as is and
 * holds every row written before its last flush. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <time.h>
#include <unistd.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <cmocka.h>
#include <hdf5.h>
#include <hdf5_hl.h>
#include "catchup.h"
#include "catchup/h5run.h"
#include "h5/h5run_rows.h"

#define CLI_TMPDIR_TEMPLATE "/tmp/cup_h5run_XXXXXX"
#include "tmpdir.h"
#include "h5read.h"

static void path_in_tmp(char *buf, size_t size, const char *name) {
  snprintf(buf, size, "%s/%s", tmpdir, name);
}

/* A writer of dim-state rows into the temporary folder's NAME (its path
 * into buf), which must open. */
static cup_h5run *create_in_tmp(char *buf, size_t size, const char *name, int dim) {
  path_in_tmp(buf, size, name);
  cup_h5run *w = NULL;
  assert_int_equal(cup_h5run_create(&w, buf, dim, NULL), CUP_OK);
  return w;
}

/* ---- reference values: any 64-bit pattern, NaN payloads and -0 included ---- */

static uint64_t mix(uint64_t z) {                       /* splitmix64 finaliser */
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/* Entry j of sample k (j = -1: the time). */
static double value(long k, int j, int dim) {
  uint64_t bits = mix((uint64_t)k * (uint64_t)(dim + 1) + (uint64_t)(j + 1));
  double v;
  memcpy(&v, &bits, sizeof v);
  return v;
}

static void sample(long k, int dim, double *t, double *x) {
  *t = value(k, -1, dim);
  for (int j = 0; j < dim; j++) x[j] = value(k, j, dim);
}

static int write_samples(cup_h5run *w, long from, long to, int dim) {
  double *x = malloc(sizeof(double) * (size_t)dim), t;
  int st = CUP_OK;
  for (long k = from; k < to && st == CUP_OK; k++) {
    sample(k, dim, &t, x);
    st = cup_h5run_sink(k, t, x, w);
  }
  free(x);
  return st;
}

/* ---- independent reader ---- */

typedef struct {
  hsize_t n, dim;
  double *t, *x;
} run_file;

/* One dataset: float64 little-endian, chunked, first dimension unlimited. */
static hid_t open_checked(hid_t f, const char *name, int rank, hsize_t *dims) {
  hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
  assert_true(d >= 0);
  hid_t type = H5Dget_type(d);
  assert_true(H5Tequal(type, H5T_IEEE_F64LE) > 0);
  H5Tclose(type);
  hid_t space = H5Dget_space(d);
  hsize_t maxdims[2];
  assert_int_equal(H5Sget_simple_extent_ndims(space), rank);
  H5Sget_simple_extent_dims(space, dims, maxdims);
  assert_true(maxdims[0] == H5S_UNLIMITED);
  H5Sclose(space);
  hid_t dcpl = H5Dget_create_plist(d);
  assert_int_equal(H5Pget_layout(dcpl), H5D_CHUNKED);
  H5Pclose(dcpl);
  return d;
}

static void read_run(const char *path, run_file *r) {
  hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  hsize_t dt[1], dx[2];
  hid_t t = open_checked(f, "t", 1, dt);
  hid_t x = open_checked(f, "x", 2, dx);
  assert_true(dt[0] == dx[0]);
  r->n = dx[0];
  r->dim = dx[1];
  r->t = malloc(sizeof(double) * (r->n + 1));
  r->x = malloc(sizeof(double) * (r->n * r->dim + 1));
  if (r->n > 0) {
    assert_true(H5Dread(t, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, r->t) >= 0);
    assert_true(H5Dread(x, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, r->x) >= 0);
  }
  H5Dclose(t);
  H5Dclose(x);
  H5Fclose(f);
}

/* Rows [0, n) equal the reference bit for bit. */
static void check_rows(const run_file *r, long n) {
  int dim = (int)r->dim;
  double *x = malloc(sizeof(double) * (size_t)dim), t;
  for (long k = 0; k < n; k++) {
    sample(k, dim, &t, x);
    if (memcmp(&t, r->t + k, sizeof t) != 0) fail_msg("t[%ld] differs", k);
    if (memcmp(x, r->x + (size_t)k * (size_t)dim, sizeof(double) * (size_t)dim) != 0)
      fail_msg("x[%ld, :] differs", k);
  }
  free(x);
}

static void free_run(run_file *r) { free(r->t); free(r->x); }

/* The file at path holds the rows 0..n-1 of write_samples, of dim states
 * (dim 0: any). */
static void expect_run(const char *path, long n, int dim) {
  run_file r;
  read_run(path, &r);
  assert_int_equal(r.n, n);
  if (dim) assert_int_equal(r.dim, dim);
  check_rows(&r, n);
  free_run(&r);
}

/* ---- round trip of N samples of dimension dim ---- */

typedef struct { long n; int dim; } shape;
static const shape shapes[] = {
  {0, 3}, {1, 3}, {4095, 3}, {4097, 3}, {100003, 3},  /* around the 4096-row chunk */
  {10, 1}, {1000, 700},                               /* 128-row chunks for wide x */
  {5, 150000},                                        /* a row wider than 1 MiB */
};

static void test_roundtrip(void **state) {
  const shape *s = *state;
  char path[256];
  path_in_tmp(path, sizeof path, "roundtrip.h5");
  cup_h5run *w = NULL;
  char err[CUP_ERRMSG_LEN] = "";
  assert_int_equal(cup_h5run_create(&w, path, s->dim, err), CUP_OK);
  assert_int_equal(write_samples(w, 0, s->n, s->dim), CUP_OK);
  assert_int_equal(cup_h5run_count(w), s->n);
  assert_int_equal(cup_h5run_close(&w, err), CUP_OK);
  assert_null(w);
  expect_run(path, s->n, s->dim);
}

/* Explicit flushes of partial buffers in between: writes realign to chunk
 * boundaries afterwards and nothing is duplicated or lost. */
static void test_flushes_in_between(void **state) {
  (void)state;
  char path[256];
  cup_h5run *w = create_in_tmp(path, sizeof path, "flushes.h5", 2);
  long cuts[] = {0, 10, 5010, 5013, 9000, 13001};
  for (size_t i = 1; i < sizeof cuts / sizeof cuts[0]; i++) {
    assert_int_equal(write_samples(w, cuts[i - 1], cuts[i], 2), CUP_OK);
    assert_int_equal(cup_h5run_flush(w), CUP_OK);
    assert_int_equal(cup_h5run_flush(w), CUP_OK);       /* nothing buffered */
  }
  assert_int_equal(cup_h5run_close(&w, NULL), CUP_OK);
  expect_run(path, 13001, 0);
}

/* The file's signals a, b, c, ... against value(k, dim + s, dim + nsig),
 * bit for bit. */
static void expect_signals(const char *path, long N, int DIM, int NSIG) {
  hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  double *got = malloc(sizeof(double) * (size_t)N);
  for (int s = 0; s < NSIG; s++) {
    hsize_t dims[1];
    char name[16];
    snprintf(name, sizeof name, "signals/%c", 'a' + s);
    hid_t d = open_checked(f, name, 1, dims);
    assert_true(dims[0] == (hsize_t)N);
    assert_true(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, got) >= 0);
    for (long k = 0; k < N; k++) {
      double v = value(k, DIM + s, DIM + NSIG);
      if (memcmp(&v, got + k, sizeof v) != 0) fail_msg("signal %d, row %ld differs", s, k);
    }
    H5Dclose(d);
  }
  free(got);
  H5Fclose(f);
}

/* Rows in batches (h5run_append_rows, catchup-run's samples inside a
 * step) of every size from 1 to 300, against the chunk of 4096 rows and
 * the writer's clock looks: the file holds the reference rows and signals
 * bit for bit, as written one by one. */
static void test_rows_in_batches(void **state) {
  (void)state;
  enum { N = 10007, DIM = 2, NSIG = 3, MAXB = 300 };
  char path[256];
  cup_h5run *w = create_in_tmp(path, sizeof path, "batches.h5", DIM);
  assert_int_equal(cup_h5run_signals(w, NSIG, (const char *const[]){"a", "b", "c"}), CUP_OK);
  static double t[MAXB], x[MAXB * DIM], sig[MAXB * NSIG];
  int done = -1;
  assert_int_equal(h5run_append_rows(w, 0, t, x, sig, MAXB, &done), CUP_OK);
  assert_int_equal(done, 0);
  assert_int_equal(h5run_append_rows(w, 1, t, x, NULL, MAXB, &done), CUP_ERR_ARG);
  assert_int_equal(h5run_append_rows(w, 2, t, x, sig, 1, &done), CUP_ERR_ARG);   /* columns overlap */
  for (long k = 0, b = 1; k < N; k += b, b = b % MAXB + 1) {
    int c = (int)(k + b <= N ? b : N - k);
    for (int i = 0; i < c; i++) {
      sample(k + i, DIM, &t[i], x + (size_t)i * DIM);
      for (int s = 0; s < NSIG; s++) sig[s * MAXB + i] = value(k + i, DIM + s, DIM + NSIG);
    }
    assert_int_equal(h5run_append_rows(w, c, t, x, sig, MAXB, &done), CUP_OK);
    assert_int_equal(done, c);
  }
  assert_int_equal(cup_h5run_count(w), N);
  assert_int_equal(cup_h5run_close(&w, NULL), CUP_OK);
  expect_run(path, N, DIM);
  expect_signals(path, N, DIM, NSIG);
}

/* Rows one by one as catchup-run's put gives a step's end (h5run_take_row,
 * signal k at sig + k stride), a few entries and a wide row (beyond the
 * unrolled copies): 1 for every row taken, and the file holds the
 * reference rows and signals bit for bit across the chunks and the clock's
 * looks. */
static void test_rows_one_by_one(void **state) {
  (void)state;
  enum { N = 10007, NSIG = 3, STRIDE = 7 };
  for (int dim = 2; dim <= 6; dim += 4) {
    char path[256];
    cup_h5run *w = create_in_tmp(path, sizeof path, "one-by-one.h5", dim);
    assert_int_equal(cup_h5run_signals(w, NSIG, (const char *const[]){"a", "b", "c"}), CUP_OK);
    double t, x[6], sig[NSIG * STRIDE];
    for (long k = 0; k < N; k++) {
      sample(k, dim, &t, x);
      for (int s = 0; s < NSIG; s++) sig[s * STRIDE] = value(k, dim + s, dim + NSIG);
      assert_int_equal(h5run_take_row(w, t, x, sig, STRIDE), 1);
    }
    assert_int_equal(cup_h5run_count(w), N);
    assert_int_equal(cup_h5run_close(&w, NULL), CUP_OK);
    expect_run(path, N, dim);
    expect_signals(path, N, dim, NSIG);
  }
}

/* ---- attributes ---- */

static void read_attr(hid_t f, const char *name, hid_t expect_type, hid_t mem_type, void *buf) {
  hid_t a = H5Aopen(f, name, H5P_DEFAULT);
  if (a < 0) fail_msg("attribute %s missing", name);
  hid_t type = H5Aget_type(a);
  assert_true(H5Tequal(type, expect_type) > 0);
  H5Tclose(type);
  assert_true(H5Aread(a, mem_type, buf) >= 0);
  H5Aclose(a);
}

static void check_string_attr(hid_t f, const char *name, const char *expect) {
  hid_t a = H5Aopen(f, name, H5P_DEFAULT);
  if (a < 0) fail_msg("attribute %s missing", name);
  hid_t type = H5Aget_type(a);
  assert_int_equal(H5Tget_class(type), H5T_STRING);
  assert_true(H5Tis_variable_str(type) > 0);
  assert_int_equal(H5Tget_cset(type), H5T_CSET_UTF8);
  char *s = NULL;
  assert_true(H5Aread(a, type, &s) >= 0);
  assert_string_equal(s, expect);
  H5free_memory(s);
  H5Tclose(type);
  H5Aclose(a);
}

static const char utf8_text[] = "\xce\xb5_n = n^-2.1 \xe2\x80\x94 \xce\xb7_n = n^-1.05";

static char *long_text(size_t len) {         /* beyond the 64 KiB header limit */
  char *s = malloc(len + 1);
  for (size_t i = 0; i < len; i++) s[i] = (char)('a' + i % 26);
  s[len] = '\0';
  return s;
}

static void write_attrs(cup_h5run *w, const char *big) {
  assert_int_equal(cup_h5run_attr_double(w, "T", 0.75), CUP_OK);
  assert_int_equal(cup_h5run_attr_double(w, "minus_zero", -0.0), CUP_OK);
  assert_int_equal(cup_h5run_attr_double(w, "tiny", 4.9e-324), CUP_OK);
  assert_int_equal(cup_h5run_attr_double(w, "nan", NAN), CUP_OK);
  assert_int_equal(cup_h5run_attr_long(w, "n", 100000000L), CUP_OK);
  assert_int_equal(cup_h5run_attr_long(w, "lmin", LONG_MIN), CUP_OK);
  assert_int_equal(cup_h5run_attr_long(w, "lmax", LONG_MAX), CUP_OK);
  assert_int_equal(cup_h5run_attr_string(w, "scheme", "explicit"), CUP_OK);
  assert_int_equal(cup_h5run_attr_string(w, "empty", ""), CUP_OK);
  assert_int_equal(cup_h5run_attr_string(w, "eps", utf8_text), CUP_OK);
  assert_int_equal(cup_h5run_attr_string(w, "scene", big), CUP_OK);
  /* Rewritten with another type, as catchup-run does with its status. */
  assert_int_equal(cup_h5run_attr_string(w, "status", "running"), CUP_OK);
  assert_int_equal(cup_h5run_attr_long(w, "status", -14), CUP_OK);
  assert_int_equal(cup_h5run_attr_double(w, "T", 1.0), CUP_OK);
}

static void check_attrs(const char *path, const char *big) {
  hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  double d;
  read_attr(f, "T", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &d);
  assert_true(d == 1.0);
  read_attr(f, "minus_zero", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &d);
  assert_true(d == 0.0 && signbit(d));
  read_attr(f, "tiny", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &d);
  assert_true(d == 4.9e-324);
  read_attr(f, "nan", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &d);
  assert_true(isnan(d));
  int64_t v;
  read_attr(f, "n", H5T_STD_I64LE, H5T_NATIVE_INT64, &v);
  assert_true(v == 100000000);
  read_attr(f, "lmin", H5T_STD_I64LE, H5T_NATIVE_INT64, &v);
  assert_true(v == INT64_MIN);
  read_attr(f, "lmax", H5T_STD_I64LE, H5T_NATIVE_INT64, &v);
  assert_true(v == INT64_MAX);
  read_attr(f, "status", H5T_STD_I64LE, H5T_NATIVE_INT64, &v);
  assert_true(v == -14);
  check_string_attr(f, "scheme", "explicit");
  check_string_attr(f, "empty", "");
  check_string_attr(f, "eps", utf8_text);
  check_string_attr(f, "scene", big);
  H5Fclose(f);
}

static void test_attributes_roundtrip(void **state) {
  (void)state;
  char path[256];
  char *big = long_text(200000);
  cup_h5run *w = create_in_tmp(path, sizeof path, "attrs.h5", 3);
  write_attrs(w, big);
  assert_int_equal(cup_h5run_attr_double(NULL, "x", 1), CUP_ERR_ARG);
  assert_int_equal(cup_h5run_attr_string(w, "x", NULL), CUP_ERR_ARG);
  assert_int_equal(cup_h5run_attr_long(w, "", 1), CUP_ERR_ARG);
  assert_int_equal(cup_h5run_close(&w, NULL), CUP_OK);
  check_attrs(path, big);
  free(big);
}

/* What a user sees with the HDF5 tools: typed, readable values. */
static void test_h5dump_reads_attributes(void **state) {
  (void)state;
#ifndef CUP_H5DUMP
  skip();
#else
  char path[256], cmd[512], out[8192];
  cup_h5run *w = create_in_tmp(path, sizeof path, "dump.h5", 3);
  assert_int_equal(cup_h5run_attr_string(w, "scheme", "explicit"), CUP_OK);
  assert_int_equal(cup_h5run_attr_long(w, "n", 1000), CUP_OK);
  assert_int_equal(cup_h5run_attr_double(w, "T", 0.5), CUP_OK);
  assert_int_equal(cup_h5run_close(&w, NULL), CUP_OK);
  snprintf(cmd, sizeof cmd, "%s -A '%s' 2>&1", CUP_H5DUMP, path);
  FILE *p = popen(cmd, "r");
  assert_non_null(p);
  size_t len = fread(out, 1, sizeof out - 1, p);
  out[len] = '\0';
  assert_int_equal(pclose(p), 0);
  const char *expect[] = {"ATTRIBUTE \"scheme\"", "H5T_VARIABLE", "H5T_CSET_UTF8",
                          "\"explicit\"", "ATTRIBUTE \"n\"", "H5T_STD_I64LE", "1000",
                          "ATTRIBUTE \"T\"", "H5T_IEEE_F64LE", "0.5",
                          "DATASET \"t\"", "DATASET \"x\""};
  for (size_t i = 0; i < sizeof expect / sizeof expect[0]; i++)
    if (!strstr(out, expect[i])) fail_msg("h5dump output lacks %s:\n%s", expect[i], out);
#endif
}

/* ---- errors: a status and a message, never a print ---- */

static int stray_prints;
static herr_t count_prints(hid_t estack, void *data) {
  (void)estack; (void)data;
  stray_prints++;
  return 0;
}

/* Run fn with stderr redirected to a file; return how many bytes it wrote. */
static long stderr_bytes(void (*fn)(void *), void *arg) {
  char path[256];
  path_in_tmp(path, sizeof path, "stderr.txt");
  fflush(stderr);
  int saved = dup(2), fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
  assert_true(saved >= 0 && fd >= 0);
  dup2(fd, 2);
  fn(arg);
  fflush(stderr);
  dup2(saved, 2);
  close(saved);
  close(fd);
  struct stat st;
  assert_int_equal(stat(path, &st), 0);
  return (long)st.st_size;
}

typedef struct { const char *path; int status; char err[CUP_ERRMSG_LEN]; cup_h5run *w; } create_call;
static void call_create(void *arg) {
  create_call *c = arg;
  c->status = cup_h5run_create(&c->w, c->path, 3, c->err);
}

static void test_unwritable_path_names_path(void **state) {
  (void)state;
  H5E_auto2_t fn0; void *data0;
  H5Eget_auto2(H5E_DEFAULT, &fn0, &data0);
  H5Eset_auto2(H5E_DEFAULT, count_prints, NULL);   /* the application's handler */
  stray_prints = 0;
  char missing[256];
  path_in_tmp(missing, sizeof missing, "no/such/dir/out.h5");
  const char *paths[] = {missing, tmpdir, "/dev/null"};  /* no directory; a directory; a device */
  for (int i = 0; i < 3; i++) {
    create_call c = {paths[i], 0, "", (cup_h5run *)&c};
    assert_int_equal(stderr_bytes(call_create, &c), 0);
    assert_int_equal(c.status, CUP_ERR_IO);
    assert_null(c.w);
    if (!strstr(c.err, paths[i]) || !strstr(c.err, "create"))
      fail_msg("message does not name the path and operation: %s", c.err);
    if (i == 0 && !strstr(c.err, "No such file or directory")) fail_msg("%s", c.err);
  }
  /* The application's handler is back in place and was never called. */
  H5E_auto2_t fn; void *data;
  H5Eget_auto2(H5E_DEFAULT, &fn, &data);
  assert_true(fn == count_prints);
  assert_int_equal(stray_prints, 0);
  H5Eset_auto2(H5E_DEFAULT, fn0, data0);
}

static void test_bad_arguments(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN] = "", path[256];
  path_in_tmp(path, sizeof path, "args.h5");
  cup_h5run *w = (cup_h5run *)err;
  assert_int_equal(cup_h5run_create(&w, path, 0, err), CUP_ERR_ARG);
  assert_null(w);
  assert_non_null(strstr(err, path));
  assert_int_equal(cup_h5run_create(&w, NULL, 3, err), CUP_ERR_ARG);
  assert_int_equal(cup_h5run_create(NULL, path, 3, NULL), CUP_ERR_ARG);
  double x[3] = {0, 0, 0};
  assert_true(cup_h5run_sink(0, 0.0, x, NULL) != 0);
  assert_int_equal(cup_h5run_flush(NULL), CUP_ERR_ARG);
  assert_int_equal(cup_h5run_close(NULL, NULL), CUP_OK);
  assert_int_equal(cup_h5run_close(&w, NULL), CUP_OK);   /* w == NULL */
  assert_int_equal(cup_h5run_count(NULL), 0);
}

/* A failure in the data path (here: the datasets closed behind the writer's
 * back) makes the sink return nonzero from then on, close reports it with
 * the path, and the rows written before it stay in the file. */
static void close_all_datasets(void) {
  hid_t ids[8];
  ssize_t n = H5Fget_obj_ids(H5F_OBJ_ALL, H5F_OBJ_DATASET, 8, ids);
  for (ssize_t i = 0; i < n; i++) H5Dclose(ids[i]);
}

typedef struct {
  cup_h5run *w;
  int sink_status, close_status, status_before;
  char err[CUP_ERRMSG_LEN], err_before[CUP_ERRMSG_LEN], errmsg_before[CUP_ERRMSG_LEN];
} fail_call;
static void call_failing_writes(void *arg) {
  fail_call *c = arg;
  close_all_datasets();
  c->sink_status = write_samples(c->w, 4096, 8192, 3);
  c->status_before = cup_h5run_status(c->w, c->err_before);        /* before close: the sink's words */
  snprintf(c->errmsg_before, sizeof c->errmsg_before, "%s", cup_h5run_errmsg(c->w));
  c->close_status = cup_h5run_close(&c->w, c->err);
}

static void test_write_failure_is_reported(void **state) {
  (void)state;
  char path[256];
  path_in_tmp(path, sizeof path, "fail.h5");
  fail_call c = {.w = NULL};
  assert_int_equal(cup_h5run_create(&c.w, path, 3, NULL), CUP_OK);
  assert_int_equal(write_samples(c.w, 0, 4096, 3), CUP_OK);   /* one chunk, flushed */
  assert_int_equal(stderr_bytes(call_failing_writes, &c), 0);
  assert_int_equal(c.sink_status, CUP_ERR_IO);
  assert_int_equal(c.close_status, CUP_ERR_IO);
  assert_null(c.w);
  if (!strstr(c.err, path) || !strstr(c.err, "append")) fail_msg("%s", c.err);
  /* the one way (cup_h5run_status) and the older form tell the words close gives, byte for byte */
  assert_int_equal(c.status_before, CUP_ERR_IO);
  assert_string_equal(c.err_before, c.err);
  assert_string_equal(c.errmsg_before, c.err);
  expect_run(path, 4096, 0);
}

/* cup_h5run_status: CUP_OK with errmsg untouched while nothing failed; a
 * refused call's status and its words (the expected text written out here)
 * afterwards, the same as cup_h5run_errmsg's. */
static void test_status_one_way(void **state) {
  (void)state;
  char path[256], err[CUP_ERRMSG_LEN] = "untouched";
  cup_h5run *w = create_in_tmp(path, sizeof path, "status.h5", 2);
  assert_int_equal(cup_h5run_status(w, err), CUP_OK);
  assert_string_equal(err, "untouched");
  assert_int_equal(cup_h5run_status(w, NULL), CUP_OK);
  assert_int_equal(cup_h5run_signals(w, 1, (const char *const[]){"a/b"}), CUP_ERR_ARG);
  assert_int_equal(cup_h5run_status(w, err), CUP_ERR_ARG);
  assert_string_equal(err, "h5run: signal 0: 'a/b' is not a dataset name");
  assert_string_equal(cup_h5run_errmsg(w), err);
  assert_int_equal(cup_h5run_status(NULL, err), CUP_ERR_ARG);
  assert_int_equal(cup_h5run_close(&w, NULL), CUP_OK);
}

/* No PATH.part* file is left in the temporary folder. */
static int staged_left(void) {
  char cmd[512];
  snprintf(cmd, sizeof cmd, "ls %s | grep -q '\\.part'", tmpdir);
  return system(cmd) == 0;
}

/* cup_h5run_begin writes a sibling: the file at the path keeps the earlier
 * run's rows (bit for bit) while the new one is written, after a discard,
 * and after a close without commit; cup_h5run_commit replaces it in one
 * rename; nothing is left beside it. */
static void test_staged_replace(void **state) {
  (void)state;
  char path[256];
  cup_h5run *w = create_in_tmp(path, sizeof path, "staged.h5", 3);
  assert_int_equal(write_samples(w, 0, 10, 3), CUP_OK);
  assert_int_equal(cup_h5run_close(&w, NULL), CUP_OK);
  for (int round = 0; round < 3; round++) {
    assert_int_equal(cup_h5run_begin(&w, path, 2, NULL), CUP_OK);
    assert_int_equal(write_samples(w, 0, 5, 2), CUP_OK);
    assert_int_equal(cup_h5run_flush(w), CUP_OK);
    if (round == 1) assert_true(staged_left());            /* the sibling, while it is written */
    expect_run(path, 10, 3);
    if (round == 0) cup_h5run_discard(&w);
    else if (round == 1) assert_int_equal(cup_h5run_close(&w, NULL), CUP_OK);   /* not committed */
    else assert_int_equal(cup_h5run_commit(w), CUP_OK);
    assert_false(staged_left());
  }
  assert_int_equal(write_samples(w, 5, 7, 2), CUP_OK);
  assert_int_equal(cup_h5run_close(&w, NULL), CUP_OK);
  expect_run(path, 7, 2);
  cup_h5run_discard(&w);                                    /* NULL: nothing */
}

static void test_version(void **state) {
  (void)state;
  char buf[64];
  unsigned a, b, c;
  H5get_libversion(&a, &b, &c);
  char expect[64];
  snprintf(expect, sizeof expect, "HDF5 %u.%u.%u", a, b, c);
  assert_int_equal(cup_h5_version(buf, sizeof buf), (int)strlen(expect));
  assert_string_equal(buf, expect);
}

/* ---- crash: a child writes, flushes, and dies before close ---- */

enum { DIE_KILL, DIE_EXIT };
typedef struct { long before_flush, after_flush; double pause; int how; } crash_case;

static void sleep_seconds(double s) {
  struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
  while (nanosleep(&ts, &ts) != 0) {}
}

/* Child: exit codes 10.. report a failure before the planned death. */
static void child_run(const char *path, const crash_case *c) {
  cup_h5run *w = NULL;
  if (cup_h5run_create(&w, path, 3, NULL) != CUP_OK) _exit(10);
  if (cup_h5run_attr_string(w, "status_name", "running") != CUP_OK) _exit(11);
  if (write_samples(w, 0, c->before_flush, 3) != CUP_OK) _exit(12);
  if (c->pause > 0) {
    sleep_seconds(c->pause);            /* the next sample is due a timed flush */
    if (write_samples(w, c->before_flush, c->before_flush + 1, 3) != CUP_OK) _exit(13);
  } else if (cup_h5run_flush(w) != CUP_OK) {
    _exit(14);
  }
  long from = cup_h5run_count(w);
  if (write_samples(w, from, from + c->after_flush, 3) != CUP_OK) _exit(15);
  if (c->how == DIE_KILL) raise(SIGKILL);
  _exit(0);
}

static void test_crash_keeps_flushed_rows(void **state) {
  const crash_case *c = *state;
  char path[256];
  path_in_tmp(path, sizeof path, "crash.h5");
  fflush(NULL);
  pid_t pid = fork();
  if (pid < 0) skip();                   /* no fork here (some sanitizer setups) */
  if (pid == 0) child_run(path, c);
  int wst = 0;
  assert_int_equal(waitpid(pid, &wst, 0), pid);
  if (c->how == DIE_KILL) {
    if (!WIFSIGNALED(wst) || WTERMSIG(wst) != SIGKILL)
      fail_msg("child did not die by SIGKILL (exit code %d)", WIFEXITED(wst) ? WEXITSTATUS(wst) : -1);
  } else {
    assert_true(WIFEXITED(wst));
    assert_int_equal(WEXITSTATUS(wst), 0);
  }
  long flushed = c->before_flush + (c->pause > 0 ? 1 : 0);
  run_file r;
  read_run(path, &r);                    /* opens as is: no h5clear */
  if ((long)r.n < flushed || (long)r.n > flushed + c->after_flush)
    fail_msg("%ld rows in the file, %ld were flushed", (long)r.n, flushed);
  check_rows(&r, (long)r.n);
  free_run(&r);
  hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  check_string_attr(f, "status_name", "running");
  H5Fclose(f);
}

static const crash_case crashes[] = {
  {5000, 123, 0, DIE_KILL},   /* a chunk written when full, the rest by cup_h5run_flush */
  {10, 5, 1.2, DIE_KILL},     /* a flush due to wall time (1 s) */
  {3, 7, 0, DIE_EXIT},        /* _exit without close */
};

/* ---- fixture: one scratch directory for the whole program ---- */

/* /events: every event written (2.5 buffers' worth, interleaved with
 * samples) reads back in order, with its time, row and flag; a file with
 * none has the dataset, empty. */
static void test_events(void **state) {
  (void)state;
  char path[512];
  path_in_tmp(path, sizeof path, "events.h5");
  for (int count = 0; count <= 2500; count += 2500) {
    cup_h5run *w = NULL;
    assert_int_equal(cup_h5run_create(&w, path, 2, NULL), CUP_OK);
    double x[2] = {0, 0};
    for (int k = 0; k < count; k++) {
      assert_int_equal(cup_h5run_event(0.5 * k, k % 7, k % 3 == 0, w), CUP_OK);
      if (k % 10 == 0) assert_int_equal(cup_h5run_sink(k, k, x, w), CUP_OK);
    }
    assert_int_equal(cup_h5run_close(&w, NULL), CUP_OK);
    typedef struct { int8_t on; double t; int32_t row; } ev;   /* another order than the writer's */
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    hsize_t n = 0;
    ev *e = read_events(f, sizeof(ev), HOFFSET(ev, t), HOFFSET(ev, row), HOFFSET(ev, on), &n);
    assert_int_equal((long)n, count);
    for (int k = 0; k < count; k++)
      if (e[k].t != 0.5 * k || e[k].row != k % 7 || e[k].on != (k % 3 == 0))
        fail_msg("event %d read back as (%g, %d, %d)", k, e[k].t, e[k].row, e[k].on);
    free(e);
    H5Fclose(f);
  }
}

/* Dimension scales and CF attributes, read back with the H5DS API: /x's
 * dimensions are /t and /state (labels), /events' a dimension without a
 * coordinate (netCDF-4's NAME), a group's dataset finds /t at the root and
 * a dataset named as its dimension is its own scale. */
static void test_dimension_scales(void **state) {
  (void)state;
  char path[512], buf[128];
  cup_h5run *w = create_in_tmp(path, sizeof path, "dims.h5", 2);
  const char *names[2] = {"q(C4)", "i(L3)"};
  assert_int_equal(cup_h5run_strings(w, "state", 2, names), CUP_OK);
  assert_int_equal(cup_h5run_dims(w, "x", (const char *const[]){"t", "state"}), CUP_OK);
  assert_int_equal(cup_h5run_describe(w, "x", "C, A", "state x(t)"), CUP_OK);
  assert_int_equal(cup_h5run_describe(w, "t", "s", "time"), CUP_OK);
  assert_int_equal(cup_h5run_dims(w, "events", (const char *const[]){"event"}), CUP_OK);
  long n = 3;
  double v[3] = {0, 1, 2};
  assert_int_equal(cup_h5run_array(w, "steps/t", 1, &n, v), CUP_OK);
  assert_int_equal(cup_h5run_array(w, "steps/gap", 1, &n, v), CUP_OK);
  assert_int_equal(cup_h5run_dims(w, "steps/t", (const char *const[]){"t"}), CUP_OK);
  assert_int_equal(cup_h5run_dims(w, "steps/gap", (const char *const[]){"t"}), CUP_OK);
  assert_int_equal(cup_h5run_dims(w, "nope", (const char *const[]){"t"}), CUP_ERR_IO);
  assert_int_equal(cup_h5run_close(&w, NULL), CUP_ERR_IO);       /* the failed call is sticky */

  assert_int_equal(cup_h5run_create(&w, path, 2, NULL), CUP_OK);
  assert_int_equal(cup_h5run_strings(w, "state", 2, names), CUP_OK);
  assert_int_equal(cup_h5run_dims(w, "x", (const char *const[]){"t", "state"}), CUP_OK);
  assert_int_equal(cup_h5run_describe(w, "x", "C, A", "state x(t)"), CUP_OK);
  assert_int_equal(cup_h5run_dims(w, "events", (const char *const[]){"event"}), CUP_OK);
  assert_int_equal(cup_h5run_array(w, "steps/t", 1, &n, v), CUP_OK);
  assert_int_equal(cup_h5run_array(w, "steps/gap", 1, &n, v), CUP_OK);
  assert_int_equal(cup_h5run_dims(w, "steps/t", (const char *const[]){"t"}), CUP_OK);
  assert_int_equal(cup_h5run_dims(w, "steps/gap", (const char *const[]){"t"}), CUP_OK);
  assert_int_equal(cup_h5run_signals(w, 1, (const char *const[]){"v(out)"}), CUP_OK);
  assert_int_equal(cup_h5run_dims(w, "signals/v(out)", (const char *const[]){"t"}), CUP_OK);
  assert_int_equal(cup_h5run_close(&w, NULL), CUP_OK);

  hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t x = H5Dopen2(f, "x", H5P_DEFAULT), t = H5Dopen2(f, "t", H5P_DEFAULT), st = H5Dopen2(f, "state", H5P_DEFAULT);
  assert_true(H5DSis_scale(t) > 0 && H5DSis_scale(st) > 0);
  assert_true(H5DSis_attached(x, t, 0) > 0 && H5DSis_attached(x, st, 1) > 0 && H5DSis_attached(x, t, 1) == 0);
  assert_true(H5DSget_scale_name(t, buf, sizeof buf) > 0);
  assert_string_equal(buf, "t");
  attr_str(x, "units", buf, sizeof buf);
  assert_string_equal(buf, "C, A");
  attr_str(x, "long_name", buf, sizeof buf);
  assert_string_equal(buf, "state x(t)");
  hid_t e = H5Dopen2(f, "events", H5P_DEFAULT), ev = H5Dopen2(f, "event", H5P_DEFAULT);
  assert_true(H5DSis_attached(e, ev, 0) > 0);
  assert_true(H5DSget_scale_name(ev, buf, sizeof buf) > 0);
  assert_true(strncmp(buf, "This is a netCDF dimension but not a netCDF variable.", 53) == 0);
  hid_t s = H5Dopen2(f, "signals/v(out)", H5P_DEFAULT), gt = H5Dopen2(f, "steps/t", H5P_DEFAULT),
        gg = H5Dopen2(f, "steps/gap", H5P_DEFAULT);
  assert_true(H5DSis_attached(s, t, 0) > 0);
  assert_true(H5DSis_scale(gt) > 0 && H5DSis_attached(gg, gt, 0) > 0 && H5DSis_attached(gg, t, 0) == 0);
  hid_t types[] = {x, t, st, e, ev, s, gt, gg};
  for (size_t k = 0; k < sizeof types / sizeof types[0]; k++) H5Dclose(types[k]);
  H5Fclose(f);
}

#define ROUNDTRIP(i) cmocka_unit_test_prestate(test_roundtrip, (void *)&shapes[i])
#define CRASH(i) cmocka_unit_test_prestate(test_crash_keeps_flushed_rows, (void *)&crashes[i])

int main(void) {
  const struct CMUnitTest tests[] = {
    ROUNDTRIP(0), ROUNDTRIP(1), ROUNDTRIP(2), ROUNDTRIP(3),
    ROUNDTRIP(4), ROUNDTRIP(5), ROUNDTRIP(6), ROUNDTRIP(7),
    cmocka_unit_test(test_flushes_in_between),
    cmocka_unit_test(test_rows_in_batches),
    cmocka_unit_test(test_rows_one_by_one),
    cmocka_unit_test(test_events),
    cmocka_unit_test(test_dimension_scales),
    cmocka_unit_test(test_attributes_roundtrip),
    cmocka_unit_test(test_h5dump_reads_attributes),
    cmocka_unit_test(test_unwritable_path_names_path),
    cmocka_unit_test(test_bad_arguments),
    cmocka_unit_test(test_write_failure_is_reported),
    cmocka_unit_test(test_status_one_way),
    cmocka_unit_test(test_staged_replace),
    cmocka_unit_test(test_version),
    CRASH(0), CRASH(1), CRASH(2),
  };
  return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}

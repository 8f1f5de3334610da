/* Stress: long runs of the paper's case 1 through catchup-run, with 1001
 * decimated samples (output: {samples: 1001}) and exact projections.
 *
 *   test_stress_long N1 N2     (default 10^4 10^6; CATCHUP_LONG_TESTS: 10^6 10^8)
 *
 * For each n: the run succeeds; the sample times are the grid's, t = k h
 * with k = round(j n / 1000) and the last exactly T (compared also with the
 * correctly rounded k T / n); the max-norm error against the
 * reference limit (ref_case1_limit_richardson.csv, t = j/1000) is 1.52/n
 * within 2%; and the peak RSS of the catchup-run process (wait4) does not
 * grow from N1 to N2 steps by more than 1 MiB: memory is flat in n. */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE              /* wait4 */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <math.h>
#include <fcntl.h>
#include <time.h>
#include <unistd.h>
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <cmocka.h>
#include <hdf5.h>
#include "util/clock.h"

static long ns[2] = {10000, 1000000};
#define CLI_TMPDIR_TEMPLATE "/tmp/cup_stress_long_XXXXXX"
#include "tmpdir.h"
static double ref[1001][3];

typedef struct { long n; double wall, maxrss_mb; double err; long t_mismatch_kTn; } outcome;

static void load_ref(void) {
  FILE *f = fopen(CUP_TEST_DATA_DIR "/ref_case1_limit_richardson.csv", "r");
  if (!f) fail_msg("cannot open the reference %s", CUP_TEST_DATA_DIR "/ref_case1_limit_richardson.csv");
  char line[512];
  assert_non_null(fgets(line, sizeof line, f));
  for (int j = 0; j <= 1000; j++) {
    double t;
    assert_non_null(fgets(line, sizeof line, f));
    assert_int_equal(sscanf(line, "%lf,%lf,%lf,%lf", &t, &ref[j][0], &ref[j][1], &ref[j][2]), 4);
    assert_true(fabs(t - j / 1000.0) < 1e-15);
  }
  fclose(f);
}

static hsize_t read_all(hid_t f, const char *name, double **out) {
  hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
  assert_true(d >= 0);
  hid_t s = H5Dget_space(d);
  hsize_t dims[2] = {0, 0};
  int rank = H5Sget_simple_extent_ndims(s);
  H5Sget_simple_extent_dims(s, dims, NULL);
  hsize_t count = dims[0] * (rank == 2 ? dims[1] : 1);
  *out = malloc(sizeof(double) * (count + 1));
  if (count) assert_true(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, *out) >= 0);
  H5Sclose(s);
  H5Dclose(d);
  return dims[0];
}

static void run_one(long n, outcome *o) {
  char out[300], nstr[32], errf[300];
  snprintf(out, sizeof out, "%s/case1_%ld.h5", tmpdir, n);
  snprintf(errf, sizeof errf, "%s/stderr_%ld.txt", tmpdir, n);
  snprintf(nstr, sizeof nstr, "%ld", n);
  const char *argv[] = {CUP_CATCHUP_RUN, CUP_SOURCE_DIR "/examples/paper-fig2.yaml", "-o", out,
                        "--n", nstr, "--eps", "0", "--eta", "0", "--set", "output={samples: 1001}",
                        "--quiet", NULL};
  fflush(NULL);
  double t0 = now_seconds();
  pid_t pid = fork();
  if (pid < 0) skip();
  if (pid == 0) {
    int fd = open(errf, O_WRONLY | O_CREAT | O_TRUNC, 0600), nul = open("/dev/null", O_WRONLY);
    dup2(fd, 2);
    dup2(nul, 1);
    execv(CUP_CATCHUP_RUN, (char *const *)argv);
    _exit(127);
  }
  int st = 0;
  struct rusage ru;
  assert_int_equal(wait4(pid, &st, 0, &ru), pid);
  o->n = n;
  o->wall = now_seconds() - t0;
  o->maxrss_mb = (double)ru.ru_maxrss / 1024;       /* KiB on Linux */
  if (!WIFEXITED(st) || WEXITSTATUS(st) != 0) fail_msg("catchup-run --n %ld failed (status %d), see %s", n, st, errf);
  hid_t f = H5Fopen(out, H5F_ACC_RDONLY, H5P_DEFAULT);
  assert_true(f >= 0);
  double *t, *x;
  assert_int_equal(read_all(f, "t", &t), 1001);
  assert_int_equal(read_all(f, "x", &x), 1001);
  H5Fclose(f);
  double h = 1.0 / (double)n, err = 0;
  o->t_mismatch_kTn = 0;
  for (int j = 0; j <= 1000; j++) {
    long k = (long)llround((double)j * (double)n / 1000.0);
    double tk = j == 1000 ? 1.0 : (double)k * h;    /* the grid: t_k = k h, t_n = T */
    if (t[j] != tk) fail_msg("n %ld: sample %d at t = %.17g, expected t_%ld = %.17g", n, j, t[j], k, tk);
    double exact = (double)k / (double)n;           /* k T / n, correctly rounded (T = 1) */
    if (t[j] != exact) {
      o->t_mismatch_kTn++;
      assert_true(fabs(t[j] - exact) <= nextafter(exact, INFINITY) - exact);   /* within an ulp */
    }
    for (int c = 0; c < 3; c++) err = fmax(err, fabs(x[3 * j + c] - ref[j][c]));
  }
  assert_true(t[1000] == 1.0);
  o->err = err;
  free(t);
  free(x);
  unlink(out);
}

static void test_long_runs(void **state) {
  (void)state;
  load_ref();
  outcome o[2];
  for (int i = 0; i < 2; i++) {
    run_one(ns[i], &o[i]);
    print_message("n = %ld: %.2f s wall (%.3g us/step), peak RSS %.2f MiB, error %.4e = %.4f / n, "
                  "%ld of 1001 sample times differ from the correctly rounded k T / n (by <= 1 ulp)\n",
                  o[i].n, o[i].wall, 1e6 * o[i].wall / (double)o[i].n, o[i].maxrss_mb, o[i].err,
                  o[i].err * (double)o[i].n, o[i].t_mismatch_kTn);
    if (!(fabs(o[i].err * (double)o[i].n - 1.52) <= 0.02 * 1.52))
      fail_msg("n = %ld: error %.4e = %.4f / n, expected 1.52 / n within 2%%", o[i].n, o[i].err,
               o[i].err * (double)o[i].n);
  }
  double growth = o[1].maxrss_mb - o[0].maxrss_mb;
  print_message("peak RSS growth from n = %ld to n = %ld: %+.2f MiB\n", ns[0], ns[1], growth);
  assert_true(growth <= 1.0);
}

int main(int argc, char **argv) {
  if (argc == 3) { ns[0] = atol(argv[1]); ns[1] = atol(argv[2]); }
  if (ns[0] < 1000 || ns[1] < ns[0] || ns[0] % 1000 || ns[1] % 1000) {
    fprintf(stderr, "usage: test_stress_long N1 N2 (multiples of 1000, N1 <= N2)\n");
    return 2;
  }
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_long_runs),
  };
  return cmocka_run_group_tests(tests, make_tmpdir, remove_tmpdir);
}

/* The paper cases' reference trajectories in tests/data (t = j/1000,
 * j = 0..1000, columns t,x1,x2,x3; tests/data/README.md), for the tests that
 * measure errors against them. Include after cmocka.h; the test program
 * defines CUP_TEST_DATA_DIR. */
#ifndef CUP_TEST_REFDATA_H
#define CUP_TEST_REFDATA_H

#include <math.h>
#include <stdio.h>

/* tests/data/NAME into ref (1001 x 3, row-major). */
static inline void ref_load(const char *name, double *ref) {
  char path[512], line[512];
  snprintf(path, sizeof path, "%s/%s", CUP_TEST_DATA_DIR, name);
  FILE *f = fopen(path, "r");
  if (!f) fail_msg("cannot open %s", path);
  assert_non_null(fgets(line, sizeof line, f));
  for (int j = 0; j <= 1000; j++) {
    double t;
    assert_non_null(fgets(line, sizeof line, f));
    assert_int_equal(sscanf(line, "%lf,%lf,%lf,%lf", &t, &ref[3 * j], &ref[3 * j + 1], &ref[3 * j + 2]), 4);
    if (!(fabs(t - j / 1000.0) <= 1e-15)) fail_msg("%s: row %d has t = %.17g", path, j, t);
  }
  fclose(f);
}

/* max |x - ref| over the 1001 x 3 entries. */
static inline double ref_diff(const double *x, const double *ref) {
  double err = 0;
  for (int k = 0; k < 1001 * 3; k++) err = fmax(err, fabs(x[k] - ref[k]));
  return err;
}

#endif

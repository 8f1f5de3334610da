/* Reading a run's HDF5 file back in the tests, through HDF5 alone (not the
 * writer): rows of a dataset, numeric and string attributes, /events. One
 * copy for test_h5run.c and, through cliutil.h, test_catchup_run.c and
 * test_stress_cli.c. Includes cmocka.h and hdf5.h first. */
#ifndef CUP_TEST_H5READ_H
#define CUP_TEST_H5READ_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

/* Dataset NAME of rank 1 or 2 (cols columns) into *out (malloc'd); its rows. */
static inline hsize_t read_rows(hid_t f, const char *name, int rank, hsize_t cols, double **out) {
  hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
  assert_true(d >= 0);
  hid_t s = H5Dget_space(d);
  hsize_t dims[2] = {0, 0};
  assert_int_equal(H5Sget_simple_extent_ndims(s), rank);
  H5Sget_simple_extent_dims(s, dims, NULL);
  if (rank == 2) assert_true(dims[1] == cols);
  *out = malloc(sizeof(double) * (dims[0] * cols + 1));
  if (dims[0] > 0)
    assert_true(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, *out) >= 0);
  H5Sclose(s);
  H5Dclose(d);
  return dims[0];
}

/* Attribute NAME of obj, which must exist, read as mem_type into buf. */
static inline void attr_num(hid_t obj, const char *name, hid_t mem_type, void *buf) {
  hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
  if (a < 0) fail_msg("attribute %s missing", name);
  assert_true(H5Aread(a, mem_type, buf) >= 0);
  H5Aclose(a);
}

static inline int64_t attr_i64(hid_t f, const char *name) {
  int64_t v = 0;
  attr_num(f, name, H5T_NATIVE_INT64, &v);
  return v;
}

static inline double attr_f64(hid_t f, const char *name) {
  double v = 0;
  attr_num(f, name, H5T_NATIVE_DOUBLE, &v);
  return v;
}

/* A string attribute (variable-length UTF-8, as every writer of catchup
 * makes it) into out, cut at size. */
static inline void attr_str(hid_t obj, const char *name, char *out, size_t size) {
  hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
  if (a < 0) fail_msg("attribute %s missing", name);
  hid_t t = H5Aget_type(a);
  assert_true(H5Tis_variable_str(t) > 0 && H5Tget_cset(t) == H5T_CSET_UTF8);
  char *v = NULL;
  assert_true(H5Aread(a, t, &v) >= 0);
  snprintf(out, size, "%s", v);
  H5free_memory(v);
  H5Tclose(t);
  H5Aclose(a);
}

/* /events (t, row, on), read by name into the caller's record layout (size
 * bytes, the fields at the offsets given: a double, an int32, an int8);
 * the records malloc'd (one spare), their count in *n. */
static inline void *read_events(hid_t f, size_t size, size_t off_time, size_t off_row, size_t off_on, hsize_t *n) {
  hid_t d = H5Dopen2(f, "events", H5P_DEFAULT), mt = H5Tcreate(H5T_COMPOUND, size);
  assert_true(d >= 0);
  H5Tinsert(mt, "t", off_time, H5T_NATIVE_DOUBLE);
  H5Tinsert(mt, "row", off_row, H5T_NATIVE_INT32);
  H5Tinsert(mt, "on", off_on, H5T_NATIVE_INT8);
  hid_t sp = H5Dget_space(d);
  *n = 0;
  H5Sget_simple_extent_dims(sp, n, NULL);
  void *e = malloc(size * (*n + 1));
  if (*n) assert_true(H5Dread(d, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, e) >= 0);
  H5Sclose(sp);
  H5Tclose(mt);
  H5Dclose(d);
  return e;
}

#endif

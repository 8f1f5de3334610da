/* sweep_check — reads catchup-sweep results files for the tests, through the
 * HDF5 API alone (not the writer's code):
 *
 *   sweep_check open FILE            every dataset opens and reads (after a kill)
 *   sweep_check compare A B          /summary (all fields but wall_time_s), /runs,
 *                                    /references (but wall_time_s), /variants equal
 *   sweep_check donelist FILE OUT    task ids with done = 1, one per line, into OUT
 *   sweep_check failed FILE          "3,7,11": done tasks with status < 0, and their status names
 *   sweep_check complete FILE        exit 0 iff every task and reference is done
 *   sweep_check refdiff FILE V CSV TOL   max |/references/x[V] - CSV| at the CSV's rows
 *                                    t = j T / (samples - 1) (CSV on a finer grid k / (rows - 1))
 *   sweep_check forget-reference FILE V  make reference V not done and its tasks' errors NaN, as if
 *                                    they had finished before it (for --resume to fill them)
 *   compare A B nox                  the same without /runs/x (a sweep with output.samples 0)
 *   crowd-vs-run FILE TASK RUN.h5    a crowd sweep's task against catchup-run's file of the same
 *                                    scene: /crowd's agents, agents out, evacuation time (the
 *                                    largest /crowd/exit_time), smallest gap (of /steps/gap) and
 *                                    /summary's steps and certified (eps, eta), all exactly equal;
 *                                    /runs/x (if stored): the run's /x, NaN beyond its 2N
 *   crowd-forget FILE TASK           task TASK not done, its /crowd row spoilt (for --resume)
 *
 * Exit status 0 on success, 1 on a difference or failed check (one line
 * saying which), 2 on usage. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <hdf5.h>

typedef struct { void *buf; hid_t type; hsize_t n; size_t size; } table;

static int read_all(hid_t f, const char *name, table *t) {
  memset(t, 0, sizeof *t);
  hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
  if (d < 0) return -1;
  hid_t ft = H5Dget_type(d), sp = H5Dget_space(d);
  t->type = H5Tget_native_type(ft, H5T_DIR_ASCEND);
  t->n = (hsize_t)H5Sget_simple_extent_npoints(sp);
  t->size = H5Tget_size(t->type);
  t->buf = calloc(t->n ? t->n : 1, t->size);
  int r = t->buf && H5Dread(d, t->type, H5S_ALL, H5S_ALL, H5P_DEFAULT, t->buf) >= 0 ? 0 : -1;
  H5Sclose(sp);
  H5Tclose(ft);
  H5Dclose(d);
  return r;
}

/* (variable-length strings inside /variants are left to the process exit) */
static void free_table(table *t) {
  free(t->buf);
  if (t->type > 0) H5Tclose(t->type);
}

static int same_double(const void *a, const void *b) {
  double x, y;
  memcpy(&x, a, 8);
  memcpy(&y, b, 8);
  return x == y || (isnan(x) && isnan(y));
}

/* Compare element i of two tables of the same type, skipping `skip`. */
static int same_element(hid_t type, const char *a, const char *b, const char *skip, char *which) {
  H5T_class_t c = H5Tget_class(type);
  if (c == H5T_COMPOUND) {
    int nm = H5Tget_nmembers(type);
    for (int k = 0; k < nm; k++) {
      char *name = H5Tget_member_name(type, (unsigned)k);
      hid_t mt = H5Tget_member_type(type, (unsigned)k);
      size_t off = H5Tget_member_offset(type, (unsigned)k);
      int ok = (skip && !strcmp(name, skip)) || same_element(mt, a + off, b + off, NULL, which);
      if (!ok) snprintf(which, 64, "%s", name);
      H5Tclose(mt);
      H5free_memory(name);
      if (!ok) return 0;
    }
    return 1;
  }
  if (c == H5T_STRING && H5Tis_variable_str(type) > 0) {
    const char *x = *(char *const *)(const void *)a, *y = *(char *const *)(const void *)b;
    return (!x && !y) || (x && y && !strcmp(x, y));
  }
  if (c == H5T_FLOAT && H5Tget_size(type) == 8) return same_double(a, b);
  return memcmp(a, b, H5Tget_size(type)) == 0;
}

static int compare_dataset(hid_t fa, hid_t fb, const char *name, const char *skip, int optional) {
  table a, b;
  int ra = read_all(fa, name, &a), rb = read_all(fb, name, &b), ok = 1;
  if (ra || rb) {
    ok = optional && ra && rb;
    if (!ok) printf("sweep_check: %s: cannot read in %s\n", name, ra ? "the first file" : "the second file");
  } else if (a.n != b.n || H5Tequal(a.type, b.type) <= 0) {
    printf("sweep_check: %s: shapes or types differ\n", name);
    ok = 0;
  } else {
    char which[64] = "";
    for (hsize_t i = 0; i < a.n && ok; i++)
      if (!same_element(a.type, (char *)a.buf + i * a.size, (char *)b.buf + i * b.size, skip, which)) {
        printf("sweep_check: %s: element %llu differs (%s)\n", name, (unsigned long long)i, which);
        ok = 0;
      }
  }
  free_table(&a);
  free_table(&b);
  return ok;
}

static hid_t open_file(const char *path) {
  hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) printf("sweep_check: %s: cannot open\n", path);
  return f;
}

static int cmd_compare(const char *pa, const char *pb, int with_x) {
  hid_t fa = open_file(pa), fb = open_file(pb);
  if (fa < 0 || fb < 0) return 1;
  int ok = compare_dataset(fa, fb, "summary", "wall_time_s", 0) &&
           compare_dataset(fa, fb, "runs/t", NULL, 0) &&
           (!with_x || compare_dataset(fa, fb, "runs/x", NULL, 1)) &&
           compare_dataset(fa, fb, "references/x", NULL, 0) &&
           compare_dataset(fa, fb, "references/summary", "wall_time_s", 0) &&
           compare_dataset(fa, fb, "variants", NULL, 0) &&
           compare_dataset(fa, fb, "crowd", NULL, 1);
  H5Fclose(fa);
  H5Fclose(fb);
  if (ok) printf("sweep_check: %s and %s hold the same results\n", pa, pb);
  return ok ? 0 : 1;
}

static int cmd_open(const char *path) {
  hid_t f = open_file(path);
  if (f < 0) return 1;
  const char *names[] = {"summary", "runs/t", "references/x", "references/summary", "variants"};
  table t;
  for (size_t k = 0; k < sizeof names / sizeof names[0]; k++) {
    if (read_all(f, names[k], &t)) { printf("sweep_check: %s: cannot read %s\n", path, names[k]); return 1; }
    free_table(&t);
  }
  if (H5Lexists(f, "runs/x", H5P_DEFAULT) > 0) {
    if (read_all(f, "runs/x", &t)) { printf("sweep_check: %s: cannot read runs/x\n", path); return 1; }
    free_table(&t);
  }
  H5Fclose(f);
  return 0;
}

/* One column of /summary (or another compound dataset) as native values. */
static void *column(hid_t f, const char *dset, const char *field, hid_t type, hsize_t *n) {
  hid_t d = H5Dopen2(f, dset, H5P_DEFAULT);
  if (d < 0) return NULL;
  hid_t sp = H5Dget_space(d);
  *n = (hsize_t)H5Sget_simple_extent_npoints(sp);
  size_t size = H5Tget_size(type);
  hid_t mt = H5Tcreate(H5T_COMPOUND, size);
  H5Tinsert(mt, field, 0, type);
  void *buf = calloc(*n ? *n : 1, size);
  if (buf && H5Dread(d, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0) { free(buf); buf = NULL; }
  H5Tclose(mt);
  H5Sclose(sp);
  H5Dclose(d);
  return buf;
}

static int cmd_donelist(const char *path, const char *out) {
  hid_t f = open_file(path);
  if (f < 0) return 1;
  hsize_t n = 0;
  signed char *done = column(f, "summary", "done", H5T_NATIVE_SCHAR, &n);
  FILE *o = fopen(out, "w");
  if (!done || !o) { printf("sweep_check: %s: cannot read done flags or write %s\n", path, out); return 1; }
  long count = 0;
  for (hsize_t i = 0; i < n; i++)
    if (done[i]) { fprintf(o, "%llu\n", (unsigned long long)i); count++; }
  fclose(o);
  printf("%ld\n", count);
  free(done);
  H5Fclose(f);
  return 0;
}

static int cmd_failed(const char *path) {
  hid_t f = open_file(path);
  if (f < 0) return 1;
  hsize_t n = 0, n2 = 0;
  signed char *done = column(f, "summary", "done", H5T_NATIVE_SCHAR, &n);
  int *status = column(f, "summary", "status", H5T_NATIVE_INT, &n2);
  hid_t st = H5Tcopy(H5T_C_S1);
  H5Tset_size(st, 32);
  H5Tset_cset(st, H5T_CSET_UTF8);         /* the file's strings are UTF-8 (format 3) */
  char *names = column(f, "summary", "status_name", st, &n2);
  H5Tclose(st);
  if (!done || !status || !names) { printf("sweep_check: %s: cannot read /summary\n", path); return 1; }
  int first = 1;
  for (hsize_t i = 0; i < n; i++)
    if (done[i] && status[i] < 0) {
      printf("%s%llu:%.32s", first ? "" : ",", (unsigned long long)i, names + 32 * i);
      first = 0;
    }
  printf("\n");
  free(done);
  free(status);
  free(names);
  H5Fclose(f);
  return 0;
}

static int cmd_complete(const char *path) {
  hid_t f = open_file(path);
  if (f < 0) return 1;
  hsize_t n = 0, nr = 0, left = 0;
  signed char *done = column(f, "summary", "done", H5T_NATIVE_SCHAR, &n);
  signed char *rdone = column(f, "references/summary", "done", H5T_NATIVE_SCHAR, &nr);
  if (!done || !rdone) { printf("sweep_check: %s: cannot read done flags\n", path); return 1; }
  for (hsize_t i = 0; i < n; i++) left += !done[i];
  for (hsize_t i = 0; i < nr; i++) left += !rdone[i];
  free(done);
  free(rdone);
  H5Fclose(f);
  if (left) printf("sweep_check: %s: %llu jobs not done\n", path, (unsigned long long)left);
  return left ? 1 : 0;
}

static int cmd_refdiff(const char *path, int v, const char *csv, double tol) {
  hid_t f = open_file(path);
  if (f < 0) return 1;
  table x;
  if (read_all(f, "references/x", &x)) { printf("sweep_check: cannot read /references/x\n"); return 1; }
  hid_t d = H5Dopen2(f, "references/x", H5P_DEFAULT), sp = H5Dget_space(d);
  hsize_t dims[3];
  H5Sget_simple_extent_dims(sp, dims, NULL);
  H5Sclose(sp);
  H5Dclose(d);
  FILE *c = fopen(csv, "r");
  if (!c) { printf("sweep_check: cannot open %s\n", csv); return 1; }
  char line[1024];
  double *rows = NULL;
  long nrow = 0, cap = 0;
  int dim = (int)dims[2];
  if (!fgets(line, sizeof line, c)) return 1;            /* header */
  while (fgets(line, sizeof line, c)) {
    if (nrow == cap) rows = realloc(rows, sizeof(double) * (size_t)((cap = 2 * cap + 1024) * (dim + 1)));
    char *p = line;
    for (int j = 0; j <= dim; j++) { rows[nrow * (dim + 1) + j] = strtod(p, &p); if (*p == ',') p++; }
    nrow++;
  }
  fclose(c);
  long S = (long)dims[1];
  if ((nrow - 1) % (S - 1)) { printf("sweep_check: %ld CSV rows do not hold %ld samples\n", nrow, S); return 1; }
  long stride = (nrow - 1) / (S - 1);
  const double *xr = (const double *)x.buf + (size_t)v * (size_t)(S * dim);
  double e = 0;
  for (long j = 0; j < S; j++)
    for (int i = 0; i < dim; i++) {
      double dd = fabs(xr[j * dim + i] - rows[j * stride * (dim + 1) + 1 + i]);
      e = isnan(dd) ? INFINITY : fmax(e, dd);
    }
  printf("sweep_check: reference of variant %d vs %s: max |difference| = %.3g over %ld samples\n", v, csv, e, S);
  free(rows);
  free_table(&x);
  H5Fclose(f);
  return e <= tol ? 0 : 1;
}

/* Write one field of the rows selected by `pick` (NULL: all). */
static int write_field(hid_t d, const char *field, hid_t type, const void *value, const int *pick, hsize_t n) {
  hid_t mt = H5Tcreate(H5T_COMPOUND, H5Tget_size(type));
  H5Tinsert(mt, field, 0, type);
  hid_t fs = H5Dget_space(d), ms = H5Screate_simple(1, (hsize_t[]){1}, NULL);
  int ok = 1;
  for (hsize_t i = 0; i < n && ok; i++) {
    if (pick && !pick[i]) continue;
    hsize_t one = 1;
    ok = H5Sselect_hyperslab(fs, H5S_SELECT_SET, &i, NULL, &one, NULL) >= 0 &&
         H5Dwrite(d, mt, ms, fs, H5P_DEFAULT, value) >= 0;
  }
  H5Sclose(ms);
  H5Sclose(fs);
  H5Tclose(mt);
  return ok ? 0 : -1;
}

static int cmd_forget_reference(const char *path, int v) {
  hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
  if (f < 0) { printf("sweep_check: %s: cannot open for writing\n", path); return 1; }
  hsize_t n = 0, nr = 0;
  int *variant = column(f, "summary", "variant", H5T_NATIVE_INT, &n);
  int *rvariant = column(f, "references/summary", "variant", H5T_NATIVE_INT, &nr);
  if (!variant || !rvariant || v < 0 || (hsize_t)v >= nr) { printf("sweep_check: no variant %d\n", v); return 1; }
  int *pick = calloc(n, sizeof *pick), *rpick = calloc(nr, sizeof *rpick);
  for (hsize_t i = 0; i < n; i++) pick[i] = variant[i] == v;
  rpick[v] = 1;
  double nan = NAN;
  signed char zero = 0;
  hid_t s = H5Dopen2(f, "summary", H5P_DEFAULT), r = H5Dopen2(f, "references/summary", H5P_DEFAULT);
  int bad = write_field(s, "error", H5T_NATIVE_DOUBLE, &nan, pick, n) ||
            write_field(r, "done", H5T_NATIVE_SCHAR, &zero, rpick, nr);
  hid_t x = H5Dopen2(f, "references/x", H5P_DEFAULT), sp = H5Dget_space(x);
  hsize_t dims[3];
  H5Sget_simple_extent_dims(sp, dims, NULL);
  hsize_t start[3] = {(hsize_t)v, 0, 0}, cnt[3] = {1, dims[1], dims[2]};
  double *buf = malloc(sizeof(double) * dims[1] * dims[2]);
  for (hsize_t i = 0; i < dims[1] * dims[2]; i++) buf[i] = NAN;
  hid_t ms = H5Screate_simple(3, cnt, NULL);
  bad |= H5Sselect_hyperslab(sp, H5S_SELECT_SET, start, NULL, cnt, NULL) < 0 ||
         H5Dwrite(x, H5T_NATIVE_DOUBLE, ms, sp, H5P_DEFAULT, buf) < 0;
  H5Sclose(ms); H5Sclose(sp); H5Dclose(x); H5Dclose(s); H5Dclose(r);
  free(buf); free(pick); free(rpick); free(variant); free(rvariant);
  H5Fclose(f);
  if (bad) printf("sweep_check: %s: cannot write\n", path);
  return bad ? 1 : 0;
}

/* ---- crowd sweeps ---- */

static int read_doubles(hid_t f, const char *name, table *t) {
  int r = read_all(f, name, t);
  return r || H5Tget_class(t->type) != H5T_FLOAT || t->size != 8 ? -1 : 0;
}

static double attr_double(hid_t f, const char *name) {
  double v = NAN;
  hid_t a = H5Aopen(f, name, H5P_DEFAULT);
  if (a >= 0) { H5Aread(a, H5T_NATIVE_DOUBLE, &v); H5Aclose(a); }
  return v;
}

static int differs(const char *what, double sweep, double run) {
  if (sweep == run || (isnan(sweep) && isnan(run))) return 0;
  printf("sweep_check: %s: %.17g in the sweep, %.17g in the run\n", what, sweep, run);
  return 1;
}

static int cmd_crowd_vs_run(const char *path, long task, const char *runpath) {
  hid_t f = open_file(path), r = open_file(runpath);
  if (f < 0 || r < 0) return 1;
  hsize_t n = 0;
  double *evac = column(f, "crowd", "evacuation_time", H5T_NATIVE_DOUBLE, &n);
  double *gap = column(f, "crowd", "min_gap", H5T_NATIVE_DOUBLE, &n);
  int *agents = column(f, "crowd", "agents", H5T_NATIVE_INT, &n);
  int *out = column(f, "crowd", "agents_out", H5T_NATIVE_INT, &n);
  long long *steps = column(f, "summary", "stopped_step", H5T_NATIVE_LLONG, &n);
  double *eps = column(f, "summary", "max_eps_cert", H5T_NATIVE_DOUBLE, &n);
  double *eta = column(f, "summary", "max_eta_cert", H5T_NATIVE_DOUBLE, &n);
  table exit_t, gaps;
  if (!evac || !gap || !agents || !out || !steps || !eps || !eta || task < 0 || (hsize_t)task >= n ||
      read_doubles(r, "crowd/exit_time", &exit_t) || read_doubles(r, "steps/gap", &gaps)) {
    printf("sweep_check: cannot read task %ld of %s's /crowd and /summary, or %s's /crowd and /steps\n", task,
           path, runpath);
    return 1;
  }
  const double *et = exit_t.buf, *g = gaps.buf;
  double last = -INFINITY, min_gap = INFINITY;
  long gone = 0;
  for (hsize_t i = 0; i < exit_t.n; i++)
    if (!isnan(et[i])) { gone++; last = fmax(last, et[i]); }
  for (hsize_t i = 0; i < gaps.n; i++) min_gap = fmin(min_gap, g[i]);
  int bad = differs("agents", agents[task], (double)exit_t.n) + differs("agents out", out[task], (double)gone) +
            differs("evacuation time", evac[task], gone == (long)exit_t.n ? last : NAN) +
            differs("smallest gap", gap[task], min_gap) +
            differs("steps", (double)steps[task], (double)(gaps.n - 1)) +
            differs("max eps_cert", eps[task], attr_double(r, "max_eps_cert")) +
            differs("max eta_cert", eta[task], attr_double(r, "max_eta_cert"));
  table xs, xr;
  if (!read_doubles(f, "runs/x", &xs)) {
    if (read_doubles(r, "x", &xr)) return 1;
    hsize_t dim2 = 2 * exit_t.n, samples = xr.n / dim2, dim = xs.n / n / samples;
    const double *a = (const double *)xs.buf + task * samples * dim, *b = xr.buf;
    for (hsize_t j = 0; j < samples * dim && !bad; j++)
      bad = differs("/runs/x", a[j], j % dim < dim2 ? b[j / dim * dim2 + j % dim] : NAN);
    free_table(&xs);
    free_table(&xr);
  }
  if (!bad)
    printf("sweep_check: task %ld: %d agents, %d out, evacuation %.4g s, smallest gap %.3g, as in %s\n", task,
           agents[task], out[task], evac[task], gap[task], runpath);
  free(evac); free(gap); free(agents); free(out); free(steps); free(eps); free(eta);
  free_table(&exit_t);
  free_table(&gaps);
  H5Fclose(f);
  H5Fclose(r);
  return bad ? 1 : 0;
}

static int cmd_crowd_forget(const char *path, long task) {
  hid_t f = H5Fopen(path, H5F_ACC_RDWR, H5P_DEFAULT);
  if (f < 0) { printf("sweep_check: %s: cannot open for writing\n", path); return 1; }
  hsize_t n = 0;
  int *variant = column(f, "crowd", "variant", H5T_NATIVE_INT, &n);
  if (!variant || task < 0 || (hsize_t)task >= n) { printf("sweep_check: no task %ld in /crowd\n", task); return 1; }
  int *pick = calloc(n, sizeof *pick);
  pick[task] = 1;
  signed char zero = 0;
  double spoilt = -1;
  int minus = -1;
  hid_t s = H5Dopen2(f, "summary", H5P_DEFAULT), c = H5Dopen2(f, "crowd", H5P_DEFAULT);
  int bad = write_field(s, "done", H5T_NATIVE_SCHAR, &zero, pick, n) ||
            write_field(c, "done", H5T_NATIVE_SCHAR, &zero, pick, n) ||
            write_field(c, "evacuation_time", H5T_NATIVE_DOUBLE, &spoilt, pick, n) ||
            write_field(c, "min_gap", H5T_NATIVE_DOUBLE, &spoilt, pick, n) ||
            write_field(c, "agents_out", H5T_NATIVE_INT, &minus, pick, n);
  H5Dclose(s); H5Dclose(c);
  free(pick); free(variant);
  H5Fclose(f);
  if (bad) printf("sweep_check: %s: cannot write\n", path);
  return bad ? 1 : 0;
}

int main(int argc, char **argv) {
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  if (argc == 3 && !strcmp(argv[1], "open")) return cmd_open(argv[2]);
  if (argc == 4 && !strcmp(argv[1], "compare")) return cmd_compare(argv[2], argv[3], 1);
  if (argc == 5 && !strcmp(argv[1], "compare") && !strcmp(argv[4], "nox")) return cmd_compare(argv[2], argv[3], 0);
  if (argc == 4 && !strcmp(argv[1], "forget-reference")) return cmd_forget_reference(argv[2], atoi(argv[3]));
  if (argc == 4 && !strcmp(argv[1], "donelist")) return cmd_donelist(argv[2], argv[3]);
  if (argc == 3 && !strcmp(argv[1], "failed")) return cmd_failed(argv[2]);
  if (argc == 3 && !strcmp(argv[1], "complete")) return cmd_complete(argv[2]);
  if (argc == 6 && !strcmp(argv[1], "refdiff")) return cmd_refdiff(argv[2], atoi(argv[3]), argv[4], atof(argv[5]));
  if (argc == 5 && !strcmp(argv[1], "crowd-vs-run")) return cmd_crowd_vs_run(argv[2], atol(argv[3]), argv[4]);
  if (argc == 4 && !strcmp(argv[1], "crowd-forget")) return cmd_crowd_forget(argv[2], atol(argv[3]));
  fprintf(stderr, "usage: sweep_check open|compare|donelist|failed|complete|refdiff|forget-reference|"
          "crowd-vs-run|crowd-forget ...\n");
  return 2;
}

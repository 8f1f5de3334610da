/* sweep_file_create — creating the results file of a sweep (sweep_file.h):
 * every group, dataset and attribute, the /variants table and the pending
 * /summary rows are written here, up front, then flushed once; afterwards
 * sweep_file.c only overwrites raw bytes (the design is in sweep_h5.h). */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <sys/stat.h>
#include <hdf5.h>
#include <hdf5_hl.h>
#include "catchup/h5run.h"
#include "sweep_crowd.h"
#include "sweep_steady.h"
#include "sweep_file.h"
#include "sweep_h5.h"

typedef struct sw_varrow {
  int32_t variant;
  char name[SW_NAME_LEN];
  char *scene_file, *overrides, *scene;
  int64_t n_ref;
} sw_varrow;

static hid_t varrow_type(void) {
  hid_t T = H5Tcreate(H5T_COMPOUND, sizeof(sw_varrow));
  hid_t sname = sw_h5_str(SW_NAME_LEN), vs = h5_vlen_str();
  H5Tinsert(T, "variant", HOFFSET(sw_varrow, variant), H5T_NATIVE_INT32);
  H5Tinsert(T, "name", HOFFSET(sw_varrow, name), sname);
  H5Tinsert(T, "scene_file", HOFFSET(sw_varrow, scene_file), vs);
  H5Tinsert(T, "overrides", HOFFSET(sw_varrow, overrides), vs);
  H5Tinsert(T, "scene", HOFFSET(sw_varrow, scene), vs);
  H5Tinsert(T, "n_ref", HOFFSET(sw_varrow, n_ref), H5T_NATIVE_INT64);
  H5Tclose(sname);
  H5Tclose(vs);
  return T;
}

static hid_t fixed_group(hid_t loc, const char *name) {
  hid_t gcpl = H5Pcreate(H5P_GROUP_CREATE);
  H5Pset_obj_track_times(gcpl, 0);
  hid_t g = H5Gcreate2(loc, name, H5P_DEFAULT, gcpl, H5P_DEFAULT);
  H5Pclose(gcpl);
  return g;
}

static int attr_write(hid_t loc, const char *name, hid_t type, int rank, hsize_t len, const void *buf) {
  hid_t space = rank ? H5Screate_simple(1, &len, NULL) : H5Screate(H5S_SCALAR);
  hid_t a = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT);
  int ok = a >= 0 && H5Awrite(a, type, buf) >= 0;
  if (a >= 0) H5Aclose(a);
  H5Sclose(space);
  return ok ? 0 : -1;
}

static int attr_str(hid_t loc, const char *name, const char *v) {
  hid_t t = h5_vlen_str();
  int r = attr_write(loc, name, t, 0, 0, &v);
  H5Tclose(t);
  return r;
}

static int attr_i64(hid_t loc, const char *name, int64_t v) {
  return attr_write(loc, name, H5T_NATIVE_INT64, 0, 0, &v);
}

static int attr_f64(hid_t loc, const char *name, double v) {
  return attr_write(loc, name, H5T_NATIVE_DOUBLE, 0, 0, &v);
}

static int attr_strs(hid_t loc, const char *name, const char *const *v, int len) {
  hid_t t = h5_vlen_str();
  int r = attr_write(loc, name, t, 1, (hsize_t)len, v);
  H5Tclose(t);
  return r;
}

static const char *const reference_adaptive =
  "per variant: the adaptive scheme at tol = 1e-13 (absolute and relative), at the common sample times "
  "t_j = j T / (samples - 1) (exact flow between events located by root finding; docs/adaptive.md); "
  "/references/summary 'correction' holds that run's a posteriori error estimate.";

static const char *const reference_checked =
  "per variant: the adaptive scheme at tol = 1e-13 (absolute and relative), at the common sample times "
  "t_j = j T / (samples - 1) (exact flow between events located by root finding; docs/adaptive.md); "
  "/references/summary 'correction' holds that run's a posteriori error estimate, 'cross_check' its max-norm "
  "difference from the Richardson limit 2 x(2 n_ref) - x(n_ref) of two exact-projection explicit runs.";

static const char *const reference_method =
  "per variant: Richardson extrapolation x_ref = 2 x(2 n_ref) - x(n_ref) of two exact-projection "
  "(eps = eta = 0, certified to rounding) explicit catching-up runs, at the common sample times "
  "t_j = j T / (samples - 1); n_ref is a multiple of samples - 1 (auto: the smallest one >= 4 x the "
  "largest n of the variant's tasks). The scheme is first order, so the extrapolation removes the 1/n "
  "term; /references/summary 'correction' = max |x(2 n_ref) - x(n_ref)| bounds what it removed.";

static int write_grid_attrs(hid_t root, const sw_sweep *s) {
  int r = 0;
  if (s->len[SW_AXIS_N]) {
    int64_t *n = malloc(sizeof *n * (size_t)s->len[SW_AXIS_N]);
    if (!n) return -1;
    for (int k = 0; k < s->len[SW_AXIS_N]; k++) n[k] = s->n[k];
    r |= attr_write(root, "grid_n", H5T_NATIVE_INT64, 1, (hsize_t)s->len[SW_AXIS_N], n);
    free(n);
  }
  if (s->len[SW_AXIS_EPS]) r |= attr_strs(root, "grid_eps", (const char *const *)s->eps, s->len[SW_AXIS_EPS]);
  if (s->len[SW_AXIS_ETA]) r |= attr_strs(root, "grid_eta", (const char *const *)s->eta, s->len[SW_AXIS_ETA]);
  if (s->len[SW_AXIS_TOL])
    r |= attr_write(root, "grid_tol", H5T_NATIVE_DOUBLE, 1, (hsize_t)s->len[SW_AXIS_TOL], s->tol);
  int ls = s->len[SW_AXIS_SCHEME], lp = s->len[SW_AXIS_PROJECTOR];
  const char **w = malloc(sizeof *w * (size_t)(ls > lp ? ls : lp) + 1);
  if (!w) return -1;
  for (int k = 0; k < ls; k++) w[k] = cup_scheme_name(s->scheme[k]);
  if (ls) r |= attr_strs(root, "grid_scheme", w, ls);
  for (int k = 0; k < lp; k++) w[k] = cup_proj_method_name(s->projector[k]);
  if (lp) r |= attr_strs(root, "grid_projector", w, lp);
  free(w);
  char *g = sw_grid_text(s);
  r |= g ? attr_str(root, "grid", g) : -1;
  free(g);
  return r;
}

static int write_root_attrs(hid_t root, const sw_sweep *s, const sw_provenance *p) {
  char created[64];
  time_t now = time(NULL);
  struct tm tm;
  gmtime_r(&now, &tm);
  strftime(created, sizeof created, "%Y-%m-%dT%H:%M:%SZ", &tm);
  int r = attr_str(root, "format", FORMAT_NAME);
  r |= attr_str(root, "catchup_version", p->catchup_version);
  r |= attr_str(root, "dependency_versions", p->dependency_versions);
  r |= attr_str(root, "git_revision", p->git_revision);
  r |= attr_str(root, "command", p->command ? p->command : "");
  r |= attr_str(root, "created", created);
  r |= attr_str(root, "sweep_name", s->name);
  r |= attr_str(root, "sweep_file", s->path);
  r |= attr_str(root, "sweep_text", s->text);
  r |= attr_str(root, "sweep_sha256", s->sha256);
  char *inputs = file_list_text(&s->files);   /* every file read, for --resume (and sha256sum -c) */
  r |= inputs ? attr_str(root, "inputs_sha256", inputs) : -1;
  free(inputs);
  r |= attr_str(root, "reference_method", s->crowd ? SW_CROWD_REFERENCE : s->steady ? SW_STEADY_REFERENCE
                : s->ref_method == SW_REF_ADAPTIVE ? (s->ref_check ? reference_checked : reference_adaptive)
                : reference_method);
  r |= attr_i64(root, "samples", s->samples);
  r |= attr_i64(root, "output_samples", s->out_samples);
  r |= attr_f64(root, "T", s->T);
  r |= attr_i64(root, "dim", s->dim);
  r |= attr_i64(root, "n_variants", s->n_variants);
  r |= attr_i64(root, "n_tasks", s->n_tasks);
  return r | write_grid_attrs(root, s);
}

static void pending_summary_row(const sw_sweep *s, long id, void *row) { sw_pending_row(s, id, row); }

static int create_summary(sw_file *f) {
  return sw_h5_task_table(f, "summary", f->row_t, sizeof(sw_row), pending_summary_row, &f->summary);
}

/* A steady-state sweep has no reference trajectories, and its references'
 * rows are done at creation (none: each task's figures are its result):
 * no job computes them. */
static int create_references(sw_file *f, hid_t g) {
  const sw_sweep *s = f->s;
  double nan = NAN;
  hsize_t V = (hsize_t)s->n_variants, dims[3] = {V, (hsize_t)s->samples, (hsize_t)s->dim};
  if (!s->steady && (f->ref_x = sw_h5_fixed_dataset(g, "x", H5T_IEEE_F64LE, 3, dims, H5T_NATIVE_DOUBLE, &nan)) < 0)
    return sw_h5_fail(f, "create /references/x in");
  dims[2] = (hsize_t)s->nsig;
  if (!s->steady && s->nsig &&
      (f->ref_sig = sw_h5_fixed_dataset(g, "signals", H5T_IEEE_F64LE, 3, dims, H5T_NATIVE_DOUBLE, &nan)) < 0)
    return sw_h5_fail(f, "create /references/signals in");
  hid_t ft = H5Tcopy(f->refrow_t);
  H5Tpack(ft);
  f->ref_summary = sw_h5_fixed_dataset(g, "summary", ft, 1, &V, 0, NULL);
  H5Tclose(ft);
  if (f->ref_summary < 0) return sw_h5_fail(f, "create /references/summary in");
  sw_refrow *rows = calloc(V, sizeof *rows);
  if (!rows) return CUP_ERR_NOMEM;
  for (hsize_t k = 0; k < V; k++) {
    rows[k].variant = (int32_t)k;
    sw_copy_str(rows[k].variant_name, sizeof rows[k].variant_name, s->var[k].name);
    rows[k].n_ref = s->var[k].n_ref;
    rows[k].status = CUP_ERR_INTERRUPTED;
    sw_copy_str(rows[k].status_name, sizeof rows[k].status_name, "pending");
    rows[k].wall_time_s = rows[k].correction = rows[k].cross_check = rows[k].max_eps_cert = rows[k].max_eta_cert = NAN;
    if (!s->steady) continue;
    rows[k].status = CUP_OK;
    sw_copy_str(rows[k].status_name, sizeof rows[k].status_name, cup_status_name(CUP_OK));
    sw_copy_str(rows[k].message, sizeof rows[k].message, SW_STEADY_REFERENCE);
    rows[k].wall_time_s = 0;
    rows[k].done = 1;
    f->ref_done[k] = 1;
  }
  int st = sw_h5_write_rows(f->ref_summary, f->refrow_t, 0, V, rows, H5P_DEFAULT) ? sw_h5_fail(f, "write /references/summary in") : 0;
  free(rows);
  return st;
}

static char *join_overrides(const sw_variant *v) {
  size_t len = 1;
  for (int j = 0; j < v->n_set; j++) len += strlen(v->set[j]) + 2;
  char *s = malloc(len);
  if (!s) return NULL;
  s[0] = '\0';
  for (int j = 0; j < v->n_set; j++) {
    if (j) strcat(s, "; ");
    strcat(s, v->set[j]);
  }
  return s;
}

static int create_variants(sw_file *f) {
  const sw_sweep *s = f->s;
  hsize_t V = (hsize_t)s->n_variants;
  hid_t mt = varrow_type();
  f->failed |= mt < 0;
  sw_varrow *rows = calloc(V, sizeof *rows);
  int st = rows ? CUP_OK : CUP_ERR_NOMEM;
  for (hsize_t k = 0; k < V && !st; k++) {
    const sw_variant *v = &s->var[k];
    rows[k].variant = (int32_t)k;
    sw_copy_str(rows[k].name, sizeof rows[k].name, v->name);
    rows[k].scene_file = v->scene_file;
    rows[k].scene = v->scene_text;
    rows[k].n_ref = v->n_ref;
    if (!(rows[k].overrides = join_overrides(v))) st = CUP_ERR_NOMEM;
  }
  hid_t d = -1;
  if (!st) {
    hid_t ft = H5Tcopy(mt);
    H5Tpack(ft);
    d = sw_h5_fixed_dataset(f->file, "variants", ft, 1, &V, 0, NULL);
    H5Tclose(ft);
    if (d < 0 || sw_h5_write_rows(d, mt, 0, V, rows, H5P_DEFAULT)) st = sw_h5_fail(f, "write /variants in");
  }
  if (d >= 0) H5Dclose(d);
  for (hsize_t k = 0; rows && k < V; k++) free(rows[k].overrides);
  free(rows);
  H5Tclose(mt);
  return st;
}

/* ---- description: CF attributes and netCDF-4 dimensions ---- */

static int describe(hid_t d, const char *units, const char *long_name) {
  return (units ? attr_str(d, "units", units) : 0) | attr_str(d, "long_name", long_name);
}

static int describe_path(hid_t file, const char *path, const char *units, const char *long_name) {
  hid_t d = H5Dopen2(file, path, H5P_DEFAULT);
  int r = d < 0 ? -1 : describe(d, units, long_name);
  if (d >= 0) H5Dclose(d);
  return r;
}

/* A dimension without a coordinate, netCDF-4's way (see h5run.c). */
static int pure_dim(hid_t loc, const char *name, hsize_t len) {
  char nc[80];
  snprintf(nc, sizeof nc, "This is a netCDF dimension but not a netCDF variable.%10llu", (unsigned long long)len);
  hid_t d = sw_h5_fixed_dataset(loc, name, H5T_IEEE_F32LE, 1, &len, 0, NULL);
  int r = d < 0 || H5DSset_scale(d, nc) < 0 ? -1 : 0;
  if (d >= 0) H5Dclose(d);
  return r;
}

/* Attach the scales at the paths dims[k] (NULL: none) to path's axes. */
static int attach(hid_t file, const char *path, int rank, const char *const *dims) {
  hid_t d = H5Dopen2(file, path, H5P_DEFAULT);
  int r = d < 0 ? -1 : 0;
  for (int k = 0; k < rank && !r; k++) {
    if (!dims[k]) continue;
    hid_t s = H5Dopen2(file, dims[k], H5P_DEFAULT);
    r = s < 0 || H5DSattach_scale(d, s, (unsigned)k) < 0 ? -1 : 0;
    if (s >= 0) H5Dclose(s);
  }
  if (d >= 0) H5Dclose(d);
  return r;
}

/* Labels: n variable-length strings at path, made the dimension scale `scale`. */
static int label_scale(hid_t file, const char *path, const char *scale, const char *const *names, hsize_t n,
                       const char *long_name) {
  hid_t t = h5_vlen_str(), sp = H5Screate_simple(1, &n, NULL);
  hid_t d = H5Dcreate2(file, path, t, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  int r = d < 0 || H5Dwrite(d, t, H5S_ALL, H5S_ALL, H5P_DEFAULT, names) < 0 || H5DSset_scale(d, scale) < 0 ||
          describe(d, NULL, long_name) ? -1 : 0;
  if (d >= 0) H5Dclose(d);
  H5Sclose(sp);
  H5Tclose(t);
  return r;
}

/* Appends unit to the list "u1, u2, ..." in units (size bytes); returns the
 * bytes written so far. */
static size_t add_unit(char *units, size_t size, size_t w, const char *unit) {
  if (w + strlen(unit) + 3 < size) w += (size_t)snprintf(units + w, size - w, "%s%s", w ? ", " : "", unit);
  return w;
}

/* /runs/state: the names of the state's components (the variant with the
 * largest state's: a crowd's x0, y0, ... up to the largest N), and the unit
 * of /runs/x: the components' one unit, or their units in order. */
static int write_state(hid_t file, const sw_sweep *s, char *units, size_t size) {
  hsize_t n = (hsize_t)s->dim;
  const cup_scene *sc = s->var[0].scene;
  for (int k = 0; k < s->n_variants; k++)
    if (cup_scene_dim(sw_variant_settings(s, k)) == s->dim) { sc = sw_variant_settings(s, k); break; }
  char **names = calloc(n, sizeof *names);
  int r = names ? 0 : -1, same = 1;
  const char *first = NULL;
  size_t w = 0;
  units[0] = '\0';
  for (hsize_t j = 0; j < n && !r; j++) {
    char buf[128];
    const char *u = "1";
    cup_scene_state_label(sc, (int)j, buf, sizeof buf, &u);
    if (!(names[j] = strdup(buf))) r = -1;
    if (!first) first = u;
    same &= !strcmp(u, first);
    w = add_unit(units, size, w, u);
  }
  if (same && first) snprintf(units, size, "%s", first);
  if (!r) r = label_scale(file, "runs/state", "state", (const char *const *)names, n,
                          "state component: the last axis of /runs/x and /references/x");
  for (hsize_t j = 0; names && j < n; j++) free(names[j]);
  free(names);
  return r;
}

/* A netlist sweep's signals: /runs/signal (their names, the scale
 * "signal"), and their units, in order, as catchup-run's /signals. */
static int describe_signals(sw_file *f) {
  const sw_sweep *s = f->s;
  const cup_netlist *nl = cup_scene_netlist(s->var[0].scene);
  hsize_t n = (hsize_t)s->nsig;
  const char **names = malloc(sizeof *names * n);
  char units[512] = "";
  size_t w = 0;
  for (hsize_t k = 0; names && k < n; k++) {
    names[k] = sw_signal_name(s, (int)k);
    w = add_unit(units, sizeof units, w, cup_netlist_signal_unit(nl, (int)k));
  }
  int r = names ? label_scale(f->file, "runs/signal", "signal", names, n,
                              "a netlist's signal: the last axis of /runs/signals and /references/signals") : -1;
  free(names);
  if (f->ref_sig >= 0) {
    r |= describe(f->ref_sig, units, "each variant's reference signals at the sample times");
    r |= attach(f->file, "references/signals", 3, (const char *const[]){"variant", "runs/t", "runs/signal"});
  }
  if (f->runs_sig >= 0) {
    r |= describe(f->runs_sig, units, "each task's signals (node voltages, branch currents) at the sample times");
    r |= attach(f->file, "runs/signals", 3, (const char *const[]){"task", "runs/t", "runs/signal"});
  }
  return r;
}

/* Units, long names and dimensions (task, variant, t, state) of every
 * dataset, written with the rest of the metadata at creation. */
static int describe_layout(sw_file *f) {
  const sw_sweep *s = f->s;
  hid_t file = f->file;
  char xunits[256];
  int r = pure_dim(file, "task", (hsize_t)s->n_tasks) | pure_dim(file, "variant", (hsize_t)s->n_variants);
  r |= write_state(file, s, xunits, sizeof xunits);
  r |= describe_path(file, "runs/t", "s", "common sample time t_j = j T / (samples - 1)");
  hid_t t = H5Dopen2(file, "runs/t", H5P_DEFAULT);
  r |= t < 0 || H5DSset_scale(t, "t") < 0 ? -1 : 0;
  if (t >= 0) H5Dclose(t);
  r |= describe(f->summary, NULL, "one row per task: its parameters, status, error and certificates (docs/sweep-format.md)");
  r |= attach(file, "summary", 1, (const char *const[]){"task"});
  r |= describe_path(file, "variants", NULL, "the variants: name, scene file, overrides, scene text");
  r |= attach(file, "variants", 1, (const char *const[]){"variant"});
  r |= describe(f->ref_summary, NULL, "each variant's reference: method, status, correction");
  r |= attach(file, "references/summary", 1, (const char *const[]){"variant"});
  if (f->ref_x >= 0) {
    r |= describe(f->ref_x, xunits, "each variant's reference trajectory at the sample times");
    r |= attach(file, "references/x", 3, (const char *const[]){"variant", "runs/t", "runs/state"});
  }
  if (f->runs_x >= 0) {
    r |= describe(f->runs_x, xunits, "each task's state at the sample times (NaN where not reached)");
    r |= attach(file, "runs/x", 3, (const char *const[]){"task", "runs/t", "runs/state"});
  }
  if (s->nsig) r |= describe_signals(f);
  if (s->crowd) {
    r |= describe(f->crowd, NULL, "one row per task: agents, agents out, evacuation time [s], smallest gap [m]");
    r |= attach(file, "crowd", 1, (const char *const[]){"task"});
  }
  if (s->steady) {
    r |= describe(f->steady, NULL, "one row per task: the steady state's period [s], Newton steps, residual, largest "
                  "Floquet multiplier modulus, efficiency, and each measured signal's average, rms, min, max and "
                  "peak-to-peak over the period (the signal's units)");
    r |= attach(file, "steady_state", 1, (const char *const[]){"task"});
  }
  return r;
}

static int create_layout(sw_file *f, const sw_provenance *p) {
  const sw_sweep *s = f->s;
  if (write_root_attrs(f->file, s, p)) return sw_h5_fail(f, "write attributes in");
  int st = create_variants(f);
  if (!st) st = create_summary(f);
  if (!st && s->crowd) st = sw_crowd_create(f);
  if (!st && s->steady) st = sw_steady_create(f);
  hid_t g = st ? -1 : fixed_group(f->file, "runs");
  if (!st && g < 0) st = sw_h5_fail(f, "create /runs in");
  if (!st) {
    hsize_t S = (hsize_t)s->samples;
    double *t = malloc(sizeof(double) * S);
    if (!t) st = CUP_ERR_NOMEM;
    for (hsize_t j = 0; t && j < S; j++)    /* t_j = j T / (S - 1), t_{S-1} = T exactly */
      t[j] = j + 1 == S ? s->T : (double)j * (s->T / (double)(S - 1));
    hid_t d = st ? -1 : sw_h5_fixed_dataset(g, "t", H5T_IEEE_F64LE, 1, &S, 0, NULL);
    if (!st && (d < 0 || H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, t) < 0))
      st = sw_h5_fail(f, "write /runs/t in");
    if (d >= 0) H5Dclose(d);
    free(t);
  }
  if (!st && s->out_samples > 0) {
    double nan = NAN;
    hsize_t dims[3] = {(hsize_t)s->n_tasks, (hsize_t)s->samples, (hsize_t)s->dim};
    f->runs_x = sw_h5_fixed_dataset(g, "x", H5T_IEEE_F64LE, 3, dims, H5T_NATIVE_DOUBLE, &nan);
    if (f->runs_x < 0) st = sw_h5_fail(f, "create /runs/x in");
    dims[2] = (hsize_t)s->nsig;
    if (!st && s->nsig && (f->runs_sig = sw_h5_fixed_dataset(g, "signals", H5T_IEEE_F64LE, 3, dims, H5T_NATIVE_DOUBLE,
                                                       &nan)) < 0)
      st = sw_h5_fail(f, "create /runs/signals in");
  }
  if (g >= 0) H5Gclose(g);
  g = st ? -1 : fixed_group(f->file, "references");
  if (!st && g < 0) st = sw_h5_fail(f, "create /references in");
  if (!st) st = create_references(f, g);
  if (g >= 0) H5Gclose(g);
  if (!st && describe_layout(f)) st = sw_h5_fail(f, "describe the datasets in");
  if (!st && H5Fflush(f->file, H5F_SCOPE_LOCAL) < 0) st = sw_h5_fail(f, "flush");
  return st;
}

static double file_bytes(const sw_sweep *s) {
  double rows = (double)s->n_tasks * (sizeof(sw_row) + 16 + (s->crowd ? sizeof(sw_crowd_row) : 0) +
                                       (s->steady ? sizeof(sw_steady_row) : 0));
  double traj = (double)sw_traj_len(s) * 8.0 * ((s->out_samples ? (double)s->n_tasks : 0) + s->n_variants);
  return rows + traj + 65536.0 + 2.0 * strlen(s->text);
}

int sw_file_create(sw_file **out, const char *path, const sw_sweep *s, const sw_provenance *p, char *errmsg) {
  *out = NULL;
  struct stat sb;
  if (stat(path, &sb) == 0 && !S_ISREG(sb.st_mode)) {
    snprintf(errmsg, SW_ERR_LEN, "%s: cannot create: not a regular file", path);
    return CUP_ERR_IO;
  }
  if (h5_file_in_use(path)) {
    snprintf(errmsg, SW_ERR_LEN, SW_IN_USE_FMT, path, "create");
    return CUP_ERR_IO;
  }
  double need = file_bytes(s), avail = 0;
  if (h5_space_short(path, 1, need, &avail)) {
    snprintf(errmsg, SW_ERR_LEN, "%s: cannot create: the file needs %.3g MiB and %u MiB kept free beside it, and "
             "its device has %.3g MiB free (store fewer samples: output.samples)", path, need / 1048576,
             CUP_H5_SPACE_MARGIN >> 20, avail / 1048576);
    return CUP_ERR_IO;
  }
  /* the whole layout goes to a new sibling first, renamed over path once
   * written: an earlier results file stays whole until then */
  char *staged = h5_staged_name(path);
  if (!staged) {
    snprintf(errmsg, SW_ERR_LEN, "%s: cannot create: cannot create a file beside it (%s): its folder must take "
             "new files; an existing %s is left as it was", path, strerror(errno), path);
    return CUP_ERR_IO;
  }
  sw_file *f = sw_h5_file_new(s, path);
  if (!f) { unlink(staged); free(staged); snprintf(errmsg, SW_ERR_LEN, "%s: out of memory", path); return CUP_ERR_NOMEM; }
  quiet_t q = quiet_begin();
  hid_t fapl = h5_file_access(1);          /* raw writes go out at once, in order */
  f->file = fapl < 0 ? H5I_INVALID_HID : H5Fcreate(staged, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  int st = f->file < 0 ? sw_h5_fail(f, "create") : create_layout(f, p);
  if (fapl >= 0) H5Pclose(fapl);
  quiet_end(q);
  if (!st && h5_file_in_use(path)) {
    snprintf(f->errmsg, sizeof f->errmsg, SW_IN_USE_FMT, path, "replace");
    st = CUP_ERR_IO;
  }
  if (!st && rename(staged, path) != 0) {
    snprintf(f->errmsg, sizeof f->errmsg, "%s: cannot replace it: %s; the file is left as it was", path,
             strerror(errno));
    st = CUP_ERR_IO;
  }
  if (st) {
    snprintf(errmsg, SW_ERR_LEN, "%s", f->errmsg[0] ? f->errmsg : "out of memory");
    sw_h5_file_free(f);
    unlink(staged);
  }
  free(staged);
  if (!st) *out = f;
  return st;
}


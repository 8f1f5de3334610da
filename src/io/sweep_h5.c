/* sweep_h5 — the results file of a sweep (docs/sweep-format.md, "Output").
 *
 * Crash safety by a fixed layout instead of SWMR. Everything that is
 * metadata — every group, dataset, attribute, the /variants table with its
 * variable-length strings, the task parameters in /summary — is written when
 * the file is created, followed by one H5Fflush. Every dataset is contiguous
 * and allocated early (at its full size, filled with NaN or the pending
 * rows), and object modification times are not tracked, so afterwards a
 * result only overwrites raw bytes at fixed offsets: no B-tree, heap or
 * object header changes ever again. The file uses the 1.8 format (superblock
 * version 0: no "open for writing" flag, so no h5clear after a kill; the
 * same lesson as h5run.c). HDF5's sieve buffer is switched off so that every
 * H5Dwrite reaches the operating system when it returns, in our order: a
 * task's trajectory first, then its /summary row with done = 1. A process
 * killed at any point therefore leaves a file that opens as is, with every
 * row whose done flag is 1 complete (strace shows two pwrites per task after
 * the first flush, and H5Fclose rewriting an identical superblock). H5Fflush
 * still runs regularly (it
 * writes nothing here but is what HDF5 promises consistency for), and does
 * not fsync: a machine crash may lose what the OS had not written.
 *
 * The full allocation at creation also means the disk cannot fill up during
 * the run (HDF5 1.10 cannot close a file after a failed write, h5run.c). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <libgen.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <hdf5.h>
#include "file_in_use.h"
#include "sweep.h"

#define FORMAT_NAME "catchup-sweep 1"
#define SPACE_MARGIN (8.0 * 1048576)

/* One /summary row in memory (the file type is the same, packed). */
typedef struct sw_row {
  int64_t task_id;
  int32_t variant;
  char variant_name[SW_NAME_LEN];
  int64_t n;
  char eps[SW_SPEC_LEN];
  double eps_value;
  char eta[SW_SPEC_LEN];
  double eta_value;
  char scheme[SW_WORD_LEN];
  char projector[SW_WORD_LEN];
  int32_t status;
  char status_name[SW_STATUS_LEN];
  char message[SW_MSG_LEN];
  int32_t error_code;
  double wall_time_s, error, max_eps_cert, max_eta_cert;
  int64_t projected, skipped, not_certified, dual_iterations, factorizations, stopped_step;
  int8_t done;
} sw_row;

typedef struct sw_refrow {
  int32_t variant;
  char variant_name[SW_NAME_LEN];
  int64_t n_ref;
  int32_t status;
  char status_name[SW_STATUS_LEN];
  char message[SW_MSG_LEN];
  double wall_time_s, correction, max_eps_cert, max_eta_cert;
  int64_t dual_iterations;
  int8_t done;
} sw_refrow;

typedef struct sw_varrow {
  int32_t variant;
  char name[SW_NAME_LEN];
  char *scene_file, *overrides, *scene;
  int64_t n_ref;
} sw_varrow;

struct sw_file {
  const cup_sweep *s;
  char *path;
  hid_t file, summary, runs_x, ref_x, ref_summary;
  hid_t row_t, refrow_t;           /* memory types */
  hid_t dxpl;                      /* small conversion buffers (see file_new) */
  int failed;                      /* an HDF5 call failed: only close is attempted */
  int8_t *done;                    /* per task */
  int32_t *status;
  double *error;
  int8_t *ref_done;                /* per variant */
  double **xref;                   /* per variant, samples * dim, NULL while unknown */
  char errmsg[SW_ERR_LEN];
};

/* ---- HDF5 errors: never printed; the innermost description is kept ---- */

typedef struct { H5E_auto2_t fn; void *data; } quiet_t;

static quiet_t quiet_begin(void) {
  quiet_t q = {NULL, NULL};
  H5Eget_auto2(H5E_DEFAULT, &q.fn, &q.data);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  return q;
}

static void quiet_end(quiet_t q) { H5Eset_auto2(H5E_DEFAULT, q.fn, q.data); }

#define IN_USE_FMT "%s: cannot %s: the file is in use by another process (HDF5 file locking; another " \
  "catchup-sweep may be writing it): wait for that run to end, or stop it, then --resume; the file is " \
  "left as it was"

typedef struct { char desc[160]; int locked; } h5_err;

static herr_t innermost(unsigned n, const H5E_error2_t *e, void *out) {
  h5_err *r = out;
  if (n == 0 && e->desc) snprintf(r->desc, sizeof r->desc, "%s", e->desc);
  if (e->min_num == H5E_CANTLOCKFILE) r->locked = 1;
  return 0;
}

/* Call right after the failed HDF5 call: any later API call (even
 * H5Pclose) clears the error stack that says why. */
static int h5_fail(sw_file *f, const char *op) {
  h5_err e = {"", 0};
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, innermost, &e);
  if (!e.desc[0]) snprintf(e.desc, sizeof e.desc, "HDF5 call failed");
  if (!f->errmsg[0] && e.locked) snprintf(f->errmsg, sizeof f->errmsg, IN_USE_FMT, f->path, op);
  if (!f->errmsg[0]) snprintf(f->errmsg, sizeof f->errmsg, "%s: cannot %s: %s", f->path, op, e.desc);
  f->failed = 1;
  H5Eclear2(H5E_DEFAULT);
  return CUP_ERR_IO;
}

const char *sw_file_errmsg(const sw_file *f) { return f ? f->errmsg : ""; }

/* ---- types ---- */

static hid_t str_type(size_t size) {
  hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, size);
  H5Tset_strpad(t, H5T_STR_NULLTERM);
  return t;
}

static hid_t vlen_str_type(void) {
  hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, H5T_VARIABLE);
  H5Tset_cset(t, H5T_CSET_UTF8);
  return t;
}

#define INS(T, name, field, type) H5Tinsert(T, name, HOFFSET(sw_row, field), type)
static hid_t row_type(void) {
  hid_t T = H5Tcreate(H5T_COMPOUND, sizeof(sw_row));
  hid_t sname = str_type(SW_NAME_LEN), sspec = str_type(SW_SPEC_LEN), sword = str_type(SW_WORD_LEN),
        sstat = str_type(SW_STATUS_LEN), smsg = str_type(SW_MSG_LEN);
  INS(T, "task_id", task_id, H5T_NATIVE_INT64);
  INS(T, "variant", variant, H5T_NATIVE_INT32);
  INS(T, "variant_name", variant_name, sname);
  INS(T, "n", n, H5T_NATIVE_INT64);
  INS(T, "eps", eps, sspec);
  INS(T, "eps_value", eps_value, H5T_NATIVE_DOUBLE);
  INS(T, "eta", eta, sspec);
  INS(T, "eta_value", eta_value, H5T_NATIVE_DOUBLE);
  INS(T, "scheme", scheme, sword);
  INS(T, "projector", projector, sword);
  INS(T, "status", status, H5T_NATIVE_INT32);
  INS(T, "status_name", status_name, sstat);
  INS(T, "message", message, smsg);
  INS(T, "error_code", error_code, H5T_NATIVE_INT32);
  INS(T, "wall_time_s", wall_time_s, H5T_NATIVE_DOUBLE);
  INS(T, "error", error, H5T_NATIVE_DOUBLE);
  INS(T, "max_eps_cert", max_eps_cert, H5T_NATIVE_DOUBLE);
  INS(T, "max_eta_cert", max_eta_cert, H5T_NATIVE_DOUBLE);
  INS(T, "projected", projected, H5T_NATIVE_INT64);
  INS(T, "skipped", skipped, H5T_NATIVE_INT64);
  INS(T, "not_certified", not_certified, H5T_NATIVE_INT64);
  INS(T, "dual_iterations", dual_iterations, H5T_NATIVE_INT64);
  INS(T, "factorizations", factorizations, H5T_NATIVE_INT64);
  INS(T, "stopped_step", stopped_step, H5T_NATIVE_INT64);
  INS(T, "done", done, H5T_NATIVE_INT8);
  H5Tclose(sname); H5Tclose(sspec); H5Tclose(sword); H5Tclose(sstat); H5Tclose(smsg);
  return T;
}
#undef INS

#define INS(T, name, field, type) H5Tinsert(T, name, HOFFSET(sw_refrow, field), type)
static hid_t refrow_type(void) {
  hid_t T = H5Tcreate(H5T_COMPOUND, sizeof(sw_refrow));
  hid_t sname = str_type(SW_NAME_LEN), sstat = str_type(SW_STATUS_LEN), smsg = str_type(SW_MSG_LEN);
  INS(T, "variant", variant, H5T_NATIVE_INT32);
  INS(T, "variant_name", variant_name, sname);
  INS(T, "n_ref", n_ref, H5T_NATIVE_INT64);
  INS(T, "status", status, H5T_NATIVE_INT32);
  INS(T, "status_name", status_name, sstat);
  INS(T, "message", message, smsg);
  INS(T, "wall_time_s", wall_time_s, H5T_NATIVE_DOUBLE);
  INS(T, "correction", correction, H5T_NATIVE_DOUBLE);
  INS(T, "max_eps_cert", max_eps_cert, H5T_NATIVE_DOUBLE);
  INS(T, "max_eta_cert", max_eta_cert, H5T_NATIVE_DOUBLE);
  INS(T, "dual_iterations", dual_iterations, H5T_NATIVE_INT64);
  INS(T, "done", done, H5T_NATIVE_INT8);
  H5Tclose(sname); H5Tclose(sstat); H5Tclose(smsg);
  return T;
}
#undef INS

static hid_t varrow_type(void) {
  hid_t T = H5Tcreate(H5T_COMPOUND, sizeof(sw_varrow));
  hid_t sname = str_type(SW_NAME_LEN), vs = vlen_str_type();
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

/* A one-field memory type for reading one column of a compound dataset. */
static hid_t column_type(const char *name, size_t size, hid_t type) {
  hid_t T = H5Tcreate(H5T_COMPOUND, size);
  H5Tinsert(T, name, 0, type);
  return T;
}

/* ---- creation ---- */

static hid_t file_access(void) {
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  H5Pset_libver_bounds(fapl, H5F_LIBVER_EARLIEST, H5F_LIBVER_V18);
  H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG);
  H5Pset_sieve_buf_size(fapl, 0);          /* raw writes go out at once, in order */
  return fapl;
}

/* Contiguous, allocated (and filled) at creation, no modification times. */
static hid_t fixed_dataset(hid_t loc, const char *name, hid_t ftype, int rank, const hsize_t *dims,
                           hid_t fill_type, const void *fill) {
  hid_t space = H5Screate_simple(rank, dims, NULL);
  hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_layout(dcpl, H5D_CONTIGUOUS);
  H5Pset_alloc_time(dcpl, H5D_ALLOC_TIME_EARLY);
  H5Pset_obj_track_times(dcpl, 0);
  if (fill) {
    H5Pset_fill_value(dcpl, fill_type, fill);
    H5Pset_fill_time(dcpl, H5D_FILL_TIME_ALLOC);
  }
  hid_t d = H5Dcreate2(loc, name, ftype, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  H5Pclose(dcpl);
  H5Sclose(space);
  return d;
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
  hid_t t = vlen_str_type();
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
  hid_t t = vlen_str_type();
  int r = attr_write(loc, name, t, 1, (hsize_t)len, v);
  H5Tclose(t);
  return r;
}

static const char *const reference_method =
  "per variant: Richardson extrapolation x_ref = 2 x(2 n_ref) - x(n_ref) of two exact-projection "
  "(eps = eta = 0, certified to rounding) explicit catching-up runs, at the common sample times "
  "t_j = j T / (samples - 1); n_ref is a multiple of samples - 1 (auto: the smallest one >= 4 x the "
  "largest n of the variant's tasks). The scheme is first order, so the extrapolation removes the 1/n "
  "term; /references/summary 'correction' = max |x(2 n_ref) - x(n_ref)| bounds what it removed.";

static int write_grid_attrs(hid_t root, const cup_sweep *s) {
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

static int write_root_attrs(hid_t root, const cup_sweep *s, const sw_provenance *p) {
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
  r |= attr_str(root, "reference_method", reference_method);
  r |= attr_i64(root, "samples", s->samples);
  r |= attr_i64(root, "output_samples", s->out_samples);
  r |= attr_f64(root, "T", s->T);
  r |= attr_i64(root, "dim", s->dim);
  r |= attr_i64(root, "n_variants", s->n_variants);
  r |= attr_i64(root, "n_tasks", s->n_tasks);
  return r | write_grid_attrs(root, s);
}

static void copy_str(char *dst, size_t size, const char *src) { snprintf(dst, size, "%s", src ? src : ""); }

/* A task's row before it ran: its parameters, status "pending". */
static void pending_row(const cup_sweep *s, long id, sw_row *r) {
  sw_task t;
  memset(r, 0, sizeof *r);
  sw_task_get(s, id, &t);
  r->task_id = id;
  r->variant = t.variant;
  copy_str(r->variant_name, sizeof r->variant_name, s->var[t.variant].name);
  r->n = t.n;
  copy_str(r->eps, sizeof r->eps, t.eps);
  copy_str(r->eta, sizeof r->eta, t.eta);
  r->eps_value = cup_schedule_value(&t.eps_s, t.n);
  r->eta_value = cup_schedule_value(&t.eta_s, t.n);
  copy_str(r->scheme, sizeof r->scheme, cup_scheme_name(t.scheme));
  copy_str(r->projector, sizeof r->projector, cup_proj_method_name(t.projector));
  r->status = r->error_code = CUP_ERR_INTERRUPTED;
  copy_str(r->status_name, sizeof r->status_name, "pending");
  r->wall_time_s = r->error = r->max_eps_cert = r->max_eta_cert = NAN;
}

static int write_rows(hid_t d, hid_t memtype, hsize_t at, hsize_t count, const void *buf, hid_t dxpl) {
  hid_t fs = H5Dget_space(d), ms = H5Screate_simple(1, &count, NULL);
  int ok = fs >= 0 && ms >= 0 && H5Sselect_hyperslab(fs, H5S_SELECT_SET, &at, NULL, &count, NULL) >= 0 &&
           H5Dwrite(d, memtype, ms, fs, dxpl, buf) >= 0;
  if (ms >= 0) H5Sclose(ms);
  if (fs >= 0) H5Sclose(fs);
  return ok ? 0 : -1;
}

static int create_summary(sw_file *f) {
  const cup_sweep *s = f->s;
  hsize_t N = (hsize_t)s->n_tasks;
  hid_t ft = H5Tcopy(f->row_t);
  H5Tpack(ft);
  f->summary = fixed_dataset(f->file, "summary", ft, 1, &N, 0, NULL);
  H5Tclose(ft);
  if (f->summary < 0) return h5_fail(f, "create /summary in");
  enum { BLOCK = 1024 };
  sw_row *rows = malloc(sizeof *rows * BLOCK);
  if (!rows) return CUP_ERR_NOMEM;
  int st = CUP_OK;
  for (hsize_t at = 0; at < N && !st; at += BLOCK) {
    hsize_t cnt = N - at < BLOCK ? N - at : BLOCK;
    for (hsize_t k = 0; k < cnt; k++) pending_row(s, (long)(at + k), &rows[k]);
    if (write_rows(f->summary, f->row_t, at, cnt, rows, H5P_DEFAULT)) st = h5_fail(f, "write /summary in");
  }
  free(rows);
  return st;
}

static int create_references(sw_file *f, hid_t g) {
  const cup_sweep *s = f->s;
  double nan = NAN;
  hsize_t V = (hsize_t)s->n_variants, dims[3] = {V, (hsize_t)s->samples, (hsize_t)s->dim};
  f->ref_x = fixed_dataset(g, "x", H5T_IEEE_F64LE, 3, dims, H5T_NATIVE_DOUBLE, &nan);
  if (f->ref_x < 0) return h5_fail(f, "create /references/x in");
  hid_t ft = H5Tcopy(f->refrow_t);
  H5Tpack(ft);
  f->ref_summary = fixed_dataset(g, "summary", ft, 1, &V, 0, NULL);
  H5Tclose(ft);
  if (f->ref_summary < 0) return h5_fail(f, "create /references/summary in");
  sw_refrow *rows = calloc(V, sizeof *rows);
  if (!rows) return CUP_ERR_NOMEM;
  for (hsize_t k = 0; k < V; k++) {
    rows[k].variant = (int32_t)k;
    copy_str(rows[k].variant_name, sizeof rows[k].variant_name, s->var[k].name);
    rows[k].n_ref = s->var[k].n_ref;
    rows[k].status = CUP_ERR_INTERRUPTED;
    copy_str(rows[k].status_name, sizeof rows[k].status_name, "pending");
    rows[k].wall_time_s = rows[k].correction = rows[k].max_eps_cert = rows[k].max_eta_cert = NAN;
  }
  int st = write_rows(f->ref_summary, f->refrow_t, 0, V, rows, H5P_DEFAULT) ? h5_fail(f, "write /references/summary in") : 0;
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
  const cup_sweep *s = f->s;
  hsize_t V = (hsize_t)s->n_variants;
  hid_t mt = varrow_type();
  f->failed |= mt < 0;
  sw_varrow *rows = calloc(V, sizeof *rows);
  int st = rows ? CUP_OK : CUP_ERR_NOMEM;
  for (hsize_t k = 0; k < V && !st; k++) {
    const sw_variant *v = &s->var[k];
    rows[k].variant = (int32_t)k;
    copy_str(rows[k].name, sizeof rows[k].name, v->name);
    rows[k].scene_file = v->scene_file;
    rows[k].scene = v->scene_text;
    rows[k].n_ref = v->n_ref;
    if (!(rows[k].overrides = join_overrides(v))) st = CUP_ERR_NOMEM;
  }
  hid_t d = -1;
  if (!st) {
    hid_t ft = H5Tcopy(mt);
    H5Tpack(ft);
    d = fixed_dataset(f->file, "variants", ft, 1, &V, 0, NULL);
    H5Tclose(ft);
    if (d < 0 || write_rows(d, mt, 0, V, rows, H5P_DEFAULT)) st = h5_fail(f, "write /variants in");
  }
  if (d >= 0) H5Dclose(d);
  for (hsize_t k = 0; rows && k < V; k++) free(rows[k].overrides);
  free(rows);
  H5Tclose(mt);
  return st;
}

static int create_layout(sw_file *f, const sw_provenance *p) {
  const cup_sweep *s = f->s;
  if (write_root_attrs(f->file, s, p)) return h5_fail(f, "write attributes in");
  int st = create_variants(f);
  if (!st) st = create_summary(f);
  hid_t g = st ? -1 : fixed_group(f->file, "runs");
  if (!st && g < 0) st = h5_fail(f, "create /runs in");
  if (!st) {
    hsize_t S = (hsize_t)s->samples;
    double *t = malloc(sizeof(double) * S);
    if (!t) st = CUP_ERR_NOMEM;
    for (hsize_t j = 0; t && j < S; j++)    /* t_j = j T / (S - 1), t_{S-1} = T exactly */
      t[j] = j + 1 == S ? s->T : (double)j * (s->T / (double)(S - 1));
    hid_t d = st ? -1 : fixed_dataset(g, "t", H5T_IEEE_F64LE, 1, &S, 0, NULL);
    if (!st && (d < 0 || H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, t) < 0))
      st = h5_fail(f, "write /runs/t in");
    if (d >= 0) H5Dclose(d);
    free(t);
  }
  if (!st && s->out_samples > 0) {
    double nan = NAN;
    hsize_t dims[3] = {(hsize_t)s->n_tasks, (hsize_t)s->samples, (hsize_t)s->dim};
    f->runs_x = fixed_dataset(g, "x", H5T_IEEE_F64LE, 3, dims, H5T_NATIVE_DOUBLE, &nan);
    if (f->runs_x < 0) st = h5_fail(f, "create /runs/x in");
  }
  if (g >= 0) H5Gclose(g);
  g = st ? -1 : fixed_group(f->file, "references");
  if (!st && g < 0) st = h5_fail(f, "create /references in");
  if (!st) st = create_references(f, g);
  if (g >= 0) H5Gclose(g);
  if (!st && H5Fflush(f->file, H5F_SCOPE_LOCAL) < 0) st = h5_fail(f, "flush");
  return st;
}

/* ---- state ---- */

static sw_file *file_new(const cup_sweep *s, const char *path) {
  sw_file *f = calloc(1, sizeof *f);
  if (!f) return NULL;
  f->s = s;
  f->file = f->summary = f->runs_x = f->ref_x = f->ref_summary = H5I_INVALID_HID;
  f->path = strdup(path);
  size_t N = (size_t)s->n_tasks, V = (size_t)s->n_variants;
  f->done = calloc(N, 1);
  f->status = calloc(N, sizeof *f->status);
  f->error = malloc(N * sizeof *f->error);
  f->ref_done = calloc(V, 1);
  f->xref = calloc(V, sizeof *f->xref);
  f->row_t = row_type();
  f->refrow_t = refrow_type();
  /* A row write converts a compound type (to the packed file type): HDF5
   * would otherwise allocate and clear a 1 MiB conversion buffer each time. */
  f->dxpl = H5Pcreate(H5P_DATASET_XFER);
  H5Pset_buffer(f->dxpl, 4 * sizeof(sw_row), NULL, NULL);
  if (!f->path || !f->done || !f->status || !f->error || !f->ref_done || !f->xref) {
    free(f->path); free(f->done); free(f->status); free(f->error); free(f->ref_done); free(f->xref);
    H5Tclose(f->row_t); H5Tclose(f->refrow_t); H5Pclose(f->dxpl);
    free(f);
    return NULL;
  }
  for (size_t k = 0; k < N; k++) { f->error[k] = NAN; f->status[k] = CUP_ERR_INTERRUPTED; }
  return f;
}

static void file_free(sw_file *f) {
  quiet_t q = quiet_begin();
  hid_t h[] = {f->summary, f->runs_x, f->ref_x, f->ref_summary};
  for (size_t k = 0; k < sizeof h / sizeof h[0]; k++)
    if (h[k] >= 0) H5Dclose(h[k]);
  if (f->file >= 0) H5Fclose(f->file);
  H5Tclose(f->row_t);
  H5Tclose(f->refrow_t);
  H5Pclose(f->dxpl);
  H5Eclear2(H5E_DEFAULT);
  quiet_end(q);
  for (int k = 0; k < f->s->n_variants; k++) free(f->xref[k]);
  free(f->xref); free(f->ref_done); free(f->done); free(f->status); free(f->error); free(f->path);
  free(f);
}

static double file_bytes(const cup_sweep *s) {
  double rows = (double)s->n_tasks * (sizeof(sw_row) + 16);
  double traj = (double)s->samples * s->dim * 8.0 * ((s->out_samples ? (double)s->n_tasks : 0) + s->n_variants);
  return rows + traj + 65536.0 + 2.0 * strlen(s->text);
}

int sw_file_create(sw_file **out, const char *path, const cup_sweep *s, const sw_provenance *p, char *errmsg) {
  *out = NULL;
  struct stat sb;
  if (stat(path, &sb) == 0 && !S_ISREG(sb.st_mode)) {
    snprintf(errmsg, SW_ERR_LEN, "%s: cannot create: not a regular file", path);
    return CUP_ERR_IO;
  }
  if (cup_file_in_use(path)) {
    snprintf(errmsg, SW_ERR_LEN, IN_USE_FMT, path, "create");
    return CUP_ERR_IO;
  }
  char *copy = strdup(path);
  struct statvfs v;
  double need = file_bytes(s);
  if (copy && statvfs(dirname(copy), &v) == 0 && v.f_blocks &&
      (double)v.f_bavail * (double)v.f_frsize < need + SPACE_MARGIN) {
    snprintf(errmsg, SW_ERR_LEN, "%s: cannot create: the file needs %.0f MiB and its device has %.0f MiB free "
             "(store fewer samples: output.samples)", path, need / 1048576,
             (double)v.f_bavail * (double)v.f_frsize / 1048576);
    free(copy);
    return CUP_ERR_IO;
  }
  free(copy);
  sw_file *f = file_new(s, path);
  if (!f) { snprintf(errmsg, SW_ERR_LEN, "%s: out of memory", path); return CUP_ERR_NOMEM; }
  quiet_t q = quiet_begin();
  hid_t fapl = file_access();
  f->file = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  int st = f->file < 0 ? h5_fail(f, "create") : create_layout(f, p);
  H5Pclose(fapl);
  quiet_end(q);
  if (st) {
    snprintf(errmsg, SW_ERR_LEN, "%s", f->errmsg[0] ? f->errmsg : "out of memory");
    file_free(f);
    return st;
  }
  *out = f;
  return CUP_OK;
}

/* ---- resume ---- */

static int read_attr_str(hid_t loc, const char *name, char *buf, size_t size) {
  hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  if (a < 0) return -1;
  hid_t t = vlen_str_type();
  char *v = NULL;
  int ok = H5Aread(a, t, &v) >= 0;
  if (ok) snprintf(buf, size, "%s", v ? v : "");
  if (ok && v) H5free_memory(v);
  H5Tclose(t);
  H5Aclose(a);
  return ok ? 0 : -1;
}

static int read_attr_i64(hid_t loc, const char *name, int64_t *v) {
  hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  if (a < 0) return -1;
  int ok = H5Aread(a, H5T_NATIVE_INT64, v) >= 0;
  H5Aclose(a);
  return ok ? 0 : -1;
}

/* The stored layout must be the one this sweep makes. */
static int check_layout(sw_file *f, char *errmsg) {
  const cup_sweep *s = f->s;
  char fmt[64] = "", hash[80] = "";
  int64_t ntask = -1, samples = -1, dim = -1, nvar = -1, outs = -1;
  if (read_attr_str(f->file, "format", fmt, sizeof fmt) || strcmp(fmt, FORMAT_NAME) ||
      read_attr_str(f->file, "sweep_sha256", hash, sizeof hash)) {
    snprintf(errmsg, SW_ERR_LEN, "%s: cannot resume: not a catchup-sweep results file "
             "(or one killed while it was being created); run without --resume to start again", f->path);
    return CUP_ERR_IO;
  }
  if (strcmp(hash, s->sha256)) {
    snprintf(errmsg, SW_ERR_LEN, "%s: cannot resume: it was made from a different sweep file "
             "(stored SHA-256 %s, %s has %s)", f->path, hash, s->path, s->sha256);
    return CUP_ERR_ARG;
  }
  read_attr_i64(f->file, "n_tasks", &ntask);
  read_attr_i64(f->file, "samples", &samples);
  read_attr_i64(f->file, "dim", &dim);
  read_attr_i64(f->file, "n_variants", &nvar);
  read_attr_i64(f->file, "output_samples", &outs);
  if (ntask != s->n_tasks || samples != s->samples || dim != s->dim || nvar != s->n_variants ||
      outs != s->out_samples) {
    snprintf(errmsg, SW_ERR_LEN, "%s: cannot resume: its layout (%lld tasks, %lld variants, %lld samples, "
             "dimension %lld) differs from the sweep's (%ld, %d, %ld, %d)", f->path, (long long)ntask,
             (long long)nvar, (long long)samples, (long long)dim, s->n_tasks, s->n_variants, s->samples, s->dim);
    return CUP_ERR_ARG;
  }
  return CUP_OK;
}

/* A variant's scene (after overrides) must not have changed since the file
 * was made: the sweep file's hash does not cover the scene files. */
static int check_scenes(sw_file *f, char *errmsg) {
  const cup_sweep *s = f->s;
  hsize_t V = (hsize_t)s->n_variants;
  hid_t d = H5Dopen2(f->file, "variants", H5P_DEFAULT);
  hid_t vs = vlen_str_type(), mt = column_type("scene", sizeof(char *), vs);
  char **texts = calloc(V, sizeof *texts);
  int st = d < 0 || !texts || H5Dread(d, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, texts) < 0
               ? h5_fail(f, "read /variants in") : CUP_OK;
  for (hsize_t k = 0; k < V && !st; k++)
    if (!texts[k] || strcmp(texts[k], s->var[k].scene_text)) {
      snprintf(errmsg, SW_ERR_LEN, "%s: cannot resume: variant '%s' has a different scene now than when the "
               "file was made (%s or its overrides changed)", f->path, s->var[k].name, s->var[k].scene_file);
      st = CUP_ERR_ARG;
    }
  if (texts && st != CUP_ERR_IO) {
    hid_t space = H5Dget_space(d);
    H5Dvlen_reclaim(mt, space, H5P_DEFAULT, texts);
    H5Sclose(space);
  }
  free(texts);
  H5Tclose(mt);
  H5Tclose(vs);
  if (d >= 0) H5Dclose(d);
  return st;
}

static int read_column(sw_file *f, hid_t d, const char *name, hid_t type, size_t size, void *buf) {
  hid_t mt = column_type(name, size, type);
  int ok = H5Dread(d, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0;
  H5Tclose(mt);
  return ok ? CUP_OK : h5_fail(f, "read /summary in");
}

static int read_state(sw_file *f) {
  const cup_sweep *s = f->s;
  int st = read_column(f, f->summary, "done", H5T_NATIVE_INT8, 1, f->done);
  if (!st) st = read_column(f, f->summary, "status", H5T_NATIVE_INT32, 4, f->status);
  if (!st) st = read_column(f, f->summary, "error", H5T_NATIVE_DOUBLE, 8, f->error);
  if (!st) st = read_column(f, f->ref_summary, "done", H5T_NATIVE_INT8, 1, f->ref_done);
  int32_t *ref_status = calloc((size_t)s->n_variants, sizeof *ref_status);
  if (!ref_status) return CUP_ERR_NOMEM;
  if (!st) st = read_column(f, f->ref_summary, "status", H5T_NATIVE_INT32, 4, ref_status);
  long count = s->samples * s->dim;
  for (int k = 0; k < s->n_variants && !st; k++) {
    if (!f->ref_done[k] || ref_status[k] < 0) continue;   /* a failed reference gives no errors */
    if (!(f->xref[k] = malloc(sizeof(double) * (size_t)count))) { st = CUP_ERR_NOMEM; break; }
    hsize_t start[3] = {(hsize_t)k, 0, 0}, cnt[3] = {1, (hsize_t)s->samples, (hsize_t)s->dim};
    hid_t fs = H5Dget_space(f->ref_x), ms = H5Screate_simple(3, cnt, NULL);
    if (H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, cnt, NULL) < 0 ||
        H5Dread(f->ref_x, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, f->xref[k]) < 0)
      st = h5_fail(f, "read /references/x in");
    H5Sclose(ms);
    H5Sclose(fs);
  }
  free(ref_status);
  return st;
}

int sw_file_open(sw_file **out, const char *path, const cup_sweep *s, char *errmsg) {
  *out = NULL;
  struct stat sb;
  if (stat(path, &sb) != 0 || !S_ISREG(sb.st_mode)) {
    snprintf(errmsg, SW_ERR_LEN, "%s: cannot resume: no such file (run without --resume to create it)", path);
    return CUP_ERR_IO;
  }
  sw_file *f = file_new(s, path);
  if (!f) { snprintf(errmsg, SW_ERR_LEN, "%s: out of memory", path); return CUP_ERR_NOMEM; }
  quiet_t q = quiet_begin();
  hid_t fapl = file_access();
  f->file = H5Fopen(path, H5F_ACC_RDWR, fapl);
  int st = f->file < 0 ? h5_fail(f, "open") : CUP_OK;
  H5Pclose(fapl);
  if (!st) st = check_layout(f, errmsg);
  if (!st) {
    f->summary = H5Dopen2(f->file, "summary", H5P_DEFAULT);
    f->ref_x = H5Dopen2(f->file, "references/x", H5P_DEFAULT);
    f->ref_summary = H5Dopen2(f->file, "references/summary", H5P_DEFAULT);
    if (s->out_samples > 0) f->runs_x = H5Dopen2(f->file, "runs/x", H5P_DEFAULT);
    if (f->summary < 0 || f->ref_x < 0 || f->ref_summary < 0 || (s->out_samples > 0 && f->runs_x < 0))
      st = h5_fail(f, "open the datasets of");
  }
  if (!st) st = check_scenes(f, errmsg);
  if (!st) st = read_state(f);
  quiet_end(q);
  if (st) {
    if (f->errmsg[0] && (st == CUP_ERR_IO || st == CUP_ERR_NOMEM)) snprintf(errmsg, SW_ERR_LEN, "%s", f->errmsg);
    file_free(f);
    return st;
  }
  *out = f;
  return CUP_OK;
}

/* ---- the run: raw data only ---- */

int sw_file_task_done(const sw_file *f, long task) { return f->done[task]; }
double sw_file_task_error(const sw_file *f, long task) { return f->error[task]; }
int sw_file_task_status(const sw_file *f, long task) { return f->status[task]; }
const double *sw_file_reference(const sw_file *f, int variant) { return f->xref[variant]; }
int sw_file_reference_done(const sw_file *f, int variant) { return f->ref_done[variant]; }

static int write_traj(sw_file *f, hid_t d, hsize_t row, const double *traj) {
  const cup_sweep *s = f->s;
  hsize_t start[3] = {row, 0, 0}, cnt[3] = {1, (hsize_t)s->samples, (hsize_t)s->dim};
  hid_t fs = H5Dget_space(d), ms = H5Screate_simple(3, cnt, NULL);
  int ok = H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, cnt, NULL) >= 0 &&
           H5Dwrite(d, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, traj) >= 0;
  H5Sclose(ms);
  H5Sclose(fs);
  return ok ? 0 : -1;
}

static void result_row(const sw_file *f, long task, const sw_result *r, double error, sw_row *row) {
  pending_row(f->s, task, row);
  row->status = r->status;
  copy_str(row->status_name, sizeof row->status_name, cup_status_name(r->status));
  copy_str(row->message, sizeof row->message, r->message);
  row->error_code = r->status < 0 ? r->status : 0;
  row->wall_time_s = r->wall;
  row->error = error;
  row->max_eps_cert = r->max_eps_cert;
  row->max_eta_cert = r->max_eta_cert;
  row->projected = r->projected;
  row->skipped = r->skipped;
  row->not_certified = r->not_certified;
  row->dual_iterations = r->dual_iterations;
  row->factorizations = r->factorizations;
  row->stopped_step = r->stopped_step;
  row->done = 1;
}

int sw_file_write_task(sw_file *f, long task, const sw_result *r, const double *traj, double error) {
  if (f->failed) return CUP_ERR_IO;
  quiet_t q = quiet_begin();
  sw_row row;
  result_row(f, task, r, error, &row);
  int st = CUP_OK;
  if (f->runs_x >= 0 && write_traj(f, f->runs_x, (hsize_t)task, traj)) st = h5_fail(f, "write /runs/x in");
  if (!st && write_rows(f->summary, f->row_t, (hsize_t)task, 1, &row, f->dxpl)) st = h5_fail(f, "write /summary in");
  quiet_end(q);
  if (!st) {
    f->done[task] = 1;
    f->status[task] = r->status;
    f->error[task] = error;
  }
  return st;
}

int sw_file_set_error(sw_file *f, long task, double error) {
  if (f->failed) return CUP_ERR_IO;
  quiet_t q = quiet_begin();
  hsize_t at = (hsize_t)task, one = 1;
  sw_row row;
  hid_t fs = H5Dget_space(f->summary), ms = H5Screate_simple(1, &one, NULL);
  int ok = H5Sselect_hyperslab(fs, H5S_SELECT_SET, &at, NULL, &one, NULL) >= 0 &&
           H5Dread(f->summary, f->row_t, ms, fs, f->dxpl, &row) >= 0;
  H5Sclose(ms);
  H5Sclose(fs);
  int st = ok ? CUP_OK : h5_fail(f, "read /summary in");
  row.error = error;
  if (!st && write_rows(f->summary, f->row_t, at, 1, &row, f->dxpl)) st = h5_fail(f, "write /summary in");
  quiet_end(q);
  if (!st) f->error[task] = error;
  return st;
}

int sw_file_read_traj(sw_file *f, long task, double *traj) {
  if (f->runs_x < 0) return CUP_ERR_ARG;
  if (f->failed) return CUP_ERR_IO;
  const cup_sweep *s = f->s;
  quiet_t q = quiet_begin();
  hsize_t start[3] = {(hsize_t)task, 0, 0}, cnt[3] = {1, (hsize_t)s->samples, (hsize_t)s->dim};
  hid_t fs = H5Dget_space(f->runs_x), ms = H5Screate_simple(3, cnt, NULL);
  int ok = H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, cnt, NULL) >= 0 &&
           H5Dread(f->runs_x, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, traj) >= 0;
  H5Sclose(ms);
  H5Sclose(fs);
  int st = ok ? CUP_OK : h5_fail(f, "read /runs/x in");
  quiet_end(q);
  return st;
}

int sw_file_write_reference(sw_file *f, int k, const sw_result *r, const double *xref) {
  if (f->failed) return CUP_ERR_IO;
  const cup_sweep *s = f->s;
  sw_refrow row;
  memset(&row, 0, sizeof row);
  row.variant = k;
  copy_str(row.variant_name, sizeof row.variant_name, s->var[k].name);
  row.n_ref = s->var[k].n_ref;
  row.status = r->status;
  copy_str(row.status_name, sizeof row.status_name, cup_status_name(r->status));
  copy_str(row.message, sizeof row.message, r->message);
  row.wall_time_s = r->wall;
  row.correction = r->correction;
  row.max_eps_cert = r->max_eps_cert;
  row.max_eta_cert = r->max_eta_cert;
  row.dual_iterations = r->dual_iterations;
  row.done = 1;
  quiet_t q = quiet_begin();
  int st = write_traj(f, f->ref_x, (hsize_t)k, xref) ? h5_fail(f, "write /references/x in") : CUP_OK;
  if (!st && write_rows(f->ref_summary, f->refrow_t, (hsize_t)k, 1, &row, f->dxpl))
    st = h5_fail(f, "write /references/summary in");
  quiet_end(q);
  if (st) return st;
  f->ref_done[k] = 1;
  long count = s->samples * s->dim;
  if (r->status >= 0 && !f->xref[k]) {
    if (!(f->xref[k] = malloc(sizeof(double) * (size_t)count))) return CUP_ERR_NOMEM;
    memcpy(f->xref[k], xref, sizeof(double) * (size_t)count);
  }
  return CUP_OK;
}

int sw_file_flush(sw_file *f) {
  if (f->failed) return CUP_ERR_IO;
  quiet_t q = quiet_begin();
  int st = H5Fflush(f->file, H5F_SCOPE_LOCAL) < 0 ? h5_fail(f, "flush") : CUP_OK;
  quiet_end(q);
  return st;
}

int sw_file_close(sw_file **pf, char *errmsg) {
  if (!pf || !*pf) return CUP_OK;
  sw_file *f = *pf;
  int st = f->failed ? CUP_ERR_IO : sw_file_flush(f);
  quiet_t q = quiet_begin();
  hid_t h[] = {f->summary, f->runs_x, f->ref_x, f->ref_summary};
  for (size_t k = 0; k < sizeof h / sizeof h[0]; k++)
    if (h[k] >= 0 && H5Dclose(h[k]) < 0 && !st) st = h5_fail(f, "close a dataset of");
  f->summary = f->runs_x = f->ref_x = f->ref_summary = H5I_INVALID_HID;
  if (H5Fclose(f->file) < 0 && !st) st = h5_fail(f, "close");
  f->file = H5I_INVALID_HID;
  quiet_end(q);
  if (st && errmsg) snprintf(errmsg, SW_ERR_LEN, "%s", f->errmsg);
  file_free(f);
  *pf = NULL;
  return st;
}

/* sweep_file — the results file of a sweep once it exists (sweep_file.h):
 * reopening it for --resume, the raw writes of the run, and closing it;
 * creating it is sweep_file_create.c. The design, crash safety by a fixed
 * layout, is described in sweep_h5.h. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <hdf5.h>
#include "sweep_crowd.h"
#include "sweep_steady.h"
#include "sweep_file.h"
#include "sweep_h5.h"

const char *sw_file_errmsg(const sw_file *f) { return f ? f->errmsg : ""; }

/* A one-field memory type for reading one column of a compound dataset. */
static hid_t column_type(const char *name, size_t size, hid_t type) {
  hid_t T = H5Tcreate(H5T_COMPOUND, size);
  H5Tinsert(T, name, 0, type);
  return T;
}

/* ---- resume ---- */

static int read_attr_str(hid_t loc, const char *name, char *buf, size_t size) {
  hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  if (a < 0) return -1;
  hid_t t = h5_vlen_str();
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
  const sw_sweep *s = f->s;
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

/* Every file the sweep reads (its scenes, their Matrix Market files,
 * netlists and what those include) must hold what it held when the file
 * was made: the sweep file's hash covers none of them. A file made before
 * this check (no inputs_sha256) has the scene texts' check below only. */
static int check_inputs(sw_file *f, char *errmsg) {
  hid_t a = H5Aopen(f->file, "inputs_sha256", H5P_DEFAULT);
  if (a < 0) { H5Eclear2(H5E_DEFAULT); return CUP_OK; }
  hid_t t = h5_vlen_str();
  char *v = NULL;
  int st = H5Aread(a, t, &v) >= 0 ? CUP_OK : sw_h5_fail(f, "read the attribute inputs_sha256 of");
  H5Tclose(t);
  H5Aclose(a);
  if (!st) {
    int w = snprintf(errmsg, SW_ERR_LEN, "%s: cannot resume: ", f->path);
    if (file_list_compare(&f->s->files, v ? v : "", "the file", errmsg + w, (size_t)(SW_ERR_LEN - w))) {
      size_t len = strlen(errmsg);
      snprintf(errmsg + len, SW_ERR_LEN - len, "; run without --resume to start again");
      st = CUP_ERR_ARG;
    }
  }
  if (v) H5free_memory(v);
  return st;
}

/* A variant's scene (after overrides) must not have changed since the file
 * was made: the sweep file's hash does not cover the scene files. */
static int check_scenes(sw_file *f, char *errmsg) {
  const sw_sweep *s = f->s;
  hsize_t V = (hsize_t)s->n_variants;
  hid_t d = H5Dopen2(f->file, "variants", H5P_DEFAULT);
  hid_t vs = h5_vlen_str(), mt = column_type("scene", sizeof(char *), vs);
  char **texts = calloc(V, sizeof *texts);
  int st = d < 0 || !texts || H5Dread(d, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, texts) < 0
               ? sw_h5_fail(f, "read /variants in") : CUP_OK;
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
  return ok ? CUP_OK : sw_h5_fail(f, "read /summary in");
}

static int read_state(sw_file *f) {
  const sw_sweep *s = f->s;
  int st = read_column(f, f->summary, "done", H5T_NATIVE_INT8, 1, f->done);
  if (!st) st = read_column(f, f->summary, "status", H5T_NATIVE_INT32, 4, f->status);
  if (!st) st = read_column(f, f->summary, "error", H5T_NATIVE_DOUBLE, 8, f->error);
  if (!st) st = read_column(f, f->ref_summary, "done", H5T_NATIVE_INT8, 1, f->ref_done);
  int32_t *ref_status = calloc((size_t)s->n_variants, sizeof *ref_status);
  if (!ref_status) return CUP_ERR_NOMEM;
  if (!st) st = read_column(f, f->ref_summary, "status", H5T_NATIVE_INT32, 4, ref_status);
  long count = s->samples * s->dim;
  for (int k = 0; k < s->n_variants && !st; k++) {
    if (!f->ref_done[k] || ref_status[k] < 0 || f->ref_x < 0) continue;   /* a failed reference gives no errors */
    if (!(f->xref[k] = malloc(sizeof(double) * (size_t)count))) { st = CUP_ERR_NOMEM; break; }
    hsize_t start[3] = {(hsize_t)k, 0, 0}, cnt[3] = {1, (hsize_t)s->samples, (hsize_t)s->dim};
    hid_t fs = H5Dget_space(f->ref_x), ms = H5Screate_simple(3, cnt, NULL);
    if (H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, cnt, NULL) < 0 ||
        H5Dread(f->ref_x, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, f->xref[k]) < 0)
      st = sw_h5_fail(f, "read /references/x in");
    H5Sclose(ms);
    H5Sclose(fs);
  }
  free(ref_status);
  return st;
}

int sw_file_open(sw_file **out, const char *path, const sw_sweep *s, char *errmsg) {
  *out = NULL;
  struct stat sb;
  if (stat(path, &sb) != 0 || !S_ISREG(sb.st_mode)) {
    snprintf(errmsg, SW_ERR_LEN, "%s: cannot resume: no such file (run without --resume to create it)", path);
    return CUP_ERR_IO;
  }
  sw_file *f = sw_h5_file_new(s, path);
  if (!f) { snprintf(errmsg, SW_ERR_LEN, "%s: out of memory", path); return CUP_ERR_NOMEM; }
  quiet_t q = quiet_begin();
  hid_t fapl = h5_file_access(1);          /* raw writes go out at once, in order */
  f->file = fapl < 0 ? H5I_INVALID_HID : H5Fopen(path, H5F_ACC_RDWR, fapl);
  int st = f->file < 0 ? sw_h5_fail(f, "open") : CUP_OK;
  if (fapl >= 0) H5Pclose(fapl);
  if (!st) st = check_layout(f, errmsg);
  if (!st) {
    f->summary = H5Dopen2(f->file, "summary", H5P_DEFAULT);
    if (!s->steady) f->ref_x = H5Dopen2(f->file, "references/x", H5P_DEFAULT);
    f->ref_summary = H5Dopen2(f->file, "references/summary", H5P_DEFAULT);
    if (s->out_samples > 0) f->runs_x = H5Dopen2(f->file, "runs/x", H5P_DEFAULT);
    if (s->crowd) f->crowd = H5Dopen2(f->file, "crowd", H5P_DEFAULT);
    if (s->steady) f->steady = H5Dopen2(f->file, "steady_state", H5P_DEFAULT);
    if (s->nsig && !s->steady) f->ref_sig = H5Dopen2(f->file, "references/signals", H5P_DEFAULT);
    if (s->nsig && s->out_samples > 0) f->runs_sig = H5Dopen2(f->file, "runs/signals", H5P_DEFAULT);
    int refs = !s->steady;                     /* a steady-state sweep has no reference trajectories */
    if (f->summary < 0 || (refs && f->ref_x < 0) || f->ref_summary < 0 || (s->out_samples > 0 && f->runs_x < 0) ||
        (s->crowd && f->crowd < 0) || (s->steady && f->steady < 0) || (refs && s->nsig && f->ref_sig < 0) ||
        (s->nsig && s->out_samples > 0 && f->runs_sig < 0))
      st = sw_h5_fail(f, "open the datasets of");
  }
  if (!st) st = check_inputs(f, errmsg);
  if (!st) st = check_scenes(f, errmsg);
  if (!st) st = read_state(f);
  quiet_end(q);
  if (st) {
    if (f->errmsg[0] && (st == CUP_ERR_IO || st == CUP_ERR_NOMEM)) snprintf(errmsg, SW_ERR_LEN, "%s", f->errmsg);
    sw_h5_file_free(f);
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

static int write_traj(sw_file *f, hid_t d, hsize_t row, const double *traj, int width) {
  const sw_sweep *s = f->s;
  hsize_t start[3] = {row, 0, 0}, cnt[3] = {1, (hsize_t)s->samples, (hsize_t)width};
  hid_t fs = H5Dget_space(d), ms = H5Screate_simple(3, cnt, NULL);
  int ok = H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, cnt, NULL) >= 0 &&
           H5Dwrite(d, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, traj) >= 0;
  H5Sclose(ms);
  H5Sclose(fs);
  return ok ? 0 : -1;
}

static void result_row(const sw_file *f, long task, const sw_result *r, double error, sw_row *row) {
  sw_pending_row(f->s, task, row);
  row->status = r->status;
  sw_copy_str(row->status_name, sizeof row->status_name, cup_status_name(r->status));
  sw_copy_str(row->message, sizeof row->message, r->message);
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
  row->err_est = r->err_est;
  row->events = r->events;
  row->done = 1;
}

/* Room for count tasks in the staging buffers. */
static int reserve(sw_file *f, long count) {
  if (count <= f->cap) return CUP_OK;
  long cap = count > 2 * f->cap ? count : 2 * f->cap;
  size_t traj = (size_t)(f->s->samples * f->s->dim);
  long *ids = realloc(f->ids, sizeof *ids * (size_t)cap);
  if (ids) f->ids = ids;
  sw_row *rows = realloc(f->rows, sizeof *rows * (size_t)cap);
  if (rows) f->rows = rows;
  double *x = f->s->out_samples > 0 ? realloc(f->x, sizeof *x * traj * (size_t)cap) : NULL;
  if (x) f->x = x;
  sw_crowd_row *crows = f->s->crowd ? realloc(f->crows, sizeof *crows * (size_t)cap) : NULL;
  if (crows) f->crows = crows;
  sw_steady_row *ssrows = f->s->steady ? realloc(f->ssrows, sizeof *ssrows * (size_t)cap) : NULL;
  if (ssrows) f->ssrows = ssrows;
  int with_sig = f->runs_sig >= 0;
  size_t sig_len = (size_t)(f->s->samples * f->s->nsig);
  double *sig = with_sig ? realloc(f->sig, sizeof *sig * sig_len * (size_t)cap) : NULL;
  if (sig) f->sig = sig;
  if (!ids || !rows || (f->s->out_samples > 0 && !x) || (f->s->crowd && !crows) || (f->s->steady && !ssrows) ||
      (with_sig && !sig))
    return CUP_ERR_NOMEM;
  f->cap = cap;
  return CUP_OK;
}

void sw_file_tally(const sw_file *f, sw_tally *out) {
  const sw_sweep *s = f->s;
  sw_tally c = {0};
  double *scale = calloc((size_t)s->n_variants, sizeof *scale);
  long per = s->samples * s->dim;
  for (int k = 0; scale && k < s->n_variants; k++)
    for (long j = 0; f->xref[k] && j < per; j++) scale[k] = fmax(scale[k], fabs(f->xref[k][j]));
  for (long i = 0; i < s->n_tasks; i++) {
    if (!f->done[i]) continue;
    c.done++;
    int st = f->status[i], missed = 0;
    sw_task t;
    if (!sw_task_get(s, i, &t) && t.scheme == CUP_SCHEME_ADAPTIVE) {
      c.adaptive++;
      missed = scale && f->error[i] > t.tol_abs + t.tol_rel * scale[t.variant];
    }
    if (st < 0) c.failed++;
    else if (st == CUP_WARN_NOT_CERTIFIED) c.not_certified++;
    else if (st > 0) c.warned++;
    if (st >= 0 && missed) c.tol_missed++;
    if (st == CUP_OK && !missed) c.ok++;
  }
  free(scale);
  *out = c;
}

int sw_file_write_tasks(sw_file *f, const sw_task_out *t, long count) {
  if (f->failed) return CUP_ERR_IO;
  int st = count > 0 ? reserve(f, count) : CUP_OK;
  if (st || count <= 0) return st;
  long per = f->s->samples * f->s->dim;
  for (long j = 0; j < count; j++) {
    if (t[j].task < 0 || t[j].task >= f->s->n_tasks || (j && t[j].task <= t[j - 1].task)) {
      snprintf(f->errmsg, sizeof f->errmsg, "%s: cannot write task %ld (after task %ld): tasks go in increasing "
               "order, each once", f->path, t[j].task, j ? t[j - 1].task : -1L);
      return CUP_ERR_ARG;
    }
    f->ids[j] = t[j].task;
    result_row(f, t[j].task, t[j].r, t[j].error, &f->rows[j]);
    if (f->runs_x >= 0) memcpy(f->x + per * j, t[j].traj, sizeof(double) * (size_t)per);
    if (f->runs_sig >= 0)                      /* the signals follow the states (sw_traj_len) */
      memcpy(f->sig + f->s->samples * f->s->nsig * j, t[j].traj + per,
             sizeof(double) * (size_t)(f->s->samples * f->s->nsig));
  }
  quiet_t q = quiet_begin();
  if (f->runs_x >= 0) st = sw_h5_task_io(f, f->runs_x, H5T_NATIVE_DOUBLE, count, f->x, H5P_DEFAULT, 1, "write /runs/x in");
  if (!st && f->runs_sig >= 0)
    st = sw_h5_task_io(f, f->runs_sig, H5T_NATIVE_DOUBLE, count, f->sig, H5P_DEFAULT, 1, "write /runs/signals in");
  if (!st && f->crowd >= 0) st = sw_crowd_write(f, t, count);
  if (!st && f->steady >= 0) st = sw_steady_write(f, t, count);
  if (!st) st = sw_h5_task_io(f, f->summary, f->row_t, count, f->rows, H5P_DEFAULT, 1, "write /summary in");
  quiet_end(q);
  for (long j = 0; j < count && !st; j++) {
    f->done[t[j].task] = 1;
    f->status[t[j].task] = t[j].r->status;
    f->error[t[j].task] = t[j].error;
  }
  return st;
}

/* The tasks in f->ids[0..count): their trajectories and rows read back,
 * the rows written again with their error. */
static int fill_chunk(sw_file *f, const double *xref, long count) {
  long per = f->s->samples * f->s->dim;
  quiet_t q = quiet_begin();
  int st = sw_h5_task_io(f, f->runs_x, H5T_NATIVE_DOUBLE, count, f->x, H5P_DEFAULT, 0, "read /runs/x in");
  if (!st) st = sw_h5_task_io(f, f->summary, f->row_t, count, f->rows, H5P_DEFAULT, 0, "read /summary in");
  for (long j = 0; j < count && !st; j++) f->rows[j].error = sw_max_error(f->x + per * j, xref, per);
  if (!st) st = sw_h5_task_io(f, f->summary, f->row_t, count, f->rows, H5P_DEFAULT, 1, "write /summary in");
  quiet_end(q);
  for (long j = 0; j < count && !st; j++) f->error[f->ids[j]] = f->rows[j].error;
  return st;
}

int sw_file_fill_errors(sw_file *f, int k) {
  enum { CHUNK = 256 };
  const sw_sweep *s = f->s;
  if (!f->xref[k] || f->runs_x < 0) return CUP_OK;
  if (f->failed) return CUP_ERR_IO;
  int st = reserve(f, CHUNK);
  long n = 0, end = (k + 1) * s->per_variant;
  for (long t = k * s->per_variant; t < end && !st; t++) {
    if (f->done[t] && f->status[t] >= 0 && isnan(f->error[t])) f->ids[n++] = t;
    if (n == CHUNK || (n && t + 1 == end)) {
      st = fill_chunk(f, f->xref[k], n);
      n = 0;
    }
  }
  return st;
}

int sw_file_write_reference(sw_file *f, int k, const sw_result *r, const double *xref) {
  if (f->failed) return CUP_ERR_IO;
  const sw_sweep *s = f->s;
  sw_refrow row;
  memset(&row, 0, sizeof row);
  row.variant = k;
  sw_copy_str(row.variant_name, sizeof row.variant_name, s->var[k].name);
  row.n_ref = s->var[k].n_ref;
  row.status = r->status;
  sw_copy_str(row.status_name, sizeof row.status_name, cup_status_name(r->status));
  sw_copy_str(row.message, sizeof row.message, r->message);
  row.wall_time_s = r->wall;
  row.correction = r->correction;
  row.cross_check = r->cross_check;
  row.max_eps_cert = r->max_eps_cert;
  row.max_eta_cert = r->max_eta_cert;
  row.dual_iterations = r->dual_iterations;
  row.done = 1;
  quiet_t q = quiet_begin();
  int st = f->ref_x >= 0 && write_traj(f, f->ref_x, (hsize_t)k, xref, s->dim) ? sw_h5_fail(f, "write /references/x in")
                                                                               : CUP_OK;
  if (!st && f->ref_sig >= 0 && write_traj(f, f->ref_sig, (hsize_t)k, xref + s->samples * s->dim, s->nsig))
    st = sw_h5_fail(f, "write /references/signals in");
  if (!st && sw_h5_write_rows(f->ref_summary, f->refrow_t, (hsize_t)k, 1, &row, f->dxpl))
    st = sw_h5_fail(f, "write /references/summary in");
  quiet_end(q);
  if (st) return st;
  f->ref_done[k] = 1;
  long count = s->samples * s->dim;
  if (r->status >= 0 && !f->xref[k] && f->ref_x >= 0) {
    if (!(f->xref[k] = malloc(sizeof(double) * (size_t)count))) return CUP_ERR_NOMEM;
    memcpy(f->xref[k], xref, sizeof(double) * (size_t)count);
  }
  return CUP_OK;
}

int sw_file_flush(sw_file *f) {
  if (f->failed) return CUP_ERR_IO;
  quiet_t q = quiet_begin();
  int st = H5Fflush(f->file, H5F_SCOPE_LOCAL) < 0 ? sw_h5_fail(f, "flush") : CUP_OK;
  quiet_end(q);
  return st;
}

int sw_file_close(sw_file **pf, char *errmsg) {
  if (!pf || !*pf) return CUP_OK;
  sw_file *f = *pf;
  int st = f->failed ? CUP_ERR_IO : sw_file_flush(f);
  quiet_t q = quiet_begin();
  hid_t h[] = {f->summary, f->runs_x, f->ref_x, f->ref_summary, f->crowd, f->steady};
  for (size_t k = 0; k < sizeof h / sizeof h[0]; k++)
    if (h[k] >= 0 && H5Dclose(h[k]) < 0 && !st) st = sw_h5_fail(f, "close a dataset of");
  f->summary = f->runs_x = f->ref_x = f->ref_summary = f->crowd = f->steady = H5I_INVALID_HID;
  if (H5Fclose(f->file) < 0 && !st) st = sw_h5_fail(f, "close");
  f->file = H5I_INVALID_HID;
  quiet_end(q);
  if (st && errmsg) snprintf(errmsg, SW_ERR_LEN, "%s", f->errmsg);
  sw_h5_file_free(f);
  *pf = NULL;
  return st;
}


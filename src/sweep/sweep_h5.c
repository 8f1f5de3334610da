/* sweep_h5 — the results file's layout and what its writers share
 * (sweep_h5.h): errors, types, the state kept in memory, the one-row-per-
 * task tables. The design, crash safety by a fixed layout, is described in
 * sweep_h5.h. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <hdf5.h>
#include "sweep_h5.h"

/* ---- HDF5 errors: never printed; the innermost description is kept ---- */

/* Call right after the failed HDF5 call: any later API call (even
 * H5Pclose) clears the error stack that says why. */
int sw_h5_fail(sw_file *f, const char *op) {
  h5_detail e;
  h5_error_detail(&e, 0);
  if (!f->errmsg[0] && e.locked) snprintf(f->errmsg, sizeof f->errmsg, SW_IN_USE_FMT, f->path, op);
  if (!f->errmsg[0]) snprintf(f->errmsg, sizeof f->errmsg, "%s: cannot %s: %s", f->path, op, e.desc);
  f->failed = 1;
  H5Eclear2(H5E_DEFAULT);
  return CUP_ERR_IO;
}

/* ---- types ---- */

hid_t sw_h5_str(size_t size) {
  hid_t t = H5Tcopy(H5T_C_S1);
  H5Tset_size(t, size);
  H5Tset_strpad(t, H5T_STR_NULLTERM);
  H5Tset_cset(t, H5T_CSET_UTF8);
  return t;
}

#define INS(T, name, field, type) H5Tinsert(T, name, HOFFSET(sw_row, field), type)
static hid_t row_type(void) {
  hid_t T = H5Tcreate(H5T_COMPOUND, sizeof(sw_row));
  hid_t sname = sw_h5_str(SW_NAME_LEN), sspec = sw_h5_str(SW_SPEC_LEN), sword = sw_h5_str(SW_WORD_LEN),
        sstat = sw_h5_str(SW_STATUS_LEN), smsg = sw_h5_str(SW_MSG_LEN);
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
  INS(T, "tol_abs", tol_abs, H5T_NATIVE_DOUBLE);
  INS(T, "tol_rel", tol_rel, H5T_NATIVE_DOUBLE);
  INS(T, "err_est", err_est, H5T_NATIVE_DOUBLE);
  INS(T, "events", events, H5T_NATIVE_INT64);
  INS(T, "done", done, H5T_NATIVE_INT8);
  H5Tclose(sname); H5Tclose(sspec); H5Tclose(sword); H5Tclose(sstat); H5Tclose(smsg);
  return T;
}
#undef INS

#define INS(T, name, field, type) H5Tinsert(T, name, HOFFSET(sw_refrow, field), type)
static hid_t refrow_type(void) {
  hid_t T = H5Tcreate(H5T_COMPOUND, sizeof(sw_refrow));
  hid_t sname = sw_h5_str(SW_NAME_LEN), sstat = sw_h5_str(SW_STATUS_LEN), smsg = sw_h5_str(SW_MSG_LEN);
  INS(T, "variant", variant, H5T_NATIVE_INT32);
  INS(T, "variant_name", variant_name, sname);
  INS(T, "n_ref", n_ref, H5T_NATIVE_INT64);
  INS(T, "status", status, H5T_NATIVE_INT32);
  INS(T, "status_name", status_name, sstat);
  INS(T, "message", message, smsg);
  INS(T, "wall_time_s", wall_time_s, H5T_NATIVE_DOUBLE);
  INS(T, "correction", correction, H5T_NATIVE_DOUBLE);
  INS(T, "cross_check", cross_check, H5T_NATIVE_DOUBLE);
  INS(T, "max_eps_cert", max_eps_cert, H5T_NATIVE_DOUBLE);
  INS(T, "max_eta_cert", max_eta_cert, H5T_NATIVE_DOUBLE);
  INS(T, "dual_iterations", dual_iterations, H5T_NATIVE_INT64);
  INS(T, "done", done, H5T_NATIVE_INT8);
  H5Tclose(sname); H5Tclose(sstat); H5Tclose(smsg);
  return T;
}
#undef INS

#define INS(T, name, field, type) H5Tinsert(T, name, HOFFSET(sw_crowd_row, field), type)
static hid_t crowd_row_type(void) {
  hid_t T = H5Tcreate(H5T_COMPOUND, sizeof(sw_crowd_row));
  INS(T, "task_id", task_id, H5T_NATIVE_INT64);
  INS(T, "variant", variant, H5T_NATIVE_INT32);
  INS(T, "agents", agents, H5T_NATIVE_INT32);
  INS(T, "agents_out", agents_out, H5T_NATIVE_INT32);
  INS(T, "evacuation_time", evacuation_time, H5T_NATIVE_DOUBLE);
  INS(T, "min_gap", min_gap, H5T_NATIVE_DOUBLE);
  INS(T, "done", done, H5T_NATIVE_INT8);
  return T;
}
#undef INS

const char *const sw_steady_figures[SW_SS_FIGURES] = {"average", "rms", "min", "max", "peak_to_peak"};

#define INS(T, name, field, type) H5Tinsert(T, name, HOFFSET(sw_steady_row, field), type)
static hid_t steady_row_type(const sw_sweep *s) {
  hid_t T = H5Tcreate(H5T_COMPOUND, sizeof(sw_steady_row));
  INS(T, "task_id", task_id, H5T_NATIVE_INT64);
  INS(T, "variant", variant, H5T_NATIVE_INT32);
  INS(T, "status", status, H5T_NATIVE_INT32);
  INS(T, "solved", solved, H5T_NATIVE_INT32);
  INS(T, "newton_iterations", newton_iterations, H5T_NATIVE_INT32);
  INS(T, "period_runs", period_runs, H5T_NATIVE_INT64);
  INS(T, "period", period, H5T_NATIVE_DOUBLE);
  INS(T, "residual", residual, H5T_NATIVE_DOUBLE);
  INS(T, "max_multiplier", max_multiplier, H5T_NATIVE_DOUBLE);
  INS(T, "efficiency", efficiency, H5T_NATIVE_DOUBLE);
  for (int j = 0; j < s->ss_nm; j++)
    for (int q = 0; q < SW_SS_FIGURES; q++) {
      char name[160];
      snprintf(name, sizeof name, "%.120s_%s", sw_signal_name(s, s->ss_sig[j]), sw_steady_figures[q]);
      H5Tinsert(T, name, HOFFSET(sw_steady_row, fig) + sizeof(double) * (size_t)(j * SW_SS_FIGURES + q),
                H5T_NATIVE_DOUBLE);
    }
  INS(T, "done", done, H5T_NATIVE_INT8);
  return T;
}
#undef INS

/* snprintf(dst, size, "%s", src), zero-padded, at a fraction of its cost
 * (rank 0 fills a row's strings for every result it writes). */
void sw_copy_str(char *dst, size_t size, const char *src) {
  size_t n = src ? strnlen(src, size - 1) : 0;
  if (n) memcpy(dst, src, n);
  memset(dst + n, 0, size - n);
}

void sw_pending_row(const sw_sweep *s, long id, sw_row *r) {
  sw_task t;
  memset(r, 0, sizeof *r);
  sw_task_get(s, id, &t);
  r->task_id = id;
  r->variant = t.variant;
  sw_copy_str(r->variant_name, sizeof r->variant_name, s->var[t.variant].name);
  r->n = t.n;
  sw_copy_str(r->eps, sizeof r->eps, t.eps);
  sw_copy_str(r->eta, sizeof r->eta, t.eta);
  r->eps_value = cup_schedule_value(&t.eps_s, t.n);
  r->eta_value = cup_schedule_value(&t.eta_s, t.n);
  sw_copy_str(r->scheme, sizeof r->scheme, cup_scheme_name(t.scheme));
  sw_copy_str(r->projector, sizeof r->projector, cup_proj_method_name(t.projector));
  r->tol_abs = t.scheme == CUP_SCHEME_ADAPTIVE ? t.tol_abs : NAN;
  r->tol_rel = t.scheme == CUP_SCHEME_ADAPTIVE ? t.tol_rel : NAN;
  r->err_est = NAN;
  r->status = r->error_code = CUP_ERR_INTERRUPTED;
  sw_copy_str(r->status_name, sizeof r->status_name, "pending");
  r->wall_time_s = r->error = r->max_eps_cert = r->max_eta_cert = NAN;
}

int sw_h5_write_rows(hid_t d, hid_t memtype, hsize_t at, hsize_t count, const void *buf, hid_t dxpl) {
  hid_t fs = H5Dget_space(d), ms = H5Screate_simple(1, &count, NULL);
  int ok = fs >= 0 && ms >= 0 && H5Sselect_hyperslab(fs, H5S_SELECT_SET, &at, NULL, &count, NULL) >= 0 &&
           H5Dwrite(d, memtype, ms, fs, dxpl, buf) >= 0;
  if (ms >= 0) H5Sclose(ms);
  if (fs >= 0) H5Sclose(fs);
  return ok ? 0 : -1;
}

/* ---- datasets made at creation ---- */

hid_t sw_h5_fixed_dataset(hid_t loc, const char *name, hid_t ftype, int rank, const hsize_t *dims,
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

int sw_h5_task_table(sw_file *f, const char *name, hid_t memtype, size_t row_size, sw_pending_fn pending,
                     hid_t *d) {
  const sw_sweep *s = f->s;
  hsize_t N = (hsize_t)s->n_tasks;
  char op[64];
  hid_t ft = H5Tcopy(memtype);
  H5Tpack(ft);
  *d = sw_h5_fixed_dataset(f->file, name, ft, 1, &N, 0, NULL);
  H5Tclose(ft);
  snprintf(op, sizeof op, "create /%s in", name);
  if (*d < 0) return sw_h5_fail(f, op);
  enum { BLOCK = 1024 };
  char *rows = malloc(row_size * BLOCK);
  if (!rows) return CUP_ERR_NOMEM;
  int st = CUP_OK;
  snprintf(op, sizeof op, "write /%s in", name);
  for (hsize_t at = 0; at < N && !st; at += BLOCK) {
    hsize_t cnt = N - at < BLOCK ? N - at : BLOCK;
    for (hsize_t k = 0; k < cnt; k++) pending(s, (long)(at + k), rows + row_size * k);
    if (sw_h5_write_rows(*d, memtype, at, cnt, rows, H5P_DEFAULT)) st = sw_h5_fail(f, op);
  }
  free(rows);
  return st;
}

/* ---- state ---- */

sw_file *sw_h5_file_new(const sw_sweep *s, const char *path) {
  sw_file *f = calloc(1, sizeof *f);
  if (!f) return NULL;
  f->s = s;
  f->file = f->summary = f->runs_x = f->ref_x = f->ref_summary = f->crowd = f->runs_sig = f->ref_sig = H5I_INVALID_HID;
  f->steady = H5I_INVALID_HID;
  f->path = strdup(path);
  size_t N = (size_t)s->n_tasks, V = (size_t)s->n_variants;
  f->done = calloc(N, 1);
  f->status = calloc(N, sizeof *f->status);
  f->error = malloc(N * sizeof *f->error);
  f->ref_done = calloc(V, 1);
  f->xref = calloc(V, sizeof *f->xref);
  f->row_t = row_type();
  f->refrow_t = refrow_type();
  f->crowd_row_t = crowd_row_type();
  f->ss_row_t = steady_row_type(s);
  /* A reference row's write converts a compound type (to the packed file
   * type): HDF5 would otherwise allocate and clear a 1 MiB conversion
   * buffer each time. */
  f->dxpl = H5Pcreate(H5P_DATASET_XFER);
  H5Pset_buffer(f->dxpl, 4 * sizeof(sw_refrow), NULL, NULL);
  if (!f->path || !f->done || !f->status || !f->error || !f->ref_done || !f->xref) {
    free(f->path); free(f->done); free(f->status); free(f->error); free(f->ref_done); free(f->xref);
    H5Tclose(f->row_t); H5Tclose(f->refrow_t); H5Tclose(f->crowd_row_t); H5Tclose(f->ss_row_t); H5Pclose(f->dxpl);
    free(f);
    return NULL;
  }
  for (size_t k = 0; k < N; k++) { f->error[k] = NAN; f->status[k] = CUP_ERR_INTERRUPTED; }
  return f;
}

void sw_h5_file_free(sw_file *f) {
  quiet_t q = quiet_begin();
  hid_t h[] = {f->summary, f->runs_x, f->ref_x, f->ref_summary, f->crowd, f->runs_sig, f->ref_sig, f->steady};
  for (size_t k = 0; k < sizeof h / sizeof h[0]; k++)
    if (h[k] >= 0) H5Dclose(h[k]);
  if (f->file >= 0) H5Fclose(f->file);
  H5Tclose(f->row_t);
  H5Tclose(f->refrow_t);
  H5Tclose(f->crowd_row_t);
  H5Tclose(f->ss_row_t);
  H5Pclose(f->dxpl);
  H5Eclear2(H5E_DEFAULT);
  quiet_end(q);
  for (int k = 0; k < f->s->n_variants; k++) free(f->xref[k]);
  free(f->ids); free(f->rows); free(f->x); free(f->crows); free(f->ssrows); free(f->sig);
  free(f->xref); free(f->ref_done); free(f->done); free(f->status); free(f->error); free(f->path);
  free(f);
}

/* The tasks' ids increase: one hyperslab per run of consecutive tasks. */
int sw_h5_task_io(sw_file *f, hid_t d, hid_t memtype, long count, void *buf, hid_t dxpl, int writing,
                  const char *op) {
  hsize_t dims[3] = {0, 1, 1}, start[3] = {0, 0, 0};
  hid_t fs = H5Dget_space(d), ms = -1;
  int rank = fs < 0 ? -1 : H5Sget_simple_extent_dims(fs, dims, NULL), ok = rank >= 1 && rank <= 3;
  for (long j = 0, e; j < count && ok; j = e) {
    for (e = j + 1; e < count && f->ids[e] == f->ids[e - 1] + 1; e++) {}
    start[0] = (hsize_t)f->ids[j];
    dims[0] = (hsize_t)(e - j);
    ok = H5Sselect_hyperslab(fs, j ? H5S_SELECT_OR : H5S_SELECT_SET, start, NULL, dims, NULL) >= 0;
  }
  dims[0] = (hsize_t)count;
  if (ok) ok = (ms = H5Screate_simple(rank, dims, NULL)) >= 0;
  if (ok) ok = (writing ? H5Dwrite(d, memtype, ms, fs, dxpl, buf) : H5Dread(d, memtype, ms, fs, dxpl, buf)) >= 0;
  int st = ok ? CUP_OK : sw_h5_fail(f, op);
  if (ms >= 0) H5Sclose(ms);
  if (fs >= 0) H5Sclose(fs);
  return st;
}

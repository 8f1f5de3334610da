/* h5run_stop — a run's file after a stop (include/catchup/h5run.h): the
 * checkpoint of a stopped run beside its rows (/checkpoint, the bytes of
 * cup_integrator_checkpoint_save with the rows and events it covers), and
 * the file opened again to continue that run: its datasets reopened, cut
 * back to the checkpoint, appended to as by a new writer. A kill during the
 * continued run leaves the checkpoint in place, so that the next --resume
 * cuts back to it again. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <hdf5.h>
#include "catchup.h"
#include "catchup/h5run.h"
#include "h5run_impl.h"
#include "util/fail.h"

/* ---- reopening ---- */

/* The first dimension of dataset d, or -1. */
static long rows_of(hid_t d, int rank, hsize_t *cols) {
  hsize_t dims[2] = {0, 0};
  hid_t space = H5Dget_space(d);
  int ok = space >= 0 && H5Sget_simple_extent_ndims(space) == rank && H5Sget_simple_extent_dims(space, dims, NULL) >= 0;
  if (space >= 0) H5Sclose(space);
  if (cols) *cols = dims[1];
  return ok ? (long)dims[0] : -1;
}

/* /signals holds exactly names, in their order (its attribute `names`). */
static int same_signals(cup_h5run *w, int nsig, const char *const *names) {
  hid_t a = H5Aopen(w->group, "names", H5P_DEFAULT);
  if (a < 0) return 0;
  hid_t space = H5Aget_space(a), type = h5_vlen_str();
  hssize_t n = space >= 0 ? H5Sget_simple_extent_npoints(space) : -1;
  int same = n == nsig && type >= 0;
  char **got = same ? calloc((size_t)nsig + 1, sizeof *got) : NULL;
  if (got && H5Aread(a, type, got) >= 0) {
    for (int k = 0; k < nsig; k++) same &= got[k] && !strcmp(got[k], names[k]);
    H5Dvlen_reclaim(type, space, H5P_DEFAULT, got);
  } else {
    same = 0;
  }
  free(got);
  if (type >= 0) H5Tclose(type);
  if (space >= 0) H5Sclose(space);
  H5Aclose(a);
  return same;
}

static int open_signals(cup_h5run *w, int nsig, const char *const *names) {
  htri_t has = H5Lexists(w->file, "signals", H5P_DEFAULT);
  if (nsig == 0) return has > 0 ? -1 : 0;
  w->group = has > 0 ? H5Gopen2(w->file, "signals", H5P_DEFAULT) : H5I_INVALID_HID;
  if (w->group < 0 || !same_signals(w, nsig, names)) return -1;
  w->dset_s = malloc(sizeof(hid_t) * (size_t)nsig);
  if (!w->dset_s) return -1;
  for (int k = 0; k < nsig; k++) {
    w->dset_s[k] = H5Dopen2(w->group, names[k], H5P_DEFAULT);
    w->nsig = k + 1;
    if (w->dset_s[k] < 0) return -1;
  }
  return 0;
}

int cup_h5run_open(cup_h5run **out, const char *path, int dim, int nsig, const char *const *names, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "h5run: output pointer is NULL");
  *out = NULL;
  if (nsig < 0 || (nsig && !names)) return fail_fmt(errmsg, CUP_ERR_ARG, "h5run: bad signal names");
  struct stat sb;
  if (!path || stat(path, &sb) != 0 || !S_ISREG(sb.st_mode))
    return fail_fmt(errmsg, CUP_ERR_IO, "h5run: cannot continue '%s': no such file", path ? path : "(null)");
  if (h5_file_in_use(path))
    return fail_fmt(errmsg, CUP_ERR_IO, "h5run: cannot continue '%s': the file is in use by another process (HDF5 "
                    "file locking): wait for that run to end; the file is left as it was", path);
  int st;
  cup_h5run *w = writer_new(path, dim, errmsg, &st);
  if (!w) return st;
  quiet_t q = quiet_begin();
  hid_t fapl = h5_file_access(0);
  if (fapl >= 0) w->file = H5Fopen(path, H5F_ACC_RDWR, fapl);
  if (fapl >= 0) H5Pclose(fapl);
  hsize_t cols = 0;
  if (w->file >= 0) {
    w->dset_t = H5Dopen2(w->file, "t", H5P_DEFAULT);
    w->dset_x = H5Dopen2(w->file, "x", H5P_DEFAULT);
    w->dset_e = H5Dopen2(w->file, "events", H5P_DEFAULT);
  }
  long nt = w->dset_t >= 0 ? rows_of(w->dset_t, 1, NULL) : -1, nx = w->dset_x >= 0 ? rows_of(w->dset_x, 2, &cols) : -1;
  long ne = w->dset_e >= 0 ? rows_of(w->dset_e, 1, NULL) : -1;
  if (w->file < 0 || nt < 0 || nx < 0 || ne < 0 || event_types(w) < 0)
    st = fail_fmt(errmsg, CUP_ERR_IO, "h5run: cannot continue '%s': not a file of catchup-run (no /t, /x and /events)",
                  path);
  else if ((int)cols != dim)
    st = fail_fmt(errmsg, CUP_ERR_ARG, "h5run: cannot continue '%s': its states have %d entries, this run's %d", path,
                  (int)cols, dim);
  else if (open_signals(w, nsig, names) < 0)
    st = fail_fmt(errmsg, CUP_ERR_ARG, "h5run: cannot continue '%s': it records other signals than this run (its "
                  "/signals and --probe must agree)", path);
  H5Eclear2(H5E_DEFAULT);
  quiet_end(q);
  if (st) {
    free_writer(w);
    return st;
  }
  w->written = (hsize_t)(nt < nx ? nt : nx);
  w->ewritten = (hsize_t)ne;
  *out = w;
  return CUP_OK;
}

/* Shrink d to rows rows (and keep its other dimension). */
static herr_t shrink(hid_t d, hsize_t rows, hsize_t cols) {
  hsize_t ext[2] = {rows, cols};
  return H5Dset_extent(d, ext);
}

int cup_h5run_truncate(cup_h5run *w, long rows, long events) {
  if (!w || rows < 0 || events < 0 || (hsize_t)rows > w->written + w->nbuf ||
      (hsize_t)events > w->ewritten + w->enbuf)
    return CUP_ERR_ARG;
  int st = cup_h5run_flush(w);
  if (st) return st;
  quiet_t q = quiet_begin();
  herr_t r = shrink(w->dset_t, (hsize_t)rows, 1);
  if (r >= 0) r = shrink(w->dset_x, (hsize_t)rows, (hsize_t)w->dim);
  for (int k = 0; k < w->nsig && r >= 0; k++) r = shrink(w->dset_s[k], (hsize_t)rows, 1);
  if (r >= 0) r = shrink(w->dset_e, (hsize_t)events, 1);
  if (r < 0) st = set_error(w, CUP_ERR_IO, "cut back the rows of");
  quiet_end(q);
  if (st) return st;
  w->written = (hsize_t)rows;
  w->ewritten = (hsize_t)events;
  return cup_h5run_flush(w);
}

/* ---- the checkpoint ---- */

static int put_long(hid_t loc, const char *name, long v) {
  int64_t v64 = (int64_t)v;
  hid_t space = H5Screate(H5S_SCALAR), a = H5I_INVALID_HID;
  if (space >= 0) a = H5Acreate2(loc, name, H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT);
  int ok = a >= 0 && H5Awrite(a, H5T_NATIVE_INT64, &v64) >= 0;
  if (a >= 0) H5Aclose(a);
  if (space >= 0) H5Sclose(space);
  return ok;
}

static int get_long(hid_t loc, const char *name, long *v) {
  int64_t v64 = 0;
  hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
  int ok = a >= 0 && H5Aread(a, H5T_NATIVE_INT64, &v64) >= 0;
  if (a >= 0) H5Aclose(a);
  *v = (long)v64;
  return ok;
}

int cup_h5run_drop_checkpoint(cup_h5run *w) {
  if (!w) return CUP_ERR_ARG;
  if (w->h5_failed) return w->data_status;
  quiet_t q = quiet_begin();
  htri_t has = H5Lexists(w->file, "checkpoint", H5P_DEFAULT);
  int st = has < 0 || (has > 0 && H5Ldelete(w->file, "checkpoint", H5P_DEFAULT) < 0)
               ? set_error(w, CUP_ERR_IO, "remove /checkpoint from") : CUP_OK;
  quiet_end(q);
  return st;
}

int cup_h5run_put_checkpoint(cup_h5run *w, const void *blob, unsigned long size) {
  if (!w || !blob || size == 0) return CUP_ERR_ARG;
  int st = cup_h5run_flush(w);                   /* the rows and events it covers, on disk */
  if (!st) st = cup_h5run_drop_checkpoint(w);
  if (st) return st;
  quiet_t q = quiet_begin();
  hsize_t n = size;
  hid_t space = H5Screate_simple(1, &n, NULL), d = H5I_INVALID_HID;
  if (space >= 0) d = H5Dcreate2(w->file, "checkpoint", H5T_STD_U8LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  int ok = d >= 0 && H5Dwrite(d, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, blob) >= 0 &&
           put_long(d, "rows", (long)w->written) && put_long(d, "events", (long)w->ewritten);
  hid_t err = keep_stack(!ok);
  if (d >= 0) H5Dclose(d);
  if (space >= 0) H5Sclose(space);
  restore_stack(err);
  if (!ok) st = set_error(w, CUP_ERR_IO, "write /checkpoint in");
  quiet_end(q);
  return st ? st : cup_h5run_flush(w);
}

int cup_h5run_get_checkpoint(cup_h5run *w, void **blob, unsigned long *size, long *rows, long *events) {
  if (!w || !blob || !size || !rows || !events) return CUP_ERR_ARG;
  *blob = NULL;
  *size = 0;
  quiet_t q = quiet_begin();
  hid_t d = H5Lexists(w->file, "checkpoint", H5P_DEFAULT) > 0 ? H5Dopen2(w->file, "checkpoint", H5P_DEFAULT)
                                                               : H5I_INVALID_HID;
  long n = d >= 0 ? rows_of(d, 1, NULL) : -1;
  void *b = n > 0 ? malloc((size_t)n) : NULL;
  int ok = b && H5Dread(d, H5T_NATIVE_UINT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, b) >= 0 && get_long(d, "rows", rows) &&
           get_long(d, "events", events);
  if (d >= 0) H5Dclose(d);
  H5Eclear2(H5E_DEFAULT);
  quiet_end(q);
  if (!ok) {
    free(b);
    return d < 0 ? CUP_ERR_ARG : CUP_ERR_IO;
  }
  *blob = b;
  *size = (unsigned long)n;
  return CUP_OK;
}

/* ---- attributes, read back ---- */

int cup_h5run_get_string(cup_h5run *w, const char *name, char **value) {
  if (!w || !name || !value) return CUP_ERR_ARG;
  *value = NULL;
  quiet_t q = quiet_begin();
  hid_t a = H5Aexists(w->file, name) > 0 ? H5Aopen(w->file, name, H5P_DEFAULT) : H5I_INVALID_HID;
  hid_t type = h5_vlen_str();
  char *s = NULL;
  int ok = a >= 0 && type >= 0 && H5Aread(a, type, &s) >= 0 && s;
  if (ok) *value = strdup(s);
  if (s) H5free_memory(s);
  if (type >= 0) H5Tclose(type);
  if (a >= 0) H5Aclose(a);
  H5Eclear2(H5E_DEFAULT);
  quiet_end(q);
  return !ok ? CUP_ERR_ARG : *value ? CUP_OK : CUP_ERR_NOMEM;
}

int cup_h5run_get_double(cup_h5run *w, const char *name, double *v) {
  if (!w || !name || !v) return CUP_ERR_ARG;
  quiet_t q = quiet_begin();
  hid_t a = H5Aexists(w->file, name) > 0 ? H5Aopen(w->file, name, H5P_DEFAULT) : H5I_INVALID_HID;
  int ok = a >= 0 && H5Aread(a, H5T_NATIVE_DOUBLE, v) >= 0;
  if (a >= 0) H5Aclose(a);
  H5Eclear2(H5E_DEFAULT);
  quiet_end(q);
  return ok ? CUP_OK : CUP_ERR_ARG;
}

int cup_h5run_drop_attr(cup_h5run *w, const char *name) {
  if (!w || !name) return CUP_ERR_ARG;
  if (w->h5_failed) return w->data_status;
  quiet_t q = quiet_begin();
  htri_t has = H5Aexists(w->file, name);
  int st = has < 0 || (has > 0 && H5Adelete(w->file, name) < 0) ? set_error(w, CUP_ERR_IO, "remove an attribute of")
                                                                 : CUP_OK;
  quiet_end(q);
  return st;
}

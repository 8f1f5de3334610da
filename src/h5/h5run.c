/* h5run — HDF5 output of one run: /t [N] and /x [N, dim], appended in
 * chunk-sized blocks from a fixed in-memory buffer. This file owns the
 * file: its creation (staged, committed or discarded), its datasets and
 * their chunk size, /signals, attributes, descriptions and close; the
 * rows' path (the buffers, appends, flushes and the crash safety they
 * give) and the first failure that stops it (set_error) are
 * h5run_rows.c's. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>
#include <hdf5.h>
#include <hdf5_hl.h>
#include "catchup.h"
#include "catchup/h5run.h"
#include "h5run_impl.h"
#include "util/clock.h"
#include "util/fail.h"

enum { MAX_CHUNK_ROWS = 4096 };
_Static_assert((MAX_CHUNK_ROWS & (MAX_CHUNK_ROWS - 1)) == 0, "room() (h5run_rows.c) masks by chunk_rows - 1: chunk_rows_for halves it");
#define CHUNK_BYTES (1u << 20)  /* fits HDF5's default 1 MiB chunk cache */
/* A chunk must stay under HDF5's 4 GiB limit even when it holds one row. */
#define MAX_DIM ((int)(UINT32_MAX / sizeof(double)))

/* ---- file and datasets ---- */

static hid_t create_dataset(hid_t file, const char *name, int rank, hsize_t dim,
                            hsize_t chunk_rows) {
  hsize_t dims[2] = {0, dim}, maxdims[2] = {H5S_UNLIMITED, dim};
  hsize_t chunk[2] = {chunk_rows, dim};
  hid_t space = H5Screate_simple(rank, dims, maxdims);
  hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  hid_t d = H5I_INVALID_HID;
  if (space >= 0 && dcpl >= 0 && H5Pset_chunk(dcpl, rank, chunk) >= 0)
    d = H5Dcreate2(file, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  hid_t err = keep_stack(d < 0);
  if (dcpl >= 0) H5Pclose(dcpl);
  if (space >= 0) H5Sclose(space);
  restore_stack(err);
  return d;
}

/* /events' rows (t float64, row int32, on int8): the file type is packed
 * (13 bytes), the memory type follows the struct, and HDF5 converts one to
 * the other in the writer's own buffers: by default it takes and zeroes
 * two of 1 MiB at each write (2.1 million instructions a write, half of
 * the precision rectifier's run on its 10001 samples). */
int event_types(cup_h5run *w) {
  w->etype_file = H5Tcreate(H5T_COMPOUND, 13);
  w->etype_mem = H5Tcreate(H5T_COMPOUND, sizeof(h5_event));
  w->exfer = H5Pcreate(H5P_DATASET_XFER);
  if (w->etype_file < 0 || w->etype_mem < 0 || w->exfer < 0 ||
      H5Pset_buffer(w->exfer, sizeof w->etconv, w->etconv, w->ebkg) < 0 ||
      H5Tinsert(w->etype_file, "t", 0, H5T_IEEE_F64LE) < 0 ||
      H5Tinsert(w->etype_file, "row", 8, H5T_STD_I32LE) < 0 ||
      H5Tinsert(w->etype_file, "on", 12, H5T_STD_I8LE) < 0 ||
      H5Tinsert(w->etype_mem, "t", HOFFSET(h5_event, t), H5T_NATIVE_DOUBLE) < 0 ||
      H5Tinsert(w->etype_mem, "row", HOFFSET(h5_event, row), H5T_NATIVE_INT32) < 0 ||
      H5Tinsert(w->etype_mem, "on", HOFFSET(h5_event, on), H5T_NATIVE_INT8) < 0)
    return -1;
  return 0;
}

/* /events, chunked and extendable. */
static hid_t create_events(cup_h5run *w) {
  if (event_types(w) < 0) return H5I_INVALID_HID;
  hsize_t dims[1] = {0}, maxdims[1] = {H5S_UNLIMITED}, chunk[1] = {EVENT_ROWS};
  hid_t space = H5Screate_simple(1, dims, maxdims);
  hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  hid_t d = H5I_INVALID_HID;
  if (space >= 0 && dcpl >= 0 && H5Pset_chunk(dcpl, 1, chunk) >= 0)
    d = H5Dcreate2(w->file, "events", w->etype_file, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  hid_t err = keep_stack(d < 0);
  if (dcpl >= 0) H5Pclose(dcpl);
  if (space >= 0) H5Sclose(space);
  restore_stack(err);
  return d;
}

/* The file at `at` (the staged sibling, or the path itself), its datasets. */
static int open_file(cup_h5run *w, const char *at) {
  if (h5_file_in_use(w->path)) {
    snprintf(w->errmsg, sizeof w->errmsg, "h5run: cannot create '%s': the file is in use by another "
             "process (HDF5 file locking): close it there or wait for that run to end; the file is "
             "left as it was", w->path);
    return w->err_status = CUP_ERR_IO;
  }
  if (h5_space_short(w->path, 1, 0, NULL)) {   /* the folder it goes into */
    snprintf(w->errmsg, sizeof w->errmsg, "h5run: cannot create '%s': less than %u MiB "
             "left on its device", w->path, CUP_H5_SPACE_MARGIN >> 20);
    return w->err_status = CUP_ERR_IO;
  }
  hid_t fapl = h5_file_access(0);
  if (fapl >= 0) w->file = H5Fcreate(at, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  hid_t err = keep_stack(w->file < 0);
  if (fapl >= 0) H5Pclose(fapl);
  restore_stack(err);
  if (w->file < 0) return set_error(w, CUP_ERR_IO, "create");
  w->dset_t = create_dataset(w->file, "t", 1, 1, w->chunk_rows);
  if (w->dset_t < 0) return set_error(w, CUP_ERR_IO, "create dataset /t in");
  w->dset_x = create_dataset(w->file, "x", 2, (hsize_t)w->dim, w->chunk_rows);
  if (w->dset_x < 0) return set_error(w, CUP_ERR_IO, "create dataset /x in");
  w->dset_e = create_events(w);
  if (w->dset_e < 0) return set_error(w, CUP_ERR_IO, "create dataset /events in");
  /* On disk and readable (with N = 0) before the first sample arrives. */
  if (H5Fflush(w->file, H5F_SCOPE_LOCAL) < 0) return set_error(w, CUP_ERR_IO, "flush");
  return CUP_OK;
}

/* Rows per chunk: 4096, halved while an /x chunk exceeds CHUNK_BYTES. */
static hsize_t chunk_rows_for(int dim) {
  hsize_t rows = MAX_CHUNK_ROWS;
  while (rows > 1 && rows * (hsize_t)dim * sizeof(double) > CHUNK_BYTES) rows /= 2;
  return rows;
}

static void close_signals(cup_h5run *w) {
  for (int k = 0; k < w->nsig; k++)
    if (w->dset_s[k] >= 0) H5Dclose(w->dset_s[k]);
  if (w->group >= 0) H5Gclose(w->group);
  w->group = H5I_INVALID_HID;
  w->nsig = 0;
}

void free_writer(cup_h5run *w) {
  quiet_t q = quiet_begin();
  close_signals(w);
  if (w->dset_e >= 0) H5Dclose(w->dset_e);
  if (w->etype_file >= 0) H5Tclose(w->etype_file);
  if (w->etype_mem >= 0) H5Tclose(w->etype_mem);
  if (w->exfer >= 0) H5Pclose(w->exfer);
  if (w->dset_x >= 0) H5Dclose(w->dset_x);
  if (w->dset_t >= 0) H5Dclose(w->dset_t);
  if (w->file >= 0) H5Fclose(w->file);
  H5Eclear2(H5E_DEFAULT);
  quiet_end(q);
  free(w->tbuf);
  free(w->xbuf);
  free(w->dset_s);
  free(w->sbuf);
  free(w->path);
  free(w->staged);
  free(w);
}

cup_h5run *writer_new(const char *path, int dim, char *errmsg, int *st) {
  if (!path || !path[0]) return *st = fail_fmt(errmsg, CUP_ERR_ARG, "h5run: empty file name"), NULL;
  if (dim < 1 || dim > MAX_DIM) {
    *st = fail_fmt(errmsg, CUP_ERR_ARG, "h5run: '%s': state dimension %d outside [1, %d]", path, dim, MAX_DIM);
    return NULL;
  }
  cup_h5run *w = calloc(1, sizeof *w);
  if (!w) return *st = fail_fmt(errmsg, CUP_ERR_NOMEM, "h5run: '%s': out of memory", path), NULL;
  w->file = w->dset_t = w->dset_x = w->dset_e = w->etype_file = w->etype_mem = w->exfer = w->group =
      H5I_INVALID_HID;
  w->dim = dim;
  w->chunk_rows = chunk_rows_for(dim);
  w->path = strdup(path);
  if (!w->path) {
    free_writer(w);
    *st = fail_fmt(errmsg, CUP_ERR_NOMEM, "h5run: '%s': out of memory", path);
    return NULL;
  }
  w->last_flush = w->last_tick = tick_seconds();
  w->tick_every = w->tick_left = 1;
  *st = CUP_OK;
  return w;
}

int cup_h5run_begin(cup_h5run **out, const char *path, int dim, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "h5run: output pointer is NULL");
  *out = NULL;
  /* HDF5 1.10 leaks internal state when a create fails after open() (a
   * device, a /proc file) and then prints at exit; refuse those up front. */
  struct stat sb;
  if (path && stat(path, &sb) == 0 && !S_ISREG(sb.st_mode))
    return fail_fmt(errmsg, CUP_ERR_IO, "h5run: cannot create '%s': not a regular file", path);
  int st;
  cup_h5run *w = writer_new(path, dim, errmsg, &st);
  if (!w) return st;
  w->staged = h5_staged_name(path);
  if (!w->staged) {
    st = fail_fmt(errmsg, CUP_ERR_IO, "h5run: cannot create '%s': cannot create a file beside it (%s): its "
                  "folder must take new files; an existing '%s' is left as it was", path, strerror(errno), path);
    free_writer(w);
    return st;
  }
  quiet_t q = quiet_begin();
  st = open_file(w, w->staged);
  quiet_end(q);
  if (st != CUP_OK) {
    if (errmsg) snprintf(errmsg, CUP_ERRMSG_LEN, "%s", w->errmsg);
    cup_h5run_discard(&w);
    return st;
  }
  *out = w;
  return CUP_OK;
}

/* The staged file replaces path in one rename: a reader sees the old file
 * or the new one, never a part of either. Refused while another process
 * holds path open (it would go on writing a file no name leads to). */
int cup_h5run_commit(cup_h5run *w) {
  if (!w) return CUP_ERR_ARG;
  if (!w->staged) return CUP_OK;
  int st = cup_h5run_flush(w);
  if (st) return st;
  if (h5_file_in_use(w->path)) {
    snprintf(w->errmsg, sizeof w->errmsg, "h5run: cannot replace '%s': the file is in use by another process "
             "(HDF5 file locking): close it there or wait for that run to end; the file is left as it was", w->path);
    return w->err_status = w->data_status = CUP_ERR_IO;
  }
  if (rename(w->staged, w->path) != 0) {
    snprintf(w->errmsg, sizeof w->errmsg, "h5run: cannot replace '%s': %s; the file is left as it was", w->path,
             strerror(errno));
    return w->err_status = w->data_status = CUP_ERR_IO;
  }
  free(w->staged);
  w->staged = NULL;
  return CUP_OK;
}

/* Closes the writer; a file still staged is removed, so that a run that
 * fails its checks leaves nothing beside the output it did not replace. */
void cup_h5run_discard(cup_h5run **pw) {
  if (!pw || !*pw) return;
  cup_h5run *w = *pw;
  char *staged = w->staged;
  w->staged = NULL;
  free_writer(w);
  if (staged) unlink(staged);
  free(staged);
  *pw = NULL;
}

int cup_h5run_create(cup_h5run **out, const char *path, int dim, char *errmsg) {
  int st = cup_h5run_begin(out, path, dim, errmsg);
  if (st == CUP_OK && (st = cup_h5run_commit(*out)) != CUP_OK) {
    if (errmsg) snprintf(errmsg, CUP_ERRMSG_LEN, "%s", (*out)->errmsg);
    cup_h5run_discard(out);
  }
  return st;
}

/* ---- /signals, and the writer's status ---- */

/* The names, in order, as a variable-length string array attribute. */
static int names_attr(cup_h5run *w, int nsig, const char *const *names) {
  hsize_t n = (hsize_t)nsig;
  hid_t type = h5_vlen_str(), space = H5Screate_simple(1, &n, NULL), a = H5I_INVALID_HID;
  int ok = type >= 0 && space >= 0;
  if (ok) a = H5Acreate2(w->group, "names", type, space, H5P_DEFAULT, H5P_DEFAULT);
  ok = a >= 0 && H5Awrite(a, type, names) >= 0;
  hid_t err = keep_stack(!ok);
  if (a >= 0) H5Aclose(a);
  if (space >= 0) H5Sclose(space);
  if (type >= 0) H5Tclose(type);
  restore_stack(err);
  return ok;
}

int cup_h5run_signals(cup_h5run *w, int nsig, const char *const *names) {
  if (!w || nsig < 0 || (nsig && !names)) return CUP_ERR_ARG;
  if (w->nsig || w->written + w->nbuf > 0 || w->h5_failed) return CUP_ERR_ARG;
  if (nsig == 0) return CUP_OK;
  if ((double)nsig * (double)w->chunk_rows * sizeof(double) > (double)(64u << 20)) {
    snprintf(w->errmsg, sizeof w->errmsg, "h5run: '%s': %d signals are too many to buffer (at most %u)",
             w->path, nsig, (unsigned)((64u << 20) / (w->chunk_rows * sizeof(double))));
    return w->err_status = CUP_ERR_ARG;
  }
  for (int k = 0; k < nsig; k++)
    if (!names[k] || !names[k][0] || strchr(names[k], '/') || !strcmp(names[k], ".")) {
      snprintf(w->errmsg, sizeof w->errmsg, "h5run: signal %d: '%.60s' is not a dataset name", k,
               names[k] ? names[k] : "(null)");
      return w->err_status = CUP_ERR_ARG;
    }
  w->dset_s = malloc(sizeof(hid_t) * (size_t)nsig);
  if (!w->dset_s) return CUP_ERR_NOMEM;
  quiet_t q = quiet_begin();
  w->group = H5Gcreate2(w->file, "signals", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  int st = w->group >= 0 ? CUP_OK : set_error(w, CUP_ERR_IO, "create group /signals in");
  for (int k = 0; k < nsig && !st; k++) {
    w->dset_s[k] = create_dataset(w->group, names[k], 1, 1, w->chunk_rows);
    w->nsig = k + 1;
    if (w->dset_s[k] < 0) {
      char op[128];
      snprintf(op, sizeof op, "create dataset /signals/%.60s (a repeated name?) in", names[k]);
      st = set_error(w, CUP_ERR_IO, op);
    }
  }
  if (!st && !names_attr(w, nsig, names)) st = set_error(w, CUP_ERR_IO, "write /signals's names in");
  if (!st && H5Fflush(w->file, H5F_SCOPE_LOCAL) < 0) st = set_error(w, CUP_ERR_IO, "flush");
  quiet_end(q);
  return st;
}

int cup_h5run_status(const cup_h5run *w, char *errmsg) {
  if (!w) return CUP_ERR_ARG;
  if (w->err_status && errmsg) snprintf(errmsg, CUP_ERRMSG_LEN, "%s", w->errmsg);
  return w->err_status;
}

/* The older form (h5run.h): the same words, read in place. */
const char *cup_h5run_errmsg(const cup_h5run *w) {
  return w ? w->errmsg : "";
}

/* ---- attributes on the root group ---- */

/* Replace (delete, then create) the scalar attribute `name` of obj, so that
 * a value written before the run ("status" = running) can be rewritten
 * after it, even with another type; 1 when written (else the failure's
 * error stack is kept for set_error). */
static int replace_attr(hid_t obj, const char *name, hid_t ftype, hid_t mtype, const void *buf) {
  hid_t space = H5Screate(H5S_SCALAR), a = H5I_INVALID_HID;
  htri_t exists = space >= 0 ? H5Aexists(obj, name) : -1;
  int ok = exists >= 0 && (exists == 0 || H5Adelete(obj, name) >= 0);
  if (ok) a = H5Acreate2(obj, name, ftype, space, H5P_DEFAULT, H5P_DEFAULT);
  ok = a >= 0 && H5Awrite(a, mtype, buf) >= 0;
  hid_t err = keep_stack(!ok);
  if (a >= 0) H5Aclose(a);
  if (space >= 0) H5Sclose(space);
  restore_stack(err);
  return ok;
}

/* set_error for "WHAT 'NAME' in" (a dataset or attribute name cut at 120
 * characters). */
static int fail_op(cup_h5run *w, const char *what, const char *name) {
  char op[200];
  snprintf(op, sizeof op, "%s '%.120s' in", what, name);
  return set_error(w, CUP_ERR_IO, op);
}

static int put_attr(cup_h5run *w, const char *name, hid_t ftype, hid_t mtype, const void *buf) {
  if (!w || !name || !name[0]) return CUP_ERR_ARG;
  if (w->h5_failed) return w->data_status;   /* see set_error */
  quiet_t q = quiet_begin();
  int st = replace_attr(w->file, name, ftype, mtype, buf) ? CUP_OK : fail_op(w, "write attribute", name);
  quiet_end(q);
  return st;
}

int cup_h5run_attr_double(cup_h5run *w, const char *name, double v) {
  return put_attr(w, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &v);
}

int cup_h5run_attr_long(cup_h5run *w, const char *name, long v) {
  int64_t v64 = (int64_t)v;
  return put_attr(w, name, H5T_STD_I64LE, H5T_NATIVE_INT64, &v64);
}

/* Variable-length UTF-8: h5py returns str, h5dump prints the text, and the
 * text lives in the global heap, so a long scene document does not hit the
 * 64 KiB limit of an attribute stored in the object header. */
int cup_h5run_attr_string(cup_h5run *w, const char *name, const char *v) {
  if (!w || !v) return CUP_ERR_ARG;
  quiet_t q = quiet_begin();
  hid_t type = h5_vlen_str();
  int st = type >= 0 ? CUP_OK : set_error(w, CUP_ERR_IO, "make a string type for");
  quiet_end(q);
  if (st == CUP_OK) st = put_attr(w, name, type, type, &v);
  if (type >= 0) H5Tclose(type);
  return st;
}

/* A whole float64 array at once (rank 1 or 2), in a group made as needed:
 * "crowd/radius". For what a run knows only at its end or from its set-up. */
int cup_h5run_array(cup_h5run *w, const char *name, int rank, const long *dims, const double *data) {
  if (!w || !name || !name[0] || rank < 1 || rank > 2 || !dims || (!data && dims[0] * (rank == 2 ? dims[1] : 1) > 0))
    return CUP_ERR_ARG;
  if (w->h5_failed) return w->data_status;
  hsize_t hd[2] = {(hsize_t)dims[0], rank == 2 ? (hsize_t)dims[1] : 1};
  quiet_t q = quiet_begin();
  hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
  int ok = lcpl >= 0 && H5Pset_create_intermediate_group(lcpl, 1) >= 0;
  hid_t space = ok ? H5Screate_simple(rank, hd, NULL) : H5I_INVALID_HID;
  hid_t d = space >= 0 ? H5Dcreate2(w->file, name, H5T_IEEE_F64LE, space, lcpl, H5P_DEFAULT, H5P_DEFAULT)
                       : H5I_INVALID_HID;
  ok = d >= 0 && (hd[0] * hd[1] == 0 || H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0);
  hid_t err = keep_stack(!ok);
  if (d >= 0) H5Dclose(d);
  if (space >= 0) H5Sclose(space);
  if (lcpl >= 0) H5Pclose(lcpl);
  restore_stack(err);
  int st = ok ? CUP_OK : fail_op(w, "write dataset", name);
  quiet_end(q);
  return st;
}

/* ---- describing datasets (CF attributes, dimension scales) ---- */

/* A string attribute on an object (dataset or group) by path, replaced. */
static int obj_string_attr(hid_t obj, const char *name, const char *v) {
  hid_t type = h5_vlen_str();
  int ok = type >= 0 && replace_attr(obj, name, type, type, &v);
  hid_t err = keep_stack(!ok);
  if (type >= 0) H5Tclose(type);
  restore_stack(err);
  return ok;
}

int cup_h5run_describe(cup_h5run *w, const char *dataset, const char *units, const char *long_name) {
  if (!w || !dataset || !dataset[0]) return CUP_ERR_ARG;
  if (w->h5_failed) return w->data_status;
  quiet_t q = quiet_begin();
  hid_t d = H5Oopen(w->file, dataset, H5P_DEFAULT);
  int ok = d >= 0 && (!units || obj_string_attr(d, "units", units)) &&
           (!long_name || obj_string_attr(d, "long_name", long_name));
  hid_t err = keep_stack(!ok);
  if (d >= 0) H5Oclose(d);
  restore_stack(err);
  int st = ok ? CUP_OK : fail_op(w, "describe", dataset);
  quiet_end(q);
  return st;
}

int cup_h5run_strings(cup_h5run *w, const char *name, long n, const char *const *v) {
  if (!w || !name || !name[0] || n < 1 || !v) return CUP_ERR_ARG;
  if (w->h5_failed) return w->data_status;
  for (long k = 0; k < n; k++) if (!v[k]) return CUP_ERR_ARG;
  hsize_t hn = (hsize_t)n;
  quiet_t q = quiet_begin();
  hid_t type = h5_vlen_str(), lcpl = H5Pcreate(H5P_LINK_CREATE);
  hid_t space = H5Screate_simple(1, &hn, NULL), d = H5I_INVALID_HID;
  int ok = type >= 0 && lcpl >= 0 && space >= 0 && H5Pset_create_intermediate_group(lcpl, 1) >= 0;
  if (ok) d = H5Dcreate2(w->file, name, type, space, lcpl, H5P_DEFAULT, H5P_DEFAULT);
  ok = d >= 0 && H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) >= 0;
  hid_t err = keep_stack(!ok);
  if (d >= 0) H5Dclose(d);
  if (space >= 0) H5Sclose(space);
  if (lcpl >= 0) H5Pclose(lcpl);
  if (type >= 0) H5Tclose(type);
  restore_stack(err);
  int st = ok ? CUP_OK : fail_op(w, "write dataset", name);
  quiet_end(q);
  return st;
}

/* netCDF-4's way of a dimension without a coordinate variable: an empty
 * dataset of the dimension's size that is a scale with this NAME. */
#define NC_DIM_ONLY "This is a netCDF dimension but not a netCDF variable."

/* The scale for dimension `dim` of a dataset in group `group` ("" = root),
 * axis length len (unlimited when grows): the dataset group/dim, else /dim,
 * made a scale if it is not one; else a new dimension-only dataset group/dim. */
static hid_t scale_for(cup_h5run *w, const char *group, const char *dim, hsize_t len, int grows,
                       const char *self) {
  char path[256];
  for (int pass = 0; pass < 2; pass++) {
    if (pass && !group[0]) break;
    int n = snprintf(path, sizeof path, "%s%s%s", pass ? "" : group, pass || !group[0] ? "" : "/", dim);
    if (n < 0 || (size_t)n >= sizeof path) return H5I_INVALID_HID;
    if (H5Lexists(w->file, path, H5P_DEFAULT) > 0) {
      hid_t s = H5Dopen2(w->file, path, H5P_DEFAULT);
      if (s >= 0 && H5DSis_scale(s) <= 0 && H5DSset_scale(s, dim) < 0) { H5Dclose(s); return H5I_INVALID_HID; }
      if (s >= 0 && !strcmp(path, self)) { H5Dclose(s); return 0; }   /* the coordinate itself */
      return s;
    }
  }
  int n = snprintf(path, sizeof path, "%s%s%s", group, group[0] ? "/" : "", dim);
  if (n < 0 || (size_t)n >= sizeof path) return H5I_INVALID_HID;
  hsize_t dims[1] = {grows ? 0 : len}, maxdims[1] = {grows ? H5S_UNLIMITED : len}, chunk[1] = {1024};
  hid_t space = H5Screate_simple(1, dims, maxdims), dcpl = H5Pcreate(H5P_DATASET_CREATE);
  hid_t s = H5I_INVALID_HID;
  char name[80];
  snprintf(name, sizeof name, "%s%10llu", NC_DIM_ONLY, (unsigned long long)len);
  if (space >= 0 && dcpl >= 0 && (!grows || H5Pset_chunk(dcpl, 1, chunk) >= 0))
    s = H5Dcreate2(w->file, path, H5T_IEEE_F32LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  if (s >= 0 && H5DSset_scale(s, name) < 0) { H5Dclose(s); s = H5I_INVALID_HID; }
  hid_t err = keep_stack(s < 0);
  if (dcpl >= 0) H5Pclose(dcpl);
  if (space >= 0) H5Sclose(space);
  restore_stack(err);
  return s;
}

int cup_h5run_dims(cup_h5run *w, const char *dataset, const char *const *dims) {
  if (!w || !dataset || !dataset[0] || !dims) return CUP_ERR_ARG;
  if (w->h5_failed) return w->data_status;
  char group[256];
  const char *slash = strrchr(dataset, '/');
  snprintf(group, sizeof group, "%.*s", slash ? (int)(slash - dataset) : 0, dataset);
  quiet_t q = quiet_begin();
  hid_t d = H5Dopen2(w->file, dataset, H5P_DEFAULT), space = d >= 0 ? H5Dget_space(d) : H5I_INVALID_HID;
  hsize_t cur[2] = {0, 0}, max[2] = {0, 0};
  int rank = space >= 0 ? H5Sget_simple_extent_dims(space, cur, max) : -1;
  int ok = rank >= 1 && rank <= 2;
  for (int k = 0; ok && k < rank; k++) {
    if (!dims[k]) { ok = 0; break; }
    hid_t s = scale_for(w, group, dims[k], cur[k], max[k] == H5S_UNLIMITED, dataset);
    ok = s == 0 || (s > 0 && H5DSattach_scale(d, s, (unsigned)k) >= 0);
    hid_t err = keep_stack(!ok);
    if (s > 0) H5Dclose(s);
    restore_stack(err);
  }
  hid_t err = keep_stack(!ok);
  if (space >= 0) H5Sclose(space);
  if (d >= 0) H5Dclose(d);
  restore_stack(err);
  int st = ok ? CUP_OK : fail_op(w, "attach dimension scales to", dataset);
  quiet_end(q);
  return st;
}

/* ---- close ---- */

int cup_h5run_close(cup_h5run **pw, char *errmsg) {
  if (!pw || !*pw) return CUP_OK;
  cup_h5run *w = *pw;
  int st = cup_h5run_flush(w);   /* returns the earlier data failure, if any */
  quiet_t q = quiet_begin();
  close_signals(w);
  herr_t r = H5Dclose(w->dset_x);
  r = H5Dclose(w->dset_e) < 0 ? -1 : r;
  H5Tclose(w->etype_file);
  H5Tclose(w->etype_mem);
  H5Pclose(w->exfer);
  r = H5Dclose(w->dset_t) < 0 ? -1 : r;
  r = H5Fclose(w->file) < 0 ? -1 : r;
  w->dset_x = w->dset_t = w->dset_e = w->etype_file = w->etype_mem = w->exfer = w->file = H5I_INVALID_HID;
  if (r < 0 && st == CUP_OK) st = set_error(w, CUP_ERR_IO, "close");
  quiet_end(q);
  if (st != CUP_OK && errmsg) snprintf(errmsg, CUP_ERRMSG_LEN, "%s", w->errmsg);
  cup_h5run_discard(pw);        /* a file never committed is not left behind */
  return st;
}

int cup_h5_version(char *buf, unsigned long size) {
  unsigned maj = 0, min = 0, rel = 0;
  H5get_libversion(&maj, &min, &rel);
  return snprintf(buf, size, "HDF5 %u.%u.%u", maj, min, rel);
}

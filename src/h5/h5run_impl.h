/* h5run_impl — the run writer's state, shared by h5run.c (create,
 * attributes, close), h5run_rows.c (the data path) and h5run_stop.c (a
 * staged file and its commit, reopening a stopped run's file, checkpoints).
 * Internal to catchup_h5: the functions below are hidden from the shared
 * library's users. */
#ifndef CUP_H5RUN_IMPL_H
#define CUP_H5RUN_IMPL_H

#include <stdint.h>
#include <hdf5.h>
#include "catchup.h"
#include "catchup/h5run.h"
#include "h5util.h"

#define H5R_HIDDEN __attribute__((visibility("hidden")))

/* One row of /events, in memory. */
typedef struct { double t; int32_t row; int8_t on; } h5_event;
enum { EVENT_ROWS = 1024 };     /* chunk and buffer of /events */

struct cup_h5run {
  hid_t file, dset_t, dset_x, dset_e;
  hid_t etype_file, etype_mem;  /* /events' compound types */
  hid_t exfer;                  /* /events' transfer: its conversion buffers below (event_types) */
  hsize_t ewritten, enbuf;      /* events handed to HDF5, buffered */
  h5_event ebuf[EVENT_ROWS];
  h5_event etconv[EVENT_ROWS], ebkg[EVENT_ROWS];   /* HDF5's type conversion of ebuf, in place */
  int dim;
  hsize_t chunk_rows;     /* rows per chunk = buffer capacity */
  hsize_t written;        /* rows already handed to HDF5 */
  hsize_t nbuf;           /* rows waiting in the buffer */
  double *tbuf, *xbuf;    /* chunk_rows and chunk_rows * dim entries; NULL until the first row */
  int nsig;               /* named signals: /signals/<name> */
  hid_t group;
  hid_t *dset_s;
  double *sbuf;           /* chunk_rows * nsig entries, one signal after another; as tbuf */
  double last_flush;      /* monotonic seconds */
  double last_tick;       /* monotonic seconds at the last look at the clock (cup_h5run_append) */
  int tick_every, tick_left;   /* rows between those looks (1 to TICK_ROWS_MAX), rows until the next */
  double unflushed;       /* bytes handed to HDF5 since the last H5Fflush: HDF5's chunk cache may
                             hold them (1 MiB per dataset), so the disk has not seen them yet */
  int data_status;        /* first failure of the data path; sticky */
  int h5_failed;          /* an HDF5 call failed: only close is attempted */
  char *path;
  char *staged;           /* cup_h5run_begin: the sibling written until cup_h5run_commit renames
                             it to path; NULL once committed (or reopened) */
  char errmsg[CUP_ERRMSG_LEN]; /* first failure of any kind (cup_h5run_status) */
  int err_status;         /* its status; CUP_OK while errmsg is "" */
};

/* h5run_rows.c: record the first HDF5 failure ("h5run: cannot OP 'PATH':
 * ...") and stop the writer, h5run.c's failures too (a message into
 * errmsg: util/fail.h's fail_fmt, compiled into catchup_h5 too). */
H5R_HIDDEN int set_error(cup_h5run *w, int status, const char *op);

/* Closing handles after a failure is itself an HDF5 call, which clears the
 * error stack: keep the failure's stack across the cleanup for set_error.
 * (Inline: h5run_rows.c's appends and h5run.c's set-up inline them, as
 * when both were one file.) */
static inline hid_t keep_stack(int failed) {
  return failed ? H5Eget_current_stack() : H5I_INVALID_HID;
}

static inline void restore_stack(hid_t saved) {
  if (saved >= 0) H5Eset_current_stack(saved);
}

/* A writer for path and dim, no file yet and no row buffers (taken at the first row) (NULL: the
 * status, with the message, in *st). */
H5R_HIDDEN cup_h5run *writer_new(const char *path, int dim, char *errmsg, int *st);
H5R_HIDDEN void free_writer(cup_h5run *w);
/* /events' file and memory types, and its transfer list, into w. 0 or -1. */
H5R_HIDDEN int event_types(cup_h5run *w);

#endif

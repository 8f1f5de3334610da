/* sweep_h5 — the results file of a sweep (docs/sweep-format.md, "Output"):
 * its layout, and what its writers share (sweep_h5.c): errors, row types,
 * the state kept in memory, the one-row-per-task tables. Below the crowd
 * sweeps' /crowd (sweep_crowd.c) and the file's writers (sweep_file.c,
 * sweep_file_create.c).
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
 * same lesson as h5run_rows.c). HDF5's sieve buffer is switched off so that every
 * H5Dwrite reaches the operating system when it returns, in our order: the
 * trajectories of a batch of tasks first, then their /summary rows with
 * done = 1, each row in one piece with done as its last byte. A process
 * killed at any point therefore leaves a file that opens as is, with every
 * row whose done flag is 1 complete (strace shows, after the first flush,
 * two pwrites per run of consecutive tasks in a batch — mostly one run —
 * and H5Fclose rewriting an identical superblock). H5Fflush still runs
 * regularly (it writes nothing here but is what HDF5 promises consistency
 * for), and does not fsync: a machine crash may lose what the OS had not
 * written.
 *
 * The full allocation at creation also means the disk cannot fill up during
 * the run (HDF5 1.10 cannot close a file after a failed write, h5util.h). */
#ifndef CUP_SWEEP_H5_H
#define CUP_SWEEP_H5_H

#include <stddef.h>
#include <stdint.h>
#include <hdf5.h>
#include "h5/h5util.h"
#include "sweep.h"

/* 2: /summary has tol_abs, tol_rel, err_est, events; 3: the tables' strings
 * are UTF-8, the datasets have CF attributes and dimension scales */
#define FORMAT_NAME "catchup-sweep 3"

/* One /summary row, packed as it is in the file: HDF5 then writes rows
 * as they are, where a conversion to the file's layout would first read
 * the rows it overwrites (its background buffer) and cost ~50 us a call. */
typedef struct __attribute__((packed)) sw_row {
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
  double tol_abs, tol_rel, err_est;
  int64_t events;
  int8_t done;
} sw_row;
/* A write cut short by a kill stops between pages, in address order: a row
 * whose last byte says done is whole. */
_Static_assert(offsetof(sw_row, done) + sizeof(int8_t) == sizeof(sw_row), "done is the last byte of a row");

/* One /crowd row (crowd sweeps, sweep_crowd.c), packed like sw_row; its
 * memory type is f->crowd_row_t. */
typedef struct __attribute__((packed)) sw_crowd_row {
  int64_t task_id;
  int32_t variant, agents, agents_out;
  double evacuation_time, min_gap;
  int8_t done;
} sw_crowd_row;

/* One /steady_state row (steady-state sweeps, sweep_steady.c), packed like
 * sw_row; its memory type (f->ss_row_t) names the figures of the measured
 * signals only ("v(out)_average", ...), the rest of fig unused. */
typedef struct __attribute__((packed)) sw_steady_row {
  int64_t task_id;
  int32_t variant, status, solved, newton_iterations;
  int64_t period_runs;
  double period, residual, max_multiplier, efficiency;
  double fig[SW_SS_SIGNALS][SW_SS_FIGURES];
  int8_t done;
} sw_steady_row;
/* The figures' names, in fig's order. */
extern const char *const sw_steady_figures[SW_SS_FIGURES];

typedef struct sw_refrow {
  int32_t variant;
  char variant_name[SW_NAME_LEN];
  int64_t n_ref;
  int32_t status;
  char status_name[SW_STATUS_LEN];
  char message[SW_MSG_LEN];
  double wall_time_s, correction, max_eps_cert, max_eta_cert;
  double cross_check;
  int64_t dual_iterations;
  int8_t done;
} sw_refrow;

struct sw_file {
  const sw_sweep *s;
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
  long cap;                        /* batched writes: room for cap tasks' ids, rows, trajectories */
  long *ids;
  sw_row *rows;
  double *x;
  /* crowd sweeps: /crowd, its memory type and staging rows (cap of them) */
  hid_t crowd, crowd_row_t;
  sw_crowd_row *crows;
  /* steady-state sweeps: /steady_state, its memory type and staging rows (cap of them) */
  hid_t steady, ss_row_t;
  sw_steady_row *ssrows;
  /* netlist sweeps: /runs/signals, /references/signals, staging (cap tasks' signals) */
  hid_t runs_sig, ref_sig;
  double *sig;
};

/* Keep the innermost HDF5 error as "PATH: cannot OP: detail" (the first
 * one only); the file is then failed: only close is attempted. */
int sw_h5_fail(sw_file *f, const char *op);
/* The message for a file another process holds (path, what we tried). */
#define SW_IN_USE_FMT "%s: cannot %s: the file is in use by another process (HDF5 file locking; another " \
  "catchup-sweep may be writing it): wait for that run to end, or stop it, then --resume; the file is " \
  "left as it was"
/* A fixed-length (NUL-terminated) UTF-8 string type (h5util.h has the
 * variable-length one). */
hid_t sw_h5_str(size_t size);
void sw_copy_str(char *dst, size_t size, const char *src);
/* A task's row before it ran: its parameters, status "pending". */
void sw_pending_row(const sw_sweep *s, long id, sw_row *r);
/* Rows at..at+count-1 of a one-dimensional compound dataset. */
int sw_h5_write_rows(hid_t d, hid_t memtype, hsize_t at, hsize_t count, const void *buf, hid_t dxpl);
/* The state in memory (no file yet), or NULL; sw_h5_file_free closes what is open. */
sw_file *sw_h5_file_new(const sw_sweep *s, const char *path);
void sw_h5_file_free(sw_file *f);
/* A dataset that is contiguous, allocated (and filled with *fill of
 * fill_type, unless fill is NULL) at creation, without modification times. */
hid_t sw_h5_fixed_dataset(hid_t loc, const char *name, hid_t ftype, int rank, const hsize_t *dims,
                          hid_t fill_type, const void *fill);
/* A task's row before it ran, into row (row_size bytes). */
typedef void (*sw_pending_fn)(const sw_sweep *s, long id, void *row);
/* Create the one-row-per-task dataset name (memtype packed), filled with
 * every task's pending row. */
int sw_h5_task_table(sw_file *f, const char *name, hid_t memtype, size_t row_size, sw_pending_fn pending,
                     hid_t *d);
/* Read or write, between buf (count entries) and dataset d whose first
 * dimension is the task, the entries of tasks f->ids[0..count). */
int sw_h5_task_io(sw_file *f, hid_t d, hid_t memtype, long count, void *buf, hid_t dxpl, int writing,
                  const char *op);

#endif

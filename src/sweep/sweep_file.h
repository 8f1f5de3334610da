/* sweep_file — the results file of a sweep (docs/sweep-format.md,
 * "Output"): created with its whole layout (sweep_file_create.c), reopened
 * for --resume, written as results arrive, closed (sweep_file.c). Rank 0 of
 * catchup-sweep is its only user. The layout and the design, crash safety
 * by a fixed layout, are in sweep_h5.h. Internal; not installed. */
#ifndef CUP_SWEEP_FILE_H
#define CUP_SWEEP_FILE_H

#include "sweep.h"

typedef struct sw_provenance {
  const char *catchup_version, *dependency_versions, *git_revision, *command;
} sw_provenance;

/* Create (replace) path with every dataset at full size and all metadata,
 * and flush: afterwards only raw data changes. */
int sw_file_create(sw_file **f, const char *path, const sw_sweep *s, const sw_provenance *p,
                   char *errmsg);
/* Reopen for --resume: the stored sweep hash and variants must match s. */
int sw_file_open(sw_file **f, const char *path, const sw_sweep *s, char *errmsg);
int sw_file_close(sw_file **f, char *errmsg);
int sw_file_flush(sw_file *f);

/* State read at open (and kept up to date by the writes). */
int sw_file_task_done(const sw_file *f, long task);
double sw_file_task_error(const sw_file *f, long task);
int sw_file_task_status(const sw_file *f, long task);
/* The variant's reference (samples * dim), or NULL while not known (or failed). */
const double *sw_file_reference(const sw_file *f, int variant);
/* 1 once the variant's reference job finished (even if it failed). */
int sw_file_reference_done(const sw_file *f, int variant);

/* What the tasks in the file came to, counted apart so that a summary
 * hides none: failed (an error status), not certified (a projection's
 * (eps, eta) not certified: CUP_WARN_NOT_CERTIFIED), tolerance missed (an
 * adaptive task whose error against its reference exceeds
 * tol_abs + tol_rel * max|x_ref|), other warnings, and ok (done, CUP_OK,
 * and within its tolerance). */
typedef struct sw_tally {
  long done, ok, failed, not_certified, tol_missed, warned, adaptive;
} sw_tally;
void sw_file_tally(const sw_file *f, sw_tally *t);

/* Write tasks given in increasing task order: first every trajectory (when
 * stored), then every /summary row with done = 1 — two HDF5 writes whatever
 * the count, each run of consecutive tasks one piece of the file — so that a
 * row marked done is complete wherever a kill stops the writes. */
int sw_file_write_tasks(sw_file *f, const sw_task_out *t, long count);
/* The reference of a variant is now known: set the error of its tasks that
 * were written without one, from their trajectories in /runs/x (reads and
 * writes by runs of consecutive tasks, as above). */
int sw_file_fill_errors(sw_file *f, int variant);
int sw_file_write_reference(sw_file *f, int variant, const sw_result *r, const double *xref);
const char *sw_file_errmsg(const sw_file *f);

#endif

/* catchup/h5run.h — HDF5 output of one run (library catchup_h5, built with
 * the apps): datasets /t [N] and /x [N, dim] (original x coordinates),
 * float64, and /events (the adaptive scheme's changes of the active set),
 * chunked and extendable, appended as samples arrive and flushed so
 * that an interrupted run keeps every sample written before the interruption.
 *
 * Memory is one chunk of rows (at most 4096 rows and about 1 MiB), however
 * long the run. Full chunks go to HDF5 as they fill; H5Fflush runs at least
 * once per second while samples arrive, on cup_h5run_flush and on close.
 * The file uses the HDF5 1.8 format (no SWMR, no "open for writing" flag), so
 * the file of a writer killed at any point opens with any HDF5 reader as it
 * is — no h5clear — and holds every sample written before the last flush.
 * After a crash, read min(len(/t), len(/x)) rows. H5Fflush does not fsync: a
 * machine crash (not a process crash) may lose more.
 *
 * Errors return CUP_ERR_IO (or CUP_ERR_ARG / CUP_ERR_NOMEM) with a message
 * naming the operation and the file; HDF5's automatic error printing is
 * switched off inside each call and restored before it returns. The writer
 * keeps CUP_H5_SPACE_MARGIN free on the file's device beyond what HDF5
 * still holds in its caches: below that it stops taking samples
 * (CUP_ERR_IO) but still writes attributes and closes cleanly, because HDF5
 * 1.10 cannot close a file after a write failed for lack of space (the file
 * is then unreadable and the library may crash at exit). After any failed
 * HDF5 call the writer refuses everything but close, for the same reason.
 *
 * Replacing a file: cup_h5run_begin writes a new sibling (PATH.partXXXXXX)
 * and cup_h5run_commit renames it over PATH in one step, so that an earlier
 * file at PATH is replaced only by a run that got past its checks; a
 * writer closed (or discarded) before its commit removes the sibling and
 * leaves PATH as it was. cup_h5run_create is begin and commit at once. */
#ifndef CATCHUP_H5RUN_H
#define CATCHUP_H5RUN_H

#include "catchup/export.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cup_h5run cup_h5run;

/** Bytes the writers (this one and catchup-sweep's) keep free on an
 *  output's device, beyond what HDF5 may still hold in its caches: what
 *  the final attributes, the metadata and the close need. catchup-run and
 *  catchup-sweep refuse a run whose planned output does not fit beside it. */
#define CUP_H5_SPACE_MARGIN (8u << 20)

/** Create path for states of dimension dim, replacing a file there; /t and
 *  /x exist, with N = 0, on disk when this returns (cup_h5run_begin, then
 *  cup_h5run_commit). errmsg (CUP_ERRMSG_LEN bytes, may be NULL) names the
 *  path and the problem on failure; *w is then NULL and path as it was. */
CUP_API int cup_h5run_create(cup_h5run **w, const char *path, int dim, char *errmsg);
/** The same, written to a new sibling of path (PATH.partXXXXXX, in the same
 *  folder, which must take new files) until cup_h5run_commit: path keeps
 *  what it holds while the caller declares signals, writes provenance and
 *  checks what it must. */
CUP_API int cup_h5run_begin(cup_h5run **w, const char *path, int dim, char *errmsg);
/** Flush, then rename the sibling over path (refused while another process
 *  holds path open). CUP_OK at once when there is nothing staged. */
CUP_API int cup_h5run_commit(cup_h5run *w);
/** Close and free without a word, removing a sibling not committed; *w = NULL. */
CUP_API void cup_h5run_discard(cup_h5run **w);
/** A cup_sample_fn: append (t, x) through ctx = the cup_h5run (k is not
 *  stored). Returns nonzero (the status) once writing has failed or space
 *  ran short, so that a run stops instead of computing what cannot be saved. */
CUP_API int cup_h5run_sink(long k, double t, const double *x, void *ctx);
/** A cup_event_fn: append one change of the active set (adaptive scheme)
 *  to /events through ctx = the cup_h5run. /events exists in every file
 *  (empty for fixed-step runs): one row per event, a compound of t (float64,
 *  the event time), row (int32, 0-based) and on (int8: 1 the row turns on,
 *  0 off), which h5py reads as a structured array (f["events"]["t"]).
 *  Buffered like the samples (1024 rows, flushed with them). */
CUP_API int cup_h5run_event(double t, int row, int on, void *ctx);
/** Declare named signals (a netlist's node voltages and branch currents):
 *  the group /signals gets one dataset per name, [N] float64, appended
 *  with /t by cup_h5run_append. Call once, before the first sample; names
 *  must be distinct and hold no '/'. The group's attribute `names` lists
 *  them in the order given (h5py lists a group's members sorted). */
CUP_API int cup_h5run_signals(cup_h5run *w, int nsig, const char *const *names);
/** Append one sample: t, x (dim entries) and the signals (nsig entries;
 *  NULL when none were declared). cup_h5run_sink is this with no signals. */
CUP_API int cup_h5run_append(cup_h5run *w, double t, const double *x, const double *sig);
/** Scalar attributes on the root group, replacing one of the same name:
 *  float64, int64, and variable-length UTF-8 string (h5py reads it as str).
 *  They reach the disk at the next flush or close. */
CUP_API int cup_h5run_attr_double(cup_h5run *w, const char *name, double v);
CUP_API int cup_h5run_attr_long(cup_h5run *w, const char *name, long v);
CUP_API int cup_h5run_attr_string(cup_h5run *w, const char *name, const char *v);
/** A whole float64 dataset (rank 1: dims[0]; rank 2: dims[0] x dims[1]),
 *  row-major, created with its groups ("crowd/exit_time"); an existing name
 *  is an error. For what a run knows at its set-up or its end. */
CUP_API int cup_h5run_array(cup_h5run *w, const char *name, int rank, const long *dims, const double *data);
/** Describe a dataset (or group) the CF way, as xarray and netCDF tools
 *  read it: string attributes `units` and `long_name` (either may be NULL:
 *  not written). dataset is a path: "x", "signals/v(out)". */
CUP_API int cup_h5run_describe(cup_h5run *w, const char *dataset, const char *units, const char *long_name);
/** A dataset of n variable-length UTF-8 strings (a coordinate of labels:
 *  "state", "crowd/wall_column"), created with its groups. */
CUP_API int cup_h5run_strings(cup_h5run *w, const char *name, long n, const char *const *v);
/** Name a dataset's dimensions (rank entries) by HDF5 dimension scales, as
 *  netCDF-4 does: for each axis, the 1-D dataset of that name beside the
 *  dataset, else at the root ("t"), becomes the scale (the coordinate); if
 *  there is none, a dimension without coordinates is made beside it. A
 *  1-D dataset named as its own dimension ("steps/t") becomes the scale. */
CUP_API int cup_h5run_dims(cup_h5run *w, const char *dataset, const char *const *dims);
/** Write what is buffered and flush the file to the OS. */
CUP_API int cup_h5run_flush(cup_h5run *w);
/** Flush, close, free, set *w = NULL. Returns the first failure of the data
 *  path during the writer's life (samples were lost) or of the close, with
 *  its message in errmsg (may be NULL). */
CUP_API int cup_h5run_close(cup_h5run **w, char *errmsg);
/** A stopped run's file, continued (catchup-run --resume).
 *
 *  Reopen path, written by this writer for states of dimension dim with
 *  the nsig signals `names` (in /signals, in that order): refused, naming
 *  what differs, when it is not such a file; appending goes on after its
 *  rows (the file is not staged: it is the run's own). */
CUP_API int cup_h5run_open(cup_h5run **w, const char *path, int dim, int nsig, const char *const *names, char *errmsg);
/** Cut /t, /x and /signals back to `rows` rows and /events to `events`. */
CUP_API int cup_h5run_truncate(cup_h5run *w, long rows, long events);
/** Store a checkpoint (cup_integrator_checkpoint_save's bytes) as the
 *  dataset /checkpoint (uint8), replacing one, with the rows and events
 *  written so far as its attributes `rows` and `events`; flushed. */
CUP_API int cup_h5run_put_checkpoint(cup_h5run *w, const void *blob, unsigned long size);
/** The stored checkpoint (malloc'd into *blob, size bytes) and the rows and
 *  events it covers; CUP_ERR_ARG when the file has none. */
CUP_API int cup_h5run_get_checkpoint(cup_h5run *w, void **blob, unsigned long *size, long *rows, long *events);
/** Remove /checkpoint (nothing when there is none). */
CUP_API int cup_h5run_drop_checkpoint(cup_h5run *w);
/** A root attribute read back: a string (malloc'd into *value) or a float64;
 *  CUP_ERR_ARG when there is no such attribute of that type. */
CUP_API int cup_h5run_get_string(cup_h5run *w, const char *name, char **value);
CUP_API int cup_h5run_get_double(cup_h5run *w, const char *name, double *v);
/** Remove a root attribute (nothing when there is none). */
CUP_API int cup_h5run_drop_attr(cup_h5run *w, const char *name);
/** Samples accepted so far (written or buffered). */
CUP_API long cup_h5run_count(const cup_h5run *w);
/** The writer's first failure, the one way errors travel (README, "Errors: one way"):
 *  its status (CUP_OK if nothing failed) and its words into errmsg
 *  (CUP_ERRMSG_LEN bytes, may be NULL; untouched when nothing failed). The
 *  writer stops at its first failure, so these words explain every later
 *  refusal too, and a failing sink (a callback, which returns only a status)
 *  is explained here. */
CUP_API int cup_h5run_status(const cup_h5run *w, char *errmsg);
/** The older form, kept for its users: the same words as cup_h5run_status
 *  gives, read in place ("" if nothing failed). A thin wrapper. */
CUP_API const char *cup_h5run_errmsg(const cup_h5run *w);
/** "HDF5 1.10.8" of the linked library, into buf (snprintf semantics). */
CUP_API int cup_h5_version(char *buf, unsigned long size);

#ifdef __cplusplus
}
#endif
#endif

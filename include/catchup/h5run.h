/* catchup/h5run.h — HDF5 output of one run (library catchup_h5, built with
 * the apps): datasets /t [N] and /x [N, dim] (original x coordinates),
 * chunked and extendable, appended as samples arrive and flushed so that an
 * interrupted run keeps every sample written before the interruption. */
#ifndef CATCHUP_H5RUN_H
#define CATCHUP_H5RUN_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cup_h5run cup_h5run;

/** Create (truncate) path for states of dimension dim. */
int cup_h5run_create(cup_h5run **w, const char *path, int dim, char *errmsg);
/** A cup_sample_fn: append (t, x) through ctx = the cup_h5run. */
int cup_h5run_sink(long k, double t, const double *x, void *ctx);
/** Root attributes. */
int cup_h5run_attr_double(cup_h5run *w, const char *name, double v);
int cup_h5run_attr_long(cup_h5run *w, const char *name, long v);
int cup_h5run_attr_string(cup_h5run *w, const char *name, const char *v);
/** Write what is buffered and flush the file to the OS. */
int cup_h5run_flush(cup_h5run *w);
/** Flush, close, free, set *w = NULL. errmsg (may be NULL) on failure. */
int cup_h5run_close(cup_h5run **w, char *errmsg);
/** Samples written so far. */
long cup_h5run_count(const cup_h5run *w);
/** "HDF5 1.10.8" of the linked library, into buf (snprintf semantics). */
int cup_h5_version(char *buf, unsigned long size);

#ifdef __cplusplus
}
#endif
#endif

/* h5run_rows — rows of samples appended at once (catchup-run's batches of
 * samples inside a step, integrator/record.h's put). Internal to catchup
 * and its apps, which link catchup_h5 statically. */
#ifndef CUP_H5RUN_ROWS_H
#define CUP_H5RUN_ROWS_H

#include "catchup/h5run.h"

/* Append count samples, as count calls of cup_h5run_append would, row by
 * row: t (count), x (count x dim, row-major), sig by columns, signal
 * k's count values at sig + k stride (stride >= count; NULL when none
 * were declared: a column's memcpy, as the writer keeps them). The rows
 * the calls would have taken with CUP_OK into *done, and the status of
 * the call after them (CUP_OK: all count). */
__attribute__((visibility("hidden")))
int h5run_append_rows(cup_h5run *w, int count, const double *t, const double *x, const double *sig, int stride,
                      int *done);

/* One sample, as cup_h5run_append (w, x and sig as that takes them; no
 * check), signal k at sig + k stride: a step's end (put's count 1). 1 if
 * it was taken (cup_h5run_append's CUP_OK), 0 if not (the writer's status
 * says why): the sink's own answer, so that put ends in a jump here. */
__attribute__((visibility("hidden")))
int h5run_take_row(cup_h5run *w, double t, const double *x, const double *sig, int stride);

#endif

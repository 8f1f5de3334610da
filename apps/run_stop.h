/* run_stop — what catchup-run does at a stop by SIGINT or SIGTERM and on
 * --resume (docs/run-output.md, "Interrupts"): the run's checkpoint goes into
 * the file (/checkpoint) and the state where it stopped becomes the file's
 * last row, flagged by the attribute stop_row; --resume reopens such a file,
 * checks that it continues this very run (the scene after overrides, the
 * SHA-256 of every input file, the signals), restores the integrator and
 * cuts the file back to the checkpoint's rows. */
#ifndef CUP_RUN_STOP_H
#define CUP_RUN_STOP_H

#include <stddef.h>
#include "catchup.h"
#include "catchup/h5run.h"

/* The signals of a netlist's run (nl NULL: none), with room for zeta and
 * the values, as catchup-run's sink computes them. */
typedef struct run_signals {
  cup_netlist *nl;
  double *zeta, *sig;
} run_signals;

/* At a stop: the checkpoint (when the run can resume: *resumable = 1) and
 * the state as the flagged last row. Returns the writer's status. */
int run_stop_save(cup_h5run *w, const cup_integrator *I, const cup_run_info *info, const run_signals *s,
                  int *resumable);
/* --resume: *w is OUT reopened, checked against the scene, its files and
 * the signals, cut back to its checkpoint; I restored from it; *wall the
 * seconds the run took before. A one-line message in err (size bytes). */
int run_stop_reopen(const char *out, const cup_scene *sc, cup_integrator *I, const run_signals *s, cup_h5run **w,
                    double *wall, char *err, size_t size);
/* After a run that ended (not by a signal): no checkpoint, no flag. */
int run_stop_clear(cup_h5run *w);

#endif

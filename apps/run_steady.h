/* run_steady — catchup-run --steady-state (docs/steady-state.md): the
 * steady state solved before the output is touched, the run turned into
 * one period from it, the period's samples kept for the measurements, and
 * the /steady_state group and the summary lines. When there is no steady
 * state the run falls back to the transient (or stops, fallback: false). */
#ifndef CUP_RUN_STEADY_H
#define CUP_RUN_STEADY_H

#include <stdio.h>
#include "catchup.h"
#include "catchup/h5run.h"

typedef struct run_steady run_steady;

/* The scene's request (NULL: none, and nothing else here is called). */
run_steady *run_steady_new(const cup_scene *scene);
void run_steady_free(run_steady **s);
/* With a netlist: the signals to measure and the power elements' v and i,
 * probed after the run's own probes (before /signals is declared). */
int run_steady_probes(run_steady *s, cup_netlist *nl, char *err, size_t size);
/* Solve with the run's options (scheme, tolerances, the interrupt flag),
 * the period map from the phase t0 of the sources (cup_scene_steady_phase).
 * Solved: o becomes one period from the steady state (T, the samples), and
 * the scene's sources stay read from t0 on.
 * Not solved: 0 with a warning in err when the request falls back to the
 * transient (o unchanged), else nonzero with the error in err. */
int run_steady_solve(run_steady *s, cup_scene *scene, cup_integrator_options *o, char *err, size_t size);
/* The phase t0 of the period run (0 when not solved): the scene's sources
 * are read from t0 on, and the run's t is t0 + t of the sources as written. */
double run_steady_t0(const run_steady *s);
/* The run's x0: the steady state if solved, else the scene's. */
const double *run_steady_x0(const run_steady *s, const double *scene_x0);
/* The run's integrator (options o): once solved, the one that notes the
 * period's switchings and events for the measurements of the signals that
 * jump (scene_pss_period_integrator); else cup_scene_integrator's. */
int run_steady_integrator(run_steady *s, cup_scene *scene, const cup_integrator_options *o, cup_integrator **I,
                          char *errmsg);
/* A sample of the period (the sink's), for the measurements. */
void run_steady_record(run_steady *s, double t, const double *x, const double *sig);
/* /steady_state into the file (and its measurements once the period ran
 * to its end); the status of the writes. */
int run_steady_write(run_steady *s, cup_h5run *w, const cup_scene *scene, int run_status);
/* The summary lines. */
void run_steady_report(const run_steady *s, const char *scene, FILE *f);

#endif

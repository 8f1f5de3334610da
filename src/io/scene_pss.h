/* scene_pss — a scene's steady state as catchup-run --steady-state
 * (apps/run_steady.c) and the steady-state sweeps (src/sweep/sweep_steady.c)
 * both solve it (docs/steady-state.md): the period and its phase t0 (the
 * scene's sources then read from t0 on), Newton's method on the period map
 * of the run's integrator options, and the options of one period from the
 * steady state. The period itself is each caller's run (catchup-run's is
 * its output run, streamed to its file with its events; a sweep's task
 * samples it in memory) by the integrator scene_pss_period_integrator
 * makes, which notes the times a signal may jump; its samples are measured
 * by pss_measure with those times (analysis/pss_run.h). Internal: the apps and src/sweep link the static
 * library. */
#ifndef CUP_SCENE_PSS_H
#define CUP_SCENE_PSS_H

#include "catchup.h"
#include "analysis/pss_run.h"

/* The steady state of scene s's request (cup_scene_steady_state) with the
 * run's options o (scheme, n over the scene's T, tolerances, the interrupt
 * flag, the wall-time limit): *T and *t0 the period and its phase
 * (cup_scene_steady_phase), the period map pss_map_options(o, the
 * scene's T, T, the request's map_tol) from the scene's x0. Solved (a
 * status >= 0): *period the options of one period from cup_pss_x0(*r): the
 * map's, with the request's samples from t = 0 (the time t0 of the sources
 * as written), and the scene's sources stay read from t0 on. Not solved: a
 * status < 0, the scene's sources as written again, and the cause in
 * errmsg when *r is NULL, else in *r's info; *stage says how far it got. */
enum { SCENE_PSS_PHASE, SCENE_PSS_SETUP, SCENE_PSS_NEWTON };   /* the period and phase; the map's integrator; Newton */
int scene_pss_solve(cup_scene *s, const cup_integrator_options *o, cup_pss **r, double *T, double *t0,
                    cup_integrator_options *period, int *stage, char *errmsg);

/* The integrator of one period from the steady state (options period,
 * scene_pss_solve's), as cup_scene_integrator makes it, that notes into J
 * (pss_jumps_init'ed; it must outlive *I) the times at which a signal may
 * jump: each break of the sources (cup_input_next_break: a PULSE's edges
 * and corners), each change of the switches' configuration and each event
 * of the adaptive scheme (the options' own on_event still called). */
int scene_pss_period_integrator(cup_scene *s, const cup_integrator_options *period, pss_jumps *J,
                                cup_integrator **I, char *errmsg);

#endif

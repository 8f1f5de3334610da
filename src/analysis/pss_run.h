/* pss_run — what the steady-state runs of a scene share (catchup-run
 * --steady-state, apps/run_steady.c; the steady-state sweeps,
 * src/sweep/sweep_steady.c): the period map's options, an element's power
 * probes and its average power over the period. Internal: the apps and
 * src/sweep link the static library. */
#ifndef CUP_PSS_RUN_H
#define CUP_PSS_RUN_H

#include "catchup.h"
#include "catchup/pss.h"

/* The period map's options for the steady state of a run with options
 * `run` over run_T: T the period and the final state only (output FINAL
 * from t = 0, no event callback); a fixed-step scheme keeps its step (n
 * scaled from run_T to T, at least 1); the adaptive scheme's tol_abs and
 * tol_rel map_tol unless 0. The rest (the interrupt flag, on_step, the
 * wall-time limit) is run's. catchup-run --steady-state, the steady-state
 * sweeps and cup_pss_solve take their maps from it. */
void pss_map_options(const cup_integrator_options *run, double run_T, double T, double map_tol,
                     cup_integrator_options *mo);
/* Probe netlist element `element`'s voltage v(a,b) (a, b its nodes) and
 * current i(element), whose product is the power it absorbs: their
 * signal indices in *v and *i (cup_netlist_probe: a signal probed before
 * keeps its index). CUP_ERR_ARG naming the element otherwise. */
int pss_probe_power(cup_netlist *nl, const char *element, int *v, int *i, char *errmsg);

/* What is measured over one period (catchup-run --steady-state, the
 * steady-state sweeps) and the figures (pss_measure). */
typedef struct pss_figures {
  int nm;                   /* signals measured: columns idx[0 .. nm) of the samples (idx NULL: 0 .. nm) */
  const int *idx;
  int harmonics;            /* their harmonics up to this order into amp and phase (nm rows of
                               harmonics + 1; NULL: none) */
  int np;                   /* elements whose average power is measured: from signals pv[j] and pc[j] */
  const int *pv, *pc;
  int eff_out, eff_in;      /* efficiency = power[eff_out] / -power[eff_in]; eff_out < 0: none */
  cup_measure *me;          /* out: nm figures */
  double *amp, *phase;      /* out, or NULL */
  double *power;            /* out: np averages */
  double efficiency;        /* out (untouched without eff_out) */
  const double *jt;         /* the period's jump times (pss_jumps_finish): nj, sorted, in [0, T); NULL: none */
  int nj;
  double T;
  int ends;                 /* a jump at 0 is one at T too (the sources break there: pss_jumps_finish) */
} pss_figures;

/* The figures f asks for of one period of N samples of ns signals each
 * (row-major, as recorded): cup_measure_period of each signal, then the
 * average of v i of each element, then the efficiency; stops at the
 * first error. w: N doubles of scratch. With jump times (f->jt), a signal
 * (or a product v i) that jumps at one of them (by more than the change
 * over a sample beside it and 1e-6 of its largest magnitude: a continuous
 * signal does not, and keeps cup_measure_period's figures) is measured
 * instead as the piecewise-linear interpolant of its samples with each
 * jump at its own time, each side's value extrapolated linearly from the
 * samples on its side (a jump on a sample: the sample is the side it
 * continues): its exact average, RMS, extremes (both sides of each jump)
 * and Fourier coefficients. O(h^2) on the smooth pieces, exact for
 * piecewise-linear signals (docs/steady-state.md). */
int pss_measure(const double *sig, long N, int ns, pss_figures *f, double *w, char *errmsg);

/* The times inside one period's run (0 < t < T, the run's own clock) at
 * which a signal may jump: each switching of the switches (scene_pss's
 * period integrator) and each event of the adaptive scheme
 * (pss_jumps_event, chained to the run's own on_event). Room for 4
 * samples + 64 times, allocated at init: nothing during the run. */
typedef struct pss_jumps {
  double *t;
  long n, cap;
  int overflow;             /* more than cap (4 a sample + 64; a time noted twice counts twice): none is used */
  int at_ends;              /* pss_jumps_breaks: the sources break at T too (so at 0 of the next period) */
  double T;
  cup_event_fn on_event;    /* the run's own, called after (or NULL) */
  void *event_ctx;
  cup_switching sw;         /* the model's switching, which scene_pss's wrapper calls */
} pss_jumps;

int pss_jumps_init(pss_jumps *J, double T, long samples);
void pss_jumps_free(pss_jumps *J);
void pss_jumps_add(pss_jumps *J, double t);
/* The breaks of the sources u in (0, J->T) (cup_input_next_break: a PULSE's
 * edges and corners, a PWL's knots), each noted as a jump time; at_ends
 * set if they break at T (within 1e-12 T) too. */
void pss_jumps_breaks(pss_jumps *J, const cup_input *u);
/* A cup_event_fn: the event's time, then the run's own on_event. */
int pss_jumps_event(double t, int row, int on, void *ctx);
/* The times sorted into f (jt, nj, T, ends; J keeps them), 0 first when
 * the sources break at T (at_ends): the last sample then reads them from
 * the next period, and the jump at T is one of the signals too (a
 * circuit without switches, a source's edge at the period's end); none if
 * they overflowed (J->overflow: more than 4 a sample + 64, which the samples
 * cannot resolve: the signals measured as by cup_measure_period alone). */
void pss_jumps_finish(pss_jumps *J, pss_figures *f);

#endif

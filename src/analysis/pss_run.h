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

/* The average power over one period of N samples of ns signals each
 * (row-major, as recorded), signals v and i (pss_probe_power): the
 * average of v i by cup_measure_period, in *avg. w: N doubles of scratch. */
int measure_power(const double *sig, long N, int ns, int v, int i, double *w, double *avg,
                  char *errmsg);

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
} pss_figures;

/* The figures f asks for of one period of N samples of ns signals each
 * (row-major, as recorded): cup_measure_period of each signal, then
 * measure_power of each element, then the efficiency; stops at the
 * first error. w: N doubles of scratch. */
int pss_measure(const double *sig, long N, int ns, pss_figures *f, double *w, char *errmsg);

#endif

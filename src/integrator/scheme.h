/* scheme — an integration scheme as the driver (integrator.c) holds it: a
 * table of functions and a workspace, as GSL's gsl_odeiv2_step_type and
 * the projector's proj_method (projector/proj_ws.h). A scheme is one file
 * with a static table and an exported pointer; schemes.c lists the ones
 * the options choose from, and the driver calls through the table and
 * names none. Types only. Internal to the library. */
#ifndef CUP_SCHEME_H
#define CUP_SCHEME_H

#include "catchup.h"
#include "freestep.h"
#include "record.h"
#include "util/ckpt.h"

/* What a scheme is made from, after the front door's checks (an LCS's or a
 * process's model; the integrator holds the same in its fields). */
typedef struct scheme_model {
  const freestep_drift *D;               /* A x + E u */
  const cup_lcs *L;                 /* an LCS (its B and D), or NULL */
  const cup_process_desc *pd;       /* a process (its set and f terms), or NULL */
  const cup_polyset *K;             /* the polyset's rows, or NULL (another set) */
  const la_sparse *G;              /* the offset's motion, or NULL */
  const cup_input *u;
  const cup_integrator_options *o;
  struct adaptive_scratch **scratch;  /* the adaptive scheme's run scratch shared with other workspaces
                                         (a switched run's configurations, adaptive.h), or NULL */
} scheme_model;

/* What a checkpoint's header names of a scheme's set-up beyond the options
 * (checkpoint.c): its grid step h, eps_n and eta_n, and whether the exact
 * LCP step stands in for the projector; zeros for a scheme without them. */
typedef struct scheme_grid {
  double h, eps_n, eta_n;
  int theta_step;
} scheme_grid;


typedef struct scheme_type {
  const char *name;
  /* 1 when it is the scheme the options name; NULL: made by its own front
   * door only (switched.c) */
  int (*takes)(const cup_integrator_options *o);
  /* set up for I from the model (I's options and model fields are filled);
   * *ws its workspace, freed by free also when this fails */
  int (*create)(cup_integrator *I, const scheme_model *md, void **ws, char *errmsg);
  void (*free)(void *ws);
  int (*run)(void *ws, const double *x0, cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
  const double *(*state)(const void *ws);
  int (*zeta)(void *ws, double *zeta);
  /* inside the sink: signals S at its sample (record.h), 1; 0 (or NULL):
   * not known here */
  int (*record)(void *ws, const struct signal_map *S, double *out);
  /* record.h's integrator_set_put; NULL: not taken */
  int (*set_put)(void *ws, cup_netlist *nl, record_put_fn put);
  /* the next runs' wall-time limit, in seconds from each run's start (0:
   * none): a caller running it many times under one limit (a switched
   * run's windows, a steady state's period runs) gives each run what is
   * left; NULL: the scheme has none */
  void (*wall_limit)(void *ws, double seconds);
  /* checkpoints (checkpoint.c; checkpoint NULL: none): what the header
   * names of the set-up; 1 when this one's
   * stops can be saved (saves NULL: always); 1 when the last run stopped
   * where it can resume, with the status and message the stop replaced
   * into info; its state to or from the stream; the restored run continued */
  void (*grid)(const void *ws, scheme_grid *g);   /* NULL: zeros */
  int (*saves)(const void *ws);
  int (*stopped)(const void *ws, cup_run_info *info);
  void (*checkpoint)(void *ws, ckpt *c);
  int (*resume)(void *ws, cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
} scheme_type;

#endif

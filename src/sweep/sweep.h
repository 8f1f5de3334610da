/* sweep — parameter studies for catchup-sweep (docs/sweep-format.md): the
 * sweep file (YAML, read with the scene loader's readers, io/scene_read.h,
 * so that every error names FILE:LINE:COL and the key), its tasks in a
 * fixed order, and what a job gives back. Above it in this folder: one
 * job's computation (sweep_run.h), the crowd sweeps' part (sweep_crowd.h)
 * and the HDF5 results file (sweep_file.h). No MPI here: the driver
 * (apps/catchup-sweep.c) moves job numbers and results between ranks.
 *
 * Jobs: 0 .. V-1 are the variants' references, V .. V+N-1 the tasks (task
 * id = job - V). Internal to the apps and tests; not installed. */
#ifndef CUP_SWEEP_H
#define CUP_SWEEP_H

#include <stdint.h>
#include "catchup.h"
#include "io/read_text.h"

#define SW_ERR_LEN (2 * CUP_ERRMSG_LEN)   /* messages: a scene's message, whole, inside a sweep's */

enum { SW_AXIS_N, SW_AXIS_EPS, SW_AXIS_ETA, SW_AXIS_SCHEME, SW_AXIS_PROJECTOR, SW_AXIS_TOL, SW_NAXES };

/* How the variants' references are made (reference.method). */
enum { SW_REF_RICHARDSON, SW_REF_ADAPTIVE };
#define SW_REF_ADAPTIVE_TOL 1e-13  /* the adaptive reference's tol (absolute and relative) */

/* String sizes of the /summary fields (fixed-length, NUL-terminated). */
/* SW_MSG_LEN: a task's message is its run's (cup_run_info.message), whole,
 * after a prefix of at most 64 characters ("set-up: ", "injected failure"). */
enum { SW_NAME_LEN = 64, SW_SPEC_LEN = 32, SW_WORD_LEN = 16, SW_STATUS_LEN = 32, SW_MSG_LEN = CUP_RUN_MSG_LEN + 64 };

/* A steady-state sweep measures at most this many signals and elements. */
enum { SW_SS_SIGNALS = 8, SW_SS_POWER = 8, SW_SS_FIGURES = 5 };

typedef struct sw_variant {
  char *name;
  char *scene_file;          /* path as resolved against the sweep file's directory */
  char *scene_dir;           /* its directory (Matrix Market files), or NULL */
  char **set;                /* overrides "key=value", in file order */
  int n_set;
  int line, col;             /* where the variant is written, for messages */
  int from_base;             /* its scene is the sweep's base */
  int proto;                 /* the variant whose scene stands for this one's settings (n, T, ...)
                                until a task loads it: itself, or its generated entry's first */
  char *scene_text;          /* after sw_resolve: cup_scene_text (overrides applied); a lazy
                                variant's only after sw_lazy_texts (rank 0: /variants) */
  char *file_text;           /* an entry's first with lazy variants: its scene file's text, which
                                their overrides apply to when a job loads one (sw_variant_load) */
  cup_scene *scene;          /* loaded from scene_text (the same on every rank); NULL for a lazy
                                variant (sw_variant_lazy): each job loads it (sw_variant_load) */
  long n_ref;                /* reference steps (a multiple of samples - 1) */
} sw_variant;

typedef struct sw_sweep {
  char *path;                /* the sweep file as named on the command line */
  char *dir;                 /* its directory, or NULL */
  char *text;                /* its full text (hashed, stored) */
  char sha256[65];
  file_list files;       /* rank 0, after sw_resolve_files: every file read (the sweep
                                file, its scenes and theirs: read_text.h), hashed */
  char *name;
  int base_line, base_col;   /* where base: is written, for messages */
  int n_variants;
  sw_variant *var;
  /* Axes: len[a] = 0 when absent (the variant's scene supplies the value). */
  int len[SW_NAXES];
  long *n;
  char **eps, **eta;         /* schedules as written ("n^-2.1", "0") */
  int *scheme, *projector;
  double *tol;               /* the adaptive scheme's tol (absolute and relative) */
  int zip[SW_NAXES];         /* zip group of each axis, -1 when not zipped */
  long samples;              /* common sample times t_j = j T / (samples - 1) */
  long ref_n;                /* reference.n as written; 0 = auto */
  int ref_method;            /* SW_REF_RICHARDSON or SW_REF_ADAPTIVE */
  int ref_check;             /* adaptive: also the Richardson limit, and their difference (reference.check) */
  long out_samples;          /* trajectories stored per task: samples or 0 */
  /* After sw_resolve: */
  double T;                  /* every variant's final time (they must agree) */
  int dim;                   /* every variant's state dimension */
  long per_variant;          /* tasks per variant */
  long n_tasks;              /* n_variants * per_variant */
  /* crowd sweeps (sweep_crowd.c): */
  int out_given;             /* output.samples is written in the file */
  int crowd;                 /* the variants are crowd: scenes (then dim is the largest 2N) */
  /* netlist sweeps: the signals every task records (variants.0's netlist's
   * probes, or its defaults; every variant's must be the same) */
  int nsig;
  /* steady-state sweeps (sweep_steady.c): the variants' scenes ask for the
   * steady state (steady_state:, or the netlist's .options steadystate); each
   * task solves it and measures one period (/steady_state) */
  int steady;
  int ss_nm, ss_np;                /* measured signals, power elements (variants.0's request) */
  int ss_sig[SW_SS_SIGNALS];       /* the measured signals' indices among the netlist's */
  int ss_pv[SW_SS_POWER], ss_pc[SW_SS_POWER];   /* each power element's v(a,b) and i(E) signal */
} sw_sweep;

/* A job's trajectory: samples * dim states, then samples * nsig signals;
 * none in a steady-state sweep (its figures are in the result). */
static inline long sw_traj_len(const sw_sweep *s) { return s->steady ? 0 : s->samples * (s->dim + s->nsig); }
/* Signal k's name (a netlist sweep's), e.g. "v(out)". */
const char *sw_signal_name(const sw_sweep *s, int k);

/* One task's parameters (sw_task_get). */
typedef struct sw_task {
  long id;
  int variant;
  long n;
  const char *eps, *eta;     /* specs as written */
  cup_schedule eps_s, eta_s;
  int scheme, projector;
  double tol_abs, tol_rel;   /* the adaptive scheme's */
} sw_task;

/* What a job sends back, followed by sw_traj_len doubles (the trajectory
 * at the common times, then its signals; NaN where not reached). Plain data: it travels as
 * bytes between ranks of one machine type. */
typedef struct sw_result {
  int64_t job;
  int32_t status;            /* cup status of the run */
  int32_t pad_;
  double wall;               /* seconds: integrator set-up + run (+ the second run of a reference) */
  double max_eps_cert, max_eta_cert;
  int64_t projected, skipped, not_certified, dual_iterations, factorizations;
  int64_t stopped_step;      /* steps completed */
  double correction;         /* references: max |x(2 n_ref) - x(n_ref)| at the common times */
  double cross_check;        /* references with check: max |x_adaptive - x_richardson| (NaN: none) */
  char message[SW_MSG_LEN];
  double err_est;            /* the run's a posteriori error estimate (NaN: none) */
  int64_t events;            /* the adaptive scheme's changes of the active set */
  /* crowd sweeps: a task's evacuation (/crowd, sweep_crowd.c) */
  struct sw_crowd_result {
    int32_t agents, agents_out;
    double evacuation_time;  /* the last agent's exit time if all left, else NaN */
    double min_gap;          /* smallest gap of the run's states (negative: overlap) */
  } crowd;
  /* steady-state sweeps: a task's steady state and its period's figures (/steady_state) */
  struct sw_steady_result {
    int32_t solved, iterations;  /* solved: 0 when no steady state was found (the figures NaN) */
    int64_t period_runs;
    double period, residual, max_multiplier, efficiency;
    double fig[SW_SS_SIGNALS][SW_SS_FIGURES];   /* average, rms, min, max, peak-to-peak */
  } steady;
} sw_result;

/* The results file (sweep_file.h; its layout is sweep_h5.h's), and one
 * task's result on its way there (sw_file_write_tasks). */
typedef struct sw_file sw_file;
typedef struct sw_task_out {
  long task;
  const sw_result *r;
  const double *traj;        /* samples * dim; unused when no trajectories are stored */
  double error;              /* against the variant's reference; NaN while not known */
} sw_task_out;

/* ---- the sweep file ---- */

/* Parse the sweep file's text (no file access). path names it in messages
 * and locates base/scene files. errmsg: SW_ERR_LEN bytes. */
int sw_parse(sw_sweep **s, const char *text, size_t len, const char *path, char *errmsg);
/* Read and parse a sweep file. */
int sw_load(sw_sweep **s, const char *path, char *errmsg);
/* Every variant's scene text after its overrides (rank 0): sw_resolve_scenes,
 * then sw_lazy_texts. */
int sw_resolve_files(sw_sweep *s, char *errmsg);
/* The scenes (rank 0): a variant that is not lazy loaded from its file (its
 * files join s->files), the scene file's text of an entry with lazy
 * variants read once (file_text: what their jobs need); then
 * sw_resolve_texts. The lazy variants' texts are not made: a sweep on
 * several ranks makes them (sw_lazy_texts) once the workers have work. */
int sw_resolve_scenes(sw_sweep *s, char *errmsg);
/* Each lazy variant's scene text (its entry's file_text after its
 * overrides, as cup_scene_text would give it), for /variants and --resume. */
int sw_lazy_texts(sw_sweep *s, char *errmsg);
/* Keep the variants' scene texts (what rank 0 broadcast; NULL for a lazy
 * variant), load the scenes of those that are not lazy, check that T and
 * the dimension agree, fix n_ref and the task count. */
int sw_resolve_texts(sw_sweep *s, char *const *texts, char *errmsg);
/* Lazy variants (loaded by sweep_variant.c): a generated variant beyond its entry's
 * first, in a sweep that is not of crowds, is loaded by its own jobs only
 * (a design study of 10^4 variants would otherwise load every scene on
 * every rank before the first task); its entry's first stands for its
 * settings until then, and its job checks that they agree. */
int sw_variant_lazy(const sw_sweep *s, int k);
/* The scene that gives variant k's settings (n, T, the scheme, ...): its
 * own once loaded, else its entry's first's. */
const cup_scene *sw_variant_settings(const sw_sweep *s, int k);
/* Load lazy variant k's scene from its entry's file_text and its own
 * overrides into *sc (the caller frees it),
 * probed as the sweep's scenes are, and checked against the scene that
 * stood for it: a located error in errmsg (SW_ERR_LEN) otherwise. */
int sw_variant_load(const sw_sweep *s, int k, cup_scene **sc, char *errmsg);
/* per_variant and n_tasks from the axes (after the variants are known). */
void sw_count_tasks(sw_sweep *s);
void sw_free(sw_sweep **s);

int sw_task_get(const sw_sweep *s, long id, sw_task *t);
/* Relative cost of a job (references first: they are the costliest). */
double sw_job_cost(const sw_sweep *s, long job);
/* Jobs in the order to dispatch: references by decreasing cost, then the
 * tasks in blocks of consecutive ids whose costs are within SW_BLOCK_SPREAD
 * of each other, blocks by decreasing largest cost (ties: the lower ids).
 * out: n_variants + n_tasks entries. */
#define SW_BLOCK_SPREAD 4.0
void sw_schedule(const sw_sweep *s, long *out);
/* The grid in words, for the file's attributes: "n: [100, 1000]; eps: ..." */
char *sw_grid_text(const sw_sweep *s);

/* Max-norm of traj - ref over times and components; NaN if any entry is NaN. */
double sw_max_error(const double *traj, const double *ref, long count);

#endif

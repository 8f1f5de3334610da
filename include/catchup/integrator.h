/* catchup/integrator.h — the inexact catching-up algorithm (paper, Sec. 3):
 *     x_{k+1} in proj^{eps_n, eta_n}_{K(t_{k+1})}( free step from x_k ),
 * on the uniform grid t_k = k T / n (each t_k computed directly from k,
 * never by accumulating t += h, so t_n = T exactly). */
#ifndef CATCHUP_INTEGRATOR_H
#define CATCHUP_INTEGRATOR_H

#include "catchup/export.h"
#include "catchup/lcs.h"
#include "catchup/input.h"
#include "catchup/projector.h"
#include "catchup/set.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cup_integrator cup_integrator;

/* One list of the schemes: X(enumerator, value, name, what it is). The enum,
 * cup_scheme_name/parse, catchup-run --help, the scene reader's messages,
 * the Fortran constants and the docs tables are all made from it. Values
 * are part of the ABI: append, never renumber. */
#define CUP_SCHEME_LIST(X)                                                              \
  X(CUP_SCHEME_EXPLICIT, 0, "explicit",                                                 \
    "the paper's scheme: x_k + h A x_k + E int u + int f, then project")              \
  X(CUP_SCHEME_IMPLICIT, 1, "implicit",                                                 \
    "(I - h A)^-1 (x_k + E int u + int f), then project (stable for stiff A)")        \
  X(CUP_SCHEME_EXPONENTIAL, 2, "exponential",                                           \
    "exact flow of A with the exact input convolution, then project")                 \
  X(CUP_SCHEME_THETA, 3, "theta",                                                       \
    "Moreau-Jean theta-method: W = (I - h theta A)^-1 and the step's exact LCP "       \
    "(theta = 1/2: second order where the solution is smooth; small dense systems)")  \
  X(CUP_SCHEME_ADAPTIVE, 4, "adaptive",                                                 \
    "event-driven: the exact flow of each active set's linear system, events located "  \
    "by root finding and the next active set by the velocity LCP; steps end on the "    \
    "input's breakpoints; tol sets the error, which is estimated (small dense systems)")

typedef enum cup_scheme {
#define CUP_SCHEME_ENUM_(e, v, name, doc) e = v,
  CUP_SCHEME_LIST(CUP_SCHEME_ENUM_)
#undef CUP_SCHEME_ENUM_
} cup_scheme;
#define CUP_SCHEME_ONE_(e, v, name, doc) +1
/** The number of schemes: values 0 .. CUP_SCHEME_COUNT - 1. */
enum { CUP_SCHEME_COUNT = 0 CUP_SCHEME_LIST(CUP_SCHEME_ONE_) };
#undef CUP_SCHEME_ONE_

/** A tolerance schedule: value(n) = coef * n^power ("n^-2.1": coef 1,
 *  power -2.1; "1e-6": coef 1e-6, power 0; "0.5*n^-1.05"). */
typedef struct cup_schedule {
  double coef;
  double power;
} cup_schedule;
/** Parse "n^-2.1", "3e-7", "0.5*n^-1" (spaces allowed). Returns CUP_ERR_PARSE
 *  with a message for anything else (a NaN or negative coefficient too). */
CUP_API int cup_schedule_parse(const char *spec, cup_schedule *out, char *errmsg);
CUP_API double cup_schedule_value(const cup_schedule *s, long n);
/** Format back as the canonical text ("n^-2.1", "1e-06", "0.5*n^-1.05"). */
CUP_API int cup_schedule_format(const cup_schedule *s, char *buf, unsigned long size);

/* One list of the output modes: X(enumerator, value, name, as written in a
 * scene, what is kept). Values are part of the ABI: append, never renumber. */
#define CUP_OUTPUT_LIST(X)                                                              \
  X(CUP_OUTPUT_EVERY, 0, "every", "{every: K}", "steps 0, K, 2K, ... and always the last") \
  X(CUP_OUTPUT_SAMPLES, 1, "samples", "{samples: N}",                                   \
    "N >= 2 states at t_j = j T / (N - 1), j = 0..N-1, interpolated between steps")   \
  X(CUP_OUTPUT_FINAL, 2, "final", "final", "the final state only")                      \
  X(CUP_OUTPUT_NONE, 3, "none", "none", "nothing: statistics only")                     \
  X(CUP_OUTPUT_TOL, 4, "tol", "{tol: X}",                                               \
    "every step's end and, inside the steps, the points of the exact flow that linear "   \
    "interpolation needs to stay within X of it (adaptive scheme; docs/run-output.md)")

typedef enum cup_output_kind {
#define CUP_OUTPUT_ENUM_(e, v, name, form, doc) e = v,
  CUP_OUTPUT_LIST(CUP_OUTPUT_ENUM_)
#undef CUP_OUTPUT_ENUM_
} cup_output_kind;
#define CUP_OUTPUT_ONE_(e, v, name, form, doc) +1
/** The number of output modes: values 0 .. CUP_OUTPUT_COUNT - 1. */
enum { CUP_OUTPUT_COUNT = 0 CUP_OUTPUT_LIST(CUP_OUTPUT_ONE_) };
#undef CUP_OUTPUT_ONE_

/** Perturbation f(t, x) (n entries into f); return nonzero to stop the run
 *  with CUP_ERR_CALLBACK. Its integral over a step, x frozen at x_k, uses
 *  Gauss-Legendre quadrature of the given order (exact for polynomials in t
 *  of degree 2 order - 1). Callable from Fortran (bind(C)). */
typedef int (*cup_rhs_fn)(double t, const double *x, double *f, void *ctx);

/** A term of f whose integral over a step the user computes exactly: write
 *  int_{t0}^{t1} f(s, x) ds (x frozen at x_k, as in the paper; n entries)
 *  into F; return nonzero to stop the run with CUP_ERR_CALLBACK. Callable
 *  from Fortran (bind(C)). */
typedef int (*cup_rhs_integral_fn)(double t0, double t1, const double *x, double *F, void *ctx);
/** A change of the active set (adaptive scheme): row (0-based) turns on
 *  (on = 1: the constraint holds with zeta >= 0; a diode of the paper's
 *  circuit conducts; a netlist row whose current the state fixes blocks) or
 *  off (on = 0) at time t (the located root; for a breakpoint, its time).
 *  Return nonzero to stop the run (CUP_ERR_INTERRUPTED). */
typedef int (*cup_event_fn)(double t, int row, int on, void *ctx);

/** Receives the selected states: step k, time t_k = k h, state x (n entries,
 *  original x coordinates). Return nonzero to stop the run (CUP_ERR_INTERRUPTED). */
typedef int (*cup_sample_fn)(long k, double t, const double *x, void *ctx);

/** Per-step report: step k (1..n) just taken to time t, with the statistics
 *  of its projection (pi->skipped is 1 when the free point was already in
 *  K). Return nonzero to stop the run (CUP_ERR_INTERRUPTED). */
typedef int (*cup_step_fn)(long k, double t, const cup_proj_info *pi, void *ctx);

typedef struct cup_integrator_options {
  cup_scheme scheme;          /**< CUP_SCHEME_EXPLICIT */
  double T;                   /**< final time, > 0 */
  long n;                     /**< steps, >= 1 */
  cup_schedule eps;           /**< eps_n (absolute, squared length); default n^-2.1;
                                   a zero schedule asks for the exact projection
                                   (certified to 1e-12 relative) */
  cup_schedule eta;           /**< eta_n (absolute, length); default n^-1.05;
                                   zero: 1e-10 relative */
  cup_projector_options proj; /**< method and limits; its eps/eta are replaced by the schedules.
                                   The explicit scheme with method AUTO on a small set in
                                   dense form (and no feasible_point) solves each step's
                                   projection exactly by principal pivoting on its m x m
                                   dual (the theta step with W = I), certified as the
                                   projector certifies; the projector takes over if that
                                   fails (an empty K(t) gets its Farkas certificate) */
  cup_output_kind output;     /**< CUP_OUTPUT_EVERY */
  long output_every;          /**< EVERY: stride (default 1) */
  long output_samples;        /**< SAMPLES: N >= 2 */
  cup_rhs_fn f;               /**< extra perturbation, or NULL */
  void *f_ctx;                /**< passed to f */
  int f_order;                /**< Gauss-Legendre points for int f (default 3) */
  double max_wall_seconds;    /**< stop with CUP_ERR_TIME_LIMIT after this (0: none) */
  double theta;               /**< THETA: in [0, 1]; default 0.5 */
  cup_step_fn on_step;        /**< per-step projector statistics, or NULL */
  void *step_ctx;             /**< passed to on_step */
  const volatile int *interrupt; /**< polled every 1024 steps: nonzero stops the run with
                                      CUP_ERR_INTERRUPTED (e.g. set by a signal handler) */
  /* the adaptive scheme and error estimates */
  double tol_abs;             /**< ADAPTIVE: absolute error target on x (max norm); default 1e-6 */
  double tol_rel;             /**< ADAPTIVE: error target relative to ||x(t)||_inf; default 1e-6 */
  double max_event_rate;      /**< ADAPTIVE: events per unit time beyond which they are taken for an
                                   accumulation (Zeno, chattering): CUP_WARN_ZENO, and catching-up
                                   steps across it; 0: 1e5 / T */
  cup_event_fn on_event;      /**< ADAPTIVE: each change of the active set, or NULL */
  void *event_ctx;            /**< passed to on_event */
  int estimate;               /**< fixed-step schemes: 1 estimates the error by step doubling, from a
                                   second run at n/2 in step (half again the work; n even); the
                                   adaptive scheme always estimates */
  double hmax;                /**< ADAPTIVE: no step longer than this (SPICE's TMAX); 0: none */
  double output_t0;           /**< SAMPLES: the first sample's time (SPICE's TSTART), in [0, T);
                                   the samples are at output_t0 + j (T - output_t0) / (N - 1),
                                   the adaptive scheme's from its exact flow, the fixed-step
                                   schemes' interpolated linearly between the steps around
                                   them (a sample on a step is that step's state); default 0 */
  double output_tol;          /**< TOL (adaptive scheme): > 0, finite. Each step's end is kept, as
                                   EVERY with K = 1 keeps it, and inside a step the points of its
                                   exact flow that make the straight lines between consecutive
                                   kept points stay within output_tol max(s_i, tol_abs + tol_rel
                                   max_j s_j) of x_i(t) in every component i, s_i = max |x_i| over
                                   the points of the run so far (docs/run-output.md, "Output tol") */
} cup_integrator_options;

/** What a run did. A run stops at the first error and says where. */
typedef struct cup_run_info {
  int status;                 /**< CUP_OK, a warning (first one seen), or the error */
  long step;                  /**< steps completed (n when finished) */
  double t;                   /**< t_step = step * h */
  long projected;             /**< steps whose free point was outside K and projected */
  long skipped;               /**< steps whose free point was already in K */
  long not_certified;         /**< projections returned with CUP_WARN_NOT_CERTIFIED */
  long long dual_iterations;  /**< total projector iterations */
  long factorizations;        /**< sparse numeric factorizations */
  double max_eps_cert;        /**< largest certified eps over the run */
  double max_eta_cert;        /**< largest certified eta over the run */
  double eps_target;          /**< eps_n used */
  double eta_target;          /**< eta_n used */
  double h_rho;               /**< h * spectral radius of A */
  long samples;               /**< states passed to the sink */
  char message[CUP_RUN_MSG_LEN]; /**< what went wrong, with step and time (never cut) */
  /* general sets (cup_integrator_create_process) */
  long set_rebuilds;          /**< state polyset: symbolic analyses of the run (and their
                                   allocations): the one at t = 0, then one per step whose rows
                                   brought a pattern not in the pool */
  long max_rows;              /**< state polyset: the most rows of one step */
  /* the adaptive scheme and error estimates */
  double err_est;             /**< a posteriori estimate of max over t of ||x(t) - x_exact(t)||_inf
                                   (adaptive scheme, or estimate = 1); NaN when not estimated */
  long events;                /**< ADAPTIVE: changes of the active set (rows switched) */
  long rejected;              /**< ADAPTIVE: steps rejected by the error test (callback inputs) */
} cup_run_info;

CUP_API void cup_integrator_options_default(cup_integrator_options *o);

/** Set up an integrator for the LCS with input u (may be NULL when the LCS
 *  has no input). Does everything that does not depend on the state: the
 *  free-step operator (e^{hA}, (I - hA)^-1), input integrals when u is
 *  constant, the projector (factored once), the stiffness check. An LCS
 *  with D = 0 is the sweeping process on its polyset {C x + G u + F >= 0}
 *  with f = A x + E u: cup_integrator_create_process on that set makes the
 *  same integrator (the same trajectory and zeta, bit for bit). This door
 *  also takes what a process cannot say: D != 0 and an active network's B
 *  (the theta and adaptive schemes). */
CUP_API int cup_integrator_create(cup_integrator **I, const cup_lcs *L, const cup_input *u,
                                  const cup_integrator_options *o, char *errmsg);
CUP_API void cup_integrator_free(cup_integrator **I);

/** Set up an integrator for a switched LCS (catchup/lcs.h, cup_switching;
 *  a netlist with switches gives one): each configuration's integrator is
 *  made from its LCS when the configuration first occurs and kept; the run
 *  steps to the switching times and jumps the state onto each new
 *  configuration's constraints there. The adaptive scheme steps to the
 *  switching times and locates those of switches the circuit gates; the
 *  fixed-step schemes keep their grid and split a step that holds a
 *  switching time of a switch the sources gate there (its pieces by the
 *  configurations' exact flows, the adaptive scheme's at tol_abs/tol_rel),
 *  and take a switching of one the circuit gates at the end of the step
 *  whose end state passes its threshold. The same run, state, zeta and free as any
 *  integrator's, and the fixed-step schemes' step-doubling estimate (a
 *  switched run at n/2 first); no checkpoints (CUP_ERR_UNSUPPORTED). */
CUP_API int cup_integrator_create_switched(cup_integrator **I, const cup_switching *sw, const cup_input *u,
                                           const cup_integrator_options *o, char *errmsg);

/** A general sweeping process (paper, Sec. 3)
 *      x'(t) in -N(C(t); x(t)) + f(t, x(t)),
 *  f(t, x) = A x + E u(t) + f_cb(t, x) + (a term given by its exact integral),
 *  stepped by x_{k+1} in proj^{eps_n, eta_n}_{C(t_{k+1})}(free step from x_k),
 *  in the set's metric P; a state-dependent set is taken at (t_{k+1}, x_k).
 *  The affine part has the schemes of an LCS (explicit, implicit,
 *  exponential; theta needs a polyset, whose step it solves as an LCP with
 *  B = P^-1 C^T); the other terms are added to the free step. Everything
 *  but the set and u is copied; both must outlive the integrator. */
typedef struct cup_process_desc {
  int n;                      /**< state dimension: the set's */
  int p;                      /**< input dimension: u(t) moves the set (its p parameters, if any)
                                   and enters f through E */
  const cup_set *C;           /**< the moving set (borrowed) */
  const cup_input *u;         /**< u(t), p components (borrowed); NULL when p = 0 */
  cup_csc A;                  /**< n x n; absent (ncol = 0): no A x */
  cup_csc E;                  /**< n x p; absent: no E u */
  cup_rhs_fn f;               /**< f_cb(t, x), integrated by Gauss-Legendre of order
                                   options.f_order (added to options.f), or NULL */
  void *f_ctx;                /**< passed to f */
  cup_rhs_integral_fn f_integral; /**< a term given by its exact integral over a step, or NULL */
  void *f_integral_ctx;       /**< passed to f_integral */
} cup_process_desc;

/** Set up an integrator for a general sweeping process; the same options,
 *  run, state, zeta and free as an LCS's (both doors end in one builder).
 *  A polyset is stepped exactly as an LCS with that set (the same code, the
 *  same trajectory and zeta); other sets go through their cup_setproj.
 *  Errors name the field ("A is 2 x 3, expected 3 x 3"). */
CUP_API int cup_integrator_create_process(cup_integrator **I, const cup_process_desc *d,
                                          const cup_integrator_options *o, char *errmsg);

/** The range of a state: a step whose state has an entry beyond CUP_STATE_MAX
 *  in magnitude, or NaN or Inf, has diverged. Every scheme stops there with
 *  CUP_ERR_DIVERGED (the step and time in info->message) before storing or
 *  returning that state; the states before it were passed to the sink. The
 *  bound leaves room below sqrt(DBL_MAX) = 1.3e154, where ||x||_P^2 (the
 *  projector's scale) overflows, for n P up to 1e8. x0 beyond it is
 *  CUP_ERR_ARG. */
#define CUP_STATE_MAX 1e150

/** Run from x0 (n entries) over [0, T], passing the selected states to sink
 *  (may be NULL). Allocates nothing per step. Returns info->status. */
CUP_API int cup_integrator_run(cup_integrator *I, const double *x0, cup_sample_fn sink,
                               void *sink_ctx, cup_run_info *info);

/** Checkpoints. A run stopped at a step's end before T — by the interrupt
 *  flag, by the sink or the step callback returning nonzero (status
 *  CUP_ERR_INTERRUPTED), or by the wall-time limit — can be saved as an
 *  opaque, versioned byte blob: the step, x_k, what the scheme carries
 *  from step to step (the projector's warm start and the anchor of its
 *  certificates, the LCP step's active set; the adaptive scheme's step
 *  size, active set, kept exponentials and error estimate), the output
 *  schedule's place and the run's statistics. An integrator made from the
 *  same model with the same options restores it, and cup_integrator_resume
 *  continues the run: the same steps, bit for bit, and the same samples
 *  (the one the sink refused is passed again), events and statistics as a
 *  run that was not stopped (a sparse set's Newton projections start from
 *  a fresh factorization of the same rows: the same answers to rounding).
 *  The blob holds no model: restoring refuses one from another
 *  configuration (scheme, dimensions, n, T, tolerances, output), naming
 *  what differs; keeping the model's values the same is the caller's part
 *  (catchup-run compares its input files' SHA-256). Processes of sets other
 *  than a polyset and switched LCSs cannot be saved (CUP_ERR_UNSUPPORTED). A blob is read by
 *  the build that wrote it, on the same kind of machine.
 *
 *  The size of the blob of the last run's stop: bytes, or a negative status
 *  (CUP_ERR_ARG: it did not stop where it can resume; CUP_ERR_UNSUPPORTED). */
CUP_API long cup_integrator_checkpoint_size(const cup_integrator *I);
/** Write it into buf (size bytes): info is what the stopped run returned. */
CUP_API int cup_integrator_checkpoint_save(const cup_integrator *I, const cup_run_info *info, void *buf,
                                           unsigned long size);
/** Read a blob into I (made as the saved one was); errmsg says why not. */
CUP_API int cup_integrator_checkpoint_restore(cup_integrator *I, const void *buf, unsigned long size, char *errmsg);
/** Continue the restored run to T (or its next stop), as cup_integrator_run
 *  would have; info starts from the saved run's statistics. */
CUP_API int cup_integrator_resume(cup_integrator *I, cup_sample_fn sink, void *sink_ctx, cup_run_info *info);

/** The final state of the last run (n entries). */
CUP_API const double *cup_integrator_state(const cup_integrator *I);
/** zeta of the last step taken (m entries into zeta, m the LCS's rows):
 *  the theta step's LCP solution, or the projection's multipliers divided
 *  by h (the impulse of the step over its length). Before the first step
 *  (x0's sample): theta's LCP at x0, 0 <= zeta _|_ C x0 + D zeta + g >= 0,
 *  which its first step starts from (with D = 0, or x0 not consistent: 0),
 *  the other fixed-step schemes' 0. Valid inside the sink, for the state
 *  it receives (a netlist's diode currents and voltages,
 *  cup_netlist_signals). The adaptive scheme gives the multipliers of the
 *  active set that holds from the sample's time on (at an event, the one
 *  chosen there; at t = 0 the one the solution takes right after it, the
 *  right limit), and zeros on its catching-up steps across accumulating
 *  events. A process on a polyset
 *  has them too, one per row of its set: its normal cone is
 *  {P^-1 C^T zeta : 0 <= zeta _|_ C x + g}, so x' = f + P^-1 C^T zeta as an
 *  LCS's x' = A x + E u + B zeta. CUP_ERR_UNSUPPORTED for a process on any
 *  other set (a ball, an oracle, a polyset and a ball, a state polyset):
 *  its normal cone has no fixed rows to give multipliers of. */
CUP_API int cup_integrator_zeta(const cup_integrator *I, double *zeta);
/** m, the entries cup_integrator_zeta writes: the LCS's rows, or the rows of
 *  a process's polyset; 0 for a process on another set (zeta refuses it). */
CUP_API int cup_integrator_rows(const cup_integrator *I);

/** The name of a scheme in CUP_SCHEME_LIST ("explicit", ...); "unknown" otherwise. */
CUP_API const char *cup_scheme_name(int scheme);
/** A name of CUP_SCHEME_LIST -> its value; -1 if unknown. */
CUP_API int cup_scheme_parse(const char *name);
/** The name of an output mode in CUP_OUTPUT_LIST ("every", ...); "unknown" otherwise. */
CUP_API const char *cup_output_name(int output);
/** A name of CUP_OUTPUT_LIST -> its value; -1 if unknown. */
CUP_API int cup_output_parse(const char *name);

#ifdef __cplusplus
}
#endif
#endif

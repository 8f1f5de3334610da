/* adaptive — the event-driven scheme CUP_SCHEME_ADAPTIVE: its entry of the
 * scheme table (scheme.h), and what switched.c and analysis/pss.c call of
 * it directly. */
#ifndef CUP_ADAPTIVE_H
#define CUP_ADAPTIVE_H

#include "catchup/integrator.h"
#include "model/input_impl.h"
#include "freestep.h"
#include "scheme.h"
#include "util/ckpt.h"

typedef struct adaptive_ws adaptive_ws;

extern const scheme_type *const scheme_adaptive;

/* I's adaptive scheme, or NULL when I runs another. */
adaptive_ws *adaptive_of(const cup_integrator *I);

/* x' = A x + E u + B zeta, 0 <= zeta _|_ C x + g0 + G u(t) >= 0 (D's
 * drift; K's rows, offset g0 and metric P, B = P^-1 C^T; G m x p or NULL):
 * an LCS's, or a general process's with a polyset and no other term.
 * An LCS with D != 0 gives its B and D (n x m, m x m; both NULL when
 * D = 0): then w = C x + D zeta + g0 + G u and x' = A x + B zeta + E u.
 * Requires a small dense set (K in dense form), no perturbation f, and
 * state plus input generators within the dense limit; errmsg says which
 * does not hold. Copies what it uses. scratch non-NULL: the run scratch
 * (what a window writes before it reads: the exponentials', the active
 * sets' construction's and choice's, the step's flow series, the
 * eigenvalue workspace; adaptive.c, struct adaptive_scratch) is *scratch's,
 * made on the first call (*scratch NULL) and shared by every workspace
 * made with it, which must never run at once (a switched run's
 * configurations, one window at a time); NULL: its own. */
typedef struct adaptive_scratch adaptive_scratch;
int adaptive_create(adaptive_ws **A, const freestep_drift *D, const cup_polyset *K, const la_sparse *G,
                    const la_sparse *B, const la_sparse *Dm, const cup_input *u,
                    const cup_integrator_options *o, adaptive_scratch **scratch, char *errmsg);
void adaptive_free(adaptive_ws **A);
/* The shared scratch, after every workspace that uses it is freed. */
void adaptive_scratch_free(adaptive_scratch **s);
/* A switched run's wall-time limit (switched.c): the seconds left of the
 * run's, for the next window (0: none). */
void adaptive_wall_limit(adaptive_ws *A, double seconds);
/* A switched run's window: its step callback (NULL: none), for the next
 * window (switched.c calls it only where it checks something). */
void adaptive_on_step(adaptive_ws *A, cup_step_fn fn, void *ctx);
int adaptive_run(adaptive_ws *A, const double *x0, cup_sample_fn sink, void *sink_ctx,
                 cup_run_info *info);
/* The run from ta (state xa) to tb only: a switched circuit's stretch in
 * one configuration (integrator/switched.c). first: ta = 0, x0 as given is
 * the first sample; jumped: xa is the state after a jump at ta (a switching),
 * which output every 1 records at ta, after the one before it that ended the
 * window before (jumped & 2: the sample the window before held,
 * adaptive_hold_end, given at ta; jumped & 4: the input has no breakpoint
 * in (ta, tb), cup_switching's quiet: none asked); steps and next_sample carry the
 * numbering across the windows. The statistics of the window into info. */
int adaptive_window(adaptive_ws *A, double ta, double tb, const double *xa, int first, int jumped,
                    long *steps, long *next_sample, cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
/* A switched run's windows of this configuration (switched.c, window):
 * from now on each tries the active set the last one started with before
 * its LCP (on: 1); 0 forgets it and stops (a run starts afresh). */
void adaptive_seed(adaptive_ws *A, int on);
/* A switched run's windows of this configuration (switched.c, sw_run):
 * on, the sample due at a window's end tb < T is not given there (the
 * state before the switching's jump) but by the next window, from the
 * state after it, offered at its start (adaptive_window's jumped & 2).
 * adaptive_held: 1 when the last window held one (cleared). */
void adaptive_hold_end(adaptive_ws *A, int on);
/* Output tol (adaptive_outtol.c) in a switched run: A's scales (each
 * state's largest |x_i| so far) are from's, one set for all the run's
 * configurations (a no-op for another output); adaptive_tol_reset zeroes
 * them (a run's start). */
void adaptive_tol_share(adaptive_ws *A, const adaptive_ws *from);
void adaptive_tol_reset(adaptive_ws *A);
int adaptive_held(adaptive_ws *A);
/* A held sample given after all (the run stopped before the next window):
 * the state the window left at its end t, as it would have been. */
int adaptive_offer_held(adaptive_ws *A, double t, long steps, long *next_sample, cup_sample_fn sink,
                        void *sink_ctx, cup_run_info *info);
/* What a record at a window's end asks of the input, and the next
 * window's first piece asks again at the same time: cup_input_next_break's
 * last answer (ad_next_break), and the workspace that built the last
 * piece's exosystem states (ad_inputs_on). */
typedef struct adaptive_breaks {
  input_breaks nb;
  const adaptive_ws *piece_of;
} adaptive_breaks;
/* A switched run's windows of this configuration (switched.c, sw_run) keep
 * them in *b, shared by all of the run's configurations (same input; the
 * run zeroes *b at its start); NULL: the workspace's own, forgotten at each
 * run's start. */
void adaptive_share_breaks(adaptive_ws *A, adaptive_breaks *b);
const double *adaptive_state(const adaptive_ws *A);
/* Inside the sink: zeta at the output time (m entries), the multipliers of
 * the active set that holds from there (at an event or a breakpoint, the one
 * chosen there; zeros at t = 0 and on catching-up steps across accumulating
 * events, whose multipliers are the projections' impulses). */
int adaptive_zeta(adaptive_ws *A, double *zeta);
/* Inside the sink, at a sample inside a step: S's signals there from the
 * step's flow state (record.h), 1; else 0. */
int adaptive_record(adaptive_ws *A, const struct signal_map *S, double *out);
/* record.h's integrator_set_put: the samples inside a step and at its
 * end to put with nl's signals (NULL put: all to the sink); 1, or
 * CUP_ERR_NOMEM. adaptive_put_on: with on 0, the next windows' samples
 * all go to the sink (switched.c: a sink of its own, not the user's). */
int adaptive_set_put(adaptive_ws *A, cup_netlist *nl, record_put_fn put);
void adaptive_put_on(adaptive_ws *A, int on);
/* Checkpoints (integrator.h): 1 when the last run stopped at a step's end,
 * where it can resume; the status and message the stop replaced, into
 * info; the run's state to or from a checkpoint (util/ckpt.h); and the
 * restored run continued (info: the saved run's statistics). */
int adaptive_stopped(const adaptive_ws *A);
/* 1 when the last run or window stopped because its sink refused a sample
 * (at a step's end or inside a step), not its step callback or a limit. */
int adaptive_refused(const adaptive_ws *A);
void adaptive_unstop(const adaptive_ws *A, cup_run_info *info);
void adaptive_checkpoint(adaptive_ws *A, ckpt *c);
int adaptive_resume(adaptive_ws *A, cup_sample_fn sink, void *sink_ctx, cup_run_info *info);
/* The derivative of the final state by x0 (the steady state's monodromy,
 * src/analysis/pss.c): with on, each run carries V = dx(t)/dx0 from V = I
 * through the linear maps the error estimate follows (each active set's
 * homogeneous flow; at an event, a jump or a new active set the
 * P-orthogonal projection onto its manifold, which is the saltation matrix
 * of a constraint that becomes active, and the identity for one released
 * with its multiplier at 0). D = 0 only: with D != 0 a switch that D
 * couples is not that projection (resonant.cir's slowest multiplier came
 * out 0.997 against the differences' 0.903), CUP_ERR_UNSUPPORTED.
 * Allocates when turned on; CUP_ERR_NOMEM. */
int adaptive_tangent(adaptive_ws *A, int on);
/* V after the last run (n x n, column-major), or NULL when off. */
const double *adaptive_tangent_matrix(const adaptive_ws *A);

#endif

/* switched — a switched LCS (cup_switching, catchup/lcs.h) run one
 * configuration at a time (docs/netlist.md, "Switches"; docs/design.md,
 * "Switched circuits"). Each configuration has its own integrator, made
 * from its LCS the first time the configuration is in force and kept: a
 * run allocates nothing once every configuration has occurred. The
 * integrator steps to the switching times, which the sources alone fix
 * for switches gated by them (breakpoints, found by the model), and at each
 * one the state jumps onto the new configuration's constraints (the model's
 * projection in the energy metric), then its integrator goes on from there
 * (projecting onto its K(t) first, as at any breakpoint).
 *
 * The adaptive scheme steps to the switching times (its steps end on
 * breakpoints already; a window [ta, tb] of one configuration is its run
 * from ta to tb, adaptive_window) and locates those of switches the
 * circuit gates. The fixed-step schemes keep their grid (t_k = k T / n,
 * windows of integrator_window) and step to the switching times of
 * the switches the sources gate: a step that holds one is split there,
 * its pieces run by the configurations' exact flows (the adaptive scheme
 * on each configuration's LCS, made on its first split step), so that the
 * error stays the scheme's own order. A switching of a switch the circuit
 * gates is taken at the end of the step whose end state passes the
 * threshold: a crossing that comes and goes inside one step is not seen.
 * A sample at a switching time is its right limit under every scheme: the
 * window that ends there holds it back, and the next one gives it after
 * the jump, from the configuration in force (docs/netlist.md, .tran). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "integrator_impl.h"
#include "adaptive.h"
#include "estimate.h"
#include "record.h"
#include "util/clock.h"

typedef struct switched_run switched_run;

#define SW_MAX 64          /* configurations (the model forms at most this many) */

struct switched_run {
  cup_switching ops;
  const cup_input *u;
  cup_integrator_options o;
  int n;
  cup_integrator *child[SW_MAX];
  adaptive_ws *ad[SW_MAX];  /* ... their adaptive scheme's workspace (the adaptive scheme's windows) */
  adaptive_scratch *scratch;   /* ... whose run scratch is one, theirs (one window at a time) */
  cup_integrator *twin[SW_MAX];   /* each configuration's exact flow, for split steps (fixed-step schemes) */
  int twin_off[SW_MAX];    /* ... which the adaptive scheme does not take */
  unsigned char gated[SW_MAX], moves[SW_MAX];   /* the adaptive scheme's windows: state_gated and moves of
                                                   each configuration, asked at its first window of a run */
  double piece_end, *xprev, *zsplit;   /* a split step: a piece's end, its start (x_{k-1}, or after a jump),
                                          zeta at its end */
  int cur;                 /* the configuration in force (its child answers state and zeta) */
  double *x;
  adaptive_breaks breaks; /* the input's next breakpoint, asked at a window's end and the next's start
                             (the adaptive scheme's windows, or the split steps' pieces, twin_of) */
  /* circuit-gated switches: each sample and step end of a window is checked */
  int watch;               /* checking (the window's configuration has such a switch) */
  int crossed;             /* one changed: at tbad, after tg */
  int user_stop;           /* the user's sink or step callback stopped the run */
  int probing;             /* locating a change: the user's step callback is not called */
  int refused;             /* the sample the check stopped at (1), or a step's end (0) */
  double tg, tbad;         /* the last time checked unchanged (state xg), the first changed */
  double *xg;
  cup_sample_fn sink;      /* the user's */
  void *sink_ctx;
  record_put_fn put;       /* integrator_set_put's, each configuration's adaptive scheme's (child_make) */
  cup_netlist *put_nl;
  cup_step_fn on_step;
  void *step_ctx;
  double wall0;            /* the run's start, when it has a wall-time limit */
  int coarse;              /* the estimate's run at n/2: its records are compared by step, no jump's */
  int holds;               /* a window's samples at a switching time wait for the jump (the right limit) */
  int unoffered;           /* adaptive: a window that failed had not offered the one the window before held */
  long kheld;              /* fixed-step: the step whose samples on t_k are held (-1: none), ... */
  int cheld;               /* ... by this configuration's integrator */
  cup_integrator *half;    /* estimate (fixed-step schemes): the same switched run at n/2, or NULL */
  estimate_ws est;        /* ... and the comparison with it at each step's end */
};

/* The check at a sample or a step's end (t, x): 1 stops the window. */
static int check(switched_run *S, double t, const double *x) {
  if (!S->watch || !(t > S->tg)) return 0;
  int c = S->ops.crossed(S->ops.ctx, S->cur, t, x);
  if (c) { S->crossed = 1; S->tbad = t; return 1; }   /* (c < 0, a failed input, is caught again by settle) */
  S->tg = t;
  la_copy(S->xg, x, S->n);
  return 0;
}

static int watch_sink(long k, double t, const double *x, void *ctx) {
  switched_run *S = ctx;
  if (check(S, t, x)) { S->refused = 1; return 1; }
  if (S->sink && S->sink(k, t, x, S->sink_ctx)) { S->user_stop = 1; return 1; }
  return 0;
}

static int watch_step(long k, double t, const cup_proj_info *pi, void *ctx) {
  switched_run *S = ctx;
  if (S->half) estimate_compare(&S->est, k, cup_integrator_state(S->child[S->cur]));
  if (S->watch && check(S, t, cup_integrator_state(S->child[S->cur]))) return 1;   /* (a call a step saved) */
  if (!S->probing && S->on_step && S->on_step(k, t, pi, S->step_ctx)) { S->user_stop = 1; return 1; }
  return 0;
}

static int child_make(switched_run *S, int topo, char *errmsg);

/* Configuration topo's integrator, made the first time it is in force. */
static inline int child_of(switched_run *S, int topo, char *errmsg) {
  return topo >= 0 && topo < SW_MAX && S->child[topo] ? CUP_OK : child_make(S, topo, errmsg);
}

static int child_make(switched_run *S, int topo, char *errmsg) {
  if (topo < 0 || topo >= SW_MAX) return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED, "more than %d switch configurations", SW_MAX);
  const cup_lcs *L = S->ops.lcs(S->ops.ctx, topo);
  char msg[CUP_ERRMSG_LEN];
  cup_integrator_options o = S->o;
  o.estimate = 0;                                  /* the run's, not each configuration's (S->half) */
  /* the circuit-gated switches' checks, then the user's; a fixed-step run
   * checks them at its grid (sw_fixed_run), so there the callback serves
   * the estimate's comparison and the user's alone: without either, no
   * call a step (and the fused steps, faststep.c, where they apply) */
  int calls = S->o.scheme == CUP_SCHEME_ADAPTIVE || S->o.estimate || S->on_step;
  o.on_step = calls ? watch_step : NULL;
  o.step_ctx = calls ? S : NULL;
  int st = integrator_create_shared(&S->child[topo], L, S->u, &o, &S->scratch, msg);
  if (st) return fail_fmt(errmsg, st, "switch configuration %d: %s", topo, msg);
  S->ad[topo] = adaptive_of(S->child[topo]);
  if (S->ad[topo] && S->put && (st = adaptive_set_put(S->ad[topo], S->put_nl, S->put)) < 0)
    return fail_fmt(errmsg, st, "switch configuration %d: out of memory", topo);
  return CUP_OK;
}


static void sw_free(void *ws) {
  switched_run *S = ws;
  for (int k = 0; k < SW_MAX; k++) {
    cup_integrator_free(&S->child[k]);
    cup_integrator_free(&S->twin[k]);
  }
  adaptive_scratch_free(&S->scratch);              /* (after its users) */
  cup_integrator_free(&S->half);
  estimate_free(&S->est);
  free(S->x);
  free(S->xprev);
  free(S->zsplit);
  free(S->xg);
  free(S);
}

/* The configuration in force's integrator answers state and zeta. */
static const double *sw_state(const void *ws) {
  const switched_run *S = ws;
  return cup_integrator_state(S->child[S->cur]);
}

static int sw_zeta(void *ws, double *zeta) {
  switched_run *S = ws;
  return cup_integrator_zeta(S->child[S->cur], zeta);
}

static int sw_record(void *ws, const struct signal_map *sig, double *out) {
  switched_run *S = ws;
  adaptive_ws *A = S->ad[S->cur];                  /* (the adaptive scheme's record without the table's calls) */
  return A ? adaptive_record(A, sig, out) : integrator_record(S->child[S->cur], sig, out);
}

/* record.h's integrator_set_put: the configurations' adaptive schemes,
 * those made later too (child_make); a window whose sink is watch_sink
 * gives its samples to the sink (window). */
static int sw_set_put(void *ws, cup_netlist *nl, record_put_fn put) {
  switched_run *S = ws;
  int took = 0;
  S->put = nl ? put : NULL;
  S->put_nl = nl;
  for (int k = 0; k < SW_MAX; k++) {
    if (!S->ad[k]) continue;
    int st = adaptive_set_put(S->ad[k], nl, S->put);
    if (st < 0) return st;
    took = 1;
  }
  return took && S->put;
}

/* One window's statistics into the run's. */
static void add_info(cup_run_info *info, const cup_run_info *w) {
  info->status = status_merge(info->status, w->status);   /* (linalg.h's: a window's call saved) */
  /* (a window's message is a string: its tail past the end is not cleared, adaptive_window) */
  if ((w->status != CUP_OK && info->message[0] == '\0') || w->status < 0)
    memcpy(info->message, w->message, strnlen(w->message, sizeof w->message - 1) + 1);
  info->step = w->step;
  info->t = w->t;
  info->projected += w->projected;
  info->skipped += w->skipped;
  info->not_certified += w->not_certified;
  info->dual_iterations += w->dual_iterations;
  info->factorizations += w->factorizations;
  info->max_eps_cert = la_fmax(info->max_eps_cert, w->max_eps_cert);
  info->max_eta_cert = la_fmax(info->max_eta_cert, w->max_eta_cert);
  info->samples += w->samples;
  info->events += w->events;
  info->rejected += w->rejected;
  if (!(info->err_est >= w->err_est)) info->err_est = isnan(w->err_est) ? info->err_est : w->err_est;
}

/* The wall-time limit is the run's, not a window's (each window's clock
 * starts afresh): the next window of configuration topo gets what is left
 * of it, and nothing left stops the run at step k, time t. */
static int wall_left(switched_run *S, int topo, long k, double t, cup_run_info *info) {
  if (!(S->o.max_wall_seconds > 0)) return CUP_OK;
  double left = S->o.max_wall_seconds - (now_seconds() - S->wall0);
  if (!(left > 0))
    return fail_fmt(info->message, CUP_ERR_TIME_LIMIT, "step %ld (t = %.17g): wall-time limit reached", k, t);
  integrator_wall_limit(S->child[topo], left);
  return CUP_OK;
}

/* Configuration topo's window from (t, x) to tb with the user's sink
 * (through the checks when watching); the state at its end into S->x. */
static int window(switched_run *S, int topo, double t, double tb, int first, int jumped, long *steps,
                  long *next_sample, int watching, cup_run_info *info) {
  adaptive_ws *A = S->ad[topo];
  cup_run_info w;
  S->watch = watching;
  S->crossed = S->user_stop = S->refused = 0;
  S->tg = t;
  if (watching) la_copy(S->xg, S->x, S->n);     /* (check's and locate's alone) */
  /* a step's callback checks the circuit-gated switches, or is the user's:
   * without either (a converter's PWM), no call a step */
  adaptive_on_step(A, watching || S->on_step ? watch_step : NULL, S);
  /* with nothing to check at a sample, the user's sink itself (a call a
   * sample saved); its refusal is the user's stop, as watch_sink's */
  int direct = !watching && S->sink;
  adaptive_put_on(A, direct);
  int st = adaptive_window(A, t, tb, S->x, first, jumped, steps, next_sample, direct ? S->sink : watch_sink,
                           direct ? S->sink_ctx : S, &w);
  if (direct && st < 0 && adaptive_refused(A)) S->user_stop = 1;
  S->watch = 0;
  if (S->crossed) {                                /* our stop, not an error; its sample not taken */
    st = CUP_OK;
    w.status = CUP_OK;
    w.message[0] = '\0';
    w.samples -= S->refused;
  }
  add_info(info, &w);
  if (st < 0) {
    /* the sample the window before held is offered (the sink may refuse
     * it: its stop) once the start chose the active set; a start that
     * failed offered none */
    S->unoffered = (jumped & 2) && w.samples == 0;
    return st;
  }
  la_copy(S->x, adaptive_state(A), S->n);
  return CUP_OK;
}

/* A circuit-gated switch changed in (tg, tbad]: the time by bisection on
 * the exact flow from (tg, xg) (windows without output), to the last bit;
 * then the window to it with the samples it holds. S->x and *t: there. */
static int locate(switched_run *S, int topo, double *t, long *steps, long *next_sample, cup_run_info *info) {
  cup_integrator *C = S->child[topo];
  double lo = S->tg, hi = S->tbad;
  long ksave = *steps, jsave = *next_sample;
  memcpy(S->x, S->xg, sizeof(double) * (size_t)S->n);
  double *x0 = S->xg;
  S->probing = 1;
  for (int it = 0; it < 200 && nextafter(lo, hi) < hi; it++) {
    double mid = lo + (hi - lo) / 2;
    long k = ksave, j = jsave;
    cup_run_info w;
    int st = adaptive_window(adaptive_of(C), S->tg, mid, x0, 0, 0, &k, &j, NULL, NULL, &w);
    if (st < 0) { S->probing = 0; add_info(info, &w); return st; }
    int c = S->ops.crossed(S->ops.ctx, topo, mid, adaptive_state(adaptive_of(C)));
    if (c < 0) { S->probing = 0; return fail_fmt(info->message, CUP_ERR_CALLBACK, "t = %g: the input u(t) failed", mid); }
    if (c) hi = mid; else lo = mid;
  }
  S->probing = 0;
  double ta = S->tg;
  la_copy(S->x, x0, S->n);
  int st = window(S, topo, ta, hi, 0, 0, steps, next_sample, 0, info);
  *t = hi;
  return st;
}

/* x0 moved by the jump into the configuration at t = 0: a warning. */
static void x0_moved(const switched_run *S, const double *x0, cup_run_info *info) {
  if (!memcmp(S->x, x0, sizeof(double) * (size_t)S->n)) return;
  info->status = CUP_WARN_X0_OUTSIDE;
  snprintf(info->message, sizeof info->message, "x0 is off the constraints of the switches' configuration at "
           "t = 0 (a loop of capacitors or a cut of inductors): it is projected onto them, and the first "
           "sample is the projection");
}

/* A configuration's exact flow (its LCS under the adaptive scheme, made
 * on the first split step it takes part in and kept): the pieces of a
 * fixed-step run's step that switching times split. NULL when the
 * adaptive scheme does not take the configuration (an active network: B
 * kept as given): its switchings are then taken at the step's end. */
static cup_integrator *twin_of(switched_run *S, int topo) {
  if (S->twin[topo] || S->twin_off[topo]) return S->twin[topo];
  cup_integrator_options o = S->o;
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.output = CUP_OUTPUT_EVERY;                     /* each step's end to twin_sink (the piece's end's zeta) */
  o.output_every = 1;
  o.on_step = NULL;
  o.estimate = 0;
  o.max_wall_seconds = 0;
  char msg[CUP_ERRMSG_LEN];
  if (cup_integrator_create(&S->twin[topo], S->ops.lcs(S->ops.ctx, topo), S->u, &o, msg)) S->twin_off[topo] = 1;
  else {
    adaptive_seed(adaptive_of(S->twin[topo]), 1);   /* its pieces try the last start's set (sw_run) */
    adaptive_share_breaks(adaptive_of(S->twin[topo]), &S->breaks);   /* (a piece's start asks, as a window's) */
  }
  return S->twin[topo];
}

/* The last piece's samples: none; at its end (t_k), zeta. */
static int twin_sink(long k, double t, const double *x, void *ctx) {
  (void)k; (void)x;
  switched_run *S = ctx;
  if (t == S->piece_end) cup_integrator_zeta(S->twin[S->cur], S->zsplit);
  return 0;
}

/* Configuration topo's exact flow from (ta, S->x) to tb, into S->x; the
 * last piece of a step (last) leaves zeta at tb in S->zsplit (the pieces
 * before it have no sink: their zeta, a solve at each end, went unused). */
static int piece(switched_run *S, int topo, double ta, double tb, int last, cup_run_info *info) {
  cup_integrator *W = S->twin[topo];
  long steps = 0, next = 0;
  cup_run_info w;
  S->cur = topo;
  S->piece_end = tb;
  if (last) la_zero(S->zsplit, cup_lcs_rows(W->L));
  int st = adaptive_window(adaptive_of(W), ta, tb, S->x, 0, 0, &steps, &next, last ? twin_sink : NULL, S, &w);
  if (st < 0) {
    add_info(info, &w);
    return st;
  }
  info->events += w.events;
  la_copy(S->x, adaptive_state(adaptive_of(W)), S->n);
  return CUP_OK;
}

/* The step (t_{k-1}, t_k] holds the switching time tb (on no grid time):
 * it is split there. From x_{k-1} (S->x) each configuration in force runs
 * by its exact flow to the next switching time and the state jumps onto
 * the next one's constraints, up to t_k; then step k's end is given to the
 * configuration in force (its samples, zeta the last piece's). The
 * samples inside the step are each piece's, given by its configuration
 * between the piece's ends (the state before the jump at its end, after
 * the one at its start), zeta the piece's at its end: on their side of
 * every jump. 1 when a configuration has no exact flow (nothing done: the
 * step is taken as before, switching at its end). (Out of line: inlined
 * into sw_run, its registers cost the adaptive scheme's windows.) */
static __attribute__((noinline)) int split_step(switched_run *S, long k, double *tb, int *topo, long *next_j,
                                                cup_run_info *info) {
  const cup_switching *sw = &S->ops;
  cup_integrator *C = S->child[*topo];
  double ta = integrator_grid_time(C, k - 1), tk = integrator_grid_time(C, k);
  double snap = 1e-9 * integrator_grid_step(C);
  if (!twin_of(S, *topo)) return 1;
  la_copy(S->xprev, S->x, S->n);
  int st = CUP_OK, to = *topo;
  for (;;) {
    double te = *tb < tk - snap ? *tb : tk;        /* within 1e-9 h of t_k: on it (as sw_fixed_run snaps) */
    /* a sample before te: the piece's zeta there, and its samples */
    int inside = te < tk && S->holds && integrator_sample_time(S->child[to], *next_j) < te;
    if ((st = piece(S, to, ta, te, te == tk || inside, info)) < 0) return st;
    if (te == tk) break;
    if (inside) {
      cup_run_info w;
      st = integrator_split_piece(S->child[to], k, ta, S->xprev, te, S->x, S->zsplit, next_j, S->sink, S->sink_ctx,
                                  &w);
      add_info(info, &w);
      if (st < 0) return st;
    }
    if ((st = sw->settle(sw->ctx, &to, te, S->x, NULL, info->message)) < 0) return st;
    sw->jump(sw->ctx, to, S->x);
    if ((st = child_of(S, to, info->message)) != CUP_OK) return st;
    if (!twin_of(S, to))
      return fail_fmt(info->message, CUP_ERR_UNSUPPORTED, "t = %.17g: switch configuration %d has no exact flow "
                      "(an active network) to step from the switching time to the grid", te, to);
    ta = te;
    la_copy(S->xprev, S->x, S->n);                 /* the next piece's start: after the jump */
    if (sw->next(sw->ctx, to, ta, S->o.T, tb))
      return fail_fmt(info->message, CUP_ERR_CALLBACK, "t = %g: the input u(t) failed", ta);
  }
  *topo = to;
  S->cur = to;
  cup_run_info w;
  int hold = S->holds && k < S->o.n && (*tb <= tk + snap || sw->state_gated(sw->ctx, to));   /* a switching at t_k */
  st = integrator_split_end(S->child[to], k, ta, S->xprev, S->x, S->zsplit, hold, next_j, S->sink, S->sink_ctx, &w);
  add_info(info, &w);
  if (hold && st >= 0) S->kheld = k, S->cheld = to;   /* (a stop before them: not reached, never offered) */
  return st;
}

/* The grid step k1 whose end is the first at or after the switching time
 * tb, from step k on: a switching time within 1e-9 h of a grid time is on
 * it (the gate's edges k PER + PW and the grid k T / n round apart by an
 * ulp, and a whole step more of the old configuration would follow: a
 * buck on a grid holding its edges had 29 of 200 periods one step longer) */
static long grid_step_at(const cup_integrator *C, long k, long n, double tb) {
  long k1 = (long)ceil(tb / integrator_grid_step(C));
  if (k1 > n) k1 = n;
  while (k1 > k + 1 && integrator_grid_time(C, k1 - 1) >= tb) k1--;
  while (k1 < n && integrator_grid_time(C, k1) < tb) k1++;
  if (k1 > k + 1 && tb - integrator_grid_time(C, k1 - 1) <= 1e-9 * integrator_grid_step(C)) k1--;
  return k1 <= k ? k + 1 : k1;
}

/* The model's configuration in force (its signals' rows) set to topo
 * again: the jump's call sets it (on a copy of the state: S->xg). */
static void in_force(switched_run *S, int topo) {
  la_copy(S->xg, S->x, S->n);
  S->ops.jump(S->ops.ctx, topo, S->xg);
}

/* The samples on t_k that the window before the switching there held
 * back: the right limit, from the configuration in force from t_k on
 * (topo: the state after the jump, S->x, and zeta as at a run's start,
 * with that configuration's signals, as the adaptive scheme's sample
 * there); topo < 0, the run stopped before the switching: as the window
 * would have given them (its configuration set in force again). */
static int release(switched_run *S, int topo, long *next_j, cup_run_info *info) {
  int cur = S->cur, by = topo >= 0 ? topo : S->cheld;
  long k = S->kheld;
  cup_run_info w;
  S->kheld = -1;
  if (topo < 0) in_force(S, by);
  S->cur = by;
  int st = integrator_held(S->child[by], k, topo >= 0 ? S->x : NULL, next_j, S->sink, S->sink_ctx, &w);
  S->cur = cur;
  add_info(info, &w);
  return st;
}

/* Configuration topo's window to step kw stopped (status st): right after
 * its last step (the interrupt, the wall-time limit), the samples it held
 * on t_kw are the run's stop's to give (release). st. */
static int stopped_holding(switched_run *S, int topo, int hold, long kw, long *next_j, int st) {
  if (hold && integrator_window_reached(S->child[topo], kw, next_j)) S->kheld = kw, S->cheld = topo;
  return st;
}

/* The fixed-step schemes: each configuration's integrator on the run's
 * grid (all have the same T and n), a window from t_k up to the next
 * source-gated switching time, or one step when a switch the circuit gates
 * is in force. A switching time on a grid time is taken there; one inside
 * a step splits it (split_step: the pieces by the configurations' exact
 * flows). A circuit-gated switching is taken at the end of the step whose
 * end state passes the threshold (settle there). */
static int sw_fixed_run(switched_run *S, double t, int topo, cup_run_info *info) {
  const cup_switching *sw = &S->ops;
  long k = 0, n = S->o.n, next_j = 0;
  int st = CUP_OK, known = -1;                     /* the configuration whose next switching time tb holds */
  int each = S->sink && S->o.output == CUP_OUTPUT_EVERY && S->o.output_every == 1 && !S->coarse;
  int last = topo;                                 /* the configuration that ran up to t */
  double tb = 0;
  S->holds = S->sink && !each && !S->coarse;
  S->kheld = -1;
  for (int first = 1; st >= 0 && k < n; first = 0) {
    int jumps = each && !first && topo != last;
    if (jumps) la_copy(S->xprev, S->x, S->n);
    if (!first) {
      sw->jump(sw->ctx, topo, S->x);
      if (S->half) estimate_anchor(&S->est, k, S->x);   /* (a jump: the samples after it start from it) */
    }
    st = child_of(S, topo, info->message);
    if (st) break;
    if (S->kheld >= 0 && (st = release(S, topo, &next_j, info)) < 0) break;
    S->cur = last = topo;
    cup_integrator *C = S->child[topo];
    /* every step recorded: a switching that moved the state has a second
     * record at t_k, after the jump (a line through the records shows the
     * jump, not a ramp across the next step), as the adaptive scheme's */
    if (jumps && memcmp(S->xprev, S->x, sizeof(double) * (size_t)S->n) != 0) {
      cup_run_info w;
      st = integrator_jump_sample(C, k, S->x, S->sink, S->sink_ctx, &w);
      add_info(info, &w);
      if (st < 0) break;
    }
    /* after a split step, tb is topo's first switching time after its
     * last piece's start: past t, it is the first after t too (lcs.h) */
    if ((known != topo || !(tb > t)) && sw->next(sw->ctx, topo, t, S->o.T, &tb)) {
      st = fail_fmt(info->message, CUP_ERR_CALLBACK, "t = %g: the input u(t) failed", t);
      break;
    }
    if ((st = wall_left(S, topo, k, t, info))) break;
    long k1 = grid_step_at(C, k, n, tb);
    /* inside step k1: the steps before it, then that one split */
    int split = tb < integrator_grid_time(C, k1) - 1e-9 * integrator_grid_step(C);
    long kw = split ? k1 - 1 : k1;
    if (sw->state_gated(sw->ctx, topo) && kw > k) kw = k + 1, split = 0;   /* its end checked */
    cup_run_info w;
    if (kw > k || first) {
      int hold = S->holds && !split && kw < n;     /* a switching at t_kw */
      int wst = integrator_window(C, k, kw, S->x, first, hold, &next_j, S->sink, S->sink_ctx, &w);
      add_info(info, &w);
      if (wst < 0) { st = stopped_holding(S, topo, hold, kw, &next_j, wst); break; }
      la_copy(S->x, cup_integrator_state(C), S->n);
      if (hold) S->kheld = kw, S->cheld = topo;
    }
    k = kw;
    known = -1;
    if (split) {
      int sst = split_step(S, k1, &tb, &topo, &next_j, info);
      if (sst < 0) { st = sst; break; }
      if (sst == 0) {                              /* tb: the next switching time, at or after t_k1 */
        last = topo;
        k = k1;
        t = integrator_grid_time(C, k);
        double snap = 1e-9 * integrator_grid_step(C), ts = tb > t && tb - t <= snap ? tb : t;
        known = topo;
        /* no source-gated switching in (the last piece's start, tb) and no
         * state-gated switch: the rule at t_k gives topo again (settle is
         * for switching times, as the adaptive scheme's windows have it) */
        if (k < n && (tb <= t + snap || sw->state_gated(sw->ctx, topo)))
          st = sw->settle(sw->ctx, &topo, ts, S->x, NULL, info->message);
        continue;
      }
      S->cur = topo;                               /* no exact flow: the step as the grid has it */
      int hold = S->holds && k1 < n;
      int wst = integrator_window(C, k, k1, S->x, 0, hold, &next_j, S->sink, S->sink_ctx, &w);
      add_info(info, &w);
      if (wst < 0) { st = stopped_holding(S, topo, hold, k1, &next_j, wst); break; }
      la_copy(S->x, cup_integrator_state(C), S->n);
      if (hold) S->kheld = k1, S->cheld = topo;
      k = k1;
    }
    t = integrator_grid_time(C, k);
    /* the rule at the switching time when the grid time was snapped to it from below */
    if (k < n) st = sw->settle(sw->ctx, &topo, t > tb ? t : tb, S->x, NULL, info->message);
  }
  if (st >= 0 && k == n) integrator_split_verdict(S->child, SW_MAX, info);
  if (S->kheld >= 0) {                             /* stopped before the switching: the samples as they were */
    cup_run_info w = *info;
    release(S, -1, &next_j, &w);
    info->samples = w.samples;
  }
  if (st < 0) info->status = st;
  else info->t = t;                                /* (a stop's: the window's, from add_info) */
  return info->status;
}

/* The estimate's run at n/2 (fixed.c's coarse_run for a switched
 * run): its states kept at the compared points. 1 when the interrupt flag
 * stopped it (the run stops too), its status in info. */
static int coarse_run(switched_run *S, const double *x0, cup_run_info *info) {
  cup_run_info hi;
  int st = cup_integrator_run(S->half, x0, estimate_keep, &S->est, &hi);
  estimate_start(&S->est, st >= 0);
  if (!(st == CUP_ERR_INTERRUPTED && S->o.interrupt && *S->o.interrupt)) return 0;
  info->status = CUP_ERR_INTERRUPTED;
  snprintf(info->message, sizeof info->message, "step 0 (t = 0): interrupted (in the estimate's run at n/2)");
  return 1;
}

static int sw_run(void *ws, const double *x0, cup_sample_fn sink, void *sink_ctx, cup_run_info *info) {
  switched_run *S = ws;
  const cup_switching *sw = &S->ops;
  double T = S->o.T, t = 0;
  memset(info, 0, sizeof *info);
  info->err_est = NAN;
  S->sink = sink;
  S->sink_ctx = sink_ctx;
  la_copy(S->x, x0, S->n);
  S->wall0 = S->o.max_wall_seconds > 0 ? now_seconds() : 0;
  int topo = 0, st = sw->settle(sw->ctx, &topo, 0, x0, NULL, info->message);
  long steps = 0, next_sample = 0;
  S->breaks = (adaptive_breaks){0};                /* (the input may have changed between runs) */
  if (st >= 0 && S->o.scheme != CUP_SCHEME_ADAPTIVE) {
    for (int k = 0; k < SW_MAX; k++)               /* the pieces' guesses afresh (a run never reads the one before) */
      if (S->twin[k]) adaptive_seed(adaptive_of(S->twin[k]), 1);
    if (S->half && coarse_run(S, x0, info)) return info->status;
    sw->jump(sw->ctx, topo, S->x);
    if (S->half) estimate_anchor(&S->est, 0, S->x);
    x0_moved(S, x0, info);
    integrator_split_reset(S->child, SW_MAX);
    st = sw_fixed_run(S, 0, topo, info);
    if (S->half) info->err_est = estimate_value(&S->est);
    return st;
  }
  /* every step recorded (output tol too: adaptive_outtol.c's points
   * between): a jump at a switching is recorded after it too */
  int each = S->sink && ((S->o.output == CUP_OUTPUT_EVERY && S->o.output_every == 1) || S->o.output == CUP_OUTPUT_TOL);
  adaptive_tol_reset(S->ad[0]);                    /* (output tol's scales: the run's, shared by its configurations) */
  /* else a sample at a switching time is the state after its jump: the
   * window before holds it (adaptive_hold_end) and, when the jump moved
   * the state, the next window gives it, else this one after all */
  int held = 0, hc = 0;                            /* hc: the configuration whose window held it */
  uint64_t seeded = 0, asked = 0;                  /* configurations whose windows try the last start's set; */
  for (int first = 1; st >= 0 && t < T; first = 0) {   /* ... whose gated and moves are known */
    int in = topo >= 0 && topo < SW_MAX;           /* (else child_of below fails) */
    if (in && !(asked >> topo & 1)) {              /* (a formed configuration's: settle formed topo) */
      S->gated[topo] = sw->state_gated(sw->ctx, topo) != 0;
      S->moves[topo] = !sw->moves || sw->moves(sw->ctx, topo);
      asked |= (uint64_t)1 << topo;
    }
    int mv = each && (!in || S->moves[topo]);      /* (a jump that cannot move x: no copy, no comparison) */
    if (mv) la_copy(S->xprev, S->x, S->n);
    sw->jump(sw->ctx, topo, S->x);               /* onto the configuration's constraints */
    int jumped = mv && memcmp(S->xprev, S->x, sizeof(double) * (size_t)S->n) != 0;
    if (first) x0_moved(S, x0, info);
    st = child_of(S, topo, info->message);
    if (st) break;
    if (!(seeded >> topo & 1)) {                   /* (afresh each run: a run never reads the one before) */
      adaptive_seed(S->ad[topo], 1);
      adaptive_share_breaks(S->ad[topo], &S->breaks);
      adaptive_hold_end(S->ad[topo], S->sink && !each);
      adaptive_tol_share(S->ad[topo], S->ad[0]);
      seeded |= (uint64_t)1 << topo;
    }
    S->cur = topo;
    double tb;
    st = sw->next(sw->ctx, topo, t, T, &tb);
    if (st) { st = fail_fmt(info->message, CUP_ERR_CALLBACK, "t = %g: the input u(t) failed", t); break; }
    if ((st = wall_left(S, topo, steps, t, info))) break;
    int give = held && t < tb;                     /* the window gives it at its start */
    if (give) held = 0;
    /* no breakpoint of the input before tb (the model's search knows): the window asks for none */
    int quiet = sw->quiet && sw->quiet(sw->ctx, topo, S->u, t, tb) == 1;
    st = window(S, topo, t, tb, first, jumped | give << 1 | quiet << 2, &steps, &next_sample, S->gated[topo], info);
    if (S->user_stop) t = info->t;                 /* where the window stopped */
    if (st < 0 || S->user_stop) {
      if (st < 0 && S->unoffered) held = 1;        /* its start failed: the stop below gives it */
      break;
    }
    if (S->crossed) st = locate(S, topo, &tb, &steps, &next_sample, info);
    if (st < 0) break;
    if (adaptive_held(S->ad[topo])) held = 1, hc = topo;
    t = tb;
    if (t < T) st = sw->settle(sw->ctx, &topo, t, S->x, NULL, info->message);
  }
  if (held && st < 0) {                            /* stopped at t before the next window: its sample as it was */
    cup_run_info w = *info;
    in_force(S, hc);
    S->cur = hc;                                   /* (the sink's record: hc's signals and zeta, not the failed window's) */
    adaptive_offer_held(S->ad[hc], t, steps, &next_sample, S->sink, S->sink_ctx, &w);
    info->samples = w.samples;
  }
  if (st < 0) info->status = st;
  if (S->user_stop && info->status >= 0) {
    info->status = CUP_ERR_INTERRUPTED;
    snprintf(info->message, sizeof info->message, "t = %.17g: stopped by the output sink or the step callback", t);
  }
  info->step = steps;
  info->t = t;
  return info->status;
}


/* The estimate's coarse run: the same switched circuit at n/2, its output
 * every stride steps into the comparison's rows. */
static int create_half(switched_run *S, const cup_switching *sw, const cup_input *u, char *errmsg) {
  if (estimate_init(&S->est, S->o.n, S->n) || estimate_samples(&S->est, &S->o))
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "error estimate: out of memory");
  cup_integrator_options h = S->o;
  h.n = S->o.n / 2;
  h.estimate = 0;
  h.on_step = NULL;
  h.output = CUP_OUTPUT_EVERY;
  h.output_every = estimate_stride(&S->est);
  int st = cup_integrator_create_switched(&S->half, sw, u, &h, errmsg);
  if (!st) ((switched_run *)S->half->ws)->coarse = 1;
  return st;
}

/* The run's limit (its windows share it: wall_left). */
static void sw_wall_limit(void *ws, double seconds) { ((switched_run *)ws)->o.max_wall_seconds = seconds; }

/* Made by its own front door below, never chosen by the options; no checkpoints. */
static const scheme_type switched_type = {
  .name = "switched", .free = sw_free, .run = sw_run, .state = sw_state, .zeta = sw_zeta, .record = sw_record,
  .set_put = sw_set_put, .wall_limit = sw_wall_limit,
};

int cup_integrator_create_switched(cup_integrator **out, const cup_switching *sw, const cup_input *u,
                                   const cup_integrator_options *o, char *errmsg) {
  if (!out || !sw || !o || !sw->settle || !sw->next || !sw->lcs || !sw->jump || !sw->state_gated || !sw->crossed)
    return fail_fmt(errmsg, CUP_ERR_ARG, "switched integrator: NULL argument");
  *out = NULL;
  int estimate = o->estimate && o->scheme != CUP_SCHEME_ADAPTIVE;   /* (the adaptive scheme estimates always) */
  if (estimate && (o->n < 2 || o->n % 2))
    return fail_fmt(errmsg, CUP_ERR_ARG, "the step-doubling estimate compares with a run at n/2: n = %ld "
                    "must be even", o->n);
  cup_integrator *I = calloc(1, sizeof *I);
  switched_run *S = calloc(1, sizeof *S);
  if (!I || !S) { free(I); free(S); return fail_fmt(errmsg, CUP_ERR_NOMEM, "out of memory"); }
  I->sch = &switched_type;
  I->ws = S;
  S->ops = *sw;
  S->u = u;
  S->o = *o;
  S->on_step = o->on_step;
  S->step_ctx = o->step_ctx;
  int st = child_of(S, 0, errmsg);
  if (!st) {
    const cup_lcs *L = sw->lcs(sw->ctx, 0);
    I->o = *o;
    I->L = L;
    I->u = u;
    I->n = S->n = cup_lcs_dim(L);
    I->m = cup_lcs_rows(L);
    I->p = cup_lcs_inputs(L);
    S->x = malloc(sizeof(double) * ((size_t)S->n + 1));
    S->xg = malloc(sizeof(double) * ((size_t)S->n + 1));
    S->xprev = malloc(sizeof(double) * ((size_t)S->n + 1));
    S->zsplit = malloc(sizeof(double) * ((size_t)I->m + 1));
    if (!S->x || !S->xg || !S->xprev || !S->zsplit) st = fail_fmt(errmsg, CUP_ERR_NOMEM, "out of memory");
  }
  if (!st && estimate) st = create_half(S, sw, u, errmsg);
  if (st) { cup_integrator_free(&I); return st; }
  *out = I;
  return CUP_OK;
}

/* adaptive — the event-driven scheme (docs/adaptive.md). Internal layout
 * shared by adaptive.c (set-up), adaptive_mode.c (one active set's linear
 * system, its exact flow, the velocity LCP), adaptive_series.c (a step's flow
 * from one vector as Taylor series pieces), adaptive_split.c (with D != 0,
 * the algebraic part of a mode), adaptive_dae.c (with D != 0, the choice of
 * the active set and the state jump), adaptive_event.c (the event functions, detection and
 * location of a crossing) and adaptive_run.c (the run: steps, breakpoints,
 * switches and the error estimate).
 *
 * Between events the active set J is fixed and, with B = P^-1 C^T, the LCS is
 * a linear ODE on the manifold C_J x + g_J(t) = 0 with zeta_J eliminated.
 * In v = x + K_J u (K_J = B_J S_J^-1 G_J, S_J = C_J B_J) it reads
 *     v' = Pi_J A v + Pi_J (E - A K_J) u,   Pi_J = I - B_J S_J^-1 C_J,
 * and the input is the output of a small exosystem w' = W w, u = U w (the
 * built-in waveforms between breakpoints; for a callback, the Taylor form of
 * its interpolating polynomial on each step), so y = (v, w) obeys y' = M_J y
 * and one matrix exponential is its exact flow and dense output. The
 * multipliers zeta_J and the slacks of the other rows are linear in y: the
 * event functions, whose sign changes are located by root finding on the
 * exact flow. */
#ifndef CUP_ADAPTIVE_IMPL_H
#define CUP_ADAPTIVE_IMPL_H

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <string.h>
#include <gsl/gsl_eigen.h>
#include "catchup/integrator.h"
#include "model/input_impl.h"
#include "set/polyset_impl.h"
#include "lcp/lcp.h"
#include "lcp/step.h"
#include "util/block.h"
#include "record.h"

#define AD_MODES 10         /* active sets kept with their matrices (least recently used goes): a
                               six-pulse bridge meets 10 in its first period (the inrush, then the
                               commutations), and 8 slots built 2 of them twice */
#define AD_ALIASES 16       /* sets with a dependent row remembered with the subset they hold as */
#define AD_BATCH 64         /* samples inside a step a call of integrator_set_put's put */
#define AD_JUMPS 8          /* with D, the jump's LCP: warm starts remembered with the set solved from them */
#define AD_SVD_MEMO 256     /* with D, the SVDs of D_JJ kept by its values: 2 KB (a six-pulse bridge's 14
                               SVDs are of 6 matrices; 214 doubles) */
#define AD_KNOWN 32         /* with D, row sets whose N was factored, remembered regular or singular */
#define AD_CACHE 3          /* exponentials kept per active set, by step length */
#define AD_DEGREE 7         /* callback inputs: interpolating polynomial degree per step */
#define AD_ZENO_RING 64     /* events counted for the rate cap */
#define AD_CARRY 64         /* with D, steps in a row that start from the last one's end (adaptive_run.c):
                               then one starts from the state put on the manifold and the input's own
                               states (the drift of y off the manifold and of the exosystem's flow
                               from the input: rounding, at most AD_CARRY steps of it) */

typedef struct ad_mode {
  uint64_t mask;            /* the active rows J */
  long stamp;               /* last use (0: empty) */
  int nj;
  int *rows;                /* J, m entries */
  double *M;                /* na x na generator, column-major */
  int *mp, *mi, *mj;        /* M's nonzeros by column (na + 1 starts, rows, columns), their values mx: M is */
  double *mx;               /* [Pi Q; 0 W], its w rows almost empty (a few percent of M in a converter) */
  double *L;                /* m x na event rows, row-major: zeta_i (i in J), slack_i (else) */
  double *Lc;               /* m constants of the event rows (F_i for slacks, 0 for zeta) */
  int *lp, *li;             /* the nonzeros of L or Lm by row (m + 1 starts, columns), their values */
  double *lx, *lmx;         /* in L and Lm: the event rows' sums over them, in the dense order; Lm
                               (not kept dense: its nonzeros alone) the magnitudes of the terms an
                               event value is computed from (|C_i| |X| for a slack: a row that
                               depends on the active ones has a tiny L_i, but its slack rounds at
                               that) */
  unsigned char *is_zeta;   /* m */
  double *X;                /* n x na, row-major: x = X y */
  int nz;                   /* the rows of the manifold: nj when D = 0; with D, those of Z^T (left
                               null space of D_JJ), the others fix zeta algebraically */
  double *Zt;               /* D != 0: nz x nj, row-major: Z^T (the manifold Z^T (C_J x + g_J) = 0) */
  double *R;                /* n x nz, column-major: B_J S_J^-1 (the manifold correction; with D,
                               B_J N^-1 on the Z rows) */
  double *KU;               /* n x nw, column-major: v = x + K_J U w */
  double mnorm;             /* ||M||_inf */
  double snorm;             /* max(||Pi A||_inf, ||W||_inf): M's diagonal blocks, which set how
                               fast a flow series' terms fall (its pieces' length) */
  double hmax;              /* step limit for event detection (< 0: not computed yet, ad_mode_hmax) */
  double hc[AD_CACHE];      /* cached exponentials exp(h M): h, matrix, last use */
  double *Ec[AD_CACHE];
  long cstamp[AD_CACHE];
  int *ep[AD_CACHE], *ei[AD_CACHE];   /* ... and their input states' rows' nonzeros by column (na + 1 */
  double *ex[AD_CACHE];     /* starts, rows), their values: exp(h [Pi Q; 0 W]) keeps the zeros of
                               [0 W] (written and read with 9 states or more, of which at most 6 the
                               circuit's, adaptive_mode.c's expm_rows_read: else ad_matvec's sums) */
} ad_mode;

typedef struct adaptive_ws adaptive_ws;   /* as in adaptive.h, which the run's API is in */

/* A step's flow from one vector as polynomials in theta: on each of nseg
 * equal pieces of [0, h] (hs = h / nseg, hs snorm <= 1),
 * exp((j hs + theta hs) M) y0 = sum_k c_jk theta^k, c_jk = (hs M)^k y_j / k!,
 * y_j the previous piece's end. Built once per step (about 20 products by
 * M's nonzeros a piece, made when first needed) and valued at any tau in
 * [0, h] by Horner's rule (na per term): an event's probes, its root's
 * Newton steps and the error's flows each took a Taylor series of their own
 * from the step's start (ad_series_at). */
#define AD_SERIES_MAX 40    /* terms a piece */
#define AD_SERIES_SEGS 16   /* pieces at most (h snorm <= 16; ad_flow beyond) */
typedef struct ad_series {
  const struct ad_mode *md; /* the mode it was asked for (NULL: not yet in this step) */
  const double *y0;         /* ... and the start vector */
  double h;
  int dim;                  /* the components it carries: na, or n for start vectors (v, 0) (the
                               error's: M = [Pi Q; 0 W] keeps w = 0, and its first n columns'
                               nonzeros are the Pi Q block's) */
  int nseg;                 /* pieces; 0: not usable (h snorm > AD_SERIES_SEGS), ad_flow instead */
  int built;                /* the pieces made so far (each when a tau first falls in it) */
  int K[AD_SERIES_SEGS];    /* a piece's c_j0 .. c_jK */
  double *c;                /* AD_SERIES_SEGS x (AD_SERIES_MAX + 1) x dim, and a spare dim */
  double *mag;              /* na: the largest term of each component */
  double *v;                /* na: a start vector the caller keeps here */
} ad_series;

/* One run's progress (adaptive_run.c). */
typedef struct ad_run {
  cup_run_info *info;
  cup_sample_fn sink;
  void *sink_ctx;
  double t, tb;             /* now; the next breakpoint of the input (or T) */
  struct ad_mode *md;       /* the active set's system */
  long steps, next_sample;
  double est_max;           /* the largest error estimate so far */
  double r2, rloc;          /* rounding (sum of squares), unsigned local contributions */
  double h_cb;              /* callback inputs: the next step size */
  int floor_warned;
  double wall0;
  double tend;              /* catching-up steps across accumulating events until tend (0: none) */
  long ev0;                 /* the events before the step under way (the accumulation check after it) */
  int after_event;          /* the steps since the last event met no breakpoint: a step that ends on
                               one (not at its length limit) has a length that will not recur */
  int kept;                 /* at_break found x inside K(t) with the offset A->gk (2: A->gbrk, not
                               copied): start_piece's check at t+ with the same offset would find
                               it again */
} ad_run;

/* Where a run stopped at a step's end (adaptive_run.c, for a checkpoint). */
enum { AD_STOP_NONE, AD_STOP_STEP, AD_STOP_SAMPLE, AD_STOP_DENSE };
typedef struct ad_stop {
  int phase;                /* AD_STOP_STEP: the step's sample and what follows it are next;
                               AD_STOP_SAMPLE: the sink refused that sample;
                               AD_STOP_DENSE: it refused a sample inside the step (ad_pend), the
                               step is taken: its samples from that one on, its callback and its
                               end's sample are next */
  cup_proj_info pi;         /* AD_STOP_DENSE: the step's, for its callback */
  ad_run R;                 /* the run's scalars (its pointers are set again on resume) */
  int md, pinned1;          /* slots of R.md and of the other set in use (-1: none) */
  int carry;                /* the step's end is carried to the next step's start (adaptive_ws's) */
  int status;               /* the run's status and message before the stop replaced them */
  char message[CUP_RUN_MSG_LEN];
} ad_stop;

/* What a run or a window resets at its start (run_begin): where it
 * stopped, the event-rate ring. A switched run's configurations run one
 * window at a time and share one (adaptive_scratch's): 2 KB less a
 * configuration to set up (switched.c reads a configuration's stop right
 * after its window, and such a run has no checkpoint); a workspace
 * without a shared scratch carries its own after itself (zeroed: the
 * block's layout, and so the pages a single run touches first, as before). */
typedef struct ad_window_state {
  ad_stop stop;
  double zeno[AD_ZENO_RING];
  int zeno_row[AD_ZENO_RING];
} ad_window_state;

struct adaptive_ws {
  void *block;              /* the arrays the set-up sizes (adaptive.c, alloc_block): one allocation */
  void *slots;              /* the active sets' slots' arrays: in block with a shared scratch, else
                               their own allocation (ad_modes_take, at a run's start: NULL before) */
  int slots_lost;           /* a checkpoint's kept sets were not rebuilt: no memory for the slots */
  struct adaptive_scratch *scratch; /* the run scratch's owner when shared (adaptive_create), or NULL */
  const double *F;          /* the offset at u = 0: K's g0 */
  const cup_input *u;
  const cup_polyset *K;
  cup_integrator_options o;
  double tend;              /* where the run ends: T, or a window's end (adaptive_window) */
  int n, m, p, nw, na;
  int callback;             /* u is a callback: polynomial exosystem of degree AD_DEGREE */
  /* D != 0 (adaptive_dae.c): w = C x + D zeta + G u + F, x' = A x + B zeta + E u */
  int has_D;
  double *Bd;               /* n x m, column-major: B (P^-1 C^T when D = 0) */
  double *Dd;               /* m x m, column-major */
  double *CB;               /* m x m, column-major: C B */
  unsigned char *dcpl;      /* rows with a nonzero in their row or column of D */
  unsigned char *jseed;     /* m: the jump's last active set (ad_dae_jump's warm start) */
  uint64_t jfrom[AD_JUMPS], jto[AD_JUMPS];   /* the jump's LCP: a warm start, the set it solved at */
  long njump;               /* ... (written in turn; checkpointed: the pivots counted depend on it) */
  int one;                  /* the exosystem's constant state 1 (F reaches zeta through D), or -1 */
  int nwu;                  /* the input's own exosystem states (nw without the constant) */
  int seed_on;              /* a switched run's windows (adaptive_seed): the active set chosen at ... */
  uint64_t seed;            /* ... the last window's start is tried at the next one's before the LCP */
  int hold_end;             /* a switched run's windows (adaptive_hold_end): the sample at a window's end
                               before T waits for the next window, after the jump (the right limit) */
  int held_end;             /* ... one waited (adaptive_held) */
  int piece_ok;             /* built-in waveforms: piece_w holds the states on [piece_t0, piece_t1] */
  double piece_t0, piece_t1, *piece_w;   /* (a piece's start and its one step ask for the same: nwu) */
  int piece_from_t0;        /* ... states that are functions of t0 alone (sines, constants): any t1 */
  input_breaks nb_own;      /* ad_next_break's memo, the workspace's own ... */
  struct adaptive_breaks *nb;   /* ... or a switched run's (adaptive_share_breaks), NULL */
  double *wscale;           /* nw: the scale each state's value rounds at (a sine's amplitude, a
                               table's largest value; 0 for a slope: its own size) */
  double *gscale;           /* m: the scale of g's rounding, sum |G_iq| over the inputs' scales */
  double *N, *Ninv;         /* m x m: a mode's N = [Y^T D_JJ; Z^T C_J B_J], its inverse */
  double *svd_u, *svd_v, *svd_s, *svd_w;  /* SVD of D_JJ (m x m, m, m) */
  double *svd_memo;         /* AD_SVD_MEMO doubles: SVDs of D_JJ kept by its values (adaptive_split.c), */
  int svd_memo_used;        /* ... the doubles its entries fill (ad_dae_init's own allocation) */
  double *jM, *jq;          /* the jump LCP, 2m x 2m and 2m */
  lcp_solver jlcp;
  double *dq0, *dq1;        /* the choice of the active set: slack and its velocity at zeta = 0 */
  double *sz, *eqr, *eqc;   /* m: the manifold's residual Z^T s_J; N's equilibration */
  double *cg, *cd, *cd2, *cthr, *cy, *cMy;   /* a candidate's check: m values, slopes, curvatures,
                                                thresholds; na: y, M y */
  double *jx;               /* n: a jump, or a candidate's state on its manifold */
  double *Ry, *Ym, *Zc;     /* mode construction: B_J N^-1 on the Y rows (n x m), the Y rows' terms
                               ((m + 1) x na: the last row their constants), Z^T C_J (m x n) */
  cup_input gen;            /* built-in waveforms: u's terms that E or G reads (copies; adaptive.c,
                               live_terms), those the exosystem holds */
  int *first_state;         /* ... and the first exosystem state of each (in gen.terms' block), */
  input_gen_rot *gen_rot;   /* ... and the sines that share another's states (input_gen_rot_plan; likewise) */
  int gen_whole;            /* gen holds every term of u but its constants 0 (live_terms) */
  const cup_input *held;    /* &gen, or a callback's u: the breakpoints that end an exosystem piece
                               (adaptive_zeta's; a gate's corners move no state) */
  double *A, *E, *G;        /* dense, column-major: n x n, n x p, m x p */
  double *U, *W;            /* p x nw, nw x nw, column-major */
  int *up, *ui, *gp, *gi;   /* U's nonzeros by column (nw + 1 starts, rows), G's by row (m + 1 starts, columns) */
  double *ux, *gx;          /* ... their values (ad_offset) */
  int *gterm, ngterm;       /* built-in waveforms: the terms whose input has a column in G (at_break's
                               g = F + G u(t): a switch's gate source moves no row) */
  /* DC sources alone reach E and G (a converter's supply; its gates reach
   * neither): the exosystem's states, u and g are the same at every time,
   * made once at set-up by the sums each piece, step and breakpoint made
   * (a buck-boost's 200 windows computed them some 1,600 times) */
  int w_const;              /* every exosystem state is a constant: wc (nw), and u = U wc (uc, p) and
                               g = F + G uc (gc, m), ad_offset's for w = wc bit for bit */
  double *wc, *uc, *gc;
  int gbrk_const;           /* every term of gterm is a constant: at_break's g = F + G u(t) (gbrk) */
  double *gbrk;
  int gc_brk;               /* both, and gc = gbrk bit for bit: a piece's offset is its breakpoint's */
  double hmax_input;        /* an eighth of the fastest sine's period, at most T / 8 */
  double pinf;              /* ||v||_inf <= pinf ||v||_P */
  ad_mode modes[AD_MODES + 1];  /* the last: a spare, where a new one is built (ad_mode_get) */
  uint64_t alias_from[AD_ALIASES], alias_to[AD_ALIASES];   /* a set asked for, the subset it holds as */
  long nalias;
  uint64_t known[AD_KNOWN]; /* with D: row sets factored (ad_dae_factor), and whether N was singular */
  unsigned char known_singular[AD_KNOWN];
  long nknown;
  long clock;
  ad_mode *got;             /* the slot ad_mode_get answered last (looked at first: its mask and stamp
                               say whether it still holds that set) */
  ad_mode *got2;            /* ... and the one before it (looked at next) */
  const ad_mode *pinned[2]; /* in use by the run: never evicted */
  /* scratch of the mode construction */
  double *S, *Sl, *Sinv, *T1, *T2, *T3;
  int *perm;
  gsl_eigen_nonsymm_workspace *eig;
  gsl_matrix *eigA;
  gsl_vector_complex *eigv;
  /* scratch of the run */
  double *ework;            /* 7 na^2: exponentials (5 work, the scaled M, one out) */
  double *ya, *yb, *yt, *yr, *My, *fa, *fb;
  /* with D: a step that ended inside a piece with no event leaves its end
   * (yb, gb, tb, db) to the next step on carry_md from carry_t, which
   * starts there instead of lifting the state put on the manifold again
   * (at every step the same mode's flow of the same y: rounding apart, the
   * same point; the state x is put on the manifold at each step's end as
   * before); NULL: none */
  const struct ad_mode *carry_md;
  double carry_t;
  int carried;              /* steps in a row that started from a carried end (at most AD_CARRY) */
  /* a step that ended with no event leaves end_md (its mask end_mask) and
   * end_t: (gb, tb, db) are the event functions at yb on that mode, and a
   * step from end_t on it whose lifted start has yb's bits takes them
   * rather than evaluating them again (the same function of the same
   * y: a D = 0 mode with no manifold rows gives its own y back); NULL:
   * none */
  const struct ad_mode *end_md;
  uint64_t end_mask;
  double end_t;
  ad_series sy, se;         /* this step's flow from ya, and from (e, 0) (the error's), when asked */
  double *yhi;              /* an event's bracket: the flow at its right end (ad_event's hi_ok) */
  double *ga, *gb, *gt, *da, *db, *dt, *ta, *tb, *tt;   /* event values, slopes, thresholds: bracket ends, probe */
  double *cz, *cs;          /* per row, the late-switch error (docs/adaptive.md): pinf ||B_i||_P and
                               pinf ||A B_i||_P / (C B)_ii (pinf ||B_i||_P / D_ii where D_ii > 0) */
  double *c1;               /* per row: ||c_i||_1 */
  double *x, *xs, *xr, *xf, *s, *gam, *g, *ut, *udot, *uerr, *wa, *wt;
  double *gk;               /* m: the offset at_break found x inside K with (ad_run's kept) */
  int inside;               /* the last make_consistent found x inside, by the slack alone */
  double *e, *et;           /* the propagated error estimate, n */
  double *xok;              /* the last state within range (run-state check), n */
  double *zero;             /* m zeros */
  lcp_solver lcp;
  double *lcpM, *lcpq;
  unsigned char *touch;
  lcp_step proj;        /* W = I, h = 1: the certified P-projection onto K(t) */
  cup_projector *projector; /* ... and the projector where pivoting fails (degenerate rows, empty K) */
  /* callback inputs: Chebyshev-Lobatto nodes on [0, 1], samples, coefficients */
  double node[AD_DEGREE + 1], *samp, *samp_mid, *coef;
  double *zeno;              /* AD_ZENO_RING: times and rows of the last changes of the active set */
  int *zeno_row;            /* (with the stop record, ad_window_state's) */
  long nzeno;
  /* the multipliers at an output time (adaptive_zeta, inside the sink) */
  const ad_mode *zmd;       /* the active set that holds there (at x0's sample: the one chosen at 0+), */
  double zt;                /* or NULL (none chosen, catching-up steps) */
  double *zw, *zy;          /* nw, na */
  int zy_ready;             /* a sample inside a step: zy is its y already */
  int zx0;                  /* x0's sample: the sink has x0 as given, not A->x (adaptive_record declines) */
  double *xo, *dy, *de, *de2, *ed; /* n, 2 na, na, na, n: a sample inside a step (dense output), its error */
  int *erp, *erj;           /* na + 1, na * na: the sample spacing's exp(dt M) by rows, its nonzeros ... */
  double *erx;              /* na * na: ... and their values (adaptive_sample.c); er_n: 1 + the */
  int er_n;                 /* last row with a nonzero in one of the first n columns */
  int *xrp, *xrj;           /* n + m + 1, (n + m) na: the step's X and its zeta rows of L likewise ... */
  double *xrx;              /* (n + m) na: ... (rows_ready: made for the samples of this step) */
  int rows_ready;
  /* catchup-run's signals at a sample inside a step (adaptive_record): a
   * signal map composed with a mode's rows of x, u and zeta over y, sparse
   * by row, an entry per set of mode buffers (a mode's matrices move with
   * its buffers: X names them; the same rows in them, mask, are the same
   * matrices, a mode being built from its rows alone), allocated at the
   * first record (a switched run's configurations are made in the run too) */
  struct ad_rec {
    const double *X;        /* the mode's buffers, NULL: empty */
    uint64_t mask;          /* ... the mode they held, and the map's key, when composed */
    const void *key;
    int ok;                 /* 0: not composed (another map's sizes or input) */
    int *rp, *rj;           /* ns + 1, ns na */
    double *rx, *rc;        /* ns na, ns: the rows' nonzeros, their constants (zeta's Lc) */
    int nu, *uc;            /* the input components the map reads that y leaves out (a switch's
                               gate, a supply a configuration disconnects): nu of them, p room */
    double *ux;             /* ns x p: each row's coefficients on uc's components */
  } rec[AD_MODES + 1];
  int rec_ns;               /* the signals the entries have room for (0: none yet) */
  struct ad_rec *rec_last;  /* the last entry used */
  void *rec_block;
  double *rec_acc, *rec_u;  /* na: a row being composed; p: u(t) when an entry's nu > 0 */
  /* integrator_set_put (record.h): the samples inside a step with put_nl's
   * signals (put_ns of them) to put, AD_BATCH at a time, NULL: to the
   * sink; a batch's times, states, signals (by columns of AD_BATCH) and
   * estimates (bt, bx, bs, best) and its samples' y and error (by, be:
   * AD_BATCH + 1 of each, the next batch's first last), and with na <= 4
   * the signals' rows over y dense (bk, ns x na by rows, bkc their
   * constants), in one block (put_block) */
  record_put_fn put;
  cup_netlist *put_nl;
  int put_ns;
  void *put_block;
  double *bt, *bx, *bs, *best, *by, *be, *bk, *bkc;
  ad_stop *stop;            /* where the last run stopped (ad_window_state's) */
  double *tan;              /* the period map's tangent dx(t)/dx0 (n x n, column-major), or NULL:
                               carried through the error estimate's linear maps (adaptive.h) */
  /* a sample inside a step that the sink refused: the step goes on to its
   * end without offering more, and the run stops there (AD_STOP_DENSE);
   * the samples from it on are offered again by the resumed run, from the
   * same states (bit for bit): the refused one's y and error on mode md up
   * to t_end, then a second piece's (an event's new flow) from its start */
  struct ad_pend {
    int active, md, seg2, md2;
    long k;                 /* the step number the sink was given */
    double t_end, t2a, t2b;
    double *zy, *de, *y2, *e2;   /* na, na, na, n */
    /* output tol: the refused point's piece, chosen again from its start
     * (zy its y there, at ta, with the scales opk then), offered from tr on */
    double ta, tr, *opk;    /* opk: n */
    int with_t0;            /* ... its start is offered too (an event's new flow) */
    int with_yb;            /* ... its end's y is y2, the run's own (a step's, which has no second
                               piece), else its levels' */
    int taylor;             /* ... its middle by flow_taylor (adaptive_outtol.c's A->otaylor) */
  } pend;
  /* output tol (adaptive_outtol.c; allocated with CUP_OUTPUT_TOL alone):
   * each state's largest |x_i| over the points so far and its tolerance
   * (n, n), a piece's X M (n x na), and the points halving holds
   * (AD_TOL_DEPTH + 3 of t, x, x' and y: 1 + 2n + na each) */
  double *opeak, *othr, *oxm, *ostk;
  double *olev;             /* ... with na <= AD_TOL_LEVELS_NA, exp(2^-j h M) for a piece of length h
                               (AD_TOL_DEPTH + 2 of them, na x na column-major, as halving needs
                               them; then two to make them), or NULL: the piece's Taylor series */
  uint64_t olev_ok;         /* ... the levels j made (bit j) for the piece length olev_h on the mode
                               olev_md holding olev_mask (the X M of A->oxm too) */
  const struct ad_mode *olev_md;
  uint64_t olev_mask;
  double olev_h;
  int olev_base;            /* ... the level made by its series, the coarser by squaring (beyond
                               AD_TOL_DEPTH: none, the piece's series instead) */
  int oevent;               /* the run emits an event's pieces: not a step's, which ends on A->yb */
  int otaylor;              /* the piece's middle by its Taylor series when its slopes pass, not a level */
  /* integrator_set_put's, continued: a switched run's window, the map, a
   * step's end's rows (ad_put_row) */
  int put_off;              /* a switched run's window whose sink is not the user's (watch_sink): to the sink */
  const struct signal_map *put_map;   /* put_nl's map of this workspace's configuration (ad_put_map), NULL:
                                         not asked yet */
  double *rk, *rkc;         /* a step's end's signals' rows over y (ad_put_row, na <= 4: as bk and bkc) ... */
  const struct ad_rec *rk_rec;   /* ... of this entry (NULL: none; compose forgets it) */
};
#define AD_TOL_DEPTH 30     /* output tol: halvings of a step's piece at most (2^-30 of it) */
#define AD_TOL_LEVELS_NA 4  /* output tol: up to this na, a point is exp(2^-j h M) times its left end's y
                               (na^2 a point; a level's matrix na^3 a Taylor term, made when first
                               needed), beyond it the piece's series (ad_series_at) */

/* ---- adaptive.c: the run's messages ---- */
/* "step k (t = ...): " and the text into the run's message; ad_fail also
 * sets the status and returns it. */
void ad_say(ad_run *R, const char *fmt, va_list ap);
__attribute__((format(printf, 3, 4)))
int ad_fail(ad_run *R, int status, const char *fmt, ...);

/* ---- adaptive_record.c ---- */
/* Entry e's ns rows times y, each from its constant, in column order,
 * into out[k stride]: the signals that read no input outside y (e->nu 0,
 * else add them). */
static inline void ad_rec_rows(const struct ad_rec *e, int ns, const double *y, double *out, int stride) {
  const double *rx = e->rx, *rc = e->rc;
  const int *rp = e->rp, *rj = e->rj;
  for (int k = 0; k < ns; k++) {
    double acc = rc[k];
    for (int q = rp[k]; q < rp[k + 1]; q++) acc += rx[q] * y[rj[q]];
    out[(size_t)k * stride] = acc;
  }
}
/* md's entry composed for S (NULL: not composable); ad_rec_of looks at
 * the last one used first, inline (a call a record was 17 instructions,
 * 13 k on the full bridge's own steps). */
const struct ad_rec *ad_rec_entry(adaptive_ws *A, const ad_mode *md, const struct signal_map *S);
static inline const struct ad_rec *ad_rec_of(adaptive_ws *A, const ad_mode *md, const struct signal_map *S) {
  const struct ad_rec *e = A->rec_last;
  if (e && e->X == md->X && e->mask == md->mask && e->key == S->key && A->rec_ns == S->ns) return e->ok ? e : NULL;
  return ad_rec_entry(A, md, S);
}
/* The input components entry e reads that y leaves out (e->nu), at A->zt,
 * added to its ns signals in out: 1, or 0 when the input failed. */
int ad_rec_inputs(adaptive_ws *A, const struct ad_rec *e, int ns, double *out);
/* put_nl's signal map: the configuration in force at the first ask (a
 * switched run's workspace is one configuration's; set_put forgets it). */
const struct signal_map *ad_put_map_ask(adaptive_ws *A);
static inline const struct signal_map *ad_put_map(adaptive_ws *A) {
  return A->put_map ? A->put_map : ad_put_map_ask(A);
}

/* ---- adaptive_put.c ---- */
/* The sample at a step's end (offer_x: A->zt, A->zmd, state x = A->x)
 * with its signals to put, as the sink would compute them
 * (integrator_record's sums): 0 taken, 1 refused; -1 not here (the
 * signals not from y: the sink's). */
int ad_put_row(adaptive_ws *A, ad_run *R, const double *x);

/* ---- adaptive_sample.c ---- */
/* Output time j: t0 + j (T - t0) / (N - 1), T itself for the last. */
double ad_sample_time(const adaptive_ws *A, long j);
/* Where a step ending at t1 stops giving its dense samples: before a
 * switched run's window end (adaptive_hold_end), those within 8 ulps of
 * it are the end's, held for the next window (a .tran time and a gate's
 * edge, computed apart, round a few ulps apart). */
static inline double ad_dense_end(const adaptive_ws *A, double t1) {
  return A->hold_end && t1 == A->tend && t1 < A->o.T ? t1 - 8 * DBL_EPSILON * fabs(t1) : t1;
}
/* The samples due in [t0, t1) on md's flow from y = ya with error e0
 * (output samples; output tol's points), offered to the sink (a refusal
 * kept in A->pend: the step goes on, the run stops at its end); CUP_OK or
 * an error. The other outputs have none: no call. */
int ad_emit_out(adaptive_ws *A, ad_run *R, ad_mode *md, const double *ya, const double *e0, double t0,
                double t1);
static inline int ad_emit_dense(adaptive_ws *A, ad_run *R, ad_mode *md, const double *ya, const double *e0,
                                double t0, double t1) {
  int out = A->o.output;
  return out == CUP_OUTPUT_SAMPLES || out == CUP_OUTPUT_TOL ? ad_emit_out(A, R, md, ya, e0, t0, t1) : CUP_OK;
}
/* integrator_set_put's put of a batch's c points (A->bt, bx, bs; step
 * number k): how many it took, within [0, c], and the samples offered
 * counted (those taken, and a refused one); adaptive_sample.c's dense
 * samples and adaptive_outtol.c's points. */
static inline int ad_put_batch(adaptive_ws *A, ad_run *R, long k, int c) {
  int took = c ? A->put(R->sink_ctx, k, c, A->bt, A->bx, A->bs, AD_BATCH) : 0;
  if (took < 0) took = 0;
  if (took > c) took = c;
  R->info->samples += took < c ? took + 1 : c;
  return took;
}
/* The signals' rows of re over y into A->bk by rows, dense with their
 * zeros, and their constants into A->bkc (na <= 4: ad_batch_signals'). */
static inline void ad_dense_rows(const struct ad_rec *re, int ns, int na, double *K, double *kc) {
  memset(K, 0, sizeof(double) * (size_t)ns * (size_t)na);
  for (int k = 0; k < ns; k++) {
    kc[k] = re->rc[k];
    for (int q = re->rp[k]; q < re->rp[k + 1]; q++) K[(size_t)k * na + re->rj[q]] = re->rx[q];
  }
}
static inline void ad_signal_rows(adaptive_ws *A, const struct ad_rec *re, int ns) {
  ad_dense_rows(re, ns, A->na, A->bk, A->bkc);
}
/* The signals of a batch's first q samples (their y in by: A->by, na at
 * most 4 a constant here) into so (A->bs), by ad_signal_rows' rows (K, kc:
 * A->bk, A->bkc), each from its
 * constant, every term, zeros too: a zero's term is +-0 (y finite), which
 * leaves a sum begun at +0 or at a constant as it was, so these are
 * ad_rec_rows' sums bit for bit (dense samples, output tol's points). */
static inline __attribute__((always_inline)) void ad_batch_signals(int na, const double *restrict K,
                                                                   const double *restrict kc,
                                                                   const double *restrict by, double *restrict so,
                                                                   int ns, int q) {
  for (int k = 0; k < ns; k++, K += na) {        /* (a row's terms held across the samples) */
    double kr[4] = {0}, c0 = kc[k];
    for (int j = 0; j < na; j++) kr[j] = K[j];
    const double *restrict y = by;
    for (int s = 0; s < q; s++, y += na) {
      double acc = c0;
#pragma GCC unroll 4
      for (int j = 0; j < na; j++) acc += kr[j] * y[j];
      so[(size_t)k * AD_BATCH + s] = acc;
    }
  }
}
/* A sample refused inside the step in progress (on md, step number k, the
 * step ending at t1): A->pend active, no second piece yet; the caller
 * keeps the states to start again from. */
static inline struct ad_pend *ad_pend_start(adaptive_ws *A, const ad_mode *md, long k, double t1) {
  struct ad_pend *p = &A->pend;
  p->active = 1;
  p->seg2 = 0;
  p->md = (int)(md - A->modes);
  p->k = k;
  p->t_end = t1;
  return p;
}
/* A stop at a refused sample inside a step, resumed: that sample and the
 * rest of the step's; 1 if the sink refused one again. */
int ad_dense_resume(adaptive_ws *A, ad_run *R);

/* ---- adaptive_outtol.c ---- */
/* Output tol: the points inside [t0, t1) on md's flow from y = ya (and t0
 * itself when with_t0; yb: the flow's y at t1 when the caller has it, else
 * NULL), those before skip not offered (taylor: a refused piece's choice
 * of its middle, pend's, else -1); as ad_emit_dense:
 * a refusal kept in A->pend, 1; else 0 or an error. */
int ad_emit_tol(adaptive_ws *A, ad_run *R, ad_mode *md, const double *ya, const double *yb, double t0, double t1,
                long k, int with_t0, double skip, int taylor);
/* The input's exosystem states at t0 for a step to t1 into w (a callback's
 * interpolation error per component into err); nonzero if the input failed.
 * The same t0 and t1 as the last piece's (the workspace's own, or in a
 * switched run the last window's, adaptive_breaks) copy its states. */
int ad_inputs_varied(adaptive_ws *A, double t0, double t1, double *w, double *err);
/* (No input states, or DC sources alone, every piece's the same, inline:
 * the call was half of a full bridge's step's; the others, a waveform's
 * pieces and a callback's: ad_inputs_varied.) */
static inline int ad_inputs_on(adaptive_ws *A, double t0, double t1, double *w, double *err) {
  if (A->nwu && !A->w_const) return ad_inputs_varied(A, t0, t1, w, err);
  if (A->one >= 0) w[A->one] = 1;
  la_copy_few(w, A->wc, A->nwu);
  return CUP_OK;
}
/* A record at a step's end (A->zt, state A->x) on md's manifold: its y
 * into A->zy, the input's states from there on (adaptive_zeta's); nonzero
 * if the input failed. */
int ad_record_y(adaptive_ws *A, const ad_mode *md);
/* cup_input_next_break(A->u, t), the last answer again when t is the same. */
double ad_next_break(adaptive_ws *A, double t);

/* ---- adaptive_mode.c ---- */
/* The active set with rows `mask` (built, or found among the kept ones). A
 * set whose rows are linearly dependent keeps an independent subset (the
 * mode's mask says which). Allocates nothing: the slots are taken at the
 * run's start (ad_modes_take). */
ad_mode *ad_mode_get_other(adaptive_ws *A, uint64_t mask);
/* (The set the last ask answered, inline: a window asks for the set the
 * last one ran on; the others, the one before and the slots' search, in
 * ad_mode_get_other.) */
static inline ad_mode *ad_mode_get(adaptive_ws *A, uint64_t mask) {
  ad_mode *md = A->got;
  if (md && md->stamp && md->mask == mask) { md->stamp = ++A->clock; return md; }
  return ad_mode_get_other(A, mask);
}
/* The slots' matrices from b, not zeroed: a slot's arrays are written
 * whole when a set is built in it, mode_factor and mode_finish, before
 * they are read; its exponentials by their lengths, md->hc. A switched
 * run's configuration (made in the run) has them in its one block
 * (adaptive.c's); a workspace of its own takes them at its first run's or
 * window's start, an allocation of their own (ad_modes_take: not at
 * set-up, before a program makes its output file, whose library's freed
 * buffers the run's memory then reuses, pages already touched). CUP_OK
 * (taken already too) or CUP_ERR_NOMEM. The series' small vectors and the
 * construction's scratch (zeroed) by ad_scratch_layout; series S's
 * coefficients by ad_series_layout, not zeroed. */
void ad_modes_layout(adaptive_ws *A, block_arena *b);
int ad_modes_take(adaptive_ws *A);
void ad_scratch_layout(adaptive_ws *A, block_arena *b);
void ad_series_layout(adaptive_ws *A, ad_series *S, block_arena *b);
/* The eigenvalue workspace (gsl's own allocations). */
int ad_modes_init(adaptive_ws *A);
void ad_modes_free(adaptive_ws *A);
/* A checkpoint's kept active set in slot s: its rows (mask), built again
 * (the slots taken first, ad_modes_take; without memory A->slots_lost),
 * its exponentials for the step lengths hc (< 0: none) computed again (the
 * same bits: the same function of the same h M) and its stamps of use. */
void ad_mode_restore(adaptive_ws *A, int s, uint64_t mask, long stamp, const double *hc, const long *cstamp);
/* exp(h M_J), cached by h (NULL: h = 0 needs none): a step's length h
 * ending at t (t_end) takes a cached one within two ulps of t of it
 * (adaptive_mode.c); t_end = 0 takes only h itself (the samples' spacing,
 * applied sample after sample). */
const double *ad_expm_miss(adaptive_ws *A, ad_mode *md, double h);
/* The cached exponential that ad_expm would take, or NULL (nothing
 * computed), inline. A step's length is the difference of two times, each
 * rounded to half an ulp of itself: lengths that differ by two ulps of the
 * step's end t are
 * the same length to the rounding of the times, and take the same
 * exponential. (A gate's windows k PER + PW .. (k+1) PER differ by ulps
 * of t, hundreds of ulps of h, and each took its own exponential: 7 % of
 * the buck's time loop.) The state moves by |x'| 2 eps |t| at most, what
 * rounding t itself does. The samples' spacing is applied sample after
 * sample, where such differences would add up: it takes only itself. */
static inline const double *ad_expm_cached(adaptive_ws *A, ad_mode *md, double h, double t_end) {
  double same = 2 * DBL_EPSILON * fabs(t_end);
  for (int c = 0; c < AD_CACHE; c++)
    if (fabs(md->hc[c] - h) <= same) { md->cstamp[c] = ++A->clock; return md->Ec[c]; }
  return NULL;
}
/* (The cache's look-up inline: its call and register saves were half of a
 * full bridge's hmax step's look-up; a miss computes the exponential into
 * the least recently used slot: ad_expm_miss.) */
static inline const double *ad_expm(adaptive_ws *A, ad_mode *md, double h, double t_end) {
  const double *E = ad_expm_cached(A, md, h, t_end);
  return E ? E : ad_expm_miss(A, md, h);
}
/* out = E y for E = exp(h M_J) that ad_expm returned for md (ad_matvec's
 * sums over E's nonzeros: the same bits). */
void ad_expm_mv(const adaptive_ws *A, const ad_mode *md, const double *E, const double *y, double *out);
/* out = M_J y over M's nonzeros (the dense product's sums, bit for bit). */
void ad_mode_mv(const adaptive_ws *A, const ad_mode *md, const double *y, double *out);
/* ... with na <= 4 by M's dense columns in registers, unrolled (the zeros'
 * terms are +-0, which leave a sum started at +0 as it was: the same sums)
 * by ad_mode_mv_few: 1, else 0 (nothing done). */
static inline __attribute__((always_inline)) void ad_mode_mv_dense(int na, const double *M, const double *y,
                                                                   double *out) {
  double v[4] = {0};
  for (int j = 0; j < na; j++) {
    double yj = y[j];
    for (int i = 0; i < na; i++) v[i] += M[i + (size_t)j * na] * yj;
  }
  for (int i = 0; i < na; i++) out[i] = v[i];
}
static inline __attribute__((always_inline)) int ad_mode_mv_few(int na, const double *M, const double *y,
                                                                double *out) {
  switch (na) {
    case 1: ad_mode_mv_dense(1, M, y, out); return 1;
    case 2: ad_mode_mv_dense(2, M, y, out); return 1;
    case 3: ad_mode_mv_dense(3, M, y, out); return 1;
    case 4: ad_mode_mv_dense(4, M, y, out); return 1;
  }
  return 0;
}
/* out = E y for E the n x n head of a column-major matrix with leading
 * dimension lda (the terms of a y_j = 0 left out: +-0 each, they leave a
 * sum started at +0 as it was). */
void ad_matvec(int n, int lda, const double *E, const double *y, double *out);
/* Its sums for a constant n, each out_i's in a register (inline). */
static inline __attribute__((always_inline)) void ad_matvec_sums(int n, int lda, const double *E, const double *y,
                                                                 double *out) {
  double v[8] = {0};
  for (int j = 0; j < n; j++) {
    double yj = y[j];
    if (yj == 0) continue;
    for (int i = 0; i < n; i++) v[i] += E[i + (size_t)j * lda] * yj;
  }
  for (int i = 0; i < n; i++) out[i] = v[i];
}
/* ad_matvec inline for n <= 4 (a converter's states: a step's error
 * product, whose call and register saves were two thirds of it). */
static inline __attribute__((always_inline)) void ad_matvec_few(int n, int lda, const double *E, const double *y,
                                                                double *out) {
  switch (n) {
    case 1: ad_matvec_sums(1, lda, E, y, out); return;
    case 2: ad_matvec_sums(2, lda, E, y, out); return;
    case 3: ad_matvec_sums(3, lda, E, y, out); return;
    case 4: ad_matvec_sums(4, lda, E, y, out); return;
  }
  ad_matvec(n, lda, E, y, out);
}
/* y_out = exp(tau M_J) y_in (a short tau by a vector Taylor series). */
void ad_flow(adaptive_ws *A, ad_mode *md, double tau, const double *y_in, double *y_out);
/* y_out = exp(tau M_J) y0 for 0 <= tau <= h, y0 the step's start vector
 * that S stands for: by S's series (built on the first call in a step: S->md
 * = NULL; the caller resets it; its first S->dim components), or ad_flow
 * when h snorm > AD_SERIES_SEGS. */
void ad_series_at(adaptive_ws *A, ad_series *S, ad_mode *md, double h, const double *y0, double tau,
                  double *y_out);
/* y = (x + K_J U w, w) and back: x = X_J y. */
void ad_lift(const adaptive_ws *A, const ad_mode *md, const double *x, const double *w, double *y);
/* ad_lift's sums: v = x + K_J U w into y (n), each v_i's sum in a register
 * for a constant n (at most 6), the zero w_c's terms left out. */
static inline __attribute__((always_inline)) void ad_lift_sums(int n, int nw, const double *KU, const double *x,
                                                               const double *w, double *y) {
  double v[6];
  for (int i = 0; i < n; i++) v[i] = x[i];
  for (int c = 0; c < nw; c++) {
    double wc = w[c];
    if (wc == 0) continue;
    for (int i = 0; i < n; i++) v[i] += KU[i + (size_t)c * n] * wc;
  }
  for (int i = 0; i < n; i++) y[i] = v[i];
}
void ad_state(const adaptive_ws *A, const ad_mode *md, const double *y, double *x);
/* x onto C_J x + g_J = 0 along B_J (P-orthogonal): removes rounding drift. */
void ad_manifold(const adaptive_ws *A, const ad_mode *md, const double *g, double *x);
/* The active set that continues from (x, t): the velocity LCP on the rows
 * that touch (slack at rounding level, or in hint: rows held until now,
 * active in a projection just made, or whose event it is), given u = U w
 * and u' = U W w. Returns CUP_OK or CUP_ERR_LINALG; pivots are added to
 * *pivots. */
int ad_select(adaptive_ws *A, const double *x, const double *w, uint64_t hint, uint64_t *mask,
              int *pivots);
/* ... with g = F + G U w in A->g and u in A->ut already (ad_offset's). */
int ad_select_at(adaptive_ws *A, const double *x, const double *w, uint64_t hint, uint64_t *mask,
                 int *pivots);
/* ... and the slack C x + g in A->s too (make_consistent's, x unmoved since). */
int ad_select_slack(adaptive_ws *A, const double *x, const double *w, uint64_t hint, uint64_t *mask,
                    int *pivots);
/* g = F + G U w (u = U w into A->ut). */
void ad_offset(const adaptive_ws *A, const double *w, double *g);
/* g = F + G u, by G's nonzeros. */
void ad_offset_of(const adaptive_ws *A, const double *u, double *g);
/* 1 if a and b hold the same n doubles, bit for bit. */
static inline int ad_same_bits(const double *a, const double *b, int n) {
  for (int k = 0; k < n; k++) {
    uint64_t x, y;
    memcpy(&x, a + k, sizeof x);
    memcpy(&y, b + k, sizeof y);
    if (x != y) return 0;
  }
  return 1;
}
/* u' (A->udot, from the input's piece w) and the free velocity
 * A->xf = A x + E u (u in A->ut). */
void ad_free_velocity(adaptive_ws *A, const double *x, const double *w);

/* pinf ||v||_P: a bound on the max norm of v, and of what the flow makes of
 * it when the LCS is passive (its flow does not expand the P-norm): the
 * measure of an event's local error, whose effect a resonance carries from
 * one component to another (scratch: n). */
double ad_energy_bound(const adaptive_ws *A, const double *v, double *scratch);
/* The step limit of event detection of md (computed on first use, by
 * ad_mode_hmax_first; inline: a call a step was some 50 instructions of a
 * buck-boost's window). */
double ad_mode_hmax_first(adaptive_ws *A, ad_mode *md);
static inline double ad_mode_hmax(adaptive_ws *A, ad_mode *md) {
  return md->hmax >= 0 ? md->hmax : ad_mode_hmax_first(A, md);
}
/* Row i of C, dense, into out (n entries). */
void ad_row_of_C(const cup_polyset *K, int i, double *out);

/* ---- adaptive_split.c (D != 0) ---- */
/* Of the rows J (nj, in increasing order), a subset whose N is nonsingular
 * (all of them when it is): returns the new count and writes Zt (nz x nj),
 * nz, and A->Ninv (nj x nj, column-major: N's rows are Y's then Z's).
 * With pending non-NULL, a subset whose factors the tries did not leave
 * in the buffers is not factored again: *pending = 1 says so, and
 * ad_dae_refactor does it when the caller needs them. */
int ad_dae_factor(adaptive_ws *A, int *rows, int nj, double *Zt, int *nz, int *pending);
void ad_dae_refactor(adaptive_ws *A, const int *rows, int nj, double *Zt, int *nz);

/* ---- adaptive_dae.c (D != 0) ---- */
int ad_dae_init(adaptive_ws *A);
void ad_dae_free(adaptive_ws *A);
/* The active set that continues from (x, w) at a time: the mode cur with
 * the event row flipped (with no event, cur itself) when that fits, else
 * seed when nonzero and it fits, else the finite-h LCP with D
 * (docs/adaptive.md), each candidate checked on the mode's own flow, x
 * on its manifold to rounding or (near > 0: an event's located state)
 * within near of it in the P-norm.
 * Leaves F + G u(w) in A->g (ad_offset; u in A->ut). CUP_OK, or
 * CUP_ERR_LINALG when no candidate continues (or the LCP has no
 * solution). */
int ad_dae_select(adaptive_ws *A, const double *x, const double *w, uint64_t cur, int row, uint64_t hint,
                  uint64_t seed, double tscale, double near, uint64_t *mask, int *pivots);
/* ... with A->g and A->ut holding w's already (a piece's start, start_piece). */
int ad_dae_select_at(adaptive_ws *A, const double *x, const double *w, uint64_t cur, int row, uint64_t hint,
                     uint64_t seed, double tscale, double near, uint64_t *mask, int *pivots);
/* x onto the consistent states Q(t) = {x : C x + D zeta + g >= 0 for some
 * zeta >= 0} by the impulsive LCP (x + B mu; the P-projection when
 * P B = C^T), for an x outside K(t) whose slack C x + g is in A->dq0
 * (make_consistent's check): 0 if x was consistent, 1 if it jumped (rows
 * with mu > 0 in *active), CUP_ERR_LINALG if the LCP has no solution. */
int ad_dae_jump(adaptive_ws *A, double *x, uint64_t *active, int *pivots);

/* ---- adaptive_event.c ---- */
/* g = L y + Lc and the rounding thresholds thr. */
void ad_events_eval(const adaptive_ws *A, const ad_mode *md, const double *y, double *g, double *thr);
/* Row i's rounding threshold from mag, the magnitudes' sum |Lc_i| + sum
 * |L_ij y_j|, and vmax, the state's scale |x|_inf: a few ulps of the terms
 * summed, and a slack of the state's scale, to which the held rows are
 * kept (a row that depends on them sits at zero with that rounding). One
 * formula for ad_events_eval, ad_events_both's and the window start's
 * check (adaptive_dae.c's mode_fits). */
static inline double ad_row_rounding(const adaptive_ws *A, const ad_mode *md, int i, double mag, double vmax) {
  return 64 * DBL_EPSILON * (mag + (md->is_zeta[i] ? 0 : A->c1[i] * vmax));
}
/* d = L M y (the event functions' time derivatives). */
void ad_events_deriv(adaptive_ws *A, const ad_mode *md, const double *y, double *d);
/* Both, the same bits (na > 4: M y in A->My, as ad_events_deriv leaves
 * it; na <= 4: M y's components where a row reads them, A->My not
 * written), but thr only where g < 0 (or the state is not finite), 0
 * elsewhere: a value >= 0 crosses nothing, whatever its threshold. */
void ad_events_both(adaptive_ws *A, const ad_mode *md, const double *y, double *g, double *thr, double *d);
/* Every row's threshold at y, as ad_events_eval's (a checkpoint's). */
void ad_events_thresholds(const adaptive_ws *A, const ad_mode *md, const double *y, double *thr);

typedef struct ad_event {
  double t0;                /* the step's start time (for rounding floors) */
  double h;                 /* the step's length (the flow's series: A->sy) */
  double tau_lo, tau_sw;    /* the bracket from the step start: no crossing at tau_lo, one at tau_sw */
  double tau_est;           /* best estimate of the root */
  double cfac;              /* multiplies the late-switch error model (1; more after an underestimate) */
  double cmin;              /* a floor under the model's c: 2 err / delay^2 measured (0 at first) */
  int row;                  /* the row whose function crosses first */
  int evals;                /* flow evaluations spent */
  int hi_ok;                /* A->yhi holds the flow from the step's start to tau_sw (a probe's) */
} ad_event;
/* After a step of length h from ya (values ga, slopes da, thresholds ta at
 * the start; gb, db, tb at the end; take_step asks where ad_detect_may
 * says one can): 1 if an event function crosses zero downwards (an
 * interior dip below zero included), with the bracket (tau_lo, tau_sw] and
 * the values at its ends in ga.. and gb..; 0 if none. */
int ad_detect(adaptive_ws *A, ad_mode *md, double h, ad_event *ev);
/* Whether ad_detect can find anything (inline: the common step's test, a
 * row at a time): a crossing needs gb < 0 (gb < -tb, tb >= 0), a dip da <
 * 0 < db; with neither, none of its tests can fire. (Out of line with the
 * event's set-up, the call and the set-up were 40 % of the test a full
 * bridge's step.) */
static inline int ad_detect_may(const adaptive_ws *A) {
  const double *gb = A->gb, *da = A->da, *db = A->db;
  int m = A->m, i = 0;
  while (i < m && !(gb[i] < 0) && !(da[i] < 0 && db[i] > 0)) i++;
  return i < m;
}
/* Shrink the bracket around the earliest crossing until the switch at its
 * right end, tau_sw, lies past the root by no more than the time accuracy
 * at which the late switch's effect on x, second order in that delay
 * (docs/adaptive.md), is a fixed fraction of tolw (the absolute error
 * target at this state). tau_est: the root, refined by Newton steps on the
 * exact flow. */
void ad_locate(adaptive_ws *A, ad_mode *md, double tolw, ad_event *ev);
/* The late-switch error model's fraction of tol per event. */
#define AD_EVENT_SHARE 0.4

#endif

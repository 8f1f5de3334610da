/* adaptive_sample — the adaptive scheme's samples and input on a step
 * (adaptive_impl.h, docs/adaptive.md): the output times' states from the
 * exact flow inside a step (dense output: no step ends at a sample), one
 * the sink refused kept for a resumed run, the multipliers at a sample,
 * and the input's exosystem states on a step (a callback's by
 * interpolation). Allocates nothing. */
#include <float.h>
#include <math.h>
#include <string.h>
#include "catchup.h"
#include "adaptive.h"
#include "adaptive_impl.h"
#include "tally.h"
#include "model/signal_map.h"

double ad_sample_time(const adaptive_ws *A, long j) {
  long last = A->o.output_samples - 1;
  double t0 = A->o.output_t0;
  return j >= last ? A->o.T : t0 + (A->o.T - t0) * (double)j / (double)last;
}

/* E by rows, its nonzeros alone, each row's in column order (A->erp,
 * erj, erx). Most of a sample's exp(dt M) is zero: the inputs' states
 * move among themselves (the lower left block, n columns of the last
 * na - n rows, was exactly 0 on every converter), a sine's by a 2 x 2
 * rotation. Nothing relies on it: a zero is left out wherever it is. */
static void by_rows(adaptive_ws *A, const double *E) {
  int na = A->na, nz = 0;
  A->er_n = 0;
  for (int i = 0; i < na; i++) {
    A->erp[i] = nz;
    for (int j = 0; j < na; j++) {
      double v = E[i + (size_t)j * na];
      if (v != 0) { A->erj[nz] = j; A->erx[nz++] = v; }
    }
    if (nz > A->erp[i] && A->erj[A->erp[i]] < A->n) A->er_n = i + 1;
  }
  A->erp[na] = nz;
}

/* The step's x = X y and zeta rows of L (md) by rows likewise (A->xrp,
 * xrj, xrx: X's n rows, then L's m, those not zeta empty): a sample's
 * state and multipliers are sums over them from +0 in column order, as
 * la_dot's, bit for bit (the argument of times, below). */
static void rows_of(adaptive_ws *A, const ad_mode *md) {
  int n = A->n, m = A->m, na = A->na, nz = 0;
  for (int i = 0; i < n + m; i++) {
    A->xrp[i] = nz;
    const double *r = i < n ? md->X + (size_t)i * na : md->L + (size_t)(i - n) * na;
    if (i >= n && !md->is_zeta[i - n]) continue;
    for (int j = 0; j < na; j++)
      if (r[j] != 0) { A->xrj[nz] = j; A->xrx[nz++] = r[j]; }
  }
  A->xrp[n + m] = nz;
  A->rows_ready = 1;
}

/* Row i of rows_of's times y. */
static double row_times(const adaptive_ws *A, int i, const double *y) {
  double acc = 0;
  for (int k = A->xrp[i]; k < A->xrp[i + 1]; k++) acc += A->xrx[k] * y[A->xrj[k]];
  return acc;
}

typedef struct {                                 /* by_rows' product, read once for a run of them */
  const int *rp, *rj;
  const double *rx;
  int na, n, er_n;
} e_rows;

static e_rows rows_e_of(const adaptive_ws *A) {
  return (e_rows){.rp = A->erp, .rj = A->erj, .rx = A->erx, .na = A->na, .n = A->n, .er_n = A->er_n};
}

/* The next sample's y and error, E y and E e into yo and eo, in one
 * pass over by_rows' nonzeros; the columns of e's trailing zeros (its
 * inputs' part) left out of E e (*nc: 1 + e's last nonzero, or -1 not
 * known yet; then the new e's). Each row summed from 0 in column order,
 * as the dense product's, bit for bit: a term left out is +-0 (E finite),
 * and a sum begun at +0 is never -0, so adding +-0 changed nothing.
 * The rows after by_rows' er_n (the inputs' states, when the error's
 * nonzeros are in the first n columns, as they are) get E y alone and
 * e_i = +0, what their sums of no term gave. (Dense, these products were
 * 60 % of a sample's instructions on the six-pulse rectifier's grid.) */
static inline __attribute__((always_inline)) int times_by(const e_rows *E, const double *y, const double *e,
                                                          double *yo, double *eo, int nc) {
  int na = E->na, last = -1;
  if (nc < 0)
    for (nc = na; nc > 0 && e[nc - 1] == 0;) nc--;
  const int *rp = E->rp, *rj = E->rj;
  const double *rx = E->rx;
  int rows_e = nc <= E->n ? E->er_n : na, i = 0;   /* the rows after have no column < nc: e_i = +0 */
  for (; i < rows_e; i++) {
    double a = 0, b = 0;
    int k = rp[i], end = rp[i + 1];
    for (; k < end && rj[k] < nc; k++) {
      a += rx[k] * y[rj[k]];
      b += rx[k] * e[rj[k]];
    }
    for (; k < end; k++) a += rx[k] * y[rj[k]];
    yo[i] = a;
    eo[i] = b;
    if (b != 0) last = i;
  }
  for (; i < na; i++) {                          /* (an input's states: rows of 1 or 2 terms, a sine's rotation) */
    int k = rp[i], len = rp[i + 1] - k;
    const int *j = rj + k;
    const double *c = rx + k;
    double a;
    if (len == 2) a = (0 + c[0] * y[j[0]]) + c[1] * y[j[1]];
    else if (len == 1) a = 0 + c[0] * y[j[0]];
    else {
      a = 0;
      for (int q = 0; q < len; q++) a += c[q] * y[j[q]];
    }
    yo[i] = a;
    eo[i] = 0;
  }
  return last + 1;
}

static inline __attribute__((always_inline)) void times(const adaptive_ws *A, const double *y, const double *e,
                                                       double *yo, double *eo, int *ncp) {
  e_rows E = rows_e_of(A);
  *ncp = times_by(&E, y, e, yo, eo, *ncp);
}

/* times by E itself (column-major, na x na; na a constant here, the
 * loops unrolled): every term, zeros too, each sum from +0 in column
 * order. A zero's term is +-0 (E, y and e finite), which leaves a sum
 * begun at +0 as it was, and E e's terms of e's trailing zeros (from
 * column nc on) are +-0 too, so these are times_by's sums bit for bit,
 * without an index a term: its rows from er_n on (no nonzero below
 * column n) get +0 here too. E e takes e's first ce columns (a constant
 * too: 1 when e's nonzeros are in its first, as a converter's one state
 * has it, E e's other terms being +-0 then) in its first re rows (re 1:
 * with ce 1 and E's first column 0 below its first row, the others are
 * 0 + (+-0) = +0). Returns times_by's nc. */
static inline __attribute__((always_inline)) int times_dense(int na, int ce, int re, const double *E,
                                                             const double *y, const double *e, double *yo,
                                                             double *eo) {
  int last = -1;
#pragma GCC unroll 4
  for (int i = 0; i < na; i++) {
    double a = 0, b = 0;
#pragma GCC unroll 4
    for (int j = 0; j < na; j++) a += E[i + j * na] * y[j];
    if (i < re)
#pragma GCC unroll 4
      for (int j = 0; j < ce; j++) b += E[i + j * na] * e[j];
    yo[i] = a;
    eo[i] = b;
    if (i < re && b != 0) last = i;
  }
  return last + 1;
}

#define TIMES_DENSE(NA)                                                                        \
  {                                                                                                \
    double Ev[NA * NA];                          /* (E's own copy: in registers, not read again a sample) */ \
    memcpy(Ev, E, sizeof Ev);                                                                      \
    int low0 = 1;                                /* (E's first column 0 below its first row) */    \
    for (int i = 1; i < NA; i++) low0 &= Ev[i] == 0;                                               \
    for (int s = 0; s < count; s++, y += NA, e += NA)                                              \
      nc = nc == 0 || nc == 1 ? (low0 ? times_dense(NA, 1, 1, Ev, y, e, y + NA, e + NA)             \
                                      : times_dense(NA, 1, NA, Ev, y, e, y + NA, e + NA))           \
                              : times_dense(NA, NA, NA, Ev, y, e, y + NA, e + NA);                  \
  }                                                                                                \
  break

/* times from slot 0 of y and e (na each) into slots 1 to count: E (the
 * matrix by_rows took) dense up to 4 states with the inputs' (at most 16
 * terms a row, unrolled: by_rows' lists cost an index and a loop a term,
 * 125 instructions a sample on the precision rectifier's 3), else by_rows'
 * arrays, read once. */
static void times_run(const adaptive_ws *A, const double *E, double *y, double *e, int count, int *ncp) {
  int na = A->na, nc = *ncp;
  if (count <= 0) return;                        /* (E not made: NULL) */
  switch (na) {
    case 1: TIMES_DENSE(1);
    case 2: TIMES_DENSE(2);
    case 3: TIMES_DENSE(3);
    case 4: TIMES_DENSE(4);
    default: {
      e_rows R = rows_e_of(A);
      for (int s = 0; s < count; s++, y += na, e += na) nc = times_by(&R, y, e, y + na, e + na, nc);
    }
  }
  *ncp = nc;
}
#undef TIMES_DENSE

/* A sample's state xo at ts beyond its range (tally.h): the run stops. */
static int diverged(ad_run *R, double ts, const double *xo, int n) {
  int w = tally_state_worst(xo, n);
  return ad_fail(R, CUP_ERR_DIVERGED, "the state left its range ||x||_1 <= %g at t = %.17g (x[%d] = %.3g): "
                 "the scheme diverged", CUP_STATE_MAX, ts, w, xo[w]);
}

/* A sample refused by the sink inside the step in progress: its states
 * (A->zy, A->de) kept in A->pend, the step going on to its end where the
 * run stops. Returns 1. */
static int pend_refused(adaptive_ws *A, const ad_mode *md, long k, double t1) {
  struct ad_pend *p = ad_pend_start(A, md, k, t1);
  la_copy(p->zy, A->zy, A->na);
  la_copy(p->de, A->de, A->na);
  return 1;
}

/* The samples due before t1 on the flow of md, the first of them (sample
 * R->next_sample) in A->zy with its error in A->de; each next one by the
 * cached exp(dt M) of the output spacing dt (one product a sample: asking
 * 10^5 samples adds no steps). The sink is given step number k. A refused
 * sample leaves its states in A->pend (the step goes on to its end, where
 * the run stops): 1; else 0, or an error. A->zy and A->de point to the
 * sample's states, which times writes into the other pair of A->dy's
 * halves and those (no copy a sample); dense_from puts them back. What
 * the loop does not change is read once before it (the sink, its context,
 * the run's counts: the sink may write anywhere, so each was read again
 * at every sample); A->zmd and zy_ready (adaptive_zeta) are set by
 * dense_loop around it. */
static int dense_samples(adaptive_ws *A, ad_run *R, ad_mode *md, double t1, long k) {
  const cup_integrator_options *o = &A->o;
  int n = A->n, na = A->na;
  long nsamples = o->output_samples;
  double dt = (o->T - o->output_t0) / (double)(o->output_samples - 1);
  double rnd = R->rloc + sqrt(R->r2);            /* (fixed inside the step) */
  const double *E = NULL;                        /* exp(dt M), looked up at the second sample */
  double ts = ad_sample_time(A, R->next_sample);
  double *yn = A->dy, *en = A->dy + na;          /* the next sample's */
  double *xo = A->xo;
  int nc = -1;                                   /* (times) */
  cup_sample_fn sink = R->sink;
  void *ctx = R->sink_ctx;
  long *samples = &R->info->samples;
  A->rows_ready = 0;
  for (;;) {
    R->next_sample++;
    double est = la_norm_inf(A->de, n) + rnd;
    if (!(est <= R->est_max)) R->est_max = fmax(R->est_max, est);   /* (the call only when it moves) */
    if (sink) {
      if (!A->rows_ready) ad_state(A, md, A->zy, xo);
      else for (int i = 0; i < n; i++) xo[i] = row_times(A, i, A->zy);
      if (tally_state_beyond(xo, n)) return diverged(R, ts, xo, n);   /* as step_done: never a state out of range */
      ++*samples;
      A->zt = ts;
      if (sink(k, ts, xo, ctx)) {                   /* inside the step in progress: refused */
        R->next_sample--;
        return pend_refused(A, md, k, t1);
      }
    }
    if (!(R->next_sample < nsamples)) return 0;
    ts = ad_sample_time(A, R->next_sample);
    if (!(ts < t1)) return 0;
    if (!E) {
      E = ad_expm(A, md, dt, 0);   /* (applied sample after sample: dt itself) */
      by_rows(A, E);
      rows_of(A, md);
    }
    times(A, A->zy, A->de, yn, en, &nc);
    double *y = A->zy, *e = A->de;
    A->zy = yn;
    A->de = en;
    yn = y;
    en = e;
  }
}

/* A batch of put's (integrator_set_put): the c samples from
 * R->next_sample on, their states y and errors in A->by and A->be, the
 * rest in A->bt, bx, bs and best. What dense_samples' sink calls do, as
 * the sink would have been called: the estimate and count of each sample
 * offered, R->next_sample after those taken, A->zy and A->de the last
 * offered one's, and a refused one kept in A->pend (1; else 0). */
static int batch_put(adaptive_ws *A, ad_run *R, ad_mode *md, double t1, long k, int c) {
  int na = A->na, took = ad_put_batch(A, R, k, c);
  int offered = took < c ? took + 1 : c;
  for (int i = 0; i < offered; i++)
    if (!(A->best[i] <= R->est_max)) R->est_max = fmax(R->est_max, A->best[i]);
  R->next_sample += took;
  if (!offered) return 0;
  la_copy(A->zy, A->by + (size_t)(offered - 1) * na, na);
  la_copy(A->de, A->be + (size_t)(offered - 1) * na, na);
  A->zt = A->bt[offered - 1];
  if (took == c) return 0;
  return pend_refused(A, md, k, t1);             /* inside the step in progress: refused */
}

/* A batch's c samples from slot 0, na (at most 4) a constant here: each
 * one's estimate, state x = X y (md's rows, la_dot's sums as ad_state's)
 * and signals (ad_signal_rows', each from its constant), every term, zeros
 * too, unrolled. A zero's term is +-0 (y finite, as times_dense has it),
 * which leaves a sum begun at +0 or at a constant as it was (a constant
 * is never -0: compose's sums begin at +0), so these are the sums of
 * row_times and ad_rec_rows over the nonzeros bit for bit. Returns the
 * first sample whose state is beyond range (its signals not made), else
 * c. (Sample by sample through each row's list, x and the 3 signals
 * over y's 3 took 236 k instructions of the precision rectifier's 3001
 * samples; so, about 130 k.) */
static inline __attribute__((always_inline)) int samples_dense(int na, adaptive_ws *A, const double *X, int ns,
                                                               int c, double rnd) {
  int n = A->n;
  const double *restrict y = A->by, *restrict e = A->be, *restrict K = A->bk, *restrict kc = A->bkc;
  double *restrict xo = A->bx, *restrict so = A->bs, *restrict best = A->best;
  int q = 0;
  for (; q < c; q++, y += na, e += na, xo += n) {
    best[q] = la_norm_inf(e, n) + rnd;
    for (int i = 0; i < n; i++) xo[i] = la_dot(X + (size_t)i * na, y, na);
    if (tally_state_beyond(xo, n)) break;
  }
  ad_batch_signals(na, K, kc, A->by, so, ns, q);
  return q;
}

/* samples_dense by rows_of's and re's lists (any na), the first sample
 * of a step (first) by ad_state. */
static int samples_rows(adaptive_ws *A, const ad_mode *md, const struct ad_rec *re, int ns, int c, double rnd,
                        int first) {
  int n = A->n, na = A->na;
  for (int q = 0; q < c; q++) {
    const double *y = A->by + (size_t)q * na;
    double *xo = A->bx + (size_t)q * n;
    A->best[q] = la_norm_inf(A->be + (size_t)q * na, n) + rnd;
    if (first && q == 0) ad_state(A, md, y, xo);
    else for (int i = 0; i < n; i++) xo[i] = row_times(A, i, y);
    if (tally_state_beyond(xo, n)) return q;
    ad_rec_rows(re, ns, y, A->bs + q, AD_BATCH);
  }
  return c;
}

/* dense_samples with put for the sink, a batch at a time: the batch's
 * times (up to AD_BATCH, those before t1), their y and errors (slots of
 * A->by and A->be, from slot 0 by times_run: and slot c, the next batch's
 * first), then each one's estimate, state and signals (the composed rows
 * re of S, no input outside y: samples_dense, or samples_rows), and the
 * batch to put. The same sums in the same order as dense_samples and the
 * sink's integrator_record, the first sample's state as ad_state's;
 * A->zy and A->de are left as dense_samples leaves them (the last sample
 * offered). The output times are ad_sample_time's, its operands read once. */
static int dense_batch(adaptive_ws *A, ad_run *R, ad_mode *md, double t1, long k, const signal_map *S,
                       const struct ad_rec *re) {
  const cup_integrator_options *o = &A->o;
  int n = A->n, na = A->na, ns = S->ns, nc = -1, first = 1;
  long nsamples = o->output_samples, j = R->next_sample, jlast = nsamples - 1;
  double dt = (o->T - o->output_t0) / (double)(o->output_samples - 1);
  double rnd = R->rloc + sqrt(R->r2), T = o->T, t0 = o->output_t0, span = T - t0;
  double ts = ad_sample_time(A, j), *bt = A->bt, *by = A->by, *be = A->be;
  la_copy(by, A->zy, na);
  la_copy(be, A->de, na);
  const double *E = NULL;
  A->rows_ready = 0;
  if (na <= 4) ad_signal_rows(A, re, ns);
  for (;;) {
    int c = 0, last = 0;
    while (c < AD_BATCH && !last) {
      bt[c++] = ts;
      last = !(++j < nsamples) || !((ts = j >= jlast ? T : t0 + span * (double)j / (double)jlast) < t1);
    }
    int more = c - 1 + !last;                     /* the y's to make: the batch's after its first, the next's first */
    if (more && !E) {
      E = ad_expm(A, md, dt, 0);                  /* (applied sample after sample: dt itself) */
      if (na > 4) {                               /* (times_run's and samples_rows' lists) */
        by_rows(A, E);
        rows_of(A, md);
      }
    }
    times_run(A, E, by, be, more, &nc);
    int q;
    switch (na) {
      case 1: q = samples_dense(1, A, md->X, ns, c, rnd); break;
      case 2: q = samples_dense(2, A, md->X, ns, c, rnd); break;
      case 3: q = samples_dense(3, A, md->X, ns, c, rnd); break;
      case 4: q = samples_dense(4, A, md->X, ns, c, rnd); break;
      default: q = samples_rows(A, md, re, ns, c, rnd, first);
    }
    if (q < c) {                                  /* beyond range: the samples before it offered first, as they were */
      if (batch_put(A, R, md, t1, k, q)) return 1;
      R->next_sample++;
      if (!(A->best[q] <= R->est_max)) R->est_max = fmax(R->est_max, A->best[q]);
      la_copy(A->zy, by + (size_t)q * na, na);
      la_copy(A->de, be + (size_t)q * na, na);
      return diverged(R, bt[q], A->bx + (size_t)q * n, n);
    }
    first = 0;
    int st = batch_put(A, R, md, t1, k, c);
    if (st || last) return st;
    la_copy(by, by + (size_t)c * na, na);
    la_copy(be, be + (size_t)c * na, na);
  }
}

/* (A->zmd and zy_ready: adaptive_zeta's, a sample's inside the step; with
 * put, dense_batch when the map composes with md's rows alone.) */
static int dense_loop(adaptive_ws *A, ad_run *R, ad_mode *md, double t1, long k) {
  A->zmd = md;
  A->zy_ready = 1;
  const signal_map *S = A->put && !A->put_off && R->sink ? ad_put_map_ask(A) : NULL;
  const struct ad_rec *re = S && S->ns == A->put_ns ? ad_rec_of(A, md, S) : NULL;
  int st = re && !re->nu ? dense_batch(A, R, md, t1, k, S, re) : dense_samples(A, R, md, t1, k);
  A->zmd = NULL;
  A->zy_ready = 0;
  return st;
}

static int dense_from(adaptive_ws *A, ad_run *R, ad_mode *md, double t1, long k) {
  double *zy = A->zy, *de = A->de;               /* (their own buffers, which free frees) */
  int st = dense_loop(A, R, md, t1, k);
  if (A->zy != zy) {
    la_copy(zy, A->zy, A->na);
    la_copy(de, A->de, A->na);
    A->zy = zy;
    A->de = de;
  }
  return st;
}

/* A->de = exp(tau M) (e0, 0), as ad_flow's Taylor series gives it, on
 * the first n components alone: M's first n columns have their nonzeros
 * in the first n rows (the lower left block is 0), so the input states
 * stay +0 and the terms of their columns are +-0, which leave a sum begun
 * at +0 as it was; each term's test on them holds (0 <= 0). The same bits
 * at (n / na)^2 of the work (the first sample of a step: ad_flow on the
 * error was half of it, 1,400 instructions a step on the full bridge).
 * A cached exponential, or a long tau, goes through ad_flow itself. */
static void error_at(adaptive_ws *A, ad_mode *md, double tau, const double *e0) {
  int n = A->n, na = A->na, nh = md->mp[n];
  double *out = A->de, norm = fabs(tau) * md->mnorm;
  int cached = 0;
  for (int c = 0; c < AD_CACHE; c++) cached |= md->hc[c] == tau;
  if (cached || norm > 4) {
    la_zero(A->de2, na);
    la_copy(A->de2, e0, n);
    ad_flow(A, md, tau, A->de2, out);
    return;
  }
  int sub = norm > 0.5 ? (int)ceil(norm / 0.5) : 1;
  double dt = tau / sub, *term = A->fa, *tmp = A->fb;
  la_zero(out, na);
  la_copy(out, e0, n);
  for (int s = 0; s < sub; s++) {
    la_copy(term, out, n);
    for (int k = 1; k <= 30; k++) {
      for (int i = 0; i < n; i++) tmp[i] = 0;
      for (int q = 0; q < nh; q++) tmp[md->mi[q]] += md->mx[q] * term[md->mj[q]];
      int done = 1;
      for (int i = 0; i < n; i++) {
        term[i] = tmp[i] * dt / k;
        out[i] += term[i];
        done &= fabs(term[i]) <= 0.25 * DBL_EPSILON * fabs(out[i]);
      }
      if (done) break;
    }
  }
}

/* After a refused sample in this step, nothing is offered: a second
 * piece (an event's new flow) is kept for the resumed run. 1 if so. */
static int keep_second(adaptive_ws *A, ad_mode *md, const double *ya, const double *e0, double t0, double t1) {
  struct ad_pend *p = &A->pend;
  if (!p->active) return 0;
  if (!p->seg2) {
    p->seg2 = 1;
    p->md2 = (int)(md - A->modes);
    p->t2a = t0;
    p->t2b = t1;
    la_copy(p->y2, ya, A->na);
    la_copy(p->e2, e0, A->n);
  }
  return 1;
}

/* Output tol's points on the piece (adaptive_outtol.c; an event's new
 * flow: its start too). */
static int emit_tol(adaptive_ws *A, ad_run *R, ad_mode *md, const double *ya, const double *e0, double t0,
                    double t1) {
  if (keep_second(A, md, ya, e0, t0, t1)) return CUP_OK;
  int st = ad_emit_tol(A, R, md, ya, A->oevent ? NULL : A->yb, t0, t1, R->steps + 1, t0 > R->t, -INFINITY, -1);
  return st < 0 ? st : CUP_OK;
}

/* The samples due before t1 on the flow of md from (t0, ya), exact: the
 * first by exp((t_j - t0) M), the next ones by dense_from; the error
 * estimate there is e0's (the error at t0) carried along by the same flow.
 * After a refused sample in this step, nothing is offered (keep_second). */
int ad_emit_out(adaptive_ws *A, ad_run *R, ad_mode *md, const double *ya, const double *e0, double t0,
                double t1) {
  const cup_integrator_options *o = &A->o;
  if (o->output == CUP_OUTPUT_TOL) return emit_tol(A, R, md, ya, e0, t0, t1);
  struct ad_pend *p = &A->pend;
  if (keep_second(A, md, ya, e0, t0, t1)) return CUP_OK;
  if (!(R->next_sample < o->output_samples)) return CUP_OK;
  double ts = ad_sample_time(A, R->next_sample);
  t1 = ad_dense_end(A, t1);
  if (!(ts < t1)) return CUP_OK;
  ad_flow(A, md, ts - t0, ya, A->zy);
  error_at(A, md, ts - t0, e0);
  p->seg2 = 0;
  int st = dense_from(A, R, md, t1, R->steps + 1);
  return st < 0 ? st : CUP_OK;
}

/* A resumed AD_STOP_DENSE: the refused sample and the rest of its piece
 * from the states kept, then the second piece's. */
int ad_dense_resume(adaptive_ws *A, ad_run *R) {
  struct ad_pend *p = &A->pend;
  p->active = 0;
  if (A->o.output == CUP_OUTPUT_TOL) {            /* the piece chosen again, from the refused point on */
    la_copy(A->opeak, p->opk, A->n);
    int st = ad_emit_tol(A, R, &A->modes[p->md], p->zy, p->with_yb ? p->y2 : NULL, p->ta, p->t_end, p->k,
                         p->with_t0, p->tr, p->taylor);
    if (st || !p->seg2) return st;
    p->seg2 = 0;
    return ad_emit_tol(A, R, &A->modes[p->md2], p->y2, NULL, p->t2a, p->t2b, p->k, p->t2a > p->ta, -INFINITY, -1);
  }
  la_copy(A->zy, p->zy, A->na);
  la_copy(A->de, p->de, A->na);
  int st = dense_from(A, R, &A->modes[p->md], p->t_end, p->k);
  if (st) return st;
  if (!p->seg2) return CUP_OK;
  if (!(R->next_sample < A->o.output_samples && ad_sample_time(A, R->next_sample) < p->t2b)) return CUP_OK;
  ad_mode *md2 = &A->modes[p->md2];
  double ts = ad_sample_time(A, R->next_sample);
  p->seg2 = 0;                                   /* a refusal there is the only piece left */
  ad_flow(A, md2, ts - p->t2a, p->y2, A->zy);
  error_at(A, md2, ts - p->t2a, p->e2);
  return dense_from(A, R, md2, p->t2b, p->k);
}

/* A callback input on [t0, t0 + h]: its interpolant at Chebyshev-Lobatto
 * nodes, as Taylor states w = (u, u', ..., u^(q)) at t0 per component; err
 * (p entries) estimates the interpolation error from the last Chebyshev
 * coefficients (geometric decay assumed). */
static __attribute__((noinline)) int poly_input(adaptive_ws *A, double t0, double h, double *w,
                                                double *err) {
  enum { q = AD_DEGREE };
  int p = A->p;
  double *d = A->coef, *c = A->coef + (q + 1), *tau = A->coef + 2 * (q + 1);
  for (int j = 0; j <= q; j++) {
    tau[j] = h * A->node[j];
    if (cup_input_eval(A->u, j == q ? t0 + h : t0 + tau[j], A->ut)) return CUP_ERR_CALLBACK;
    for (int k = 0; k < p; k++) A->samp[k * (q + 1) + j] = A->ut[k];
  }
  for (int j = 0; j < q; j++) {                  /* and between the nodes: a check on the interpolant */
    if (cup_input_eval(A->u, t0 + 0.5 * (tau[j] + tau[j + 1]), A->ut)) return CUP_ERR_CALLBACK;
    for (int k = 0; k < p; k++) A->samp_mid[k * q + j] = A->ut[k];
  }
  for (int k = 0; k < p; k++) {
    const double *f = A->samp + k * (q + 1);
    double aq = 0, aq1 = 0, fmag = 0;          /* Chebyshev coefficients q and q - 1 */
    for (int j = 0; j <= q; j++) {
      double wj = j == 0 || j == q ? 0.5 : 1;
      aq += wj * f[j] * cos(M_PI * j * q / q) * ((q & 1) ? -1 : 1);
      aq1 += wj * f[j] * cos(M_PI * j * (q - 1) / q) * (((q - 1) & 1) ? -1 : 1);
      fmag = fmax(fmag, fabs(f[j]));
    }
    aq = fabs(aq) / q;                            /* the last coefficient is halved */
    aq1 = 2 * fabs(aq1) / q;
    err[k] = (aq1 > 0 ? aq * fmin(1, aq / aq1) : aq) + 4 * DBL_EPSILON * fmag;
    for (int j = 0; j <= q; j++) d[j] = f[j];    /* Newton's divided differences */
    for (int l = 1; l <= q; l++)
      for (int j = q; j >= l; j--) d[j] = (d[j] - d[j - 1]) / (tau[j] - tau[j - l]);
    for (int j = 0; j <= q; j++) c[j] = 0;       /* to monomials: Horner from the top */
    c[0] = d[q];
    for (int l = q - 1; l >= 0; l--) {
      for (int j = q - l; j >= 1; j--) c[j] = c[j - 1] - tau[l] * c[j];
      c[0] = d[l] - tau[l] * c[0];
    }
    /* the interpolant against the input between its nodes: the tail of the
     * Chebyshev coefficients alone underrates a step too long for degree q
     * (a 1 kHz sine over 0.3 ms: 1e-7 of its amplitude off, estimated 1e-12) */
    for (int j = 0; j < q; j++) {
      double s = 0.5 * (tau[j] + tau[j + 1]), v = c[q];
      for (int l = q - 1; l >= 0; l--) v = v * s + c[l];
      err[k] = fmax(err[k], fabs(v - A->samp_mid[k * q + j]) + 4 * DBL_EPSILON * fmag);
    }
    double fact = 1;
    for (int j = 0; j <= q; j++) {
      if (j > 0) fact *= j;
      w[k * (q + 1) + j] = fact * c[j];
    }
  }
  return CUP_OK;
}

/* The exosystem holds every term of the input (live_terms dropped none but
 * constants 0). */
static int gen_whole(const adaptive_ws *A) { return A->gen_whole; }

/* The exosystem's states for a step [t0, t1] inside a piece (and the
 * constant state, with D). Sines' and constants' states are those at t0
 * whatever t1 is: a record at a step's end (adaptive_zeta, to t0 + an
 * eighth of a period) and the next step (to its own end) take the same,
 * and on the six-pulse bridge each computed its three sines' sin and cos
 * again (a ninth of its instructions). */
static __attribute__((noinline)) void piece_states(adaptive_ws *A, double t0, double t1, double *w);

int ad_inputs_varied(adaptive_ws *A, double t0, double t1, double *w, double *err) {
  if (A->one >= 0) w[A->one] = 1;
  /* (the others out of line: their registers' saves were half of a
   * converter's call, the six-pulse bridge's pieces as often copies) */
  if (A->callback) return poly_input(A, t0, t1 - t0, w, err);
  piece_states(A, t0, t1, w);
  return CUP_OK;
}

/* A built-in input's piece: kept, the last window's, or made. */
static void piece_states(adaptive_ws *A, double t0, double t1, double *w) {
  int any = A->piece_from_t0;                    /* (gen_whole below: the same terms, the same answer) */
  if (A->piece_ok && t0 == A->piece_t0 && (any || t1 == A->piece_t1)) {   /* the same piece again */
    la_copy(w, A->piece_w, A->nwu);
    return;
  }
  /* the last window's, same input: only when both hold every term of it
   * (live_terms: a configuration whose E and G read fewer has other states) */
  const adaptive_ws *O = A->nb && gen_whole(A) ? A->nb->piece_of : NULL;
  if (O && O != A && O->piece_ok && t0 == O->piece_t0 && (any || t1 == O->piece_t1) && gen_whole(O))
    la_copy(w, O->piece_w, A->nwu);
  else input_gen_piece(&A->gen, A->first_state, A->gen_rot, t0, t1, w);
  if (A->nb) A->nb->piece_of = A;
  la_copy(A->piece_w, w, A->nwu);
  A->piece_t0 = t0;
  A->piece_t1 = t1;
  A->piece_ok = 1;
}

/* A record at a breakpoint (adaptive_zeta) and the piece that starts there
 * (start_piece, the next window's in a switched run) ask the same: on the
 * full bridge, 12 pulses' corners, 640 instructions a record. A switched
 * run's windows, one a piece, ask term by term (input_next_break_memo:
 * one gate's corner recomputed a piece rather than all four). */
double ad_next_break(adaptive_ws *A, double t) {
  input_breaks *b = A->nb ? &A->nb->nb : &A->nb_own;
  if (!b->ok || t != b->t) {
    b->next = input_next_break_memo(A->u, b->term, A->nb ? INPUT_BREAK_MEMOS : 0, t);
    b->t = t;
    b->ok = 1;
  }
  return b->next;
}

void adaptive_share_breaks(adaptive_ws *A, adaptive_breaks *b) { A->nb = b; }

int ad_record_y(adaptive_ws *A, const ad_mode *md) {
  double t = A->zt, t1 = t;
  /* no piece's end to find where the input's states read none: no states
   * or DC alone (ad_inputs_on copies them whatever the interval), or states
   * of t alone (sines, constants; the search was a fifth of a record on the
   * six-pulse bridge) */
  if (A->nwu && !A->w_const && (A->callback || !A->piece_from_t0)) {
    /* the held terms' next break (a gate's corners move no state); when they
     * are the whole input, the one start_piece asks for at t too (ad_next_break) */
    double tb = gen_whole(A) ? ad_next_break(A, t) : cup_input_next_break(A->held, t);
    double h = fmin(A->hmax_input, (tb < INFINITY ? tb : t + A->o.T) - t);
    t1 = A->callback && t >= A->o.T ? t - h : t + h;
  }
  if (ad_inputs_on(A, t, t1, A->zw, A->uerr)) return CUP_ERR_CALLBACK;
  ad_lift(A, md, A->x, A->zw, A->zy);
  return CUP_OK;
}

/* adaptive_record.c's composed rows (adaptive_record.c holds them and the
 * batches' buffers; the records' y, here, ad_record_y). */
int adaptive_record(adaptive_ws *A, const signal_map *S, double *out) {
  const ad_mode *md = A->zmd;
  if (!md || A->zx0) return 0;                   /* (x0's sample: its signals from x0 as given, by the caller) */
  const struct ad_rec *e = ad_rec_of(A, md, S);
  if (!e || (!A->zy_ready && ad_record_y(A, md))) return 0;   /* (a failed input: adaptive_zeta's zeros, as before) */
  ad_rec_rows(e, S->ns, A->zy, out, 1);
  return e->nu ? ad_rec_inputs(A, e, S->ns, out) : 1;
}

/* zeta_J = L_J y on the active set's manifold (adaptive_impl.h), y from the
 * state and the input's states from the output time on. */
int adaptive_zeta(adaptive_ws *A, double *zeta) {
  const ad_mode *md = A->zmd;
  if (md && A->zy_ready && A->rows_ready) {      /* a sample inside a step, by rows_of's rows: one pass */
    for (int i = 0; i < A->m; i++) zeta[i] = md->is_zeta[i] ? md->Lc[i] + row_times(A, A->n + i, A->zy) : 0;
    return CUP_OK;
  }
  la_zero_few(zeta, A->m);
  if (!md) return CUP_OK;
  if (A->zy_ready) {                             /* a sample inside a step: its y is known */
    for (int i = 0; i < A->m; i++)
      if (md->is_zeta[i]) zeta[i] = md->Lc[i] + la_dot(md->L + (size_t)i * A->na, A->zy, A->na);
    return CUP_OK;
  }
  if (ad_record_y(A, md)) return CUP_ERR_CALLBACK;
  for (int i = 0; i < A->m; i++)
    if (md->is_zeta[i]) zeta[i] = md->Lc[i] + la_dot(md->L + (size_t)i * A->na, A->zy, A->na);
  return CUP_OK;
}


/* faststep — see faststep.h. Each piece below names the general code whose
 * arithmetic it repeats; tests/test_faststep.c compares the two. */
#include <math.h>
#include "catchup.h"
#include "faststep.h"
#include "lcp/step.h"
#include "tally.h"

static long dispatch(faststep_ws *f, long k, long stop, double *x, double *xnew, cup_proj_info *pi, int *st,
                     cup_run_info *info);
static long dispatch_konst(faststep_ws *f, long k, long stop, double *x, double *xnew, cup_proj_info *pi, int *st,
                           cup_run_info *info);

/* The one column of A with entries: its index, -1 for none (or no A), -2
 * for several. */
static int one_column(const la_sparse *A) {
  int c = -1;
  for (int j = 0; A && j < A->ncol; j++)
    if (A->p[j + 1] > A->p[j]) c = c == -1 ? j : -2;
  return c;
}

/* The input component the steps read, and the terms that make it up: an
 * input of several components qualifies when one alone has a column in E
 * or G (a switched circuit's configuration keeps the gate sources, whose
 * components move neither the state nor the set); the others are left
 * out, whatever their kind, as freestep.c's and fixed.c's sums leave them
 * (their zero columns add +0 to sums that are never -0: they start from
 * +0). Returns 0 when it does not qualify. */
static int input_terms(faststep_ws *f, const freestep_ws *fs, const la_sparse *G) {
  const cup_input *u = fs->u;
  int p = fs->p, comp = 0;
  if (!u) return 1;
  if (u->fn) return 0;
  if (p > 1) {
    int ce = fs->d.has_E ? one_column(&fs->d.E) : -1, cg = one_column(G);
    if (ce == -2 || cg == -2 || (ce >= 0 && cg >= 0 && ce != cg) || (fs->d.has_E && fs->d.E.ncol != p) ||
        (G && G->ncol != p))
      return 0;
    comp = ce >= 0 ? ce : cg;
    f->has = f->has && ce >= 0;
    if (fs->const_input && f->has) {         /* freestep.c adds Gam's zero columns times h u: finite */
      for (int c = 0; c < p; c++)
        if (!isfinite(fs->ubuf[c])) return 0;
    }
  }
  for (int k = 0; k < u->nterms; k++) {
    const input_term *w = &u->terms[k];
    if (w->comp != comp) continue;           /* (p = 1: all) */
    if (f->nterms == CUP_FAST_TERMS) return 0;
    if (w->kind != CUP_WAVE_CONSTANT && w->kind != CUP_WAVE_SINE && w->kind != CUP_WAVE_SQUARE) return 0;
    f->term[f->nterms] = w;
    f->term_h[f->nterms++] = fs->term_h[k];
  }
  f->comp = comp;
  return 1;
}

/* An input whose terms are all constants (a switched circuit's DC supply,
 * its gate sources left out) is the same at every step: its integral and
 * the offset it gives are taken here, as inputs_ahead would take them
 * (the sums from +0, term by term), and the steps skip inputs_ahead. */
static void constant_terms(faststep_ws *f) {
  double ui = 0, u = 0;
  for (int q = 0; q < f->nterms && (f->integrate || f->moving); q++) {
    if (f->term[q]->kind != CUP_WAVE_CONSTANT) return;
    ui += f->term_h[q];
    u += input_term_value(f->term[q], 0);
  }
  if (f->integrate) {
    f->integrate = 0;
    f->uconst = ui;
  }
  f->gk = !f->moving ? f->g0 : v2_select(u != 0 ? f->grows : (v2l){0, 0}, f->g0 + f->gdir * u, f->g0);
  f->konst = 1;
}

void faststep_init(faststep_ws *f, const freestep_ws *fs, lcp_step *th, const cup_polyset *K,
                   const la_sparse *G, double *g, int use_theta, double eps_n, double eta_n, long steps,
                   double T) {
  *f = (faststep_ws){.th = th, .g = g, .eps_n = eps_n, .eta_n = eta_n, .steps = steps, .T = T, .h = fs->h,
                      .last_t = NAN};
  const cup_input *u = fs->u;
  if (!use_theta || !th->small || !fs->affine || fs->has_f || !(eps_n > 0) || !(eta_n > 0)) return;
  f->has = u && fs->d.has_E;                /* freestep.c's step_input */
  if (!input_terms(f, fs, G)) return;
  int n = fs->n, p = fs->p;
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) f->Phi[j][i >> 1][i & 1] = fs->Phi[i * n + j];
  f->integrate = f->has && !fs->const_input;
  f->uconst = f->has ? fs->ubuf[f->comp] : 0;
  for (int i = 0; i < n && f->has; i++) f->Gam[i >> 1][i & 1] = fs->Gam[i * p + f->comp];
  for (int i = 0; i < K->m; i++) f->g0[i] = K->g0[i];
  f->moving = G && u;
  if (f->moving)
    for (int q = G->p[f->comp]; q < G->p[f->comp + 1]; q++) {
      if (f->grows[G->i[q]]) return;        /* a repeated row: la_sparse_gaxpy adds twice */
      f->grows[G->i[q]] = -1;
      f->gdir[G->i[q]] = G->x[q];
    }
  constant_terms(f);
  f->key = n * 8 + th->m + 64 * f->konst;
  f->go = f->konst ? dispatch_konst : dispatch;
  f->on = 1;
}

/* The values of CUP_FAST_AHEAD steps: written two at a time, read one at a
 * time (a lane picked by a variable costs a few instructions, an element
 * one). */
typedef union faststep_ahead {
  v2d v[CUP_FAST_AHEAD / 2];
  double d[CUP_FAST_AHEAD];
} faststep_ahead;

/* One square wave's share of ui and u1 (inputs_ahead) for the steps
 * ending at t1: its position q(t) serves both its integral and its value,
 * and its antiderivative at a step's start is the one at the last step's
 * end. Returns 1 when its value is the same at all these steps. */
static int square_ahead(faststep_ws *f, int q, double t0, const faststep_ahead *t1, int cnt, faststep_ahead *ui,
                        faststep_ahead *u1) {
  const input_term *w = f->term[q];
  const double omega = w->omega, ph = w->phase / M_PI;        /* input_square_q */
  const double height = w->amp * M_PI / w->omega, amp = w->amp;   /* input_term_integral, input_term_value */
  v2d qs[CUP_FAST_AHEAD / 2], r[CUP_FAST_AHEAD / 2], sg[CUP_FAST_AHEAD / 2];
  faststep_ahead tri;
  v2d before = {0, t0 == f->last_t ? f->last_tri[q] : input_sign_sin_q_integral(input_square_q(w, t0))};
  for (int p = 0; p < CUP_FAST_AHEAD / 2; p++) qs[p] = omega * t1->v[p] / M_PI + ph;
  int same = input_square_block(qs, CUP_FAST_AHEAD / 2, r, sg);   /* omega > 0: q rises with t */
  for (int p = 0; p < CUP_FAST_AHEAD / 2; p++) {
    tri.v[p] = input_triangle_r2(r[p]);
    ui->v[p] += height * (tri.v[p] - v2_shuffle(before, tri.v[p], 1, 2));
    before = tri.v[p];
  }
  if (cnt) f->last_tri[q] = tri.d[cnt - 1];
  for (int p = 0; p < CUP_FAST_AHEAD / 2 && f->moving; p++) u1->v[p] += amp * sg[p];
  return same;
}

/* The inputs of steps k, k + 1, ..., k + CUP_FAST_AHEAD - 1, step k + j in
 * lane j & 1 of entry j >> 1: t1 (each step's end), ui (the integral of u
 * over it: freestep.c's freestep_term_integral summed term by term as
 * waveform_step_integral sums one input) and, for a moving set, g (the
 * offset at its end: integrator.c's moving_offset of cup_input_eval's u,
 * once for the stretch when u is the same at all its steps); returns how
 * many of them to take, none past stop.
 * Term by term over the steps, so that a term's kind is looked at once, and
 * apart from the steps, so that the sines (some 60 cycles of latency each)
 * overlap one another and the steps' chains; two steps at a time, and always
 * all of them (a few wasted at the end of a stretch) so that the loops have
 * no exits. */
static int inputs_ahead(faststep_ws *f, long k, long stop, faststep_ahead *t1, faststep_ahead *ui, v2d *g) {
  enum { P = CUP_FAST_AHEAD / 2 };
  int cnt = stop - k + 1 < CUP_FAST_AHEAD ? (int)(stop - k + 1) : CUP_FAST_AHEAD;
  faststep_ahead t0, u1;                              /* t0: each step's start */
  v2d kk = {(double)k, (double)k + 1}, tmid[P];
  for (int p = 0; p < P; p++) {                  /* t_{k+j} as tally_grid_time gives it: */
    t0.v[p] = (kk + 2 * p) * f->h;               /* (double)(k + j) exactly: k < 2^53 */
    t1->v[p] = (kk + (2 * p + 1)) * f->h;
    ui->v[p] = u1.v[p] = (v2d){0, 0};
  }
  if (k <= f->steps && f->steps - k <= CUP_FAST_AHEAD) {   /* t_steps = T */
    if (f->steps - k < CUP_FAST_AHEAD) t0.d[f->steps - k] = f->T;
    if (f->steps > k) t1->d[f->steps - k - 1] = f->T;
  }
  for (int p = 0; p < P; p++) tmid[p] = 0.5 * (t0.v[p] + t1->v[p]);
  int integrate = f->integrate, moving = f->moving, same = 1;
  for (int q = 0; q < f->nterms && (integrate || moving); q++) {
    const input_term *w = f->term[q];
    double th = f->term_h[q];
    if (w->kind == CUP_WAVE_SQUARE && w->omega != 0) {
      same &= square_ahead(f, q, t0.d[0], t1, cnt, ui, &u1);
      continue;
    }
    if (w->kind == CUP_WAVE_CONSTANT || (w->kind == CUP_WAVE_SINE && !(w->omega > 0)))
      for (int p = 0; p < P; p++) ui->v[p] += th;
    else if (w->kind == CUP_WAVE_SINE)
      for (int p = 0; p < P; p++) ui->v[p] += th * trig_sin2(w->omega * tmid[p] + w->phase);
    else
      for (int j = 0; j < CUP_FAST_AHEAD; j++) ui->d[j] += input_term_integral(w, t0.d[j], t1->d[j]);
    same &= w->kind == CUP_WAVE_CONSTANT;
    for (int j = 0; j < CUP_FAST_AHEAD && moving; j++) u1.d[j] += input_term_value(w, t1->d[j]);
  }
  if (cnt) f->last_t = t1->d[cnt - 1];
  for (int p = 0; p < P && !integrate; p++)   /* a constant input's h u, or none */
    ui->v[p] = (v2d){f->uconst, f->uconst};
  /* moving_offset: g0 where u = 0, as la_sparse_gaxpy skips a zero;
   * lcp_small_core declines an offset that is not finite */
  for (int j = 0; j < CUP_FAST_AHEAD && moving; j++) {
    double u = u1.d[same ? 0 : j];
    g[j] = same && j ? g[0] : v2_select(u != 0 ? f->grows : (v2l){0, 0}, f->g0 + f->gdir * u, f->g0);
  }
  return cnt;
}

/* One step from x into z (xf: the free point, g: the offset), its input
 * given: the status, or CUP_FAST_DECLINED with nothing but scratch changed. */
static inline __attribute__((always_inline)) int
fast_step(const faststep_ws *f, lcp_small_carry *c, double uint, v2d g, const v2d *restrict x,
          v2d *restrict xf, v2d *restrict z, lcp_small_out *o, const int n, const int m) {
  for (int r = 0; r < (n + 1) / 2; r++) {                 /* freestep.c's affine_rows */
    v2d acc = {0, 0};
    for (int j = 0; j < n; j++) acc += f->Phi[j][r] * v2_lane(x, j);
    xf[r] = acc + f->Gam[r] * uint;   /* without input 0 * 0: + 0 changes no sum but -0, never a 0 + ... */
  }
  /* the scale (cup_polyset_norm of xf) only goes into pi: not computed */
  return lcp_small_core(f->th, c, g, xf, z, f->eps_n, f->eta_n, o, n, m) ? o->status : CUP_FAST_DECLINED;
}

/* The statistics of the steps run() booked, through step kb (its end t),
 * into info. */
static inline __attribute__((always_inline)) void
book(cup_run_info *info, long kb, double t, long booked, long skipped, long long iterations, v2d max_cert) {
  info->step = kb;
  info->t = t;
  info->skipped += skipped;
  info->projected += booked - skipped;
  info->dual_iterations += iterations;
  info->max_eps_cert = max_cert[0];
  info->max_eta_cert = max_cert[1];
}

/* Whether z left the state's range (tally_state_beyond, the same sum). */
static inline __attribute__((always_inline)) int beyond(const v2d *z, const int n) {
  double s = 0;
  for (int j = 0; j < n; j++) s += fabs(v2_lane(z, j));
  return !(s <= CUP_STATE_MAX);
}

/* integrator.c's loop from step k, the state, the LCP's warm start and the
 * statistics in registers: each step that ends CUP_OK before stop is booked
 * as the loop books it (tally_projection, step, t: added up here, written into
 * info at the end); the first other one, or step stop, is left pending.
 * Recording (konst runs only, f->recording): each booked step's sample
 * goes to the sink as the loop gives it (its state in x, the one before in
 * xnew, lambda in the LCP step, zeta_from 1), each state checked against
 * its range first (a record cannot be taken back: one beyond is left
 * pending, declined, for the loop to find); a sink that refuses ends the
 * run there (*st = CUP_FAST_REFUSED, the step booked); with f->book_last,
 * step stop is booked and recorded too (*st = CUP_FAST_DONE). */
static inline __attribute__((always_inline)) long
run(faststep_ws *f, long k, long stop, double *xp, double *xnewp, cup_proj_info *pi, int *st,
    cup_run_info *info, const int n, const int m, const int konst) {
  v2d x[2] = {{0, 0}, {0, 0}}, xf[2], z[2], g = konst ? f->gk : f->g0;
  const int rec = konst && f->recording, last = rec && f->book_last;
  faststep_ahead t1, ui;
  v2d gs[CUP_FAST_AHEAD];
  for (int j = 0; j < n; j++) x[j >> 1][j & 1] = xp[j];
  lcp_small_carry c = lcp_small_load(f->th, m);
  lcp_small_out o;
  long booked = 0, skipped = 0;
  long long iterations = 0;
  v2d max_cert = {info->max_eps_cert, info->max_eta_cert};
  double t = info->t;
  for (int have = 0, a = 0;; k++, a++) {
    if (!konst && a == have) {
      have = inputs_ahead(f, k, stop, &t1, &ui, gs);
      a = 0;
    }
    if (!konst && f->moving) g = gs[a];
    lcp_small_carry c0 = c;
    int s = fast_step(f, &c, konst ? f->uconst : ui.d[a], g, x, xf, z, &o, n, m);
    if (rec && s == CUP_OK && (k != stop || last) && beyond(z, n)) {
      c = c0;
      s = CUP_FAST_DECLINED;
    }
    if ((k == stop && !last) || s != CUP_OK) {
      for (int j = 0; j < n; j++) xp[j] = v2_lane(x, j);
      if (s != CUP_FAST_DECLINED) {
        for (int j = 0; j < n; j++) xnewp[j] = v2_lane(z, j);
        lcp_small_info(pi, &o, NAN, f->eps_n, f->eta_n);
      }
      lcp_small_store(f->th, &c, m);
      for (int i = 0; i < m && f->moving; i++) f->g[i] = g[i];
      if (booked) book(info, k, konst ? tally_grid_time(k, f->steps, f->T, f->h) : t, booked, skipped, iterations,
                       max_cert);
      *st = s;
      return k;
    }
    for (int j = 0; j < n && rec; j++) xnewp[j] = v2_lane(x, j);
    x[0] = z[0];
    x[1] = z[1];
    if (!konst) t = t1.d[a];
    booked++;
    skipped += o.skipped;                                 /* tally_projection, per step */
    iterations += o.iterations;
    /* the tally's !(cert <= max) ? cert : max as max > cert ? max : cert
     * (SSE2's maxpd): the same but for zeros of opposite signs, and the
     * certificates are never -0 (max(gap, 0), a distance) */
    max_cert = v2_max(max_cert, (v2d){o.eps_cert, o.eta_cert});
    if (rec) {
      double tb = tally_grid_time(k + 1, f->steps, f->T, f->h);
      for (int j = 0; j < n; j++) xp[j] = v2_lane(x, j);
      lcp_small_store(f->th, &c, m);
      *f->rec.zeta_from = 1;
      info->samples++;
      int refused = f->rec.sink(k + 1, tb, xp, f->rec.ctx);
      if (refused || (last && k == stop)) {     /* (stop booked too: nothing pending) */
        for (int i = 0; i < m && f->moving; i++) f->g[i] = g[i];
        book(info, k + 1, tb, booked, skipped, iterations, max_cert);
        *st = refused ? CUP_FAST_REFUSED : CUP_FAST_DONE;
        return k + 1;
      }
    }
  }
}

/* What a run of steps changes besides scratch, to take it back. */
typedef struct fast_undo {
  double x[CUP_STEP_SMALL_N], lam[CUP_STEP_SMALL_M], g[CUP_STEP_SMALL_M], lq;
  int prev[CUP_STEP_SMALL_M];
  long step, skipped, projected;   /* the info it books */
  long long dual_iterations;
  double t, max_eps_cert, max_eta_cert;
} fast_undo;

static void undo_save(fast_undo *u, const faststep_ws *f, const double *x, const cup_run_info *info) {
  const lcp_step *th = f->th;
  for (int j = 0; j < th->n; j++) u->x[j] = x[j];
  for (int i = 0; i < th->m; i++) {
    u->lam[i] = th->lcp.lam[i];
    u->prev[i] = th->lcp.prev[i];
    u->g[i] = f->moving ? f->g[i] : 0;
  }
  u->lq = th->lq;
  u->step = info->step;
  u->t = info->t;
  u->skipped = info->skipped;
  u->projected = info->projected;
  u->dual_iterations = info->dual_iterations;
  u->max_eps_cert = info->max_eps_cert;
  u->max_eta_cert = info->max_eta_cert;
}

static void undo_apply(const fast_undo *u, faststep_ws *f, double *x, cup_run_info *info) {
  lcp_step *th = f->th;
  for (int j = 0; j < th->n; j++) x[j] = u->x[j];
  for (int i = 0; i < th->m; i++) {
    th->lcp.lam[i] = u->lam[i];
    th->lcp.prev[i] = u->prev[i];
    if (f->moving) f->g[i] = u->g[i];
  }
  th->lq = u->lq;
  info->step = u->step;
  info->t = u->t;
  info->skipped = u->skipped;
  info->projected = u->projected;
  info->dual_iterations = u->dual_iterations;
  info->max_eps_cert = u->max_eps_cert;
  info->max_eta_cert = u->max_eta_cert;
}

/* run() for the sizes: each size's steps compiled apart, the konst ones
 * (which record, and need more registers) in a function of their own, so
 * that they do not add to the others' entry and exit (f->go: one or the
 * other). */
#define CUP_FAST_CASE(N, M, C) \
  case (N) * 8 + (M) + 64 * (C): return run(f, k, stop, x, xnew, pi, st, info, N, M, C);
static __attribute__((noinline)) long dispatch_konst(faststep_ws *f, long k, long stop, double *x, double *xnew,
                                                     cup_proj_info *pi, int *st, cup_run_info *info) {
  switch (f->key) {
    CUP_FAST_CASE(1, 1, 1) CUP_FAST_CASE(2, 1, 1) CUP_FAST_CASE(3, 1, 1) CUP_FAST_CASE(4, 1, 1)
    CUP_FAST_CASE(1, 2, 1) CUP_FAST_CASE(2, 2, 1) CUP_FAST_CASE(3, 2, 1) CUP_FAST_CASE(4, 2, 1)
  }
  *st = CUP_FAST_DECLINED;
  return k;
}

static __attribute__((noinline)) long dispatch(faststep_ws *f, long k, long stop, double *x, double *xnew,
                                               cup_proj_info *pi, int *st, cup_run_info *info) {
  switch (f->key) {
    CUP_FAST_CASE(1, 1, 0) CUP_FAST_CASE(2, 1, 0) CUP_FAST_CASE(3, 1, 0) CUP_FAST_CASE(4, 1, 0)
    CUP_FAST_CASE(1, 2, 0) CUP_FAST_CASE(2, 2, 0) CUP_FAST_CASE(3, 2, 0) CUP_FAST_CASE(4, 2, 0)
  }
  *st = CUP_FAST_DECLINED;
  return k;
}
#undef CUP_FAST_CASE

/* A run of more than one step, its last booked state checked. */
static __attribute__((noinline)) long run_checked(faststep_ws *f, long k, long stop, double *x, double *xnew,
                                                  cup_proj_info *pi, int *st, cup_run_info *info) {
  fast_undo u;
  undo_save(&u, f, x, info);
  long pending = f->go(f, k, stop, x, xnew, pi, st, info);
  /* the last booked state against its range, here and not in run(): there
   * it cost the loop registers (1.4-3.5 instructions a step) */
  if (pending > k && tally_state_beyond(x, f->th->n)) {
    undo_apply(&u, f, x, info);
    f->hold = pending;
    *st = CUP_FAST_DECLINED;
    return k;
  }
  return pending;
}

long faststep_run(faststep_ws *f, long k, long stop, double *x, double *xnew, cup_proj_info *pi, int *st,
                  cup_run_info *info) {
  return stop == k ? f->go(f, k, stop, x, xnew, pi, st, info)     /* one step alone books nothing */
                   : run_checked(f, k, stop, x, xnew, pi, st, info);
}

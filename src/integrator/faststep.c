/* faststep — see faststep.h. Each piece below names the general code whose
 * arithmetic it repeats; tests/test_faststep.c compares the two. */
#include <math.h>
#include "catchup.h"
#include "faststep.h"
#include "lcp/step.h"
#include "tally.h"

void cup_faststep_init(cup_faststep *f, const cup_freestep *fs, cup_lcp_step *th, const cup_polyset *K,
                       const cup_sparse *G, double *g, int use_theta, double eps_n, double eta_n, long steps,
                       double T) {
  *f = (cup_faststep){.th = th, .g0 = K->g0, .g = g, .eps_n = eps_n, .eta_n = eta_n, .steps = steps, .T = T,
                      .h = fs->h, .last_t = NAN};
  const cup_input *u = fs->u;
  if (!use_theta || !th->small || !fs->affine || fs->has_f || fs->p > 1 || !(eps_n > 0) || !(eta_n > 0) ||
      (u && (u->fn || u->nterms > CUP_FAST_TERMS)))
    return;
  int n = fs->n;
  for (int q = 0; q < n * n; q++) f->Phi[q] = fs->Phi[q];
  f->has = u && fs->d.has_E;                /* freestep.c's step_input */
  f->integrate = f->has && !fs->const_input;
  f->uconst = f->has ? fs->ubuf[0] : 0;
  for (int i = 0; i < n && f->has; i++) f->Gam[i] = fs->Gam[i];
  f->nterms = u ? u->nterms : 0;
  for (int k = 0; k < f->nterms; k++) {
    f->term[k] = &u->terms[k];
    f->term_h[k] = fs->term_h[k];
    cup_wave_kind kind = u->terms[k].kind;
    if (kind != CUP_WAVE_CONSTANT && kind != CUP_WAVE_SINE && kind != CUP_WAVE_SQUARE) return;
  }
  f->moving = G && u;
  if (f->moving) {
    if (G->ncol != 1 || G->nnz > CUP_STEP_SMALL_M) return;
    for (int q = G->p[0]; q < G->p[1]; q++) {
      f->grow[f->gnnz] = G->i[q];
      f->gval[f->gnnz++] = G->x[q];
    }
  }
  f->on = 1;
}

/* The inputs of steps k, k + 1, ..., at most CUP_FAST_AHEAD and none past
 * stop, into t1 (each step's end), ui (the integral of u over it: freestep.c's
 * cup_freestep_term_integral summed term by term as waveform_step_integral
 * sums one input) and u1 (u at its end, for a moving set: cup_input_eval);
 * returns how many. Term by term over the steps, so that a term's kind is
 * looked at once, and apart from the steps, so that the sines (some 60
 * cycles of latency each) overlap one another and the steps' chains. A
 * square wave's position q(t) serves both its integral and its value, and
 * its antiderivative at a step's start is the one at the last step's end. */
static int inputs_ahead(cup_faststep *f, long k, long stop, double *t1, double *ui, double *u1) {
  int cnt = stop - k + 1 < CUP_FAST_AHEAD ? (int)(stop - k + 1) : CUP_FAST_AHEAD;
  double t0[CUP_FAST_AHEAD], tmid[CUP_FAST_AHEAD];
  for (int j = 0; j < cnt; j++) {
    t0[j] = j ? t1[j - 1] : cup_grid_time(k, f->steps, f->T, f->h);
    t1[j] = cup_grid_time(k + j + 1, f->steps, f->T, f->h);
    tmid[j] = 0.5 * (t0[j] + t1[j]);
    ui[j] = u1[j] = 0;
  }
  int integrate = f->integrate, moving = f->moving;
  for (int q = 0; q < f->nterms && (integrate || moving); q++) {
    const cup_term *w = f->term[q];
    double th = f->term_h[q];
    if (w->kind == CUP_WAVE_SQUARE && w->omega != 0) {
      double tri0 = t0[0] == f->last_t ? f->last_tri[q] : cup_sign_sin_q_integral(cup_square_q(w, t0[0]));
      for (int j = 0; j < cnt; j++) {
        double q1 = cup_square_q(w, t1[j]), tri1 = cup_sign_sin_q_integral(q1);
        ui[j] += w->amp * M_PI / w->omega * (tri1 - tri0);    /* cup_term_integral */
        if (moving) u1[j] += w->amp * cup_sign_sin_q(q1);      /* cup_term_value */
        tri0 = tri1;
      }
      f->last_tri[q] = tri0;
      continue;
    }
    if (w->kind == CUP_WAVE_CONSTANT)
      for (int j = 0; j < cnt; j++) ui[j] += th;
    else if (w->kind == CUP_WAVE_SINE && w->omega > 0)
      for (int j = 0; j < cnt; j++) ui[j] += th * cup_sin(w->omega * tmid[j] + w->phase);
    else if (w->kind == CUP_WAVE_SINE)
      for (int j = 0; j < cnt; j++) ui[j] += th;
    else
      for (int j = 0; j < cnt; j++) ui[j] += cup_term_integral(w, t0[j], t1[j]);
    for (int j = 0; j < cnt && moving; j++) u1[j] += cup_term_value(w, t1[j]);
  }
  if (cnt) f->last_t = t1[cnt - 1];
  for (int j = 0; j < cnt && !integrate; j++) ui[j] = f->uconst;   /* a constant input's h u, or none */
  return cnt;
}

/* One step from x into z (xf: the free point), its input given: the
 * status, or CUP_FAST_DECLINED with nothing but scratch changed. */
static inline __attribute__((always_inline)) int
fast_step(cup_faststep *f, double uint, double u1, const double *restrict x, double *restrict xf,
          double *restrict z, cup_proj_info *pi, const int n, const int m) {
  for (int i = 0; i < n; i++) {                             /* freestep.c's affine_rows */
    double acc = 0;
    for (int j = 0; j < n; j++) acc += f->Phi[i * n + j] * x[j];
    if (f->has) acc += f->Gam[i] * uint;
    xf[i] = acc;
  }
  const double *g = f->g0;
  if (f->moving) {                                          /* integrator.c's moving_offset */
    for (int i = 0; i < m; i++) f->g[i] = f->g0[i];
    if (u1 != 0)
      for (int q = 0; q < f->gnnz; q++) f->g[f->grow[q]] += f->gval[q] * u1;
    for (int i = 0; i < m; i++)
      if (!isfinite(f->g[i])) return CUP_FAST_DECLINED;
    g = f->g;
  }
  /* the scale (cup_polyset_norm of xf) only goes into pi: not computed */
  return cup_small_step(f->th, g, xf, z, NAN, f->eps_n, f->eta_n, pi, n, m) ? pi->status : CUP_FAST_DECLINED;
}

/* integrator.c's loop from step k, the state in registers: each step that
 * ends CUP_OK before stop is booked as the loop books it; the first other
 * one, or step stop, is left pending. */
static inline __attribute__((always_inline)) long
run(cup_faststep *f, long k, long stop, double *xp, double *xnewp, cup_proj_info *pi, int *st,
    cup_run_info *info, const int n, const int m) {
  double x[CUP_STEP_SMALL_N], xf[CUP_STEP_SMALL_N], z[CUP_STEP_SMALL_N];
  double t1[CUP_FAST_AHEAD], ui[CUP_FAST_AHEAD], u1[CUP_FAST_AHEAD];
  for (int j = 0; j < n; j++) x[j] = xp[j];
  cup_proj_info p;
  for (int have = 0, a = 0;; k++, a++) {
    if (a == have) {
      have = inputs_ahead(f, k, stop, t1, ui, u1);
      a = 0;
    }
    int s = fast_step(f, ui[a], u1[a], x, xf, z, &p, n, m);
    if (k == stop || s != CUP_OK) {
      for (int j = 0; j < n; j++) xp[j] = x[j];
      for (int j = 0; j < n && s != CUP_FAST_DECLINED; j++) xnewp[j] = z[j];
      *pi = p;
      *st = s;
      return k;
    }
    for (int j = 0; j < n; j++) x[j] = z[j];
    info->step = k + 1;
    info->t = t1[a];
    cup_tally(info, &p);
  }
}

long cup_faststep_run(cup_faststep *f, long k, long stop, double *x, double *xnew, cup_proj_info *pi, int *st,
                      cup_run_info *info) {
#define CUP_FAST_CASE(N, M) \
  case (N) * 8 + (M): return run(f, k, stop, x, xnew, pi, st, info, N, M);
  switch (f->th->n * 8 + f->th->m) {
    CUP_FAST_CASE(1, 1) CUP_FAST_CASE(2, 1) CUP_FAST_CASE(3, 1) CUP_FAST_CASE(4, 1)
    CUP_FAST_CASE(1, 2) CUP_FAST_CASE(2, 2) CUP_FAST_CASE(3, 2) CUP_FAST_CASE(4, 2)
  }
#undef CUP_FAST_CASE
  *st = CUP_FAST_DECLINED;
  return k;
}

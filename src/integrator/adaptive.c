/* adaptive — the event-driven scheme (adaptive_impl.h, docs/adaptive.md):
 * set-up, the energy bound and the late-switch model, the run's messages. */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <stddef.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include "catchup.h"
#include "adaptive.h"
#include "adaptive_impl.h"
#include "freestep.h"
#include "projector/choose.h"

static void *take(size_t count, size_t size, int *fail) {
  void *q = calloc(count ? count : 1, size);
  if (!q) *fail = 1;
  return q;
}

/* ||v||_inf <= pinf ||v||_P with pinf = 1 / sqrt(lambda_min(P)). */
static double p_to_inf(const cup_polyset *K) {
  int n = K->n;
  if (K->pkind == CUP_METRIC_IDENTITY) return 1;
  if (K->pkind == CUP_METRIC_DIAGONAL) {
    double dmin = INFINITY;
    for (int j = 0; j < n; j++) dmin = fmin(dmin, K->pd[j]);
    return 1 / sqrt(dmin);
  }
  gsl_matrix *P = gsl_matrix_calloc((size_t)n, (size_t)n);
  gsl_vector *ev = gsl_vector_alloc((size_t)n), *col = gsl_vector_alloc((size_t)n);
  gsl_eigen_symm_workspace *w = gsl_eigen_symm_alloc((size_t)n);
  double r = INFINITY;
  if (P && ev && col && w) {
    for (int j = 0; j < n; j++) {
      gsl_vector_set_zero(col);
      gsl_vector_set(col, (size_t)j, 1);
      polyset_metric_apply(K, col->data, ev->data);
      for (int i = 0; i < n; i++) gsl_matrix_set(P, (size_t)i, (size_t)j, ev->data[i]);
    }
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    if (gsl_eigen_symm(P, ev, w) == 0) r = 1 / sqrt(gsl_vector_min(ev));
    gsl_set_error_handler(old);
  }
  if (w) gsl_eigen_symm_free(w);
  if (col) gsl_vector_free(col);
  if (ev) gsl_vector_free(ev);
  if (P) gsl_matrix_free(P);
  return r;
}

static void dense_of(const la_sparse *S, int has, double *out, int ld) {
  if (!has) return;
  for (int j = 0; j < S->ncol; j++)
    for (int k = S->p[j]; k < S->p[j + 1]; k++) out[S->i[k] + (size_t)j * ld] = S->x[k];
}

/* The input's exosystem: the waveforms' of the terms live_terms kept
 * (input_impl.h), and the step limit of every sine, or for a callback
 * per component the Taylor states (u, u', ..., u^(q)) of the step's
 * interpolating polynomial, w_j' = w_{j+1}. */
static void exosystem(adaptive_ws *A) {
  int p = A->p, nw = A->nw;
  const cup_input *u = A->u;
  for (int k = 0; u && !A->callback && k < u->nterms; k++)   /* all terms: the steps of the whole input */
    if ((u->terms[k].kind == CUP_WAVE_SINE || u->terms[k].kind == CUP_WAVE_DAMPED_SINE) &&
        u->terms[k].omega > 0)
      A->hmax_input = fmin(A->hmax_input, M_PI / 4 / u->terms[k].omega);
  if (!A->nwu) return;
  if (A->callback) {
    for (int c = 0; c < p; c++) {
      int g = c * (AD_DEGREE + 1);
      A->U[c + (size_t)g * p] = 1;
      for (int j = 0; j < AD_DEGREE; j++) A->W[(g + j) + (size_t)(g + j + 1) * nw] = 1;
    }
    return;
  }
  const cup_input *gen = &A->gen;
  input_gen_output(gen, A->gen_rot, A->first_state, A->U, p);
  for (int k = 0; k < gen->nterms; k++) {        /* the rounding scale of the value states */
    const input_term *t = &gen->terms[k];
    if (A->gen_rot[k].base >= 0) continue;       /* (its base's states, at the base's amplitude) */
    double sc = fabs(t->value) + fabs(t->amp);
    if (t->kind == CUP_WAVE_PULSE) sc = fmax(fabs(t->value), fabs(t->value2));
    for (int j = 0; t->kind == CUP_WAVE_PWL && j < t->np; j++) sc = fmax(sc, fabs(t->v[j]));
    A->wscale[A->first_state[k]] = sc;
    if (t->kind == CUP_WAVE_SINE || t->kind == CUP_WAVE_DAMPED_SINE) A->wscale[A->first_state[k] + 1] = sc;
  }
  input_gen_dynamics(gen, A->gen_rot, A->first_state, A->W, nw);
  A->piece_from_t0 = input_gen_from_start(gen);
}

/* The built-in waveforms whose component a column of E (the drift) or of
 * G (the offset) reads, into A->gen with their exosystem's first states:
 * the others reach nothing the scheme integrates (a switch's gate source,
 * which the switched run reads from the input itself). On the full bridge
 * the four PULSE gates' 8 states made the flow 11 x 11 where 3 x 3 does
 * (L, C and the DC source). Breakpoints still come from the whole input
 * (A->u), and so does the step limit of a sine (exosystem). A constant 0
 * reaches nothing either: each SIN's VO makes one, and the six-pulse
 * bridge's three made its flow 11 x 11 where 8 x 8 does. Sines of one
 * frequency share one sine's two states (input_gen_rot_plan): its three
 * phases, 8 x 8 where 4 x 4 does. */
static int live_terms(adaptive_ws *A, const freestep_drift *D, const la_sparse *G, int *fail) {
  const cup_input *u = A->u;
  A->gen = (cup_input){.p = u ? u->p : 0};
  /* the terms, their rotations and first states in one zeroed block that
   * terms owns, sized for all the input's (a switched run makes one a
   * configuration: two callocs and two frees less) */
  size_t nt = u ? (size_t)u->nterms : 0;
  A->gen.terms = take(1, sizeof(input_term) * (nt ? nt : 1) + (sizeof(input_gen_rot) + sizeof(int)) * (nt + 1), fail);
  A->gen_whole = u != NULL;
  for (int k = 0; u && !*fail && k < u->nterms; k++) {
    const input_term *t = &u->terms[k];
    int q = t->comp;
    if (t->kind == CUP_WAVE_CONSTANT && t->value == 0) continue;   /* (a SIN's VO = 0: a state that stays 0) */
    if ((D->has_E && q < D->E.ncol && D->E.p[q + 1] > D->E.p[q]) || (G && q < G->ncol && G->p[q + 1] > G->p[q]))
      A->gen.terms[A->gen.nterms++] = *t;
    else
      A->gen_whole = 0;
  }
  if (*fail) return 0;
  A->gen_rot = (input_gen_rot *)(A->gen.terms + (nt ? nt : 1));
  A->first_state = (int *)(A->gen_rot + nt + 1);
  input_gen_rot_plan(&A->gen, A->gen_rot);
  return input_gen_dim(&A->gen, A->gen_rot, A->first_state);
}

/* D != 0: B and D dense, C B, the rows D couples; the late-switch model of
 * a row whose D_ii > 0 (its multiplier is a function, no impulse: switched
 * on late by delta it misses (1/2) delta^2 |s'| B_i / D_ii). */
static void dae_setup(adaptive_ws *A, const la_sparse *B, const la_sparse *Dm) {
  int n = A->n, m = A->m;
  dense_of(B, 1, A->Bd, n);
  dense_of(Dm, 1, A->Dd, m);
  for (int j = 0; j < m; j++)
    for (int i = 0; i < m; i++) {
      double acc = 0;
      for (int k = A->K->Ct.p[i]; k < A->K->Ct.p[i + 1]; k++)
        acc += A->K->Ct.x[k] * A->Bd[A->K->Ct.i[k] + (size_t)j * n];
      A->CB[i + (size_t)j * m] = acc;
      if (A->Dd[i + (size_t)j * m] != 0) A->dcpl[i] = A->dcpl[j] = 1;
    }
}

/* "step k (t = ...): " and the text into info->message. */
void ad_say(ad_run *R, const char *fmt, va_list ap) {
  cup_run_info *info = R->info;
  int len = snprintf(info->message, sizeof info->message, "step %ld (t = %.17g): ", R->steps, R->t);
  if (len >= 0 && (size_t)len < sizeof info->message)
    vsnprintf(info->message + len, sizeof info->message - (size_t)len, fmt, ap);
}

int ad_fail(ad_run *R, int status, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  ad_say(R, fmt, ap);
  va_end(ap);
  return R->info->status = status;
}

double ad_energy_bound(const adaptive_ws *A, const double *v, double *scratch) {
  polyset_metric_apply(A->K, v, scratch);
  return A->pinf * sqrt(fmax(0, la_dot(v, scratch, A->n)));
}

/* The late-switch error model per row (docs/adaptive.md), in the energy
 * bound: B_i, and A B_i / (C B)_ii (B_i / D_ii where D_ii > 0). */
static void switch_model(adaptive_ws *A) {
  const cup_polyset *K = A->K;
  int n = A->n, m = A->m;
  for (int i = 0; i < m; i++) {
    const double *b = A->has_D ? A->Bd + (size_t)i * n : K->Bt + (size_t)i * n;
    for (int r = 0; r < n; r++) {
      double acc = 0;
      for (int c = 0; c < n; c++) acc += A->A[r + (size_t)c * n] * b[c];
      A->xr[r] = acc;
    }
    double bn = ad_energy_bound(A, b, A->xf), abn = ad_energy_bound(A, A->xr, A->xf);
    A->cz[i] = bn;
    for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) A->c1[i] += fabs(K->Ct.x[k]);
    if (!A->has_D) {
      A->cs[i] = K->Md[i + (size_t)i * m] > 0 ? abn / K->Md[i + (size_t)i * m] : 0;
      continue;
    }
    double dii = A->Dd[i + (size_t)i * m], cb = A->CB[i + (size_t)i * m];
    A->cs[i] = dii > 0 ? bn / dii : cb > 0 ? abn / cb : 0;
  }
}

/* U's and G's nonzeros, for ad_offset (a step's g from the input's
 * states): U holds one 1 a waveform (a sine that shares another's states,
 * two factors), G the sources each row sees; on the
 * full bridge the dense products were 9 % of the run. */
static void offset_pattern(adaptive_ws *A) {
  int m = A->m, p = A->p, nw = A->nw, k = 0;
  for (int c = 0; c < nw; c++) {
    A->up[c] = k;
    for (int q = 0; q < p; q++)
      if (A->U[q + (size_t)c * p] != 0) { A->ui[k] = q; A->ux[k++] = A->U[q + (size_t)c * p]; }
  }
  A->up[nw] = k;
  k = 0;
  for (int i = 0; i < m; i++) {
    A->gp[i] = k;
    for (int q = 0; q < p; q++)
      if (A->G[i + (size_t)q * m] != 0) { A->gi[k] = q; A->gx[k++] = A->G[i + (size_t)q * m]; }
  }
  A->gp[m] = k;
  A->ngterm = 0;
  for (int t = 0; A->u && !A->u->fn && t < A->u->nterms; t++) {
    int q = A->u->terms[t].comp, live = 0;
    for (int i = 0; i < m; i++) live |= A->G[i + (size_t)q * m] != 0;
    if (live) A->gterm[A->ngterm++] = t;
  }
}

/* DC sources alone reach E and G (adaptive_impl.h's w_const): the
 * exosystem's states, u and g once, by the sums ad_inputs_on, ad_offset
 * and at_break make (the same bits at every time); likewise at_break's
 * g when the terms G reads are constants (gbrk_const). */
static void constant_inputs(adaptive_ws *A) {
  const cup_input *u = A->u;
  int w_const = !A->callback;
  for (int k = 0; w_const && k < A->gen.nterms; k++) w_const = A->gen.terms[k].kind == CUP_WAVE_CONSTANT;
  if (w_const) {
    if (A->nwu) input_gen_piece(&A->gen, A->first_state, A->gen_rot, 0, 0, A->wc);
    if (A->one >= 0) A->wc[A->one] = 1;
    ad_offset(A, A->wc, A->gc);                  /* (its sums: w_const is not set yet) */
    la_copy(A->uc, A->ut, A->p);
    A->w_const = 1;
  }
  A->gbrk_const = !A->callback;
  for (int q = 0; A->gbrk_const && u && q < A->ngterm; q++)
    A->gbrk_const = u->terms[A->gterm[q]].kind == CUP_WAVE_CONSTANT;
  if (!A->gbrk_const) return;
  if (u) input_eval_terms(u, A->gterm, A->ngterm, 0, A->ut);
  ad_offset_of(A, A->ut, A->gbrk);
  A->gc_brk = A->w_const && ad_same_bits(A->gc, A->gbrk, A->m);
}

/* Every matrix and vector of the run (its sizes set), from block b (block_take). */
static void vectors(adaptive_ws *A, block_arena *b) {
  int n = A->n, m = A->m, p = A->p, nw = A->nw, na = A->na;
  size_t NA = (size_t)na * na;
  A->A = block_take(b, (size_t)n * n, sizeof(double));
  A->E = block_take(b, (size_t)n * p, sizeof(double));
  A->G = block_take(b, (size_t)m * p, sizeof(double));
  A->U = block_take(b, (size_t)p * nw, sizeof(double));
  A->W = block_take(b, (size_t)nw * nw, sizeof(double));
  A->up = block_take(b, (size_t)nw + 1, sizeof(int));
  A->ui = block_take(b, (size_t)p * nw + 1, sizeof(int));
  A->ux = block_take(b, (size_t)p * nw + 1, sizeof(double));
  A->gp = block_take(b, (size_t)m + 1, sizeof(int));
  A->gi = block_take(b, (size_t)m * p + 1, sizeof(int));
  A->gx = block_take(b, (size_t)m * p + 1, sizeof(double));
  A->gterm = block_take(b, A->u && !A->u->fn ? (size_t)A->u->nterms + 1 : 1, sizeof(int));
  if (!A->scratch) A->ework = block_take(b, 7 * NA, sizeof(double));   /* (shared: scratch_carve's) */
  double **vecs_na[] = {&A->ya, &A->yb, &A->yt, &A->yr, &A->My, &A->fa, &A->fb, &A->yhi};
  for (size_t k = 0; k < sizeof vecs_na / sizeof *vecs_na; k++)
    *vecs_na[k] = block_take(b, (size_t)na, sizeof(double));
  double **vecs_m[] = {&A->ga, &A->gb, &A->gt, &A->da, &A->db, &A->dt, &A->ta, &A->tb, &A->tt,
                       &A->cz, &A->cs, &A->c1, &A->s, &A->gam, &A->g, &A->lcpq, &A->zero, &A->gk,
                       &A->gc, &A->gbrk};
  for (size_t k = 0; k < sizeof vecs_m / sizeof *vecs_m; k++)
    if (!A->scratch || vecs_m[k] != &A->lcpq) *vecs_m[k] = block_take(b, (size_t)m, sizeof(double));
  double **vecs_n[] = {&A->x, &A->xs, &A->xr, &A->xf, &A->e, &A->et, &A->xok};
  for (size_t k = 0; k < sizeof vecs_n / sizeof *vecs_n; k++)
    *vecs_n[k] = block_take(b, (size_t)n, sizeof(double));
  A->ut = block_take(b, (size_t)p, sizeof(double));
  A->uc = block_take(b, (size_t)p, sizeof(double));
  A->wc = block_take(b, (size_t)nw, sizeof(double));
  A->udot = block_take(b, (size_t)p, sizeof(double));
  A->uerr = block_take(b, (size_t)p, sizeof(double));
  A->wa = block_take(b, (size_t)nw, sizeof(double));
  A->wt = block_take(b, (size_t)nw, sizeof(double));
  A->piece_w = block_take(b, (size_t)nw, sizeof(double));
  A->wscale = block_take(b, (size_t)nw, sizeof(double));
  A->gscale = block_take(b, (size_t)m, sizeof(double));
  A->zw = block_take(b, (size_t)nw, sizeof(double));
  A->zy = block_take(b, (size_t)na, sizeof(double));
  A->xo = block_take(b, (size_t)n, sizeof(double));
  A->dy = block_take(b, 2 * (size_t)na, sizeof(double));
  A->erp = block_take(b, (size_t)na + 1, sizeof(int));
  A->erj = block_take(b, NA, sizeof(int));
  A->erx = block_take(b, NA, sizeof(double));
  A->xrp = block_take(b, (size_t)n + m + 1, sizeof(int));
  A->xrj = block_take(b, ((size_t)n + m) * na, sizeof(int));
  A->xrx = block_take(b, ((size_t)n + m) * na, sizeof(double));
  A->de = block_take(b, (size_t)na, sizeof(double));
  A->de2 = block_take(b, (size_t)na, sizeof(double));
  A->ed = block_take(b, (size_t)n, sizeof(double));
  A->pend.zy = block_take(b, (size_t)na, sizeof(double));
  A->pend.de = block_take(b, (size_t)na, sizeof(double));
  A->pend.y2 = block_take(b, (size_t)na, sizeof(double));
  A->pend.e2 = block_take(b, (size_t)n, sizeof(double));
  if (!A->scratch) {
    A->lcpM = block_take(b, (size_t)m * m, sizeof(double));
    A->touch = block_take(b, (size_t)m, 1);
  }
  if (A->has_D) {
    A->Bd = block_take(b, (size_t)n * m, sizeof(double));
    A->Dd = block_take(b, (size_t)m * m, sizeof(double));
    A->CB = block_take(b, (size_t)m * m, sizeof(double));
    A->dcpl = block_take(b, (size_t)m, 1);
    A->jseed = block_take(b, (size_t)m, 1);
  }
  if (A->o.output == CUP_OUTPUT_TOL) {           /* adaptive_outtol.c's (the other outputs' layout as it was; a
                                                   * configuration's own, not the shared scratch's) */
    size_t slot = 1 + 2 * (size_t)n + (size_t)na;
    A->opeak = block_take(b, (size_t)n, sizeof(double));
    A->pend.opk = block_take(b, (size_t)n, sizeof(double));
    A->othr = block_take(b, (size_t)n, sizeof(double));
    A->oxm = block_take(b, (size_t)n * na, sizeof(double));
    A->ostk = block_take(b, (AD_TOL_DEPTH + 3) * slot, sizeof(double));
    if (na <= AD_TOL_LEVELS_NA)                  /* (exp(2^-j h M) a halving level, and two to make them) */
      A->olev = block_take(b, (AD_TOL_DEPTH + 4) * NA, sizeof(double));
  }
  if (A->scratch) return;                         /* (shared: scratch_carve's) */
  A->samp = block_take(b, (size_t)p * (AD_DEGREE + 1), sizeof(double));
  A->samp_mid = block_take(b, (size_t)p * AD_DEGREE, sizeof(double));
  A->coef = block_take(b, 4 * (size_t)(AD_DEGREE + 1), sizeof(double));
  ad_scratch_layout(A, b);
}

/* The run's arrays in one block, zeroed as callocs were, but for the two
 * series' coefficients (each written before it is read): a switched run
 * makes its integrators as it goes, and each array was a calloc of its own
 * (some 280 a configuration on the full bridge). The series come first and
 * after the zeroed part, each starting on a page the set-up touches (the
 * block's header, the zeroed part), as their own mallocs did: not the
 * run's first use (3 page faults more in the six-pulse run else). A
 * switched run's configuration (made in the run) has the active sets'
 * slots last, not zeroed: that was some 70 % of the memset (16 k
 * instructions a configuration on the full bridge), and the pages of slots
 * no set is built in are never touched. A workspace of its own takes them
 * at its run's start (ad_modes_take: the six-pulse bridge's 12 pages of
 * them, laid out here before catchup-run made its file, faulted in fresh;
 * a malloc of their own in each configuration cost the full bridge 13 k
 * instructions). */
static void carve(adaptive_ws *A, block_arena *b, size_t *z0, size_t *z1) {
  if (!A->scratch) ad_series_layout(A, &A->sy, b);
  *z0 = b->used;
  vectors(A, b);
  *z1 = b->used;
  if (!A->scratch) ad_series_layout(A, &A->se, b);
  if (!A->scratch) return;
  A->slots = b->base ? b->base + b->used : NULL;
  ad_modes_layout(A, b);
}

/* A switched run's configurations run one window at a time: the scratch
 * of a window (what it writes before it reads: the exponentials', the
 * active sets' construction's and choice's (the velocity LCP; with D, the
 * candidates' checks, N and the jump's LCP), a callback input's
 * interpolation's, the step's flow series) is one block for
 * all of them, carved for the largest sizes and again for each one's own
 * (each array grows with n, m and na: a carve for smaller sizes fits in
 * it). Each configuration had its own, zeroed at its set-up: on the full
 * bridge 9 of them, in the run, some 4 KB and a page fault each. */
#define AD_SCRATCH_USERS 64        /* workspaces (switched.c's SW_MAX configurations) */
struct adaptive_scratch {
  void *block;
  int n, m, na, p, has_D;          /* the sizes it is carved for: its users' largest (with D's arrays
                                      when one has D) */
  int nuser;
  adaptive_ws *user[AD_SCRATCH_USERS];
  ad_window_state win;             /* the stop record and event-rate ring of the window under way */
  /* ad_mode_hmax's eigenvalue workspace (gsl's own allocations), for n
   * states: its first user's, which it owns from then on */
  gsl_eigen_nonsymm_workspace *eig;
  gsl_matrix *eigA;
  gsl_vector_complex *eigv;
  int eig_n;
};

/* The eigenvalue workspace: a shared scratch's when it has one for n
 * states (a switched run's configurations all have the run's), else A's
 * own (ad_modes_init), which the scratch then takes over. */
static int modes_init(adaptive_ws *A) {
  adaptive_scratch *s = A->scratch;
  if (s && s->eig && s->eig_n == A->n) {
    A->eig = s->eig, A->eigA = s->eigA, A->eigv = s->eigv;
    return CUP_OK;
  }
  int st = ad_modes_init(A);
  if (!st && s && !s->eig) s->eig = A->eig, s->eigA = A->eigA, s->eigv = A->eigv, s->eig_n = A->n;
  return st;
}

/* With D (adaptive_dae.c's ad_dae_init, its own callocs without a shared
 * scratch): the active sets' choice and check, the jump's LCP, N and its
 * SVD. */
static void dae_carve(adaptive_ws *A, block_arena *b) {
  int n = A->n, m = A->m, na = A->na;
  size_t MM = (size_t)m * m;
  double **mm[] = {&A->N, &A->Ninv, &A->svd_u, &A->svd_v};
  for (size_t k = 0; k < sizeof mm / sizeof *mm; k++) *mm[k] = block_take(b, MM, sizeof(double));
  A->jM = block_take(b, 4 * MM, sizeof(double));
  A->jq = block_take(b, 2 * (size_t)m, sizeof(double));
  A->Ry = block_take(b, (size_t)n * m, sizeof(double));
  A->Ym = block_take(b, ((size_t)m + 1) * na, sizeof(double));
  A->Zc = block_take(b, (size_t)m * n, sizeof(double));
  double **vm[] = {&A->svd_s, &A->svd_w, &A->dq0, &A->dq1, &A->sz, &A->eqr, &A->eqc, &A->cg, &A->cd, &A->cd2,
                   &A->cthr};
  for (size_t k = 0; k < sizeof vm / sizeof *vm; k++) *vm[k] = block_take(b, (size_t)m, sizeof(double));
  A->cy = block_take(b, (size_t)na, sizeof(double));
  A->cMy = block_take(b, (size_t)na, sizeof(double));
  A->jx = block_take(b, (size_t)n, sizeof(double));
}

/* A's scratch from b: the part its own block zeroed (its end in *z), then the series. */
static void scratch_carve(adaptive_ws *A, block_arena *b, size_t *z) {
  int na = A->na, m = A->m, p = A->p;
  ad_scratch_layout(A, b);
  A->ework = block_take(b, 7 * (size_t)na * na, sizeof(double));
  A->lcpM = block_take(b, (size_t)m * m, sizeof(double));
  A->lcpq = block_take(b, (size_t)m, sizeof(double));
  A->touch = block_take(b, (size_t)m, 1);
  A->samp = block_take(b, (size_t)p * (AD_DEGREE + 1), sizeof(double));
  A->samp_mid = block_take(b, (size_t)p * AD_DEGREE, sizeof(double));
  A->coef = block_take(b, 4 * (size_t)(AD_DEGREE + 1), sizeof(double));
  if (A->has_D) dae_carve(A, b);
  *z = b->used;
  ad_series_layout(A, &A->sy, b);
  ad_series_layout(A, &A->se, b);
}

static size_t scratch_point(adaptive_ws *A, adaptive_scratch *s) {
  block_arena b = {s->block, 0};
  size_t z;
  scratch_carve(A, &b, &z);
  return z;
}

/* A joins s: the block made (or made again, larger, for every user) to fit
 * A. The first is carved for as many states as the input can give any
 * configuration (each one's are some of its terms', live_terms, and D's
 * constant) and D's arrays: its pages past the part A uses are touched
 * by none (a buck-boost's second configuration, one input state more than
 * the first's, made it again in the run). That part is zeroed, as A's own
 * would have been; the rest is not, nor a block made again (each array is
 * written before it is read: a window's scratch is another's leftovers
 * already), and only the pages the windows use are touched. */
static int scratch_join(adaptive_ws *A, adaptive_scratch *s) {
  if (s->nuser == AD_SCRATCH_USERS) return CUP_ERR_NOMEM;   /* (switched.c makes no more) */
  int first = !s->block, n = A->n > s->n ? A->n : s->n, m = A->m > s->m ? A->m : s->m,
      na = A->na > s->na ? A->na : s->na, p = A->p > s->p ? A->p : s->p, has_D = A->has_D || s->has_D || first;
  if (first) {
    int bound = A->n + (A->callback ? A->p * (AD_DEGREE + 1) : input_gen_dim(A->u, NULL, NULL)) + 1;
    if (bound > na + 16) bound = na + 16;          /* (a wide input's room: address space alone) */
    if (bound > CUP_EXPONENTIAL_MAX_DIM) bound = CUP_EXPONENTIAL_MAX_DIM;
    if (bound > na) na = bound;
  }
  if (first || n > s->n || m > s->m || na > s->na || p > s->p || has_D > s->has_D) {
    int own[5] = {A->n, A->m, A->na, A->p, A->has_D};
    block_arena b = {0};
    size_t z;
    A->n = n, A->m = m, A->na = na, A->p = p, A->has_D = has_D;   /* (sized for the largest) */
    scratch_carve(A, &b, &z);
    A->n = own[0], A->m = own[1], A->na = own[2], A->p = own[3], A->has_D = own[4];
    void *blk = malloc(b.used);
    if (!blk) return CUP_ERR_NOMEM;
    free(s->block);
    s->block = blk;
    s->n = n, s->m = m, s->na = na, s->p = p, s->has_D = has_D;
    for (int k = 0; k < s->nuser; k++) scratch_point(s->user[k], s);
  }
  s->user[s->nuser++] = A;
  size_t z = scratch_point(A, s);
  if (first) memset(s->block, 0, z);
  return CUP_OK;
}

void adaptive_scratch_free(adaptive_scratch **s) {
  if (!s || !*s) return;
  if ((*s)->eig) gsl_eigen_nonsymm_free((*s)->eig);
  if ((*s)->eigA) gsl_matrix_free((*s)->eigA);
  if ((*s)->eigv) gsl_vector_complex_free((*s)->eigv);
  free((*s)->block);
  free(*s);
  *s = NULL;
}

static int alloc_block(adaptive_ws *A) {
  block_arena b = {0};
  size_t z0, z1;
  carve(A, &b, &z0, &z1);
  if (!(A->block = malloc(b.used))) return CUP_ERR_NOMEM;
  memset((char *)A->block + z0, 0, z1 - z0);
  b = (block_arena){A->block, 0};
  carve(A, &b, &z0, &z1);
  for (int s = 0; s <= AD_MODES; s++) {          /* (ws_new left the slots' scalars unset) */
    ad_mode *md = &A->modes[s];
    md->mask = 0, md->stamp = 0, md->nj = md->nz = 0;
    md->mnorm = md->snorm = md->hmax = 0;
    memset(md->hc, 0, sizeof md->hc);
    memset(md->cstamp, 0, sizeof md->cstamp);
  }
  return CUP_OK;
}

/* The stop record and event-rate ring A uses: w's. */
static void window_state(adaptive_ws *A, ad_window_state *w) {
  A->stop = &w->stop, A->zeno = w->zeno, A->zeno_row = w->zeno_row;
}

/* A workspace zeroed as a calloc's, but for the active sets' slots (3.8 KB:
 * their pointers are alloc_block's layout's, their scalars zeroed there)
 * and the record entries (1 KB, each written whole by adaptive_record.c's
 * room before one is read): of its 9.7 KB, the 4.8 KB that a switched run
 * zeroed again for each configuration (as rep stosb, some 4.8 k
 * instructions each under callgrind). */
static adaptive_ws *ws_new(int own_window) {
  adaptive_ws *A = malloc(sizeof *A + (own_window ? sizeof(ad_window_state) : 0));
  if (!A) return NULL;
  char *a = (char *)A;
  size_t m0 = offsetof(adaptive_ws, modes), m1 = m0 + sizeof A->modes;
  size_t r0 = offsetof(adaptive_ws, rec), r1 = r0 + sizeof A->rec;
  _Static_assert(offsetof(adaptive_ws, modes) + sizeof(((adaptive_ws *)0)->modes) <= offsetof(adaptive_ws, rec),
                 "ws_new: the slots come before the record entries");
  memset(a, 0, m0);
  memset(a + m1, 0, r0 - m1);
  memset(a + r1, 0, sizeof *A - r1);
  if (own_window) {                               /* (zeroed: a checkpoint writes the whole ring) */
    memset(A + 1, 0, sizeof(ad_window_state));
    window_state(A, (ad_window_state *)(A + 1));
  }
  return A;
}

int adaptive_create(adaptive_ws **out, const freestep_drift *D, const cup_polyset *K, const la_sparse *G,
                    const la_sparse *B, const la_sparse *Dm, const cup_input *u,
                    const cup_integrator_options *o, adaptive_scratch **scratch, char *errmsg) {
  *out = NULL;
  if (!K->dense)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED,
                    "adaptive scheme: %d rows and %d states exceed the dense limits (%d rows, %d states); "
                    "%s", K->m, K->n, CUP_DENSE_MAX_ROWS, CUP_DENSE_MAX_DIM, Dm
                    ? "with D != 0 (a diode whose current the state does not fix) no scheme runs it"
                    : "use a fixed-step scheme");
  if (o->f)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED,
                    "adaptive scheme: a perturbation f(t, x) is not supported (the scheme integrates "
                    "each active set's linear system exactly); use a fixed-step scheme");
  if (D->p > 0 && !u)
    return fail_fmt(errmsg, CUP_ERR_ARG, "the %s has %d input(s) but no input u(t) was given", D->what, D->p);
  if (u && D->p > 0 && cup_input_dim(u) != D->p)
    return fail_fmt(errmsg, CUP_ERR_DIM, "the input has %d component(s), the %s expects %d",
                    cup_input_dim(u), D->what, D->p);
  if (D->p > 0) {
    int st = input_gen_check(u, "adaptive", errmsg);
    if (st) return st;
  }
  adaptive_ws *A = ws_new(!scratch);
  if (scratch && !*scratch) *scratch = calloc(1, sizeof **scratch);
  if (!A || (scratch && !*scratch)) {
    free(A);
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "adaptive scheme: out of memory");
  }
  A->scratch = scratch ? *scratch : NULL;         /* (joined at the end: nothing here runs a window) */
  A->F = K->g0;
  A->u = D->p > 0 ? u : NULL;
  A->K = K;
  A->o = *o;
  A->tend = o->T;
  A->n = D->n; A->m = K->m; A->p = D->p;
  A->callback = A->u && A->u->fn;
  A->has_D = Dm != NULL;
  int fail = 0, n = A->n, m = A->m, p = A->p;
  A->nwu = A->nw = A->callback ? p * (AD_DEGREE + 1) : live_terms(A, D, G, &fail);
  A->held = A->callback ? A->u : &A->gen;
  A->one = -1;
  for (int i = 0; A->has_D && i < m && A->one < 0; i++)
    if (K->g0[i] != 0) A->one = A->nw++;         /* F reaches the multipliers through D: a constant state */
  int nw = A->nw, na = A->na = n + nw;
  if (!fail && na > CUP_EXPONENTIAL_MAX_DIM) {
    adaptive_free(&A);
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED,
                    "adaptive scheme: %d states plus %d input generator states exceed the dense limit %d; "
                    "use a fixed-step scheme", n, nw, CUP_EXPONENTIAL_MAX_DIM);
  }
  if (A->scratch) window_state(A, &A->scratch->win);
  if (fail || alloc_block(A) || modes_init(A) || lcp_init(&A->lcp, m) || (A->has_D && ad_dae_init(A))) {
    adaptive_free(&A);
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "adaptive scheme: out of memory");
  }
  if (lcp_step_init(&A->proj, K, NULL, 1)) {   /* K is dense: only memory can fail */
    adaptive_free(&A);
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "adaptive scheme: out of memory");
  }
  cup_projector_options po = o->proj;             /* exact, certified relative to the scale */
  po.eps_abs = po.eta_abs = 0;
  po.eps_rel = 1e-12;
  po.eta_rel = 1e-10;
  po = proj_backup_options(K, &po);                /* one LCP onto K: A->proj */
  int st = cup_projector_create(&A->projector, K, &po, errmsg);
  if (st) { adaptive_free(&A); return st; }
  dense_of(&D->A, D->has_A, A->A, n);
  dense_of(&D->E, D->has_E, A->E, n);
  if (G) dense_of(G, 1, A->G, m);
  A->hmax_input = o->T / 8;
  exosystem(A);
  offset_pattern(A);
  if (A->one >= 0) A->wscale[A->one] = 1;
  constant_inputs(A);
  for (int i = 0; i < m; i++)                    /* g's rounding scale: sum |G_iq| |u_q| at most */
    for (int c = 0; c < nw; c++)
      for (int q = 0; q < p; q++)
        A->gscale[i] += fabs(A->G[i + (size_t)q * m] * A->U[q + (size_t)c * p]) * A->wscale[c];
  for (int j = 0; j <= AD_DEGREE; j++) A->node[j] = 0.5 * (1 - cos(M_PI * j / AD_DEGREE));
  A->pinf = p_to_inf(K);
  if (A->has_D) dae_setup(A, B, Dm);
  switch_model(A);
  if (A->scratch && scratch_join(A, A->scratch)) {
    adaptive_free(&A);
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "adaptive scheme: out of memory");
  }
  *out = A;
  return CUP_OK;
}

void adaptive_wall_limit(adaptive_ws *A, double seconds) { A->o.max_wall_seconds = seconds; }

void adaptive_on_step(adaptive_ws *A, cup_step_fn fn, void *ctx) {
  A->o.on_step = fn;
  A->o.step_ctx = ctx;
}

void adaptive_seed(adaptive_ws *A, int on) {
  A->seed_on = on;
  A->seed = 0;
}

void adaptive_tol_share(adaptive_ws *A, const adaptive_ws *from) {
  if (A && from && A->opeak && from->opeak) A->opeak = from->opeak;   /* (from's block holds them: it lives as long) */
}

void adaptive_tol_reset(adaptive_ws *A) {
  if (A && A->opeak) la_zero(A->opeak, A->n);
}

void adaptive_hold_end(adaptive_ws *A, int on) {
  A->hold_end = on;
  A->held_end = 0;
}

int adaptive_held(adaptive_ws *A) {
  int h = A->held_end;
  A->held_end = 0;
  return h;
}

void adaptive_free(adaptive_ws **Ap) {
  if (!Ap || !*Ap) return;
  adaptive_ws *A = *Ap;
  if (!A->scratch || A->eig != A->scratch->eig) ad_modes_free(A);   /* (else the scratch's) */
  if (A->has_D) ad_dae_free(A);
  lcp_free(&A->lcp);
  lcp_step_free(&A->proj);
  cup_projector_free(&A->projector);
  free(A->gen.terms); free(A->block);             /* (gen_rot, first_state in terms' block) */
  if (!A->scratch) free(A->slots);
  free(A->tan);
  free(A->rec_block);
  free(A->put_block);
  free(A);
  *Ap = NULL;
}

const double *adaptive_state(const adaptive_ws *A) { return A ? A->x : NULL; }

int adaptive_tangent(adaptive_ws *A, int on) {
  if (on && A->has_D) return CUP_ERR_UNSUPPORTED;
  if (!on) {
    free(A->tan);
    A->tan = NULL;
    return CUP_OK;
  }
  if (!A->tan && !(A->tan = calloc((size_t)A->n * (size_t)A->n + 1, sizeof(double)))) return CUP_ERR_NOMEM;
  return CUP_OK;
}

const double *adaptive_tangent_matrix(const adaptive_ws *A) { return A->tan; }

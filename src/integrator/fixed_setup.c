/* fixed_setup — the fixed-step schemes (explicit, implicit, exponential,
 * theta; fixed.c runs them) set up once on the grid t_k = k T / n: the free
 * step, the projector or the exact LCP step, the buffers, the estimate's
 * run at n/2; and what the driver asks of them between runs (state, zeta,
 * their part of a checkpoint, free). Their workspace is a fixed_ws
 * (fixed_impl.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "fixed_setup.h"
#include "options.h"
#include "integrator_impl.h"
#include "fixed_impl.h"
#include "model/lcs_impl.h"
#include "set/polyset_impl.h"
#include "set/set_impl.h"
#include "projector/projector.h"
#include "projector/choose.h"
#include "util/fail.h"

/* Of the fixed-step schemes only the theta step's LCP takes D: the
 * catching-up schemes project onto K(t) = {C x + G u + F >= 0}, which
 * exists only when D = 0, and an active network (B kept as given) only
 * theta (adaptive_scheme.c checks the adaptive scheme's part). */
static int needs_theta(const cup_lcs *L, cup_scheme scheme, char *errmsg) {
  if (!L->has_D || scheme == CUP_SCHEME_THETA) return CUP_OK;
  if (L->keep_B)
    return lcs_needs_reciprocal(cup_scheme_name(scheme), "it projects in the energy metric P", errmsg);
  int *rows = calloc((size_t)L->m + 1, sizeof(int)), k = 0;
  unsigned char *used = calloc((size_t)L->m + 1, 1);
  if (!rows || !used) { free(rows); free(used); return fail_fmt(errmsg, CUP_ERR_NOMEM, "integrator: out of memory"); }
  for (int j = 0; j < L->m; j++)
    for (int q = L->D.p[j]; q < L->D.p[j + 1]; q++)
      if (L->D.x[q] != 0) used[L->D.i[q]] = used[j] = 1;
  for (int i = 0; i < L->m; i++) if (used[i]) rows[k++] = i;
  char text[128], what[160];
  lcs_rows_text(L, rows, k, text, sizeof text);
  free(rows); free(used);
  /* theta and the adaptive scheme, the two that take D != 0, are dense:
   * beyond their limits no scheme runs it, and the advice says so */
  if (L->m <= CUP_DENSE_MAX_ROWS && L->n <= CUP_DENSE_MAX_DIM)
    snprintf(what, sizeof what, "use the theta or the adaptive scheme");
  else
    snprintf(what, sizeof what, "no scheme runs it: theta and the adaptive scheme, which take D != 0, are dense "
             "(at most %d rows and %d states; this has %d and %d)", CUP_DENSE_MAX_ROWS, CUP_DENSE_MAX_DIM, L->m, L->n);
  return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED, "the %s scheme needs D = 0 (it projects onto K(t) = {C x + G u "
                  "+ F >= 0}, which D != 0 does not define); %s %s D != 0 (a diode whose current the state does "
                  "not fix): %s", cup_scheme_name(scheme), text, k == 1 ? "has" : "have", what);
}

/* The theta step; an LCS with D != 0 gives it B and D as dense arrays. */
static int theta_step_init(fixed_ws *F, const double *W, double theta, char *errmsg) {
  const cup_lcs *L = F->L;
  int n = F->n, m = F->m, st = CUP_OK;
  double *B = NULL, *D = NULL;
  if (L && L->has_D) {
    B = calloc((size_t)n * m + 1, sizeof(double));
    D = calloc((size_t)m * m + 1, sizeof(double));
    if (!B || !D) st = CUP_ERR_NOMEM;
    for (int j = 0; !st && j < m; j++) {
      for (int k = L->B.p[j]; k < L->B.p[j + 1]; k++) B[L->B.i[k] + (size_t)j * n] = L->B.x[k];
      for (int k = L->D.p[j]; k < L->D.p[j + 1]; k++) D[L->D.i[k] + (size_t)j * m] = L->D.x[k];
    }
  }
  if (!st) st = lcp_step_init_bd(&F->th, F->K, W, F->h, B, D, theta);
  free(B);
  free(D);
  return st ? fail_fmt(errmsg, CUP_ERR_NOMEM, "theta scheme: out of memory") : CUP_OK;
}

/* The polyset path: the projector, and the exact LCP step where it is
 * cheaper or the scheme needs it. */
static int polyset_setup(fixed_ws *F, char *errmsg) {
  const cup_integrator_options *o = &F->o;
  int st = CUP_OK;
  /* The theta step with W = I is the P-projection of the explicit free
   * point, solved exactly by principal pivoting on the m x m dual: for a
   * small dense set that is what the auto projector would do, certified the
   * same way, in fewer operations (70 against 107 ns a step on the paper's
   * circuit). The projector decides (a user's feasible point keeps it). */
  F->use_theta = o->scheme == CUP_SCHEME_THETA ||
                 (o->scheme == CUP_SCHEME_EXPLICIT && proj_small_lcp(F->K, &o->proj));
  if (F->use_theta && !F->K->dense)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED,
                    "theta scheme: %d rows and %d states exceed the dense limits (%d rows, %d states); "
                    "%s", F->K->m, F->K->n, CUP_DENSE_MAX_ROWS, CUP_DENSE_MAX_DIM, F->L && F->L->has_D
                    ? "with D != 0 (a diode whose current the state does not fix) no scheme runs it"
                    : "use the explicit, implicit or exponential scheme");
  if (F->use_theta) {
    double *W = F->fs.W, *eye = NULL;
    if (!W) {
      eye = calloc((size_t)F->n * (size_t)F->n, sizeof(double));
      if (!eye) return fail_fmt(errmsg, CUP_ERR_NOMEM, "integrator: out of memory");
      for (int j = 0; j < F->n; j++) eye[j + (size_t)j * F->n] = 1;
      W = eye;
    }
    st = theta_step_init(F, W, o->scheme == CUP_SCHEME_THETA ? o->theta : 0, errmsg);
    free(eye);
  }
  return st;
}

/* The terms of a waveform input that move the set (their input has a
 * column in G), when some do not (a switch's gate source moves none): the
 * offset's input evaluates those alone (fixed.c's moving_offset). */
static int offset_terms(fixed_ws *F) {
  const cup_input *u = F->u;
  if (!u || u->fn || !F->G || F->G->ncol != u->p) return 0;
  int live = 0;
  for (int k = 0; k < u->nterms; k++) live += F->G->p[u->terms[k].comp + 1] > F->G->p[u->terms[k].comp];
  if (live == u->nterms) return 0;
  F->gterms = malloc(sizeof(int) * ((size_t)live + 1));
  if (!F->gterms) return 1;
  for (int k = 0; k < u->nterms; k++)
    if (F->G->p[u->terms[k].comp + 1] > F->G->p[u->terms[k].comp]) F->gterms[F->ngterms++] = k;
  return 0;
}

/* Everything but the model: buffers, the free step, the projection. */
static int setup(fixed_ws *F, const freestep_drift *D, const cup_process_desc *pd, char *errmsg) {
  const cup_integrator_options *o = &F->o;
  F->h = o->T / (double)o->n;
  F->kend = o->n;
  F->eps_n = cup_schedule_value(&o->eps, o->n);
  F->eta_n = cup_schedule_value(&o->eta, o->n);
  size_t N = (size_t)F->n, M = (size_t)F->m + 1, P = (size_t)F->p + 1;
  F->x = calloc(N, sizeof(double));
  F->xnew = calloc(N, sizeof(double));
  F->xf = calloc(N, sizeof(double));
  F->g = calloc(M, sizeof(double));
  F->ut = calloc(P, sizeof(double));
  F->s0 = calloc(M, sizeof(double));
  F->sg = calloc(M, sizeof(double));
  F->v = calloc(2 * N, sizeof(double));
  F->xs = calloc(N, sizeof(double));
  F->zprev = calloc(M, sizeof(double));
  F->zs = 1;
  if (!F->x || !F->xnew || !F->xf || !F->g || !F->ut || !F->s0 || !F->sg || !F->v || !F->xs || !F->zprev)
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "integrator: out of memory");
  if (offset_terms(F)) return fail_fmt(errmsg, CUP_ERR_NOMEM, "integrator: out of memory");
  if (o->scheme == CUP_SCHEME_THETA && !F->K)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED,
                    "theta scheme: the set is a %s; the theta step solves an LCP on a polyset's rows "
                    "(use the explicit, implicit or exponential scheme)", cup_set_kind_name(F->S->kind));
  int st = freestep_init(&F->fs, D, F->K, F->u, o->scheme, o->theta, F->h, o->f_order, errmsg);
  if (!st) st = freestep_add_rhs(&F->fs, o->f, o->f_ctx);
  if (!st && pd) st = freestep_add_rhs(&F->fs, pd->f, pd->f_ctx);
  if (!st && pd) freestep_set_rhs_integral(&F->fs, pd->f_integral, pd->f_integral_ctx);
  if (!st && F->K) st = polyset_setup(F, errmsg);
  /* the paper's tolerances are absolute; a zero schedule asks for the exact
   * projection, certified relative to the problem's scale */
  cup_projector_options po = o->proj;
  po.eps_abs = F->eps_n;
  po.eps_rel = F->eps_n > 0 ? 0 : 1e-12;
  po.eta_abs = F->eta_n;
  po.eta_rel = F->eta_n > 0 ? 0 : 1e-10;
  if (!st && F->use_theta) po = proj_backup_options(F->K, &po);   /* one LCP: the step's */
  if (!st && F->K) st = cup_projector_create(&F->proj, F->K, &po, errmsg);
  if (!st && !F->K) st = cup_setproj_create(&F->sp, F->S, &po, errmsg);
  if (st) return st;
  F->h_rho = freestep_h_rho(D, F->h);
  F->split = freestep_splitting(&F->fs, &F->split_row);
  if (F->K && (st = splitcheck_init(&F->chk, &F->fs, F->K, errmsg))) return st;
  if (F->K)
    faststep_init(&F->fast, &F->fs, &F->th, F->K, F->fixed || !F->u ? NULL : F->G, F->g, F->use_theta,
                  F->eps_n, F->eta_n, o->n, o->T);
  return CUP_OK;
}

/* The step-doubling estimate: the same model and scheme at n/2 (borrowing
 * this workspace's model), keeping its states where the two grids meet
 * (estimate.h). */
static int create_half(fixed_ws *F, const freestep_drift *D, const cup_process_desc *pd, char *errmsg) {
  cup_integrator_options h = F->o;
  h.n = F->o.n / 2;
  h.estimate = 0;
  h.on_step = NULL;
  if (estimate_init(&F->est, F->o.n, F->n) || estimate_samples(&F->est, &F->o) ||
      !(F->x0 = calloc((size_t)F->n, sizeof(double))))
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "error estimate: out of memory");
  h.output = CUP_OUTPUT_EVERY;
  h.output_every = estimate_stride(&F->est);
  int st = options_check(&h, errmsg);
  if (st) return st;
  fixed_ws *H = F->half = calloc(1, sizeof *H);
  if (!H) return fail_fmt(errmsg, CUP_ERR_NOMEM, "integrator: out of memory");
  H->o = h;
  H->u = F->u;
  H->L = F->L;                                   /* the theta step takes D from it */
  H->n = F->n; H->m = F->m; H->p = F->p;
  H->S = F->S; H->K = F->K; H->G = F->G; H->fixed = F->fixed;
  return setup(H, D, pd, errmsg);
}

int fixed_create(cup_integrator *I, const scheme_model *md, void **ws, char *errmsg) {
  fixed_ws *F = *ws = calloc(1, sizeof *F);
  if (!F) return fail_fmt(errmsg, CUP_ERR_NOMEM, "integrator: out of memory");
  F->o = I->o;                                   /* the model, as the front door checked it */
  F->u = md->u;
  F->L = md->L;
  F->n = I->n; F->m = I->m; F->p = I->p;
  F->S = I->S; F->K = md->K; F->G = md->G; F->fixed = I->fixed;
  int st = md->L ? needs_theta(md->L, F->o.scheme, errmsg) : CUP_OK;
  if (st) return st;
  if (!F->S) {                                   /* an LCS: its polyset as a set */
    st = set_wrap_polyset(&F->S_own, F->K, F->G, F->p, errmsg);
    F->S = F->S_own;
  }
  if (!st) st = setup(F, md->D, md->pd, errmsg);
  if (!st && F->o.estimate) st = create_half(F, md->D, md->pd, errmsg);
  return st;
}

void fixed_free(void *ws) {
  fixed_ws *F = ws;
  if (F->half) fixed_free(F->half);              /* the estimate's: its model borrowed */
  estimate_free(&F->est);
  freestep_free(&F->fs);
  splitcheck_free(&F->chk);
  cup_projector_free(&F->proj);
  cup_setproj_free(&F->sp);
  cup_set_free(&F->S_own);
  if (F->use_theta) lcp_step_free(&F->th);
  free(F->x); free(F->xnew); free(F->xf); free(F->g); free(F->ut); free(F->s0); free(F->sg); free(F->v);
  free(F->xs); free(F->zprev); free(F->gterms);
  free(F->x0);
  free(F);
}

void integrator_split_reset(cup_integrator *const *child, int count) {
  for (int c = 0; c < count; c++)
    if (child[c]) splitcheck_reset(&((fixed_ws *)child[c]->ws)->chk);
}

void integrator_split_verdict(cup_integrator *const *child, int count, cup_run_info *info) {
  splitcheck all = {0};
  const fixed_ws *F = NULL;
  for (int c = 0; c < count; c++)
    if (child[c]) splitcheck_merge(&all, &(F = child[c]->ws)->chk);
  if (F) splitcheck_verdict(&all, F->o.scheme, F->o.n, info);
}

const double *fixed_state(const void *ws) { return ((const fixed_ws *)ws)->x; }

void fixed_grid(const void *ws, scheme_grid *g) {
  const fixed_ws *F = ws;
  *g = (scheme_grid){F->h, F->eps_n, F->eta_n, F->use_theta};
}

/* The LCP's lambda is zeta itself (H = h W B); the projector's multipliers
 * are the impulse of the step, h zeta. A process on a polyset has them as
 * an LCS (its normal cone is P^-1 C^T zeta, B = P^-1 C^T); on another set
 * there are no rows to give them of. */
int fixed_zeta(void *ws, double *zeta) {
  const fixed_ws *F = ws;
  if (!F->K) return CUP_ERR_UNSUPPORTED;
  if (F->zeta_from == 1 && !(F->zs < 1 && F->zprev)) {   /* the LCP step's, on a step: a theta run's records */
    for (int i = 0; i < F->m; i++) zeta[i] = F->th.lcp.lam[i];   /* (1 * lam below: the same) */
    return CUP_OK;
  }
  const double *lam = F->zeta_from == 1 ? F->th.lcp.lam : F->zeta_from == 2 ? cup_projector_lambda(F->proj)
                    : F->zeta_from == 3 ? F->zeta_ext : NULL;
  double s = F->zeta_from == 2 ? 1 / F->h : 1;
  for (int i = 0; i < F->m; i++) zeta[i] = lam ? s * lam[i] : 0;
  if (F->zs < 1 && F->zprev)                     /* a sample between two steps */
    for (int i = 0; i < F->m; i++) zeta[i] = F->zprev[i] + F->zs * (zeta[i] - F->zprev[i]);
  return CUP_OK;
}

/* ---- checkpoints (checkpoint.c writes the header) ---------------------------------- */

/* A run on a polyset can resume: another set's projections keep state
 * (a crowd's rows, an oracle's) that no checkpoint holds. */
int fixed_saves(const void *ws) { return !((const fixed_ws *)ws)->sp; }

int fixed_stopped(const void *ws, cup_run_info *info) {
  const fixed_ws *F = ws;
  if (F->stop.phase == CUP_STOP_NONE) return 0;
  info->status = F->stop.status;
  memcpy(info->message, F->stop.message, sizeof info->message);
  return 1;
}

/* Where the run stopped, x_k (and x_{k-1}, zeta_{k-1} for a sample between
 * steps), the estimate's x0 and its comparisons so far, the projector's
 * and the LCP step's warm starts. */
void fixed_checkpoint(void *ws, ckpt *c) {
  fixed_ws *F = ws;
  fixed_stop *s = &F->stop;
  CUP_CKPT_IO(c, s->phase);
  CUP_CKPT_IO(c, s->k);
  CUP_CKPT_IO(c, s->next_j);
  CUP_CKPT_IO(c, F->zeta_from);
  CUP_CKPT_IO(c, F->jump);
  ckpt_io(c, F->x, sizeof(double) * (size_t)F->n);
  if (F->o.output == CUP_OUTPUT_SAMPLES) {      /* a sample between steps k - 1 and k: x_{k-1}, zeta_{k-1} */
    ckpt_io(c, F->xnew, sizeof(double) * (size_t)F->n);
    if (F->zprev) ckpt_io(c, F->zprev, sizeof(double) * (size_t)F->m);
  }
  if (F->half) {
    ckpt_io(c, F->x0, sizeof(double) * (size_t)F->n);
    CUP_CKPT_IO(c, F->est.err);
  }
  if (F->chk.on) {                               /* the splitting check's sums so far (splitcheck.h) */
    splitcheck *k = &F->chk;
    ckpt_io(c, k->e, sizeof(double) * (size_t)k->n);
    CUP_CKPT_IO(c, k->live); CUP_CKPT_IO(c, k->emax); CUP_CKPT_IO(c, k->peak);
    CUP_CKPT_IO(c, k->worst); CUP_CKPT_IO(c, k->tworst); CUP_CKPT_IO(c, k->first); CUP_CKPT_IO(c, k->tfirst);
  }
  projector_checkpoint(F->proj, c);
  if (F->use_theta) lcp_step_checkpoint(&F->th, c);
}

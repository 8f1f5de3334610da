/* fixed_setup — the fixed-step schemes (explicit, implicit, exponential,
 * theta; fixed.c runs them) set up once on the grid t_k = k T / n: the free
 * step, the projector or the exact LCP step, the buffers, the estimate's
 * run at n/2; and what the driver asks of them between runs (state, zeta,
 * their part of a checkpoint, free). Their workspace is the integrator. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "fixed_setup.h"
#include "options.h"
#include "integrator_impl.h"
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
  char text[128];
  lcs_rows_text(L, rows, k, text, sizeof text);
  free(rows); free(used);
  return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED, "the %s scheme needs D = 0 (it projects onto K(t) = {C x + G u "
                  "+ F >= 0}, which D != 0 does not define); %s %s D != 0 (a diode whose current the state does "
                  "not fix): use the theta or the adaptive scheme", cup_scheme_name(scheme), text,
                  k == 1 ? "has" : "have");
}

/* The theta step; an LCS with D != 0 gives it B and D as dense arrays. */
static int theta_step_init(cup_integrator *I, const double *W, double theta, char *errmsg) {
  const cup_lcs *L = I->L;
  int n = I->n, m = I->m, st = CUP_OK;
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
  if (!st) st = lcp_step_init_bd(&I->th, I->K, W, I->h, B, D, theta);
  free(B);
  free(D);
  return st ? fail_fmt(errmsg, CUP_ERR_NOMEM, "theta scheme: out of memory") : CUP_OK;
}

/* The polyset path: the projector, and the exact LCP step where it is
 * cheaper or the scheme needs it. */
static int polyset_setup(cup_integrator *I, char *errmsg) {
  const cup_integrator_options *o = &I->o;
  int st = CUP_OK;
  /* The theta step with W = I is the P-projection of the explicit free
   * point, solved exactly by principal pivoting on the m x m dual: for a
   * small dense set that is what the auto projector would do, certified the
   * same way, in fewer operations (70 against 107 ns a step on the paper's
   * circuit). The projector decides (a user's feasible point keeps it). */
  I->use_theta = o->scheme == CUP_SCHEME_THETA ||
                 (o->scheme == CUP_SCHEME_EXPLICIT && proj_small_lcp(I->K, &o->proj));
  if (I->use_theta && !I->K->dense)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED,
                    "theta scheme: %d rows and %d states exceed the dense limits (%d rows, %d states); "
                    "use the explicit, implicit or exponential scheme", I->K->m, I->K->n, CUP_DENSE_MAX_ROWS,
                    CUP_DENSE_MAX_DIM);
  if (I->use_theta) {
    double *W = I->fs.W, *eye = NULL;
    if (!W) {
      eye = calloc((size_t)I->n * (size_t)I->n, sizeof(double));
      if (!eye) return fail_fmt(errmsg, CUP_ERR_NOMEM, "integrator: out of memory");
      for (int j = 0; j < I->n; j++) eye[j + (size_t)j * I->n] = 1;
      W = eye;
    }
    st = theta_step_init(I, W, o->scheme == CUP_SCHEME_THETA ? o->theta : 0, errmsg);
    free(eye);
  }
  return st;
}

/* Everything but the model: buffers, the free step, the projection. */
static int setup(cup_integrator *I, const freestep_drift *D, const cup_process_desc *pd, char *errmsg) {
  const cup_integrator_options *o = &I->o;
  I->h = o->T / (double)o->n;
  I->kend = o->n;
  I->eps_n = cup_schedule_value(&o->eps, o->n);
  I->eta_n = cup_schedule_value(&o->eta, o->n);
  size_t N = (size_t)I->n, M = (size_t)I->m + 1, P = (size_t)I->p + 1;
  I->x = calloc(N, sizeof(double));
  I->xnew = calloc(N, sizeof(double));
  I->xf = calloc(N, sizeof(double));
  I->g = calloc(M, sizeof(double));
  I->ut = calloc(P, sizeof(double));
  I->s0 = calloc(M, sizeof(double));
  I->sg = calloc(M, sizeof(double));
  I->v = calloc(2 * N, sizeof(double));
  I->xs = calloc(N, sizeof(double));
  I->zprev = calloc(M, sizeof(double));
  I->zs = 1;
  if (!I->x || !I->xnew || !I->xf || !I->g || !I->ut || !I->s0 || !I->sg || !I->v || !I->xs || !I->zprev)
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "integrator: out of memory");
  if (o->scheme == CUP_SCHEME_THETA && !I->K)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED,
                    "theta scheme: the set is a %s; the theta step solves an LCP on a polyset's rows "
                    "(use the explicit, implicit or exponential scheme)", cup_set_kind_name(I->S->kind));
  int st = freestep_init(&I->fs, D, I->K, I->u, o->scheme, o->theta, I->h, o->f_order, errmsg);
  if (!st) st = freestep_add_rhs(&I->fs, o->f, o->f_ctx);
  if (!st && pd) st = freestep_add_rhs(&I->fs, pd->f, pd->f_ctx);
  if (!st && pd) freestep_set_rhs_integral(&I->fs, pd->f_integral, pd->f_integral_ctx);
  if (!st && I->K) st = polyset_setup(I, errmsg);
  /* the paper's tolerances are absolute; a zero schedule asks for the exact
   * projection, certified relative to the problem's scale */
  cup_projector_options po = o->proj;
  po.eps_abs = I->eps_n;
  po.eps_rel = I->eps_n > 0 ? 0 : 1e-12;
  po.eta_abs = I->eta_n;
  po.eta_rel = I->eta_n > 0 ? 0 : 1e-10;
  if (!st && I->use_theta) po = proj_backup_options(I->K, &po);   /* one LCP: the step's */
  if (!st && I->K) st = cup_projector_create(&I->proj, I->K, &po, errmsg);
  if (!st && !I->K) st = cup_setproj_create(&I->sp, I->S, &po, errmsg);
  if (st) return st;
  I->h_rho = freestep_h_rho(D, I->h);
  I->split = freestep_splitting(&I->fs, &I->split_row);
  if (I->K)
    faststep_init(&I->fast, &I->fs, &I->th, I->K, I->fixed || !I->u ? NULL : I->G, I->g, I->use_theta,
                  I->eps_n, I->eta_n, o->n, o->T);
  return CUP_OK;
}

/* The step-doubling estimate: the same model and scheme at n/2 (borrowing
 * this integrator's model), keeping its states where the two grids meet
 * (estimate.h). */
static int create_half(cup_integrator *I, const freestep_drift *D, const cup_process_desc *pd, char *errmsg) {
  cup_integrator_options h = I->o;
  h.n = I->o.n / 2;
  h.estimate = 0;
  h.on_step = NULL;
  if (estimate_init(&I->est, I->o.n, I->n) || !(I->x0 = calloc((size_t)I->n, sizeof(double))))
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "error estimate: out of memory");
  h.output = CUP_OUTPUT_EVERY;
  h.output_every = estimate_stride(&I->est);
  int st;
  cup_integrator *H = I->half = integrator_new(&h, errmsg, &st);
  if (!H) return st;
  H->u = I->u;
  H->L = I->L;                                   /* the theta step takes D from it */
  H->n = I->n; H->m = I->m; H->p = I->p;
  H->S = I->S; H->K = I->K; H->G = I->G; H->fixed = I->fixed;
  return setup(H, D, pd, errmsg);
}

int fixed_create(cup_integrator *I, const scheme_model *md, void **ws, char *errmsg) {
  *ws = I;
  int st = md->L ? needs_theta(md->L, I->o.scheme, errmsg) : CUP_OK;
  if (st) return st;
  if (!I->S) {                                   /* an LCS: its polyset as a set */
    st = set_wrap_polyset(&I->S_own, I->K, I->G, I->p, errmsg);
    I->S = I->S_own;
  }
  if (!st) st = setup(I, md->D, md->pd, errmsg);
  if (!st && I->o.estimate) st = create_half(I, md->D, md->pd, errmsg);
  return st;
}

void fixed_free(void *ws) {
  cup_integrator *I = ws;
  if (I->half) {                                 /* the estimate's: its model borrowed */
    fixed_free(I->half);
    free(I->half);
    I->half = NULL;
  }
  estimate_free(&I->est);
  freestep_free(&I->fs);
  cup_projector_free(&I->proj);
  cup_setproj_free(&I->sp);
  cup_set_free(&I->S_own);
  if (I->use_theta) lcp_step_free(&I->th);
  free(I->x); free(I->xnew); free(I->xf); free(I->g); free(I->ut); free(I->s0); free(I->sg); free(I->v);
  free(I->xs); free(I->zprev);
  free(I->x0);
}

const double *fixed_state(const void *ws) { return ((const cup_integrator *)ws)->x; }

/* The LCP's lambda is zeta itself (H = h W B); the projector's multipliers
 * are the impulse of the step, h zeta. A process on a polyset has them as
 * an LCS (its normal cone is P^-1 C^T zeta, B = P^-1 C^T); on another set
 * there are no rows to give them of. */
int fixed_zeta(void *ws, double *zeta) {
  const cup_integrator *I = ws;
  if (!I->K) return CUP_ERR_UNSUPPORTED;
  const double *lam = I->zeta_from == 1 ? I->th.lcp.lam : I->zeta_from == 2 ? cup_projector_lambda(I->proj)
                    : I->zeta_from == 3 ? I->zeta_ext : NULL;
  double s = I->zeta_from == 2 ? 1 / I->h : 1;
  for (int i = 0; i < I->m; i++) zeta[i] = lam ? s * lam[i] : 0;
  if (I->zs < 1 && I->zprev)                     /* a sample between two steps */
    for (int i = 0; i < I->m; i++) zeta[i] = I->zprev[i] + I->zs * (zeta[i] - I->zprev[i]);
  return CUP_OK;
}

/* ---- checkpoints (checkpoint.c writes the header) ---------------------------------- */

/* A run on a polyset can resume: another set's projections keep state
 * (a crowd's rows, an oracle's) that no checkpoint holds. */
int fixed_saves(const void *ws) { return !((const cup_integrator *)ws)->sp; }

int fixed_stopped(const void *ws, cup_run_info *info) {
  const cup_integrator *I = ws;
  if (I->stop.phase == CUP_STOP_NONE) return 0;
  info->status = I->stop.status;
  memcpy(info->message, I->stop.message, sizeof info->message);
  return 1;
}

/* Where the run stopped, x_k (and x_{k-1}, zeta_{k-1} for a sample between
 * steps), the estimate's x0 and its comparisons so far, the projector's
 * and the LCP step's warm starts. */
void fixed_checkpoint(void *ws, ckpt *c) {
  cup_integrator *I = ws;
  integrator_ckpt_stop *s = &I->stop;
  CUP_CKPT_IO(c, s->phase);
  CUP_CKPT_IO(c, s->k);
  CUP_CKPT_IO(c, s->next_j);
  CUP_CKPT_IO(c, I->zeta_from);
  CUP_CKPT_IO(c, I->jump);
  ckpt_io(c, I->x, sizeof(double) * (size_t)I->n);
  if (I->o.output == CUP_OUTPUT_SAMPLES) {      /* a sample between steps k - 1 and k: x_{k-1}, zeta_{k-1} */
    ckpt_io(c, I->xnew, sizeof(double) * (size_t)I->n);
    if (I->zprev) ckpt_io(c, I->zprev, sizeof(double) * (size_t)I->m);
  }
  if (I->half) {
    ckpt_io(c, I->x0, sizeof(double) * (size_t)I->n);
    CUP_CKPT_IO(c, I->est.err);
  }
  projector_checkpoint(I->proj, c);
  if (I->use_theta) lcp_step_checkpoint(&I->th, c);
}

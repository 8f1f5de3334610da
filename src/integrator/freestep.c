/* freestep — the free step of the catching-up scheme (see freestep.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <gsl/gsl_complex_math.h>
#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_integration.h>
#include "catchup.h"
#include "freestep.h"
#include "set/polyset_impl.h"

static void *zalloc(size_t count, size_t size, int *fail) {
  void *q = calloc(count ? count : 1, size);
  if (!q) *fail = 1;
  return q;
}

/* Gauss-Legendre nodes and weights on [0, 1]. */
static int gl_nodes(int order, double *node, double *weight) {
  gsl_integration_glfixed_table *t = gsl_integration_glfixed_table_alloc((size_t)order);
  if (!t) return CUP_ERR_NOMEM;
  for (int i = 0; i < order; i++) gsl_integration_glfixed_point(0, 1, (size_t)i, &node[i], &weight[i], t);
  gsl_integration_glfixed_table_free(t);
  return CUP_OK;
}

static void dense_A(const freestep_drift *D, double *a) {
  int n = D->n;
  memset(a, 0, sizeof(double) * (size_t)n * n);
  if (!D->has_A) return;
  for (int j = 0; j < n; j++)
    for (int k = D->A.p[j]; k < D->A.p[j + 1]; k++) a[D->A.i[k] + (size_t)j * n] = D->A.x[k];
}

double freestep_h_rho(const freestep_drift *D, double h) {
  int n = D->n;
  if (!D->has_A) return 0;
  if (n > CUP_IMPLICIT_MAX_DIM) {            /* Gershgorin: rho <= max row sum of |A| */
    double *row = calloc((size_t)n, sizeof(double)), r = 0;
    if (!row) return INFINITY;
    for (int j = 0; j < n; j++)
      for (int k = D->A.p[j]; k < D->A.p[j + 1]; k++) row[D->A.i[k]] += fabs(D->A.x[k]);
    for (int i = 0; i < n; i++) r = fmax(r, row[i]);
    free(row);
    return h * r;
  }
  gsl_matrix *a = gsl_matrix_calloc((size_t)n, (size_t)n);
  gsl_vector_complex *ev = gsl_vector_complex_alloc((size_t)n);
  gsl_eigen_nonsymm_workspace *w = gsl_eigen_nonsymm_alloc((size_t)n);
  double rho = INFINITY;
  if (a && ev && w) {
    for (int j = 0; j < n; j++)
      for (int k = D->A.p[j]; k < D->A.p[j + 1]; k++) gsl_matrix_set(a, (size_t)D->A.i[k], (size_t)j, D->A.x[k]);
    gsl_error_handler_t *old = gsl_set_error_handler_off();
    if (gsl_eigen_nonsymm(a, ev, w) == 0) {
      rho = 0;
      for (int i = 0; i < n; i++) rho = fmax(rho, gsl_complex_abs(gsl_vector_complex_get(ev, (size_t)i)));
    }
    gsl_set_error_handler(old);
  }
  if (w) gsl_eigen_nonsymm_free(w);
  if (ev) gsl_vector_complex_free(ev);
  if (a) gsl_matrix_free(a);
  return h * rho;
}

/* ---- exponential scheme: inputs as outputs of small linear generators -------- */

/* The input's exosystem (input_impl.h): one generator block per term. */
static int exp_init(freestep_ws *fs, char *errmsg) {
  const freestep_drift *D = &fs->d;
  const cup_input *u = fs->u;
  int n = fs->n, fail = 0;
  int nterms = u && !u->fn ? u->nterms : 0;
  fs->nw = 0;
  fs->gen_of_term = zalloc((size_t)nterms + 1, sizeof(int), &fail);
  if (!fail) fs->nw = input_gen_dim(u, NULL, fs->gen_of_term);
  if (!fail) {
    int st = input_gen_check(u, "exponential", errmsg);
    if (st) return st;
  }
  int na = fs->na = n + fs->nw;
  if (na > CUP_EXPONENTIAL_MAX_DIM)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED,
                    "exponential scheme: state plus input generators = %d exceeds the dense limit %d; "
                    "use the explicit or implicit scheme", na, CUP_EXPONENTIAL_MAX_DIM);
  size_t NA = (size_t)na * na;
  fs->M = zalloc(NA, sizeof(double), &fail);
  fs->Eh = zalloc(NA, sizeof(double), &fail);
  fs->Es = zalloc(NA, sizeof(double), &fail);
  fs->ework = zalloc(4 * NA, sizeof(double), &fail);
  fs->wgen = zalloc((size_t)fs->nw + 1, sizeof(double), &fail);
  fs->xa = zalloc((size_t)na, sizeof(double), &fail);
  fs->xa2 = zalloc((size_t)na, sizeof(double), &fail);
  if (fail) return fail_fmt(errmsg, CUP_ERR_NOMEM, "exponential scheme: out of memory");
  /* M = [A  E_coupling; 0  W] */
  if (D->has_A)
    for (int j = 0; j < n; j++)
      for (int k = D->A.p[j]; k < D->A.p[j + 1]; k++) fs->M[D->A.i[k] + (size_t)j * na] = D->A.x[k];
  for (int k = 0; k < nterms; k++) {
    const input_term *t = &u->terms[k];
    int g = n + fs->gen_of_term[k];
    if (D->has_E)                            /* x' += E(:, comp) * (first generator state) */
      for (int q = D->E.p[t->comp]; q < D->E.p[t->comp + 1]; q++) fs->M[D->E.i[q] + (size_t)g * na] = D->E.x[q];
  }
  if (nterms) input_gen_dynamics(u, NULL, fs->gen_of_term, fs->M + n + (size_t)n * na, na);
  double *hM = fs->Es;
  for (size_t q = 0; q < NA; q++) hM[q] = fs->h * fs->M[q];
  la_dense_expm(hM, na, fs->Eh, fs->ework);
  /* callback input: Gauss-Legendre convolution with e^{A h (1 - tau)} E */
  if (u && u->fn && D->has_E) {
    fs->nu = 8;
    if (gl_nodes(fs->nu, fs->unode, fs->uweight)) return fail_fmt(errmsg, CUP_ERR_NOMEM, "out of memory");
    fs->Q = zalloc((size_t)fs->nu * n * fs->p, sizeof(double), &fail);
    double *expA = zalloc((size_t)n * n, sizeof(double), &fail), *hA = zalloc((size_t)n * n, sizeof(double), &fail);
    double *w3 = zalloc(3 * (size_t)n * n, sizeof(double), &fail);
    if (fail) { free(expA); free(hA); free(w3); return fail_fmt(errmsg, CUP_ERR_NOMEM, "out of memory"); }
    dense_A(D, hA);
    for (int q = 0; q < fs->nu; q++) {
      double tau = fs->h * (1 - fs->unode[q]);
      double *sc = fs->Es;                   /* tau A, then exp */
      for (size_t e = 0; e < (size_t)n * n; e++) sc[e] = tau * hA[e];
      la_dense_expm(sc, n, expA, w3);
      double *Qq = fs->Q + (size_t)q * n * fs->p;
      for (int c = 0; c < fs->p; c++)
        for (int r = 0; r < n; r++) {
          double s = 0;
          for (int k = D->E.p[c]; k < D->E.p[c + 1]; k++) s += expA[r + (size_t)D->E.i[k] * n] * D->E.x[k];
          Qq[r + (size_t)c * n] = s;
        }
    }
    free(expA); free(hA); free(w3);
  }
  return CUP_OK;
}

/* x <- top block of E [x; w(a..b)], E = exp((b - a) M). */
static void exp_propagate(freestep_ws *fs, const double *E, double *x, double a, double b) {
  int n = fs->n, na = fs->na;
  if (fs->nw) input_gen_values(fs->u, fs->gen_of_term, a, b, fs->wgen);
  memcpy(fs->xa, x, sizeof(double) * (size_t)n);
  memcpy(fs->xa + n, fs->wgen, sizeof(double) * (size_t)fs->nw);
  for (int i = 0; i < n; i++) {
    double s = 0;
    for (int j = 0; j < na; j++) s += E[i + (size_t)j * na] * fs->xa[j];
    x[i] = s;
  }
}

/* A step holding square-wave jumps or table knots is split there; each piece
 * needs exp(tau M) for its own length (rare: a few steps per period). */
static void exp_step(freestep_ws *fs, double t0, double t1, const double *x, double *xf) {
  memcpy(xf, x, sizeof(double) * (size_t)fs->n);
  double brk = fs->nw ? cup_input_next_break(fs->u, t0) : INFINITY;
  if (!(brk < t1)) {
    exp_propagate(fs, fs->Eh, xf, t0, t1);
    return;
  }
  size_t NA = (size_t)fs->na * fs->na;
  for (double a = t0; a < t1;) {
    double b = fmin(cup_input_next_break(fs->u, a), t1);
    double *scaled = fs->ework + 3 * NA;     /* (b - a) M */
    for (size_t q = 0; q < NA; q++) scaled[q] = (b - a) * fs->M[q];
    la_dense_expm(scaled, fs->na, fs->Es, fs->ework);
    exp_propagate(fs, fs->Es, xf, a, b);
    a = b;
  }
}

/* ---- set-up and the step ------------------------------------------------------- */

static int implicit_init(freestep_ws *fs, char *errmsg) {
  int n = fs->n, fail = 0;
  if (n > CUP_IMPLICIT_MAX_DIM)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED,
                    "implicit scheme: state dimension %d exceeds the dense limit %d; use the explicit scheme",
                    n, CUP_IMPLICIT_MAX_DIM);
  fs->lu = zalloc((size_t)n * n, sizeof(double), &fail);
  fs->piv = zalloc((size_t)n, sizeof(int), &fail);
  if (fail) return fail_fmt(errmsg, CUP_ERR_NOMEM, "implicit scheme: out of memory");
  dense_A(&fs->d, fs->lu);
  for (size_t q = 0; q < (size_t)n * n; q++) fs->lu[q] *= -fs->h;
  for (int i = 0; i < n; i++) fs->lu[i + (size_t)i * n] += 1;
  int bad = la_dense_lu(fs->lu, n, fs->piv);
  if (bad)
    return fail_fmt(errmsg, CUP_ERR_LINALG, "implicit scheme: I - h A is singular (column %d)", bad - 1);
  return CUP_OK;
}

/* W = (I - h theta A)^-1 as an explicit dense matrix (the theta step
 * multiplies by it twice: the free step and H = h W B). */
static int theta_init(freestep_ws *fs, double theta, char *errmsg) {
  int n = fs->n, fail = 0;
  if (n > CUP_EXPONENTIAL_MAX_DIM)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED,
                    "theta scheme: state dimension %d exceeds the dense limit %d", n, CUP_EXPONENTIAL_MAX_DIM);
  fs->lu = zalloc((size_t)n * n, sizeof(double), &fail);
  fs->piv = zalloc((size_t)n, sizeof(int), &fail);
  fs->W = zalloc((size_t)n * n, sizeof(double), &fail);
  fs->rhs = zalloc((size_t)n, sizeof(double), &fail);
  if (fail) return fail_fmt(errmsg, CUP_ERR_NOMEM, "theta scheme: out of memory");
  dense_A(&fs->d, fs->lu);
  for (size_t q = 0; q < (size_t)n * n; q++) fs->lu[q] *= -fs->h * theta;
  for (int i = 0; i < n; i++) fs->lu[i + (size_t)i * n] += 1;
  int bad = la_dense_lu(fs->lu, n, fs->piv);
  if (bad) return fail_fmt(errmsg, CUP_ERR_LINALG, "theta scheme: I - h theta A is singular (column %d)", bad - 1);
  for (int j = 0; j < n; j++) {
    double *col = fs->W + (size_t)j * n;
    col[j] = 1;
    la_dense_lu_solve(fs->lu, n, fs->piv, col, fs->work);
  }
  return CUP_OK;
}

/* The free step of a small system as one dense affine map:
 *   explicit  Phi = I + h A,           Gam = E,       f term as is
 *   implicit  Phi = (I - h A)^-1,      Gam = Phi E,   f term through Phi
 *   theta     Phi = I + h W A,         Gam = W E,     f term through W */
static int affine_init(freestep_ws *fs, char *errmsg) {
  const freestep_drift *D = &fs->d;
  int n = fs->n, p = fs->p, fail = 0;
  fs->Phi = zalloc((size_t)n * n, sizeof(double), &fail);
  fs->Gam = zalloc((size_t)n * (p ? p : 1), sizeof(double), &fail);
  double *A = zalloc((size_t)n * n, sizeof(double), &fail);
  if (fail) { free(A); return fail_fmt(errmsg, CUP_ERR_NOMEM, "free step: out of memory"); }
  dense_A(D, A);
  const double *M = NULL;                 /* the map applied after h A x + E u */
  if (fs->scheme == CUP_SCHEME_IMPLICIT) {
    for (int j = 0; j < n; j++) {         /* Phi = (I - h A)^-1, column by column */
      double *col = fs->Phi + (size_t)j * n;
      col[j] = 1;
      la_dense_lu_solve(fs->lu, n, fs->piv, col, fs->work);
    }
    M = fs->Phi;
  } else {
    if (fs->scheme == CUP_SCHEME_THETA) M = fs->W;
    for (int j = 0; j < n; j++)           /* Phi = I + h M A */
      for (int i = 0; i < n; i++) {
        double acc = 0;
        for (int k = 0; k < n; k++) acc += (M ? M[i + (size_t)k * n] : (i == k)) * A[k + (size_t)j * n];
        fs->Phi[i + (size_t)j * n] = (i == j) + fs->h * acc;
      }
  }
  if (D->has_E)                           /* Gam = M E */
    for (int c = 0; c < p; c++)
      for (int k = D->E.p[c]; k < D->E.p[c + 1]; k++)
        for (int i = 0; i < n; i++)
          fs->Gam[i + (size_t)c * n] += (M ? M[i + (size_t)D->E.i[k] * n] : (i == D->E.i[k])) * D->E.x[k];
  fs->Fmap = M;
  /* row-major for the step: each entry of x_free is one dot product kept
   * in a register (column sweeps chain every update through memory) */
  for (size_t q = 0; q < (size_t)n * n; q++) A[q] = fs->Phi[q];
  for (int i = 0; i < n; i++)
    for (int j = 0; j < n; j++) fs->Phi[(size_t)i * n + j] = A[i + (size_t)j * n];
  if (p) {
    double *GamR = zalloc((size_t)n * p, sizeof(double), &fail);
    if (fail) { free(A); return fail_fmt(errmsg, CUP_ERR_NOMEM, "free step: out of memory"); }
    for (int i = 0; i < n; i++)
      for (int c = 0; c < p; c++) GamR[(size_t)i * p + c] = fs->Gam[i + (size_t)c * n];
    free(fs->Gam);
    fs->Gam = GamR;
  }
  free(A);
  fs->affine = 1;
  return CUP_OK;
}

static void waveform_step_integral(freestep_ws *fs, double t0, double t1);

/* int u over the step into fs->ubuf (p entries); *has = 0 without input. */
static int step_input(freestep_ws *fs, double t0, double t1, int *has) {
  *has = fs->u && fs->d.has_E;
  if (!*has || fs->const_input) return CUP_OK;   /* a constant input: ubuf holds h u */
  if (fs->u->fn) return input_integral_ws(fs->u, t0, t1, fs->ubuf, &fs->qws);
  waveform_step_integral(fs, t0, t1);
  return CUP_OK;
}

/* xf = Phi x + Gam u (u NULL: no input), Phi n x n and Gam n x p row-major;
 * inlined with a constant n for small systems. */
static inline __attribute__((always_inline)) void
affine_rows(int n, int p, const double *restrict Phi, const double *restrict Gam,
            const double *restrict x, const double *restrict u, double *restrict xf) {
  for (int i = 0; i < n; i++) {
    const double *restrict row = Phi + (size_t)i * n;
    double acc = 0;
    for (int j = 0; j < n; j++) acc += row[j] * x[j];
    if (u) {
      const double *restrict grow = Gam + (size_t)i * p;
      for (int c = 0; c < p; c++) acc += grow[c] * u[c];
    }
    xf[i] = acc;
  }
}

static int affine_apply(freestep_ws *fs, double t0, double t1, const double *restrict x,
                        double *restrict xf, int with_f) {
  int n = fs->n, p = fs->p, has;
  const double *restrict Phi = fs->Phi, *restrict Gam = fs->Gam;
  int st = step_input(fs, t0, t1, &has);
  if (st < 0) return st;
  const double *restrict u = has ? fs->ubuf : NULL;
  /* fixed small sizes (one input is the common case) unroll completely */
#define CUP_AFFINE_CASE(N) \
  case N: if (p == 1) affine_rows(N, 1, Phi, Gam, x, u, xf); else affine_rows(N, p, Phi, Gam, x, u, xf); break;
  switch (n) {
    CUP_AFFINE_CASE(1) CUP_AFFINE_CASE(2) CUP_AFFINE_CASE(3)
    CUP_AFFINE_CASE(4) CUP_AFFINE_CASE(5) CUP_AFFINE_CASE(6)
    default: affine_rows(n, p, Phi, Gam, x, u, xf); break;
  }
#undef CUP_AFFINE_CASE
  if (with_f) {
    const double *restrict F = fs->Fmap, *restrict fsum = fs->fsum;
    for (int j = 0; j < n; j++)
      for (int i = 0; i < n; i++) xf[i] += (F ? F[i + (size_t)j * n] : (i == j)) * fsum[j];
  }
  return st;
}

int freestep_init(freestep_ws *fs, const freestep_drift *D, const cup_polyset *K, const cup_input *u,
                  int scheme, double theta, double h, int f_order, char *errmsg) {
  memset(fs, 0, sizeof *fs);
  fs->scheme = scheme;
  fs->n = D->n;
  fs->p = D->p;
  fs->h = h;
  fs->d = *D;
  fs->K = K;
  fs->u = D->p > 0 ? u : NULL;
  int n = fs->n, p = fs->p, fail = 0;
  if (p > 0 && !u)
    return fail_fmt(errmsg, CUP_ERR_ARG, "the %s has %d input(s) but no input u(t) was given",
                    D->what, p);
  if (u && D->p > 0 && cup_input_dim(u) != p)
    return fail_fmt(errmsg, CUP_ERR_DIM, "the input has %d component(s), the %s expects %d",
                    cup_input_dim(u), D->what, p);
  fs->ubuf = zalloc((size_t)p + 1, sizeof(double), &fail);
  fs->eu_const = zalloc((size_t)n, sizeof(double), &fail);
  fs->fsum = zalloc((size_t)n, sizeof(double), &fail);
  fs->fbuf = zalloc((size_t)n, sizeof(double), &fail);
  fs->work = zalloc(2 * (size_t)n, sizeof(double), &fail);
  if (fail) return fail_fmt(errmsg, CUP_ERR_NOMEM, "free step: out of memory");
  if (f_order < 1 || f_order > CUP_GL_MAX)
    return fail_fmt(errmsg, CUP_ERR_ARG, "f_order = %d must be in [1, %d]", f_order, CUP_GL_MAX);
  fs->nf = f_order;
  if (gl_nodes(fs->nf, fs->fnode, fs->fweight)) return fail_fmt(errmsg, CUP_ERR_NOMEM, "out of memory");
  if (fs->u && fs->u->fn && input_quad_ws_init(&fs->qws, p))
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "input quadrature: out of memory");
  if (fs->u && !fs->u->fn) {
    fs->term_h = zalloc((size_t)fs->u->nterms + 1, sizeof(double), &fail);
    fs->live = zalloc((size_t)fs->u->nterms + 1, sizeof(int), &fail);
    if (fail) return fail_fmt(errmsg, CUP_ERR_NOMEM, "free step: out of memory");
    for (int k = 0; k < fs->u->nterms; k++) {
      const input_term *t = &fs->u->terms[k];
      int c = t->comp;                         /* (a switch's gate source drives no state) */
      if (!D->has_E || D->E.ncol != p || D->E.p[c + 1] > D->E.p[c]) fs->live[fs->nlive++] = k;
      if (t->kind == CUP_WAVE_CONSTANT) fs->term_h[k] = t->value * h;
      else if (t->kind == CUP_WAVE_SINE)
        fs->term_h[k] = t->omega > 0 ? 2 * t->amp / t->omega * sin(0.5 * t->omega * h)
                                     : t->amp * sin(t->phase) * h;
    }
  }
  /* a constant input is integrated once */
  fs->const_input = !fs->u || cup_input_is_constant(fs->u);
  if (fs->u && fs->const_input && D->has_E) {   /* ubuf keeps h u for the affine path */
    input_integral_ws(fs->u, 0, h, fs->ubuf, NULL);
    la_sparse_gaxpy(&D->E, fs->ubuf, fs->eu_const);
  }
  int st = CUP_OK;
  if (scheme == CUP_SCHEME_IMPLICIT) st = implicit_init(fs, errmsg);
  else if (scheme == CUP_SCHEME_EXPONENTIAL) return exp_init(fs, errmsg);
  else if (scheme == CUP_SCHEME_THETA) st = theta_init(fs, theta, errmsg);
  else if (scheme != CUP_SCHEME_EXPLICIT) return fail_fmt(errmsg, CUP_ERR_ARG, "unknown scheme %d", scheme);
  if (!st && n <= CUP_AFFINE_MAX_DIM) st = affine_init(fs, errmsg);
  return st;
}

void freestep_free(freestep_ws *fs) {
  free(fs->eu_const); free(fs->term_h); free(fs->live); free(fs->ubuf); free(fs->fsum); free(fs->fbuf); free(fs->work);
  input_quad_ws_free(&fs->qws);
  free(fs->lu); free(fs->piv); free(fs->W); free(fs->rhs); free(fs->Phi); free(fs->Gam);
  free(fs->gen_of_term); free(fs->M); free(fs->Eh); free(fs->Es); free(fs->ework);
  free(fs->wgen); free(fs->xa); free(fs->xa2); free(fs->Q);
  memset(fs, 0, sizeof *fs);
}

/* int_{t0}^{t1} u over a full step of the grid, term by term
 * (freestep_term_integral); one input is summed in a register. Several:
 * those with a column in E only (each moves the state by E's column times
 * its integral; a switch's gate source has none, and in a full bridge the
 * four gates' pulses were 4/5 of the step's input work); the others stay
 * 0, which Gam's zero columns meet as their integrals did, so that x_free
 * keeps its bits (but for the sign of a zero state with a negative
 * input). */
static void waveform_step_integral(freestep_ws *fs, double t0, double t1) {
  const cup_input *u = fs->u;
  double tmid = 0.5 * (t0 + t1);
  if (fs->p == 1) {
    double acc = 0;
    for (int k = 0; k < u->nterms; k++) acc += freestep_term_integral(fs, k, t0, t1, tmid);
    fs->ubuf[0] = acc;
    return;
  }
  for (int j = 0; j < fs->p; j++) fs->ubuf[j] = 0;
  for (int q = 0; q < fs->nlive; q++) {
    int k = fs->live[q];
    fs->ubuf[u->terms[k].comp] += freestep_term_integral(fs, k, t0, t1, tmid);
  }
}

/* xf += E int_{t0}^{t1} u (nothing without input; the precomputed h E u
 * for a constant one). */
static int add_input(freestep_ws *fs, double t0, double t1, double *xf) {
  const freestep_drift *D = &fs->d;
  if (!fs->u || !D->has_E) return CUP_OK;
  if (fs->const_input) {
    for (int i = 0; i < fs->n; i++) xf[i] += fs->eu_const[i];
    return CUP_OK;
  }
  int st = CUP_OK;
  if (fs->u->fn) st = input_integral_ws(fs->u, t0, t1, fs->ubuf, &fs->qws);
  else waveform_step_integral(fs, t0, t1);
  if (st < 0) return st;
  la_sparse_gaxpy(&D->E, fs->ubuf, xf);
  return st;
}

int freestep_add_rhs(freestep_ws *fs, cup_rhs_fn f, void *ctx) {
  if (!f) return CUP_OK;
  if (fs->nrhs == CUP_RHS_MAX) return CUP_ERR_ARG;
  fs->fcb[fs->nrhs] = f;
  fs->fcb_ctx[fs->nrhs++] = ctx;
  fs->has_f = 1;
  return CUP_OK;
}

void freestep_set_rhs_integral(freestep_ws *fs, cup_rhs_integral_fn F, void *ctx) {
  fs->rhs_int = F;
  fs->rhs_int_ctx = ctx;
  fs->has_f = fs->nrhs > 0 || F;
}

/* int_{t0}^{t1} f(s, x) ds, x frozen (paper, Sec. 3): Gauss-Legendre for the
 * pointwise callbacks, the user's own integral for the other. */
static int rhs_term(freestep_ws *fs, double t0, double t1, const double *x) {
  int n = fs->n;
  memset(fs->fsum, 0, sizeof(double) * (size_t)n);
  for (int c = 0; c < fs->nrhs; c++)
    for (int q = 0; q < fs->nf; q++) {
      if (fs->fcb[c](t0 + fs->fnode[q] * fs->h, x, fs->fbuf, fs->fcb_ctx[c]) != 0) return CUP_ERR_CALLBACK;
      for (int i = 0; i < n; i++) {
        if (!isfinite(fs->fbuf[i])) return CUP_ERR_CALLBACK;
        fs->fsum[i] += fs->h * fs->fweight[q] * fs->fbuf[i];
      }
    }
  if (fs->rhs_int) {
    if (fs->rhs_int(t0, t1, x, fs->fbuf, fs->rhs_int_ctx) != 0) return CUP_ERR_CALLBACK;
    for (int i = 0; i < n; i++) {
      if (!isfinite(fs->fbuf[i])) return CUP_ERR_CALLBACK;
      fs->fsum[i] += fs->fbuf[i];
    }
  }
  return CUP_OK;
}

/* Callback input under the exponential scheme: Gauss-Legendre on the
 * convolution with the precomputed e^{A h (1 - tau_q)} E. */
static int exp_callback_input(freestep_ws *fs, double t0, double *xf) {
  int n = fs->n, p = fs->p;
  for (int q = 0; q < fs->nu; q++) {
    if (cup_input_eval(fs->u, t0 + fs->unode[q] * fs->h, fs->ubuf)) return CUP_ERR_CALLBACK;
    const double *Qq = fs->Q + (size_t)q * n * p;
    for (int c = 0; c < p; c++) {
      double wc = fs->h * fs->uweight[q] * fs->ubuf[c];
      for (int r = 0; r < n; r++) xf[r] += Qq[r + (size_t)c * n] * wc;
    }
  }
  return CUP_OK;
}

int freestep_apply(freestep_ws *fs, double t0, double t1, const double *x, double *xf) {
  const freestep_drift *D = &fs->d;
  int n = fs->n, st = CUP_OK, f = fs->has_f;
  if (f && (st = rhs_term(fs, t0, t1, x)) < 0) return st;
  if (fs->affine) return status_merge(st, affine_apply(fs, t0, t1, x, xf, f));
  switch (fs->scheme) {
    case CUP_SCHEME_EXPLICIT:
      la_copy(xf, x, n);
      if (D->has_A)                          /* + h A x */
        for (int j = 0; j < n; j++) {
          double hx = fs->h * x[j];
          for (int k = D->A.p[j]; k < D->A.p[j + 1]; k++) xf[D->A.i[k]] += D->A.x[k] * hx;
        }
      if ((st = status_merge(st, add_input(fs, t0, t1, xf))) < 0) return st;
      break;
    case CUP_SCHEME_IMPLICIT:
      for (int i = 0; i < n; i++) xf[i] = x[i] + (f ? fs->fsum[i] : 0);
      if ((st = status_merge(st, add_input(fs, t0, t1, xf))) < 0) return st;
      la_dense_lu_solve(fs->lu, n, fs->piv, xf, fs->work);
      return st;
    case CUP_SCHEME_THETA:                  /* x + W (h A x + E int u + int f) */
      la_zero(fs->rhs, n);
      if (D->has_A)
        for (int j = 0; j < n; j++) {
          double hx = fs->h * x[j];
          for (int k = D->A.p[j]; k < D->A.p[j + 1]; k++) fs->rhs[D->A.i[k]] += D->A.x[k] * hx;
        }
      if (f)
        for (int i = 0; i < n; i++) fs->rhs[i] += fs->fsum[i];
      if ((st = status_merge(st, add_input(fs, t0, t1, fs->rhs))) < 0) return st;
      for (int i = 0; i < n; i++) {
        double acc = x[i];
        for (int j = 0; j < n; j++) acc += fs->W[i + (size_t)j * n] * fs->rhs[j];
        xf[i] = acc;
      }
      return st;
    case CUP_SCHEME_EXPONENTIAL:
      exp_step(fs, t0, t1, x, xf);
      if (fs->u && fs->u->fn && D->has_E && exp_callback_input(fs, t0, xf)) return CUP_ERR_CALLBACK;
      break;
  }
  if (f)
    for (int i = 0; i < n; i++) xf[i] += fs->fsum[i];
  return st;
}

/* v <- (W - I) v for the linear part W of the implicit ((I - h A)^-1) or
 * exponential (e^{hA}) free step; work: n. */
static void linear_minus_identity(const freestep_ws *fs, double *v, double *work) {
  int n = fs->n;
  if (fs->scheme == CUP_SCHEME_EXPONENTIAL) {
    for (int i = 0; i < n; i++) {
      double acc = 0;
      for (int j = 0; j < n; j++) acc += fs->Eh[i + (size_t)j * fs->na] * v[j];
      work[i] = acc - v[i];
    }
  } else {
    for (int i = 0; i < n; i++) work[i] = v[i];
    la_dense_lu_solve(fs->lu, n, fs->piv, work, work + n);
    for (int i = 0; i < n; i++) work[i] -= v[i];
  }
  for (int i = 0; i < n; i++) v[i] = work[i];
}

double freestep_splitting(const freestep_ws *fs, int *row) {
  const cup_polyset *K = fs->K;
  if (row) *row = -1;
  if ((fs->scheme != CUP_SCHEME_IMPLICIT && fs->scheme != CUP_SCHEME_EXPONENTIAL) || !K || !K->dense ||
      K->m == 0)
    return 0;
  int n = fs->n;
  double *b = malloc(sizeof(double) * 4 * (size_t)n);
  if (!b) return NAN;
  double *d = b + n, *work = b + 2 * (size_t)n, worst = 0;
  for (int i = 0; i < K->m; i++) {
    const double *Bi = K->Bt + (size_t)i * n;   /* b_i = P^-1 c_i, so <v, b_i>_P = c_i^T v */
    double bb = 0;
    for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) bb += K->Ct.x[k] * Bi[K->Ct.i[k]];
    if (!(bb > 0)) continue;
    for (int j = 0; j < n; j++) d[j] = Bi[j];
    linear_minus_identity(fs, d, work);
    double db = 0;
    for (int k = K->Ct.p[i]; k < K->Ct.p[i + 1]; k++) db += K->Ct.x[k] * d[K->Ct.i[k]];
    double alpha = -db / bb;                     /* the part of b_i relaxed in one step */
    for (int j = 0; j < n; j++) d[j] -= db / bb * Bi[j];
    double leak = cup_polyset_norm(K, d) / sqrt(bb);   /* what that relaxation moved elsewhere */
    if (!(leak > CUP_SPLIT_LEAK_MIN)) continue;
    if (!(alpha <= worst)) { worst = alpha; if (row) *row = i; }   /* NaN stays */
  }
  free(b);
  return worst;
}

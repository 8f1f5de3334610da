/* freestep — the free step of the catching-up scheme, before projection:
 *   explicit:    x_k + h A x_k + E int u + int f
 *   implicit:    (I - h A)^-1 (x_k + E int u + int f)
 *   exponential: e^{hA} x_k + int e^{A(t_{k+1}-s)} E u(s) ds + int f
 *   theta:       x_k + W (h A x_k + E int u + int f),  W = (I - h theta A)^-1
 * with f(s, x_k) frozen at x_k as in the paper. */
#ifndef CUP_FREESTEP_H
#define CUP_FREESTEP_H

#include "catchup/integrator.h"
#include "model/input_impl.h"
#include "set/polyset_impl.h"
#include "util/trig.h"

/* Dense limits of the implicit and exponential schemes (the explicit scheme
 * has none: A stays sparse). */
#define CUP_IMPLICIT_MAX_DIM 512
#define CUP_EXPONENTIAL_MAX_DIM 256
#define CUP_GL_MAX 16
/* Up to this dimension the explicit, implicit and theta free steps are one
 * dense affine map x_free = Phi x + Gam int u (+ the f term). */
#define CUP_AFFINE_MAX_DIM 32

/* The affine part of f, A x + E u(t) (an LCS's, or a general process's);
 * the matrices are shared, not owned. */
typedef struct freestep_drift {
  int n, p;
  int has_A, has_E;
  la_sparse A, E;          /* n x n, n x p when present */
  const char *what;         /* "LCS", "process": for messages */
} freestep_drift;

/* Pointwise callbacks f(t, x) a free step sums (an LCS's perturbation and a
 * process's f). */
#define CUP_RHS_MAX 2

typedef struct freestep_ws {
  int scheme, n, p;
  double h;
  freestep_drift d;
  const cup_polyset *K;     /* the rows the splitting check looks at, or NULL */
  const cup_input *u;
  int has_f, nrhs;          /* f: pointwise callbacks and/or an exact integral */
  cup_rhs_fn fcb[CUP_RHS_MAX];
  void *fcb_ctx[CUP_RHS_MAX];
  cup_rhs_integral_fn rhs_int;
  void *rhs_int_ctx;
  int const_input;          /* u constant: E int u = h E u precomputed */
  double *eu_const;         /* n */
  double *ubuf, *fsum, *fbuf, *work;       /* p, n, n, 2 n scratch */
  input_quad_ws qws;          /* callback input quadrature */
  double *term_h;           /* per waveform term over a full step: constant c h;
                               sine 2A/w sin(w h / 2) (times sin(w t_mid + phase)) */
  int *live, nlive;         /* the terms whose input has a column in E (the others move no state) */
  /* Gauss-Legendre nodes on [0, 1] for int f and for callback convolutions */
  int nf;
  double fnode[CUP_GL_MAX], fweight[CUP_GL_MAX];
  int nu;
  double unode[CUP_GL_MAX], uweight[CUP_GL_MAX];
  /* implicit: LU of I - h A */
  double *lu;
  int *piv;
  /* theta: W = (I - h theta A)^-1 (n x n) */
  double *W, *rhs;
  /* small systems: x_free = Phi x + Gam int u + Fmap int f */
  int affine;
  double *Phi, *Gam;        /* n x n, n x p (row-major) */
  const double *Fmap;       /* n x n applied to int f, or NULL for the identity */
  /* exponential */
  int nw, na;               /* generator states, n + nw */
  int *gen_of_term;         /* first generator state of each input term */
  double *M;                /* na x na augmented generator */
  double *Eh;               /* exp(h M), na x na */
  double *Es, *ework;       /* exp(tau M) for split steps; 3 na^2 work */
  double *wgen, *xa, *xa2;  /* nw; na; na */
  double *Q;                /* callback input: e^{A h (1 - tau_q)} E, n x p per node */
} freestep_ws;

/* K (may be NULL) is the polyset of the splitting check. */
int freestep_init(freestep_ws *fs, const freestep_drift *D, const cup_polyset *K, const cup_input *u,
                  int scheme, double theta, double h, int f_order, char *errmsg);
/* Add f(t, x) (NULL: nothing), integrated by Gauss-Legendre; CUP_ERR_ARG
 * beyond CUP_RHS_MAX. */
int freestep_add_rhs(freestep_ws *fs, cup_rhs_fn f, void *ctx);
/* Add a term given by its exact integral over a step (NULL: none). */
void freestep_set_rhs_integral(freestep_ws *fs, cup_rhs_integral_fn F, void *ctx);
void freestep_free(freestep_ws *fs);
/* The splitting defect of the implicit and exponential schemes. They move
 * by the free step W = (I - h A)^-1 or e^{hA} and then project along
 * B = P^-1 C^T. When the dynamics along a constraint direction b_i is fast
 * (time constant below h), the free step relaxes it within the step and
 * the relaxation moves the other states too; the projection along b_i
 * restores b_i's part but not that motion, at every step where row i is
 * active: an O(alpha_i) relative error that does not vanish until h is
 * well below the fast time constant (the consistent step, the theta scheme,
 * corrects along W B instead). Returns
 *     max_i alpha_i,  alpha_i = -<(W - I) b_i, b_i>_P / <b_i, b_i>_P
 * (the fraction of b_i relaxed in one step: about h / tau_i while small,
 * 1 when h >> tau_i) over the rows whose relaxation moves other states,
 * ||(I - Pi_i)(W - I) b_i||_P > CUP_SPLIT_LEAK_MIN ||b_i||_P; *row (may be
 * NULL) is that row, or -1. 0 for other schemes, without a polyset, and
 * for polysets without their dense form; NaN without memory. */
#define CUP_SPLIT_LEAK_MIN 1e-9
/* The integrator warns (CUP_WARN_SPLITTING) above this alpha: h above the
 * direction's time constant, where the limit as n grows is wrong until h
 * falls below it. */
#define CUP_SPLIT_WARN 0.5
double freestep_splitting(const freestep_ws *fs, int *row);
/* xf from x over [t0, t1] (t1 - t0 = h). Returns CUP_OK, CUP_ERR_CALLBACK,
 * or CUP_WARN_QUADRATURE. */
int freestep_apply(freestep_ws *fs, double t0, double t1, const double *x, double *xf);
/* h * spectral radius of A (dense eigenvalues up to CUP_IMPLICIT_MAX_DIM,
 * a Gershgorin upper bound beyond). */
double freestep_h_rho(const freestep_drift *D, double h);

/* One waveform term's integral over a full grid step [t0, t1], tmid its
 * midpoint, with the step-length factors of constants and sines cached in
 * term_h (one sin per sine term and step:
 * int A sin(w s + p) = 2A/w sin(w h/2) sin(w t_mid + p)). */
static inline double freestep_term_integral(const freestep_ws *fs, int k, double t0, double t1, double tmid) {
  const input_term *t = &fs->u->terms[k];
  switch (t->kind) {
    case CUP_WAVE_CONSTANT: return fs->term_h[k];
    case CUP_WAVE_SINE: return t->omega > 0 ? fs->term_h[k] * trig_sin(t->omega * tmid + t->phase) : fs->term_h[k];
    default: return input_term_integral(t, t0, t1);
  }
}

#endif

/* Internal layout of cup_polyset, shared by the projector modules. */
#ifndef CUP_POLYSET_IMPL_H
#define CUP_POLYSET_IMPL_H

#include <cholmod.h>
#include "catchup/polyset.h"
#include "util/linalg.h"

/* Sets with at most this many rows (and CUP_DENSE_MAX_DIM columns) keep
 * M = C P^-1 C^T and P^-1 C^T dense: the exact active-set path. */
#define CUP_DENSE_MAX_ROWS 64
#define CUP_DENSE_MAX_DIM 256

struct cup_polyset {
  int n, m;
  la_sparse C;        /* m x n, CSC */
  la_sparse Ct;       /* n x m, CSC of C^T: the rows of C */
  double *g0;          /* default offset, m */
  int pkind;           /* CUP_METRIC_* after simplification */
  double *pd, *pdinv;  /* IDENTITY/DIAGONAL: P's diagonal and its inverse */
  la_sparse Pfull;    /* SPARSE: both triangles, for products P v */
  cholmod_common *cm;  /* SPARSE only (2.9 kB): owns LP; used only at creation and free */
  cholmod_factor *LP;  /* SPARSE: L L^T = Pi P Pi^T (read-only after creation) */
  double *rownorm;     /* ||c_i||_{P^-1} = sqrt(M_ii) */
  int *rownnz;         /* nonzeros per row of C */
  double *rowgam;      /* (rownnz + 2) eps: the rounding bound of a row's slack per unit magnitude */
  double lip;          /* guaranteed L >= lambda_max(M) */
  int cw_iters;        /* Collatz-Wielandt iterations of that bound */
  int cw_warm;         /* revalue: work's first m entries hold the last bound's vector (> 0) */
  int mutable_values;  /* values rewritten in place at every step (polyset_revalue) */
  double solve_amp;    /* bound on the relative error amplification of P^-1 (1, or 1/rcond) */
  int dense;           /* small set: Md and Bt below are valid */
  double *Md;          /* m x m, column-major, M = C P^-1 C^T */
  double *Bt;          /* n x m, column-major, column i = P^-1 c_i */
  double *rdir;        /* direction with C d > 0, or NULL */
  double *Crdir;       /* C d */
  double rdir_norm;    /* ||d||_P */
};

/* cup_polyset_create; with mutable_values, for a polyset whose values
 * change in place (polyset_revalue), without the dense form (Md, Bt,
 * the interior direction) and with a quicker Lipschitz bound. work: NULL,
 * or the 2 m + n doubles that polyset_revalue will be given, its first
 * m entries a vector to start the bound from as revalue does (a set rebuilt
 * with rows of the last one: their entries of its last vector, 0 for new
 * rows); the bound and the first revalue are then warm (a sparse metric's
 * bound is always cold). */
int polyset_create_ex(cup_polyset **K, const cup_csc *C, const double *g,
                      const cup_metric *P, int mutable_values, double *work, char *errmsg);
/* The values of C (C.x and Ct.x, the pattern unchanged) were rewritten:
 * recompute the row norms and the Lipschitz bound. Only for a polyset
 * without the dense form and with a diagonal metric; work: 2 m + n doubles,
 * the same from one call to the next and untouched between them: its first
 * m entries keep the bound's vector, from which the next bound starts (the
 * values change little from a step to the next). Allocates nothing. */
void polyset_revalue(cup_polyset *K, double *work);

/* P v into out (n entries). */
void polyset_metric_apply(const cup_polyset *K, const double *v, double *out);
/* Bounds on ||v||_P for a computed v: *lo <= ||v||_P <= *hi, allowing for the
 * rounding of the sum (and of forming v from one subtraction). Returns the
 * computed value. */
double polyset_metric_norm_bounds(const cup_polyset *K, const double *v, double *lo, double *hi);
/* An upper bound on ||a - b||_P (and a lower one into *lo, may be NULL);
 * scratch w: n entries. */
double polyset_metric_dist_hi(const cup_polyset *K, const double *a, const double *b, double *lo, double *w);

/* In place P^-1 v for IDENTITY/DIAGONAL metrics. SPARSE metrics go through
 * the projector's CHOLMOD workspace (certify_metric_solve in projector/certify.h). */
static inline void polyset_metric_solve_diag(const cup_polyset *K, double *v) {
  if (K->pkind == CUP_METRIC_IDENTITY) return;
  for (int j = 0; j < K->n; j++) v[j] *= K->pdinv[j];
}
/* polyset_slack's rows (inline: polyset_slack_outside's too); outside:
 * whether a row is below its rounding instead of the worst slack (gam not
 * NULL). */
static inline __attribute__((always_inline)) double polyset_slack_rows(const cup_polyset *K, const double *g,
                                                                       const double *x, double *s, double *gam,
                                                                       int outside) {
  const int *p = K->Ct.p, *ri = K->Ct.i;
  const double *cx = K->Ct.x, *rg = K->rowgam;
  double worst = INFINITY;
  int below = 0, m = K->m, rounding = outside || gam;   /* (outside: gam is not NULL) */
  for (int i = 0; i < m; i++) {
    double acc = g[i], mag = fabs(g[i]);
    for (int k = p[i]; k < p[i + 1]; k++) {
      double t = cx[k] * x[ri[k]];
      acc += t;
      mag += fabs(t);
    }
    s[i] = acc;
    double margin = rounding ? rg[i] * mag : 0;
    if (rounding) gam[i] = margin;
    if (outside) {
      below |= acc < -margin;
      continue;
    }
    double slack = acc - margin;
    if (isnan(slack) || slack < worst) worst = slack;   /* a NaN row stays the minimum */
  }
  return outside ? below : worst;
}

/* s = C x + g and, if gam is not NULL, gam_i = a bound on the rounding
 * error of s_i. Returns min_i (s_i - gam_i) (or min s_i when gam is NULL). */
double polyset_slack(const cup_polyset *K, const double *g, const double *x,
                     double *s, double *gam);
/* ... s and gam (not NULL) as it leaves them; 1 if a row is below its
 * rounding, s_i < -gam_i (the adaptive scheme's check at a breakpoint). */
static inline int polyset_slack_outside(const cup_polyset *K, const double *g, const double *x, double *s,
                                        double *gam) {
  return (int)polyset_slack_rows(K, g, x, s, gam, 1);
}

#endif

/* step — the LCP of one step onto a polyset K = {x : C x + g >= 0}:
 *     z = x_free + H lambda,  H = h W B,  B = P^-1 C^T,
 *     0 <= lambda  _|_  w = C z + g >= 0,   an LCP with M = C H.
 * With W = I and h = 1, z is the P-projection of x_free onto K and lambda
 * the projector's multipliers (its exact path for small dense sets); the
 * theta scheme (Moreau-Jean time stepping, as in Siconos's EulerMoreauOSI)
 * takes W = (I - h theta A)^-1 from its free step, theta = 0 being the
 * explicit catching-up step (M symmetric: the P-projection) and theta = 1/2
 * second order where the solution is smooth. The LCP is
 * solved exactly (lcp.h), warm-started from the previous active set, aiming
 * the rows a few ulps inside K so that the answer is certainly feasible;
 * dense, for sets with K->dense (m <= 64 rows and n <= 256). */
#ifndef CUP_LCP_STEP_H
#define CUP_LCP_STEP_H

#include "catchup/projector.h"
#include "set/polyset_impl.h"
#include "lcp.h"

/* Up to this many states and rows, without D, a step is first tried by code
 * unrolled for its sizes (the circuits' common case: a few ns instead of a
 * loop over sparse rows and a general pivoting solver); it does the same
 * arithmetic in the same order, so z, lambda and the certificates are those
 * of the general path, which takes over for anything unusual (a singular
 * block, NaN, the exact mode eps_target < 0). */
#define CUP_STEP_SMALL_N 4
#define CUP_STEP_SMALL_M 2

typedef struct cup_lcp_step {
  int n, m;
  double h;
  const cup_polyset *K;
  double *H;        /* n x m, column-major */
  double *M;        /* m x m, column-major */
  cup_lcp lcp;      /* lambda of the last step in lcp.lam */
  double *s, *gam, *v, *tau, *qs, *sv, *gamv;
  double lq;        /* lambda^T q of the last step (q: the free point's slack) */
  /* D != 0 (cup_lcp_step_init_bd): w = C z + D lambda + g */
  double *D;        /* m x m, column-major, or NULL */
  double *geff;     /* g + D lambda: the offset the step's z must satisfy */
  unsigned char *drow; /* rows with D != 0 in their row or column: zeta is a function there */
  double *Hprev;    /* n x m: h (1 - theta) W B on those rows (the trapezoid's old half), else 0 */
  double *xpred;    /* xf + Hprev lambda_k */
  /* small sets (see CUP_STEP_SMALL_N): C's rows dense for the unrolled step */
  int small;        /* 1: cup_lcp_step_solve tries the unrolled step first */
  double Cd[CUP_STEP_SMALL_M * CUP_STEP_SMALL_N];   /* row-major, zeros included */
} cup_lcp_step;

/* W (n x n, column-major; NULL: the identity) and h give H and M. Returns
 * CUP_OK, CUP_ERR_UNSUPPORTED (K is not dense) or CUP_ERR_NOMEM; callers
 * write the message, in their own name. */
int cup_lcp_step_init(cup_lcp_step *ls, const cup_polyset *K, const double *W, double h);
/* The same for an LCS with D != 0 (Siconos's EulerMoreauOSI): B (n x m,
 * column-major) replaces P^-1 C^T in H = h W B, M = C H + D (D m x m,
 * column-major); z satisfies C z + D lambda + g >= 0 and the certificates
 * below use g + D lambda; an M that is not a P-matrix (a monotone LCP) is
 * solved by Lemke's method. B NULL: P^-1 C^T; D NULL: cup_lcp_step_init.
 * On a row where D vanishes zeta is an impulse (a measure), taken whole at
 * t_{k+1} as Moreau-Jean does; on a row with D != 0 it is a function of the
 * state, and the trapezoid's weights keep theta = 1/2 second order there:
 * h theta W B in H, and h (1 - theta) W B lambda_k added to the free point
 * (lambda_0 from cup_lcp_step_start). */
int cup_lcp_step_init_bd(cup_lcp_step *ls, const cup_polyset *K, const double *W, double h,
                         const double *B, const double *D, double theta);
/* Before a run from x0 with offset g: lambda_0 on the rows with D != 0 from
 * the LCP 0 <= zeta _|_ C x0 + D zeta + g >= 0 (0 where it has none). */
void cup_lcp_step_start(cup_lcp_step *ls, const double *x0, const double *g);
void cup_lcp_step_free(cup_lcp_step *ls);
/* z from the free point xf for the offset g (scale: cup_polyset_norm of xf,
 * reported in info->scale); eps_target < 0 asks for the exact solution:
 * certified when the gap is below max(1e-12 scale^2, floor), the floor
 * being the gap of slacks at the rounding bound of forming z = xf + H lambda
 * and its slack, i.e. when the active rows' slacks are zero to rounding (a
 * relative target alone fails whenever lambda is large: stiff steps, jumps);
 * certificates in info:
 * eps_cert = 2 mu^T (s + gam) with the impulse mu = h lambda (the
 * complementarity gap, z = xf + W P^-1 C^T mu; for theta = 0 exactly the
 * projector's weak-duality certificate), eta_cert a certified distance of z
 * to K(t). Returns CUP_OK, CUP_WARN_NOT_CERTIFIED, CUP_ERR_LINALG (a
 * singular principal block: M not a P-matrix) or CUP_ERR_NONFINITE. */
int cup_lcp_step_solve(cup_lcp_step *ls, const double *g, const double *xf, double *z,
                       double scale, double eps_target, double eta_target, cup_proj_info *info);

#endif

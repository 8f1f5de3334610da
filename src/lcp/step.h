/* step — the LCP step onto a small polyset, as the theta method takes it
 * (Moreau-Jean time stepping, as in Siconos's EulerMoreauOSI):
 *     W = (I - h theta A)^-1,   x_free = x_k + W (h A x_k + E int u + int f),
 *     x_{k+1} = x_free + H lambda,  H = h W B,  B = P^-1 C^T,
 *     0 <= lambda  _|_  w = C x_{k+1} + g >= 0,   an LCP with M = C H.
 * theta = 0 is the explicit catching-up step (M symmetric: the P-projection);
 * theta = 1/2 is second order where the solution is smooth. The LCP is
 * solved exactly by least-index principal pivoting (Murty), warm-started
 * from the previous active set, aiming the rows a few ulps inside K so
 * that the answer is certainly feasible; dense, for m <= 64 rows and
 * n <= 256. */
#ifndef CUP_LCP_STEP_H
#define CUP_LCP_STEP_H

#include "catchup/projector.h"
#include "set/polyset_impl.h"

typedef struct cup_lcp_step {
  int n, m;
  double h;
  const cup_polyset *K;
  double *H;        /* n x m, column-major */
  double *M;        /* m x m, column-major */
  double *lam, *w, *rhs, *sol, *lu, *work, *s, *gam, *v, *tau, *qs;
  double lq;        /* lambda^T q of the last step (q: the free point's slack) */
  int *piv, *idx;
  unsigned char *act, *prev;
} cup_lcp_step;

/* W (n x n, column-major) from the free step builds H and M; W = NULL is
 * the identity (with h = 1: the P-projection onto K, lambda the projector's
 * multipliers). */
int cup_lcp_step_init(cup_lcp_step *th, const cup_polyset *K, const double *W, double h,
                      char *errmsg);
void cup_lcp_step_free(cup_lcp_step *th);
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
int cup_lcp_step_solve(cup_lcp_step *th, const double *g, const double *xf, double *z,
                       double scale, double eps_target, double eta_target, cup_proj_info *info);

#endif

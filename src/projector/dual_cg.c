/* dual_cg — see dual_cg.h. */
#include "dual_cg.h"

/* out = (M_FF + delta I) w on the free rows, M's rows c_i from C^T's columns. */
static void apply(const cup_polyset *K, const unsigned char *act, double delta, const double *w,
                  double *out, double *u) {
  const la_sparse *Ct = &K->Ct;
  const double *pdinv = K->pdinv;
  for (int i = 0; i < K->m; i++)
    if (act[i])
      for (int a = Ct->p[i]; a < Ct->p[i + 1]; a++) u[Ct->i[a]] += Ct->x[a] * w[i];
  for (int i = 0; i < K->m; i++) {
    if (!act[i]) continue;
    double t = delta * w[i];
    for (int a = Ct->p[i]; a < Ct->p[i + 1]; a++) t += Ct->x[a] * pdinv[Ct->i[a]] * u[Ct->i[a]];
    out[i] = t;
  }
  for (int i = 0; i < K->m; i++)
    if (act[i])
      for (int a = Ct->p[i]; a < Ct->p[i + 1]; a++) u[Ct->i[a]] = 0;
}

/* Preconditioned by M~'s diagonal (||c_i||^2_{P^-1} + delta), to a residual
 * at rounding or a few thousand iterations: the projected-Newton steps and
 * the finishing refinement need no more than a descent direction and a
 * contraction. */
#define CG_MAX_ITER 4000

void dual_cg(const cup_polyset *K, const unsigned char *act, double delta, double *v,
             double *const w[5], double *u) {
  int m = K->m;
  const double *rn = K->rownorm;
  double *x = w[0], *r = w[1], *z = w[2], *p = w[3], *q = w[4];
  double rz = 0, bb = 0;
  for (int i = 0; i < m; i++) {
    x[i] = 0;
    r[i] = act[i] ? v[i] : 0;
    z[i] = p[i] = r[i] / (rn[i] * rn[i] + delta);
    rz += r[i] * z[i];
    bb += r[i] * r[i];
  }
  for (int it = 0; it < CG_MAX_ITER && rz > 0; it++) {
    apply(K, act, delta, p, q, u);
    double pq = 0, rr = 0, rz1 = 0;
    for (int i = 0; i < m; i++) if (act[i]) pq += p[i] * q[i];
    if (!(pq > 0)) break;
    double alpha = rz / pq;
    for (int i = 0; i < m; i++) {
      if (!act[i]) continue;
      x[i] += alpha * p[i];
      r[i] -= alpha * q[i];
      z[i] = r[i] / (rn[i] * rn[i] + delta);
      rr += r[i] * r[i];
      rz1 += r[i] * z[i];
    }
    if (rr <= 1e-28 * bb) break;
    for (int i = 0; i < m; i++) if (act[i]) p[i] = z[i] + (rz1 / rz) * p[i];
    rz = rz1;
  }
  for (int i = 0; i < m; i++) if (act[i]) v[i] = x[i];
}

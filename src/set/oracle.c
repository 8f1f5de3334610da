/* oracle — a user's (eps, eta)-projection, called and checked.
 *
 * What can be checked without knowing the set: the callback succeeded, its
 * point and its claims are finite, and the claims are within what was asked
 * (else the step is reported as not certified, as the projector's are). And
 * one consistency test that catches a point farther than its claims allow:
 * the oracle's answer z' for z itself must satisfy
 *     ||z - z'||_P^2 < d(z)^2 + eps' <= eta_cert^2 + eps'
 * (the paper's definition at z, with d(z) <= eta_cert from the first call).
 * A violation means one of the two answers is false: an error. It costs one
 * more oracle call per projection. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include "catchup.h"
#include "set_impl.h"

static int finite_answer(const double *z, int n, double ec, double hc, char *msg, size_t size) {
  for (int j = 0; j < n; j++)
    if (!isfinite(z[j])) {
      snprintf(msg, size, "the oracle returned z[%d] = %g", j, z[j]);
      return 0;
    }
  if (!(ec >= 0) || !(hc >= 0) || isinf(ec) || isinf(hc)) {
    snprintf(msg, size, "the oracle certified eps = %g, eta = %g (must be finite and >= 0)", ec, hc);
    return 0;
  }
  return 1;
}

int oracle_project(const cup_set *S, double t, const double *x, double *z, double *work,
                   cup_proj_info *info, char *msg, size_t size) {
  int n = S->n;
  double *za = work, *zb = work + n, *w = work + 2 * (size_t)n;
  double et = info->eps_target, ht = info->eta_target, ec = NAN, hc = NAN, ec2 = NAN, hc2 = NAN;
  info->method = CUP_PROJ_AUTO;
  int rc = S->oracle(t, x, et, ht, za, &ec, &hc, S->oracle_ctx);
  if (rc) {
    snprintf(msg, size, "the oracle failed (returned %d)", rc);
    return info->status = CUP_ERR_CALLBACK;
  }
  if (!finite_answer(za, n, ec, hc, msg, size)) return info->status = CUP_ERR_CALLBACK;
  rc = S->oracle(t, za, et, ht, zb, &ec2, &hc2, S->oracle_ctx);
  if (rc) {
    snprintf(msg, size, "the oracle failed (returned %d) on its own answer", rc);
    return info->status = CUP_ERR_CALLBACK;
  }
  if (!finite_answer(zb, n, ec2, hc2, msg, size)) return info->status = CUP_ERR_CALLBACK;
  for (int j = 0; j < n; j++) w[j] = za[j] - zb[j];
  double lo, zz = polyset_metric_norm_bounds(S->K, w, &lo, NULL);
  double allowed = hc * hc + ec2;
  /* rounding of z' itself: a few ulps of the points' size */
  for (int j = 0; j < n; j++) w[j] = fabs(za[j]);
  double slack = 8 * DBL_EPSILON * cup_polyset_norm(S->K, w);
  if (!(lo <= sqrt(allowed) + slack)) {
    snprintf(msg, size,
             "the oracle's answer is farther than its claims allow: projecting it again moved it by "
             "%.3g > sqrt(eta_cert^2 + eps_cert') = %.3g (eta_cert %.3g, eps_cert' %.3g)",
             zz, sqrt(allowed), hc, ec2);
    return info->status = CUP_ERR_CALLBACK;
  }
  int same = 1;
  for (int j = 0; j < n; j++) {
    same &= za[j] == x[j];
    z[j] = za[j];
  }
  info->skipped = same;
  info->iterations = 2;
  info->eps_cert = ec;
  info->eta_cert = hc;
  info->status = ec <= et && hc <= ht ? CUP_OK : CUP_WARN_NOT_CERTIFIED;
  return info->status;
}

static int oracle_check(const cup_set_desc *d, char *errmsg) {
  return d->oracle ? CUP_OK : fail_fmt(errmsg, CUP_ERR_ARG, "set oracle: the oracle callback is NULL");
}

const set_kind set_kind_oracle = {.check = oracle_check};

/* options — the integrator's options: their defaults, their checks, and a
 * new integrator holding a checked copy (integrator.c's front doors and
 * the estimate's run at n/2 in fixed_setup.c). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "options.h"
#include "integrator_impl.h"

void cup_integrator_options_default(cup_integrator_options *o) {
  if (!o) return;
  memset(o, 0, sizeof *o);
  o->scheme = CUP_SCHEME_EXPLICIT;
  o->T = 1;
  o->n = 100;
  o->eps = (cup_schedule){1, -2.1};
  o->eta = (cup_schedule){1, -1.05};
  cup_projector_options_default(&o->proj);
  o->output = CUP_OUTPUT_EVERY;
  o->output_every = 1;
  o->output_samples = 0;
  o->f_order = 3;
  o->theta = 0.5;
  o->tol_abs = 1e-6;
  o->tol_rel = 1e-6;
}

/* tol of the adaptive scheme, the event rate cap, the step-doubling estimate. */
static int validate_tolerances(const cup_integrator_options *o, char *errmsg) {
  if (o->scheme == CUP_SCHEME_ADAPTIVE) {
    if (!(o->tol_abs >= 0) || !isfinite(o->tol_abs))
      return fail_fmt(errmsg, CUP_ERR_ARG, "tol_abs = %g must be finite and >= 0", o->tol_abs);
    if (!(o->tol_rel >= 0) || !isfinite(o->tol_rel))
      return fail_fmt(errmsg, CUP_ERR_ARG, "tol_rel = %g must be finite and >= 0", o->tol_rel);
    if (o->tol_abs == 0 && !(o->tol_rel >= 16 * DBL_EPSILON))
      return fail_fmt(errmsg, CUP_ERR_ARG, "tol_rel = %g with tol_abs = 0 is below what double precision "
                      "can deliver (16 eps = %.2g): raise tol_rel or give tol_abs", o->tol_rel, 16 * DBL_EPSILON);
    if (!(o->max_event_rate >= 0) || !isfinite(o->max_event_rate))
      return fail_fmt(errmsg, CUP_ERR_ARG, "max_event_rate = %g must be finite and >= 0", o->max_event_rate);
  } else if (o->estimate && (o->n < 2 || o->n % 2))
    return fail_fmt(errmsg, CUP_ERR_ARG, "the step-doubling estimate compares with a run at n/2: n = %ld "
                    "must be even", o->n);
  return CUP_OK;
}

int options_check(const cup_integrator_options *o, char *errmsg) {
  if (!(o->T > 0) || !isfinite(o->T))
    return fail_fmt(errmsg, CUP_ERR_ARG, "T = %g must be finite and > 0", o->T);
  if (o->n < 1) return fail_fmt(errmsg, CUP_ERR_ARG, "n = %ld must be >= 1", o->n);
  if ((int)o->scheme < 0 || (int)o->scheme >= (int)CUP_SCHEME_COUNT)
    return fail_fmt(errmsg, CUP_ERR_ARG, "unknown scheme %d", (int)o->scheme);
  if (o->scheme == CUP_SCHEME_THETA && !(o->theta >= 0 && o->theta <= 1))
    return fail_fmt(errmsg, CUP_ERR_ARG, "theta = %g must be in [0, 1]", o->theta);
  int st = validate_tolerances(o, errmsg);
  if (st) return st;
  double e = cup_schedule_value(&o->eps, o->n), t = cup_schedule_value(&o->eta, o->n);
  if (!(e >= 0) || !isfinite(e) || !(t >= 0) || !isfinite(t))
    return fail_fmt(errmsg, CUP_ERR_ARG, "tolerances eps_n = %g, eta_n = %g must be finite and >= 0", e, t);
  switch (o->output) {
    case CUP_OUTPUT_EVERY:
      if (o->output_every < 1)
        return fail_fmt(errmsg, CUP_ERR_ARG, "output every %ld: the stride must be >= 1", o->output_every);
      break;
    case CUP_OUTPUT_SAMPLES:
      if (o->output_samples < 2)
        return fail_fmt(errmsg, CUP_ERR_ARG, "output samples = %ld must be >= 2", o->output_samples);
      if (!(o->output_t0 >= 0 && o->output_t0 < o->T))
        return fail_fmt(errmsg, CUP_ERR_ARG, "output_t0 = %g must be in [0, T = %g)", o->output_t0, o->T);
      break;
    case CUP_OUTPUT_TOL:
      if (o->scheme != CUP_SCHEME_ADAPTIVE)
        return fail_fmt(errmsg, CUP_ERR_ARG, "output tol is the adaptive scheme's (points from its exact flow "
                        "inside a step); the %s scheme has none: choose output every or samples, or scheme "
                        "adaptive", cup_scheme_name(o->scheme));
      if (!(o->output_tol > 0) || !isfinite(o->output_tol))
        return fail_fmt(errmsg, CUP_ERR_ARG, "output tol = %g must be finite and > 0", o->output_tol);
      break;
    case CUP_OUTPUT_FINAL:
    case CUP_OUTPUT_NONE:
      break;
    default:
      return fail_fmt(errmsg, CUP_ERR_ARG, "unknown output kind %d", (int)o->output);
  }
  if (!(o->max_wall_seconds >= 0))
    return fail_fmt(errmsg, CUP_ERR_ARG, "max_wall_seconds = %g must be >= 0", o->max_wall_seconds);
  if (!(o->hmax >= 0) || !isfinite(o->hmax))
    return fail_fmt(errmsg, CUP_ERR_ARG, "hmax = %g must be finite and >= 0", o->hmax);
  return CUP_OK;
}

cup_integrator *integrator_new(const cup_integrator_options *opt, char *errmsg, int *st) {
  cup_integrator_options o;
  if (opt) o = *opt; else cup_integrator_options_default(&o);
  *st = options_check(&o, errmsg);
  if (*st) return NULL;
  cup_integrator *I = calloc(1, sizeof *I);
  if (!I) *st = fail_fmt(errmsg, CUP_ERR_NOMEM, "integrator: out of memory");
  else I->o = o;
  return I;
}

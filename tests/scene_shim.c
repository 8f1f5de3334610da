/* TEMPORARY stand-ins for the integrator functions the scene loader calls
 * (cup_schedule_*, cup_scheme_*, cup_integrator_options_default), so that
 * test_scene links before src/integrator.c lands. Linked only into
 * test_scene, and only while src/integrator.c does not exist
 * (tests/CMakeLists.txt); delete this file once it does. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"

static const char *skip(const char *s) { while (*s == ' ') s++; return s; }

/* "n^P", "C", "C*n^P" with optional spaces. */
int cup_schedule_parse(const char *spec, cup_schedule *out, char *errmsg) {
  double coef = 1, power = 0;
  const char *s = skip(spec ? spec : "");
  char *end;
  if (*s != 'n') {
    coef = strtod(s, &end);
    if (end == s) goto bad;
    s = skip(end);
    if (*s == '*') s = skip(s + 1); else if (*s) goto bad;
  }
  if (*s == 'n') {
    s = skip(s + 1);
    if (*s != '^') goto bad;
    s = skip(s + 1);
    power = strtod(s, &end);
    if (end == s) goto bad;
    s = skip(end);
  }
  if (*s || !isfinite(coef) || coef < 0 || !isfinite(power)) goto bad;
  out->coef = coef;
  out->power = power;
  return CUP_OK;
bad:
  if (errmsg) snprintf(errmsg, CUP_ERRMSG_LEN, "schedule '%s': expected like \"n^-2.1\", \"0.5*n^-1\" or \"1e-6\"", spec);
  return CUP_ERR_PARSE;
}

double cup_schedule_value(const cup_schedule *s, long n) { return s->coef * pow((double)n, s->power); }

int cup_schedule_format(const cup_schedule *s, char *buf, unsigned long size) {
  if (s->power == 0) return snprintf(buf, size, "%g", s->coef) < 0;
  if (s->coef == 1) return snprintf(buf, size, "n^%g", s->power) < 0;
  return snprintf(buf, size, "%g*n^%g", s->coef, s->power) < 0;
}

const char *cup_scheme_name(int scheme) {
  static const char *names[] = {"explicit", "implicit", "exponential"};
  return scheme >= 0 && scheme < 3 ? names[scheme] : "unknown";
}

int cup_scheme_parse(const char *name) {
  for (int k = 0; name && k < 3; k++)
    if (!strcmp(name, cup_scheme_name(k))) return k;
  return -1;
}

void cup_integrator_options_default(cup_integrator_options *o) {
  memset(o, 0, sizeof *o);
  o->scheme = CUP_SCHEME_EXPLICIT;
  o->T = 1;
  o->n = 100;
  o->eps = (cup_schedule){1, -2.1};
  o->eta = (cup_schedule){1, -1.05};
  cup_projector_options_default(&o->proj);
  o->output = CUP_OUTPUT_EVERY;
  o->output_every = 1;
  o->f_order = 3;
}

/* schedule — the paper's tolerance schedules eps_n = c n^p (include/
 * catchup/integrator.h): parsed from "n^-2.1", "0.5*n^-1.05" or a number,
 * valued at n, written back as the shortest text that reads back the same.
 * The integrator's options hold two; scenes, sweeps and apps parse them. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "catchup.h"
#include "util/fail.h"

static const char *skip_ws(const char *s) { while (isspace((unsigned char)*s)) s++; return s; }

int cup_schedule_parse(const char *spec, cup_schedule *out, char *errmsg) {
  if (!spec || !out) return fail_fmt(errmsg, CUP_ERR_ARG, "schedule: NULL argument");
  const char *s = skip_ws(spec);
  double coef = 1, power = 0;
  char *end;
  if (*s != 'n') {                           /* a number, maybe followed by "*n^p" */
    coef = strtod(s, &end);
    if (end == s) goto bad;
    s = skip_ws(end);
    if (*s == '*') {
      s = skip_ws(s + 1);
      if (*s != 'n') goto bad;
    } else if (*s) {
      goto bad;
    }
  }
  if (*s == 'n') {
    s = skip_ws(s + 1);
    if (*s == '^') {
      s = skip_ws(s + 1);
      power = strtod(s, &end);
      if (end == s) goto bad;
      s = end;
    } else {
      power = 1;
    }
    s = skip_ws(s);
    if (*s) goto bad;
  }
  if (!isfinite(coef) || !isfinite(power) || coef < 0)
    return fail_fmt(errmsg, CUP_ERR_PARSE, "schedule '%s': the coefficient must be finite and >= 0", spec);
  out->coef = coef;
  out->power = power;
  return CUP_OK;
bad:
  return fail_fmt(errmsg, CUP_ERR_PARSE,
                  "schedule '%s': expected a number, \"n^-2.1\" or \"0.5*n^-1.05\"", spec);
}

double cup_schedule_value(const cup_schedule *s, long n) {
  if (!s) return NAN;
  return s->power == 0 ? s->coef : s->coef * pow((double)n, s->power);
}

/* The shortest %g text that reads back as the same double. */
static void shortest(double v, char *out, size_t size) {
  for (int digits = 1; digits <= 17; digits++) {
    snprintf(out, size, "%.*g", digits, v);
    if (strtod(out, NULL) == v) return;
  }
}

int cup_schedule_format(const cup_schedule *s, char *buf, unsigned long size) {
  if (!s) return -1;
  char c[32], p[32];
  shortest(s->coef, c, sizeof c);
  shortest(s->power, p, sizeof p);
  if (s->power == 0) return snprintf(buf, size, "%s", c);
  if (s->coef == 1) return snprintf(buf, size, "n^%s", p);
  return snprintf(buf, size, "%s*n^%s", c, p);
}

/* record: catchup-run's signals from the adaptive scheme's own state
 * (integrator_record, src/integrator/record.h: the netlist's signal map
 * composed with the mode's rows of x, u and zeta) against the public path
 * a user's sink takes, cup_integrator_zeta then cup_netlist_signals, at
 * every record of the example circuits (switched and not, with every
 * signal probed: the configurations' constraint multipliers folded in),
 * at samples inside steps and at the steps' own ends. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>
#include "testutil.h"
#include "integrator/record.h"

typedef struct {
  cup_netlist *nl;
  const cup_integrator *I;
  int ns, m;
  long records, fast;
  double worst;              /* the largest |fast - public| / (the size of the terms summed) */
  double vmax[256];          /* |(x, u, zeta)| at its largest so far */
} cmp_t;

/* |fast - public| against the size of the terms each signal sums (the
 * map's row times |(x, u, zeta)|, each at its largest so far): an
 * op-amp's output is its gain times a difference that rounds at the
 * inputs' size (the precision rectifier's v(oa): -1.8e-12 by the public
 * path, 0 by the composed rows), and a sine rounds at its amplitude
 * (sin at a zero crossing gives 6e-16 of 5 V, its rotation 2e-16). */
static int both(long k, double t, const double *x, void *ctx) {
  (void)k;
  cmp_t *c = ctx;
  double fast[64], pub[64], zeta[64] = {0}, v[256];
  c->records++;
  const signal_map *S = nl_signal_map(c->nl);
  if (!integrator_record(c->I, S, fast)) return 0;
  c->fast++;
  assert_int_equal(cup_integrator_zeta(c->I, zeta), CUP_OK);
  assert_int_equal(cup_netlist_signals(c->nl, t, x, zeta, pub), CUP_OK);
  int nc = S->n + S->p + S->m;
  assert_true(nc <= 256);
  for (int j = 0; j < S->n; j++) v[j] = x[j];
  if (S->p) assert_int_equal(cup_input_eval(S->u, t, v + S->n), CUP_OK);
  for (int j = 0; j < S->m; j++) v[S->n + S->p + j] = zeta[j];
  for (int j = 0; j < nc; j++) c->vmax[j] = fmax(c->vmax[j], fabs(v[j]));
  for (int s = 0; s < c->ns; s++) {
    double size = 0;
    for (int j = 0; j < nc; j++) size += fabs(S->rows[(size_t)s * nc + j]) * c->vmax[j];
    c->worst = fmax(c->worst, fabs(fast[s] - pub[s]) / fmax(size, 1e-300));
    if (getenv("DBG") && fabs(fast[s] - pub[s]) > 1e-9 * size) printf("%s t=%.17g fast %.17g pub %.17g size %g\n", cup_netlist_signal_name(c->nl, s), t, fast[s], pub[s], size);
  }
  return 0;
}

/* name's netlist under the adaptive scheme over the first tenth of its
 * .tran, with samples (every = 0) or every step's end recorded, the
 * signals probes (space-separated) probed. */
static cmp_t run(const char *name, const char *probes, int every) {
  char err[CUP_ERRMSG_LEN], path[512];
  snprintf(path, sizeof path, CUP_SOURCE_DIR "/examples/circuits/%s.cir", name);
  cmp_t c = {0};
  if (cup_netlist_load(&c.nl, path, NULL, 0, err)) fail_msg("%s", err);
  char list[512], *save = NULL;
  snprintf(list, sizeof list, "%s", probes);
  for (char *p = strtok_r(list, " ", &save); p; p = strtok_r(NULL, " ", &save))
    if (cup_netlist_probe(c.nl, p, err) < 0) fail_msg("%s", err);
  c.ns = cup_netlist_signal_count(c.nl);
  assert_true(c.ns <= 64);
  double tstep, tstop;
  assert_true(cup_netlist_tran(c.nl, &tstep, &tstop));
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.tol_abs = o.tol_rel = 1e-6;
  o.T = tstop / 10;
  o.output = every ? CUP_OUTPUT_EVERY : CUP_OUTPUT_SAMPLES;
  o.output_every = 1;
  o.output_samples = 401;
  cup_integrator *I = NULL;
  cup_switching sw;
  int st = cup_netlist_switching(c.nl, &sw) ? cup_integrator_create_switched(&I, &sw, cup_netlist_input(c.nl), &o, err)
                                            : cup_integrator_create(&I, cup_netlist_lcs(c.nl), cup_netlist_input(c.nl),
                                                                    &o, err);
  if (st) fail_msg("%s: %s", name, err);
  c.I = I;
  cup_run_info info;
  st = cup_integrator_run(I, cup_netlist_x0(c.nl), both, &c, &info);
  if (st < 0) fail_msg("%s: %s", name, info.message);
  cup_integrator_free(&I);
  cup_netlist_free(&c.nl);
  return c;
}

/* Every signal of each circuit: switches' gates and supplies that a
 * configuration disconnects, which the exosystem leaves out, included (u
 * evaluated at the record for them), and the configurations' constraint
 * multipliers (the flyback's open switch: v(d) reads the cut's voltage). */
static void test_records_are_the_public_signals(void **state) {
  (void)state;
  /* (tol: of the terms' size; the series-resonant tank's source ramps
   * 200 V in 1 ns: at a corner its value rounds with t, 2e11 V/s times an
   * ulp of t, 5e-12 of the 100 V it sums with) */
  static const struct { const char *name, *probes; double tol; } cases[] = {
    {"precision-rectifier", "all", 1e-13}, {"sixpulse", "all", 1e-13}, {"bridge", "all", 1e-13},
    {"clamp", "all", 1e-13}, {"doubler", "all", 1e-13}, {"paper-fig2", "all", 1e-13}, {"buckboost", "all", 1e-13},
    {"boost", "all", 1e-13}, {"flyback", "all", 1e-13}, {"fullbridge", "all", 1e-13}, {"resonant", "all", 1e-13},
    {"ladder", "all", 1e-13}, {"halfwave-rc", "all", 1e-13}, {"rl-halfwave", "all", 1e-13},
    {"bridge-lc", "all", 1e-13}, {"series-resonant", "all", 1e-11},
  };
  for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++)
    for (int every = 0; every < 2; every++) {
      cmp_t c = run(cases[k].name, cases[k].probes, every);
      /* every record after t = 0 (a catching-up step's aside) takes the
       * composed rows: samples all of them, own steps most */
      if (c.fast < (every ? c.records / 2 : c.records - 1) || c.worst > cases[k].tol)
        fail_msg("%s (%s): %ld of %ld records by the composed rows, largest difference %.3g of the terms' size",
                 cases[k].name, every ? "own steps" : "samples", c.fast, c.records, c.worst);
      printf("%-20s %-9s %ld of %ld records composed, largest difference %.3g of the terms' size\n", cases[k].name,
             every ? "own steps" : "samples", c.fast, c.records, c.worst);
    }
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_records_are_the_public_signals),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

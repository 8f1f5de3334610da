/* stress, large circuits: a 10^4-stage diode ladder (scripts/make-ladder)
 * read and formulated from its netlist, then run by the explicit scheme
 * with exact projections against its closed form: without leaks every
 * capacitor holds the largest source voltage so far, v_k(t_j) =
 * max(0, max_{i <= j} V(t_i)) (the catching-up step is then exact: the
 * set {v1 >= V(t), v_k >= v_{k-1}} moves, and each step projects the last
 * state onto it). Times are printed, not asserted. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <time.h>
#include <cmocka.h>
#include "testutil.h"
#include "util/clock.h"

enum { STAGES = 10000 };

/* The netlist scripts/make-ladder writes, without leaks. */
static char *ladder(int n) {
  size_t cap = 64 * (size_t)n + 256, len = 0;
  char *s = malloc(cap);
  assert_non_null(s);
  len += (size_t)snprintf(s + len, cap - len, "Diode ladder, %d stages\nV1 n0 0 SIN(0 10 50)\n", n);
  for (int k = 1; k <= n; k++)
    len += (size_t)snprintf(s + len, cap - len, "D%d n%d n%d\nC%d n%d 0 1u\n", k, k - 1, k, k, k);
  snprintf(s + len, cap - len, ".tran 100u 20m\n.end\n");
  return s;
}

typedef struct { long samples; double worst, vmax; double h; } check_ctx;

static int check_sink(long k, double t, const double *x, void *vp) {
  check_ctx *c = vp;
  double V = 10 * sin(2 * M_PI * 50 * t);
  c->vmax = fmax(c->vmax, fmax(V, 0));
  for (int j = 0; j < STAGES; j++) c->worst = fmax(c->worst, fabs(x[j] - c->vmax));
  c->samples++;
  (void)k;
  return 0;
}

static void test_ladder_10k(void **state) {
  (void)state;
  char *text = ladder(STAGES), err[CUP_ERRMSG_LEN];
  cup_netlist *nl = NULL;
  double t0 = now_seconds();
  assert_int_equal(cup_netlist_load_string(&nl, text, "ladder.cir", NULL, 0, err), CUP_OK);
  double t1 = now_seconds();
  const cup_lcs *L = cup_netlist_lcs(nl);
  assert_int_equal(cup_lcs_dim(L), STAGES);
  assert_int_equal(cup_lcs_rows(L), STAGES);
  assert_int_equal(cup_netlist_row_fixed(nl, 0), 0);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.T = 6e-3;                                      /* the first rise and a little beyond */
  o.n = 30;
  o.eps = o.eta = (cup_schedule){0, 0};
  cup_integrator *I = NULL;
  assert_int_equal(cup_integrator_create(&I, L, cup_netlist_input(nl), &o, err), CUP_OK);
  check_ctx c = {0, 0, 0, o.T / (double)o.n};
  cup_run_info info;
  double t2 = now_seconds();
  int st = cup_integrator_run(I, cup_netlist_x0(nl), check_sink, &c, &info);
  double t3 = now_seconds();
  /* exact projections on a set with no interior direction known may end
   * uncertified (eta); the states are checked here against the closed form */
  assert_true(st >= 0);
  print_message("ladder %d stages: load and formulation %.3f s, create %.3f s, %ld steps %.3f s "
                "(%lld dual iterations), max |v_k - max V| = %.2e V\n", STAGES, t1 - t0, t2 - t1, o.n, t3 - t2,
                info.dual_iterations, c.worst);
  assert_int_equal(c.samples, o.n + 1);
  assert_true(c.worst <= 1e-7);                 /* measured 1.3e-8 V of 10 V: the exact projection's accuracy */
  cup_integrator_free(&I);
  cup_netlist_free(&nl);
  free(text);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_ladder_10k),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

/* scene: the shipped examples against values written out here from the
 * paper (Sec. 7) and closed-form integrals; overrides; the round trip
 * through cup_scene_text; and the malformed corpus: every .yaml file in
 * tests/scenes/bad names its expected error in a "# expect: ..." first line.
 * The LCS internals (src/lcs_impl.h) are read to compare matrices. */
#define _GNU_SOURCE                  /* dladdr */
#include <dlfcn.h>
#include <execinfo.h>
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <dirent.h>
#include <sys/stat.h>
#include <cmocka.h>
#include "testutil.h"
#include "badcorpus.h"
#include "heap.h"
#include "lcs_impl.h"
#include "polyset_impl.h"

/* ---- failed allocations (bench/heap.c's fault mode; off under ASan) -------- */
/* Dependencies whose own out-of-memory paths fail are spared (the
 * next allocation is failed instead): GSL (its default handler aborts, and
 * gsl_matrix_alloc leaks its struct when the block allocation fails),
 * CHOLMOD 3.0.14's cholmod_spsolve (dereferences X when spzeros fails), and
 * libyaml 0.2.5's growing of a stack (yaml_parser_load leaks a sequence's
 * item stack when the node stack cannot grow). */
#if HEAP_INTERPOSED
static int dependency_bug(void *caller, int grow) {
  Dl_info info;
  if (dladdr(caller, &info) && info.dli_fname && strstr(info.dli_fname, "libgsl")) return 1;
  if (grow && dladdr(caller, &info) && info.dli_fname && strstr(info.dli_fname, "libyaml")) return 1;
  void *frames[16];
  int n = backtrace(frames, 16);
  for (int k = 0; k < n; k++)
    if (dladdr(frames[k], &info) && info.dli_sname && !strcmp(info.dli_sname, "cholmod_spsolve")) return 1;
  return 0;
}
#endif

#define EX CUP_EXAMPLES_DIR
#define BAD CUP_BAD_SCENES_DIR
#define TOL 1e-14

static cup_scene *load_ok(const char *path, const char *const *ovr, int nov) {
  char err[CUP_ERRMSG_LEN] = "";
  cup_scene *s = NULL;
  int st = cup_scene_load(&s, path, ovr, nov, err);
  if (st) fail_msg("loading %s failed (%d): %s", path, st, err);
  assert_non_null(s);
  return s;
}

/* Load that must fail; returns the message (static buffer). */
static const char *load_bad(const char *path, const char *const *ovr, int nov) {
  static char err[CUP_ERRMSG_LEN];
  cup_scene *s = (cup_scene *)&err;            /* must come back NULL */
  int st = cup_scene_load(&s, path, ovr, nov, err);
  if (st == CUP_OK) fail_msg("%s loaded but should not have", path);
  assert_null(s);
  assert_null(strchr(err, '\n'));
  return err;
}

static void assert_contains(const char *msg, const char *want) {
  if (!strstr(msg, want)) fail_msg("message\n  %s\ndoes not contain\n  %s", msg, want);
}

/* ---- dense views of what the scene built (row-major) ---------------------- */

static void dense_of(const la_sparse *S, int has, int nr, int nc, double *out) {
  memset(out, 0, sizeof(double) * (size_t)nr * (size_t)nc);
  if (!has) return;
  assert_int_equal(S->nrow, nr);
  assert_int_equal(S->ncol, nc);
  for (int j = 0; j < nc; j++)
    for (int k = S->p[j]; k < S->p[j + 1]; k++) out[S->i[k] * nc + j] += S->x[k];
}

typedef struct dense_lcs {
  int n, m, p;
  double A[64], C[64], E[64], G[64], F[16], P[64];
} dense_lcs;

static void dense_lcs_of(const cup_scene *s, dense_lcs *d) {
  const cup_lcs *L = cup_scene_lcs(s);
  assert_non_null(L);
  const cup_polyset *K = L->K;
  int n = d->n = L->n, m = d->m = L->m, p = d->p = L->p;
  assert_true(n * n <= 64 && m * n <= 64 && n * p <= 64 && m * p <= 64 && m <= 16);
  dense_of(&L->A, L->has_A, n, n, d->A);
  dense_of(&K->C, 1, m, n, d->C);
  dense_of(&L->E, L->has_E, n, p, d->E);
  dense_of(&L->G, L->has_G, m, p, d->G);
  memcpy(d->F, L->F, sizeof(double) * (size_t)m);
  if (K->pkind == CUP_METRIC_SPARSE) {
    dense_of(&K->Pfull, 1, n, n, d->P);
  } else {
    memset(d->P, 0, sizeof d->P);
    for (int j = 0; j < n; j++) d->P[j * n + j] = K->pkind == CUP_METRIC_IDENTITY ? 1 : K->pd[j];
  }
}

static void assert_array_close(const double *a, const double *b, int len, double tol, const char *what) {
  for (int k = 0; k < len; k++)
    if (!(fabs(a[k] - b[k]) <= tol)) fail_msg("%s[%d] = %.17g, expected %.17g", what, k, a[k], b[k]);
}

static double integral(const cup_scene *s, int j, double a, double b) {
  double out[8];
  assert_int_equal(cup_input_integral(cup_scene_input(s), a, b, out), CUP_OK);
  return out[j];
}

static double value_at(const cup_scene *s, int j, double t) {
  double out[8];
  assert_int_equal(cup_input_eval(cup_scene_input(s), t, out), CUP_OK);
  return out[j];
}

/* The paper's circuit matrices at R1, R2, R3, L2, L3, C4 (Sec. 7). */
static void paper_A(double R1, double R2, double R3, double L2, double L3, double C4, double *A) {
  const double a[9] = {0, 1, 0, -1 / (L3 * C4), -(R1 + R3) / L3, R1 / L3, 0, R1 / L2, -(R1 + R2) / L2};
  memcpy(A, a, sizeof a);
}

/* ---- the shipped examples ------------------------------------------------- */

static void test_paper_fig2(void **state) {
  (void)state;
  cup_scene *s = load_ok(EX "/paper-fig2.yaml", NULL, 0);
  dense_lcs d;
  dense_lcs_of(s, &d);
  assert_string_equal(cup_scene_name(s), "paper-fig2");
  assert_int_equal(d.n, 3); assert_int_equal(d.m, 2); assert_int_equal(d.p, 1);
  /* R1 = 1, R2 = 2, R3 = 1, L2 = 1, L3 = 2, C4 = 1 */
  const double A[9] = {0, 1, 0, -0.5, -1, 0.5, 0, 1, -3};
  const double C[6] = {0, 1, -1, 0, 1, 0}, E[3] = {0, 0.5, 1}, G[2] = {0, 0}, F[2] = {0, 0};
  const double P[9] = {1, 0, 0, 0, 2, 0, 0, 0, 1};
  assert_array_close(d.A, A, 9, TOL, "A");
  assert_array_close(d.C, C, 6, TOL, "C");
  assert_array_close(d.E, E, 3, TOL, "E");
  assert_array_close(d.G, G, 2, TOL, "G");
  assert_array_close(d.F, F, 2, TOL, "F");
  assert_array_close(d.P, P, 9, TOL, "P");
  assert_int_equal(cup_lcs_fixed_set(cup_scene_lcs(s)), 1);
  /* u = 16 sin(6 pi t) - 0.5: int_0^0.1 = 16 (1 - cos(0.6 pi)) / (6 pi) - 0.05 */
  assert_close(integral(s, 0, 0, 0.1), 16 * (1 - cos(0.6 * M_PI)) / (6 * M_PI) - 0.05, 1e-13);
  assert_close(value_at(s, 0, 1.0 / 12), 15.5, 1e-13);
  const double zero[3] = {0, 0, 0};
  assert_array_close(cup_scene_x0(s), zero, 3, 0, "x0");
  const cup_integrator_options *o = cup_scene_options(s);
  assert_close(o->T, 1, 0);
  assert_int_equal(o->n, 100);
  assert_string_equal(cup_scene_eps_spec(s), "n^-2.1");
  assert_string_equal(cup_scene_eta_spec(s), "n^-1.05");
  assert_close(o->eps.coef, 1, 0); assert_close(o->eps.power, -2.1, 0);
  assert_close(o->eta.coef, 1, 0); assert_close(o->eta.power, -1.05, 0);
  assert_close(cup_schedule_value(&o->eps, 100), pow(10, -4.2), 1e-18);
  assert_close(cup_schedule_value(&o->eta, 100), pow(10, -2.1), 1e-16);
  assert_int_equal(o->scheme, CUP_SCHEME_EXPLICIT);
  assert_int_equal(o->proj.method, CUP_PROJ_AUTO);
  assert_int_equal(o->output, CUP_OUTPUT_EVERY);
  assert_int_equal(o->output_every, 1);
  cup_scene_free(&s);
  assert_null(s);
}

static void test_paper_fig3(void **state) {
  (void)state;
  cup_scene *s = load_ok(EX "/paper-fig3.yaml", NULL, 0);
  dense_lcs d;
  dense_lcs_of(s, &d);
  assert_string_equal(cup_scene_name(s), "paper-fig3");
  const double A[9] = {0, 1, 0, -0.5, -1, 0.5, 0, 1, -3}, G[2] = {0, 1};
  assert_array_close(d.A, A, 9, TOL, "A");
  assert_array_close(d.G, G, 2, TOL, "G");
  assert_int_equal(cup_lcs_fixed_set(cup_scene_lcs(s)), 0);
  /* u = sign(sin(4 pi t)): +1 on (0, 1/4), -1 on (1/4, 1/2), 0 at the jumps */
  assert_close(value_at(s, 0, 0.1), 1, 0);
  assert_close(value_at(s, 0, 0.3), -1, 0);
  assert_close(value_at(s, 0, 0.25), 0, 0);
  assert_close(value_at(s, 0, 0), 0, 0);
  assert_close(integral(s, 0, 0, 0.1), 0.1, 1e-15);
  assert_close(integral(s, 0, 0, 0.5), 0, 1e-15);
  assert_close(integral(s, 0, 0.2, 0.35), 0.05 - 0.1, 1e-15);
  assert_int_equal(cup_scene_options(s)->n, 100);
  cup_scene_free(&s);
}

/* The general lcs form gives the circuit's matrices; its defaults hold. */
static void test_lcs_generic_is_circuit(void **state) {
  (void)state;
  cup_scene *g = load_ok(EX "/lcs-generic.yaml", NULL, 0), *c = load_ok(EX "/paper-fig2.yaml", NULL, 0);
  dense_lcs dg, dc;
  dense_lcs_of(g, &dg);
  dense_lcs_of(c, &dc);
  assert_int_equal(dg.n, dc.n); assert_int_equal(dg.m, dc.m); assert_int_equal(dg.p, dc.p);
  assert_array_close(dg.A, dc.A, 9, TOL, "A");
  assert_array_close(dg.C, dc.C, 6, TOL, "C");
  assert_array_close(dg.E, dc.E, 3, TOL, "E");
  assert_array_close(dg.G, dc.G, 2, TOL, "G");
  assert_array_close(dg.F, dc.F, 2, TOL, "F");
  assert_array_close(dg.P, dc.P, 9, TOL, "P");
  for (double a = 0; a < 1; a += 0.125)
    assert_close(integral(g, 0, a, a + 0.1), integral(c, 0, a, a + 0.1), 1e-14);
  assert_string_equal(cup_scene_name(g), "lcs-generic");  /* the file stem */
  assert_string_equal(cup_scene_eps_spec(g), "n^-2.1");
  assert_string_equal(cup_scene_eta_spec(g), "n^-1.05");
  const cup_integrator_options *o = cup_scene_options(g);
  assert_int_equal(o->scheme, CUP_SCHEME_EXPLICIT);
  assert_int_equal(o->output, CUP_OUTPUT_EVERY);
  assert_int_equal(o->output_every, 1);
  const double zero[3] = {0, 0, 0};
  assert_array_close(cup_scene_x0(g), zero, 3, 0, "x0");
  cup_scene_free(&g);
  cup_scene_free(&c);
}

static void test_sparse_mtx(void **state) {
  (void)state;
  cup_scene *s = load_ok(EX "/sparse-mtx/scene.yaml", NULL, 0);
  dense_lcs d;
  dense_lcs_of(s, &d);
  assert_string_equal(cup_scene_name(s), "sparse-chain");
  assert_int_equal(d.n, 5); assert_int_equal(d.m, 4); assert_int_equal(d.p, 1);
  double A[25] = {0}, C[20] = {0}, P[25] = {0}, E[5] = {1, 0, 0, 0, 0};
  for (int i = 0; i < 5; i++) {
    A[i * 5 + i] = -2;
    P[i * 5 + i] = 1;
    if (i < 4) { A[i * 5 + i + 1] = A[(i + 1) * 5 + i] = 1; P[i * 5 + i + 1] = P[(i + 1) * 5 + i] = 0.2; }
    if (i < 4) { C[i * 5 + i] = 1; C[i * 5 + i + 1] = -1; }
  }
  assert_array_close(d.A, A, 25, 0, "A");
  assert_array_close(d.C, C, 20, 0, "C");
  assert_array_close(d.P, P, 25, 0, "P");   /* the symmetric file, both triangles */
  assert_array_close(d.E, E, 5, 0, "E");
  const double x0[5] = {4, 3, 2, 1, 0};
  assert_array_close(cup_scene_x0(s), x0, 5, 0, "x0");
  /* u = 2 sin(2 pi t): int_0^0.25 = 2 / (2 pi) */
  assert_close(integral(s, 0, 0, 0.25), 1 / M_PI, 1e-14);
  const cup_integrator_options *o = cup_scene_options(s);
  assert_close(o->T, 2, 0);
  assert_int_equal(o->n, 1000);
  assert_string_equal(cup_scene_eps_spec(s), "1e-10");
  assert_close(cup_schedule_value(&o->eps, 1000), 1e-10, 1e-25);
  assert_close(cup_schedule_value(&o->eta, 7), 1e-8, 1e-23);
  assert_int_equal(o->scheme, CUP_SCHEME_IMPLICIT);
  assert_int_equal(o->proj.method, CUP_PROJ_ACTIVESET);
  assert_int_equal(o->proj.max_iter, 200);
  assert_int_equal(o->output, CUP_OUTPUT_SAMPLES);
  assert_int_equal(o->output_samples, 101);
  cup_scene_free(&s);
}

/* p = 2 with one component per list; pwl; a bare number as a term. */
static void test_multi_input_and_pwl(void **state) {
  (void)state;
  const char *text =
      "lcs:\n  C: [[1, 0]]\n  E: [[1, 0], [0, 1]]\n"
      "input:\n  - [{type: pwl, points: [[0, 0], [1, 2]]}, 1]\n  - 3\n"
      "T: 2\nn: 1e6\nx0: [1, 2]\neps: 0\nprojector: {max_iter: 7}\noutput: final\n";
  char err[CUP_ERRMSG_LEN];
  cup_scene *s = NULL;
  int st = cup_scene_load_string(&s, text, "multi.yaml", NULL, NULL, 0, err);
  if (st) fail_msg("%s", err);
  assert_string_equal(cup_scene_name(s), "multi");
  /* u0 = pwl(0 -> 0, 1 -> 2, then 2) + 1, u1 = 3 */
  assert_close(integral(s, 0, 0, 1), 1 + 1, 1e-15);
  assert_close(integral(s, 0, 1, 2), 2 + 1, 1e-15);
  assert_close(integral(s, 1, 0, 2), 6, 1e-15);
  assert_close(value_at(s, 0, 0.5), 2, 1e-15);
  assert_int_equal(cup_scene_options(s)->n, 1000000);
  assert_string_equal(cup_scene_eps_spec(s), "0");
  assert_int_equal(cup_scene_options(s)->proj.max_iter, 7);
  assert_int_equal(cup_scene_options(s)->output, CUP_OUTPUT_FINAL);
  cup_scene_free(&s);
  /* no E and no G: p = 0, no input object */
  st = cup_scene_load_string(&s, "lcs: {C: [[1]]}\nT: 1\nn: 1\noutput: none\n", NULL, NULL, NULL, 0, err);
  if (st) fail_msg("%s", err);
  assert_null(cup_scene_input(s));
  assert_string_equal(cup_scene_name(s), "<string>");
  assert_int_equal(cup_scene_options(s)->output, CUP_OUTPUT_NONE);
  cup_scene_free(&s);
}

/* ---- overrides ------------------------------------------------------------- */

static void test_overrides_change_values(void **state) {
  (void)state;
  const char *ovr[] = {"circuit.R1=2", "input.0.amplitude=8", "n=1000", "x0=[0, 1, 0]"};
  cup_scene *s = load_ok(EX "/paper-fig2.yaml", ovr, 4);
  dense_lcs d;
  dense_lcs_of(s, &d);
  double A[9];
  paper_A(2, 2, 1, 1, 2, 1, A);
  const double A_by_hand[9] = {0, 1, 0, -0.5, -1.5, 1, 0, 2, -4};
  assert_array_close(A, A_by_hand, 9, 0, "paper_A");
  assert_array_close(d.A, A_by_hand, 9, TOL, "A");
  assert_close(integral(s, 0, 0, 0.1), 8 * (1 - cos(0.6 * M_PI)) / (6 * M_PI) - 0.05, 1e-13);
  assert_int_equal(cup_scene_options(s)->n, 1000);
  const double x0[3] = {0, 1, 0};
  assert_array_close(cup_scene_x0(s), x0, 3, 0, "x0");
  cup_scene_free(&s);
  /* a whole subtree */
  const char *sub[] = {"circuit={R1: 1, R2: 2, R3: 1, L2: 1, L3: 4, C4: 1}"};
  s = load_ok(EX "/paper-fig2.yaml", sub, 1);
  dense_lcs_of(s, &d);
  paper_A(1, 2, 1, 1, 4, 1, A);
  assert_array_close(d.A, A, 9, TOL, "A");
  assert_close(d.P[4], 4, 0);
  cup_scene_free(&s);
  /* one matrix entry, by list indices */
  const char *entry[] = {"lcs.A.1.2=0.25"};
  s = load_ok(EX "/lcs-generic.yaml", entry, 1);
  dense_lcs_of(s, &d);
  const double A2[9] = {0, 1, 0, -0.5, -1, 0.25, 0, 1, -3};
  assert_array_close(d.A, A2, 9, 0, "A");
  cup_scene_free(&s);
}

static void test_overrides_add_keys(void **state) {
  (void)state;
  /* lcs-generic.yaml has no eps and no output */
  const char *ovr[] = {"eps=1e-6", "output.every=10", "scheme = implicit", "name='renamed'"};
  cup_scene *s = load_ok(EX "/lcs-generic.yaml", ovr, 4);
  const cup_integrator_options *o = cup_scene_options(s);
  assert_string_equal(cup_scene_eps_spec(s), "1e-6");
  assert_close(o->eps.coef, 1e-6, 0);
  assert_close(o->eps.power, 0, 0);
  assert_string_equal(cup_scene_eta_spec(s), "n^-1.05");
  assert_int_equal(o->output, CUP_OUTPUT_EVERY);
  assert_int_equal(o->output_every, 10);
  assert_int_equal(o->scheme, CUP_SCHEME_IMPLICIT);
  assert_string_equal(cup_scene_name(s), "renamed");
  cup_scene_free(&s);
}

/* An override that names another shape of a value replaces the scene's
 * shape, as its user means it (docs/scene-format.md, Overrides). */
static void test_overrides_replace_shapes(void **state) {
  (void)state;
  /* output: one mode at a time */
  const char *o1[] = {"output.samples=2"};                      /* the file has {every: 1} */
  cup_scene *s = load_ok(EX "/paper-fig2.yaml", o1, 1);
  assert_int_equal(cup_scene_options(s)->output, CUP_OUTPUT_SAMPLES);
  assert_int_equal(cup_scene_options(s)->output_samples, 2);
  cup_scene_free(&s);
  const char *o2[] = {"output=final", "output.every=5"};
  s = load_ok(EX "/paper-fig2.yaml", o2, 2);
  assert_int_equal(cup_scene_options(s)->output, CUP_OUTPUT_EVERY);
  assert_int_equal(cup_scene_options(s)->output_every, 5);
  cup_scene_free(&s);
  /* projector: a word is {method: word} */
  const char *o3[] = {"projector=fista", "projector.max_iter=7"};
  s = load_ok(EX "/paper-fig2.yaml", o3, 2);
  assert_int_equal(cup_scene_options(s)->proj.method, CUP_PROJ_FISTA);
  assert_int_equal(cup_scene_options(s)->proj.max_iter, 7);
  cup_scene_free(&s);
  const char *o4[] = {"projector.method=pg"};                   /* the file has {method: activeset, max_iter: 200} */
  s = load_ok(EX "/sparse-mtx/scene.yaml", o4, 1);
  assert_int_equal(cup_scene_options(s)->proj.method, CUP_PROJ_PG);
  assert_int_equal(cup_scene_options(s)->proj.max_iter, 200);
  cup_scene_free(&s);
  /* a matrix: inline rows or {file: ...}; back to the file gives the original */
  const char *o5[] = {"lcs.A=[[1, 0, 0, 0, 0], [0, 1, 0, 0, 0], [0, 0, 1, 0, 0], [0, 0, 0, 1, 0], [0, 0, 0, 0, 1]]",
                      "lcs.A.file=A.mtx"};
  cup_scene *a = load_ok(EX "/sparse-mtx/scene.yaml", NULL, 0), *b = load_ok(EX "/sparse-mtx/scene.yaml", o5, 2);
  dense_lcs da, db;
  dense_lcs_of(a, &da);
  dense_lcs_of(b, &db);
  assert_array_close(db.A, da.A, 25, 0, "A");
  assert_close(db.A[0], -2, 0);
  cup_scene_free(&a);
  cup_scene_free(&b);
  /* circuit and lcs replace each other */
  const char *o6[] = {"circuit={R1: 1, R2: 2, R3: 1, L2: 1, L3: 4, C4: 1}"};
  s = load_ok(EX "/lcs-generic.yaml", o6, 1);
  dense_lcs_of(s, &da);
  double A[9];
  paper_A(1, 2, 1, 1, 4, 1, A);
  assert_array_close(da.A, A, 9, TOL, "A");
  cup_scene_free(&s);
  /* an input term's type: the old waveform's fields that the new one does not take go */
  const char *o7[] = {"input.0.type=square", "input.1.type=sine", "input.1.amplitude=2", "input.1.frequency=1"};
  s = load_ok(EX "/paper-fig2.yaml", o7, 4);
  /* int_0^0.1 16 sign(sin 6 pi t) + 2 sin(2 pi t) dt = 1.6 + (1 - cos 0.2 pi) / pi */
  assert_close(integral(s, 0, 0, 0.1), 1.6 + (1 - cos(0.2 * M_PI)) / M_PI, 1e-13);
  cup_scene_free(&s);
  const char *o8[] = {"input.1.type=sine"};                     /* value goes; amplitude is needed */
  assert_contains(load_bad(EX "/paper-fig2.yaml", o8, 1), "input.1.amplitude: missing");
}

/* netlist.NAME=VALUE takes VALUE as SPICE text, as the netlist would:
 * {100/13} is an expression, not a YAML mapping (which failed), and a
 * source's whole specification keeps its parentheses and blanks. */
static void test_overrides_netlist_spice(void **state) {
  (void)state;
  const char *o1[] = {"netlist.RL={100/13}", "netlist.V1 = SIN(0 5 50) "};
  cup_scene *s = load_ok(EX "/circuits/halfwave-rc.yaml", o1, 2);
  dense_lcs d;
  dense_lcs_of(s, &d);
  assert_close(d.A[0], -1 / (100.0 / 13 * 100e-6), 1e-12 / (100.0 / 13 * 100e-6));   /* -1 / (RL C1) */
  double u;
  assert_int_equal(cup_input_eval(cup_scene_input(s), 0.005, &u), CUP_OK);       /* a quarter period */
  assert_close(u, 5, 1e-14);
  cup_scene_free(&s);
  const char *o2[] = {"netlist.RL={100/}"};                    /* SPICE's message, at the override */
  assert_contains(load_bad(EX "/circuits/halfwave-rc.yaml", o2, 1),
                  "override 'netlist.RL={100/}': netlist: ");
  assert_contains(load_bad(EX "/circuits/halfwave-rc.yaml", o2, 1), "RL: the expression ends too early");
  const char *o3[] = {"netlist.probe=[v(out)]"};               /* the scene's own keys stay YAML */
  s = load_ok(EX "/circuits/halfwave-rc.yaml", o3, 1);
  cup_scene_free(&s);
}

static void test_overrides_errors(void **state) {
  (void)state;
  const char *o1[] = {"circuit.R1=-1"};
  assert_string_equal(load_bad(EX "/paper-fig2.yaml", o1, 1),
                      "override 'circuit.R1=-1': circuit.R1: must be >= 0 (got -1)");
  const char *o2[] = {"input.5.amplitude=1"};
  assert_contains(load_bad(EX "/paper-fig2.yaml", o2, 1), "override 'input.5.amplitude=1': input.5: no such item");
  const char *o3[] = {"T.x=1"};
  assert_contains(load_bad(EX "/paper-fig2.yaml", o3, 1), "override 'T.x=1': T.x: cannot go into '1'");
  const char *o4[] = {"x0=[0, 1"};
  assert_contains(load_bad(EX "/paper-fig2.yaml", o4, 1), "override 'x0=[0, 1': x0: YAML syntax error");
  const char *o5[] = {"n1000"};
  assert_contains(load_bad(EX "/paper-fig2.yaml", o5, 1), "override 'n1000': expected KEY=VALUE");
  const char *o6[] = {"n='5'"};
  assert_contains(load_bad(EX "/paper-fig2.yaml", o6, 1), "override 'n='5'': n: expected a number (got the string");
  const char *o7[] = {"circut.R1=2"};
  assert_contains(load_bad(EX "/paper-fig2.yaml", o7, 1),
                  "override 'circut.R1=2': circut: unknown key (did you mean 'circuit'?)");
  const char *o8[] = {"circuit={R1: 1}"};
  assert_contains(load_bad(EX "/paper-fig2.yaml", o8, 1), "override 'circuit={R1: 1}': circuit.R2: missing");
  const char *o9[] = {"x0=[0, 1]"};
  assert_contains(load_bad(EX "/paper-fig2.yaml", o9, 1), "override 'x0=[0, 1]': x0: expected 3 numbers");
  const char *o10[] = {"n=10", "a..b=1"};
  assert_contains(load_bad(EX "/paper-fig2.yaml", o10, 2), "override 'a..b=1': a..b: empty part");
  /* a value from the file next to an overridden one still cites the file */
  const char *o11[] = {"n=10"};
  assert_contains(load_bad(BAD "/negative-L3.yaml", o11, 1), "negative-L3.yaml:");
}

/* ---- round trip ----------------------------------------------------------- */

static void assert_same_scene(const cup_scene *a, const cup_scene *b) {
  dense_lcs da, db;
  dense_lcs_of(a, &da);
  dense_lcs_of(b, &db);
  assert_string_equal(cup_scene_name(a), cup_scene_name(b));
  assert_int_equal(da.n, db.n); assert_int_equal(da.m, db.m); assert_int_equal(da.p, db.p);
  int n = da.n, m = da.m, p = da.p;
  assert_array_close(da.A, db.A, n * n, 0, "A");
  assert_array_close(da.C, db.C, m * n, 0, "C");
  assert_array_close(da.E, db.E, n * p, 0, "E");
  assert_array_close(da.G, db.G, m * p, 0, "G");
  assert_array_close(da.F, db.F, m, 0, "F");
  assert_array_close(da.P, db.P, n * n, 0, "P");
  assert_array_close(cup_scene_x0(a), cup_scene_x0(b), n, 0, "x0");
  for (int j = 0; j < p; j++)
    for (double t = 0; t < 2; t += 0.0625) assert_close(integral(a, j, t, t + 0.05), integral(b, j, t, t + 0.05), 0);
  const cup_integrator_options *oa = cup_scene_options(a), *ob = cup_scene_options(b);
  assert_close(oa->T, ob->T, 0);
  assert_int_equal(oa->n, ob->n);
  assert_string_equal(cup_scene_eps_spec(a), cup_scene_eps_spec(b));
  assert_string_equal(cup_scene_eta_spec(a), cup_scene_eta_spec(b));
  assert_true(oa->eps.coef == ob->eps.coef && oa->eps.power == ob->eps.power);
  assert_true(oa->eta.coef == ob->eta.coef && oa->eta.power == ob->eta.power);
  assert_int_equal(oa->scheme, ob->scheme);
  assert_int_equal(oa->proj.method, ob->proj.method);
  assert_int_equal(oa->proj.max_iter, ob->proj.max_iter);
  assert_int_equal(oa->output, ob->output);
  assert_int_equal(oa->output_every, ob->output_every);
  assert_int_equal(oa->output_samples, ob->output_samples);
  assert_string_equal(cup_scene_text(a), cup_scene_text(b));   /* the text is a fixed point */
}

static void round_trip(const char *path, const char *dir, const char *const *ovr, int nov) {
  cup_scene *a = load_ok(path, ovr, nov), *b = NULL;
  char err[CUP_ERRMSG_LEN];
  int st = cup_scene_load_string(&b, cup_scene_text(a), path, dir, NULL, 0, err);
  if (st) fail_msg("reloading the text of %s failed: %s\n%s", path, err, cup_scene_text(a));
  assert_same_scene(a, b);
  cup_scene_free(&a);
  cup_scene_free(&b);
}

static void test_round_trip(void **state) {
  (void)state;
  round_trip(EX "/paper-fig2.yaml", EX, NULL, 0);
  round_trip(EX "/paper-fig3.yaml", EX, NULL, 0);
  round_trip(EX "/lcs-generic.yaml", EX, NULL, 0);
  round_trip(EX "/sparse-mtx/scene.yaml", EX "/sparse-mtx", NULL, 0);
  const char *ovr[] = {"circuit.R1=2", "x0=[0, 1, 0]", "eps=\"1e-7\"", "name='x: \"y\"'", "output.every=3"};
  round_trip(EX "/paper-fig2.yaml", EX, ovr, 5);
  /* the overridden values are in the text */
  cup_scene *s = load_ok(EX "/paper-fig2.yaml", ovr, 5);
  assert_contains(cup_scene_text(s), "R1: 2");
  assert_contains(cup_scene_text(s), "every: 3");
  cup_scene_free(&s);
}

/* ---- malformed scenes ------------------------------------------------------ */

static int load_scene(const char *path, char err[CUP_ERRMSG_LEN], int *out_null) {
  cup_scene *s = (cup_scene *)err;
  int st = cup_scene_load(&s, path, NULL, 0, err);
  *out_null = s == NULL;
  if (st == CUP_OK && s) cup_scene_free(&s);
  return st;
}

static void test_bad_corpus(void **state) {
  (void)state;
  int failures;
  int count = bad_corpus_check(BAD, ".yaml", "# expect: ", load_scene, &failures);
  print_message("%d malformed scenes checked\n", count);
  assert_int_equal(failures, 0);
  assert_true(count >= 25);
}

/* Every prefix of an example, and the example with one byte replaced by
 * each of a few YAML-significant characters, loads or fails cleanly: a
 * one-line message naming the file, *s NULL (leaks: valgrind/ASan runs). */
static void check_clean(const char *text, const char *dir) {
  char err[CUP_ERRMSG_LEN] = "";
  cup_scene *s = (cup_scene *)&err;
  int st = cup_scene_load_string(&s, text, "mut.yaml", dir, NULL, 0, err);
  if (st == CUP_OK) { assert_non_null(s); cup_scene_free(&s); return; }
  assert_null(s);
  if (strncmp(err, "mut.yaml", 8) != 0 || strchr(err, '\n'))
    fail_msg("status %d, message '%s' for\n%s", st, err, text);
}

static char *slurp_text(const char *path) {
  FILE *f = fopen(path, "rb");
  assert_non_null(f);
  char *buf = calloc(1, 1 << 16);
  size_t n = fread(buf, 1, (1 << 16) - 1, f);
  fclose(f);
  buf[n] = '\0';
  return buf;
}

static void test_mutations(void **state) {
  (void)state;
  const char *files[][2] = {{EX "/paper-fig2.yaml", EX}, {EX "/lcs-generic.yaml", EX},
                            {EX "/sparse-mtx/scene.yaml", EX "/sparse-mtx"}, {EX "/walker.yaml", EX}};
  const char subst[] = {'[', ']', '{', ':', '-', '\t', '"', '&', '*', ',', '\n'};
  for (int f = 0; f < (int)(sizeof files / sizeof files[0]); f++) {
    char *text = slurp_text(files[f][0]);
    size_t n = strlen(text);
    char *buf = malloc(n + 1);
    for (size_t k = 0; k <= n; k++) {
      memcpy(buf, text, k);
      buf[k] = '\0';
      check_clean(buf, files[f][1]);
    }
    for (size_t k = 0; k < n; k++)
      for (size_t c = 0; c < sizeof subst; c++) {
        memcpy(buf, text, n + 1);
        buf[k] = subst[c];
        check_clean(buf, files[f][1]);
      }
    free(buf);
    free(text);
  }
}

/* Fail the k-th allocation of a load, for every k until the load no longer
 * needs to fail: each must return an error with *s NULL and free every block
 * it took. */
static void fault_sweep(const char *path, int final_status) {
#if HEAP_INTERPOSED
  char err[CUP_ERRMSG_LEN];
  long k = 1;
  for (;; k++) {
    cup_scene *s = (cup_scene *)&err;
    heap_fault_calls = 0; heap_live_blocks = 0; heap_fault_at = k; heap_spare = dependency_bug;
    heap_tracking = 1;
    int st = cup_scene_load(&s, path, NULL, 0, err);
    int failed = heap_fault_calls >= heap_fault_at;   /* some allocation was refused */
    if (st == CUP_OK) cup_scene_free(&s);
    heap_tracking = 0; heap_fault_at = -1;
    if (heap_live_blocks != 0) fail_msg("%s: failing allocation %ld leaves %ld blocks", path, k, heap_live_blocks);
    if (!failed && heap_fault_calls == 0) {     /* valgrind replaced our malloc */
      print_message("%s: malloc is not interposed here; sweep skipped\n", path);
      skip();
    }
    if (!failed) { assert_int_equal(st, final_status); break; }   /* the load needs fewer: done */
    if (st == CUP_OK) continue;   /* a refusal someone absorbed (e.g. a libc buffer) */
    assert_true(st < 0);
    assert_null(s);
  }
  print_message("%s: %ld allocations, each failed once\n", path, k - 1);
#else
  (void)path; (void)final_status;
  skip();
#endif
}

static void test_allocation_failures(void **state) {
  (void)state;
#if HEAP_INTERPOSED
  void *warm[2];
  backtrace(warm, 2);                      /* its first call allocates (loads libgcc) */
#endif
  fault_sweep(EX "/paper-fig2.yaml", CUP_OK);
  fault_sweep(EX "/sparse-mtx/scene.yaml", CUP_OK);
  fault_sweep(BAD "/PB-not-CT.yaml", CUP_ERR_PB_CT);   /* the error path of cup_lcs_create */
  fault_sweep(BAD "/mtx-nan.yaml", CUP_ERR_PARSE);
  fault_sweep(EX "/walker.yaml", CUP_OK);               /* set: and f: */
  fault_sweep(EX "/rotating-disc.yaml", CUP_OK);
  fault_sweep(BAD "/set-Q-indefinite.yaml", CUP_ERR_NOT_SPD);   /* the error path of cup_set_create */
}

/* The message layout, exactly: FILE:LINE:COL: KEY: problem. */
static void test_message_layout(void **state) {
  (void)state;
  const char *text = "# the paper's circuit\nname: x\n\ncircuit:\n  R1: 1\n  R2: 2\n  L3:   -1\n"
                     "  R3: 1\n  L2: 1\n  C4: 1\nT: 1\nn: 100\n";
  char err[CUP_ERRMSG_LEN];
  cup_scene *s = NULL;
  assert_int_equal(cup_scene_load_string(&s, text, "paper-fig2.yaml", NULL, NULL, 0, err), CUP_ERR_PARSE);
  assert_string_equal(err, "paper-fig2.yaml:7:9: circuit.L3: must be > 0 (got -1)");
  assert_null(s);
}

/* The SHA-256 of a file by the system's sha256sum (an independent
 * reference for the scene's own hash), into hex[65]. */
static void sha256sum(const char *path, char hex[65]) {
  char cmd[1024];
  snprintf(cmd, sizeof cmd, "sha256sum '%s'", path);
  FILE *p = popen(cmd, "r");
  assert_non_null(p);
  assert_int_equal(fscanf(p, "%64s", hex), 1);
  pclose(p);
}

/* The files a scene was read from: each once, in the order read, with the
 * SHA-256 of its bytes (against sha256sum); a netlist's through the scene;
 * none for a scene from text that names no file. */
static void test_files_read(void **state) {
  (void)state;
  cup_scene *s = load_ok(EX "/sparse-mtx/scene.yaml", NULL, 0);
  static const char *const names[] = {"scene.yaml", "A.mtx", "C.mtx", "P.mtx", "x0.mtx"};
  assert_int_equal(cup_scene_file_count(s), 5);
  assert_string_equal(cup_scene_file(s, 0), EX "/sparse-mtx/scene.yaml");   /* then as the keys are read */
  for (int k = 0; k < 5; k++) {
    char want[256], hex[65];
    snprintf(want, sizeof want, EX "/sparse-mtx/%s", names[k]);
    int at = -1;
    for (int j = 0; j < 5; j++) at = !strcmp(cup_scene_file(s, j), want) ? j : at;
    assert_true(at >= 0);
    sha256sum(want, hex);
    assert_string_equal(cup_scene_file_sha256(s, at), hex);
  }
  assert_null(cup_scene_file(s, 5));
  assert_null(cup_scene_file(s, -1));
  cup_scene_free(&s);
  /* the same file named twice is one file */
  char err[CUP_ERRMSG_LEN];
  const char *same = "lcs:\n  C: {file: C.mtx}\n  A: {file: A.mtx}\n  P: {file: P.mtx}\n  E: {file: x0.mtx}\n"
                     "  G: [[0], [0], [0], [0]]\nx0: {file: x0.mtx}\ninput: 1\nT: 1\nn: 10\n";
  assert_int_equal(cup_scene_load_string(&s, same, "same.yaml", EX "/sparse-mtx", NULL, 0, err), CUP_OK);
  assert_int_equal(cup_scene_file_count(s), 4);             /* C, A, P, x0 (for E and for x0) */
  int x0_seen = 0;
  for (int j = 0; j < 4; j++) x0_seen += !strcmp(cup_scene_file(s, j), EX "/sparse-mtx/x0.mtx");
  assert_int_equal(x0_seen, 1);
  cup_scene_free(&s);
  s = load_ok(EX "/paper-fig2.yaml", NULL, 0);
  assert_int_equal(cup_scene_file_count(s), 1);
  cup_scene_free(&s);
  assert_int_equal(cup_scene_load_string(&s, "netlist: halfwave-rc.cir\n", "n.yaml", EX "/circuits", NULL, 0, err),
                   CUP_OK);
  assert_int_equal(cup_scene_file_count(s), 1);
  assert_string_equal(cup_scene_file(s, 0), EX "/circuits/halfwave-rc.cir");
  cup_scene_free(&s);
  assert_int_equal(cup_scene_file_count(NULL), 0);
  /* what a netlist includes is read through the same list */
  char dir[] = "/tmp/cup_incXXXXXX", path[64], hex[65];
  assert_non_null(mkdtemp(dir));
  snprintf(path, sizeof path, "%s/rc.cir", dir);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs("rc\nV1 in 0 DC 1\n.include parts.inc\n.tran 1u 1m\n.end\n", f);
  fclose(f);
  snprintf(path, sizeof path, "%s/parts.inc", dir);
  assert_non_null(f = fopen(path, "w"));
  fputs("R1 in out 1k\nC1 out 0 1u\n", f);
  fclose(f);
  assert_int_equal(cup_scene_load_string(&s, "netlist: rc.cir\n", "inc.yaml", dir, NULL, 0, err), CUP_OK);
  assert_int_equal(cup_scene_file_count(s), 2);
  assert_string_equal(cup_scene_file(s, 1), path);
  sha256sum(path, hex);
  assert_string_equal(cup_scene_file_sha256(s, 1), hex);
  assert_int_equal(cup_scene_check_output(s, path, err), CUP_ERR_ARG);      /* the included file */
  assert_contains(err, "which the run reads");
  cup_scene_free(&s);
  char text[256];
  snprintf(text, sizeof text, "netlist: {text: \"rc\\nV1 in 0 DC 1\\n.include %s\\n.tran 1u 1m\\n.end\\n\"}\n", path);
  assert_int_equal(cup_scene_load_string(&s, text, "text.yaml", dir, NULL, 0, err), CUP_OK);
  assert_int_equal(cup_scene_file_count(s), 1);                             /* a netlist given as text: its include */
  assert_string_equal(cup_scene_file(s, 0), path);
  cup_scene_free(&s);
  char cmd[64];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  assert_int_equal(system(cmd), 0);
}

/* A folder `len` characters deep (folders of at most 200 characters) under
 * a fresh temporary one, made; *top is that temporary folder. */
static char *deep_dir(size_t len, char **top) {
  char tmpl[] = "/tmp/cup_deepXXXXXX";
  assert_non_null(mkdtemp(tmpl));
  *top = strdup(tmpl);
  char *d = malloc(len + 256);
  assert_non_null(d);
  size_t w = (size_t)snprintf(d, len + 256, "%s", tmpl);
  while (w < len) {
    size_t seg = len - w - 1 < 200 ? len - w - 1 : 200;
    if (seg == 0) seg = 1;
    d[w++] = '/';
    memset(d + w, 'd', seg);
    w += seg;
    d[w] = '\0';
    assert_int_equal(mkdir(d, 0700), 0);
  }
  return d;
}

static char *write_in(const char *dir, const char *name, const char *text) {
  size_t n = strlen(dir) + strlen(name) + 2;
  char *path = malloc(n);
  assert_non_null(path);
  snprintf(path, n, "%s/%s", dir, name);
  FILE *f = fopen(path, "w");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
  return path;
}

/* Messages are never cut (CUP_ERRMSG_LEN): through a path of 250
 * characters, and of 4000 (near PATH_MAX), a scene's error, a Matrix Market
 * file's that it names (two paths in one message) and a netlist's read
 * through the scene end as they do through a short path. */
static void test_long_path_messages(void **state) {
  (void)state;
  static const size_t lens[] = {250, 4000};
  for (size_t k = 0; k < sizeof lens / sizeof lens[0]; k++) {
    char *top, *dir = deep_dir(lens[k] - strlen("/bad.yaml"), &top), err[CUP_ERRMSG_LEN], want[CUP_ERRMSG_LEN];
    char *bad = write_in(dir, "bad.yaml", "circuit:\n  R1: 1\n  R2: 2\n  L3:   -1\n  R3: 1\n  L2: 1\n"
                                           "  C4: 1\nT: 1\nn: 100\n");
    assert_true(strlen(bad) >= lens[k]);
    cup_scene *s = NULL;
    assert_int_equal(cup_scene_load(&s, bad, NULL, 0, err), CUP_ERR_PARSE);
    snprintf(want, sizeof want, "%s:4:9: circuit.L3: must be > 0 (got -1)", bad);
    assert_string_equal(err, want);
    char *mtx = write_in(dir, "m.yaml", "lcs:\n  C: [[1]]\n  E: [[1]]\n  G: {file: missing.mtx}\ninput: 1\nT: 1\n");
    assert_int_equal(cup_scene_load(&s, mtx, NULL, 0, err), CUP_ERR_IO);
    snprintf(want, sizeof want, "%s:4:13: lcs.G.file: cannot open '%s/missing.mtx': No such file or directory",
             mtx, dir);
    assert_string_equal(err, want);
    char *cir = write_in(dir, "c.cir", "* rc\nV1 in 0 DC 1\nR1 in out 1k\nC1 out 0 1u\nD1 out 0 nomodel\n.tran 1u 1m\n");
    char *sc = write_in(dir, "n.yaml", "netlist: c.cir\n");
    assert_int_equal(cup_scene_load(&s, sc, NULL, 0, err), CUP_ERR_PARSE);
    assert_contains(err, cir);
    assert_contains(err, "model 'nomodel' is not defined (an ideal diode needs '.model nomodel D' or no model)");
    assert_null(s);
    free(bad); free(mtx); free(cir); free(sc);
    char cmd[64 + sizeof "/tmp/cup_deepXXXXXX"];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", top);
    assert_int_equal(system(cmd), 0);
    free(dir);
    free(top);
  }
}

static void test_api_edges(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN];
  cup_scene *s = NULL;
  assert_int_equal(cup_scene_load(NULL, EX "/paper-fig2.yaml", NULL, 0, err), CUP_ERR_ARG);
  assert_int_equal(cup_scene_load(&s, NULL, NULL, 0, err), CUP_ERR_ARG);
  assert_int_equal(cup_scene_load(&s, EX "/paper-fig2.yaml", NULL, 1, err), CUP_ERR_ARG);
  assert_int_equal(cup_scene_load(&s, EX "/no-such-scene.yaml", NULL, 0, err), CUP_ERR_IO);
  assert_contains(err, "no-such-scene.yaml: cannot open");
  assert_null(s);
  /* a NULL errmsg is allowed, on success and on failure */
  assert_int_equal(cup_scene_load(&s, BAD "/negative-L3.yaml", NULL, 0, NULL), CUP_ERR_PARSE);
  assert_int_equal(cup_scene_load(&s, EX "/paper-fig2.yaml", NULL, 0, NULL), CUP_OK);
  cup_scene_free(&s);
  cup_scene_free(&s);
  cup_scene_free(NULL);
  assert_null(cup_scene_name(NULL));
  assert_null(cup_scene_lcs(NULL));
  assert_null(cup_scene_options(NULL));
  assert_null(cup_scene_text(NULL));
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_paper_fig2),
    cmocka_unit_test(test_paper_fig3),
    cmocka_unit_test(test_lcs_generic_is_circuit),
    cmocka_unit_test(test_sparse_mtx),
    cmocka_unit_test(test_multi_input_and_pwl),
    cmocka_unit_test(test_overrides_change_values),
    cmocka_unit_test(test_overrides_add_keys),
    cmocka_unit_test(test_overrides_replace_shapes),
    cmocka_unit_test(test_overrides_netlist_spice),
    cmocka_unit_test(test_overrides_errors),
    cmocka_unit_test(test_round_trip),
    cmocka_unit_test(test_bad_corpus),
    cmocka_unit_test(test_mutations),
    cmocka_unit_test(test_allocation_failures),
    cmocka_unit_test(test_message_layout),
    cmocka_unit_test(test_long_path_messages),
    cmocka_unit_test(test_files_read),
    cmocka_unit_test(test_api_edges),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

/* projector: answers and certificates against an independent reference
 * (tests/testutil.h: GSL, enumeration of active sets for m <= 10, Hildreth +
 * least-squares polish for larger m). Every certificate is checked to be
 * true: eps_cert >= ||x - z||_P^2 - d_K(x)^2 and eta_cert >= d_K(z). */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdio.h>
#include <cmocka.h>
#include "testutil.h"

#include "heap.h"
#include "projector/newton.h"
#include "projector/choose.h"
#include "projector/small.h"
#include "projector/activeset.h"

/* ---- random polyhedra ---------------------------------------------------------- */

enum { GENERIC, DUPLICATE, NEAR_PARALLEL, RANK_DEFICIENT, THIN_WEDGE, CONE, NKIND };
static const char *kind_name[] = {"generic", "duplicate", "near-parallel", "rank-deficient",
                                  "thin-wedge", "cone"};

typedef struct {
  int n, m, kind, dense_p;
  double *C, *g, *P, *w0;
  tcsc Ct, Pt;
  cup_metric Pm;
  double theta;
} inst;

static void inst_make(inst *I, rng_t *r, int kind, int n, int m, int dense_p) {
  memset(I, 0, sizeof *I);
  I->n = n; I->m = m; I->kind = kind; I->dense_p = dense_p;
  I->C = calloc((size_t)m * n, sizeof(double));
  I->g = calloc((size_t)m + 1, sizeof(double));
  I->P = calloc((size_t)n * n, sizeof(double));
  I->w0 = calloc((size_t)n, sizeof(double));
  for (int a = 0; a < n; a++) I->w0[a] = kind == CONE ? 0 : rng_normal(r);
  double *C = I->C;
  for (int k = 0; k < m * n; k++) C[k] = rng_unif(r) < 0.7 ? rng_normal(r) : 0;
  for (int i = 0; i < m; i++) {                   /* no zero rows */
    int nz = 0;
    for (int a = 0; a < n; a++) nz |= C[i * n + a] != 0;
    if (!nz) C[i * n + rng_int(r, 0, n - 1)] = 1;
  }
  if (kind == DUPLICATE && m >= 2) {
    int src = rng_int(r, 0, m - 2);
    memcpy(C + (m - 1) * n, C + src * n, sizeof(double) * n);
  }
  if (kind == NEAR_PARALLEL && m >= 2) {
    int src = rng_int(r, 0, m - 2);
    for (int a = 0; a < n; a++) C[(m - 1) * n + a] = C[src * n + a] * (1 + 1e-8 * rng_normal(r));
  }
  if (kind == RANK_DEFICIENT) {                   /* C = U V with rank < min(m, n) */
    int rk = n > 1 ? rng_int(r, 1, n - 1) : 1;
    double *Um = malloc(sizeof(double) * m * rk), *V = malloc(sizeof(double) * rk * n);
    for (int k = 0; k < m * rk; k++) Um[k] = rng_normal(r);
    for (int k = 0; k < rk * n; k++) V[k] = rng_normal(r);
    for (int i = 0; i < m; i++)
      for (int a = 0; a < n; a++) {
        double s = 0;
        for (int k = 0; k < rk; k++) s += Um[i * rk + k] * V[k * n + a];
        C[i * n + a] = s;
      }
    free(Um); free(V);
  }
  if (kind == THIN_WEDGE) {                       /* theta y1 >= |y2|: cond(M) = 1/theta^2 */
    static const double thetas[] = {1e-3, 1e-4, 1e-5, 1e-6};
    I->theta = thetas[rng_int(r, 0, 3)];
    memset(C, 0, sizeof(double) * 2 * n);
    C[0] = I->theta; C[1] = 1;
    C[n] = I->theta; C[n + 1] = -1;
  }
  for (int i = 0; i < m; i++) {                   /* nonempty: w0 is feasible */
    double s = 0;
    for (int a = 0; a < n; a++) s += C[i * n + a] * I->w0[a];
    double slack = (kind == CONE || kind == THIN_WEDGE || rng_unif(r) < 0.3) ? 0 : fabs(rng_normal(r));
    I->g[i] = -s + slack;
  }
  if (kind == DUPLICATE && m >= 2 && rng_unif(r) < 0.5) I->g[m - 1] += 0.5;  /* redundant copy */
  for (int a = 0; a < n; a++) I->P[a * n + a] = 0.5 + 4.5 * rng_unif(r);
  if (dense_p)
    for (int a = 0; a < n; a++)
      for (int b = 0; b < a; b++) if (rng_unif(r) < 0.5) {
        double v = 0.4 * rng_normal(r);
        I->P[a * n + b] = I->P[b * n + a] = v;
        I->P[a * n + a] += fabs(v); I->P[b * n + b] += fabs(v);
      }
  tcsc_from_dense(&I->Ct, C, m, n);
  tcsc_from_dense(&I->Pt, I->P, n, n);
  I->Pm = (cup_metric){CUP_METRIC_SPARSE, NULL, I->Pt.view, 0};  /* diagonal is detected */
}

static void inst_free(inst *I) {
  free(I->C); free(I->g); free(I->P); free(I->w0);
  tcsc_free(&I->Ct); tcsc_free(&I->Pt);
}

/* The polyset of I; the test fails, saying why, if it is refused. */
static cup_polyset *inst_polyset(const inst *I) {
  cup_polyset *K = NULL;
  char msg[CUP_ERRMSG_LEN];
  if (cup_polyset_create(&K, &I->Ct.view, I->g, &I->Pm, msg)) fail_msg("create: %s", msg);
  return K;
}

static ref_problem inst_ref(const inst *I) {
  return (ref_problem){I->n, I->m, I->C, I->g, I->P};
}

static double pdist(const inst *I, const double *a, const double *b) {
  double *d = malloc(sizeof(double) * I->n);
  for (int k = 0; k < I->n; k++) d[k] = a[k] - b[k];
  ref_problem q = inst_ref(I);
  double v = sqrt(ref_pnorm2(&q, d));
  free(d);
  return v;
}

static void random_point(const inst *I, rng_t *r, double *x) {
  double amp = rng_unif(r) < 0.5 ? 0.3 : 3;
  for (int a = 0; a < I->n; a++) x[a] = I->w0[a] + amp * rng_normal(r);
}

/* A small instance of trial's kind (the kinds in turn): n in 2..6, m in
 * 2..8 (2 for a thin wedge), a dense P every other trial. */
static void inst_small(inst *I, rng_t *r, int trial) {
  int kind = trial % NKIND;
  int n = rng_int(r, 2, 6), m = kind == THIN_WEDGE ? 2 : rng_int(r, 2, 8);
  inst_make(I, r, kind, n, m, trial % 2);
}

/* The default options with a method and relative tolerances. */
static cup_projector_options proj_options(int method, double eps_rel, double eta_rel) {
  cup_projector_options o;
  cup_projector_options_default(&o);
  o.method = method;
  o.eps_rel = eps_rel;
  o.eta_rel = eta_rel;
  return o;
}

/* A projector onto K; the test fails, saying why, if it is refused. */
static cup_projector *proj_new(const cup_polyset *K, const cup_projector_options *o) {
  cup_projector *pr = NULL;
  char msg[CUP_ERRMSG_LEN];
  if (cup_projector_create(&pr, K, o, msg)) fail_msg("projector: %s", msg);
  return pr;
}

/* Write an instance and a point as text (for reproducing a failure outside
 * the test: CUP_TEST_DUMP=1). */
static void dump_instance(const inst *I, const double *x, const char *path) {
  FILE *f = fopen(path, "w");
  if (!f) return;
  fprintf(f, "%d %d %s\n", I->n, I->m, kind_name[I->kind]);
  for (int k = 0; k < I->m * I->n; k++) fprintf(f, "%.17g ", I->C[k]);
  fprintf(f, "\n");
  for (int k = 0; k < I->m; k++) fprintf(f, "%.17g ", I->g[k]);
  fprintf(f, "\n");
  for (int k = 0; k < I->n * I->n; k++) fprintf(f, "%.17g ", I->P[k]);
  fprintf(f, "\n");
  for (int k = 0; k < I->n; k++) fprintf(f, "%.17g ", x[k]);
  fprintf(f, "\n");
  fclose(f);
}

/* Project with the library and check the answer and both certificates
 * against the reference. Returns the status. */
typedef struct {
  int ok, warn, checked;
  double worst_rel_err;
} tally;

static int check_one(const inst *I, cup_projector *pr, const double *x, double acc_rel,
                     tally *t) {
  int n = I->n;
  double *z = malloc(sizeof(double) * n), *zr = malloc(sizeof(double) * n);
  double *zz = malloc(sizeof(double) * n);
  cup_proj_info info;
  int st = cup_project(pr, x, z, &info);
  if (st != CUP_OK && st != CUP_WARN_NOT_CERTIFIED)
    fail_msg("%s n=%d m=%d: status %s", kind_name[I->kind], I->n, I->m, cup_status_name(st));
  ref_problem q = inst_ref(I);
  if (ref_project(&q, x, zr) != 0)
    fail_msg("%s n=%d m=%d: the reference found no feasible point", kind_name[I->kind], I->n, I->m);
  double S = info.scale;
  double d = pdist(I, x, zr), dz = pdist(I, x, z);
  double excess = ref_excess(&q, x, z, zr);
  /* the reference is exact to ~1e-15 S: allow for its error in d^2 */
  double allow = 8e-15 * S * S + 1e-14 * d * d;
  if (!(info.eps_cert >= excess - allow))
    fail_msg("%s n=%d m=%d: eps_cert %.3e < excess %.3e", kind_name[I->kind], I->n, I->m,
             info.eps_cert, excess);
  /* the true distance of z to K, by projecting z with the reference */
  if (ref_project(&q, z, zz) != 0 && getenv("CUP_TEST_DUMP"))
    dump_instance(I, x, "/tmp/cupdump_fail.txt");
  if (ref_project(&q, z, zz) != 0)
    fail_msg("%s n=%d m=%d: the reference could not project z (status %s)", kind_name[I->kind],
             I->n, I->m, cup_status_name(st));
  double dist = pdist(I, z, zz);
  if (!(info.eta_cert >= dist - 1e-13 * S))
    fail_msg("%s n=%d m=%d: eta_cert %.3e < distance %.3e (violation %.3e)", kind_name[I->kind],
             I->n, I->m, info.eta_cert, dist, info.violation);
  /* what the certificates imply about z: ||z - z*|| <= eta + sqrt(eps + 2 eta ||x-z|| + eta^2) */
  double err = pdist(I, z, zr);
  double implied = info.eta_cert + sqrt(info.eps_cert + 2 * info.eta_cert * dz +
                                        info.eta_cert * info.eta_cert);
  if (!(err <= implied + 1e-12 * S))
    fail_msg("%s: ||z - z*|| = %.3e exceeds what the certificates imply (%.3e)",
             kind_name[I->kind], err, implied);
  if (st == CUP_OK) {
    t->ok++;
    assert_true(info.eps_cert <= info.eps_target);
    assert_true(info.eta_cert <= info.eta_target);
    if (!(err <= acc_rel * S))
      fail_msg("%s n=%d m=%d: ||z - z*||_P = %.3e > %.1e S (S = %.3e)", kind_name[I->kind],
               I->n, I->m, err, acc_rel, S);
    if (S > 0) t->worst_rel_err = fmax(t->worst_rel_err, err / S);
  } else {
    t->warn++;
    static int ndump = 0;
    if (getenv("CUP_TEST_DUMP") && ndump < 20) {
      char fn[64];
      snprintf(fn, sizeof fn, "/tmp/cupdump_%d.txt", ndump++);
      dump_instance(I, x, fn);
    }
    if (getenv("CUP_TEST_VERBOSE"))
      fprintf(stderr, "warn %s n=%d m=%d method %d: eps %.2e/%.2e eta %.2e/%.2e viol %.2e it %d err/S %.2e\n",
              kind_name[I->kind], I->n, I->m, info.method, info.eps_cert, info.eps_target,
              info.eta_cert, info.eta_target, info.violation, info.iterations, err / S);
  }
  t->checked++;
  free(z); free(zr); free(zz);
  return st;
}

/* Does K have an interior point? Independently: K shrunk by tau (each row
 * moved inward by tau ||c_i||_{P^-1}) is nonempty by the reference. */
static int has_interior(const inst *I) {
  ref_problem q = inst_ref(I);
  ref_work w; ref_setup(&q, &w);
  double *gs = malloc(sizeof(double) * I->m), *z = malloc(sizeof(double) * I->n);
  double tau = 1e-7 * (1 + sqrt(ref_pnorm2(&q, I->w0)));
  for (int i = 0; i < I->m; i++) gs[i] = I->g[i] - tau * sqrt(w.M[i * I->m + i]);
  ref_problem qs = {I->n, I->m, I->C, gs, I->P};
  int ok = ref_project(&qs, I->w0, z) == 0;
  free(gs); free(z); ref_free(&w);
  return ok;
}

/* >= 1000 random polyhedra, every degenerate family, diagonal and
 * non-diagonal P, default (exact) method. Tolerances sit at what floating
 * point can certify: (1e-14, 1e-12) relative, and (1e-8, 1e-6) on thin
 * wedges, whose certificates grow like u/theta. Sets without interior (a
 * vertex whose halfplanes positively span the plane makes K a point) admit
 * no certified eta for an infeasible z: there we check that the warning's
 * bounds are true. */
static void test_random_polyhedra_enumeration(void **state) {
  (void)state;
  rng_t r = {20261121};
  tally with = {0}, without = {0}, wedge = {0};
  int per_kind[NKIND] = {0};
  for (int trial = 0; trial < 1200; trial++) {
    int kind = trial % NKIND;
    int n = rng_int(&r, 2, 8), m = rng_int(&r, 1, 10);
    if (kind == DUPLICATE || kind == NEAR_PARALLEL) m = m < 2 ? 2 : m;
    if (kind == THIN_WEDGE) m = 2;
    if (kind == RANK_DEFICIENT) m = rng_int(&r, n, 10);
    inst I;
    inst_make(&I, &r, kind, n, m, trial % 3 == 0);
    cup_polyset *K = inst_polyset(&I);
    cup_projector_options o = proj_options(CUP_PROJ_AUTO, kind == THIN_WEDGE ? 1e-8 : 1e-14,
                                           kind == THIN_WEDGE ? 1e-6 : 1e-12);
    cup_projector *pr = proj_new(K, &o);
    tally *t = kind == THIN_WEDGE ? &wedge : has_interior(&I) ? &with : &without;
    double *x = malloc(sizeof(double) * n);
    for (int rep = 0; rep < 3; rep++) {
      random_point(&I, &r, x);
      check_one(&I, pr, x, kind == THIN_WEDGE ? 1e-5 : 1e-7, t);
    }
    per_kind[kind]++;
    free(x);
    cup_projector_free(&pr);
    cup_polyset_free(&K);
    inst_free(&I);
  }
  for (int k = 0; k < NKIND; k++) assert_true(per_kind[k] >= 150);
  print_message("random polyhedra with interior: %d projections, %d certified at (1e-14, 1e-12), "
                "worst ||z - z*||/S %.2e\n", with.checked, with.ok, with.worst_rel_err);
  print_message("thin wedges (theta 1e-3..1e-6): %d projections, %d certified at (1e-8, 1e-6)\n",
                wedge.checked, wedge.ok);
  print_message("sets without interior: %d projections, %d certified, %d warnings with true bounds\n",
                without.checked, without.ok, without.warn);
  assert_true(with.checked >= 2000);
  assert_true(with.ok >= 0.99 * with.checked);
  assert_true(wedge.ok >= 0.99 * wedge.checked);
}

/* Larger sets (m > 64, the sparse KKT path) against the Hildreth reference. */
static void test_random_polyhedra_sparse_path(void **state) {
  (void)state;
  rng_t r = {777};
  tally t = {0};
  static const int kinds[] = {GENERIC, DUPLICATE, GENERIC, CONE};
  for (int trial = 0; trial < 60; trial++) {
    int kind = kinds[trial % 4];
    int n = rng_int(&r, 20, 60), m = rng_int(&r, 65, 110);
    if (kind == CONE) n = m + 10;                 /* a cone with interior */
    inst I;
    inst_make(&I, &r, kind, n, m, trial % 2);
    cup_polyset *K = inst_polyset(&I);
    /* the rigorous floor 2 sum lam_i gam_i is ~1e-13 S^2 here */
    cup_projector_options o = proj_options(CUP_PROJ_AUTO, 1e-11, 1e-9);
    cup_projector *pr = proj_new(K, &o);
    double *x = malloc(sizeof(double) * n);
    random_point(&I, &r, x);
    check_one(&I, pr, x, 1e-7, &t);
    free(x);
    cup_projector_free(&pr);
    cup_polyset_free(&K);
    inst_free(&I);
  }
  print_message("sparse path: %d projections, %d certified, %d warnings, worst rel err %.2e\n",
                t.checked, t.ok, t.warn, t.worst_rel_err);
  assert_true(t.ok >= 0.95 * t.checked);
}

/* The paper's projected gradient and FISTA: certificates true at every
 * return, certified when the iteration budget allows. */
static void test_first_order_methods(void **state) {
  (void)state;
  rng_t r = {4242};
  for (int method = CUP_PROJ_PG; method <= CUP_PROJ_FISTA; method++) {
    tally t = {0};
    for (int trial = 0; trial < 200; trial++) {
      inst I;
      inst_small(&I, &r, trial);
      cup_polyset *K = inst_polyset(&I);
      cup_projector_options o = proj_options(method, 1e-9, 1e-7);
      o.max_iter = 20000;
      cup_projector *pr = proj_new(K, &o);
      double *x = malloc(sizeof(double) * I.n);
      random_point(&I, &r, x);
      check_one(&I, pr, x, 1e-3, &t);
      free(x);
      cup_projector_free(&pr);
      cup_polyset_free(&K);
      inst_free(&I);
    }
    print_message("%s: %d projections, %d certified, %d warnings (all certificates true)\n",
                  cup_proj_method_name(method), t.checked, t.ok, t.warn);
    assert_true(t.ok >= 0.6 * t.checked);   /* thin wedges need ~1/theta^2 steps */
  }
}

/* Scaling every length by s scales the answer by s (relative 1e-10). */
static void test_scaling(void **state) {
  (void)state;
  rng_t r = {99};
  static const double scales[] = {1e-9, 1e9};
  for (int trial = 0; trial < 120; trial++) {
    inst I;
    inst_small(&I, &r, trial);
    int kind = I.kind, n = I.n, m = I.m;
    double *x = malloc(sizeof(double) * n), *z = malloc(sizeof(double) * n);
    double *xs = malloc(sizeof(double) * n), *zs = malloc(sizeof(double) * n);
    double *gs = malloc(sizeof(double) * m);
    random_point(&I, &r, x);
    cup_polyset *K = inst_polyset(&I);
    cup_projector *pr = NULL;
    assert_int_equal(cup_projector_create(&pr, K, NULL, NULL), CUP_OK);
    cup_proj_info info;
    int st = cup_project(pr, x, z, &info);
    assert_true(st == CUP_OK || st == CUP_WARN_NOT_CERTIFIED);
    double S = info.scale;
    for (int k = 0; k < 2; k++) {
      double s = scales[k];
      for (int a = 0; a < n; a++) xs[a] = x[a] * s;
      for (int i = 0; i < m; i++) gs[i] = I.g[i] * s;
      cup_projector_reset(pr);
      assert_int_equal(cup_projector_set_offset(pr, gs), CUP_OK);
      assert_int_equal(cup_project(pr, xs, zs, &info), st);
      for (int a = 0; a < n; a++) zs[a] /= s;
      double e = pdist(&I, z, zs);
      if (!(e <= 1e-10 * S))
        fail_msg("%s scale %g: ||z_s/s - z|| = %.3e (S = %.3e)", kind_name[kind], s, e, S);
    }
    cup_projector_free(&pr);
    cup_polyset_free(&K);
    free(x); free(z); free(xs); free(zs); free(gs);
    inst_free(&I);
  }
}

/* A point of K comes back unchanged, bit for bit, with zero iterations. */
static void test_skip_returns_x_exactly(void **state) {
  (void)state;
  rng_t r = {5};
  inst I;
  inst_make(&I, &r, GENERIC, 5, 6, 1);
  cup_polyset *K = inst_polyset(&I);
  for (int method = 0; method < 4; method++) {
    cup_projector_options o;
    cup_projector_options_default(&o);
    o.method = method;
    cup_projector *pr = proj_new(K, &o);
    double z[5];
    cup_proj_info info;
    assert_int_equal(cup_project(pr, I.w0, z, &info), CUP_OK);
    assert_memory_equal(z, I.w0, sizeof z);
    assert_int_equal(info.iterations, 0);
    assert_int_equal(info.skipped, 1);
    assert_true(info.eps_cert == 0);
    for (int i = 0; i < 6; i++) assert_true(cup_projector_lambda(pr)[i] == 0);
    cup_projector_free(&pr);
  }
  cup_polyset_free(&K);
  inst_free(&I);
}

/* Empty sets: status, and a Farkas certificate y >= 0, C^T y = 0, g^T y < 0
 * checked here from the data. */
static void check_farkas(int n, int m, const double *C, const double *g, int method) {
  tcsc Ct;
  cup_polyset *K = tpolyset_dense(&Ct, C, m, n, g, NULL);
  cup_projector_options o;
  cup_projector_options_default(&o);
  o.method = method;
  cup_projector *pr = proj_new(K, &o);
  double x[16] = {0.3, -0.2, 0.1, 0.5}, z[16];
  assert_true(n <= 16);
  for (int a = 0; a < 16; a++) z[a] = 7;
  cup_proj_info info;
  int st = cup_project(pr, x, z, &info);
  if (st != CUP_ERR_EMPTY_SET)
    fail_msg("%s: status %s, expected CUP_ERR_EMPTY_SET", cup_proj_method_name(method),
             cup_status_name(st));
  assert_true(z[0] == 7 && z[1] == 7);        /* output untouched */
  const double *y = cup_projector_farkas(pr);
  double gy = 0, ysum = 0;
  for (int i = 0; i < m; i++) { assert_true(y[i] >= 0); gy += g[i] * y[i]; ysum += y[i]; }
  assert_true(ysum > 0);
  assert_true(gy < 0);
  for (int a = 0; a < n; a++) {
    double cty = 0;
    for (int i = 0; i < m; i++) cty += C[i * n + a] * y[i];
    assert_true(fabs(cty) <= 1e-6 * fabs(gy));
  }
  assert_true(info.farkas_gap < 0);
  cup_projector_free(&pr);
  cup_polyset_free(&K);
  tcsc_free(&Ct);
}

static void test_empty_sets(void **state) {
  (void)state;
  for (int method = 0; method < 4; method++) {
    double C1[2] = {1, -1}, g1[2] = {-1, 0};               /* y >= 1 and y <= 0 */
    check_farkas(1, 2, C1, g1, method);
    double C2[6] = {1, 0, 0, 1, -1, -1}, g2[3] = {-1, -1, 1};  /* y1,y2 >= 1, y1+y2 <= 1 */
    check_farkas(2, 3, C2, g2, method);
    double C3[4] = {1, 0, 0, 0}, g3[2] = {0, -1};           /* a zero row: 0 >= 1 */
    check_farkas(2, 2, C3, g3, method);
  }
  /* a larger empty set on the sparse path: 80 rows, the last contradicts the
   * sum of two others */
  int n = 10, m = 80;
  double *C = calloc(m * n, sizeof(double)), *g = calloc(m, sizeof(double));
  rng_t r = {3};
  for (int i = 0; i < m - 1; i++) {
    for (int a = 0; a < n; a++) C[i * n + a] = rng_normal(&r);
    g[i] = 1;
  }
  for (int a = 0; a < n; a++) C[(m - 1) * n + a] = -(C[a] + C[n + a]);
  g[m - 1] = -2.5;   /* c0 y + c1 y >= -2 and -(c0 + c1) y >= 2.5: contradiction */
  for (int method = 0; method < 4; method++) check_farkas(n, m, C, g, method);
  free(C); free(g);
}

/* The feasible point itself, on request: certainly feasible, with eta = 0. */
static void test_return_feasible(void **state) {
  (void)state;
  rng_t r = {11};
  for (int trial = 0; trial < 200; trial++) {
    inst I;
    inst_small(&I, &r, trial);
    int n = I.n, m = I.m;
    cup_polyset *K = inst_polyset(&I);
    cup_projector_options o = proj_options(trial % 3 == 0 ? CUP_PROJ_FISTA : CUP_PROJ_AUTO, 1e-8, 1e-6);
    o.return_feasible = 1;
    cup_projector *pr = proj_new(K, &o);
    double *x = malloc(sizeof(double) * n), *z = malloc(sizeof(double) * n);
    random_point(&I, &r, x);
    cup_proj_info info;
    int st = cup_project(pr, x, z, &info);
    if (st == CUP_OK) {
      assert_true(info.eta_cert == 0);
      for (int i = 0; i < m; i++) {           /* feasibility from the data, here */
        long double s = I.g[i];
        for (int a = 0; a < n; a++) s += (long double)I.C[i * n + a] * z[a];
        assert_true(s >= 0);
      }
      ref_problem q = inst_ref(&I);
      double *zr = malloc(sizeof(double) * n);
      assert_int_equal(ref_project(&q, x, zr), 0);
      assert_true(info.eps_cert >= ref_excess(&q, x, z, zr) - 8e-15 * info.scale * info.scale);
      free(zr);
    }
    free(x); free(z);
    cup_projector_free(&pr);
    cup_polyset_free(&K);
    inst_free(&I);
  }
}

static void test_bad_input(void **state) {
  (void)state;
  rng_t r = {8};
  inst I;
  inst_make(&I, &r, GENERIC, 3, 4, 0);
  cup_polyset *K = inst_polyset(&I);
  cup_projector *pr = NULL;
  char msg[CUP_ERRMSG_LEN];
  cup_projector_options o;
  cup_projector_options_default(&o);
  o.eps_rel = NAN;                               /* NaN is not >= 0 */
  assert_int_equal(cup_projector_create(&pr, K, &o, msg), CUP_ERR_ARG);
  assert_null(pr);
  assert_non_null(strstr(msg, "tolerances"));
  assert_int_equal(cup_projector_create(&pr, K, NULL, NULL), CUP_OK);
  double x[3] = {1, NAN, 0}, z[3] = {5, 5, 5};
  assert_int_equal(cup_project(pr, x, z, NULL), CUP_ERR_NONFINITE);
  assert_true(z[0] == 5 && z[1] == 5 && z[2] == 5);
  double gbad[4] = {0, 0, NAN, 0};
  assert_int_equal(cup_projector_set_offset(pr, gbad), CUP_ERR_NONFINITE);
  assert_int_equal(cup_project(NULL, x, z, NULL), CUP_ERR_ARG);
  /* an offered anchor is accepted exactly when it is certainly in K */
  assert_int_equal(cup_projector_offer_feasible(pr, I.w0), cup_polyset_contains(K, NULL, I.w0));
  double out[3] = {I.w0[0] + 100, I.w0[1] - 100, I.w0[2] + 100};
  int inside = cup_polyset_contains(K, NULL, out);
  assert_int_equal(cup_projector_offer_feasible(pr, out), inside);
  assert_int_equal(cup_projector_offer_feasible(pr, x), 0);        /* NaN */
  assert_int_equal(cup_proj_method_parse("fista"), CUP_PROJ_FISTA);
  assert_int_equal(cup_proj_method_parse("newton"), -1);
  cup_projector_free(&pr);
  cup_projector_free(&pr);                       /* a second free is harmless */
  cup_polyset_free(&K);
  inst_free(&I);
}

/* Warm start: along a slowly drifting sequence, the exact method mostly
 * finishes in one solve, and answers equal the cold ones. */
static void test_warm_start_sequence(void **state) {
  (void)state;
  int cp[4] = {0, 0, 2, 3}, ci[3] = {0, 1, 0};
  double cx[3] = {1, 1, -1}, d[3] = {1, 2, 1};
  cup_csc C = {2, 3, cp, ci, cx};
  cup_metric P = {CUP_METRIC_DIAGONAL, d, {0}, 0};
  cup_polyset *K = NULL;
  assert_int_equal(cup_polyset_create(&K, &C, NULL, &P, NULL), CUP_OK);
  cup_projector *warm = NULL, *cold = NULL;
  cup_projector_options o;
  cup_projector_options_default(&o);
  assert_int_equal(cup_projector_create(&warm, K, &o, NULL), CUP_OK);
  o.warm_start = 0;
  assert_int_equal(cup_projector_create(&cold, K, &o, NULL), CUP_OK);
  int warm_it = 0, projected = 0;
  for (int k = 0; k < 100; k++) {
    double x[3] = {0.1, -0.5 + 0.003 * k, 0.2 + 0.002 * k}, zw[3], zc[3];
    cup_proj_info iw, ic;
    assert_int_equal(cup_project(warm, x, zw, &iw), CUP_OK);
    assert_int_equal(cup_project(cold, x, zc, &ic), CUP_OK);
    for (int a = 0; a < 3; a++) assert_close(zw[a], zc[a], 1e-14);
    if (!iw.skipped) { warm_it += iw.iterations; projected++; }
    if (getenv("CUP_TEST_VERBOSE")) fprintf(stderr, "k %d skipped %d it %d active %d\n", k, iw.skipped, iw.iterations, iw.active);
  }
  assert_true(projected > 50);
  assert_true(warm_it <= projected + 3);           /* one solve per projection */
  cup_projector_free(&warm);
  cup_projector_free(&cold);
  cup_polyset_free(&K);
}

/* The identity-metric projection by Hildreth's dual coordinate ascent
 * alone (the polish of ref_project_hildreth needs independent active rows,
 * which a jam has not): z = x + C^T lam, swept until no row moves (or
 * `sweeps` times: rounding keeps a jam's rows moving by ulps); then
 * ||z - z*||^2 <= 2 sum lam_i s_i when z is feasible, which the caller
 * checks. Rows given sparse (ptr/idx/val). */
static void hildreth_identity(int n, int m, const int *ptr, const int *idx, const double *val,
                              const double *g, const double *x, int sweeps, double *z,
                              double *lam) {
  for (int a = 0; a < n; a++) z[a] = x[a];
  for (int i = 0; i < m; i++) lam[i] = 0;
  for (int sweep = 0; sweep < sweeps; sweep++) {
    double moved = 0;
    for (int i = 0; i < m; i++) {
      double s = g[i], nn = 0;
      for (int e = ptr[i]; e < ptr[i + 1]; e++) { s += val[e] * z[idx[e]]; nn += val[e] * val[e]; }
      double d = fmax(-lam[i], -s / nn);
      lam[i] += d;
      for (int e = ptr[i]; e < ptr[i + 1]; e++) z[idx[e]] += d * val[e];
      moved = fmax(moved, fabs(d) * sqrt(nn));
    }
    if (moved < 1e-15) break;
  }
}

/* A jammed packing, the degenerate case of crowds: K x K disks of diameter
 * 1 touching on a hexagonal lattice in a corner (floor and right wall),
 * about 3 contacts a disk for 2 coordinates, so M_FF is singular on the
 * free rows. The floor may have a door: no floor row under the bottom
 * disks door .. door + width - 1. Each disk is pushed towards the target
 * point with its own speed; a drifting sequence of such points,
 * warm-started, each answer certified (CUP_OK) and checked against
 * Hildreth's coordinate ascent, its certificates checked true; the exact
 * path's answers exact, as the finishing solve makes them (3.5e-14 of the
 * scale; an iterate accepted short of it was 4e-10 on the unmerged jam2). */
typedef struct {
  int door, width;          /* bottom disks without a floor row */
  double tx, ty;            /* where the disks are pushed */
  uint64_t seed;
  int method, projections;
  int sweeps;               /* Hildreth's at most */
} jam_case;

static void jammed_packing(const jam_case *jc) {
  enum { K = 7, N = K * K, n = 2 * N, MMAX = 4 * N };
  static double q[n], C[MMAX * n], g[MMAX], P[n * n], x[n], z[n], zr[n], dir[n];
  memset(C, 0, sizeof C);
  memset(P, 0, sizeof P);
  int m = 0;
  double h = sqrt(3) / 2;
  for (int r = 0; r < K; r++)
    for (int c = 0; c < K; c++) {
      q[2 * (r * K + c)] = c + 0.5 * (r % 2) - K;     /* right wall at x = 0.5 (row 1) */
      q[2 * (r * K + c) + 1] = 0.5 + r * h;           /* floor at y = 0 */
    }
  for (int i = 0; i < N; i++) {
    for (int j = i + 1; j < N; j++) {
      double ex = q[2 * i] - q[2 * j], ey = q[2 * i + 1] - q[2 * j + 1], d = hypot(ex, ey);
      if (d > 1 + 1e-9) continue;
      double *row = C + (size_t)m * n;                 /* e . (y_i - y_j) - 1 >= 0 */
      row[2 * i] = ex / d; row[2 * i + 1] = ey / d;
      row[2 * j] = -ex / d; row[2 * j + 1] = -ey / d;
      g[m++] = -1;
    }
    if (i < K && (i < jc->door || i >= jc->door + jc->width)) {   /* floor */
      C[(size_t)m * n + 2 * i + 1] = 1;
      g[m++] = -0.5;
    }
    if (q[2 * i] > -0.6) { C[(size_t)m * n + 2 * i] = -1; g[m++] = 0.5 + 0.5 * ((i / K) % 2); }
  }
  assert_true(m > n && m <= MMAX && m > 64);           /* redundant, and the sparse path */
  for (int a = 0; a < n; a++) P[a * n + a] = 1;
  tcsc Ct;
  tcsc_from_dense(&Ct, C, m, n);
  cup_metric Pm = {CUP_METRIC_IDENTITY, NULL, {0}, 0};
  cup_polyset *Kset = NULL;
  char msg[CUP_ERRMSG_LEN];
  if (cup_polyset_create(&Kset, &Ct.view, g, &Pm, msg)) fail_msg("create: %s", msg);
  cup_projector_options o = proj_options(jc->method, 1e-11, 1e-9);
  cup_projector *pr = proj_new(Kset, &o);
  ref_problem rq = {n, m, C, g, P};
  static int rp[MMAX + 1], ri[MMAX * n];
  static double rv[MMAX * n], lr[MMAX];
  rp[0] = 0;
  for (int i = 0; i < m; i++) {
    rp[i + 1] = rp[i];
    for (int a = 0; a < n; a++)
      if (C[(size_t)i * n + a] != 0) { ri[rp[i + 1]] = a; rv[rp[i + 1]++] = C[(size_t)i * n + a]; }
  }
  rng_t r = {jc->seed};
  for (int i = 0; i < N; i++) {
    double dx = jc->tx - q[2 * i], dy = jc->ty - q[2 * i + 1], d = hypot(dx, dy);
    double v = 0.05 + 0.05 * rng_unif(&r);
    dir[2 * i] = v * dx / d;
    dir[2 * i + 1] = v * dy / d;
  }
  double worst = 0;
  int total_it = 0, facts = 0, updates = 0;
  for (int k = 0; k < jc->projections; k++) {
    for (int a = 0; a < n; a++) x[a] = q[a] + (1 + 0.1 * k) * dir[a] + 1e-3 * rng_normal(&r);
    cup_proj_info info;
    int st = cup_project(pr, x, z, &info);
    if (st != CUP_OK)
      fail_msg("projection %d: %s, eps %.3g (target %.3g), eta %.3g (target %.3g)", k,
               cup_status_name(st), info.eps_cert, info.eps_target, info.eta_cert, info.eta_target);
    hildreth_identity(n, m, rp, ri, rv, g, x, jc->sweeps, zr, lr);
    double err = 0, S = sqrt(ref_pnorm2(&rq, x)), gap = 0;
    for (int i = 0; i < m; i++) {                      /* the reference's own accuracy */
      double s = g[i];
      for (int e = rp[i]; e < rp[i + 1]; e++) s += rv[e] * zr[ri[e]];
      assert_true(s >= -1e-13 * S);
      gap += lr[i] * fabs(s);
    }
    assert_true(sqrt(2 * gap) <= 1e-7 * S);
    for (int a = 0; a < n; a++) err = fmax(err, fabs(z[a] - zr[a]));
    worst = fmax(worst, err / S);
    assert_true(err <= sqrt(2 * gap) + 1e-9 * S);
    assert_true(info.eps_cert >= ref_excess(&rq, x, z, zr) - 1e-12 * S * S);
    for (int i = 0; i < m; i++) {                      /* d_K(z) >= each row's violation */
      double s = g[i];
      for (int a = 0; a < n; a++) s += C[(size_t)i * n + a] * z[a];
      double rn = 0;
      for (int a = 0; a < n; a++) rn += C[(size_t)i * n + a] * C[(size_t)i * n + a];
      assert_true(info.eta_cert >= -s / sqrt(rn) - 1e-12 * S);
    }
    total_it += info.iterations;
    facts += info.factorizations;
    updates += info.row_updates;
  }
  print_message("jammed packing (%s, door %d+%d): %d disks, %d rows, %d projections, %d iterations, "
                "%d factorizations, %d row updates, worst ||z - z*||/S %.2e\n",
                cup_proj_method_name(jc->method), jc->door, jc->width, N, m, jc->projections, total_it,
                facts, updates, worst);
  if (jc->method == CUP_PROJ_AUTO) assert_true(worst <= 1e-11);
  cup_projector_free(&pr);
  cup_polyset_free(&Kset);
  tcsc_free(&Ct);
}

static void test_jammed_packing_against_hildreth(void **state) {
  (void)state;
  jammed_packing(&(jam_case){0, 0, 0.5, 0, 4242, CUP_PROJ_AUTO, 12, 50000});
}

/* A door in the floor under the bottom row's disks 3..5, the disks pushed
 * towards and through it: the finishing solve's refinement drifts along
 * the kernel of the singular M_FF and leaves small multipliers negative
 * (1e-7 to 1e-6), and clipping them moved z out of K by more than eta's
 * target: main returned CUP_WARN_NOT_CERTIFIED at the third projection. */
static void test_jammed_packing_door_in_floor(void **state) {
  (void)state;
  jammed_packing(&(jam_case){3, 3, -3, -3, 2, CUP_PROJ_AUTO, 3, 50000});
}

/* The first-order methods on the jam: their iterates approach the answer
 * from outside K and no feasible point anchors eta (g < 0: the origin is
 * outside), so they certified nothing before they aimed inside. */
static void test_jammed_packing_first_order(void **state) {
  (void)state;
  for (int method = CUP_PROJ_PG; method <= CUP_PROJ_FISTA; method++)
    jammed_packing(&(jam_case){0, 0, 0.5, 0, 4242, method, 3, 50000});
}

/* Weighted isotonic regression by pool-adjacent-violators: argmin
 * sum_j w_j (z_j - a_j)^2 over nondecreasing z (an exact answer in O(n)). */
static void pava(const double *a, const double *w, int n, double *z) {
  double *val = malloc(sizeof(double) * n), *wt = malloc(sizeof(double) * n);
  int *len = malloc(sizeof(int) * n), nb = 0;
  for (int j = 0; j < n; j++) {
    val[nb] = a[j]; wt[nb] = w[j]; len[nb++] = 1;
    while (nb > 1 && val[nb - 2] > val[nb - 1]) {        /* pool the last two blocks */
      double W = wt[nb - 2] + wt[nb - 1];
      val[nb - 2] = (wt[nb - 2] * val[nb - 2] + wt[nb - 1] * val[nb - 1]) / W;
      wt[nb - 2] = W;
      len[nb - 2] += len[nb - 1];
      nb--;
    }
  }
  for (int b = 0, j = 0; b < nb; b++)
    for (int t = 0; t < len[b]; t++) z[j++] = val[b];
  free(val); free(wt); free(len);
}

/* A ladder of diodes, y_{i+1} - y_i + g_i >= 0 with a diagonal P: the
 * P-projection is a weighted isotonic regression of x + G (G_i = g_0 + ...
 * + g_{i-1}), computed exactly by PAVA. */
typedef struct ladder {
  int m, n;
  int *cp, *ci;
  double *cx, *g, *p, *G, *a;
  cup_polyset *K;
  double noise;
} ladder;

static void ladder_make(ladder *L, rng_t *r, int m) {
  int n = m + 1, q = 0;
  L->m = m; L->n = n; L->noise = 0;
  L->cp = malloc(sizeof(int) * (n + 1)); L->ci = malloc(sizeof(int) * 2 * m);
  L->cx = malloc(sizeof(double) * 2 * m); L->g = malloc(sizeof(double) * m);
  L->p = malloc(sizeof(double) * n); L->G = malloc(sizeof(double) * n); L->a = malloc(sizeof(double) * n);
  for (int j = 0; j < n; j++) {           /* column j: row j-1 (+1) and row j (-1) */
    L->cp[j] = q;
    if (j > 0) { L->ci[q] = j - 1; L->cx[q++] = 1; }
    if (j < m) { L->ci[q] = j; L->cx[q++] = -1; }
  }
  L->cp[n] = q;
  L->G[0] = 0;
  for (int i = 0; i < m; i++) { L->g[i] = 0.002 + 0.004 * rng_unif(r); L->G[i + 1] = L->G[i] + L->g[i]; }
  for (int j = 0; j < n; j++) L->p[j] = 1 + 9 * rng_unif(r);
  cup_csc C = {m, n, L->cp, L->ci, L->cx};
  cup_metric P = {CUP_METRIC_DIAGONAL, L->p, {0}, 0};
  L->K = NULL;
  assert_int_equal(cup_polyset_create(&L->K, &C, L->g, &P, NULL), CUP_OK);
}

/* Point k of a drifting noisy sine, and its projection zr by PAVA. */
static void ladder_point(ladder *L, rng_t *r, int k, double *x, double *zr) {
  for (int j = 0; j < L->n; j++) {
    L->noise = 0.5 * L->noise + 0.004 * rng_normal(r);
    x[j] = sin(2 * M_PI * j / 400.0 + 0.05 * k) + L->noise;
    L->a[j] = x[j] + L->G[j];
  }
  pava(L->a, L->p, L->n, zr);
  for (int j = 0; j < L->n; j++) zr[j] -= L->G[j];
}

static void ladder_free(ladder *L) {
  cup_polyset_free(&L->K);
  free(L->cp); free(L->ci); free(L->cx); free(L->g); free(L->p); free(L->G); free(L->a);
}

/* About half the rows end active in long blocks, which an active-set method
 * reaches row by row: the sparse exact path, its cold start, its restricted
 * factors and row updates, cold and warm. */
static void test_ladder_against_pava(void **state) {
  (void)state;
  rng_t r = {1855};
  ladder L;
  ladder_make(&L, &r, 3000);
  int m = L.m, n = L.n;
  double *x = malloc(sizeof(double) * n), *zr = malloc(sizeof(double) * n), *z = malloc(sizeof(double) * n);
  for (int warm = 0; warm <= 1; warm++) {
    /* the finishing solve aims the slack of the active rows ~16 ulps inside,
     * which costs 2 sum lam_i s_i ~ 1e-12 S^2 here (long blocks carry large
     * multipliers): certify a little above that floor */
    cup_projector_options o = proj_options(CUP_PROJ_AUTO, 1e-11, 1e-8);
    o.warm_start = warm;
    cup_projector *pr = proj_new(L.K, &o);
    for (int k = 0; k < 6; k++) {
      ladder_point(&L, &r, k, x, zr);
      cup_proj_info info;
      int st = cup_project(pr, x, z, &info);
      if (st != CUP_OK)
        fail_msg("%s point %d: %s after %d iterations, eps %.3g (target %.3g), eta %.3g (target %.3g)",
                 warm ? "warm" : "cold", k, cup_status_name(st), info.iterations, info.eps_cert,
                 info.eps_target, info.eta_cert, info.eta_target);
      double e2 = 0, r2 = 0, active = 0;
      for (int j = 0; j < n; j++) {
        e2 += L.p[j] * (z[j] - zr[j]) * (z[j] - zr[j]);
        r2 += L.p[j] * zr[j] * zr[j];
      }
      for (int i = 0; i < m; i++) active += fabs(zr[i + 1] - zr[i] + L.g[i]) < 1e-12;
      assert_true(active > 0.3 * m);     /* long blocks: the hard case for active sets */
      if (!(sqrt(e2 / r2) < 1e-9))
        fail_msg("%s point %d: ||z - PAVA||_P / ||PAVA||_P = %.3e", warm ? "warm" : "cold", k,
                 sqrt(e2 / r2));
      assert_true(info.eps_cert <= info.eps_target && info.eta_cert <= info.eta_target);
    }
    cup_projector_free(&pr);
  }
  ladder_free(&L);
  free(x); free(zr); free(z);
}

/* The cold start for a Stieltjes M (newton.c, grow_start) against the
 * ladder's exact multipliers: P (z* - x) = C^T lam*, i.e. lam*_j =
 * lam*_{j-1} - p_j (z*_j - x_j) from PAVA's z*. Every multiplier it returns
 * is below lam* (the proof that its rows are active rests on it), and its
 * free set settles on the active set (the multipliers there are lam* up to
 * the regularization of the solves), so the projected Newton after it has no
 * rows left to find. A set whose M has a positive off-diagonal
 * does not take this start. */
static void test_ladder_cold_start(void **state) {
  (void)state;
  rng_t r = {1856};
  ladder L;
  ladder_make(&L, &r, 3000);
  int m = L.m, n = L.n;
  double *x = malloc(sizeof(double) * n), *zr = malloc(sizeof(double) * n), *z = malloc(sizeof(double) * n);
  double *lam = malloc(sizeof(double) * m), *ls = malloc(sizeof(double) * m);
  cup_projector_options o = proj_options(CUP_PROJ_AUTO, 1e-11, 1e-8);
  o.warm_start = 0;
  cup_projector *pr = proj_new(L.K, &o);
  for (int k = 0; k < 4; k++) {
    ladder_point(&L, &r, k, x, zr);
    double prev = 0, lmax = 0;
    for (int i = 0; i < m; i++) {
      ls[i] = prev - L.p[i] * (zr[i] - x[i]);
      prev = ls[i];
      lmax = fmax(lmax, ls[i]);
    }
    int solves = newton_cold_start(pr, x, lam);
    assert_true(solves >= 1);
    double above = 0;
    int wrong = 0;
    for (int i = 0; i < m; i++) {
      above = fmax(above, lam[i] - ls[i]);
      /* the free set it ends on is PAVA's active set (rows with lam* at
       * rounding either way) */
      if (fabs(ls[i]) > 1e-9 * lmax) wrong += (lam[i] > 0) != (ls[i] > 0);
    }
    if (!(above <= 1e-10 * lmax) || wrong)
      fail_msg("point %d: cold start above lam* by %.3e (max lam* %.3e), %d rows on the wrong side",
               k, above, lmax, wrong);
    cup_proj_info info;
    assert_int_equal(cup_project(pr, x, z, &info), CUP_OK);
    if (info.iterations > solves + 2)
      fail_msg("point %d: %d Newton iterations after the cold start's %d solves", k,
               info.iterations - solves, solves);
  }
  cup_projector_free(&pr);
  L.cx[0] = -L.cx[0];                     /* row 0 turned round: M(0, 1) > 0 */
  L.cx[1] = -L.cx[1];
  cup_csc C2 = {m, n, L.cp, L.ci, L.cx};
  cup_metric P2 = {CUP_METRIC_DIAGONAL, L.p, {0}, 0};
  cup_polyset *K2 = NULL;
  assert_int_equal(cup_polyset_create(&K2, &C2, L.g, &P2, NULL), CUP_OK);
  assert_int_equal(cup_projector_create(&pr, K2, &o, NULL), CUP_OK);
  assert_int_equal(newton_cold_start(pr, x, lam), 0);
  cup_projector_free(&pr);
  cup_polyset_free(&K2);
  ladder_free(&L);
  free(x); free(zr); free(z); free(lam); free(ls);
}

/* No allocation in cup_project: 10^4 projections per configuration. */
static void test_no_allocation(void **state) {
  (void)state;
#if !HEAP_INTERPOSED
  skip();
#else
  rng_t r = {2};
  inst small, big, bigd;
  inst_make(&small, &r, GENERIC, 4, 6, 0);
  inst_make(&big, &r, GENERIC, 40, 90, 1);         /* sparse path, non-diagonal P: KKT form */
  inst_make(&bigd, &r, GENERIC, 40, 90, 0);        /* sparse path, diagonal P: row updates */
  inst *sets[3] = {&small, &big, &bigd};
  for (int s = 0; s < 3; s++) {
    inst *I = sets[s];
    cup_polyset *K = NULL;
    assert_int_equal(cup_polyset_create(&K, &I->Ct.view, I->g, &I->Pm, NULL), CUP_OK);
    for (int method = 0; method < 4; method++) {
      cup_projector_options o = proj_options(method, 1e-8, 1e-6);
      o.max_iter = 2000;
      cup_projector *pr = proj_new(K, &o);
      double *x = malloc(sizeof(double) * I->n), *z = malloc(sizeof(double) * I->n);
      double *dir = malloc(sizeof(double) * I->n);
      random_point(I, &r, x);
      for (int a = 0; a < I->n; a++) dir[a] = 1e-3 * rng_normal(&r);
      /* 10^4 projections on the small set; the big one with the exact method
       * too, fewer with the slow first-order methods */
      int nproj = s == 0 || method == CUP_PROJ_AUTO ? 10000 : 300;
      long before = heap_calls;
      heap_counting = 1;
      int bad = 0;
      for (int k = 0; k < nproj; k++) {
        for (int a = 0; a < I->n; a++) x[a] += dir[a] * (k % 200 < 100 ? 1 : -1);
        int st = cup_project(pr, x, z, NULL);
        bad += st < 0;
      }
      heap_counting = 0;
      long allocs = heap_calls - before;
      if (allocs != 0)
        fail_msg("set %d method %s: %ld allocations in %d projections", s,
                 cup_proj_method_name(method), allocs, nproj);
      assert_int_equal(bad, 0);
      free(x); free(z); free(dir);
      cup_projector_free(&pr);
    }
    cup_polyset_free(&K);
  }
  inst_free(&small);
  inst_free(&big);
  inst_free(&bigd);
#endif
}

/* The small-set path has one owner (choose.c): a scheme whose step is the
 * LCP asks proj_small_lcp, and the projector it keeps behind that step
 * (proj_backup_options) sets up no second LCP: the small method's fallback
 * alone, which still projects (against the auto projector's answer). */
static void test_backup_holds_no_second_lcp(void **state) {
  (void)state;
  double Cd[4] = {1, 0.5, -0.25, 1}, g[2] = {-1, -2}, pd[2] = {1, 2};
  tcsc C;
  cup_polyset *K = tpolyset_dense(&C, Cd, 2, 2, g, pd);
  cup_projector_options o;
  cup_projector_options_default(&o);
  o.eps_abs = o.eta_abs = 0;
  o.eps_rel = 1e-14;
  assert_true(proj_small_lcp(K, &o));
  assert_true(proj_small_lcp(K, NULL));
  cup_projector_options b = proj_backup_options(K, &o);
  assert_false(proj_small_lcp(K, &b));
  assert_ptr_equal(proj_choose(K, &b), *proj_small->fallback);
  cup_projector *pa = NULL, *pb = NULL;
  assert_int_equal(cup_projector_create(&pa, K, &o, NULL), CUP_OK);
  assert_int_equal(cup_projector_create(&pb, K, &b, NULL), CUP_OK);
  assert_ptr_equal(pa->slot[pa->method].m, proj_small);
  assert_int_equal(pb->nslots, 1);
  assert_ptr_equal(pb->slot[pb->method].m, proj_dense);
  double x[2] = {-3, 0.5}, za[2], zb[2];
  cup_proj_info ia, ib;
  assert_int_equal(cup_project(pa, x, za, &ia), CUP_OK);
  assert_int_equal(cup_project(pb, x, zb, &ib), CUP_OK);
  assert_int_equal(ia.skipped, 0);
  for (int j = 0; j < 2; j++) assert_true(fabs(za[j] - zb[j]) <= 1e-12 * (1 + fabs(za[j])));
  cup_projector_free(&pa);
  cup_projector_free(&pb);
  /* no small path, nothing to take over: the options as they are */
  o.method = CUP_PROJ_PG;
  assert_int_equal(proj_backup_options(K, &o).method, CUP_PROJ_PG);
  o.method = CUP_PROJ_AUTO;
  o.feasible_point = x;
  assert_false(proj_small_lcp(K, &o));
  assert_int_equal(proj_backup_options(K, &o).method, CUP_PROJ_AUTO);
  cup_polyset_free(&K);
  tcsc_free(&C);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_random_polyhedra_enumeration),
    cmocka_unit_test(test_random_polyhedra_sparse_path),
    cmocka_unit_test(test_first_order_methods),
    cmocka_unit_test(test_scaling),
    cmocka_unit_test(test_skip_returns_x_exactly),
    cmocka_unit_test(test_empty_sets),
    cmocka_unit_test(test_return_feasible),
    cmocka_unit_test(test_bad_input),
    cmocka_unit_test(test_warm_start_sequence),
    cmocka_unit_test(test_ladder_against_pava),
    cmocka_unit_test(test_ladder_cold_start),
    cmocka_unit_test(test_jammed_packing_against_hildreth),
    cmocka_unit_test(test_jammed_packing_door_in_floor),
    cmocka_unit_test(test_jammed_packing_first_order),
    cmocka_unit_test(test_no_allocation),
    cmocka_unit_test(test_backup_holds_no_second_lcp),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

/* catchup-bench — figures, not tests: run time and iterations of the
 * projector on problem directories, steps per second of the integrator on
 * the paper's circuit, and peak memory against n.
 *
 *   catchup-bench projector DIR... [--reps R] [--methods auto,pg,fista] [--eps-rel E] [--eta-rel E]
 *                           [--max-points K] [--verbose] [--no-updates]
 *   catchup-bench integrate [--n N] [--reps R]
 *   catchup-bench memory [--n N]...
 *   catchup-bench circuit --ref-dir DIR [--n N]... [--reps R]
 *   catchup-bench adaptive --ref-dir DIR [--tol T]... [--reps R]
 *
 * One JSON line per measurement on stdout; a table on stderr. The projector
 * runs each (problem, method, mode) in a child process that makes the
 * polyset and the projector (both timed as set-up) and reports its peak
 * resident set from the set-up on (VmHWM after malloc_trim and
 * /proc/self/clear_refs), and that minus its size before the set-up and
 * minus the library code paged in on first use (the projector's own data,
 * beside the QP peers' in scripts/bench_qp_peers.py). With the heapcount
 * shim preloaded (LD_PRELOAD=build/bench/libcatchup_heapcount.so, as
 * scripts/bench-projector does for both harnesses) it also reports the most
 * heap bytes the set-up and the projections held at once: resident pages are
 * too coarse a measure for sets of a few rows. */
#define _GNU_SOURCE   /* RTLD_DEFAULT */
#include <float.h>
#include <malloc.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <dlfcn.h>
#include <cholmod.h>
#include "catchup.h"
#include "util/clock.h"
#include "../bench/paper.h"   /* the paper's circuit, shared with the tests */

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* A number for JSON, which has no inf or nan: those are null. */
static const char *json_num(char buf[32], double v) {
  if (!isfinite(v)) return "null";
  snprintf(buf, 32, "%.3e", v);
  return buf;
}

static double median(double *v, int n) {
  qsort(v, (size_t)n, sizeof *v, cmp_double);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static void die(const char *fmt, const char *a) {
  fprintf(stderr, "catchup-bench: ");
  fprintf(stderr, fmt, a);
  fprintf(stderr, "\n");
  exit(1);
}

/* ---- problem directories (the format scripts/make_problems.py writes) ------ */

typedef struct {
  char name[256];
  int n, m, K;
  cholmod_sparse *C, *P;        /* P full symmetric */
  double *g, *x, *ref;          /* m; K x n; K x n or NULL */
  cup_polyset *set;
} problem;

static cholmod_sparse *read_mtx(const char *dir, const char *file, cholmod_common *cm) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, file);
  FILE *f = fopen(path, "r");
  if (!f) die("cannot open %s", path);
  cholmod_sparse *A = cholmod_read_sparse(f, cm);
  fclose(f);
  if (!A) die("cannot read Matrix Market file %s", path);
  if (A->stype != 0) {                     /* expand a symmetric file */
    cholmod_sparse *B = cholmod_copy(A, 0, 1, cm);
    cholmod_free_sparse(&A, cm);
    A = B;
  }
  cholmod_sort(A, cm);
  return A;
}

static double *read_numbers(const char *dir, const char *file, long count, int optional) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, file);
  FILE *f = fopen(path, "r");
  if (!f) {
    if (optional) return NULL;
    die("cannot open %s", path);
  }
  double *v = malloc(sizeof(double) * (size_t)count);
  for (long k = 0; k < count; k++)
    if (fscanf(f, "%lf", &v[k]) != 1) die("too few numbers in %s", path);
  fclose(f);
  return v;
}

static long count_lines(const char *dir, const char *file) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", dir, file);
  FILE *f = fopen(path, "r");
  if (!f) die("cannot open %s", path);
  long lines = 0;
  int c, last = '\n';
  while ((c = fgetc(f)) != EOF) { if (c == '\n') lines++; last = c; }
  if (last != '\n') lines++;
  fclose(f);
  return lines;
}

static cup_csc view(const cholmod_sparse *A) {
  return (cup_csc){(int)A->nrow, (int)A->ncol, A->p, A->i, A->x};
}

static void load_problem(problem *pb, const char *dir, cholmod_common *cm) {
  memset(pb, 0, sizeof *pb);
  const char *slash = strrchr(dir, '/');
  snprintf(pb->name, sizeof pb->name, "%s", slash && slash[1] ? slash + 1 : dir);
  pb->C = read_mtx(dir, "C.mtx", cm);
  pb->P = read_mtx(dir, "P.mtx", cm);
  pb->m = (int)pb->C->nrow;
  pb->n = (int)pb->C->ncol;
  pb->K = (int)count_lines(dir, "points.txt");
  pb->g = read_numbers(dir, "g.txt", pb->m, 0);
  pb->x = read_numbers(dir, "points.txt", (long)pb->K * pb->n, 0);
  pb->ref = read_numbers(dir, "ref.txt", (long)pb->K * pb->n, 1);
  fprintf(stderr, "%s: n %d, m %d, %d points\n", pb->name, pb->n, pb->m, pb->K);
}

/* The polyset is catchup's own structure: made in the process that is
 * measured, timed as set-up. */
static double make_set(problem *pb) {
  cup_csc C = view(pb->C);
  cup_metric P = {CUP_METRIC_SPARSE, NULL, view(pb->P), 0};
  char msg[CUP_ERRMSG_LEN];
  double t0 = now_seconds();
  if (cup_polyset_create(&pb->set, &C, pb->g, &P, msg)) die("%s", msg);
  return now_seconds() - t0;
}

/* Restart the kernel's peak-RSS record (VmHWM) at the current size, the
 * heap's free memory given back first: memory freed before (the loading's)
 * and reused by what is measured would not count (scripts/bench_qp_peers.py
 * does the same). */
static void reset_peak(void) {
  malloc_trim(0);
  FILE *f = fopen("/proc/self/clear_refs", "w");
  if (f) { fputs("5", f); fclose(f); }
}

/* Restart the heapcount shim's record, if it is preloaded; after the last
 * file read before the measure (a FILE and its buffer are 4.5 kB). */
static void reset_heap(void) {
  void (*reset)(void) = (void (*)(void))dlsym(RTLD_DEFAULT, "cup_heapcount_reset");
  if (reset) reset();
}

/* Heap bytes held at most since reset_heap, above what was held then: -1
 * without the heapcount shim. */
static long heap_peak_bytes(void) {
  long (*peak)(void) = (long (*)(void))dlsym(RTLD_DEFAULT, "cup_heapcount_peak");
  return peak ? peak() : -1;
}

/* The resident set's figures, kB, from one read of /proc/self/status: its
 * peak since reset_peak (VmHWM), its size now (VmRSS) and the part mapped
 * from files (RssFile, the libraries' code among them). One read, so that the
 * code the reading itself pages in falls on one side of it, not between two
 * figures (two reads counted libc's parsing code as the solver's data). */
typedef struct { long hwm, rss, file; } rss_figures;

static rss_figures rss_now(void) {
  rss_figures r = {-1, 0, 0};
  char buf[4096];
  FILE *f = fopen("/proc/self/status", "r");
  size_t len = f ? fread(buf, 1, sizeof buf - 1, f) : 0;
  if (f) fclose(f);
  buf[len] = 0;
  for (char *line = buf, *nl; line; line = (nl = strchr(line, '\n')) ? nl + 1 : NULL) {
    if (!strncmp(line, "VmHWM:", 6)) r.hwm = atol(line + 6);
    else if (!strncmp(line, "VmRSS:", 6)) r.rss = atol(line + 6);
    else if (!strncmp(line, "RssFile:", 8)) r.file = atol(line + 8);
  }
  if (r.hwm < 0) {          /* no /proc: the peak since the process began */
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    r.hwm = ru.ru_maxrss;
  }
  return r;
}

static void free_problem(problem *pb, cholmod_common *cm) {
  cup_polyset_free(&pb->set);
  cholmod_free_sparse(&pb->C, cm);
  cholmod_free_sparse(&pb->P, cm);
  free(pb->g); free(pb->x); free(pb->ref);
}

/* ||z - ref||_P / max(||ref||_P, ||x||_P) over the sequence */
static double rel_error(const problem *pb, const double *z, int k, double *tmp) {
  const double *r = pb->ref + (size_t)k * pb->n, *x = pb->x + (size_t)k * pb->n;
  for (int j = 0; j < pb->n; j++) tmp[j] = z[j] - r[j];
  double e = cup_polyset_norm(pb->set, tmp);
  double s = fmax(cup_polyset_norm(pb->set, r), cup_polyset_norm(pb->set, x));
  return e / (s > 0 ? s : 1);
}

/* One (method, mode) on a problem, in a child process: set-up, the timed
 * sequence, the untimed one for statistics and errors, and the memory. */
static void run_sequence(problem *pb, const char *tok, int method, int warm, int reps,
                         double eps_rel, double eta_rel, int verbose, int updates) {
  reset_peak();
  rss_figures before = rss_now();
  reset_heap();
  double set_setup = make_set(pb);
  double *z = malloc(sizeof(double) * (size_t)pb->n), *tmp = malloc(sizeof(double) * (size_t)pb->n);
  double *times = malloc(sizeof(double) * (size_t)reps);
  cup_projector_options o;
  cup_projector_options_default(&o);
  o.method = method;
  o.warm_start = warm;
  o.eps_rel = eps_rel;
  o.eta_rel = eta_rel;
  o.max_iter = 200000;
  o.factor_updates = updates;
  cup_projector *pr = NULL;
  char msg[CUP_ERRMSG_LEN];
  double t0 = now_seconds();
  if (cup_projector_create(&pr, pb->set, &o, msg)) die("%s", msg);
  double setup = now_seconds() - t0;
  /* timed: the whole sequence, one clock read before and after (a clock read per
   * projection would cost about as much as the projection on small sets); cold
   * mode resets the warm start between points, inside the timing */
  long inner = 1;                    /* sequences per timing: at least 20 ms */
  for (int r = -1; r < reps; r++) {
    double a = now_seconds();
    for (long q = 0; q < inner; q++) {
      cup_projector_reset(pr);
      for (int k = 0; k < pb->K; k++) {
        cup_project(pr, pb->x + (size_t)k * pb->n, z, NULL);
        if (!warm) cup_projector_reset(pr);
      }
    }
    double el = now_seconds() - a;
    if (r < 0) inner = el < 0.02 ? (long)ceil(0.02 / fmax(el, 1e-9)) : 1;   /* calibration */
    else times[r] = el / ((double)inner * pb->K);
  }
  /* untimed: the same sequence again for the statistics and the errors */
  long iters = 0, certified = 0, proj = 0, facts = 0;
  double maxerr = 0, eps_max = 0, eta_max = 0;
  cup_projector_reset(pr);
  for (int k = 0; k < pb->K; k++) {
    cup_proj_info info;
    double a = now_seconds();
    int st = cup_project(pr, pb->x + (size_t)k * pb->n, z, &info);
    if (!warm) cup_projector_reset(pr);
    if (verbose)
      fprintf(stderr, "  point %d: %s, %d iterations, %d factorizations, %d row updates, "
              "eps %.3g (target %.3g), eta %.3g (target %.3g), %.3g s\n", k, cup_status_name(st),
              info.iterations, info.factorizations, info.row_updates, info.eps_cert,
              info.eps_target, info.eta_cert, info.eta_target, now_seconds() - a);
    iters += info.iterations;
    facts += info.factorizations;
    certified += st == CUP_OK;
    proj++;
    /* the certified bounds relative to the targets' scale, as the options give them */
    eps_max = fmax(eps_max, info.eps_cert / fmax(info.scale * info.scale, DBL_MIN));
    eta_max = fmax(eta_max, info.eta_cert / fmax(info.scale, DBL_MIN));
    if (pb->ref) maxerr = fmax(maxerr, rel_error(pb, z, k, tmp));
  }
  long heap = heap_peak_bytes();
  rss_figures after = rss_now();
  long peak = after.hwm;
  /* library code paged in on first use is not data */
  long base_kb = before.rss + (after.file - before.file);
  double med = median(times, reps);
  fprintf(stderr, "%-16s %-6s %-5s %10.3g s %8.1f %6.1f %4ld/%-3ld %10.2e %9.3f %9ld\n", pb->name, tok,
          warm ? "warm" : "cold", med, (double)iters / proj, (double)facts / proj, certified, proj,
          pb->ref ? maxerr : NAN, set_setup + setup, peak);
  char je[32], jt[32], jr[32];   /* a bound never certified is inf: null in JSON */
  char jh[32] = "null";          /* no heap figure without the shim */
  if (heap >= 0) snprintf(jh, sizeof jh, "%ld", heap);
  printf("{\"bench\": \"projector\", \"problem\": \"%s\", \"solver\": \"catchup-%s\", "
         "\"mode\": \"%s\", \"n\": %d, \"m\": %d, \"K\": %d, \"reps\": %d, "
         "\"median_s_per_projection\": %.6g, \"iterations_mean\": %.3f, \"factorizations_mean\": %.3f, "
         "\"certified\": %ld, \"eps_rel\": %.3g, \"eta_rel\": %.3g, \"max_eps_cert_rel\": %s, "
         "\"max_eta_cert_rel\": %s, \"max_rel_err\": %s, \"setup_s\": %.4g, \"polyset_setup_s\": %.4g, "
         "\"peak_rss_kb\": %ld, \"solver_rss_kb\": %ld, \"solver_heap_bytes\": %s}\n",
         pb->name, tok, warm ? "warm" : "cold", pb->n, pb->m, pb->K, reps, med,
         (double)iters / proj, (double)facts / proj, certified, eps_rel, eta_rel, json_num(je, eps_max),
         json_num(jt, eta_max), json_num(jr, pb->ref ? maxerr : -1.0), setup, set_setup, peak,
         peak > base_kb ? peak - base_kb : 0, jh);
  cup_projector_free(&pr);
  cup_polyset_free(&pb->set);
  free(z); free(tmp); free(times);
}

static void bench_projector(int argc, char **argv) {
  int reps = 5, max_points = 0, verbose = 0, updates = 1;
  double eps_rel = 1e-12, eta_rel = 1e-8;
  const char *methods = "auto,pg,fista";
  int ndirs = 0;
  char **dirs = calloc((size_t)argc, sizeof(char *));
  for (int a = 0; a < argc; a++) {
    if (!strcmp(argv[a], "--reps") && a + 1 < argc) reps = atoi(argv[++a]);
    else if (!strcmp(argv[a], "--methods") && a + 1 < argc) methods = argv[++a];
    else if (!strcmp(argv[a], "--eta-rel") && a + 1 < argc) eta_rel = atof(argv[++a]);
    else if (!strcmp(argv[a], "--eps-rel") && a + 1 < argc) eps_rel = atof(argv[++a]);
    else if (!strcmp(argv[a], "--max-points") && a + 1 < argc) max_points = atoi(argv[++a]);
    else if (!strcmp(argv[a], "--verbose")) verbose = 1;
    else if (!strcmp(argv[a], "--no-updates")) updates = 0;
    else dirs[ndirs++] = argv[a];
  }
  if (!ndirs) die("%s", "projector: give at least one problem directory");
  cholmod_common cm;
  cholmod_start(&cm);
  cm.print = 0;
  fprintf(stderr, "%-16s %-6s %-5s %12s %8s %6s %8s %10s %9s %9s\n", "problem", "method", "mode",
          "median/proj", "iters", "facts", "cert", "max rel err", "setup s", "peak kB");
  for (int d = 0; d < ndirs; d++) {
    problem pb;
    load_problem(&pb, dirs[d], &cm);
    if (max_points > 0 && pb.K > max_points) pb.K = max_points;
    char mlist[256];
    snprintf(mlist, sizeof mlist, "%s", methods);
    for (char *tok = strtok(mlist, ","); tok; tok = strtok(NULL, ",")) {
      int method = cup_proj_method_parse(tok);
      if (method < 0) die("unknown method %s", tok);
      for (int warm = 0; warm <= 1; warm++) {
        /* each (method, mode) in its own process: its peak memory is its own */
        fflush(stdout);
        fflush(stderr);
        pid_t pid = fork();
        if (pid < 0) die("%s", "fork failed");
        if (pid == 0) {
          run_sequence(&pb, tok, method, warm, reps, eps_rel, eta_rel, verbose, updates);
          fflush(stdout);
          fflush(stderr);
          _exit(0);
        }
        int wst;
        if (waitpid(pid, &wst, 0) < 0 || !WIFEXITED(wst) || WEXITSTATUS(wst) != 0)
          die("projector: the run on %s failed", pb.name);
      }
    }
    free_problem(&pb, &cm);
  }
  cholmod_finish(&cm);
  free(dirs);
}

/* ---- the integrator on the paper's circuit ------------------------------------- */

static double run_circuit(int cas, long n, int scheme, int method, cup_output_kind out,
                          cup_run_info *info) {
  cup_lcs *L = NULL;
  char msg[CUP_ERRMSG_LEN];
  if (paper_lcs(&L, cas, msg)) die("%s", msg);
  cup_input *u = paper_input(cas);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.n = n;
  o.scheme = scheme;
  o.proj.method = method;
  o.output = out;
  o.output_samples = 1001;
  cup_integrator *I = NULL;
  if (cup_integrator_create(&I, L, u, &o, msg)) die("%s", msg);
  double x0[3] = {0, 0, 0};
  double t0 = now_seconds();
  cup_integrator_run(I, x0, NULL, NULL, info);
  double dt = now_seconds() - t0;
  cup_integrator_free(&I);
  cup_input_free(&u);
  cup_lcs_free(&L);
  return dt;
}

static void bench_integrate(int argc, char **argv) {
  long n = 1000000;
  int reps = 5;
  for (int a = 0; a < argc; a++) {
    if (!strcmp(argv[a], "--n") && a + 1 < argc) n = atol(argv[++a]);
    else if (!strcmp(argv[a], "--reps") && a + 1 < argc) reps = atoi(argv[++a]);
    else die("integrate: unknown argument %s", argv[a]);
  }
  double *t = malloc(sizeof(double) * (size_t)reps);
  fprintf(stderr, "%-5s %-11s %-9s %10s %12s %8s\n", "case", "scheme", "projector", "steps/s", "ns/step", "status");
  for (int cas = 1; cas <= 2; cas++)
    for (int scheme = 0; scheme <= CUP_SCHEME_THETA; scheme++)
      for (int method = 0; method < 4; method++) {
        if (scheme == CUP_SCHEME_THETA && method != CUP_PROJ_AUTO) continue;   /* its own LCP solver */
        cup_run_info info;
        for (int r = 0; r < reps; r++) t[r] = run_circuit(cas, n, scheme, method, CUP_OUTPUT_NONE, &info);
        double med = median(t, reps);
        fprintf(stderr, "%-5d %-11s %-9s %10.3g %12.1f %8s\n", cas, cup_scheme_name(scheme),
                cup_proj_method_name(method), n / med, med / n * 1e9, cup_status_name(info.status));
        printf("{\"bench\": \"integrate\", \"case\": %d, \"scheme\": \"%s\", \"projector\": \"%s\", "
               "\"n\": %ld, \"reps\": %d, \"median_s\": %.6g, \"steps_per_s\": %.6g, "
               "\"ns_per_step\": %.4g, \"status\": \"%s\", \"projected\": %ld, \"skipped\": %ld, "
               "\"dual_iterations\": %lld, \"max_eps_cert\": %.3e, \"max_eta_cert\": %.3e}\n",
               cas, cup_scheme_name(scheme), cup_proj_method_name(method), n, reps, med, n / med,
               med / n * 1e9, cup_status_name(info.status), info.projected, info.skipped,
               info.dual_iterations, info.max_eps_cert, info.max_eta_cert);
        fflush(stdout);
      }
  free(t);
}

/* ---- run time against error on the paper's circuit (for bench-vs-siconos) ---- */

typedef struct { const double *ref; long n, stride; double err; } circ_err;

static int circ_sink(long k, double t, const double *x, void *vp) {
  (void)t;
  circ_err *c = vp;
  long j = c->n >= 1000 ? k / c->stride : k * (1000 / c->n);
  for (int i = 0; i < 3; i++) c->err = fmax(c->err, fabs(x[i] - c->ref[3 * j + i]));
  return 0;
}

static double *load_reference(const char *path) {
  FILE *f = fopen(path, "r");
  if (!f) die("cannot open %s", path);
  double *ref = malloc(sizeof(double) * 3 * 1001);
  char line[512];
  if (!fgets(line, sizeof line, f)) die("empty reference %s", path);
  for (int j = 0; j <= 1000; j++) {
    double t;
    if (!fgets(line, sizeof line, f) ||
        sscanf(line, "%lf,%lf,%lf,%lf", &t, &ref[3 * j], &ref[3 * j + 1], &ref[3 * j + 2]) != 4)
      die("bad reference line in %s", path);
  }
  fclose(f);
  return ref;
}

/* Every scheme x projector (theta: 1/2 and 1) at each n: median wall time of
 * cup_integrator_run alone (the sink sees 1001 samples) and the max-norm
 * error against the reference limit at t = j/1000. n must divide 1000 or be
 * a multiple of it. */
static void bench_circuit(int argc, char **argv) {
  const char *refdir = NULL;
  long ns[32];
  int nn = 0, reps = 3;
  for (int a = 0; a < argc; a++) {
    if (!strcmp(argv[a], "--ref-dir") && a + 1 < argc) refdir = argv[++a];
    else if (!strcmp(argv[a], "--reps") && a + 1 < argc) reps = atoi(argv[++a]);
    else if (!strcmp(argv[a], "--n") && a + 1 < argc && nn < 32) ns[nn++] = atol(argv[++a]);
    else die("circuit: unknown argument %s", argv[a]);
  }
  if (!refdir) die("%s", "circuit: --ref-dir DIR (with ref_case1_limit_richardson.csv) is required");
  if (!nn) { for (long n = 100; n <= 10000000; n *= 10) ns[nn++] = n; }
  struct { int scheme, method; double theta; const char *name; } cfg[] = {
    {CUP_SCHEME_EXPLICIT, CUP_PROJ_AUTO, 0, "explicit/auto"},
    {CUP_SCHEME_EXPLICIT, CUP_PROJ_PG, 0, "explicit/pg"},
    {CUP_SCHEME_EXPLICIT, CUP_PROJ_FISTA, 0, "explicit/fista"},
    {CUP_SCHEME_IMPLICIT, CUP_PROJ_AUTO, 0, "implicit/auto"},
    {CUP_SCHEME_EXPONENTIAL, CUP_PROJ_AUTO, 0, "exponential/auto"},
    {CUP_SCHEME_THETA, CUP_PROJ_AUTO, 0.5, "theta0.5"},
    {CUP_SCHEME_THETA, CUP_PROJ_AUTO, 1.0, "theta1"},
  };
  double *t = malloc(sizeof(double) * (size_t)reps);
  for (int cas = 1; cas <= 2; cas++) {
    char path[1024];
    snprintf(path, sizeof path, "%s/ref_case%d_limit_richardson.csv", refdir, cas);
    double *ref = load_reference(path);
    cup_lcs *L = NULL;
    char msg[CUP_ERRMSG_LEN];
    if (paper_lcs(&L, cas, msg)) die("%s", msg);
    cup_input *u = paper_input(cas);
    for (size_t q = 0; q < sizeof cfg / sizeof cfg[0]; q++)
      for (int k = 0; k < nn; k++) {
        long n = ns[k];
        if (n < 1 || !(n % 1000 == 0 || 1000 % n == 0)) die("%s", "circuit: each n must divide 1000 or be a multiple of it");
        cup_integrator_options o;
        cup_integrator_options_default(&o);          /* the paper's tolerances */
        o.n = n;
        o.scheme = cfg[q].scheme;
        o.theta = cfg[q].theta;
        o.proj.method = cfg[q].method;
        o.output = CUP_OUTPUT_EVERY;
        o.output_every = n >= 1000 ? n / 1000 : 1;
        cup_integrator *I = NULL;
        if (cup_integrator_create(&I, L, u, &o, msg)) die("%s", msg);
        circ_err ce = {ref, n, n >= 1000 ? n / 1000 : 1, 0};
        cup_run_info info;
        double x0[3] = {0, 0, 0};
        for (int r = 0; r < reps; r++) {
          ce.err = 0;
          double a = now_seconds();
          cup_integrator_run(I, x0, circ_sink, &ce, &info);
          t[r] = now_seconds() - a;
        }
        double med = median(t, reps);
        fprintf(stderr, "case %d %-17s n %9ld: %10.4g s %8.1f ns/step error %.4e %s\n", cas, cfg[q].name,
                n, med, med / n * 1e9, ce.err, cup_status_name(info.status));
        printf("{\"bench\": \"circuit\", \"tool\": \"catchup\", \"case\": %d, \"config\": \"%s\", "
               "\"n\": %ld, \"reps\": %d, \"median_s\": %.6g, \"ns_per_step\": %.4g, \"err_max\": %.6e, "
               "\"status\": \"%s\", \"max_eps_cert\": %.3e, \"max_eta_cert\": %.3e}\n",
               cas, cfg[q].name, n, reps, med, med / n * 1e9, ce.err, cup_status_name(info.status),
               info.max_eps_cert, info.max_eta_cert);
        fflush(stdout);
        cup_integrator_free(&I);
      }
    cup_input_free(&u);
    cup_lcs_free(&L);
    free(ref);
  }
  free(t);
}

/* The adaptive scheme on the paper's circuit at each tol: median wall time
 * of cup_integrator_run (its dense output at t = j/1000 goes to the sink),
 * the max-norm error against ref_case{1,2}_adaptive.csv (tol 1e-13: the
 * Richardson limits' 1e-10 is too coarse here) and against the Richardson
 * limit (an independent method; on case 2, where the scheme is exact and
 * the first reference is this very computation, that is the figure), and
 * the run's own estimate. */
typedef struct { const double *ref, *rich; double err, err_rich; } ad_err;

static int adaptive_sink(long k, double t, const double *x, void *vp) {
  (void)k;
  ad_err *c = vp;
  long j = lround(t * 1000);
  for (int i = 0; i < 3; i++) {
    c->err = fmax(c->err, fabs(x[i] - c->ref[3 * j + i]));
    c->err_rich = fmax(c->err_rich, fabs(x[i] - c->rich[3 * j + i]));
  }
  return 0;
}

static void bench_adaptive(int argc, char **argv) {
  const char *refdir = NULL;
  double tols[32];
  int nt = 0, reps = 5;
  for (int a = 0; a < argc; a++) {
    if (!strcmp(argv[a], "--ref-dir") && a + 1 < argc) refdir = argv[++a];
    else if (!strcmp(argv[a], "--reps") && a + 1 < argc) reps = atoi(argv[++a]);
    else if (!strcmp(argv[a], "--tol") && a + 1 < argc && nt < 32) tols[nt++] = atof(argv[++a]);
    else die("adaptive: unknown argument %s", argv[a]);
  }
  if (!refdir) die("%s", "adaptive: --ref-dir DIR (with ref_case1_adaptive.csv) is required");
  if (reps < 1) die("%s", "adaptive: --reps must be >= 1");
  if (!nt) for (double tol = 1e-3; tol >= 1e-10 * 0.99; tol *= 0.1) tols[nt++] = tol;
  double *t = malloc(sizeof(double) * (size_t)reps);
  for (int cas = 1; cas <= 2; cas++) {
    char path[1024], msg[CUP_ERRMSG_LEN];
    snprintf(path, sizeof path, "%s/ref_case%d_adaptive.csv", refdir, cas);
    double *ref = load_reference(path);
    snprintf(path, sizeof path, "%s/ref_case%d_limit_richardson.csv", refdir, cas);
    double *rich = load_reference(path);
    cup_lcs *L = NULL;
    if (paper_lcs(&L, cas, msg)) die("%s", msg);
    cup_input *u = paper_input(cas);
    for (int k = 0; k < nt; k++) {
      cup_integrator_options o;
      cup_integrator_options_default(&o);
      o.scheme = CUP_SCHEME_ADAPTIVE;
      o.tol_abs = o.tol_rel = tols[k];
      o.output = CUP_OUTPUT_SAMPLES;
      o.output_samples = 1001;
      cup_integrator *I = NULL;
      if (cup_integrator_create(&I, L, u, &o, msg)) die("%s", msg);
      ad_err ce = {ref, rich, 0, 0};
      cup_run_info info;
      double x0[3] = {0, 0, 0};
      for (int r = 0; r < reps; r++) {
        ce.err = ce.err_rich = 0;
        double a = now_seconds();
        cup_integrator_run(I, x0, adaptive_sink, &ce, &info);
        t[r] = now_seconds() - a;
      }
      double med = median(t, reps);
      fprintf(stderr, "case %d adaptive tol %8.0e: %10.4g s, %5ld steps, %3ld events, error %.4e, estimate %.4e %s\n",
              cas, tols[k], med, info.step, info.events, ce.err, info.err_est, cup_status_name(info.status));
      printf("{\"bench\": \"adaptive\", \"tool\": \"catchup\", \"case\": %d, \"config\": \"adaptive\", "
             "\"tol\": %.3g, \"n\": %ld, \"reps\": %d, \"median_s\": %.6g, \"err_max\": %.6e, "
             "\"err_richardson\": %.6e, \"err_est\": %.6e, \"events\": %ld, \"status\": \"%s\"}\n",
             cas, tols[k], info.step, reps, med, ce.err, ce.err_rich, info.err_est, info.events,
             cup_status_name(info.status));
      fflush(stdout);
      cup_integrator_free(&I);
    }
    cup_input_free(&u);
    cup_lcs_free(&L);
    free(ref);
    free(rich);
  }
  free(t);
}

/* Peak resident memory of a run with decimated output, each n in a fresh
 * process so that the high-water marks do not mix. */
static void bench_memory(int argc, char **argv) {
  long ns[16];
  int k = 0;
  for (int a = 0; a < argc; a++) {
    if (!strcmp(argv[a], "--n") && a + 1 < argc && k < 16) ns[k++] = atol(argv[++a]);
    else die("memory: unknown argument %s", argv[a]);
  }
  if (!k) { ns[0] = 100000; ns[1] = 1000000; ns[2] = 10000000; ns[3] = 100000000; k = 4; }
  fprintf(stderr, "%12s %10s %12s\n", "n", "seconds", "peak RSS kB");
  for (int q = 0; q < k; q++) {
    int fd[2];
    if (pipe(fd)) die("%s", "pipe failed");
    pid_t pid = fork();
    if (pid == 0) {
      close(fd[0]);
      cup_run_info info;
      double dt = run_circuit(1, ns[q], CUP_SCHEME_EXPLICIT, CUP_PROJ_AUTO, CUP_OUTPUT_SAMPLES, &info);
      struct rusage ru;
      getrusage(RUSAGE_SELF, &ru);
      char buf[128];
      int len = snprintf(buf, sizeof buf, "%.6g %ld %d\n", dt, ru.ru_maxrss, info.status);
      if (write(fd[1], buf, (size_t)len) != len) _exit(1);
      _exit(0);
    }
    close(fd[1]);
    char buf[128] = {0};
    ssize_t got = read(fd[0], buf, sizeof buf - 1);
    close(fd[0]);
    int wst;
    waitpid(pid, &wst, 0);
    double dt = 0;
    long rss = 0;
    int st = 0;
    if (got <= 0 || sscanf(buf, "%lf %ld %d", &dt, &rss, &st) != 3) die("%s", "memory: child failed");
    fprintf(stderr, "%12ld %10.2f %12ld\n", ns[q], dt, rss);
    printf("{\"bench\": \"memory\", \"case\": 1, \"n\": %ld, \"output_samples\": 1001, "
           "\"seconds\": %.4g, \"peak_rss_kb\": %ld, \"status\": \"%s\"}\n", ns[q], dt, rss,
           cup_status_name(st));
    fflush(stdout);
  }
}

int main(int argc, char **argv) {
  if (argc < 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
    fprintf(stderr, "usage: catchup-bench projector DIR... [--reps R] [--methods auto,pg,fista] [--eps-rel E] [--eta-rel E]\n"
                    "       catchup-bench integrate [--n N] [--reps R]\n"
                    "       catchup-bench memory [--n N]...\n"
                    "       catchup-bench circuit --ref-dir DIR [--n N]... [--reps R]\n"
                    "       catchup-bench adaptive --ref-dir DIR [--tol T]... [--reps R]\n");
    return argc < 2 ? 2 : 0;
  }
  if (!strcmp(argv[1], "projector")) bench_projector(argc - 2, argv + 2);
  else if (!strcmp(argv[1], "integrate")) bench_integrate(argc - 2, argv + 2);
  else if (!strcmp(argv[1], "memory")) bench_memory(argc - 2, argv + 2);
  else if (!strcmp(argv[1], "circuit")) bench_circuit(argc - 2, argv + 2);
  else if (!strcmp(argv[1], "adaptive")) bench_adaptive(argc - 2, argv + 2);
  else die("unknown benchmark '%s' (projector, integrate, memory, circuit, adaptive)", argv[1]);
  return 0;
}

/* catchup-sweep — a parameter study over (eps_n, eta_n, n) x schemes x
 * projectors x scene variants into one restartable HDF5 file
 * (docs/sweep-format.md).
 *
 *   mpirun -n K catchup-sweep SWEEP.yaml -o RESULTS.h5 [--resume] [--quiet]
 *                             [--task-time-limit S]
 *
 * Rank 0 is the manager and the only rank that touches the file; ranks
 * 1..K-1 are workers. With one rank, rank 0 computes too. Jobs (the
 * variants' references first, then the tasks by decreasing estimated cost)
 * go out in batches sized by cost, two batches ahead per worker so that a
 * worker never waits for the manager; the manager polls with MPI_Iprobe and
 * a short sleep so that it does not take a core from the workers, and writes
 * each result as it arrives. How jobs travel between ranks is sweep_mpi.c,
 * the bookkeeping of rank 0, MPI aside, sweep_manager.c; this file is the
 * program: its command line, the sweep shared by every rank, the checks
 * before the results file is touched, and the report.
 *
 * Exit status: 0 when every task ran (failed tasks are results: their status
 * is in /summary, and one stderr line counts them); 1 when the sweep file,
 * the scenes or the results file fail (one stderr line naming the file, the
 * key and the problem); 2 usage; 128 + signal after SIGINT/SIGTERM on rank 0,
 * which stops dispatching, writes what has arrived and closes the file (a
 * second signal ends at once; the file keeps everything flushed before).
 *
 * Test hooks (environment): CATCHUP_SWEEP_INJECT_FAIL=3,7,11 makes those
 * tasks fail half-way through with CUP_ERR_CALLBACK; CATCHUP_SWEEP_DONE_LIST=
 * FILE lists task ids (one per line) that must not be computed again: a rank
 * asked to compute one aborts the whole job with a message. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <mpi.h>
#include "catchup.h"
#include "catchup/h5run.h"
#include "sweep_manager.h"
#include "sweep_mpi.h"
#include "run_plan.h"
#include "stop_signal.h"
#include "heap_pad.h"
#include "mpi_singleton.h"
#include "git_revision.h"

enum { EXIT_RUN = 1, EXIT_USAGE = 2 };

static const char usage_text[] =
  "usage: mpirun -n K catchup-sweep SWEEP.yaml -o RESULTS.h5 [--resume] [--quiet]\n"
  "                                 [--task-time-limit S] [--max-steps N]\n"
  "  -o, --output FILE      results file (HDF5); replaced unless --resume\n"
  "  --resume               continue FILE: run only the tasks not done yet\n"
  "  --quiet                no progress line and no summary line\n"
  "  --log-progress         a full progress line every 10 s instead of one rewritten in\n"
  "                         place (the default only when neither stdout nor stderr is a\n"
  "                         terminal; mpirun gives stdout a pseudo-terminal even when\n"
  "                         its output goes to a file)\n"
  "  --task-time-limit S    stop a task after S seconds (status CUP_ERR_TIME_LIMIT)\n"
  "  --max-steps N          refuse a sweep whose fixed-step task or reference takes more than N\n"
  "                         steps (default: each scene's max_steps, 1000000000 unless it says)\n"
  "  -h, --help             this text;  --version  the library versions\n";

typedef struct {
  const char *sweep, *out;
  int resume, quiet, log_progress;
  double time_limit;
  long max_steps;            /* --max-steps, or 0: each variant's scene says */
} args_t;

static int rank, nranks;

/* ---- command line (every rank parses; rank 0 reports) ---- */

static int usage_error(const char *fmt, const char *what) {
  if (rank == 0) {
    fputs("catchup-sweep: ", stderr);
    fprintf(stderr, fmt, what);
    fputs(" (catchup-sweep --help for usage)\n", stderr);
  }
  return EXIT_USAGE;
}

static int parse_args(args_t *a, int argc, char **argv) {
  memset(a, 0, sizeof *a);
  for (int i = 1; i < argc; i++) {
    const char *arg = argv[i], *eq = strchr(arg, '='), *v = NULL;
    size_t flen = strncmp(arg, "--", 2) == 0 && eq ? (size_t)(eq - arg) : strlen(arg);
    if (!strcmp(arg, "-h") || !strcmp(arg, "--help")) {
      if (rank == 0) fputs(usage_text, stdout);
      return 0;
    }
    if (!strcmp(arg, "--version")) {
      char deps[256], h5[64];
      cup_dependency_versions(deps, sizeof deps);
      cup_h5_version(h5, sizeof h5);
      if (rank == 0) printf("catchup-sweep %s (%s; %s; git %s)\n", cup_version(), deps, h5, CATCHUP_GIT_REVISION);
      return 0;
    }
    int is_out = (flen == 2 && !strncmp(arg, "-o", 2)) || (flen == 8 && !strncmp(arg, "--output", 8));
    int is_tl = flen == 17 && !strncmp(arg, "--task-time-limit", 17);
    int is_ms = flen == 11 && !strncmp(arg, "--max-steps", 11);
    if (is_out || is_tl || is_ms) {
      if (eq && arg[1] == '-') v = eq + 1;
      else if (i + 1 < argc) v = argv[++i];
      else return usage_error("%s needs a value", is_out ? "-o" : is_tl ? "--task-time-limit" : "--max-steps");
      if (is_out) { a->out = v; continue; }
      char *end;
      errno = 0;
      if (is_ms) {
        double n = strtod(v, &end);
        if (errno || end == v || *end || !(n >= 1) || n > 9.2e18 || n != floor(n))
          return usage_error("--max-steps '%s': not a positive integer", v);
        a->max_steps = (long)n;
        continue;
      }
      a->time_limit = strtod(v, &end);
      if (errno || end == v || *end || !(a->time_limit > 0) || !isfinite(a->time_limit))
        return usage_error("--task-time-limit '%s': not a positive number of seconds", v);
    } else if (!strcmp(arg, "--resume")) {
      a->resume = 1;
    } else if (!strcmp(arg, "--quiet") || !strcmp(arg, "-q")) {
      a->quiet = 1;
    } else if (!strcmp(arg, "--log-progress")) {
      a->log_progress = 1;
    } else if (arg[0] == '-' && arg[1]) {
      return usage_error("unknown option '%s'", arg);
    } else if (a->sweep) {
      return usage_error("one sweep file per run: '%s' is a second one", arg);
    } else {
      a->sweep = arg;
    }
  }
  if (!a->sweep) return usage_error("%s", "no sweep file given");
  if (!a->out) return usage_error("%s", "no output file given: -o RESULTS.h5");
  return -1;
}

/* ---- the sweep on every rank ---- */

/* Rank 0 reads the sweep file and the scenes; every rank then builds the
 * same sweep from the same texts (so that only rank 0 needs the files):
 * per variant its scene text, or for a lazy one nothing (its entry's scene
 * file's text and its overrides give it, in its job). Rank 0 makes the
 * lazy variants' texts, for the results file, itself (sw_lazy_texts). */
static int share_sweep(const args_t *a, sw_sweep **sp, char *err) {
  int st = CUP_OK;
  if (rank == 0) {
    st = sw_load(sp, a->sweep, err);
    if (!st) st = sw_resolve_scenes(*sp, err);
  }
  bcast_status(&st);
  if (st) return st;
  if (nranks == 1) return CUP_OK;
  /* the sweep file's text, then per variant its scene text and its file text ("" for none), in one message */
  sw_sweep *s = *sp;
  long lens[3] = {0, 0, 0};
  if (rank == 0) {
    lens[0] = (long)strlen(s->text);
    lens[1] = s->n_variants;
    for (int k = 0; k < s->n_variants; k++) {
      const sw_variant *v = &s->var[k];
      lens[2] += (long)((v->scene_text ? strlen(v->scene_text) : 0) + (v->file_text ? strlen(v->file_text) : 0) + 2);
    }
    if (lens[2] > INT_MAX) {
      say("%s: the variants' scenes take %ld bytes, more than one MPI message holds", a->sweep, lens[2]);
      singleton_abort(1);
    }
  }
  MPI_Bcast(lens, 3, MPI_LONG, 0, MPI_COMM_WORLD);
  char *text = rank == 0 ? s->text : malloc((size_t)lens[0] + 1);
  char *all = malloc((size_t)lens[2] + 1);
  char **scenes = calloc((size_t)lens[1] + 1, sizeof *scenes);
  if (!text || !all || !scenes) singleton_abort(1);
  MPI_Bcast(text, (int)lens[0] + 1, MPI_CHAR, 0, MPI_COMM_WORLD);
  if (rank == 0)
    for (long k = 0, at = 0; k < lens[1]; k++) {
      const sw_variant *v = &s->var[k];
      at += sprintf(all + at, "%s", v->scene_text ? v->scene_text : "") + 1;
      at += sprintf(all + at, "%s", v->file_text ? v->file_text : "") + 1;
    }
  MPI_Bcast(all, (int)lens[2], MPI_CHAR, 0, MPI_COMM_WORLD);
  if (rank) st = sw_parse(sp, text, (size_t)lens[0], a->sweep, err);
  for (long k = 0, at = 0; rank && !st && k < lens[1]; k++) {
    scenes[k] = all[at] ? all + at : NULL;
    at += (long)strlen(all + at) + 1;
    if (all[at] && !((*sp)->var[k].file_text = strdup(all + at))) st = CUP_ERR_NOMEM;
    at += (long)strlen(all + at) + 1;
  }
  if (rank && !st) st = sw_resolve_texts(*sp, scenes, err);
  free(all);
  free(scenes);
  if (rank) free(text);
  if (rank && st) {                     /* the same texts gave rank 0 no error */
    say("rank %d: %s", rank, err);
    singleton_abort(1);
  }
  return st;
}

/* ---- the run on rank 0 ---- */

/* Every fixed-step task and reference against the step limit, before the
 * results file is touched (run_plan.h): the first one beyond it, named. */
static int check_steps(const args_t *a, const sw_sweep *s, char *err) {
  for (long id = 0; id < s->n_tasks; id++) {
    sw_task t;
    if (sw_task_get(s, id, &t)) continue;
    const sw_variant *v = &s->var[t.variant];
    const cup_scene *sc = sw_variant_settings(s, t.variant);   /* a lazy variant's are its entry's first's */
    cup_integrator_options o = *cup_scene_options(sc);
    o.n = t.n;
    o.scheme = (cup_scheme)t.scheme;
    run_plan p;
    run_plan_make(&p, &o, s->dim, 0, 0);
    long limit = a->max_steps ? a->max_steps : cup_scene_max_steps(sc);
    char from[SW_ERR_LEN / 4], msg[SW_ERR_LEN / 2];  /* a variant's name, whole */
    snprintf(from, sizeof from, "task %ld, variant %s%s", id, v->name, s->len[SW_AXIS_N] ? ": grid.n" : "");
    if (run_plan_too_long(&p, &o, limit, from, "grid: {scheme: [adaptive], tol: [1e-6]}", msg, sizeof msg)) {
      snprintf(err, SW_ERR_LEN, "%s: %s", s->path, msg);
      return CUP_ERR_ARG;
    }
  }
  for (int k = 0; k < s->n_variants; k++) {
    const sw_variant *v = &s->var[k];
    long limit = a->max_steps ? a->max_steps : cup_scene_max_steps(sw_variant_settings(s, k));
    if (!s->crowd && s->ref_method == SW_REF_RICHARDSON && 2.0 * (double)v->n_ref > (double)limit) {
      snprintf(err, SW_ERR_LEN, "%s: variant %s's reference takes n = %ld and %ld steps (reference.n, or 4 x its "
               "largest n) beyond the limit of %ld (--max-steps, the scene key max_steps): take fewer steps, or "
               "reference.method: adaptive", s->path, v->name, v->n_ref, 2 * v->n_ref, limit);
      return CUP_ERR_ARG;
    }
  }
  return CUP_OK;
}

static int open_results(const args_t *a, const sw_sweep *s, int argc, char **argv, sw_file **f, char *err) {
  if (a->resume) return sw_file_open(f, a->out, s, err);
  char deps[512], h5[64];
  int n = cup_dependency_versions(deps, sizeof deps);
  cup_h5_version(h5, sizeof h5);
  if (n >= 0 && (size_t)n < sizeof deps) snprintf(deps + n, sizeof deps - (size_t)n, "; %s", h5);
  size_t len = 1, w = 0;                       /* the command line, whole */
  for (int i = 0; i < argc; i++) len += strlen(argv[i]) + 1;
  char *cmd = malloc(len);
  if (!cmd) return snprintf(err, SW_ERR_LEN, "%s: out of memory", a->out), CUP_ERR_NOMEM;
  cmd[0] = '\0';
  for (int i = 0; i < argc; i++) w += (size_t)snprintf(cmd + w, len - w, "%s%s", i ? " " : "", argv[i]);
  sw_provenance p = {cup_version(), deps, CATCHUP_GIT_REVISION, cmd};
  int st = sw_file_create(f, a->out, s, &p, err);
  free(cmd);
  return st;
}

/* The results file, with the lazy variants' texts that /variants holds
 * (and --resume compares): before the run on one rank or on a resume,
 * after the workers' first batches went out otherwise, so that they do not
 * wait for it (sweep_manager.h, open_file). */
typedef struct { const args_t *a; sw_sweep *s; int argc; char **argv; } opener;

static int open_late(void *ctx, sw_file **f, char *err) {
  const opener *o = ctx;
  int st = sw_lazy_texts(o->s, err);
  return st ? st : open_results(o->a, o->s, o->argc, o->argv, f, err);
}

/* The two summary lines. The jobs as they are: a steady-state sweep
 * dispatches no reference (its rows are written done at creation,
 * setup_queue), a crowd's compute nothing (cost 0), and neither has a
 * reference to check a tolerance against (the tasks' error is NaN). The
 * mean counts the jobs that compute (rate_jobs, sweep_manager.h); rank 0's
 * time, every job it ran. */
static void say_summary(const args_t *a, const sw_sweep *s, const manager_t *m, const sw_tally *t, double wall,
                        double cpu_manager) {
  int workers = nranks > 1 ? nranks - 1 : 1;
  char share[64] = "", tol[80] = "no tolerance check (no reference)", of[40] = "", jobs[96];
  if (nranks > 1) snprintf(share, sizeof share, ", rank 0 %.1f%%", 100 * cpu_manager / m->rank_cpu);
  if (t->adaptive) snprintf(of, sizeof of, " (of %ld adaptive)", t->adaptive);
  if (!s->steady && !s->crowd) snprintf(tol, sizeof tol, "%ld tolerance missed%s", t->tol_missed, of);
  if (s->steady) snprintf(jobs, sizeof jobs, "%ld tasks (steady states; no reference jobs)", s->n_tasks);
  else snprintf(jobs, sizeof jobs, "%ld tasks + %d references%s", s->n_tasks, s->n_variants,
                s->crowd ? " (a crowd's: they compute nothing)" : "");
  say("%s -> %s: %ld tasks: %ld ok, %ld failed, %ld not certified, %s, %ld other warnings (/summary's "
      "status_name and error say which)", a->sweep, a->out, s->n_tasks, t->ok, t->failed, t->not_certified, tol,
      t->warned);
  if (!m->jobs_done) {               /* a resume with nothing left: no averages over nothing */
    say("%s -> %s: %s = %ld jobs: %ld done before, none run now", a->sweep, a->out, jobs, m->jobs_total,
        m->jobs_skipped);
    return;
  }
  say("%s -> %s: %s = %ld jobs: %ld done before, %ld run now (%ld failed), %.3g s on %d rank%s; "
      "%s of %.3g us on average; parallel efficiency %.2f (job wall time / (workers x wall); "
      "%.2f by job CPU time); jobs took %.1f%% of the CPU time of all ranks%s; manager %.1f us per job run",
      a->sweep, a->out, jobs, m->jobs_total, m->jobs_skipped, m->jobs_done, m->failures, wall, nranks,
      nranks > 1 ? "s" : "", s->crowd ? "tasks" : "jobs",
      m->rate_jobs ? 1e6 * m->rate_work / (double)m->rate_jobs : 0.0, m->work_sum / (workers * wall),
      m->cpu_sum / (workers * wall), 100 * m->cpu_sum / m->rank_cpu, share, 1e6 * m->busy / (double)m->jobs_done);
}

static int run_manager(const args_t *a, const sw_sweep *s, sw_file *f, opener *late, const hooks_t *hooks) {
  manager_t m;
  memset(&m, 0, sizeof m);
  m.quiet = a->quiet;
  m.log_progress = a->log_progress;
  m.workers = nranks > 1 ? nranks - 1 : 1;
  m.s = s;
  m.f = f;
  m.open_file = f ? NULL : open_late;
  m.open_ctx = late;
  m.count = s->samples * s->dim;
  m.one = sizeof(sw_result) + sizeof(double) * (size_t)sw_traj_len(s);
  m.max_batch = (int)fmax(1, fmin(MAX_BATCH, (double)(MAX_MESSAGE - sizeof(msg_head)) / (double)m.one));
  if (setup_queue(&m)) { free_manager(&m); say("%s: out of memory", a->out); return EXIT_RUN; }
  m.t_start = m.last_flush = now_seconds();
  m.last_progress = 0;
  double cpu0 = clock_seconds(CLOCK_PROCESS_CPUTIME_ID);
  int lost = dispatch(&m, hooks, a->time_limit);
  double wall = now_seconds() - m.t_start, cpu_manager = clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu0;
  m.rank_cpu += cpu_manager;
  progress(&m, 1);
  sw_tally tally;
  memset(&tally, 0, sizeof tally);
  char err[SW_ERR_LEN] = "";
  sw_file *ff = m.f;
  int cst = CUP_OK;
  if (ff) {
    sw_file_tally(ff, &tally);
    cst = sw_file_close(&ff, err);
  }
  if (!m.io_status && cst) { m.io_status = cst; snprintf(m.io_msg, sizeof m.io_msg, "%s", err); }
  long done = m.jobs_done + m.jobs_skipped;
  int rc = 0;
  if (m.io_status) {
    say("%s", m.io_msg);
    rc = EXIT_RUN;
  } else if (stop_signal) {
    say("stopped by %s: %ld of %ld jobs are done and saved in %s; continue with --resume",
        stop_signal == SIGINT ? "SIGINT" : "SIGTERM", done, m.jobs_total, a->out);
    rc = 128 + stop_signal;
  } else if (done < m.jobs_total) {
    say("%s: %ld of %ld jobs did not run (the workers stopped); continue with --resume", a->out,
        m.jobs_total - done, m.jobs_total);
    rc = EXIT_RUN;
  }
  if (!rc && !a->quiet) say_summary(a, s, &m, &tally, wall, cpu_manager);
  free_manager(&m);
  if (lost) {                  /* a worker did not answer the stop: end the job */
    fflush(stderr);
    singleton_abort(rc ? rc : EXIT_RUN);
  }
  return rc;
}

int main(int argc, char **argv) {
  heap_pad();                                   /* see heap_pad.h */
  singleton_prepare();                          /* see mpi_singleton.h */
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &nranks);
  mpi_ranks(rank, nranks);
  args_t a;
  int rc = parse_args(&a, argc, argv);
  if (rc >= 0) {
    MPI_Finalize();
    singleton_cleanup();
    return rc;
  }
  install_handlers();
  hooks_t hooks;
  hooks_read(&hooks);
  sw_sweep *s = NULL;
  sw_file *f = NULL;
  char err[SW_ERR_LEN] = "";
  int st = share_sweep(&a, &s, err);
  if (!st && rank == 0) st = check_steps(&a, s, err);
  if (!st && rank == 0 && file_list_check_output(&s->files, a.out, err))
    st = CUP_ERR_ARG;                           /* an input is never an output */
  opener late = {&a, s, argc, argv};
  int early = nranks > 1 && !a.resume;          /* the workers start before the results file is made */
  if (!st && rank == 0 && !early) st = open_late(&late, &f, err);
  bcast_status(&st);
  if (st) {
    if (rank == 0) say("%s", err);
    rc = EXIT_RUN;
  } else if (rank == 0) {
    rc = run_manager(&a, s, f, &late, &hooks);
  } else {
    rc = worker(s, &hooks, a.time_limit);
  }
  sw_free(&s);
  hooks_free(&hooks);
  MPI_Finalize();
  singleton_cleanup();
  return rc;
}

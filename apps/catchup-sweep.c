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
 * each result as it arrives (the bookkeeping, MPI aside, is in
 * sweep_manager.c).
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
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <mpi.h>
#include "catchup.h"
#include "catchup/h5run.h"
#include "sweep_run.h"
#include "sweep_manager.h"
#include "run_plan.h"
#include "stop_signal.h"
#include "git_revision.h"

enum { EXIT_RUN = 1, EXIT_USAGE = 2 };
enum { TAG_WORK = 1, TAG_RESULT = 2, TAG_STOP = 3, TAG_BYE = 4 };
enum { AHEAD = 2 };
#define MAX_MESSAGE (1u << 20)   /* bytes of a batch's answer, unless one job needs more: it
                                  * arrives in ~10 rounds of fragments (see manager_mpi) */
#define STOP_GRACE_SECONDS 10.0
#define SHORT_POLL_US 50           /* the sleep between tests while an answer is in transit, */
#define SHORT_POLL_MAX_US 500      /* growing by 1/4 up to this on rank 0 (a descheduled worker) */

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

/* ---- small helpers ---- */

static void sleep_us(long us) {
  struct timespec ts = {us / 1000000, (us % 1000000) * 1000};
  nanosleep(&ts, NULL);
}

/* Wait for a request without spinning (a blocking wait would take a
 * core): test, then sleep, 50 us at first, up to max_us. */
static void wait_request(MPI_Request *req, long max_us) {
  int done = 0;
  for (long us = 50; *req != MPI_REQUEST_NULL; us = us < max_us ? 2 * us : max_us) {
    MPI_Test(req, &done, MPI_STATUS_IGNORE);
    if (done) break;
    sleep_us(us < max_us ? us : max_us);
  }
}

/* Rank 0's status to every rank, waited for without spinning: the others
 * wait while rank 0 reads the scenes or creates the results file, and must
 * not take the cores it works on. */
static void bcast_status(int *st) {
  MPI_Request req;
  MPI_Ibcast(st, 1, MPI_INT, 0, MPI_COMM_WORLD, &req);
  wait_request(&req, 1000);
}

__attribute__((format(printf, 1, 2)))
static void say(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fputs("catchup-sweep: ", stderr);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
}

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

/* ---- test hooks ---- */

typedef struct { long *id; long len; } idset;

static int cmp_long(const void *a, const void *b) {
  long x = *(const long *)a, y = *(const long *)b;
  return (x > y) - (x < y);
}

static int idset_has(const idset *s, long id) {
  return s->len && bsearch(&id, s->id, (size_t)s->len, sizeof(long), cmp_long);
}

/* Numbers separated by commas, spaces or newlines. */
static void idset_parse(idset *s, const char *text) {
  s->id = NULL;
  s->len = 0;
  if (!text) return;
  long cap = 0;
  for (const char *p = text; *p;) {
    char *end;
    long v = strtol(p, &end, 10);
    if (end == p) { p++; continue; }
    if (s->len == cap) {
      long *n = realloc(s->id, sizeof(long) * (size_t)(cap = 2 * cap + 16));
      if (!n) break;
      s->id = n;
    }
    s->id[s->len++] = v;
    p = end;
  }
  if (s->len) qsort(s->id, (size_t)s->len, sizeof(long), cmp_long);
}

static char *slurp(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  size_t cap = 4096, n = 0, got;
  char *buf = malloc(cap + 1);
  while (buf && (got = fread(buf + n, 1, cap - n, f)) > 0)
    if ((n += got) == cap) {
      char *nb = realloc(buf, (cap *= 2) + 1);
      if (!nb) free(buf);
      buf = nb;
    }
  fclose(f);
  if (buf) buf[n] = '\0';
  return buf;
}

typedef struct {
  idset inject, done_before;
  const char *done_file;
} hooks_t;

static void hooks_read(hooks_t *h) {
  idset_parse(&h->inject, getenv("CATCHUP_SWEEP_INJECT_FAIL"));
  h->done_file = getenv("CATCHUP_SWEEP_DONE_LIST");
  char *text = h->done_file && h->done_file[0] ? slurp(h->done_file) : NULL;
  if (h->done_file && h->done_file[0] && !text) {
    say("rank %d: CATCHUP_SWEEP_DONE_LIST=%s: cannot read: %s", rank, h->done_file, strerror(errno));
    MPI_Abort(MPI_COMM_WORLD, 3);
  }
  idset_parse(&h->done_before, text);
  free(text);
}

/* ---- the sweep on every rank ---- */

/* Rank 0 reads the sweep file and the scenes; every rank then builds the
 * same sweep from the same texts (so that only rank 0 needs the files). */
static int share_sweep(const args_t *a, cup_sweep **sp, char *err) {
  int st = CUP_OK;
  if (rank == 0) {
    st = sw_load(sp, a->sweep, err);
    if (!st) st = sw_resolve_files(*sp, err);
  }
  bcast_status(&st);
  if (st) return st;
  if (nranks == 1) return CUP_OK;
  cup_sweep *s = *sp;
  long lens[2] = {rank == 0 ? (long)strlen(s->text) : 0, rank == 0 ? s->n_variants : 0};
  MPI_Bcast(lens, 2, MPI_LONG, 0, MPI_COMM_WORLD);
  char *text = rank == 0 ? s->text : malloc((size_t)lens[0] + 1);
  char **scenes = rank == 0 ? NULL : calloc((size_t)lens[1], sizeof *scenes);
  if (!text || (rank && !scenes)) MPI_Abort(MPI_COMM_WORLD, 1);
  MPI_Bcast(text, (int)lens[0] + 1, MPI_CHAR, 0, MPI_COMM_WORLD);
  if (rank) st = sw_parse(sp, text, (size_t)lens[0], a->sweep, err);
  for (long k = 0; k < lens[1]; k++) {
    long len = rank == 0 ? (long)strlen(s->var[k].scene_text) : 0;
    MPI_Bcast(&len, 1, MPI_LONG, 0, MPI_COMM_WORLD);
    char *t = rank == 0 ? s->var[k].scene_text : malloc((size_t)len + 1);
    if (!t) MPI_Abort(MPI_COMM_WORLD, 1);
    MPI_Bcast(t, (int)len + 1, MPI_CHAR, 0, MPI_COMM_WORLD);
    if (rank) scenes[k] = t;
  }
  if (rank && !st) st = sw_resolve_texts(*sp, scenes, err);
  if (rank) {
    for (long k = 0; k < lens[1]; k++) free(scenes[k]);
    free(scenes);
    free(text);
  }
  if (rank && st) {                     /* the same texts gave rank 0 no error */
    say("rank %d: %s", rank, err);
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  return st;
}

/* ---- computing a job (workers, or rank 0 alone) ---- */

typedef struct {             /* a worker's answer to a batch, and its send */
  char *buf;
  size_t cap;
  MPI_Request req;
} outbuf;

typedef struct {
  const cup_sweep *s;
  const hooks_t *hooks;
  double time_limit;
  size_t one;                /* bytes of a job's answer: sw_result + trajectory */
  outbuf *out;               /* AHEAD answers (workers; NULL on rank 0 alone) */
  int sending;               /* one of them is in transit */
  long steps;                /* for polling a stop message */
  int stop_msg;              /* the manager said stop */
} computer;

/* Test the answers in transit, which moves them along; whether one still is. */
static int move_sends(outbuf *out) {
  int pending = 0;
  for (int b = 0; out && b < AHEAD; b++)
    if (out[b].req != MPI_REQUEST_NULL) {
      int done = 0;
      MPI_Test(&out[b].req, &done, MPI_STATUS_IGNORE);
      pending |= !done;
    }
  return pending;
}

/* Every 1024 steps (~0.1 ms on the paper's circuit): has the manager asked
 * to stop? Every 128 while an answer is in transit, move it along: it moves
 * only when this rank calls MPI, a round of calls on both sides per few
 * fragments, and rank 0 tests for it every 50 us meanwhile. (Workers only.) */
static int poll_stop(long k, double t, const cup_proj_info *pi, void *ctx) {
  (void)k; (void)t; (void)pi;
  computer *c = ctx;
  long step = ++c->steps;
  if (c->sending && !(step & 127)) c->sending = move_sends(c->out);
  if (step & 1023) return 0;
  int flag = 0;
  MPI_Iprobe(0, TAG_STOP, MPI_COMM_WORLD, &flag, MPI_STATUS_IGNORE);
  if (flag) c->stop_msg = 1;
  return flag || stop_signal;
}

static void compute(computer *c, long job, sw_result *r, double *traj) {
  const cup_sweep *s = c->s;
  long task = job - s->n_variants;
  if (task >= 0 && idset_has(&c->hooks->done_before, task)) {
    say("rank %d: asked to compute task %ld, which CATCHUP_SWEEP_DONE_LIST (%s) says was done before "
        "the resume: a finished task would be redone", rank, task, c->hooks->done_file);
    MPI_Abort(MPI_COMM_WORLD, 3);
  }
  _Static_assert(sizeof(sig_atomic_t) == sizeof(int), "sig_atomic_t is an int here");
  sw_run_opts o = {(const volatile int *)&stop_signal, nranks > 1 ? poll_stop : NULL, c, c->time_limit,
                   task >= 0 && idset_has(&c->hooks->inject, task)};
  sw_run_job(s, job, &o, r, traj);
}

/* ---- worker ---- */

/* Jobs ids[0..count) into buf as the manager takes them (msg_head, then
 * each result followed by its trajectory). Returns the count, short of
 * `count` when a stop interrupted a job (that is not a result). Between
 * jobs, the answers in transit move along. The CPU time is the computing
 * thread's (a system call of about a microsecond: read per batch, not per
 * job); MPI keeps threads of its own. */
static int64_t run_batch(computer *c, const long *ids, int count, char *buf) {
  msg_head h = {0, clock_seconds(CLOCK_THREAD_CPUTIME_ID)};
  for (int j = 0; j < count && !c->stop_msg && !stop_signal; j++) {
    sw_result *r = (sw_result *)(void *)(buf + sizeof h + c->one * (size_t)h.count);
    compute(c, ids[j], r, (double *)(void *)(r + 1));
    if (r->status == CUP_ERR_INTERRUPTED && (c->stop_msg || stop_signal)) break;
    h.count++;
    if (c->sending) c->sending = move_sends(c->out);
  }
  h.cpu = clock_seconds(CLOCK_THREAD_CPUTIME_ID) - h.cpu;
  memcpy(buf, &h, sizeof h);
  return h.count;
}

/* Probe for the next message from rank 0 with a sleep in between: a short
 * one while an answer is still in transit (it moves only when this rank
 * calls MPI too, and rank 0 cannot send more work before it has it). */
static void wait_message(MPI_Status *status, outbuf *out) {
  int flag = 0;
  for (long us = 50;; us = us < 1000 ? 2 * us : us) {
    MPI_Iprobe(0, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, status);
    if (flag) return;
    sleep_us(move_sends(out) ? SHORT_POLL_US : us);
  }
}

static int worker(const cup_sweep *s, const hooks_t *hooks, double time_limit) {
  size_t one = sizeof(sw_result) + sizeof(double) * (size_t)sw_traj_len(s);
  outbuf out[AHEAD];
  for (int b = 0; b < AHEAD; b++) out[b] = (outbuf){NULL, 0, MPI_REQUEST_NULL};
  computer c = {s, hooks, time_limit, one, out, 0, 0, 0};
  long ids[MAX_BATCH];
  int next = 0;
  double cpu0 = clock_seconds(CLOCK_PROCESS_CPUTIME_ID);
  for (;;) {
    MPI_Status st;
    wait_message(&st, out);
    if (st.MPI_TAG != TAG_WORK) {
      MPI_Recv(NULL, 0, MPI_BYTE, 0, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      break;                                   /* TAG_STOP */
    }
    int count = 0;
    MPI_Get_count(&st, MPI_LONG, &count);
    MPI_Recv(ids, MAX_BATCH, MPI_LONG, 0, TAG_WORK, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    outbuf *ob = &out[next];
    next = (next + 1) % AHEAD;
    wait_request(&ob->req, SHORT_POLL_US);
    size_t need = sizeof(msg_head) + one * (size_t)count;
    if (need > ob->cap) {
      free(ob->buf);
      if (!(ob->buf = malloc(ob->cap = need))) MPI_Abort(MPI_COMM_WORLD, 1);
    }
    int64_t n = run_batch(&c, ids, count, ob->buf);
    if (c.stop_msg || stop_signal) break;      /* a partial batch is not sent: the manager re-queues it */
    MPI_Isend(ob->buf, (int)(sizeof(msg_head) + one * (size_t)n), MPI_BYTE, 0, TAG_RESULT, MPI_COMM_WORLD,
              &ob->req);
    c.sending = 1;
  }
  for (int b = 0; b < AHEAD; b++) wait_request(&out[b].req, SHORT_POLL_US);
  double cpu = clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu0;   /* for the manager's account of the CPU time */
  MPI_Send(&cpu, 1, MPI_DOUBLE, 0, TAG_BYE, MPI_COMM_WORLD);
  /* After a stop, take what rank 0 sent until its STOP (for half a second at
   * most: it sends none to a worker that left first), so that its sends of
   * batches ahead complete: one of many ids is a rendezvous, which stays
   * open until the receive. */
  for (double t0 = now_seconds(); (c.stop_msg || stop_signal) && now_seconds() - t0 < 0.5;) {
    int flag = 0;
    MPI_Status st;
    MPI_Iprobe(0, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
    if (!flag) {
      sleep_us(200);
      continue;
    }
    MPI_Recv(ids, MAX_BATCH, MPI_LONG, 0, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (st.MPI_TAG == TAG_STOP) break;
  }
  for (int b = 0; b < AHEAD; b++) free(out[b].buf);
  return 0;
}

/* ---- manager: MPI ---- */

typedef struct {
  long ids[AHEAD][MAX_BATCH];
  int len[AHEAD];
  double cost[AHEAD];        /* the batches' estimated costs */
  MPI_Request sent[AHEAD];   /* the sends of the batches */
  int head, out;             /* FIFO of batches sent and not answered */
  int alive;
} wstate;

/* Keep every live worker AHEAD batches ahead while there is work; returns
 * the number of batches sent and not answered. The sends do not block: a
 * batch of more than a few hundred jobs goes by rendezvous, which a blocking
 * send would spin through until the busy worker asks for it. A slot is
 * reused once its batch was answered, so its send is complete by then. */
static int feed(manager_t *m, wstate *ws, int workers) {
  int outstanding = 0;
  for (int b = 0; b < AHEAD; b++)
    for (int dest = 1; dest <= workers; dest++) {
      wstate *w = &ws[dest];
      if (!w->alive || w->out > b || m->qhead >= m->qlen) continue;
      int slot = (w->head + w->out) % AHEAD;
      wait_request(&w->sent[slot], 1000);
      int n = next_batch(m, workers, w->ids[slot]);
      w->len[slot] = n;
      w->cost[slot] = 0;
      for (int j = 0; j < n; j++) w->cost[slot] += m->cost[w->ids[slot][j]];
      w->out++;
      MPI_Isend(w->ids[slot], n, MPI_LONG, dest, TAG_WORK, MPI_COMM_WORLD, &w->sent[slot]);
    }
  for (int dest = 1; dest <= workers; dest++) outstanding += ws[dest].out;
  return outstanding;
}

/* A worker left without being asked (its own signal): its batches go back
 * to the front of the queue. */
static void requeue(manager_t *m, wstate *w) {
  for (int b = w->out - 1; b >= 0; b--) {
    int slot = (w->head + b) % AHEAD;
    for (int j = w->len[slot] - 1; j >= 0; j--) {
      m->queue[--m->qhead] = w->ids[slot][j];
      m->cost_queued += m->cost[w->ids[slot][j]];
    }
  }
  w->out = 0;
}

/* Wait, within the grace time, for the sends of the batches to complete: a
 * worker takes its batches before it leaves (after a stop, until the STOP).
 * Should one not, its send is let go; returns whether one was. */
static int finish_sends(wstate *ws) {
  int abandoned = 0;
  double t0 = now_seconds();
  for (int w = 1; w < nranks; w++)
    for (int b = 0; b < AHEAD; b++) {
      int done = 0;
      while (!done && ws[w].sent[b] != MPI_REQUEST_NULL && now_seconds() - t0 < STOP_GRACE_SECONDS) {
        MPI_Test(&ws[w].sent[b], &done, MPI_STATUS_IGNORE);
        if (!done) sleep_us(1000);
      }
      if (ws[w].sent[b] != MPI_REQUEST_NULL) {
        MPI_Request_free(&ws[w].sent[b]);
        abandoned = 1;
      }
    }
  return abandoned;
}

/* The longest rank 0 sleeps between probes while no answer is coming in:
 * a quarter of the shortest batch under way, by the seconds per cost unit
 * seen so far (a worker that finishes a batch has the next one, so its
 * answer may wait that long), 1 ms before any job is done, within 1-20 ms.
 * Each wake-up costs ~15 us of CPU time in a virtual machine. */
static long idle_sleep_us(const manager_t *m, const wstate *ws) {
  double shortest = INFINITY;
  for (int w = 1; w < nranks; w++)
    for (int b = 0; b < ws[w].out; b++) shortest = fmin(shortest, ws[w].cost[(ws[w].head + b) % AHEAD]);
  double s = m->cost_done > 0 && isfinite(shortest) ? 0.25 * shortest * m->work_sum / m->cost_done : 1e-3;
  return (long)(1e6 * fmin(20e-3, fmax(1e-3, s)));
}

/* Rank 0 waits for answers without spinning: when a probe shows that a
 * message has come, it posts a receive for it (one per worker at a time),
 * tests the receives under way, and sleeps in between — from 200 us up to
 * idle_sleep_us while none is under way (a blocking receive would spin),
 * SHORT_POLL_US while one is: a large answer flows a few fragments at a
 * time, each round needing MPI calls on both sides, and long sleeps would
 * stretch it until the worker runs out of work. That sleep grows while
 * nothing completes: on a loaded machine the worker may not be running,
 * and each wake-up costs ~15 us of CPU time in a VM. Returns 0 when every
 * worker said goodbye, -1 when some did not within the grace time after a
 * stop. */
static int manager_mpi(manager_t *m) {
  int workers = nranks - 1, live = workers, receiving = 0;
  wstate *ws = calloc((size_t)nranks, sizeof *ws);
  MPI_Request *req = malloc(sizeof *req * (size_t)nranks);
  char **buf = calloc((size_t)nranks, sizeof *buf);
  size_t cap = sizeof(msg_head) + m->one * (size_t)m->max_batch;
  if (!ws || !req || !buf) { io_fail(m, CUP_ERR_NOMEM); free(ws); free(req); free(buf); return 0; }
  for (int w = 0; w < nranks; w++) {
    req[w] = MPI_REQUEST_NULL;
    if (w == 0) continue;
    ws[w].alive = 1;
    for (int b = 0; b < AHEAD; b++) ws[w].sent[b] = MPI_REQUEST_NULL;
    if (!(buf[w] = malloc(cap))) MPI_Abort(MPI_COMM_WORLD, 1);
  }
  int outstanding = feed(m, ws, workers), stopping = 0;
  long us = 200, fast = SHORT_POLL_US;     /* the sleeps: none, or some receive under way */
  double stop_t0 = 0;
  while (live > 0) {
    if (!stopping && (stop_signal || m->io_status || outstanding == 0)) {
      stopping = 1;                             /* done, or stop: every worker gets STOP */
      stop_t0 = now_seconds();
      for (int w = 1; w < nranks; w++)
        if (ws[w].alive) MPI_Send(NULL, 0, MPI_BYTE, w, TAG_STOP, MPI_COMM_WORLD);
    }
    if (stopping && now_seconds() - stop_t0 > STOP_GRACE_SECONDS) break;
    int idx = MPI_UNDEFINED, flag = 0, size = 0;
    MPI_Status st;
    MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
    for (int w = 1; flag && w < nranks; w++) {   /* a message has come: from whom (one receive each) */
      int here = 0;
      if (!ws[w].alive || req[w] != MPI_REQUEST_NULL) continue;
      MPI_Iprobe(w, MPI_ANY_TAG, MPI_COMM_WORLD, &here, &st);
      if (!here) continue;
      MPI_Irecv(buf[w], (int)cap, MPI_BYTE, w, st.MPI_TAG, MPI_COMM_WORLD, &req[w]);
      receiving++;
    }
    flag = 0;
    if (receiving) MPI_Testany(nranks, req, &idx, &flag, &st);
    if (!flag || idx == MPI_UNDEFINED) {
      progress(m, 0);
      maybe_flush(m, 0);
      if (receiving) {
        sleep_us(fast);
        fast = fast < SHORT_POLL_MAX_US ? fast * 5 / 4 : fast;
      } else {
        sleep_us(us);
        us = (long)fmin(1.5 * (double)us, (double)idle_sleep_us(m, ws));
      }
      continue;
    }
    us = 200;
    fast = SHORT_POLL_US;
    receiving--;
    double t0 = now_seconds();
    int src = idx;
    wstate *w = &ws[src];
    MPI_Get_count(&st, MPI_BYTE, &size);
    if (st.MPI_TAG == TAG_BYE) {
      double cpu = 0;
      if (size == (int)sizeof cpu) memcpy(&cpu, buf[src], sizeof cpu);
      m->rank_cpu += cpu;
      requeue(m, w);
      w->alive = 0;
      live--;
    } else {
      take_message(m, buf[src], (size_t)size);
      w->head = (w->head + 1) % AHEAD;
      w->out--;
    }
    if (!stopping) outstanding = feed(m, ws, workers);
    maybe_flush(m, 0);
    m->busy += now_seconds() - t0;
    progress(m, 0);
  }
  if (live > 0) return -1;   /* MPI_Abort follows: a receive under way keeps its buffer */
  int abandoned = finish_sends(ws);
  for (int w = 1; w < nranks; w++) free(buf[w]);
  free(buf);
  free(req);
  if (!abandoned) free(ws);                   /* else MPI may still read a batch's ids */
  return 0;
}

/* ---- manager: alone ---- */

static void manager_alone(manager_t *m, const hooks_t *hooks, double time_limit) {
  computer c = {m->s, hooks, time_limit, m->one, NULL, 0, 0, 0};
  char *buf = malloc(sizeof(msg_head) + m->one * (size_t)m->max_batch);
  long ids[MAX_BATCH];
  if (!buf) { io_fail(m, CUP_ERR_NOMEM); return; }
  while (m->qhead < m->qlen && !stop_signal && !m->io_status) {
    int count = next_batch(m, 1, ids);
    int64_t n = run_batch(&c, ids, count, buf);
    double t0 = now_seconds();
    take_message(m, buf, sizeof(msg_head) + m->one * (size_t)n);
    maybe_flush(m, 0);
    m->busy += now_seconds() - t0;
    progress(m, 0);
    if (n < count) break;                      /* stopped by a signal */
  }
  free(buf);
}

/* ---- the run on rank 0 ---- */

/* Every fixed-step task and reference against the step limit, before the
 * results file is touched (run_plan.h): the first one beyond it, named. */
static int check_steps(const args_t *a, const cup_sweep *s, char *err) {
  for (long id = 0; id < s->n_tasks; id++) {
    sw_task t;
    if (sw_task_get(s, id, &t)) continue;
    const sw_variant *v = &s->var[t.variant];
    cup_integrator_options o = *cup_scene_options(v->scene);
    o.n = t.n;
    o.scheme = (cup_scheme)t.scheme;
    run_plan p;
    run_plan_make(&p, &o, s->dim, 0, 0);
    long limit = a->max_steps ? a->max_steps : cup_scene_max_steps(v->scene);
    char from[SW_ERR_LEN / 4], msg[SW_ERR_LEN / 2];  /* a variant's name, whole */
    snprintf(from, sizeof from, "task %ld, variant %s%s", id, v->name, s->len[SW_AXIS_N] ? ": grid.n" : "");
    if (run_plan_too_long(&p, &o, limit, from, "grid: {scheme: [adaptive], tol: [1e-6]}", msg, sizeof msg)) {
      snprintf(err, SW_ERR_LEN, "%s: %s", s->path, msg);
      return CUP_ERR_ARG;
    }
  }
  for (int k = 0; k < s->n_variants; k++) {
    const sw_variant *v = &s->var[k];
    long limit = a->max_steps ? a->max_steps : cup_scene_max_steps(v->scene);
    if (!s->crowd && s->ref_method == SW_REF_RICHARDSON && 2.0 * (double)v->n_ref > (double)limit) {
      snprintf(err, SW_ERR_LEN, "%s: variant %s's reference takes n = %ld and %ld steps (reference.n, or 4 x its "
               "largest n) beyond the limit of %ld (--max-steps, the scene key max_steps): take fewer steps, or "
               "reference.method: adaptive", s->path, v->name, v->n_ref, 2 * v->n_ref, limit);
      return CUP_ERR_ARG;
    }
  }
  return CUP_OK;
}

static int open_results(const args_t *a, const cup_sweep *s, int argc, char **argv, sw_file **f, char *err) {
  if (cup_file_list_check_output(&s->files, a->out, err)) return CUP_ERR_ARG;   /* an input is never an output */
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

static int run_manager(const args_t *a, const cup_sweep *s, sw_file *f, const hooks_t *hooks) {
  manager_t m;
  memset(&m, 0, sizeof m);
  m.quiet = a->quiet;
  m.log_progress = a->log_progress;
  m.workers = nranks > 1 ? nranks - 1 : 1;
  m.s = s;
  m.f = f;
  m.count = s->samples * s->dim;
  m.one = sizeof(sw_result) + sizeof(double) * (size_t)sw_traj_len(s);
  m.max_batch = (int)fmax(1, fmin(MAX_BATCH, (double)(MAX_MESSAGE - sizeof(msg_head)) / (double)m.one));
  if (setup_queue(&m)) { free_manager(&m); say("%s: out of memory", a->out); return EXIT_RUN; }
  m.t_start = m.last_flush = now_seconds();
  m.last_progress = 0;
  double cpu0 = clock_seconds(CLOCK_PROCESS_CPUTIME_ID);
  /* the errors of tasks written before their reference, in an earlier run */
  for (int k = 0; k < s->n_variants; k++) fill_errors(&m, k);
  int lost = 0;
  if (nranks == 1) manager_alone(&m, hooks, a->time_limit);
  else lost = manager_mpi(&m);
  double wall = now_seconds() - m.t_start, cpu_manager = clock_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu0;
  m.rank_cpu += cpu_manager;
  progress(&m, 1);
  sw_tally tally;
  sw_file_tally(f, &tally);
  char err[SW_ERR_LEN] = "";
  sw_file *ff = f;
  int cst = sw_file_close(&ff, err);
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
  if (!rc && !a->quiet) {
    int workers = nranks > 1 ? nranks - 1 : 1;
    char share[64] = "";
    if (nranks > 1) snprintf(share, sizeof share, ", rank 0 %.1f%%", 100 * cpu_manager / m.rank_cpu);
    double per_job = m.jobs_done ? 1e6 / (double)m.jobs_done : 0.0;
    char adaptive[48] = "";
    if (tally.adaptive) snprintf(adaptive, sizeof adaptive, " (of %ld adaptive)", tally.adaptive);
    say("%s -> %s: %ld tasks: %ld ok, %ld failed, %ld not certified, %ld tolerance missed%s, %ld other "
        "warnings (/summary's status_name and error say which)", a->sweep, a->out, s->n_tasks, tally.ok,
        tally.failed, tally.not_certified, tally.tol_missed, adaptive, tally.warned);
    say("%s -> %s: %ld tasks + %d references (%ld done before), %ld failed, %.3g s on %d rank%s; "
        "jobs of %.3g us on average; parallel efficiency %.2f (job wall time / (workers x wall); "
        "%.2f by job CPU time); jobs took %.1f%% of the CPU time of all ranks%s; manager %.1f us per job",
        a->sweep, a->out, s->n_tasks, s->n_variants, m.jobs_skipped, m.failures, wall, nranks,
        nranks > 1 ? "s" : "", m.work_sum * per_job, m.work_sum / (workers * wall), m.cpu_sum / (workers * wall),
        100 * m.cpu_sum / m.rank_cpu, share, m.busy * per_job);
  }
  free_manager(&m);
  if (lost) {                  /* a worker did not answer the stop: end the job */
    fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, rc ? rc : EXIT_RUN);
  }
  return rc;
}

int main(int argc, char **argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &nranks);
  args_t a;
  int rc = parse_args(&a, argc, argv);
  if (rc >= 0) { MPI_Finalize(); return rc; }
  install_handlers();
  hooks_t hooks;
  hooks_read(&hooks);
  cup_sweep *s = NULL;
  sw_file *f = NULL;
  char err[SW_ERR_LEN] = "";
  int st = share_sweep(&a, &s, err);
  if (!st && rank == 0) st = check_steps(&a, s, err);
  if (!st && rank == 0) st = open_results(&a, s, argc, argv, &f, err);
  bcast_status(&st);
  if (st) {
    if (rank == 0) say("%s", err);
    rc = EXIT_RUN;
  } else if (rank == 0) {
    rc = run_manager(&a, s, f, &hooks);
  } else {
    rc = worker(s, &hooks, a.time_limit);
  }
  sw_free(&s);
  free(hooks.inject.id);
  free(hooks.done_before.id);
  MPI_Finalize();
  return rc;
}

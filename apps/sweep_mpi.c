/* sweep_mpi — see sweep_mpi.h. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <mpi.h>
#include "catchup.h"
#include "mpi_singleton.h"
#include "stop_signal.h"
#include "sweep_mpi.h"
#include "sweep_run.h"

enum { TAG_WORK = 1, TAG_RESULT = 2, TAG_STOP = 3, TAG_BYE = 4 };
enum { AHEAD = 2 };
#define STOP_GRACE_SECONDS 10.0
#define SHORT_POLL_US 50           /* the sleep between tests while an answer is in transit, */
#define SHORT_POLL_MAX_US 500      /* growing by 1/4 up to this on rank 0 (a descheduled worker) */

static int rank, nranks;

void mpi_ranks(int r, int n) {
  rank = r;
  nranks = n;
}

/* ---- waiting without spinning ---- */

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

void bcast_status(int *st) {
  MPI_Request req;
  MPI_Ibcast(st, 1, MPI_INT, 0, MPI_COMM_WORLD, &req);
  wait_request(&req, 1000);
}

/* ---- test hooks ---- */

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

void hooks_read(hooks_t *h) {
  idset_parse(&h->inject, getenv("CATCHUP_SWEEP_INJECT_FAIL"));
  h->done_file = getenv("CATCHUP_SWEEP_DONE_LIST");
  char *text = h->done_file && h->done_file[0] ? slurp(h->done_file) : NULL;
  if (h->done_file && h->done_file[0] && !text) {
    say("rank %d: CATCHUP_SWEEP_DONE_LIST=%s: cannot read: %s", rank, h->done_file, strerror(errno));
    singleton_abort(3);
  }
  idset_parse(&h->done_before, text);
  free(text);
}

void hooks_free(hooks_t *h) {
  free(h->inject.id);
  free(h->done_before.id);
}

/* ---- computing a job (workers, or rank 0 alone) ---- */

typedef struct {             /* a worker's answer to a batch, and its send */
  char *buf;
  size_t cap;
  MPI_Request req;
} outbuf;

typedef struct {
  const sw_sweep *s;
  const hooks_t *hooks;
  double time_limit;
  size_t one;                /* bytes of a job's answer: sw_result + trajectory */
  outbuf *out;               /* AHEAD answers (workers; NULL on rank 0 alone) */
  int sending;               /* one of them is in transit */
  long steps;                /* for polling a stop message */
  int stop_msg;              /* the manager said stop */
  sw_scene_slot slot;        /* the last lazy variant loaded */
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
  const sw_sweep *s = c->s;
  long task = job - s->n_variants;
  if (task >= 0 && idset_has(&c->hooks->done_before, task)) {
    say("rank %d: asked to compute task %ld, which CATCHUP_SWEEP_DONE_LIST (%s) says was done before "
        "the resume: a finished task would be redone", rank, task, c->hooks->done_file);
    singleton_abort(3);
  }
  _Static_assert(sizeof(sig_atomic_t) == sizeof(int), "sig_atomic_t is an int here");
  sw_run_opts o = {(const volatile int *)&stop_signal, nranks > 1 ? poll_stop : NULL, c, c->time_limit,
                   task >= 0 && idset_has(&c->hooks->inject, task), &c->slot};
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

int worker(const sw_sweep *s, const hooks_t *hooks, double time_limit) {
  size_t one = sizeof(sw_result) + sizeof(double) * (size_t)sw_traj_len(s);
  outbuf out[AHEAD];
  for (int b = 0; b < AHEAD; b++) out[b] = (outbuf){NULL, 0, MPI_REQUEST_NULL};
  computer c = {s, hooks, time_limit, one, out, 0, 0, 0, {-1, NULL}};
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
      if (!(ob->buf = malloc(ob->cap = need))) singleton_abort(1);
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
  sw_scene_slot_free(&c.slot);
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
    if (!(buf[w] = malloc(cap))) singleton_abort(1);
  }
  int outstanding = feed(m, ws, workers), stopping = 0;
  manager_file_ready(m);                   /* made while the workers start on their batches */
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
  computer c = {m->s, hooks, time_limit, m->one, NULL, 0, 0, 0, {-1, NULL}};
  char *buf = malloc(sizeof(msg_head) + m->one * (size_t)m->max_batch);
  long ids[MAX_BATCH];
  if (!buf) { io_fail(m, CUP_ERR_NOMEM); return; }
  manager_file_ready(m);
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
  sw_scene_slot_free(&c.slot);
  free(buf);
}

int dispatch(manager_t *m, const hooks_t *hooks, double time_limit) {
  if (nranks > 1) return manager_mpi(m);
  manager_alone(m, hooks, time_limit);
  return 0;
}

/* sweep_manager — see sweep_manager.h. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "sweep_manager.h"

/* Batches hold about this much work (cost units ~ steps, ~0.1 us each on
 * the paper's circuit: ~20 ms): with two batches ahead, longer than the
 * manager's reply latency (it sleeps at most a quarter of a batch, and an
 * answer of ~1 MB takes about ten rounds of its short polls to arrive);
 * each message costs rank 0 a few wake-ups, ~15 us of CPU time each in a
 * VM (measured: 50,000 units gave rank 0 5 % of the CPU time on tasks of
 * ~100 us, this 3.5 %). */
#define BATCH_COST 200000.0
#define FLUSH_SECONDS 1.0
#define PROGRESS_SECONDS 0.25
#define PROGRESS_LOG_SECONDS 10.0

void say(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fputs("catchup-sweep: ", stderr);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
}

void io_fail(manager_t *m, int st) {
  if (st && !m->io_status) {
    m->io_status = st;
    snprintf(m->io_msg, sizeof m->io_msg, "%s", sw_file_errmsg(m->f)[0] ? sw_file_errmsg(m->f) : "out of memory");
  }
}

void manager_file_ready(manager_t *m) {
  if (!m->f && m->open_file) {
    int st = m->open_file(m->open_ctx, &m->f, m->io_msg);
    if (st) { m->io_status = st; return; }
  }
  for (int k = 0; k < m->s->n_variants; k++) fill_errors(m, k);
}

static double task_error(manager_t *m, int status, const double *traj, const double *xref) {
  if (status < 0 || !xref) return NAN;
  return sw_max_error(traj, xref, m->count);
}

static int by_task(const void *a, const void *b) {
  long x = ((const sw_task_out *)a)->task, y = ((const sw_task_out *)b)->task;
  return (x > y) - (x < y);
}

/* The reference of variant k is known: fill the errors of its tasks that
 * were written without one (read back from /runs/x), then write the tasks
 * held in memory (no /runs/x to read back from), all at once. */
void fill_errors(manager_t *m, int k) {
  const double *xref = sw_file_reference(m->f, k);
  io_fail(m, sw_file_fill_errors(m->f, k));
  long n = 0;
  for (held *h = m->held[k]; h; h = h->next) n++;
  sw_task_out *t = n ? malloc(sizeof *t * (size_t)n) : NULL;
  if (n && !t) io_fail(m, CUP_ERR_NOMEM);
  n = 0;
  for (held *h = m->held[k]; h && t; h = h->next)
    t[n++] = (sw_task_out){h->task, &h->r, h->traj, task_error(m, h->r.status, h->traj, xref)};
  if (n) qsort(t, (size_t)n, sizeof *t, by_task);
  if (n && !m->io_status) io_fail(m, sw_file_write_tasks(m->f, t, n));
  free(t);
  for (held *h = m->held[k], *nx; h; h = nx) {
    nx = h->next;
    free(h->traj);
    free(h);
  }
  m->held[k] = NULL;
}

static void count_result(manager_t *m, const sw_result *r) {
  m->jobs_done++;
  m->cost_done += m->cost[r->job];
  m->cost_left -= m->cost[r->job];
  m->work_sum += r->wall;
  m->last_done = now_seconds();
  if (m->cost[r->job] > 0) {
    m->rate_jobs++;
    m->rate_work += r->wall;
    m->rate_cost += m->cost[r->job];
  }
  if (r->status < 0) m->failures++;
  if (r->status == CUP_WARN_NOT_CERTIFIED) m->not_certified++;
}

static void take_reference(manager_t *m, const sw_result *r, const double *traj) {
  count_result(m, r);
  if (m->io_status) return;
  io_fail(m, sw_file_write_reference(m->f, (int)r->job, r, traj));
  if (!m->io_status) fill_errors(m, (int)r->job);
}

/* A task's result: into t (to be written) with its error when its reference
 * is known or trajectories are stored; otherwise held until it is. Returns
 * whether t was filled. */
static int take_task(manager_t *m, const sw_result *r, const double *traj, sw_task_out *t) {
  const sw_sweep *s = m->s;
  count_result(m, r);
  if (m->io_status) return 0;
  long task = r->job - s->n_variants;
  int k = (int)(task / s->per_variant);
  const double *xref = sw_file_reference(m->f, k);
  if (!xref && s->out_samples == 0 && !sw_file_reference_done(m->f, k)) {
    held *h = malloc(sizeof *h);
    size_t bytes = sizeof(double) * (size_t)sw_traj_len(s);     /* the states and the signals */
    double *copy = malloc(bytes);
    if (!h || !copy) { free(h); free(copy); io_fail(m, CUP_ERR_NOMEM); return 0; }
    memcpy(copy, traj, bytes);
    *h = (held){task, *r, copy, m->held[k]};
    m->held[k] = h;
    return 0;
  }
  *t = (sw_task_out){task, r, traj, task_error(m, r->status, traj, xref)};
  return 1;
}

static void fmt_seconds(char *buf, size_t n, double s) {
  if (!(s >= 0) || !isfinite(s)) snprintf(buf, n, "?");
  else if (s < 120) snprintf(buf, n, "%.0f s", s);
  else if (s < 7200) snprintf(buf, n, "%.0f min %02.0f s", floor(s / 60), fmod(s, 60));
  else snprintf(buf, n, "%.0f h %02.0f min", floor(s / 3600), fmod(floor(s / 60), 60));
}

/* The progress line: rewritten in place every PROGRESS_SECONDS on a
 * terminal; on a log (--log-progress, or neither stdout nor stderr a
 * terminal: mpirun makes stderr a pipe even interactively, so stdout
 * decides, but it also makes stdout a pseudo-terminal when its own output
 * is a file) one full line every PROGRESS_LOG_SECONDS. */
void progress(manager_t *m, int final) {
  static int live = -1;
  if (live < 0)
    live = !m->log_progress && (isatty(STDOUT_FILENO) || isatty(STDERR_FILENO));
  double now = now_seconds();
  double every = live ? PROGRESS_SECONDS : PROGRESS_LOG_SECONDS;
  if (m->quiet || !m->f || (!final && now - m->last_progress < every)) return;   /* no file made: no progress */
  m->last_progress = now;
  char el[32], eta[32];
  double elapsed = now - m->t_start;
  fmt_seconds(el, sizeof el, elapsed);
  /* The work left at the seconds per cost unit that the jobs done took on
   * their ranks, spread over the workers; "?" until each worker has done
   * a job on average (one job, or the elapsed time while jobs that cost
   * nothing went first, says little about the rest). */
  double rate = m->rate_jobs >= m->workers && m->rate_cost > 0 ? m->rate_work / m->rate_cost : NAN;
  double left = rate * m->cost_left / m->workers - (now - m->last_done);
  fmt_seconds(eta, sizeof eta, isnan(rate) ? NAN : fmax(0, left));   /* fmax(0, NaN) is 0, not "?" */
  fprintf(stderr, "%scatchup-sweep: %ld/%ld done, %ld failed, %ld not certified, %s elapsed, ETA %s%s",
          live ? "\r" : "", m->jobs_done + m->jobs_skipped, m->jobs_total, m->failures, m->not_certified, el,
          m->cost_left <= 0 ? "0 s" : eta, live ? "   " : "\n");
  if (final && live) fputc('\n', stderr);
  fflush(stderr);
}

void maybe_flush(manager_t *m, int force) {
  double now = now_seconds();
  if (m->io_status || (!force && now - m->last_flush < FLUSH_SECONDS)) return;
  io_fail(m, sw_file_flush(m->f));
  m->last_flush = now;
}

/* One result message: the references first, so that the message's tasks
 * find theirs, then every task in one write. */
void take_message(manager_t *m, const char *buf, size_t size) {
  _Static_assert(sizeof(msg_head) % sizeof(double) == 0 && sizeof(sw_result) % sizeof(double) == 0,
                 "trajectories in a message are aligned");
  const sw_sweep *s = m->s;
  msg_head h = {0, 0};
  int64_t fits = size >= sizeof h ? (int64_t)((size - sizeof h) / m->one) : 0;
  if (size >= sizeof h) memcpy(&h, buf, sizeof h);
  if (h.count < 0 || h.count > fits) h.count = fits;     /* not what a worker sends */
  m->cpu_sum += h.cpu;
  const char *at = buf + sizeof h;
  long w = 0;
  for (int64_t j = 0; j < h.count; j++) {
    const sw_result *r = (const sw_result *)(const void *)(at + m->one * (size_t)j);
    if (r->job < s->n_variants) take_reference(m, r, (const double *)(const void *)(r + 1));
  }
  for (int64_t j = 0; j < h.count; j++) {
    const sw_result *r = (const sw_result *)(const void *)(at + m->one * (size_t)j);
    if (r->job >= s->n_variants) w += take_task(m, r, (const double *)(const void *)(r + 1), &m->out[w]);
  }
  if (w && !m->io_status) io_fail(m, sw_file_write_tasks(m->f, m->out, w));
}

static int cmp_job(const void *a, const void *b) {
  long x = *(const long *)a, y = *(const long *)b;
  return (x > y) - (x < y);
}

/* The next batch: jobs in queue order until the batch holds BATCH_COST of
 * work, and at most 1/(2 x workers) of the work still in the queue, so that
 * the last batches shrink and spread over the workers (guided scheduling:
 * by the queue, not by the work still to finish, which counts the batches
 * out, or a slow worker's batches ahead could be a large tail); sorted, so
 * that its results come back in task order. */
int next_batch(manager_t *m, int workers, long *ids) {
  double target = fmin(BATCH_COST, m->cost_queued / (2.0 * workers)), sum = 0;
  int n = 0;
  while (m->qhead < m->qlen && n < m->max_batch && (n == 0 || sum + m->cost[m->queue[m->qhead]] <= target)) {
    ids[n] = m->queue[m->qhead++];
    sum += m->cost[ids[n++]];
  }
  m->cost_queued -= sum;
  qsort(ids, (size_t)n, sizeof *ids, cmp_job);
  return n;
}

int setup_queue(manager_t *m) {
  const sw_sweep *s = m->s;
  long J = s->n_variants + s->n_tasks;
  long *order = malloc(sizeof(long) * (size_t)J);
  m->queue = malloc(sizeof(long) * (size_t)J);
  m->cost = malloc(sizeof(double) * (size_t)J);
  m->held = calloc((size_t)s->n_variants, sizeof *m->held);
  m->out = malloc(sizeof *m->out * MAX_BATCH);
  if (!order || !m->queue || !m->cost || !m->held || !m->out) { free(order); return CUP_ERR_NOMEM; }
  sw_schedule(s, order);
  m->jobs_total = J;
  for (long j = 0; j < J; j++) {
    long job = order[j];
    if (job < s->n_variants && s->steady) { m->jobs_total--; continue; }   /* no reference: done at creation */
    m->cost[job] = sw_job_cost(s, job);
    int done = m->f && (job < s->n_variants ? sw_file_reference_done(m->f, (int)job)
                                            : sw_file_task_done(m->f, job - s->n_variants));
    if (done) { m->jobs_skipped++; continue; }
    m->queue[m->qlen++] = job;
    m->cost_left += m->cost[job];
    m->cost_queued += m->cost[job];
  }
  free(order);
  return CUP_OK;
}

void free_manager(manager_t *m) {
  for (int k = 0; m->held && k < m->s->n_variants; k++)
    for (held *h = m->held[k], *nx; h; h = nx) { nx = h->next; free(h->traj); free(h); }
  free(m->held);
  free(m->queue);
  free(m->cost);
  free(m->out);
}

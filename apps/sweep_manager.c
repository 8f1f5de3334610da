/* sweep_manager — see sweep_manager.h. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "sweep_manager.h"

/* Batches hold about this much work (cost units ~ steps, ~0.2 us each on
 * the paper's circuit, ~10 ms here): with two batches ahead, much longer
 * than the manager's reply latency (its sleep is at most 1 ms). */
#define BATCH_COST 50000.0
#define FLUSH_SECONDS 1.0
#define PROGRESS_SECONDS 0.25
#define PROGRESS_LOG_SECONDS 10.0

void io_fail(manager_t *m, int st) {
  if (st && !m->io_status) {
    m->io_status = st;
    snprintf(m->io_msg, sizeof m->io_msg, "%s", sw_file_errmsg(m->f)[0] ? sw_file_errmsg(m->f) : "out of memory");
  }
}

static double task_error(manager_t *m, int status, const double *traj, const double *xref) {
  if (status < 0 || !xref) return NAN;
  return sw_max_error(traj, xref, m->count);
}

/* The reference of variant k is known: fill the errors of its tasks that
 * were written without one (read back from /runs/x), then write the tasks
 * held in memory (no /runs/x to read back from). */
void fill_errors(manager_t *m, int k) {
  const cup_sweep *s = m->s;
  const double *xref = sw_file_reference(m->f, k);
  if (xref && s->out_samples > 0)
    for (long t = k * s->per_variant; t < (k + 1) * s->per_variant && !m->io_status; t++) {
      if (!sw_file_task_done(m->f, t) || sw_file_task_status(m->f, t) < 0 || !isnan(sw_file_task_error(m->f, t)))
        continue;
      int st = sw_file_read_traj(m->f, t, m->scratch);
      if (!st) {
        double e = task_error(m, CUP_OK, m->scratch, xref);
        if (!isnan(e)) st = sw_file_set_error(m->f, t, e);
      }
      io_fail(m, st);
    }
  for (held *h = m->held[k], *nx; h; h = nx) {
    nx = h->next;
    if (!m->io_status)
      io_fail(m, sw_file_write_task(m->f, h->task, &h->r, h->traj, task_error(m, h->r.status, h->traj, xref)));
    free(h->traj);
    free(h);
  }
  m->held[k] = NULL;
}

void take_result(manager_t *m, const sw_result *r, const double *traj) {
  const cup_sweep *s = m->s;
  long job = r->job;
  m->jobs_done++;
  m->cost_done += m->cost[job];
  m->cost_left -= m->cost[job];
  m->work_sum += r->wall;
  m->cpu_sum += r->cpu;
  if (r->status < 0) m->failures++;
  if (m->io_status) return;
  if (job < s->n_variants) {
    io_fail(m, sw_file_write_reference(m->f, (int)job, r, traj));
    if (!m->io_status) fill_errors(m, (int)job);
    return;
  }
  long task = job - s->n_variants;
  int k = (int)(task / s->per_variant);
  const double *xref = sw_file_reference(m->f, k);
  if (!xref && s->out_samples == 0 && !sw_file_reference_done(m->f, k)) {
    held *h = malloc(sizeof *h);
    double *copy = malloc(sizeof(double) * (size_t)m->count);
    if (!h || !copy) { free(h); free(copy); io_fail(m, CUP_ERR_NOMEM); return; }
    memcpy(copy, traj, sizeof(double) * (size_t)m->count);
    *h = (held){task, *r, copy, m->held[k]};
    m->held[k] = h;
    return;
  }
  io_fail(m, sw_file_write_task(m->f, task, r, traj, task_error(m, r->status, traj, xref)));
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
  if (m->quiet || (!final && now - m->last_progress < every)) return;
  m->last_progress = now;
  char el[32], eta[32];
  double elapsed = now - m->t_start;
  fmt_seconds(el, sizeof el, elapsed);
  fmt_seconds(eta, sizeof eta, m->cost_done > 0 ? elapsed * m->cost_left / m->cost_done : NAN);
  fprintf(stderr, "%scatchup-sweep: %ld/%ld done, %ld failed, %s elapsed, ETA %s%s",
          live ? "\r" : "", m->jobs_done + m->jobs_skipped, m->jobs_total, m->failures, el,
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

/* Unpack one result message (a count, then results with trajectories). */
void take_message(manager_t *m, const char *buf, size_t size) {
  size_t one = sizeof(sw_result) + sizeof(double) * (size_t)m->count;
  int64_t n = 0;
  if (size >= sizeof n) memcpy(&n, buf, sizeof n);
  for (int64_t j = 0; j < n && sizeof n + one * (size_t)(j + 1) <= size; j++) {
    const char *at = buf + sizeof n + one * (size_t)j;
    sw_result r;
    memcpy(&r, at, sizeof r);
    take_result(m, &r, (const double *)(const void *)(at + sizeof r));
  }
}

/* The next batch: jobs in queue order until the batch holds BATCH_COST of
 * work, fewer near the end so that the last batches spread over the workers. */
int next_batch(manager_t *m, int workers, long *ids) {
  double target = fmin(BATCH_COST, m->cost_left / (2.0 * workers)), sum = 0;
  int n = 0;
  while (m->qhead < m->qlen && n < m->max_batch && (n == 0 || sum + m->cost[m->queue[m->qhead]] <= target)) {
    ids[n] = m->queue[m->qhead++];
    sum += m->cost[ids[n++]];
  }
  return n;
}

int setup_queue(manager_t *m) {
  const cup_sweep *s = m->s;
  long J = s->n_variants + s->n_tasks;
  long *order = malloc(sizeof(long) * (size_t)J);
  m->queue = malloc(sizeof(long) * (size_t)J);
  m->cost = malloc(sizeof(double) * (size_t)J);
  m->held = calloc((size_t)s->n_variants, sizeof *m->held);
  m->scratch = malloc(sizeof(double) * (size_t)m->count);
  if (!order || !m->queue || !m->cost || !m->held || !m->scratch) { free(order); return CUP_ERR_NOMEM; }
  sw_schedule(s, order);
  m->jobs_total = J;
  for (long j = 0; j < J; j++) {
    long job = order[j];
    m->cost[job] = sw_job_cost(s, job);
    int done = job < s->n_variants ? sw_file_reference_done(m->f, (int)job)
                                   : sw_file_task_done(m->f, job - s->n_variants);
    if (done) { m->jobs_skipped++; continue; }
    m->queue[m->qlen++] = job;
    m->cost_left += m->cost[job];
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
  free(m->scratch);
}

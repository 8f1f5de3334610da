/* crowd_log — see crowd_log.h. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "crowd_log.h"
#include "util/clock.h"

enum { COLS = 11 };
static const char *const names[COLS] = {"t", "inside", "rows", "active", "eps_cert", "eta_cert", "gap",
                                        "iterations", "factorizations", "seconds", "added"};
/* CF units and long names of the columns (/steps/<name>); eps bounds a
 * squared distance, eta a distance. */
static const char *const units[COLS] = {"s", "1", "1", "1", "m2", "m", "m", "1", "1", "s", "1"};
static const char *const what[COLS] = {
  "time of the state after the step", "agents inside the room after the step",
  "rows of the step's set (contacts and walls within the margin)", "rows active at the step's answer",
  "certified eps of the step's projection", "certified eta of the step's projection",
  "smallest gap of the state (negative: overlap)", "projector iterations of the step",
  "factorizations of the step", "wall time of the step", "contacts the step's rows missed, added"};

struct crowd_log {
  cup_crowd *c;
  long n;
  double *col[COLS];            /* n + 1 entries each; step 0 is the start */
  double last_clock;
  long last;                    /* the steps written (crowd_log_write), -1 before */
};

crowd_log *crowd_log_create(cup_crowd *c, long n) {
  crowd_log *L = calloc(1, sizeof *L);
  if (!L) return NULL;
  L->c = c;
  L->n = n;
  int fail = 0;
  for (int k = 0; k < COLS; k++) fail |= !(L->col[k] = calloc((size_t)n + 1, sizeof(double)));
  if (fail) { crowd_log_free(&L); return NULL; }
  L->col[1][0] = cup_crowd_agents(c);
  L->last_clock = now_seconds();
  L->last = -1;
  return L;
}

void crowd_log_free(crowd_log **L) {
  if (!L || !*L) return;
  for (int k = 0; k < COLS; k++) free((*L)->col[k]);
  free(*L);
  *L = NULL;
}

int crowd_log_step(long k, double t, const cup_proj_info *pi, void *ctx) {
  crowd_log *L = ctx;
  if (k < 1 || k > L->n) return 0;
  double clock = now_seconds();
  double v[COLS] = {t, cup_crowd_inside(L->c), cup_crowd_rows(L->c), pi->active, pi->eps_cert, pi->eta_cert,
                    NAN, pi->iterations, pi->factorizations, clock - L->last_clock, cup_crowd_added(L->c)};
  L->last_clock = clock;
  for (int c = 0; c < COLS; c++) if (c != 6) L->col[c][k] = v[c];
  L->col[6][k - 1] = cup_crowd_gap(L->c);    /* the gap of x_{k-1}, seen while building step k */
  return 0;
}

int crowd_log_write(crowd_log *L, cup_h5run *w, long last, const double *q) {
  char name[64];
  int N = cup_crowd_agents(L->c);
  L->col[6][last] = cup_crowd_min_gap(L->c, q);
  L->last = last;
  long len = last + 1, dn = N;
  int st = CUP_OK;
  for (int c = 0; c < COLS; c++) {
    snprintf(name, sizeof name, "steps/%s", names[c]);
    st = cup_status_merge(st, cup_h5run_array(w, name, 1, &len, L->col[c]));
    st = cup_status_merge(st, cup_h5run_describe(w, name, units[c], what[c]));
  }
  for (int c = 0; c < COLS; c++) {     /* once /steps/t exists: the scale of them all */
    snprintf(name, sizeof name, "steps/%s", names[c]);
    st = cup_status_merge(st, cup_h5run_dims(w, name, (const char *const[]){"t"}));
  }
  st = cup_status_merge(st, cup_h5run_array(w, "crowd/exit_time", 1, &dn, cup_crowd_exit_times(L->c)));
  st = cup_status_merge(st, cup_h5run_describe(w, "crowd/exit_time", "s", "the agent's exit time (NaN: inside)"));
  st = cup_status_merge(st, cup_h5run_dims(w, "crowd/exit_time", (const char *const[]){"agent"}));
  return cup_status_merge(st, cup_h5run_attr_long(w, "agents_out", N - cup_crowd_inside(L->c)));
}

int crowd_log_begin(crowd_log *L, cup_h5run *w) {
  long dn = cup_crowd_agents(L->c), dims2[2];
  const double *seg;
  static const char *const ends[4] = {"x0", "y0", "x1", "y1"};
  int st = cup_h5run_array(w, "crowd/radius", 1, &dn, cup_crowd_radii(L->c));
  st = cup_status_merge(st, cup_h5run_describe(w, "crowd/radius", "m", "the agent's radius"));
  st = cup_status_merge(st, cup_h5run_dims(w, "crowd/radius", (const char *const[]){"agent"}));
  dims2[0] = cup_crowd_walls(L->c, &seg);
  dims2[1] = 4;
  st = cup_status_merge(st, cup_h5run_array(w, "crowd/walls", 2, dims2, seg));
  /* the columns labelled: a segment from (x0, y0) to (x1, y1) */
  st = cup_status_merge(st, cup_h5run_strings(w, "crowd/wall_column", 4, ends));
  st = cup_status_merge(st, cup_h5run_describe(w, "crowd/wall_column", NULL, "a wall segment's end points"));
  st = cup_status_merge(st, cup_h5run_describe(w, "crowd/walls", "m", "wall segments from (x0, y0) to (x1, y1)"));
  st = cup_status_merge(st, cup_h5run_dims(w, "crowd/walls", (const char *const[]){"wall", "wall_column"}));
  return cup_status_merge(st, cup_h5run_attr_long(w, "agents", dn));
}

void crowd_log_summary(const crowd_log *L, char *buf, size_t size) {
  int N = cup_crowd_agents(L->c), out = 0;
  const double *et = cup_crowd_exit_times(L->c);
  double lastexit = NAN;
  for (int i = 0; i < N; i++)
    if (!isnan(et[i])) { out++; lastexit = isnan(lastexit) ? et[i] : fmax(lastexit, et[i]); }
  snprintf(buf, size, "%d agents, %d out (the last at t = %.4g)", N, out, lastexit);
}

int crowd_log_overlap(const crowd_log *L, char *buf, size_t size) {
  /* The state x_k's gap against the eta of the step k that made it: below
   * -sqrt(2) eta the projection is not the cause (it is exact for the rows
   * it had), but a contact the step's rows missed that its rechecks (the
   * step projected again with the contacts its answer overlapped, at most
   * 8 times) did not all catch: an agent that was farther than the contact
   * margin from another or from a wall at x_{k-1} and closed it within one
   * step. A gap's rounding is a few ulps of the positions: a billionth of
   * the largest radius is far above it. */
  const double *r = cup_crowd_radii(L->c);
  double rmax = 0;
  for (int i = 0; i < cup_crowd_agents(L->c); i++) rmax = fmax(rmax, r[i]);
  long worst = -1;
  double excess = 1e-9 * rmax;
  for (long k = 1; k <= L->last; k++) {
    double e = -L->col[6][k] - sqrt(2) * L->col[5][k];
    if (e > excess) { excess = e; worst = k; }
  }
  if (worst < 0) return 0;
  snprintf(buf, size, "overlap of %.3g m at t = %.6g (step %ld), beyond the certified eta %.3g: "
           "agents closed more than the contact margin within one step, more than the step's "
           "rechecks caught (raise crowd.margin, or take smaller steps); /steps/gap has every step's",
           -L->col[6][worst], L->col[0][worst], worst, L->col[5][worst]);
  return 1;
}

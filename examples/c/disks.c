/* disks — N disks walk to a point on a wall and pile up against it and
 * each other without overlapping: a state-dependent sweeping process
 * (include/catchup/set.h, CUP_SET_STATE_POLYSET) in the manner of Maury and
 * Venel's crowd model.
 *
 *     q' in -N(C(t, q); q) + U(q),   U_i = v (target - q_i) / max(|target - q_i|, r_i)
 *
 * C(t, q_k) is built from the state at every step: for each pair closer than
 * r_i + r_j + margin, the contact linearized at q_k,
 *     e . (y_i - y_j) - (r_i + r_j) >= 0,   e = (q_i - q_j) / |q_i - q_j|,
 * which implies |y_i - y_j| >= e . (y_i - y_j) >= r_i + r_j: no overlap, to
 * the certified eta; and for each disk the wall y >= r_i. Pairs are found
 * with a cell list, so that finding them costs O(N) for a bounded density. Rows whose
 * pattern (the pair) was seen in the last steps reuse their slot of the
 * sparse factorization; a new pair forces a new symbolic analysis (counted).
 *
 *     disks [N] [steps]      (default 60 disks, 400 steps of 0.05)
 *
 * Prints one line per 100 steps and a summary; exits 1 if any two disks
 * overlap by more than the certified eta, or if the run fails. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"

typedef struct {
  int N;
  double *r;            /* radii */
  double tx, ty, v;     /* target and speed */
  double margin;        /* pairs closer than r_i + r_j + margin get a row */
  double reach;         /* pairs closer than r_i + r_j + reach are expected (cup_rowbuf_expect) */
  /* cell list over the current positions */
  double cell;
  int gx, gy;
  double x0, y0;
  int *head, *next, head_cap;
  int *pi, *pj, pair_cap;   /* candidate pairs */
  /* checks */
  double worst_gap;     /* min over steps and pairs of |q_i - q_j| - r_i - r_j */
  double max_eta;
} crowd;

static void build_cells(crowd *c, const double *q) {
  double xmin = q[0], xmax = q[0], ymin = q[1], ymax = q[1];
  for (int i = 1; i < c->N; i++) {
    xmin = fmin(xmin, q[2 * i]); xmax = fmax(xmax, q[2 * i]);
    ymin = fmin(ymin, q[2 * i + 1]); ymax = fmax(ymax, q[2 * i + 1]);
  }
  c->x0 = xmin;
  c->y0 = ymin;
  c->gx = (int)((xmax - xmin) / c->cell) + 1;
  c->gy = (int)((ymax - ymin) / c->cell) + 1;
  if (c->gx * c->gy > c->head_cap) {      /* grows with the crowd's extent only */
    c->head_cap = 2 * c->gx * c->gy;
    free(c->head);
    c->head = malloc(sizeof(int) * (size_t)c->head_cap);
  }
  for (int k = 0; k < c->gx * c->gy; k++) c->head[k] = -1;
  for (int i = c->N - 1; i >= 0; i--) {
    int cx = (int)((q[2 * i] - c->x0) / c->cell), cy = (int)((q[2 * i + 1] - c->y0) / c->cell);
    int k = cx + c->gx * cy;
    c->next[i] = c->head[k];
    c->head[k] = i;
  }
}

/* The pairs i < j in neighbouring cells (all pairs closer than c->cell),
 * into c->pi, c->pj; returns their number. */
static int near_pairs(crowd *c, const double *q) {
  build_cells(c, q);
  int count = 0;
  for (int i = 0; i < c->N; i++) {
    int cx = (int)((q[2 * i] - c->x0) / c->cell), cy = (int)((q[2 * i + 1] - c->y0) / c->cell);
    for (int dy = -1; dy <= 1; dy++)
      for (int dx = -1; dx <= 1; dx++) {
        int ax = cx + dx, ay = cy + dy;
        if (ax < 0 || ay < 0 || ax >= c->gx || ay >= c->gy) continue;
        for (int j = c->head[ax + c->gx * ay]; j >= 0; j = c->next[j]) {
          if (j <= i) continue;
          if (count == c->pair_cap) {
            c->pair_cap = 2 * c->pair_cap + 64;
            c->pi = realloc(c->pi, sizeof(int) * (size_t)c->pair_cap);
            c->pj = realloc(c->pj, sizeof(int) * (size_t)c->pair_cap);
          }
          c->pi[count] = i;
          c->pj[count++] = j;
        }
      }
  }
  return count;
}

/* The rows of C(t, q): contacts near q (linearized there), and the wall. */
static int contact_rows(double t, const double *q, cup_rowbuf *rows, void *vp) {
  (void)t;
  crowd *c = vp;
  int st = CUP_OK, np = near_pairs(c, q);
  for (int k = 0; k < np; k++) {
    int i = c->pi[k], j = c->pj[k];
    double dx = q[2 * i] - q[2 * j], dy = q[2 * i + 1] - q[2 * j + 1], d = hypot(dx, dy);
    double R = c->r[i] + c->r[j];
    int cols[4] = {2 * i, 2 * i + 1, 2 * j, 2 * j + 1};
    if (d < R + c->margin && d > 0) {
      double e0 = dx / d, e1 = dy / d, vals[4] = {e0, e1, -e0, -e1};
      st |= cup_rowbuf_add(rows, 4, cols, vals, -R);
    } else if (d < R + c->reach) {
      st |= cup_rowbuf_expect(rows, 4, cols);   /* may be a row in a few steps */
    }
  }
  for (int i = 0; i < c->N; i++) {        /* the wall y = 0 */
    int col = 2 * i + 1;
    double one = 1;
    st |= cup_rowbuf_add(rows, 1, &col, &one, -c->r[i]);
  }
  return st;
}

/* The desired velocity: towards the target at speed v (slowing within r). */
static int walk(double t, const double *q, double *f, void *vp) {
  (void)t;
  const crowd *c = vp;
  for (int i = 0; i < c->N; i++) {
    double dx = c->tx - q[2 * i], dy = c->ty - q[2 * i + 1];
    double s = c->v / fmax(hypot(dx, dy), c->r[i]);
    f[2 * i] = s * dx;
    f[2 * i + 1] = s * dy;
  }
  return 0;
}

/* Every state: the smallest gap between two disks (and to the wall). */
static int check(long k, double t, const double *q, void *vp) {
  crowd *c = vp;
  int np = near_pairs(c, q);
  for (int p = 0; p < np; p++) {
    int i = c->pi[p], j = c->pj[p];
    double gap = hypot(q[2 * i] - q[2 * j], q[2 * i + 1] - q[2 * j + 1]) - c->r[i] - c->r[j];
    c->worst_gap = fmin(c->worst_gap, gap);
  }
  for (int i = 0; i < c->N; i++) c->worst_gap = fmin(c->worst_gap, q[2 * i + 1] - c->r[i]);
  if (k % 100 == 0) {
    double mean = 0;
    for (int i = 0; i < c->N; i++) mean += hypot(c->tx - q[2 * i], c->ty - q[2 * i + 1]) / c->N;
    printf("step %5ld  t = %6.2f  mean distance to the target %.4f\n", k, t, mean);
  }
  return 0;
}

static int on_step(long k, double t, const cup_proj_info *pi, void *vp) {
  (void)k; (void)t;
  crowd *c = vp;
  c->max_eta = fmax(c->max_eta, pi->eta_cert);
  return 0;
}

int main(int argc, char **argv) {
  int N = argc > 1 ? atoi(argv[1]) : 60;
  long steps = argc > 2 ? atol(argv[2]) : 400;
  if (N < 2 || steps < 1) {
    fprintf(stderr, "usage: disks [N >= 2] [steps >= 1]\n");
    return 2;
  }
  crowd c = {.N = N, .v = 1, .margin = 0.3, .reach = 0.45, .worst_gap = INFINITY};
  c.r = malloc(sizeof(double) * (size_t)N);
  c.next = malloc(sizeof(int) * (size_t)N);
  double *q0 = malloc(sizeof(double) * 2 * (size_t)N);
  int side = (int)ceil(sqrt((double)N));
  for (int i = 0; i < N; i++) {          /* a loose grid above the wall */
    c.r[i] = 0.4 + 0.1 * ((i * 7) % 5) / 4.0;
    q0[2 * i] = 1.25 * (i % side);
    q0[2 * i + 1] = 2 + 1.25 * (i / side);
  }
  c.tx = 1.25 * (side - 1) / 2;
  c.ty = 0;
  c.cell = 1 + c.reach;                  /* >= the largest r_i + r_j + reach */

  char err[CUP_ERRMSG_LEN];
  cup_set_desc sd = {.kind = CUP_SET_STATE_POLYSET, .n = 2 * N, .rows = contact_rows, .rows_ctx = &c};
  cup_set *S;
  if (cup_set_create(&S, &sd, err)) { fprintf(stderr, "disks: %s\n", err); return 1; }
  cup_process_desc d = {.n = 2 * N, .C = S, .f = walk, .f_ctx = &c};
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.T = 0.05 * (double)steps;
  o.n = steps;
  o.f_order = 1;                         /* U does not depend on t */
  o.on_step = on_step;
  o.step_ctx = &c;
  cup_integrator *I;
  if (cup_integrator_create_process(&I, &d, &o, err)) { fprintf(stderr, "disks: %s\n", err); return 1; }
  cup_run_info info;
  int st = cup_integrator_run(I, q0, check, &c, &info);
  printf("%d disks, %ld steps: %s; %ld projected, %lld dual iterations, %ld factorizations, "
         "most rows %ld, symbolic analyses %ld, max eps_cert %.3g, max eta_cert %.3g\n",
         N, info.step, cup_status_name(st), info.projected, info.dual_iterations,
         info.factorizations, info.max_rows, info.set_rebuilds, info.max_eps_cert, info.max_eta_cert);
  int overlap = c.worst_gap < -c.max_eta - 1e-12;
  printf("smallest gap %.3g (certified eta %.3g): %s\n", c.worst_gap, c.max_eta,
         overlap ? "OVERLAP" : "no overlap");
  cup_integrator_free(&I);
  cup_set_free(&S);
  free(c.r); free(c.next); free(c.head); free(c.pi); free(c.pj); free(q0);
  return st < 0 || overlap ? 1 : 0;
}

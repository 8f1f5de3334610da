/* crowd — Maury and Venel's crowd motion on the state-dependent polyset
 * (catchup/crowd.h), its step: the cell list that finds the pairs near
 * contact in O(N) a step, the rows of C(q_k), the contacts a step missed,
 * the desired velocity, and the queries (the crowd's set-up is in
 * crowd_create.c). Allocation happens in a step only when it has more rows
 * and patterns to come than every step before and than the 2 N + 64 the
 * stage starts with (the stage doubles, as the row buffer does). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "util/linalg.h"
#include "set/rowpool.h"
#include "set/set_impl.h"
#include "crowd_impl.h"

/* ---- the cell list ----------------------------------------------------------------- */

/* The agents inside sorted by cell (row-major), contiguous per cell and in
 * increasing internal index within one (a counting sort), with their
 * positions and radii copied in that order; the evacuated agents follow.
 * An agent's neighbours are then three runs of memory (three rows of
 * cells) instead of a linked list through the whole crowd: at 10^5 agents
 * the list's every link was a cache miss. */
static void bin_agents(cup_crowd *c, const double *q) {
  int ncell = c->gx * c->gy, nin = 0;
  memset(c->cell_ptr, 0, sizeof(int) * ((size_t)ncell + 1));
  for (int k = 0; k < c->N; k++) {             /* by internal index k: agent i = ord[k] */
    int i = c->ord[k];
    c->kcell[k] = c->out[i] ? -1 : crowd_cell_of(c, q[2 * i], q[2 * i + 1]);
    if (c->kcell[k] >= 0) { c->cell_ptr[c->kcell[k] + 1]++; nin++; }
  }
  for (int k = 0; k < ncell; k++) c->cell_ptr[k + 1] += c->cell_ptr[k];
  memcpy(c->head, c->cell_ptr, sizeof(int) * (size_t)ncell);   /* head as per-cell cursors */
  for (int k = 0, tail = nin; k < c->N; k++) {
    int a = c->kcell[k] >= 0 ? c->head[c->kcell[k]]++ : tail++, i = c->ord[k];
    c->bin[a] = (crowd_agent){q[2 * i], q[2 * i + 1], c->r[i], k};
  }
}

/* crowd_impl.h says what the visit does and in which order. */
int crowd_each_pair(cup_crowd *c, const double *q, pair_fn fn, void *ctx) {
  bin_agents(c, q);
  for (int k = 0; k < c->gx * c->gy; k++) {
    int ci = k % c->gx, cj = k / c->gx, u0 = ci > 0 ? ci - 1 : 0, u1 = ci + 1 < c->gx ? ci + 1 : ci, st;
    for (int a = c->cell_ptr[k]; a < c->cell_ptr[k + 1]; a++) {
      const crowd_agent *A = c->bin + a, *B;
      for (int e = c->wptr[k]; e < c->wptr[k + 1]; e++)
        if ((st = fn(c, a, -1 - c->widx[e], ctx))) return st;
      for (int v = cj > 0 ? cj - 1 : 0; v <= cj + 1 && v < c->gy; v++)
        for (int b = c->cell_ptr[u0 + c->gx * v]; b < c->cell_ptr[u1 + c->gx * v + 1]; b++) {
          if ((B = c->bin + b)->i <= A->i) continue;
          double dx = A->x - B->x, dy = A->y - B->y, t = c->bound + A->r + B->r;
          /* 1e-12 covers the rounding of the squares, of hypot and of the gap */
          if (dx * dx + dy * dy > t * t * (1 + 1e-12)) continue;
          if ((st = fn(c, a, b, ctx))) return st;
        }
    }
  }
  return 0;
}

/* The gap of a pair (b >= 0) or of agent a and wall -1 - b (positions in the
 * binned order), with the unit normal pushing a away and the point of
 * contact on the wall. */
static double gap_of(const cup_crowd *c, int a, int b, double *nx, double *ny, double *px, double *py) {
  double x = c->bin[a].x, y = c->bin[a].y, d;
  if (b >= 0) {
    *px = c->bin[b].x;
    *py = c->bin[b].y;
    d = hypot(x - *px, y - *py);
  } else {
    d = crowd_seg_nearest(c->seg + 4 * (-1 - b), x, y, px, py);
  }
  *nx = d > 0 ? (x - *px) / d : 0;
  *ny = d > 0 ? (y - *py) / d : 0;
  return d - c->bin[a].r - (b >= 0 ? c->bin[b].r : 0);
}

/* ---- the process: rows of C(q_k) and the desired velocity ------------------------ */

/* Whether (x, y) is in the room, as crowd_in_polygon says, by its cell
 * where the cell is clear of the room's edges (cin). */
static int in_room(const cup_crowd *c, double x, double y) {
  double u = (x - c->cx0) / c->cell, v = (y - c->cy0) / c->cell;
  if (u >= 0 && v >= 0 && u < c->gx && v < c->gy && c->cin[(int)u + c->gx * (int)v]) return 1;
  return crowd_in_polygon(c->room, c->nroom, x, y);
}

/* Agents whose centre left the room at the state of step k have evacuated
 * (at t_k); the first step of a run (t_k = 0) starts afresh. */
static void mark_exits(cup_crowd *c, const double *q, double tk) {
  if (tk <= 0) {
    memset(c->out, 0, (size_t)c->N);
    for (int i = 0; i < c->N; i++) c->exit_time[i] = NAN;
    c->inside = c->N;
  }
  for (int i = 0; i < c->N; i++)
    if (!c->out[i] && !in_room(c, q[2 * i], q[2 * i + 1])) {
      c->out[i] = 1;
      c->exit_time[i] = tk;
      c->inside--;
    }
}

/* The row of agent a and wall -1 - b, or of the pair (a, b) (binned, a's
 * internal index below b's), from gap_of's normal and point of contact:
 *   n . (y_i - p) >= r_i;  e . (y_i - y_j) >= r_i + r_j. */
static crowd_entry row_entry(const cup_crowd *c, int a, int b, int row, double nx, double ny, double px,
                             double py) {
  double ra = c->bin[a].r;
  return (crowd_entry){b < 0 ? b : c->bin[b].i, row, nx, ny,
                       b < 0 ? -(ra + nx * px + ny * py) : -(ra + c->bin[b].r)};
}

/* The row of agent a and wall -1 - b, or of the pair (a, b), when its gap
 * is within the margin, its pattern only (to come soon) within reach: kept
 * in the stage, agent by agent (crowd_each_pair makes an agent's calls together). */
static int stage_row(cup_crowd *c, int a, int b, void *ctx) {
  (void)ctx;
  double nx, ny, px, py, gap = gap_of(c, a, b, &nx, &ny, &px, &py);
  if (gap < c->gap) {                        /* pairs farther than this add nothing now */
    c->gap = gap;
    c->bound = fmax(c->reach, gap);
  }
  if (!(gap < c->reach) || (nx == 0 && ny == 0)) return 0;
  if (c->nstage == c->stage_cap) {           /* more rows than any step before */
    int cap = 2 * c->stage_cap;
    crowd_entry *s = realloc(c->stage, sizeof *s * (size_t)cap);
    if (!s) return CUP_ERR_NOMEM;
    c->stage = s;
    c->stage_cap = cap;
  }
  int i = c->bin[a].i;
  if (!c->run_len[i]) c->run_start[i] = c->nstage;
  c->run_len[i]++;
  c->stage[c->nstage++] = row_entry(c, a, b, gap < c->margin, nx, ny, px, py);
  return 0;
}

/* Pairs farther apart than this in the internal numbering count as far
 * (crowd_rows' measure of the numbering's decay). */
enum { FAR_APART = 64 };
/* Renumber when this many more of the pair rows are far than just after the
 * last renumbering (measured on 10^4 agents: 7.6 % far after a numbering,
 * 9.7 % 200 steps later), judged on at least RENUMBER_PAIRS pair rows. */
#define RENUMBER_DECAY 0.05
enum { RENUMBER_PAIRS = 256 };

/* One staged row into the buffer: a row, or a pattern to come. */
static int emit_row(cup_rowbuf *rb, int i, const crowd_entry *w, int row) {
  int pair = w->j >= 0, nnz = pair ? 4 : 2;
  int cols[4] = {2 * i, 2 * i + 1, 2 * w->j, 2 * w->j + 1};
  double vals[4] = {w->nx, w->ny, -w->nx, -w->ny};
  return row ? cup_rowbuf_add(rb, nnz, cols, vals, w->off) : cup_rowbuf_expect(rb, nnz, cols);
}

/* Agent i's forced entry for wall or agent j, searching from forced[f]
 * (the forced entries are sorted by owner), or NULL. */
static const crowd_entry *forced_of(const cup_crowd *c, int f, int i, int j) {
  for (; f < c->nforced && c->forced[f].owner == i; f++)
    if (c->forced[f].e.j == j) return &c->forced[f].e;
  return NULL;
}

/* The staged rows into the buffer by increasing internal index, in the
 * internal numbering's columns: the order of the rows, hence of every sum
 * in the projection, is the numbering's, whatever the binning (a crowd
 * evacuation is chaotic: rows in another order moved agents of
 * examples/crowd-room.yaml by metres within 200 steps). */
static int emit_rows(cup_crowd *c, cup_rowbuf *rb) {
  /* the contacts a recheck forced join their owner's rows: a pattern to
   * come becomes a row, one beyond reach follows the owner's staged rows */
  int pairs = 0, far = 0, f = 0, st;
  for (int i = 0; i < c->N; i++) {
    int r0 = c->run_start[i], r1 = r0 + c->run_len[i];
    while (f < c->nforced && c->forced[f].owner < i) f++;
    for (int e = r0; e < r1; e++) {
      const crowd_entry *w = c->stage + e;
      int row = w->row || (f < c->nforced && forced_of(c, f, i, w->j));   /* a pattern to come, forced */
      if (w->j >= 0 && row) { pairs++; far += w->j - i > FAR_APART; }
      if ((st = emit_row(rb, i, w, row))) return st;
    }
    for (; f < c->nforced && c->forced[f].owner == i; f++) {      /* forced, beyond reach */
      const crowd_entry *w = &c->forced[f].e;
      int staged = 0;
      for (int e = r0; e < r1 && !staged; e++) staged = c->stage[e].j == w->j;
      if (!staged && (st = emit_row(rb, i, w, 1))) return st;
    }
  }
  if (pairs >= RENUMBER_PAIRS) {             /* fewer: too few to judge, and all in cache anyway */
    c->far = (double)far / pairs;
    if (c->far_base < 0) c->far_base = c->far;
  }
  return 0;
}

int crowd_rows(double t, const double *q, cup_rowbuf *rows, void *vc) {
  cup_crowd *c = vc;
  double tk = t > 0 ? t - c->h : 0;
  int again = c->redo;          /* the same step again, with the contacts it missed (kept) */
  c->redo = 0;
  if (!again) c->nforced = 0;
  mark_exits(c, q, tk);
  /* a run starts numbered from its start alone, then renumbers when the
     agents have moved enough for the pairs' columns to spread out */
  if (!again && (tk <= 0 || (c->far_base >= 0 && c->far > c->far_base + RENUMBER_DECAY))) crowd_renumber(c, q);
  rowbuf_order(rows, c->colmap, c->order_gen);
  c->gap = c->bound = INFINITY;
  c->nstage = 0;
  memset(c->run_len, 0, sizeof(int) * (size_t)c->N);
  int st = crowd_each_pair(c, q, stage_row, NULL);
  if (st) return st;                          /* out of memory */
  emit_rows(c, rows);                         /* a bad row is reported by the buffer */
  c->rows = cup_rowbuf_rows(rows);
  return 0;
}

/* A contact the step's rows missed: agent (internal) owner and wall -1 - j
 * or agent j > owner, its row at q as stage_row makes it. Once a step. */
static int force_row(cup_crowd *c, int owner, crowd_entry e) {
  for (int f = 0; f < c->nforced; f++)
    if (c->forced[f].owner == owner && c->forced[f].e.j == e.j) return 0;
  if (c->nforced == c->forced_cap) {
    int cap = c->forced_cap ? 2 * c->forced_cap : 16;
    struct crowd_forced *fc = realloc(c->forced, sizeof *fc * (size_t)cap);
    if (!fc) return CUP_ERR_NOMEM;
    c->forced = fc;
    c->forced_cap = cap;
  }
  c->forced[c->nforced++] = (struct crowd_forced){owner, e};
  return 1;
}

static int cmp_forced(const void *a, const void *b) {
  const struct crowd_forced *x = a, *y = b;
  if (x->owner != y->owner) return (x->owner > y->owner) - (x->owner < y->owner);
  return (x->e.j > y->e.j) - (x->e.j < y->e.j);
}

/* The walls and agents near agent a (binned at q, displaced by da to z)
 * that had no row (a gap of at least the margin at q) and overlap it at z:
 * forced. dmax bounds every agent's displacement. Returns how many are new. */
static int missed_by(cup_crowd *c, int a, double da, double dmax, const double *z) {
  const crowd_agent *A = c->bin + a;
  int i = c->ord[A->i], found = 0, st;
  double zx = z[2 * i], zy = z[2 * i + 1], nx, ny, px, py, qx, qy;
  for (int s = 0; s < c->nseg && da > c->margin; s++) {
    if (!(gap_of(c, a, -1 - s, &nx, &ny, &px, &py) >= c->margin) ||
        !(crowd_seg_nearest(c->seg + 4 * s, zx, zy, &qx, &qy) < A->r))
      continue;
    if ((st = force_row(c, A->i, row_entry(c, a, -1 - s, 1, nx, ny, px, py))) < 0) return st;
    found += st;
  }
  /* a partner b overlaps at z only within 2 rmax + da + dmax of a at q */
  double R = 2 * c->rmax + da + dmax;
  int i0 = (int)floor((A->x - R - c->cx0) / c->cell), i1 = (int)floor((A->x + R - c->cx0) / c->cell);
  int j0 = (int)floor((A->y - R - c->cy0) / c->cell), j1 = (int)floor((A->y + R - c->cy0) / c->cell);
  for (int v = j0 < 0 ? 0 : j0; v <= j1 && v < c->gy; v++)
    for (int u = i0 < 0 ? 0 : i0; u <= i1 && u < c->gx; u++)
      for (int b = c->cell_ptr[u + c->gx * v]; b < c->cell_ptr[u + c->gx * v + 1]; b++) {
        const crowd_agent *B = c->bin + b;
        if (b == a) continue;
        int j = c->ord[B->i], lo = A->i < B->i ? a : b, hi = lo == a ? b : a;
        if (!(gap_of(c, lo, hi, &nx, &ny, &px, &py) >= c->margin) ||
            !(hypot(zx - z[2 * j], zy - z[2 * j + 1]) < A->r + B->r))
          continue;
        if ((st = force_row(c, c->bin[lo].i, row_entry(c, lo, hi, 1, nx, ny, px, py))) < 0) return st;
        found += st;
      }
  return found;
}

/* After the step from q (t_k) answered z: the contacts its rows missed. A
 * pair without a row was at least the margin apart at q, so it overlaps at
 * z only if its agents moved more than the margin between them (a wall:
 * its agent more than the margin), which in a jam an agent squeezed out
 * does (0.32 m in one step of 0.05 s was seen); such contacts get their row
 * (linearized at q like every other) and the step is projected again. */
int crowd_recheck(double t, const double *q, const double *z, void *vc) {
  cup_crowd *c = vc;
  (void)t;
  double d2 = 0;                                /* the largest displacement, squared */
  for (int i = 0; i < c->N; i++) {
    double dx = z[2 * i] - q[2 * i], dy = z[2 * i + 1] - q[2 * i + 1];
    if (!c->out[i]) d2 = la_max(dx * dx + dy * dy, d2);   /* as fmax, without a libm call */
  }
  if (!(d2 > 0.25 * c->margin * c->margin)) return 0;   /* no agent moved enough to miss anything */
  double dmax = sqrt(d2);
  bin_agents(c, q);                             /* the cell list at q (a query may have moved it) */
  int found = 0, nin = c->cell_ptr[c->gx * c->gy];
  for (int a = 0; a < nin; a++) {
    int i = c->ord[c->bin[a].i];
    double da = hypot(z[2 * i] - q[2 * i], z[2 * i + 1] - q[2 * i + 1]);
    if (!(da > c->margin - dmax)) continue;     /* neither it nor a partner moved enough */
    int st = missed_by(c, a, da, dmax, z);
    if (st < 0) return st;                      /* out of memory */
    found += st;
  }
  if (found) qsort(c->forced, (size_t)c->nforced, sizeof *c->forced, cmp_forced);
  c->redo = found > 0;
  return found;
}

/* The exact integral over a step at frozen q: h U(q_k), agent by agent in
 * the last binned order, in which neighbours read neighbouring nodes of
 * the distance grid (any order gives the same numbers). */
int crowd_walk(double t0, double t1, const double *q, double *F, void *vc) {
  cup_crowd *c = vc;
  mark_exits(c, q, t0);
  double dt = t1 - t0;
  for (int a = 0; a < c->N; a++) {
    int i = c->ord[c->bin[a].i];
    double u[2] = {0, 0};
    if (!c->out[i]) crowd_field_direction(&c->F, q[2 * i], q[2 * i + 1], u);
    F[2 * i] = dt * c->speed * u[0];
    F[2 * i + 1] = dt * c->speed * u[1];
  }
  return 0;
}

int crowd_note_worst(cup_crowd *c, int a, int b, void *ctx) {
  worst_pair *w = ctx;
  if (b < 0 && w->pairs_only) return 0;
  double nx, ny, px, py, g = gap_of(c, a, b, &nx, &ny, &px, &py);
  int i = c->ord[c->bin[a].i], j = b >= 0 ? c->ord[c->bin[b].i] : b;
  if (j >= 0 && j < i) { int t = i; i = j; j = t; }   /* the user's index, the lower first */
  if (g < w->gap || (g == w->gap && (i < w->i || (i == w->i && j < w->j)))) {
    w->gap = c->bound = g;
    w->i = i;
    w->j = j;
  }
  return 0;
}

/* ---- queries ------------------------------------------------------------------------- */

int cup_crowd_agents(const cup_crowd *c) { return c ? c->N : 0; }
const cup_process_desc *cup_crowd_process(const cup_crowd *c) { return c ? &c->proc : NULL; }
const double *cup_crowd_exit_times(const cup_crowd *c) { return c ? c->exit_time : NULL; }
int cup_crowd_inside(const cup_crowd *c) { return c ? c->inside : 0; }
double cup_crowd_gap(const cup_crowd *c) { return c ? c->gap : NAN; }
int cup_crowd_rows(const cup_crowd *c) { return c ? c->rows : 0; }
int cup_crowd_added(const cup_crowd *c) { return c ? c->nforced : 0; }
const double *cup_crowd_q0(const cup_crowd *c) { return c ? c->q0 : NULL; }
const double *cup_crowd_radii(const cup_crowd *c) { return c ? c->r : NULL; }

double cup_crowd_door_distance(const cup_crowd *c, double x, double y) {
  return c ? crowd_field_distance(&c->F, x, y) : NAN;
}

void cup_crowd_desired_velocity(const cup_crowd *c, double x, double y, double *u) {
  if (!c || !u) return;
  crowd_field_direction(&c->F, x, y, u);
  u[0] *= c->speed;
  u[1] *= c->speed;
}

int cup_crowd_walls(const cup_crowd *c, const double **seg) {
  if (!c) return 0;
  if (seg) *seg = c->seg;
  return c->nseg;
}

double cup_crowd_min_gap(cup_crowd *c, const double *q) {
  if (!c || !q) return NAN;
  worst_pair w = {INFINITY, -1, -1, 0};
  c->bound = INFINITY;
  crowd_each_pair(c, q, crowd_note_worst, &w);
  return w.gap;
}

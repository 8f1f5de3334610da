/* crowd_impl — the inside of a crowd (catchup/crowd.h): its geometry, the
 * distance grid (crowd_field.c) and the cell list. Internal to the library. */
#ifndef CUP_CROWD_IMPL_H
#define CUP_CROWD_IMPL_H

#include "catchup/crowd.h"

/* The geodesic distance to the doors on a grid of nodes (x0 + i h, y0 + j h),
 * by fast marching around the walls, and the unit direction that descends
 * it at every node. */
typedef struct crowd_field {
  int nx, ny;
  double x0, y0, h;
  double *D;            /* nx ny distances; INFINITY: blocked by a wall or unreachable */
  float *ux, *uy;       /* nx ny unit descent directions (0, 0 where undefined) */
} crowd_field;

/* Build the field over [x0, x1] x [y0, y1]: nodes outside the room (a
 * polygon of nroom vertices) or within max(h, clearance) of a wall are
 * blocked (so that no step of the front crosses one, and the distance is a
 * centre's that keeps the clearance); each door is shrunk by the clearance
 * at both ends; free nodes within seed_radius (at least the door's width
 * and 1.5 h) of a door whose straight line to their nearest door point
 * keeps the clearance from every wall start at their exact distance to it.
 * On failure errmsg names the door that has no free node within 1.5 h. */
int crowd_field_build(crowd_field *F, const double *room, int nroom, const double *seg, int nseg,
                      const double *door, int ndoor, const double box[4], double h, double seed_radius,
                      double clearance, char *errmsg);
/* Whether the polygon of np vertices is not simple: 1 with the first two
 * edges that meet (edge e runs from vertex e to e + 1), neighbours only
 * where they fold back over each other; 0 when it is simple. */
int crowd_polygon_crossing(const double *v, int np, int *ea, int *eb);
/* Crossing number: (x, y) inside the polygon of np vertices (2 each)? */
int crowd_in_polygon(const double *v, int np, double x, double y);
void crowd_field_free(crowd_field *F);
/* Bilinear on the free nodes around (x, y); INFINITY where none is finite. */
double crowd_field_distance(const crowd_field *F, double x, double y);
/* The interpolated unit direction (0, 0 where undefined). */
void crowd_field_direction(const crowd_field *F, double x, double y, double *u);
/* The nearest node of (x, y), clamped to the grid. */
int crowd_field_node(const crowd_field *F, double x, double y);

/* Point-segment distance and the nearest point. */
double crowd_seg_nearest(const double *s, double x, double y, double *px, double *py);

/* Where a wall segment comes from, for messages. */
enum { WALL_ROOM = 0, WALL_OBSTACLE = 1, WALL_EXTRA = 2 };

/* An agent as binned: position, radius, index (one cache line holds two). */
typedef struct crowd_agent {
  double x, y, r;
  int i;
} crowd_agent;

/* A row of agent i staged by the cell list: wall -1 - j or agent j > i. */
typedef struct crowd_entry {
  int j;
  int row;                          /* 1: a row (within the margin); 0: a pattern to come */
  double nx, ny, off;               /* the normal (e for a pair) and the row's offset */
} crowd_entry;

struct cup_crowd {
  char warning[CUP_ERRMSG_LEN];     /* a door no agent can pass, or "" */
  int N;
  double *q0, *r;
  double speed, h, margin, reach, rmax;
  int nroom;
  double *room;                     /* 2 nroom */
  int nobs;
  int *obs_ptr;                     /* nobs + 1 vertex starts */
  double *obs;                      /* 2 per vertex */
  int ndoor;
  double *door;                     /* 4 per door */
  int nseg;
  double *seg;                      /* 4 per wall segment */
  int *seg_kind, *seg_of, *seg_part;/* WALL_*, which room edge / obstacle / wall, which edge */
  crowd_field F;
  /* cell list over the room's box: cells of side >= 2 rmax + reach */
  double cx0, cy0, cell;
  int gx, gy;
  int *head;                        /* gx gy: per-cell cursors */
  int *wptr, *widx;                 /* per cell: the walls within rmax + reach of it */
  unsigned char *cin;               /* gx gy: 1 where the cell lies inside the room, clear of
                                       its edges (mark_exits tests a point there by its cell) */
  /* the agents inside binned by cell (crowd.c, bin_agents) */
  int *cell_ptr;                    /* gx gy + 1: each cell's agents in bin[] */
  crowd_agent *bin;                 /* N: the agents inside by cell, then the evacuated (i: the
                                       internal index) */
  int *kcell;                       /* N: each agent's cell (-1: evacuated), by internal index */
  double bound;                     /* a visit skips pairs whose gap is surely >= this */
  /* a step's rows, found in the binned order, kept until they are put in
     the index order (crowd.c, emit_rows) */
  crowd_entry *stage;               /* stage_cap entries, nstage in use */
  int nstage, stage_cap;
  int *run_start, *run_len;         /* N: each agent's entries in the stage (as the lower
                                       internal index) */
  /* the internal numbering (crowd_order.c): the agents along a Hilbert
     curve over the cells, the user's index everywhere outside */
  int *ord;                         /* N: internal agent k is the user's agent ord[k] */
  int *rank;                        /* N: the user's agent i is internal rank[i] */
  int *colmap;                      /* 2N: column k of the rows is q[colmap[k]] */
  int *hpos;                        /* gx gy: each cell's place along the curve */
  long order_gen;                   /* renumberings so far */
  double far, far_base;             /* pair rows far apart in the numbering, now and after the
                                       last renumbering (-1: not measured yet) */
  /* the run */
  unsigned char *out;               /* evacuated */
  double *exit_time;
  int inside;
  double gap;                       /* the smallest gap at the state the rows were built from */
  int rows;                         /* rows of the last step */
  /* contacts the step's rows missed (beyond the margin at q_k, overlapping
     at its answer: crowd_recheck), forced into its rows; the owner is the
     agent whose run the row joins (the lower internal index of a pair) */
  struct crowd_forced { int owner; crowd_entry e; } *forced;
  int nforced, forced_cap;
  int redo;                         /* 1: the next rows are the same step's again */
  cup_set *S;
  cup_process_desc proc;
};

/* The cell of (x, y), clamped to the grid. */
static inline int crowd_cell_of(const cup_crowd *c, double x, double y) {
  int i = (int)((x - c->cx0) / c->cell), j = (int)((y - c->cy0) / c->cell);
  i = i < 0 ? 0 : i >= c->gx ? c->gx - 1 : i;
  j = j < 0 ? 0 : j >= c->gy ? c->gy - 1 : j;
  return i + c->gx * j;
}

/* Allocate the numbering and number the agents at q (crowd_order.c). */
int crowd_order_init(cup_crowd *c, const double *q, char *errmsg);
/* Number the agents at q along the curve: by cell, then by position within
 * one, so that the numbering depends on the positions alone, never on the
 * user's. No allocation. */
void crowd_renumber(cup_crowd *c, const double *q);
void crowd_order_free(cup_crowd *c);

/* ---- the step (crowd.c), as the set-up (crowd_create.c) uses it ------------------- */

/* Visit every agent inside with the walls of its cell, fn(c, a, -1 - s,
 * ctx) for wall s, and every pair of agents inside in neighbouring cells
 * once, fn(c, a, b, ctx) with bin[a].i < bin[b].i (a, b positions in the
 * binned order; bin_agents). Agents go in the binned order, each with its
 * walls, then its pairs cell by cell (rows of cells from below, cells from
 * the left), with the agents of a cell in increasing internal index: the
 * calls of one agent come together, in the order a visit by increasing
 * index would make them. Pairs whose gap is certainly at least c->bound
 * (which fn may lower) are skipped without a square root, so the visit
 * stays exactly the one over all pairs. Stops at the first nonzero return. */
typedef int (*pair_fn)(cup_crowd *c, int a, int b, void *ctx);
int crowd_each_pair(cup_crowd *c, const double *q, pair_fn fn, void *ctx);
/* The smallest gap of a visit (crowd_each_pair) and where it is: agents i < j,
 * or agent i and wall -1 - j (the user's indices); the first pair (i, j)
 * among equals. */
typedef struct worst_pair {
  double gap;
  int i, j;
  int pairs_only;                  /* leave the walls out */
} worst_pair;
/* A pair_fn: the smallest gap so far into ctx, a worst_pair, and c->bound. */
int crowd_note_worst(cup_crowd *c, int a, int b, void *ctx);
/* The set's rows of C(q) (cup_set_desc.rows), the contacts a step missed
 * (its recheck) and the integral of the desired velocity over a step
 * (cup_process_desc.f_integral), their ctx the crowd. */
int crowd_rows(double t, const double *q, cup_rowbuf *rows, void *vc);
int crowd_recheck(double t, const double *q, const double *z, void *vc);
int crowd_walk(double t0, double t1, const double *q, double *F, void *vc);

#endif

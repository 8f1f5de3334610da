/* crowd_create — the crowd's set-up (catchup/crowd.h): the room's walls,
 * the checks of a scene's agents, the walls and the inside of each cell,
 * the distance field, creation and freeing. Every allocation of a crowd
 * happens here, in cup_crowd_create (the step, crowd.c, only grows its
 * stage and its forced rows). */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "set/set_impl.h"
#include "crowd_impl.h"

/* ---- geometry ----------------------------------------------------------------- */

/* Parameter of (x, y) along edge a -> b if it lies on it (within tol), else NAN. */
static double on_edge(const double *a, const double *b, double x, double y, double tol) {
  double dx = b[0] - a[0], dy = b[1] - a[1], L = hypot(dx, dy);
  if (!(L > 0)) return NAN;
  double t = ((x - a[0]) * dx + (y - a[1]) * dy) / (L * L);
  double off = fabs((x - a[0]) * dy - (y - a[1]) * dx) / L;
  return off <= tol && t >= -tol / L && t <= 1 + tol / L ? fmin(1, fmax(0, t)) : NAN;
}

static int add_seg(cup_crowd *c, const double *s, int kind, int of, int part) {
  int k = c->nseg++;
  memcpy(c->seg + 4 * k, s, sizeof(double) * 4);
  c->seg_kind[k] = kind;
  c->seg_of[k] = of;
  c->seg_part[k] = part;
  return k;
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* The room's edges less the doors on them, the obstacles' edges, the extra walls. */
static int build_walls(cup_crowd *c, const cup_crowd_desc *d, double tol, char *errmsg) {
  int cap = 2 * (d->room_points + d->doors) + d->walls + 1;
  for (int o = 0; o < d->obstacles; o++) cap += d->obstacle_points[o];
  c->seg = malloc(sizeof(double) * 4 * (size_t)cap);
  c->seg_kind = malloc(sizeof(int) * (size_t)cap);
  c->seg_of = malloc(sizeof(int) * (size_t)cap);
  c->seg_part = malloc(sizeof(int) * (size_t)cap);
  double *cut = malloc(sizeof(double) * (2 * (size_t)d->doors + 2));
  int *door_edge = malloc(sizeof(int) * (size_t)d->doors);
  int st = c->seg && c->seg_kind && c->seg_of && c->seg_part && cut && door_edge ? CUP_OK
           : fail_fmt(errmsg, CUP_ERR_NOMEM, "crowd: out of memory");
  for (int k = 0; !st && k < d->doors; k++) {
    const double *s = d->door + 4 * k;
    door_edge[k] = -1;
    for (int e = 0; e < c->nroom && door_edge[k] < 0; e++) {
      const double *a = c->room + 2 * e, *b = c->room + 2 * ((e + 1) % c->nroom);
      if (!isnan(on_edge(a, b, s[0], s[1], tol)) && !isnan(on_edge(a, b, s[2], s[3], tol))) door_edge[k] = e;
    }
    if (door_edge[k] < 0)
      st = fail_fmt(errmsg, CUP_ERR_ARG, "door %d (from (%g, %g) to (%g, %g)) does not lie on an edge of the room",
                    k, s[0], s[1], s[2], s[3]);
    else if (!(hypot(s[2] - s[0], s[3] - s[1]) > 0))
      st = fail_fmt(errmsg, CUP_ERR_ARG, "door %d has no width (both ends at (%g, %g))", k, s[0], s[1]);
  }
  for (int e = 0; !st && e < c->nroom; e++) {
    const double *a = c->room + 2 * e, *b = c->room + 2 * ((e + 1) % c->nroom);
    int nc = 0;
    for (int k = 0; k < d->doors; k++) {
      if (door_edge[k] != e) continue;
      const double *s = d->door + 4 * k;
      double t0 = on_edge(a, b, s[0], s[1], tol), t1 = on_edge(a, b, s[2], s[3], tol);
      cut[nc++] = fmin(t0, t1);
      cut[nc++] = fmax(t0, t1);
    }
    qsort(cut, (size_t)nc / 2, 2 * sizeof(double), cmp_double);   /* intervals by their start */
    double t = 0;
    for (int q = 0; q <= nc; q += 2) {
      double t1 = q < nc ? cut[q] : 1;
      if (t1 > t) {
        double s[4] = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]),
                       a[0] + t1 * (b[0] - a[0]), a[1] + t1 * (b[1] - a[1])};
        add_seg(c, s, WALL_ROOM, e, e);
      }
      if (q < nc) t = fmax(t, cut[q + 1]);
    }
  }
  for (int o = 0; !st && o < c->nobs; o++) {
    int np = c->obs_ptr[o + 1] - c->obs_ptr[o];
    const double *v = c->obs + 2 * c->obs_ptr[o];
    for (int e = 0; e < np; e++) {
      double s[4] = {v[2 * e], v[2 * e + 1], v[2 * ((e + 1) % np)], v[2 * ((e + 1) % np) + 1]};
      add_seg(c, s, WALL_OBSTACLE, o, e);
    }
  }
  for (int w = 0; !st && w < d->walls; w++) add_seg(c, d->wall + 4 * w, WALL_EXTRA, w, 0);
  free(cut);
  free(door_edge);
  return st;
}

/* "wall 3 (the room's edge 2, from (0, 0) to (10, 0))" */
static const char *wall_name(const cup_crowd *c, int k, char *buf, size_t size) {
  const double *s = c->seg + 4 * k;
  char what[64];
  if (c->seg_kind[k] == WALL_ROOM) snprintf(what, sizeof what, "the room's edge %d", c->seg_of[k]);
  else if (c->seg_kind[k] == WALL_OBSTACLE) snprintf(what, sizeof what, "obstacle %d's edge %d", c->seg_of[k], c->seg_part[k]);
  else snprintf(what, sizeof what, "the extra wall %d", c->seg_of[k]);
  snprintf(buf, size, "wall %d (%s, from (%g, %g) to (%g, %g))", k, what, s[0], s[1], s[2], s[3]);
  return buf;
}

/* ---- the cell list ----------------------------------------------------------------- */

/* Per cell, the walls that pass within rmax + reach of it. */
static int bin_walls(cup_crowd *c, char *errmsg) {
  int ncell = c->gx * c->gy;
  double range = c->rmax + c->reach + 0.7071067811865476 * c->cell;   /* from the cell's centre */
  c->wptr = calloc((size_t)ncell + 1, sizeof(int));
  if (!c->wptr) return fail_fmt(errmsg, CUP_ERR_NOMEM, "crowd: out of memory");
  for (int pass = 0; pass < 2; pass++) {      /* count, then fill */
    if (pass == 1) {
      for (int k = 0; k < ncell; k++) c->wptr[k + 1] += c->wptr[k];
      c->widx = malloc(sizeof(int) * ((size_t)c->wptr[ncell] + 1));
      if (!c->widx) return fail_fmt(errmsg, CUP_ERR_NOMEM, "crowd: out of memory");
    }
    int *fill = pass == 1 ? c->head : NULL;   /* head as per-cell cursors */
    if (fill) for (int k = 0; k < ncell; k++) fill[k] = c->wptr[k];
    for (int s = 0; s < c->nseg; s++) {
      const double *w = c->seg + 4 * s;
      int i0 = (int)floor((fmin(w[0], w[2]) - range - c->cx0) / c->cell), i1 = (int)floor((fmax(w[0], w[2]) + range - c->cx0) / c->cell);
      int j0 = (int)floor((fmin(w[1], w[3]) - range - c->cy0) / c->cell), j1 = (int)floor((fmax(w[1], w[3]) + range - c->cy0) / c->cell);
      for (int j = j0 < 0 ? 0 : j0; j <= j1 && j < c->gy; j++)
        for (int i = i0 < 0 ? 0 : i0; i <= i1 && i < c->gx; i++) {
          double px, py;
          if (crowd_seg_nearest(w, c->cx0 + (i + 0.5) * c->cell, c->cy0 + (j + 0.5) * c->cell, &px, &py) > range)
            continue;
          if (pass == 0) c->wptr[i + c->gx * j + 1]++;
          else c->widx[fill[i + c->gx * j]++] = s;
        }
    }
  }
  return CUP_OK;
}

/* The cells inside the room and clear of its edges: a cell whose centre
 * the crossing test finds inside and that no edge's box, widened by tol,
 * meets. Any point of such a cell is inside, and crowd_in_polygon says so
 * as for the centre: a crossing of a horizontal ray from it lies at least
 * tol from it, far beyond the rounding of the crossing's abscissa. */
static int inside_cells(cup_crowd *c, double tol, char *errmsg) {
  int ncell = c->gx * c->gy;
  c->cin = malloc((size_t)ncell);
  if (!c->cin) return fail_fmt(errmsg, CUP_ERR_NOMEM, "crowd: out of memory");
  for (int j = 0; j < c->gy; j++)
    for (int i = 0; i < c->gx; i++)
      c->cin[i + c->gx * j] = (unsigned char)crowd_in_polygon(c->room, c->nroom, c->cx0 + (i + 0.5) * c->cell,
                                                              c->cy0 + (j + 0.5) * c->cell);
  for (int a = 0, b = c->nroom - 1; a < c->nroom; b = a++) {
    const double *va = c->room + 2 * a, *vb = c->room + 2 * b;
    int i0 = (int)floor((fmin(va[0], vb[0]) - tol - c->cx0) / c->cell);
    int i1 = (int)floor((fmax(va[0], vb[0]) + tol - c->cx0) / c->cell);
    int j0 = (int)floor((fmin(va[1], vb[1]) - tol - c->cy0) / c->cell);
    int j1 = (int)floor((fmax(va[1], vb[1]) + tol - c->cy0) / c->cell);
    for (int j = j0 < 0 ? 0 : j0; j <= j1 && j < c->gy; j++)
      for (int i = i0 < 0 ? 0 : i0; i <= i1 && i < c->gx; i++) c->cin[i + c->gx * j] = 0;
  }
  return CUP_OK;
}

/* ---- creation and its checks -------------------------------------------------------- */

/* A polygon (the room, obstacle o) must be simple: its inside, the walls
 * and the distance field are those of a region only then. */
static int simple(const double *v, int np, const char *what, int o, char *errmsg) {
  int a, b;
  if (!crowd_polygon_crossing(v, np, &a, &b)) return 1;
  const double *p = v + 2 * a, *q = v + 2 * b, *p1 = v + 2 * ((a + 1) % np), *q1 = v + 2 * ((b + 1) % np);
  char name[32];
  snprintf(name, sizeof name, o < 0 ? "%s" : "%s %d", what, o);
  fail_fmt(errmsg, CUP_ERR_ARG, "%s is not a simple polygon: its edges %d, from (%g, %g) to (%g, %g), and %d, "
           "from (%g, %g) to (%g, %g), cross", name, a, p[0], p[1], p1[0], p1[1], b, q[0], q[1], q1[0], q1[1]);
  return 0;
}

static int check_numbers(const cup_crowd_desc *d, char *errmsg) {
  if (d->agents < 1) return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: %d agents (at least 1)", d->agents);
  if (!d->q0 || !d->radius) return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: no positions or no radii");
  if (d->room_points < 3 || !d->room)
    return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: the room has %d vertices (at least 3)", d->room_points);
  if (d->doors < 1 || !d->door) return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: no door (at least one exit)");
  if (d->obstacles < 0 || (d->obstacles > 0 && (!d->obstacle_points || !d->obstacle)))
    return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: %d obstacles without their vertices", d->obstacles);
  if (d->walls < 0 || (d->walls > 0 && !d->wall))
    return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: %d walls without their segments", d->walls);
  if (!(d->speed > 0) || !isfinite(d->speed))
    return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: the desired speed is %g (must be > 0)", d->speed);
  if (!(d->grid >= 0) || !(d->margin >= 0) || !(d->reach >= 0) || !(d->clearance >= 0) ||
      !isfinite(d->grid + d->margin + d->reach + d->clearance))
    return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: grid %g, margin %g, reach %g, clearance %g (must be finite and >= 0)",
                    d->grid, d->margin, d->reach, d->clearance);
  for (int i = 0; i < d->agents; i++) {
    if (!isfinite(d->q0[2 * i]) || !isfinite(d->q0[2 * i + 1]))
      return fail_fmt(errmsg, CUP_ERR_NONFINITE, "agent %d: position (%g, %g) is not finite", i, d->q0[2 * i], d->q0[2 * i + 1]);
    if (!(d->radius[i] > 0) || !isfinite(d->radius[i]))
      return fail_fmt(errmsg, CUP_ERR_ARG, "agent %d: radius %g (must be > 0)", i, d->radius[i]);
    /* a centre closer to a wall than the clearance would find no direction */
    if (d->clearance > d->radius[i])
      return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: the clearance %g exceeds agent %d's radius %g (it must be at "
                      "most the smallest radius)", d->clearance, i, d->radius[i]);
  }
  for (int o = 0, v0 = 0; o < d->obstacles; v0 += d->obstacle_points[o++])
    if (d->obstacle_points[o] < 3)
      return fail_fmt(errmsg, CUP_ERR_ARG, "obstacle %d has %d vertices (at least 3)", o, d->obstacle_points[o]);
    else if (!simple(d->obstacle + 2 * v0, d->obstacle_points[o], "obstacle", o, errmsg))
      return CUP_ERR_ARG;
  return simple(d->room, d->room_points, "the room", -1, errmsg) ? CUP_OK : CUP_ERR_ARG;
}

/* Every agent in the room, out of the obstacles, clear of the walls and of
 * each other (touching is allowed). */
static int check_agents(cup_crowd *c, double tol, char *errmsg) {
  char wb[160];
  for (int i = 0; i < c->N; i++) {
    double x = c->q0[2 * i], y = c->q0[2 * i + 1];
    if (!crowd_in_polygon(c->room, c->nroom, x, y))
      return fail_fmt(errmsg, CUP_ERR_ARG, "agent %d at (%g, %g) is outside the room", i, x, y);
    for (int o = 0; o < c->nobs; o++)
      if (crowd_in_polygon(c->obs + 2 * c->obs_ptr[o], c->obs_ptr[o + 1] - c->obs_ptr[o], x, y))
        return fail_fmt(errmsg, CUP_ERR_ARG, "agent %d at (%g, %g) is inside obstacle %d", i, x, y, o);
    for (int s = 0; s < c->nseg; s++) {
      double px, py, d = crowd_seg_nearest(c->seg + 4 * s, x, y, &px, &py);
      if (d < c->r[i] - tol)
        return fail_fmt(errmsg, CUP_ERR_ARG, "agent %d at (%g, %g), radius %g, overlaps %s by %.3g", i, x, y,
                        c->r[i], wall_name(c, s, wb, sizeof wb), c->r[i] - d);
    }
  }
  worst_pair w = {INFINITY, -1, -1, 1};
  c->bound = INFINITY;
  crowd_each_pair(c, c->q0, crowd_note_worst, &w);
  double worst = w.gap;
  int wi = w.i, wj = w.j;
  if (worst < -tol)
    return fail_fmt(errmsg, CUP_ERR_ARG, "agents %d and %d overlap by %.3g (centres (%g, %g) and (%g, %g), radii %g and %g)",
                    wi, wj, -worst, c->q0[2 * wi], c->q0[2 * wi + 1], c->q0[2 * wj], c->q0[2 * wj + 1], c->r[wi], c->r[wj]);
  return CUP_OK;
}

/* Every agent can reach a door, and every door is reached by an agent:
 * connected components of the grid's reachable nodes. */
static int check_reach(cup_crowd *c, const cup_crowd_desc *d, char *errmsg) {
  const crowd_field *F = &c->F;
  size_t nn = (size_t)F->nx * F->ny;
  int *comp = malloc(sizeof(int) * nn), *queue = malloc(sizeof(int) * nn);
  int st = comp && queue ? CUP_OK : fail_fmt(errmsg, CUP_ERR_NOMEM, "crowd: out of memory");
  int ncomp = 0;
  if (!st) for (size_t s = 0; s < nn; s++) comp[s] = -1;
  for (size_t s = 0; !st && s < nn; s++) {
    if (!isfinite(F->D[s]) || comp[s] >= 0) continue;
    int qh = 0, qt = 0;
    queue[qt++] = (int)s;
    comp[s] = ncomp;
    while (qh < qt) {
      int k = queue[qh++], i = k % F->nx, j = k / F->nx;
      int nb[4] = {i > 0 ? k - 1 : -1, i + 1 < F->nx ? k + 1 : -1, j > 0 ? k - F->nx : -1, j + 1 < F->ny ? k + F->nx : -1};
      for (int e = 0; e < 4; e++)
        if (nb[e] >= 0 && comp[nb[e]] < 0 && isfinite(F->D[nb[e]])) { comp[nb[e]] = ncomp; queue[qt++] = nb[e]; }
    }
    ncomp++;
  }
  unsigned char *reached = st ? NULL : calloc((size_t)ncomp + 1, 1);
  if (!st && !reached) st = fail_fmt(errmsg, CUP_ERR_NOMEM, "crowd: out of memory");
  for (int i = 0; !st && i < c->N; i++) {
    double x = c->q0[2 * i], y = c->q0[2 * i + 1];
    int k = crowd_field_node(F, x, y), best = -1;
    double bd = INFINITY;
    for (int dj = -2; dj <= 2; dj++)               /* the nearest reachable node around the centre */
      for (int di = -2; di <= 2; di++) {
        int ii = k % F->nx + di, jj = k / F->nx + dj;
        if (ii < 0 || jj < 0 || ii >= F->nx || jj >= F->ny || !isfinite(F->D[ii + F->nx * jj])) continue;
        double dd = hypot(F->x0 + ii * F->h - x, F->y0 + jj * F->h - y);
        if (dd < bd) { bd = dd; best = ii + F->nx * jj; }
      }
    if (best < 0)
      st = fail_fmt(errmsg, CUP_ERR_ARG, "agent %d at (%g, %g) cannot reach any door (walls or obstacles "
                    "close it in)", i, x, y);
    else reached[comp[best]] = 1;
  }
  for (int k = 0; !st && k < d->doors; k++) {
    const double *s = d->door + 4 * k;
    int hit = 0;                               /* any node the door seeded, in a reached component */
    int i0 = (int)floor((fmin(s[0], s[2]) - 2 * F->h - F->x0) / F->h), i1 = (int)ceil((fmax(s[0], s[2]) + 2 * F->h - F->x0) / F->h);
    int j0 = (int)floor((fmin(s[1], s[3]) - 2 * F->h - F->y0) / F->h), j1 = (int)ceil((fmax(s[1], s[3]) + 2 * F->h - F->y0) / F->h);
    for (int j = j0 < 0 ? 0 : j0; j <= j1 && j < F->ny && !hit; j++)
      for (int i = i0 < 0 ? 0 : i0; i <= i1 && i < F->nx && !hit; i++) {
        double px, py;
        int node = i + F->nx * j;
        hit = isfinite(F->D[node]) && reached[comp[node]] &&
              crowd_seg_nearest(s, F->x0 + i * F->h, F->y0 + j * F->h, &px, &py) <= 1.5 * F->h;
      }
    if (!hit)
      st = fail_fmt(errmsg, CUP_ERR_ARG, "door %d (from (%g, %g) to (%g, %g)) cannot be reached by any agent "
                    "(walls or obstacles close it off)", k, s[0], s[1], s[2], s[3]);
  }
  free(reached);
  free(comp);
  free(queue);
  return st;
}

static int copy_desc(cup_crowd *c, const cup_crowd_desc *d, char *errmsg) {
  int N = c->N = d->agents, nv = 0;
  for (int o = 0; o < d->obstacles; o++) nv += d->obstacle_points[o];
  c->nroom = d->room_points;
  c->nobs = d->obstacles;
  c->ndoor = d->doors;
  c->q0 = malloc(sizeof(double) * 2 * (size_t)N);
  c->r = malloc(sizeof(double) * (size_t)N);
  c->room = malloc(sizeof(double) * 2 * (size_t)c->nroom);
  c->door = malloc(sizeof(double) * 4 * (size_t)c->ndoor);
  c->obs_ptr = malloc(sizeof(int) * ((size_t)c->nobs + 1));
  c->obs = malloc(sizeof(double) * (2 * (size_t)nv + 1));
  c->out = calloc((size_t)N, 1);
  c->exit_time = malloc(sizeof(double) * (size_t)N);
  c->kcell = malloc(sizeof(int) * (size_t)N);
  c->run_start = calloc((size_t)N, sizeof(int));   /* emit_rows reads it for agents with no rows, too */
  c->run_len = malloc(sizeof(int) * (size_t)N);
  c->stage_cap = 2 * N + 64;                 /* a crowd has about 1.5 N rows and patterns to come */
  c->stage = malloc(sizeof(crowd_entry) * (size_t)c->stage_cap);
  c->bin = malloc(sizeof(crowd_agent) * (size_t)N);
  if (!c->q0 || !c->r || !c->room || !c->door || !c->obs_ptr || !c->obs || !c->out || !c->exit_time ||
      !c->bin || !c->kcell || !c->run_start || !c->run_len || !c->stage)
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "crowd: out of memory");
  for (int i = 0; i < N; i++) c->bin[i].i = i;
  memcpy(c->q0, d->q0, sizeof(double) * 2 * (size_t)N);
  memcpy(c->r, d->radius, sizeof(double) * (size_t)N);
  memcpy(c->room, d->room, sizeof(double) * 2 * (size_t)c->nroom);
  memcpy(c->door, d->door, sizeof(double) * 4 * (size_t)c->ndoor);
  c->obs_ptr[0] = 0;
  for (int o = 0; o < c->nobs; o++) c->obs_ptr[o + 1] = c->obs_ptr[o] + d->obstacle_points[o];
  if (nv) memcpy(c->obs, d->obstacle, sizeof(double) * 2 * (size_t)nv);
  for (int i = 0; i < N; i++) c->exit_time[i] = NAN;
  c->inside = N;
  return CUP_OK;
}

/* The room's box, the grid step, the margins and the cells. */
static int set_scales(cup_crowd *c, const cup_crowd_desc *d, double h, double box[4], char *errmsg) {
  box[0] = box[2] = c->room[0];
  box[1] = box[3] = c->room[1];
  for (int v = 1; v < c->nroom; v++) {
    box[0] = fmin(box[0], c->room[2 * v]); box[2] = fmax(box[2], c->room[2 * v]);
    box[1] = fmin(box[1], c->room[2 * v + 1]); box[3] = fmax(box[3], c->room[2 * v + 1]);
  }
  double rmin = INFINITY, rsum = 0;
  c->rmax = 0;
  for (int i = 0; i < c->N; i++) {
    rmin = fmin(rmin, c->r[i]);
    c->rmax = fmax(c->rmax, c->r[i]);
    rsum += c->r[i];
  }
  c->speed = d->speed;
  c->h = h;
  /* a pushed agent may move several times h speed in a step (2.5 times is
   * common in a jam): a pair farther than the margin gets no row */
  c->margin = d->margin > 0 ? d->margin : fmax(4 * d->speed * h, rsum / c->N);
  c->reach = d->reach > 0 ? fmax(d->reach, c->margin) : 1.5 * c->margin;
  c->cell = 2 * c->rmax + c->reach;
  c->cx0 = box[0];
  c->cy0 = box[1];
  /* counted in double first: a huge room's count does not fit an int */
  double gx = floor((box[2] - box[0]) / c->cell) + 1, gy = floor((box[3] - box[1]) / c->cell) + 1;
  if (!(gx * gy <= 5e7))
    return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: the room (%g x %g) needs %.3g cells of side %g: too many",
                    box[2] - box[0], box[3] - box[1], gx * gy, c->cell);
  c->gx = (int)gx;
  c->gy = (int)gy;
  c->head = malloc(sizeof(int) * (size_t)c->gx * (size_t)c->gy);
  c->cell_ptr = malloc(sizeof(int) * ((size_t)c->gx * (size_t)c->gy + 1));
  if (!c->head || !c->cell_ptr) return fail_fmt(errmsg, CUP_ERR_NOMEM, "crowd: out of memory");
  return CUP_OK;
}

/* A door narrower than the smallest agent's diameter lets no one out (a
 * run ends with every agent inside): warned, not refused (the room may
 * have other doors, or the user may want the jam). */
static void door_warning(cup_crowd *c) {
  int small = 0, shut = 0, first = -1;
  for (int i = 1; i < c->N; i++)
    if (c->r[i] < c->r[small]) small = i;
  for (int k = 0; k < c->ndoor; k++) {
    const double *s = c->door + 4 * k;
    if (hypot(s[2] - s[0], s[3] - s[1]) < 2 * c->r[small] && shut++ == 0) first = k;
  }
  if (!shut) return;
  const double *s = c->door + 4 * first;
  int len = snprintf(c->warning, sizeof c->warning, "door %d (from (%g, %g) to (%g, %g)) is %.6g wide, narrower "
                     "than the smallest agent (agent %d, diameter %.6g): no agent can pass it", first, s[0], s[1],
                     s[2], s[3], hypot(s[2] - s[0], s[3] - s[1]), small, 2 * c->r[small]);
  if (shut > 1 && len > 0 && (size_t)len < sizeof c->warning)
    snprintf(c->warning + len, sizeof c->warning - (size_t)len, "%s (%d of the %d doors are so)",
             shut == c->ndoor ? "; nor any other door: no agent can leave" : "", shut, c->ndoor);
  else if (shut == c->ndoor && len > 0 && (size_t)len < sizeof c->warning)
    snprintf(c->warning + len, sizeof c->warning - (size_t)len, "; it is the only door: no agent can leave");
}

const char *cup_crowd_warning(const cup_crowd *c) { return c && c->warning[0] ? c->warning : NULL; }

int cup_crowd_create(cup_crowd **out, const cup_crowd_desc *d, double h, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: output pointer is NULL");
  *out = NULL;
  if (!d) return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: description is NULL");
  if (!(h > 0) || !isfinite(h)) return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: the step h = %g (must be > 0)", h);
  int st = check_numbers(d, errmsg);
  if (st) return st;
  cup_crowd *c = calloc(1, sizeof *c);
  if (!c) return fail_fmt(errmsg, CUP_ERR_NOMEM, "crowd: out of memory");
  double box[4];
  st = copy_desc(c, d, errmsg);
  if (!st) st = set_scales(c, d, h, box, errmsg);
  double size = fmax(box[2] - box[0], box[3] - box[1]), tol = 1e-9 * size;
  if (!st) st = build_walls(c, d, tol, errmsg);
  if (!st) st = bin_walls(c, errmsg);
  if (!st) st = inside_cells(c, tol, errmsg);
  if (!st) st = crowd_order_init(c, c->q0, errmsg);
  if (!st) st = check_agents(c, 1e-12 * size, errmsg);
  double grid = d->grid;
  if (!st && !(grid > 0)) {                    /* half the smallest radius, at most ~4 M nodes */
    double rmin = INFINITY;
    for (int i = 0; i < c->N; i++) rmin = fmin(rmin, c->r[i]);
    grid = fmax(0.5 * rmin, sqrt((box[2] - box[0] + 1) * (box[3] - box[1] + 1) / 4e6));
  }
  /* exact distances around the doors, where agents queue (four diameters) */
  if (!st) st = crowd_field_build(&c->F, c->room, c->nroom, c->seg, c->nseg, c->door, c->ndoor, box, grid,
                                  8 * c->rmax, d->clearance, errmsg);
  if (!st) st = check_reach(c, d, errmsg);
  if (!st) {
    cup_set_desc sd = {.kind = CUP_SET_STATE_POLYSET, .n = 2 * c->N, .rows = crowd_rows, .rows_ctx = c};
    st = cup_set_create(&c->S, &sd, errmsg);
    if (!st) st = set_on_recheck(c->S, crowd_recheck);
  }
  if (st) { cup_crowd_free(&c); return st; }
  door_warning(c);
  c->proc = (cup_process_desc){.n = 2 * c->N, .C = c->S, .f_integral = crowd_walk, .f_integral_ctx = c};
  *out = c;
  return CUP_OK;
}

void cup_crowd_free(cup_crowd **cp) {
  if (!cp || !*cp) return;
  cup_crowd *c = *cp;
  cup_set_free(&c->S);
  crowd_field_free(&c->F);
  free(c->q0); free(c->r); free(c->room); free(c->door); free(c->obs_ptr); free(c->obs);
  free(c->seg); free(c->seg_kind); free(c->seg_of); free(c->seg_part);
  free(c->head); free(c->cell_ptr); free(c->wptr); free(c->widx); free(c->cin);
  free(c->bin); free(c->kcell); free(c->run_start); free(c->run_len); free(c->stage);
  free(c->out); free(c->exit_time); free(c->forced);
  crowd_order_free(c);
  free(c);
  *cp = NULL;
}

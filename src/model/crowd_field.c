/* crowd_field — the distance to the doors around walls and obstacles, by
 * Sethian's fast marching method (first-order upwind solution of
 * |grad D| = 1 on a grid, nodes accepted in increasing order from a binary
 * heap), and the desired direction -grad D / |grad D| at every node. Set-up
 * only: built once when the crowd is created. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "util/linalg.h"
#include "crowd_impl.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

double crowd_seg_nearest(const double *s, double x, double y, double *px, double *py) {
  double dx = s[2] - s[0], dy = s[3] - s[1], L2 = dx * dx + dy * dy;
  double t = L2 > 0 ? ((x - s[0]) * dx + (y - s[1]) * dy) / L2 : 0;
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  *px = s[0] + t * dx;
  *py = s[1] + t * dy;
  return hypot(x - *px, y - *py);
}

/* The sign of the turn a -> b -> c (0: collinear). */
static int turn(const double *a, const double *b, const double *c) {
  double d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  return (d > 0) - (d < 0);
}

/* p, collinear with segment [a, b], lies on it. */
static int within(const double *a, const double *b, const double *p) {
  return fmin(a[0], b[0]) <= p[0] && p[0] <= fmax(a[0], b[0]) && fmin(a[1], b[1]) <= p[1] &&
         p[1] <= fmax(a[1], b[1]);
}

/* Segments [a, b] and [c, d] meet (crossing or touching). */
static int segments_meet(const double *a, const double *b, const double *c, const double *d) {
  int o1 = turn(a, b, c), o2 = turn(a, b, d), o3 = turn(c, d, a), o4 = turn(c, d, b);
  if (o1 * o2 < 0 && o3 * o4 < 0) return 1;
  return (!o1 && within(a, b, c)) || (!o2 && within(a, b, d)) || (!o3 && within(c, d, a)) ||
         (!o4 && within(c, d, b));
}

int crowd_polygon_crossing(const double *v, int np, int *ea, int *eb) {
  for (int a = 0; a < np; a++)
    for (int b = a + 1; b < np; b++) {
      const double *p0 = v + 2 * a, *p1 = v + 2 * ((a + 1) % np), *q0 = v + 2 * b, *q1 = v + 2 * ((b + 1) % np);
      int meet;
      if (b == a + 1 || (a == 0 && b == np - 1)) {   /* neighbours share a vertex: they may only fold back */
        const double *s = b == a + 1 ? p1 : p0, *u = b == a + 1 ? p0 : p1, *w = b == a + 1 ? q1 : q0;
        meet = !turn(s, u, w) && (u[0] - s[0]) * (w[0] - s[0]) + (u[1] - s[1]) * (w[1] - s[1]) > 0;
      } else {
        meet = segments_meet(p0, p1, q0, q1);
      }
      if (meet) {
        *ea = a;
        *eb = b;
        return 1;
      }
    }
  return 0;
}

int crowd_in_polygon(const double *v, int np, double x, double y) {
  int in = 0;
  for (int a = 0, b = np - 1; a < np; b = a++) {
    double xa = v[2 * a], ya = v[2 * a + 1], xb = v[2 * b], yb = v[2 * b + 1];
    if ((ya > y) != (yb > y) && x < xa + (y - ya) * (xb - xa) / (yb - ya)) in = !in;
  }
  return in;
}

/* ---- a binary heap of nodes keyed by D, with positions for decrease-key ---- */

typedef struct heap {
  int *a, *pos, len;      /* pos[node] = index in a, or -1 */
  const double *D;
} heap;

static void heap_swap(heap *H, int i, int j) {
  int t = H->a[i];
  H->a[i] = H->a[j];
  H->a[j] = t;
  H->pos[H->a[i]] = i;
  H->pos[H->a[j]] = j;
}

static void heap_up(heap *H, int i) {
  while (i > 0 && H->D[H->a[(i - 1) / 2]] > H->D[H->a[i]]) {
    heap_swap(H, i, (i - 1) / 2);
    i = (i - 1) / 2;
  }
}

static void heap_down(heap *H, int i) {
  for (;;) {
    int l = 2 * i + 1, r = l + 1, m = i;
    if (l < H->len && H->D[H->a[l]] < H->D[H->a[m]]) m = l;
    if (r < H->len && H->D[H->a[r]] < H->D[H->a[m]]) m = r;
    if (m == i) return;
    heap_swap(H, i, m);
    i = m;
  }
}

static void heap_push(heap *H, int node) {
  if (H->pos[node] >= 0) { heap_up(H, H->pos[node]); return; }   /* D decreased */
  H->a[H->len] = node;
  H->pos[node] = H->len++;
  heap_up(H, H->len - 1);
}

static int heap_pop(heap *H) {
  int top = H->a[0];
  H->pos[top] = -1;
  if (--H->len > 0) {
    H->a[0] = H->a[H->len];
    H->pos[H->a[0]] = 0;
    heap_down(H, 0);
  }
  return top;
}

/* ---- the march ------------------------------------------------------------------ */

/* Mark the nodes within `width` of a wall (rasterized segment by segment). */
static void block_walls(crowd_field *F, unsigned char *state, const double *seg, int nseg, double width) {
  double h = F->h;
  for (int s = 0; s < nseg; s++) {
    const double *w = seg + 4 * s;
    int i0 = (int)floor((fmin(w[0], w[2]) - width - F->x0) / h), i1 = (int)ceil((fmax(w[0], w[2]) + width - F->x0) / h);
    int j0 = (int)floor((fmin(w[1], w[3]) - width - F->y0) / h), j1 = (int)ceil((fmax(w[1], w[3]) + width - F->y0) / h);
    for (int j = j0 < 0 ? 0 : j0; j <= j1 && j < F->ny; j++)
      for (int i = i0 < 0 ? 0 : i0; i <= i1 && i < F->nx; i++) {
        double px, py;
        if (crowd_seg_nearest(w, F->x0 + i * h, F->y0 + j * h, &px, &py) < width) state[i + F->nx * j] = 3;
      }
  }
}

/* The first-order upwind value at node k from its accepted neighbours. */
static double upwind(const crowd_field *F, const unsigned char *state, int k) {
  int i = k % F->nx, j = k / F->nx;
  double a = INFINITY, b = INFINITY, h = F->h;
  if (i > 0 && state[k - 1] == 2) a = F->D[k - 1];
  if (i + 1 < F->nx && state[k + 1] == 2) a = fmin(a, F->D[k + 1]);
  if (j > 0 && state[k - F->nx] == 2) b = F->D[k - F->nx];
  if (j + 1 < F->ny && state[k + F->nx] == 2) b = fmin(b, F->D[k + F->nx]);
  if (isinf(a) && isinf(b)) return INFINITY;
  if (fabs(a - b) >= h) return fmin(a, b) + h;
  return 0.5 * (a + b + sqrt(2 * h * h - (a - b) * (a - b)));
}

/* The descent direction at every node: central differences where both
 * neighbours are finite, one-sided where one is. */
static void directions(crowd_field *F, const unsigned char *exact) {
  int nx = F->nx, ny = F->ny;
  for (int j = 0; j < ny; j++)
    for (int i = 0; i < nx; i++) {
      int k = i + nx * j;
      if (exact[k]) continue;
      F->ux[k] = F->uy[k] = 0;
      if (!isfinite(F->D[k])) continue;
      double g[2];
      for (int a = 0; a < 2; a++) {
        int lo = a == 0 ? i > 0 : j > 0, hi = a == 0 ? i + 1 < nx : j + 1 < ny, step = a == 0 ? 1 : nx;
        double dm = lo ? F->D[k - step] : INFINITY, dp = hi ? F->D[k + step] : INFINITY;
        if (isfinite(dm) && isfinite(dp)) g[a] = (dp - dm) / (2 * F->h);
        else if (isfinite(dp)) g[a] = (dp - F->D[k]) / F->h;
        else if (isfinite(dm)) g[a] = (F->D[k] - dm) / F->h;
        else g[a] = 0;
      }
      double nrm = hypot(g[0], g[1]);
      if (nrm > 0) { F->ux[k] = (float)(-g[0] / nrm); F->uy[k] = (float)(-g[1] / nrm); }
    }
}

/* Do segments a-b and c-d cross at a point interior to both? (Touching at
 * an end, as a line to a door's end touches the wall there, does not.) */
static int crosses(const double *a, const double *b, const double *c, const double *d) {
  double d1 = (d[0] - c[0]) * (a[1] - c[1]) - (d[1] - c[1]) * (a[0] - c[0]);
  double d2 = (d[0] - c[0]) * (b[1] - c[1]) - (d[1] - c[1]) * (b[0] - c[0]);
  double d3 = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  double d4 = (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]);
  return d1 * d2 < 0 && d3 * d4 < 0;
}

/* Does the segment a-b keep a clearance c > 0 from the segment w? Two
 * segments that do not cross are nearest at an end of one of them. */
static int keeps_clear(const double *a, const double *b, const double *w, double c) {
  if (crosses(a, b, w, w + 2)) return 0;
  double p[2], ab[4] = {a[0], a[1], b[0], b[1]};
  double d = fmin(crowd_seg_nearest(w, a[0], a[1], &p[0], &p[1]), crowd_seg_nearest(w, b[0], b[1], &p[0], &p[1]));
  d = fmin(d, fmin(crowd_seg_nearest(ab, w[0], w[1], &p[0], &p[1]), crowd_seg_nearest(ab, w[2], w[3], &p[0], &p[1])));
  return d >= c * (1 - 1e-9);
}

/* The length of the way from P round the disc (J, c) to E on its rim: the
 * tangent from P, then the shorter arc, on the side that stays in the room
 * and keeps c from every wall; INFINITY if neither side does. u: the unit
 * direction P heads in (along the rim where P is on it). */
static double round_jamb(const double *P, const double *J, const double *E, double c, const double *seg, int nseg,
                         const double *room, int nroom, double *u) {
  double L = hypot(P[0] - J[0], P[1] - J[1]), best = INFINITY;
  if (!(L > c * (1 - 1e-9))) return best;
  double phi = atan2(P[1] - J[1], P[0] - J[0]), alpha = acos(fmin(1, c / L)), psi = atan2(E[1] - J[1], E[0] - J[0]);
  double tl = sqrt(fmax(0, L * L - c * c));
  for (int side = -1; side <= 1; side += 2) {
    double th = phi + side * alpha, turn = remainder(psi - th, 2 * M_PI), mid = th + turn / 2;
    double T[2] = {J[0] + c * cos(th), J[1] + c * sin(th)};
    if (!crowd_in_polygon(room, nroom, J[0] + c * cos(mid), J[1] + c * sin(mid))) continue;
    int clear = 1;
    for (int w = 0; w < nseg && clear && tl > 1e-9 * c; w++) clear = keeps_clear(P, T, seg + 4 * w, c);
    double d = tl + c * fabs(turn);
    if (!clear || !(d < best)) continue;
    best = d;
    if (tl > 1e-9 * c) { u[0] = (T[0] - P[0]) / tl; u[1] = (T[1] - P[1]) / tl; }
    else { u[0] = -sin(th) * (turn > 0 ? 1 : -1); u[1] = cos(th) * (turn > 0 ? 1 : -1); }
  }
  return best;
}

/* The door shrunk by c at both ends. */
static void shrink_door(const double *door, double c, double s[4]) {
  double t = c / hypot(door[2] - door[0], door[3] - door[1]);
  s[0] = door[0] + t * (door[2] - door[0]);
  s[1] = door[1] + t * (door[3] - door[1]);
  s[2] = door[2] - t * (door[2] - door[0]);
  s[3] = door[3] - t * (door[3] - door[1]);
}

/* The shortest way from node to the door shrunk by c (s) for a centre
 * keeping c from the walls: straight to the nearest point of s if that line
 * keeps c from every wall (and, with off_door, the node is not on s), else
 * round the disc (an end of the door, c) that the line cut. Returns its
 * length, INFINITY if there is none; u its unit direction (0 on s). */
static double way_out(const double *node, const double *door, const double *s, double c, int off_door,
                      const double *seg, int nseg, const double *room, int nroom, double *u) {
  double p[2], dist = crowd_seg_nearest(s, node[0], node[1], &p[0], &p[1]);
  int seen = !off_door || dist > 0;
  for (int w = 0; w < nseg && seen && c > 0; w++) seen = keeps_clear(node, p, seg + 4 * w, c);
  u[0] = dist > 0 ? (p[0] - node[0]) / dist : 0;
  u[1] = dist > 0 ? (p[1] - node[1]) / dist : 0;
  if (seen) return dist;
  double u2[2], d2 = round_jamb(node, door + 2, s + 2, c, seg, nseg, room, nroom, u2);
  dist = round_jamb(node, door, s, c, seg, nseg, room, nroom, u);
  if (d2 < dist) { dist = d2; u[0] = u2[0]; u[1] = u2[1]; }
  return dist;
}

/* The direction at a node whose own clearance cw (its distance to the
 * nearest wall) is less than the field's: its way out for a centre
 * keeping cw. */
static void band_direction(crowd_field *F, unsigned char *exact, int k, const double *node, const double *door,
                           const double *seg, int nseg, const double *room, int nroom, double cw) {
  double s[4], u[2];
  shrink_door(door, cw, s);
  if (!isfinite(way_out(node, door, s, cw, 1, seg, nseg, room, nroom, u))) return;
  exact[k] = 1;
  F->ux[k] = (float)u[0];
  F->uy[k] = (float)u[1];
}

/* Start the march near door s. With a clearance c > 0: at the free nodes
 * within R of the door, at their exact distance to the door shrunk by c at
 * both ends, for a centre keeping c from the walls (straight to the nearest
 * point of the shrunk door if that line keeps c from every wall, else round
 * the disc (end of the door, c) that the line cut), and with their exact
 * direction. Started from the nodes next to the door only, the march
 * treats each end of the door as a point source, where a first-order
 * scheme is worst: the directions around the door's ends, the ones agents
 * follow into the door, were off by up to 50 degrees at h = 0.1 and 30 at
 * 0.05 (pointing into the door instead of at its end); marched round the
 * discs from exact values elsewhere they were off by 35 degrees at both
 * steps (the march's O(h) error against exact values across a line is an
 * O(1) error of the differences there); and beside a door's edge the
 * direction turns round the disc like the square root of the distance to
 * its rim, which differences tilt into the wall. Without a clearance (0:
 * cromosim's field computed as cromosim computes it, so that the two can be
 * compared): at the nodes within 1.5 h of the door, which the march may
 * still lower. Returns the nodes seeded within 1.5 h of the door (none: the
 * grid is too coarse for it). */
static int seed_door(crowd_field *F, unsigned char *state, heap *H, const double *door, const double *seg, int nseg,
                     const double *room, int nroom, double R, double c, unsigned char *exact) {
  double h = F->h, s[4];
  int seeds = 0;
  shrink_door(door, c, s);
  R = c > 0 ? fmax(R, 1.5 * h) : 1.5 * h;
  int i0 = (int)floor((fmin(s[0], s[2]) - R - F->x0) / h), i1 = (int)ceil((fmax(s[0], s[2]) + R - F->x0) / h);
  int j0 = (int)floor((fmin(s[1], s[3]) - R - F->y0) / h), j1 = (int)ceil((fmax(s[1], s[3]) + R - F->y0) / h);
  for (int j = j0 < 0 ? 0 : j0; j <= j1 && j < F->ny; j++)
    for (int i = i0 < 0 ? 0 : i0; i <= i1 && i < F->nx; i++) {
      int k = i + F->nx * j;
      double node[2] = {F->x0 + i * h, F->y0 + j * h}, p[2], cw = c;
      double dist = crowd_seg_nearest(s, node[0], node[1], &p[0], &p[1]);
      if (dist > R || (state[k] == 3 && !(c > 0 && crowd_in_polygon(room, nroom, node[0], node[1])))) continue;
      if (state[k] == 3) {
        /* a node in the band along the walls: no distance (the march keeps
         * out), but the direction of the clearance it has, so that the
         * directions interpolated between it and the free nodes turn round
         * the door's edges as the exact ones do */
        for (int w = 0; w < nseg; w++) cw = fmin(cw, crowd_seg_nearest(seg + 4 * w, node[0], node[1], &p[0], &p[1]));
        cw *= 1 - 1e-9;
        if (!(cw > 0)) continue;
        band_direction(F, exact, k, node, door, seg, nseg, room, nroom, cw);
        continue;
      }
      double u[2];
      dist = way_out(node, door, s, c, 0, seg, nseg, room, nroom, u);
      if (!(dist <= R)) continue;
      seeds += dist <= 1.5 * h;
      if (!(dist < F->D[k])) continue;
      F->D[k] = dist;
      state[k] = c > 0 ? 4 : 1;
      heap_push(H, k);
      if (c > 0 && (u[0] != 0 || u[1] != 0)) {
        exact[k] = 1;
        F->ux[k] = (float)u[0];
        F->uy[k] = (float)u[1];
      }
    }
  return seeds;
}

int crowd_field_build(crowd_field *F, const double *room, int nroom, const double *seg, int nseg,
                      const double *door, int ndoor, const double box[4], double h, double seed_radius,
                      double clearance, char *errmsg) {
  memset(F, 0, sizeof *F);
  F->h = h;
  F->x0 = box[0] - 2 * h;
  F->y0 = box[1] - 2 * h;
  double nx = ceil((box[2] - box[0]) / h) + 5, ny = ceil((box[3] - box[1]) / h) + 5;  /* may not fit an int */
  if (!(nx * ny <= 1e8))
    return fail_fmt(errmsg, CUP_ERR_ARG, "crowd: the distance grid would have %.3g nodes (step %g): "
                    "make the grid step larger", nx * ny, h);
  F->nx = (int)nx;
  F->ny = (int)ny;
  size_t nn = (size_t)F->nx * (size_t)F->ny;
  F->D = malloc(sizeof(double) * nn);
  F->ux = malloc(sizeof(float) * nn);
  F->uy = malloc(sizeof(float) * nn);
  unsigned char *state = calloc(nn, 1);      /* 0 far, 1 trial, 2 accepted, 3 blocked, 4 exact trial */
  unsigned char *exact = calloc(nn, 1);      /* 1: the direction is known exactly */
  heap H = {malloc(sizeof(int) * nn), malloc(sizeof(int) * nn), 0, F->D};
  int st = F->D && F->ux && F->uy && state && exact && H.a && H.pos ? CUP_OK
           : fail_fmt(errmsg, CUP_ERR_NOMEM, "crowd: out of memory for the distance grid");
  if (!st) {
    for (size_t k = 0; k < nn; k++) { F->D[k] = INFINITY; H.pos[k] = -1; }
    block_walls(F, state, seg, nseg, fmax(h, clearance));
    for (int j = 0; j < F->ny; j++)            /* the front stays in the room */
      for (int i = 0; i < F->nx; i++)
        if (!crowd_in_polygon(room, nroom, F->x0 + i * h, F->y0 + j * h)) state[i + F->nx * j] = 3;
    for (int d = 0; d < ndoor && !st; d++) {
      const double *s = door + 4 * d;
      double len = hypot(s[2] - s[0], s[3] - s[1]);
      if (!(len > 2 * clearance)) {
        st = fail_fmt(errmsg, CUP_ERR_ARG, "door %d (from (%g, %g) to (%g, %g)) is %g wide: no wider than twice "
                      "the clearance %g, no centre can pass it", d, s[0], s[1], s[2], s[3], len, clearance);
        break;
      }
      if (!seed_door(F, state, &H, s, seg, nseg, room, nroom, fmax(seed_radius, len), clearance, exact))
        st = fail_fmt(errmsg, CUP_ERR_ARG, "door %d (from (%g, %g) to (%g, %g)) is too narrow for the distance "
                      "grid (step %g): every grid node near it is within one step of a wall; make the grid "
                      "step smaller", d, s[0], s[1], s[2], s[3], h);
    }
  }
  while (!st && H.len > 0) {
    int k = heap_pop(&H);
    state[k] = 2;
    int i = k % F->nx, j = k / F->nx;
    int nb[4] = {i > 0 ? k - 1 : -1, i + 1 < F->nx ? k + 1 : -1, j > 0 ? k - F->nx : -1,
                 j + 1 < F->ny ? k + F->nx : -1};
    for (int e = 0; e < 4; e++) {
      int q = nb[e];
      if (q < 0 || state[q] >= 2) continue;
      double v = upwind(F, state, q);
      if (v < F->D[q]) { F->D[q] = v; state[q] = 1; heap_push(&H, q); }
    }
  }
  if (!st) directions(F, exact);
  free(state);
  free(exact);
  free(H.a);
  free(H.pos);
  if (st) crowd_field_free(F);
  return st;
}

void crowd_field_free(crowd_field *F) {
  free(F->D);
  free(F->ux);
  free(F->uy);
  memset(F, 0, sizeof *F);
}

int crowd_field_node(const crowd_field *F, double x, double y) {
  int i = (int)lround((x - F->x0) / F->h), j = (int)lround((y - F->y0) / F->h);
  i = i < 0 ? 0 : i >= F->nx ? F->nx - 1 : i;
  j = j < 0 ? 0 : j >= F->ny ? F->ny - 1 : j;
  return i + F->nx * j;
}

/* The four nodes around (x, y) and their bilinear weights (0 off the grid). */
static void corners(const crowd_field *F, double x, double y, int k[4], double w[4]) {
  double fx = (x - F->x0) / F->h, fy = (y - F->y0) / F->h;
  int i = (int)floor(fx), j = (int)floor(fy);
  double ax = fx - i, ay = fy - j;
  for (int c = 0; c < 4; c++) {
    int ii = i + (c & 1), jj = j + (c >> 1);
    w[c] = (c & 1 ? ax : 1 - ax) * (c >> 1 ? ay : 1 - ay);
    k[c] = ii >= 0 && jj >= 0 && ii < F->nx && jj < F->ny ? ii + F->nx * jj : -1;
  }
}

double crowd_field_distance(const crowd_field *F, double x, double y) {
  int k[4];
  double w[4], sum = 0, wsum = 0;
  corners(F, x, y, k, w);
  for (int c = 0; c < 4; c++)
    if (k[c] >= 0 && isfinite(F->D[k[c]]) && w[c] > 0) { sum += w[c] * F->D[k[c]]; wsum += w[c]; }
  return wsum > 0 ? sum / wsum : INFINITY;
}

void crowd_field_direction(const crowd_field *F, double x, double y, double *u) {
  int k[4];
  double w[4], ux = 0, uy = 0;
  corners(F, x, y, k, w);
  for (int c = 0; c < 4; c++)
    if (k[c] >= 0) { ux += w[c] * F->ux[k[c]]; uy += w[c] * F->uy[k[c]]; }
  double nrm = hypot(ux, uy);
  u[0] = nrm > 0 ? ux / nrm : 0;
  u[1] = nrm > 0 ? uy / nrm : 0;
}

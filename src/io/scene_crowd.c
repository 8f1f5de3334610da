/* scene_crowd — the `crowd:` key of a scene (docs/crowd.md): a room, its
 * doors, obstacles and walls, the agents (a list, or N placed at random in a
 * region with radius r +- spread from a seed), the desired speed and the
 * grid. Errors name FILE:LINE:COL and the key, down to the agent, the door
 * or the obstacle the crowd's own checks (cup_crowd_create) complain of. */
#define _POSIX_C_SOURCE 200809L
#include <limits.h>
#include <stdint.h>
#include "scene_crowd.h"
#include "model/crowd_impl.h"

/* The geometry as read, owned until the crowd has copied it. */
typedef struct crowd_parts {
  double *room, *door, *obs, *wall, *q, *r;
  int *obs_pts;
  int nroom, ndoor, nobs, nobs_v, nwall, N;
  const st_node *room_at, *doors_at, *obs_at, *walls_at, *agents_at, *count_at;
  int listed;                      /* agents given one by one */
} crowd_parts;

static void parts_free(crowd_parts *c) {
  free(c->room); free(c->door); free(c->obs); free(c->wall); free(c->q); free(c->r); free(c->obs_pts);
}

/* [x, y] */
static int point(rd *r, const st_node *nd, const char *key, double *xy) {
  char k[KEY_LEN], b[64];
  if (nd->kind != ST_SEQ || nd->len != 2)
    return fail(r, CUP_ERR_PARSE, nd, key, "expected a point [x, y] (got %s)", st_looks(nd, b, sizeof b));
  int st = number(r, nd->item[0], joini(k, key, 0), &xy[0]);
  return st ? st : number(r, nd->item[1], joini(k, key, 1), &xy[1]);
}

/* A list of at least `least` points into a new array (2 per point). */
static int points(rd *r, const st_node *nd, const char *key, int least, double **out, int *count) {
  char k[KEY_LEN], b[64];
  if (nd->kind != ST_SEQ || nd->len < least)
    return fail(r, CUP_ERR_PARSE, nd, key, "expected a list of at least %d points [x, y] (got %s)", least,
                st_looks(nd, b, sizeof b));
  *out = malloc(sizeof(double) * 2 * (size_t)nd->len);
  if (!*out) return CUP_ERR_NOMEM;
  *count = nd->len;
  int st = CUP_OK;
  for (int k2 = 0; k2 < nd->len && !st; k2++) st = point(r, nd->item[k2], joini(k, key, k2), *out + 2 * k2);
  return st;
}

/* A list of segments [[x0, y0], [x1, y1]] into 4 numbers each. */
static int segments(rd *r, const st_node *nd, const char *key, double **out, int *count) {
  char k[KEY_LEN], b[64];
  if (nd->kind != ST_SEQ)
    return fail(r, CUP_ERR_PARSE, nd, key, "expected a list of segments [[x0, y0], [x1, y1]] (got %s)",
                st_looks(nd, b, sizeof b));
  *out = malloc(sizeof(double) * (4 * (size_t)nd->len + 1));
  if (!*out) return CUP_ERR_NOMEM;
  *count = nd->len;
  int st = CUP_OK;
  for (int s = 0; s < nd->len && !st; s++) {
    double *p = NULL;
    int np = 0;
    const char *ks = joini(k, key, s);
    st = points(r, nd->item[s], ks, 2, &p, &np);
    if (!st && np != 2)
      st = fail(r, CUP_ERR_PARSE, nd->item[s], ks, "expected a segment [[x0, y0], [x1, y1]] (got %d points)", np);
    if (!st) memcpy(*out + 4 * s, p, sizeof(double) * 4);
    free(p);
  }
  return st;
}

/* Obstacles: polygons, or {center: [x, y], radius: R} (a 32-gon around the
 * circle, so that the disk is inside it). */
static int obstacles(rd *r, const st_node *nd, const char *key, crowd_parts *c) {
  static const char *const known[] = {"center", "radius", NULL};
  char k[KEY_LEN], k2[KEY_LEN], b[64];
  if (nd->kind != ST_SEQ)
    return fail(r, CUP_ERR_PARSE, nd, key, "expected a list of polygons or circles (got %s)", st_looks(nd, b, sizeof b));
  int cap = 64;
  c->obs = malloc(sizeof(double) * 2 * (size_t)cap);
  c->obs_pts = malloc(sizeof(int) * ((size_t)nd->len + 1));
  if (!c->obs || !c->obs_pts) return CUP_ERR_NOMEM;
  int st = CUP_OK;
  for (int o = 0; o < nd->len && !st; o++) {
    const st_node *it = nd->item[o];
    const char *ko = joini(k, key, o);
    double *p = NULL;
    int np = 0;
    if (it->kind == ST_MAP) {
      const st_node *cn, *rn;
      double ctr[2], rad = 0;
      st = check_keys(r, it, ko, known);
      if (!st) st = need(r, it, ko, "center", &cn);
      if (!st) st = point(r, cn, join(k2, ko, "center"), ctr);
      if (!st) st = need(r, it, ko, "radius", &rn);
      if (!st) st = number_min(r, rn, join(k2, ko, "radius"), 0, 1, &rad);
      if (!st && !(p = malloc(sizeof(double) * 64))) st = CUP_ERR_NOMEM;
      for (int v = 0; !st && v < 32; v++) {   /* circumscribed: the edges' midpoints on the circle */
        double a = 2 * 3.14159265358979323846 * v / 32, R = rad / cos(3.14159265358979323846 / 32);
        p[2 * v] = ctr[0] + R * cos(a);
        p[2 * v + 1] = ctr[1] + R * sin(a);
      }
      np = 32;
    } else {
      st = points(r, it, ko, 3, &p, &np);
    }
    while (!st && c->nobs_v + np > cap) {
      cap *= 2;
      double *g = realloc(c->obs, sizeof(double) * 2 * (size_t)cap);
      if (!g) st = CUP_ERR_NOMEM;
      else c->obs = g;
    }
    if (!st) {
      memcpy(c->obs + 2 * c->nobs_v, p, sizeof(double) * 2 * (size_t)np);
      c->nobs_v += np;
      c->obs_pts[c->nobs++] = np;
    }
    free(p);
  }
  return st;
}

/* ---- agents ------------------------------------------------------------------- */

/* [[x, y, r], ...] */
static int agent_list(rd *r, const st_node *nd, crowd_parts *c) {
  char k[KEY_LEN], k2[KEY_LEN], b[64];
  if (nd->len == 0)
    return fail(r, CUP_ERR_PARSE, nd, "crowd.agents", "expected at least one agent [x, y, r] (got an empty list)");
  c->N = nd->len;
  c->q = malloc(sizeof(double) * 2 * (size_t)c->N);
  c->r = malloc(sizeof(double) * (size_t)c->N);
  if (!c->q || !c->r) return CUP_ERR_NOMEM;
  c->listed = 1;
  int st = CUP_OK;
  for (int i = 0; i < c->N && !st; i++) {
    const st_node *a = nd->item[i];
    const char *ka = joini(k, "crowd.agents", i);
    if (a->kind != ST_SEQ || a->len != 3)
      return fail(r, CUP_ERR_PARSE, a, ka, "expected an agent [x, y, radius] (got %s)", st_looks(a, b, sizeof b));
    st = number(r, a->item[0], joini(k2, ka, 0), &c->q[2 * i]);
    if (!st) st = number(r, a->item[1], joini(k2, ka, 1), &c->q[2 * i + 1]);
    if (!st) st = number_min(r, a->item[2], joini(k2, ka, 2), 0, 1, &c->r[i]);
  }
  return st;
}

typedef struct { uint64_t s; } splitmix;
static double unif(splitmix *g) {               /* splitmix64: the same numbers everywhere */
  uint64_t z = (g->s += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return (double)((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
}

/* Is a disk at (x, y) of radius rad in the room, out of the obstacles and
 * clear of every edge (doorways count as walls here)? */
static int clear_of_walls(const crowd_parts *c, double x, double y, double rad) {
  double px, py;
  if (!crowd_in_polygon(c->room, c->nroom, x, y)) return 0;
  for (int e = 0; e < c->nroom; e++) {
    double s[4] = {c->room[2 * e], c->room[2 * e + 1], c->room[2 * ((e + 1) % c->nroom)], c->room[2 * ((e + 1) % c->nroom) + 1]};
    if (crowd_seg_nearest(s, x, y, &px, &py) < rad) return 0;
  }
  for (int o = 0, v0 = 0; o < c->nobs; v0 += c->obs_pts[o++]) {
    const double *v = c->obs + 2 * v0;
    int np = c->obs_pts[o];
    if (crowd_in_polygon(v, np, x, y)) return 0;
    for (int e = 0; e < np; e++) {
      double s[4] = {v[2 * e], v[2 * e + 1], v[2 * ((e + 1) % np)], v[2 * ((e + 1) % np) + 1]};
      if (crowd_seg_nearest(s, x, y, &px, &py) < rad) return 0;
    }
  }
  for (int w = 0; w < c->nwall; w++)
    if (crowd_seg_nearest(c->wall + 4 * w, x, y, &px, &py) < rad) return 0;
  return 1;
}

/* Random sequential addition: each agent tries up to 2000 uniform points of
 * the region until one is clear of the walls and of the agents placed
 * (found with a grid of cells of side 2 (r + spread)). */
static int place_random(rd *r, const st_node *map, crowd_parts *c, double box[4], double rad, double spread,
                        uint64_t seed) {
  double cell = 2 * (rad + spread);
  int gx = (int)((box[2] - box[0]) / cell) + 1, gy = (int)((box[3] - box[1]) / cell) + 1;
  if ((double)gx * gy > 1e8)
    return fail(r, CUP_ERR_PARSE, map, "crowd.agents.region", "too large for agents of radius %g", rad);
  int *head = malloc(sizeof(int) * (size_t)gx * (size_t)gy), *next = malloc(sizeof(int) * (size_t)c->N);
  if (!head || !next) { free(head); free(next); return CUP_ERR_NOMEM; }
  for (long k = 0; k < (long)gx * gy; k++) head[k] = -1;
  splitmix g = {seed};
  int st = CUP_OK;
  for (int i = 0; i < c->N && !st; i++) {
    double ri = rad + spread * (2 * unif(&g) - 1);
    int ok = 0;
    for (int tr = 0; tr < 2000 && !ok; tr++) {
      double x = box[0] + (box[2] - box[0]) * unif(&g), y = box[1] + (box[3] - box[1]) * unif(&g);
      if (!clear_of_walls(c, x, y, ri)) continue;
      int ci = (int)((x - box[0]) / cell), cj = (int)((y - box[1]) / cell);
      ok = 1;
      for (int dj = -1; dj <= 1 && ok; dj++)
        for (int di = -1; di <= 1 && ok; di++) {
          int a = ci + di, b = cj + dj;
          if (a < 0 || b < 0 || a >= gx || b >= gy) continue;
          for (int j = head[a + gx * b]; j >= 0 && ok; j = next[j])
            ok = hypot(x - c->q[2 * j], y - c->q[2 * j + 1]) >= ri + c->r[j];
        }
      if (ok) {
        c->q[2 * i] = x;
        c->q[2 * i + 1] = y;
        c->r[i] = ri;
        next[i] = head[ci + gx * cj];
        head[ci + gx * cj] = i;
      }
    }
    if (!ok)
      st = fail(r, CUP_ERR_PARSE, c->count_at, "crowd.agents.count",
                "could place only %d of %d agents (radius %g +- %g) in the region without overlaps (2000 tries "
                "for the next one): give fewer agents or a larger region", i, c->N, rad, spread);
  }
  free(head);
  free(next);
  return st;
}

/* {count: N, radius: r, spread: d, region: [xmin, ymin, xmax, ymax], seed: s} */
static int agent_random(rd *r, const st_node *map, crowd_parts *c) {
  static const char *const known[] = {"count", "radius", "spread", "region", "seed", NULL};
  const st_node *nd;
  long count = 0, seed = 0;
  double rad = 0, spread = 0, box[4];
  int st = check_keys(r, map, "crowd.agents", known);
  if (!st) st = need(r, map, "crowd.agents", "count", &nd);
  if (!st) { c->count_at = nd; st = integer(r, nd, "crowd.agents.count", 1, 100000000, &count); }
  if (!st) st = need(r, map, "crowd.agents", "radius", &nd);
  if (!st) st = number_min(r, nd, "crowd.agents.radius", 0, 1, &rad);
  if (!st && (nd = opt(map, "spread"))) {
    st = number_min(r, nd, "crowd.agents.spread", 0, 0, &spread);
    if (!st && !(spread < rad)) st = fail(r, CUP_ERR_PARSE, nd, "crowd.agents.spread", "must be < radius %g (got %g)", rad, spread);
  }
  if (!st && (nd = opt(map, "seed"))) st = integer(r, nd, "crowd.agents.seed", 0, LONG_MAX, &seed);
  box[0] = box[2] = c->room[0];
  box[1] = box[3] = c->room[1];
  for (int v = 1; v < c->nroom; v++) {
    box[0] = fmin(box[0], c->room[2 * v]); box[2] = fmax(box[2], c->room[2 * v]);
    box[1] = fmin(box[1], c->room[2 * v + 1]); box[3] = fmax(box[3], c->room[2 * v + 1]);
  }
  if (!st && (nd = opt(map, "region"))) {
    double *v = NULL;
    st = vector(r, nd, "crowd.agents.region", 4, "xmin, ymin, xmax, ymax", &v);
    if (!st && !(v[0] < v[2] && v[1] < v[3]))
      st = fail(r, CUP_ERR_PARSE, nd, "crowd.agents.region", "expected xmin < xmax and ymin < ymax");
    if (!st) memcpy(box, v, sizeof box);
    free(v);
  }
  if (st) return st;
  c->N = (int)count;
  c->q = malloc(sizeof(double) * 2 * (size_t)c->N);
  c->r = malloc(sizeof(double) * (size_t)c->N);
  if (!c->q || !c->r) return CUP_ERR_NOMEM;
  return place_random(r, map, c, box, rad, spread, (uint64_t)seed);
}

/* ---- the crowd ------------------------------------------------------------------ */

/* The node a message of cup_crowd_create points at: "agent 17 ...",
 * "agents 12 and 40 ...", "door 2 ...", "obstacle 1 ..." (or the crowd). */
static const st_node *culprit(const crowd_parts *c, const st_node *map, const char *msg, char *key) {
  int i;
  if ((sscanf(msg, "agent %d", &i) == 1 || sscanf(msg, "agents %d", &i) == 1) && i >= 0 && i < c->N) {
    if (c->listed) { joini(key, "crowd.agents", i); return c->agents_at->item[i]; }
    strcpy(key, "crowd.agents");
    return c->agents_at;
  }
  if (!strncmp(msg, "the room", 8)) { strcpy(key, "crowd.room"); return c->room_at; }
  if (!strncmp(msg, "the clearance", 13) && opt(map, "clearance")) { strcpy(key, "crowd.clearance"); return opt(map, "clearance"); }
  if (sscanf(msg, "door %d", &i) == 1 && i >= 0 && i < c->ndoor) { joini(key, "crowd.doors", i); return c->doors_at->item[i]; }
  const char *o = strstr(msg, "obstacle ");
  if (o && sscanf(o, "obstacle %d", &i) == 1 && i >= 0 && i < c->nobs) { joini(key, "crowd.obstacles", i); return c->obs_at->item[i]; }
  strcpy(key, "crowd");
  return map;
}

int scene_read_crowd(rd *r, const st_node *map, double h, cup_crowd **out) {
  static const char *const known[] = {"room", "doors", "obstacles", "walls", "agents", "speed", "grid",
                                      "margin", "reach", "clearance", NULL};
  crowd_parts c = {0};
  cup_crowd_desc d = {.speed = 1};
  const st_node *nd;
  char key[KEY_LEN], lib[CUP_ERRMSG_LEN];
  int st = need_map(r, map, "crowd", "a mapping with room, doors, agents and speed");
  if (!st) st = check_keys(r, map, "crowd", known);
  if (!st) st = need(r, map, "crowd", "room", &c.room_at);
  if (!st) st = points(r, c.room_at, "crowd.room", 3, &c.room, &c.nroom);
  if (!st) st = need(r, map, "crowd", "doors", &c.doors_at);
  if (!st) st = segments(r, c.doors_at, "crowd.doors", &c.door, &c.ndoor);
  if (!st && c.ndoor == 0) st = fail(r, CUP_ERR_PARSE, c.doors_at, "crowd.doors", "expected at least one door");
  if (!st && (c.obs_at = opt(map, "obstacles"))) st = obstacles(r, c.obs_at, "crowd.obstacles", &c);
  if (!st && (c.walls_at = opt(map, "walls"))) st = segments(r, c.walls_at, "crowd.walls", &c.wall, &c.nwall);
  if (!st) st = need(r, map, "crowd", "agents", &c.agents_at);
  if (!st) {
    if (c.agents_at->kind == ST_SEQ) st = agent_list(r, c.agents_at, &c);
    else if (c.agents_at->kind == ST_MAP) st = agent_random(r, c.agents_at, &c);
    else st = fail(r, CUP_ERR_PARSE, c.agents_at, "crowd.agents", "expected a list of agents [x, y, radius] or "
                   "{count: N, radius: r, spread: d, region: [xmin, ymin, xmax, ymax], seed: s}");
  }
  double *num[5] = {&d.speed, &d.grid, &d.margin, &d.reach, &d.clearance};
  static const char *const nk[5] = {"speed", "grid", "margin", "reach", "clearance"};
  for (int k = 0; k < 5 && !st; k++)           /* a clearance of 0 is the point-agent field */
    if ((nd = opt(map, nk[k]))) st = number_min(r, nd, join(key, "crowd", nk[k]), 0, k < 4, num[k]);
  if (!st) {
    d.agents = c.N; d.q0 = c.q; d.radius = c.r;
    d.room_points = c.nroom; d.room = c.room;
    d.doors = c.ndoor; d.door = c.door;
    d.obstacles = c.nobs; d.obstacle_points = c.obs_pts; d.obstacle = c.obs;
    d.walls = c.nwall; d.wall = c.wall;
    st = cup_crowd_create(out, &d, h, lib);
    if (st && st != CUP_ERR_NOMEM) {
      const char *msg = strncmp(lib, "crowd: ", 7) ? lib : lib + 7;   /* the key says crowd already */
      const st_node *at = culprit(&c, map, msg, key);
      st = fail(r, st == CUP_ERR_ARG ? CUP_ERR_PARSE : st, at, key, "%s", msg);
    }
  }
  parts_free(&c);
  return st;
}

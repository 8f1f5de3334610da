/* test_crowd — the crowd model (catchup/crowd.h) against what is known
 * without it: the distance to a door by elementary geometry (straight, and
 * around the end of a wall), an agent alone walking at the desired speed and
 * leaving at the time its distance takes, two agents pushed head-on stopping
 * at contact (also when one step would take them through each other, or an
 * agent through a wall, from beyond the contact margin), an evacuation in
 * which every step is checked for overlaps (against the step's certified
 * eta) and for agents crossing walls, who has left an L-shaped room against
 * its two rectangles; and the errors for bad scenes. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <cmocka.h>
#include "testutil.h"

/* A 10 x 10 room with a door from (10, 4) to (10, 6); an extra wall
 * from (7, 1) to (7, 9) when walled; one agent somewhere harmless. */
static cup_crowd *square_room(int walled, double grid, double clearance, char *err) {
  static const double room[8] = {0, 0, 10, 0, 10, 10, 0, 10}, door[4] = {10, 4, 10, 6};
  static const double wall[4] = {7, 1, 7, 9}, q[2] = {1, 1}, r[1] = {0.25};
  cup_crowd_desc d = {.agents = 1, .q0 = q, .radius = r, .room_points = 4, .room = room, .doors = 1,
                      .door = door, .walls = walled, .wall = wall, .speed = 1, .grid = grid,
                      .clearance = clearance};
  cup_crowd *c = NULL;
  cup_crowd_create(&c, &d, 0.05, err);
  return c;
}

/* The crowd of d at step dt into *c and an integrator over its n steps
 * (T = n dt), output out; both must build. */
static cup_integrator *crowd_integrator(cup_crowd **c, const cup_crowd_desc *d, double dt, long n,
                                        cup_output_kind out) {
  char err[CUP_ERRMSG_LEN];
  if (cup_crowd_create(c, d, dt, err)) fail_msg("crowd: %s", err);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.n = n;
  o.T = n * dt;
  o.output = out;
  cup_integrator *I = NULL;
  if (cup_integrator_create_process(&I, cup_crowd_process(*c), &o, err)) fail_msg("integrator: %s", err);
  return I;
}

/* Do segments p-q and a-b cross? */
static int crosses(double px, double py, double qx, double qy, double ax, double ay, double bx, double by) {
  double d1 = (bx - ax) * (py - ay) - (by - ay) * (px - ax), d2 = (bx - ax) * (qy - ay) - (by - ay) * (qx - ax);
  double d3 = (qx - px) * (ay - py) - (qy - py) * (ax - px), d4 = (qx - px) * (by - py) - (qy - py) * (bx - px);
  return d1 * d2 < 0 && d3 * d4 < 0;
}

/* The geodesic distance from (x, y) to the door (10, 4)-(10, 6), around the
 * wall (7, 1)-(7, 9) when walled: the nearest of 2001 door points, reached
 * straight when the wall does not hide it, else around one of its ends. */
static double door_geodesic(double x, double y, int walled) {
  double best = INFINITY;
  for (int k = 0; k <= 2000; k++) {
    double dy = 4 + 2 * k / 2000.0;
    double d = hypot(10 - x, dy - y);
    if (walled && crosses(x, y, 10, dy, 7, 1, 7, 9))
      d = fmin(hypot(x - 7, y - 9) + hypot(3, dy - 9), hypot(x - 7, y - 1) + hypot(3, dy - 1));
    best = fmin(best, d);
  }
  return best;
}

/* The largest error of the grid distance over points at least 0.5 from the
 * walls, against the exact geodesic distance. */
static double field_error(cup_crowd *c, int walled) {
  double worst = 0;
  for (double y = 0.55; y < 9.5; y += 0.3)
    for (double x = 0.55; x < 9.5; x += 0.3) {
      if (walled && fabs(x - 7) < 0.5 && y > 0.5 && y < 9.5) continue;
      worst = fmax(worst, fabs(cup_crowd_door_distance(c, x, y) - door_geodesic(x, y, walled)));
    }
  return worst;
}

/* First-order fast marching: error O(h log 1/h), largest in the fan behind
 * a wall's end (a point source); it must shrink with h. */
static void test_distance_field(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN];
  for (int walled = 0; walled <= 1; walled++) {
    cup_crowd *c1 = square_room(walled, 0.1, 0, err), *c2 = square_room(walled, 0.05, 0, err);
    assert_non_null(c1);
    assert_non_null(c2);
    double e1 = field_error(c1, walled), e2 = field_error(c2, walled);
    printf("distance error, %s: %.4f (h = 0.1), %.4f (h = 0.05)\n", walled ? "around a wall" : "open room", e1, e2);
    assert_true(e1 < (walled ? 0.9 : 0.35));   /* measured 0.80 and 0.29 */
    assert_true(e2 < 0.6 * e1);
    /* the direction at a point in the open points at the door's nearest part */
    double u[2];
    cup_crowd_desired_velocity(c2, 3, 5, u);
    if (!walled) {
      assert_close(u[0], 1, 1e-3);
      assert_close(u[1], 0, 3e-2);
    } else {                                 /* behind the wall: towards one of its ends */
      double a = atan2(9 - 5, 7 - 3), b = atan2(1 - 5, 7 - 3), g = atan2(u[1], u[0]);
      assert_true(fmin(fabs(g - a), fabs(g - b)) < 0.05);
    }
    cup_crowd_free(&c1);
    cup_crowd_free(&c2);
  }
}

/* The distance from (x, y) to the segment s. */
static double seg_distance(const double *s, double x, double y) {
  double dx = s[2] - s[0], dy = s[3] - s[1], t = ((x - s[0]) * dx + (y - s[1]) * dy) / (dx * dx + dy * dy);
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  return hypot(x - s[0] - t * dx, y - s[1] - t * dy);
}

/* The exact direction of the shortest way out of the open square room for
 * a centre kept c from the walls: towards the nearest point of the shrunk
 * door (10, 4 + c)-(10, 6 - c) if the straight line to it keeps c from the
 * door's edges J, else along the tangent to the disc (J, c) on the door's
 * side. */
static void exact_direction(double x, double y, double c, double e[2]) {
  double ey = y < 4 + c ? 4 + c : y > 6 - c ? 6 - c : y, jy = y < 5 ? 4 : 6, s = y < 5 ? 1 : -1;
  double seg[4] = {x, y, 10, ey};
  e[0] = 10 - x;
  e[1] = ey - y;
  if (c > 0 && seg_distance(seg, 10, jy) < c * (1 - 1e-12)) {
    double L = hypot(x - 10, y - jy), t = atan2(y - jy, x - 10) - s * acos(c / L);
    e[0] = 10 + c * cos(t) - x;
    e[1] = jy + c * sin(t) - y;
  }
}

/* The largest angle, in degrees, between the desired direction and the
 * exact one over points within 1 m of the door's ends that an agent of
 * radius 0.25 can reach: where agents queue and squeeze past the door's
 * edges. */
static double door_end_angle(cup_crowd *c, double clearance) {
  double worst = 0;
  for (double y = 2.9; y <= 7.1; y += 0.01)
    for (double x = 8.9; x <= 9.75; x += 0.01) {
      double e[2], u[2], ey = y < 4 ? 4 : y > 6 ? 6 : y;
      if (fmin(hypot(10 - x, 4 - y), hypot(10 - x, 6 - y)) > 1 || hypot(10 - x, ey - y) < 0.25) continue;
      exact_direction(x, y, clearance, e);
      cup_crowd_desired_velocity(c, x, y, u);
      worst = fmax(worst, fabs(atan2(u[0] * e[1] - u[1] * e[0], u[0] * e[0] + u[1] * e[1])));
    }
  return worst * 180 / M_PI;
}

/* Each end of a door is a point source of the distance, where first-order
 * fast marching is worst: marched from the door's nodes only (clearance 0,
 * as cromosim does), the directions there point into the door by up to 50
 * degrees at h = 0.1 (30 at 0.05). With a clearance the march starts from
 * exact distances and directions around the (shrunk) door: what is left is
 * the interpolation's on the rim of the disc round each edge, where the
 * direction turns like the square root of the distance (measured 16.8 and
 * 9.4 degrees). */
static void test_door_ends(void **state) {
  (void)state;
  char err[CUP_ERRMSG_LEN];
  for (int k = 0; k < 2; k++) {
    double cl = k ? 0.25 : 0;
    cup_crowd *c1 = square_room(0, 0.1, cl, err), *c2 = square_room(0, 0.05, cl, err);
    assert_non_null(c1);
    assert_non_null(c2);
    double a1 = door_end_angle(c1, cl), a2 = door_end_angle(c2, cl);
    printf("direction error near the door's ends, clearance %g: %.2f deg (h = 0.1), %.2f deg (h = 0.05)\n", cl,
           a1, a2);
    assert_true(k ? a1 < 20 : a1 > 40);
    assert_true(a2 < 0.7 * a1);
    cup_crowd_free(&c1);
    cup_crowd_free(&c2);
  }
}

/* The shortest path for a centre kept c from the walls, from P to the
 * door (12, 4)-(12, 6) of a 12 x 10 room, round the door's edge J (a disc
 * of radius c): the tangent from P to the disc, then the arc to the point
 * where the centre crosses the door's line (J + (0, +-c)). */
static double jamb_path(double px, double py, double c) {
  double jy = py < 4 ? 4 : 6, s = py < 4 ? 1 : -1;          /* s: the way round */
  double dx = px - 12, dy = py - jy, L = hypot(dx, dy);
  double t = atan2(dy, dx) - s * acos(c / L);                 /* angle of the tangent point */
  double end = s * M_PI / 2;                                  /* angle of the crossing point */
  double arc = fabs(remainder(t - end, 2 * M_PI));
  return sqrt(L * L - c * c) + c * arc;
}

/* An agent of radius 0.25 beside the wall of a door (or farther off) with a
 * clearance of 0.25: it leaves at the first step at or after the time its
 * shortest path around the door's edge takes at the desired speed, on
 * every grid. With
 * the point-agent field (clearance 0) the direction beside the edge points
 * at the edge itself, the wall row removes its normal part and the agent
 * slows down to a stop: from (11.75, 3), 2.65 s for a 1.16 s path. */
static void test_clearance_round_the_edge(void **state) {
  (void)state;
  const double room[8] = {0, 0, 12, 0, 12, 10, 0, 10}, door[4] = {12, 4, 12, 6}, r[1] = {0.25};
  const double start[4][2] = {{11.75, 3}, {11.75, 1}, {6, 1}, {1, 9}}, grids[2] = {0.05, 0.025};
  const double v = 1.2, dt = 0.05;
  int late = 0;
  for (int g = 0; g < 2; g++)
    for (int a = 0; a < 4; a++)
      for (int point = 0; point <= 1; point++) {
        cup_crowd_desc d = {.agents = 1, .q0 = start[a], .radius = r, .room_points = 4, .room = room,
                            .doors = 1, .door = door, .speed = v, .grid = grids[g], .clearance = point ? 0 : 0.25};
        cup_crowd *c;
        cup_integrator *I = crowd_integrator(&c, &d, dt, 400, CUP_OUTPUT_FINAL);
        cup_run_info info;
        assert_int_equal(cup_integrator_run(I, start[a], NULL, NULL, &info), CUP_OK);
        double t = cup_crowd_exit_times(c)[0], ideal = jamb_path(start[a][0], start[a][1], 0.25) / v;
        printf("from (%g, %g), grid %g, clearance %s: out at %.2f s, its shortest path takes %.4f s\n",
               start[a][0], start[a][1], grids[g], point ? "0" : "0.25", t, ideal);
        if (!point) {
          assert_true(t >= ideal - 1e-9);
          assert_true(t <= ideal + dt + 1e-9);
        } else {
          late += t > ideal + 2 * dt + 1e-9;                  /* the stall the clearance removes */
        }
        cup_integrator_free(&I);
        cup_crowd_free(&c);
      }
  assert_true(late >= 4);
}

/* ---- runs ------------------------------------------------------------------ */

typedef struct run_check {
  cup_crowd *c;
  long nsteps;
  double *gap, *eta;        /* per step: smallest gap of x_k, certified eta of step k */
  const double *prev;       /* not owned */
  double *last;             /* the state before */
  int N;
  int crossed;              /* an agent that left elsewhere than through the door */
  const double *door;
} run_check;

static int sink_gaps(long k, double t, const double *q, void *ctx) {
  (void)t;
  run_check *rc = ctx;
  rc->gap[k] = cup_crowd_min_gap(rc->c, q);
  const double *et = cup_crowd_exit_times(rc->c);
  for (int i = 0; k > 0 && i < rc->N; i++) {
    /* an agent out at x_k (not yet marked: marks come with the next step)
     * crossed the door segment x = door[0], door[1] <= y <= door[3] */
    double x0 = rc->last[2 * i], y0 = rc->last[2 * i + 1], x1 = q[2 * i], y1 = q[2 * i + 1];
    if (isnan(et[i]) && x0 <= rc->door[0] && x1 > rc->door[0]) {
      double y = y0 + (y1 - y0) * (rc->door[0] - x0) / (x1 - x0);
      if (y < rc->door[1] || y > rc->door[3]) rc->crossed = 1;
    }
    if (isnan(et[i]) && (x1 < 0 || y1 < 0 || y1 > 10)) rc->crossed = 1;
  }
  memcpy(rc->last, q, sizeof(double) * 2 * (size_t)rc->N);
  return 0;
}

static int step_eta(long k, double t, const cup_proj_info *pi, void *ctx) {
  (void)t;
  run_check *rc = ctx;
  rc->eta[k] = pi->eta_cert;
  return 0;
}

/* An agent alone in a corridor 20 x 4 walks to the door at the far end
 * (centred on its line) at the desired speed, and leaves after 18 / v. */
static void test_alone(void **state) {
  (void)state;
  const double room[8] = {0, 0, 20, 0, 20, 4, 0, 4}, door[4] = {20, 1, 20, 3}, q0[2] = {2, 2}, r[1] = {0.3};
  const double v = 1.3, dt = 0.01;
  cup_crowd_desc d = {.agents = 1, .q0 = q0, .radius = r, .room_points = 4, .room = room, .doors = 1,
                      .door = door, .speed = v, .grid = 0.05};
  cup_crowd *c;
  cup_integrator *I = crowd_integrator(&c, &d, dt, 1500, CUP_OUTPUT_EVERY);
  cup_run_info info;
  assert_int_equal(cup_integrator_run(I, q0, NULL, NULL, &info), CUP_OK);
  const double *q = cup_integrator_state(I);
  /* 1500 steps of v dt: x = 2 + 19.5 had it not left; it left at the first
   * t_k with 2 + v t_k > 20, t = 13.85 (k = 1385), and stopped there */
  double t_exit = cup_crowd_exit_times(c)[0];
  assert_close(t_exit, 1385 * dt, 1e-9);
  assert_close(q[0], 2 + v * t_exit, 1e-9);
  assert_close(q[1], 2, 1e-9);
  assert_int_equal(cup_crowd_inside(c), 0);
  cup_integrator_free(&I);
  cup_crowd_free(&c);
}

/* Two agents pushed towards each other at speed 1 in the open stop at contact:
 * centres 0.5 apart from t = 1.75 on. The test's own desired velocity
 * replaces the crowd's (the crowd's set builds the contact rows). */
static int head_on(double t0, double t1, const double *q, double *F, void *ctx) {
  (void)q; (void)ctx;
  F[0] = t1 - t0; F[1] = 0; F[2] = -(t1 - t0); F[3] = 0;
  return 0;
}

static void test_head_on(void **state) {
  (void)state;
  const double room[8] = {0, 0, 20, 0, 20, 4, 0, 4}, door[4] = {20, 1, 20, 3};
  const double q0[4] = {8, 2, 12, 2}, r[2] = {0.25, 0.25};
  cup_crowd_desc d = {.agents = 2, .q0 = q0, .radius = r, .room_points = 4, .room = room, .doors = 1,
                      .door = door, .speed = 1};
  char err[CUP_ERRMSG_LEN];
  cup_crowd *c;
  assert_int_equal(cup_crowd_create(&c, &d, 0.01, err), CUP_OK);
  cup_process_desc pd = *cup_crowd_process(c);
  pd.f_integral = head_on;
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.n = 300;
  o.T = 3;
  o.eps = (cup_schedule){0, 0};
  o.eta = (cup_schedule){0, 0};
  cup_integrator *I;
  assert_int_equal(cup_integrator_create_process(&I, &pd, &o, err), CUP_OK);
  cup_run_info info;
  assert_int_equal(cup_integrator_run(I, q0, NULL, NULL, &info), CUP_OK);
  const double *q = cup_integrator_state(I);
  assert_close(q[0], 9.75, 1e-9);
  assert_close(q[2], 10.25, 1e-9);
  assert_close(q[1], 2, 1e-12);
  assert_close(q[3], 2, 1e-12);
  assert_true(info.max_eta_cert <= 1e-9);
  cup_integrator_free(&I);
  cup_crowd_free(&c);
}

/* A push of *ctx metres a step: agent 0 along +x and agent 1 along -x
 * (two agents), or agent 0 along -y (one). */
static int push(double t0, double t1, const double *q, double *F, void *ctx) {
  (void)q; (void)t0; (void)t1;
  F[0] = 0; F[1] = -*(const double *)ctx;
  return 0;
}

static int push_pair(double t0, double t1, const double *q, double *F, void *ctx) {
  (void)q; (void)t0; (void)t1;
  double v = *(const double *)ctx;
  F[0] = v; F[1] = 0; F[2] = -v; F[3] = 0;
  return 0;
}

/* Pushed 1.8 m a step with a contact margin of 0.01 m, the agents of a pair
 * 3.5 m apart (or an agent 1.75 m from a wall) get no row from the step's
 * rows; the step's first answer overlaps (passes through), the crowd finds
 * the contact it missed, and the step projected again with its row (made at
 * x_k) stops them at contact: the exact projection onto e . (y_1 - y_0) >=
 * 0.5 puts the pair at 9.75 and 10.25 (the midpoint 10 of the free points
 * 9.8 and 10.2, half a diameter each side), the agent at y = r = 0.25 on the
 * wall y = 0, and there they stay. */
static void test_missed_contacts(void **state) {
  (void)state;
  const double room[8] = {0, 0, 20, 0, 20, 4, 0, 4}, door[4] = {20, 1, 20, 3};
  const double pair0[4] = {8, 2, 12, 2}, one0[2] = {5, 2}, r[2] = {0.25, 0.25}, v = 1.8;
  for (int pair = 0; pair <= 1; pair++) {
    cup_crowd_desc d = {.agents = pair ? 2 : 1, .q0 = pair ? pair0 : one0, .radius = r, .room_points = 4,
                        .room = room, .doors = 1, .door = door, .speed = 1, .margin = 0.01};
    char err[CUP_ERRMSG_LEN];
    cup_crowd *c;
    assert_int_equal(cup_crowd_create(&c, &d, 0.05, err), CUP_OK);
    cup_process_desc pd = *cup_crowd_process(c);
    pd.f_integral = pair ? push_pair : push;
    pd.f_integral_ctx = (void *)&v;
    for (int n = 1; n <= 4; n += 3) {
      cup_integrator_options o;
      cup_integrator_options_default(&o);
      o.n = n;
      o.T = 0.05 * n;
      o.eps = (cup_schedule){0, 0};
      o.eta = (cup_schedule){0, 0};
      cup_integrator *I;
      assert_int_equal(cup_integrator_create_process(&I, &pd, &o, err), CUP_OK);
      cup_run_info info;
      assert_int_equal(cup_integrator_run(I, d.q0, NULL, NULL, &info), CUP_OK);
      const double *q = cup_integrator_state(I);
      if (pair) {
        assert_close(q[0], 9.75, 1e-12);
        assert_close(q[2], 10.25, 1e-12);
        assert_close(q[1], 2, 1e-12);
        assert_close(q[3], 2, 1e-12);
      } else {
        assert_close(q[0], 5, 1e-12);
        assert_close(q[1], 0.25, 1e-12);
      }
      assert_int_equal(cup_crowd_added(c), n == 1);   /* later steps have the row from the margin */
      assert_true(info.max_eta_cert <= 1e-9);
      cup_integrator_free(&I);
    }
    cup_crowd_free(&c);
  }
}

/* 150 agents of radii 0.2 .. 0.3 in the 10 x 10 room with a square column
 * before the door: at every step the smallest gap (pairs and walls) is at
 * least -sqrt 2 eta of the step that made it, and no agent leaves but
 * through the door. */
static void test_evacuation_checked(void **state) {
  (void)state;
  const double room[8] = {0, 0, 10, 0, 10, 10, 0, 10}, door[4] = {10, 4, 10, 6};
  const double column[8] = {7.5, 4.7, 8.1, 4.7, 8.1, 5.3, 7.5, 5.3};
  const int cpts[1] = {4};
  enum { N = 150 };
  double q0[2 * N], r[N];
  rng_t g = {7};
  for (int i = 0; i < N; i++) {              /* a jittered grid on the left 6 m */
    r[i] = 0.2 + 0.07 * rng_unif(&g);
    q0[2 * i] = 0.5 + 0.7 * (i % 9) + 0.1 * (rng_unif(&g) - 0.5);
    q0[2 * i + 1] = 0.5 + 0.55 * (i / 9);
  }
  cup_crowd_desc d = {.agents = N, .q0 = q0, .radius = r, .room_points = 4, .room = room, .doors = 1,
                      .door = door, .obstacles = 1, .obstacle_points = cpts, .obstacle = column, .speed = 1.2};
  char err[CUP_ERRMSG_LEN];
  cup_crowd *c;
  int st = cup_crowd_create(&c, &d, 0.05, err);
  if (st) fail_msg("%s", err);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.n = 400;
  o.T = 20;
  o.eta = (cup_schedule){1e-6, 0};
  run_check rc = {c, o.n, calloc((size_t)o.n + 1, sizeof(double)), calloc((size_t)o.n + 1, sizeof(double)),
                  NULL, malloc(sizeof(double) * 2 * N), N, 0, door};
  o.on_step = step_eta;
  o.step_ctx = &rc;
  cup_integrator *I;
  assert_int_equal(cup_integrator_create_process(&I, cup_crowd_process(c), &o, err), CUP_OK);
  cup_run_info info;
  st = cup_integrator_run(I, q0, sink_gaps, &rc, &info);
  if (st) fail_msg("%s: %s", cup_status_name(st), info.message);
  double worst = INFINITY;
  for (long k = 1; k <= o.n; k++) {
    if (rc.gap[k] < -M_SQRT2 * rc.eta[k] - 1e-12)
      fail_msg("step %ld: gap %.3g below -sqrt 2 eta = %.3g", k, rc.gap[k], -M_SQRT2 * rc.eta[k]);
    worst = fmin(worst, rc.gap[k]);
  }
  printf("evacuation: %d of %d out, smallest gap %.3g, largest eta %.3g\n", N - cup_crowd_inside(c), N,
         worst, info.max_eta_cert);
  assert_int_equal(rc.crossed, 0);
  assert_true(N - cup_crowd_inside(c) > N / 3);  /* a flow through the door, past the column */
  free(rc.gap); free(rc.eta); free(rc.last);
  cup_integrator_free(&I);
  cup_crowd_free(&c);
}

/* Who has left an L-shaped room (its notch is outside), at points spread
 * over and around it: the crowd's exit marks (the desired velocity's step
 * marks them, from t = 0 afresh) against membership of one of the L's two
 * rectangles. The edges cut cells of the crowd's grid (side 0.4 m here)
 * whose centres are inside: there the crowd's answer must be the crossing
 * test's, elsewhere it may be its cell's. */
static void test_exits_notched_room(void **state) {
  (void)state;
  const double room[12] = {0, 0, 20.3, 0, 20.3, 8.3, 8.3, 8.3, 8.3, 20.3, 0, 20.3};
  const double door[4] = {20.3, 2, 20.3, 4};
  enum { N = 1500 };
  double q0[2 * N], r[N], q[2 * N], F[2 * N];
  for (int i = 0; i < N; i++) {              /* a grid in the L's upright */
    r[i] = 0.05;
    q0[2 * i] = 0.5 + 0.25 * (i % 30);
    q0[2 * i + 1] = 0.5 + 0.38 * (i / 30);
  }
  cup_crowd_desc d = {.agents = N, .q0 = q0, .radius = r, .room_points = 6, .room = room, .doors = 1,
                      .door = door, .speed = 1};
  char err[CUP_ERRMSG_LEN];
  cup_crowd *c;
  int st = cup_crowd_create(&c, &d, 0.05, err);
  if (st) fail_msg("%s", err);
  const cup_process_desc *pd = cup_crowd_process(c);
  rng_t g = {11};
  int out = 0;
  for (int i = 0; i < N; i++) {
    double x = -2 + 24 * rng_unif(&g), y = -2 + 24 * rng_unif(&g);
    q[2 * i] = x;
    q[2 * i + 1] = y;
    out += !((x > 0 && x < 20.3 && y > 0 && y < 8.3) || (x > 0 && x < 8.3 && y > 0 && y < 20.3));
  }
  assert_int_equal(pd->f_integral(0, 0.05, q, F, pd->f_integral_ctx), 0);
  const double *te = cup_crowd_exit_times(c);
  for (int i = 0; i < N; i++) {
    double x = q[2 * i], y = q[2 * i + 1];
    int in = (x > 0 && x < 20.3 && y > 0 && y < 8.3) || (x > 0 && x < 8.3 && y > 0 && y < 20.3);
    if (in != isnan(te[i])) fail_msg("agent %d at (%.6f, %.6f): %s, exit time %g", i, x, y, in ? "in" : "out", te[i]);
  }
  assert_int_equal(cup_crowd_inside(c), N - out);
  assert_true(out > N / 3 && out < 2 * N / 3);  /* the L is 268 of the 576 m^2 */
  cup_crowd_free(&c);
}

/* ---- errors ----------------------------------------------------------------- */

static void expect_error(const cup_crowd_desc *d, const char *what) {
  char err[CUP_ERRMSG_LEN];
  cup_crowd *c = (cup_crowd *)d;    /* must come back NULL */
  int st = cup_crowd_create(&c, d, 0.05, err);
  if (st >= 0) fail_msg("expected an error with '%s'", what);
  assert_null(c);
  if (!strstr(err, what)) fail_msg("expected '%s' in: %s", what, err);
}

static void test_errors(void **state) {
  (void)state;
  const double room[8] = {0, 0, 10, 0, 10, 10, 0, 10}, door[4] = {10, 4, 10, 6};
  double q[4] = {2, 2, 5, 5}, r[2] = {0.25, 0.25};
  cup_crowd_desc d = {.agents = 2, .q0 = q, .radius = r, .room_points = 4, .room = room, .doors = 1,
                      .door = door, .speed = 1};
  q[2] = 2.3; q[3] = 2.1;
  expect_error(&d, "agents 0 and 1 overlap by");
  q[2] = 11; q[3] = 5;
  expect_error(&d, "agent 1 at (11, 5) is outside the room");
  q[2] = 9.9; q[3] = 8;
  expect_error(&d, "agent 1 at (9.9, 8), radius 0.25, overlaps wall 2 (the room's edge 1, from (10, 6) to (10, 10)) by 0.15");
  q[2] = 5; q[3] = 5;
  const double off[4] = {9, 4, 9, 6};
  d.door = off;
  expect_error(&d, "door 0 (from (9, 4) to (9, 6)) does not lie on an edge of the room");
  d.door = door;
  const double box[8] = {4, 4, 6, 4, 6, 6, 4, 6};
  const int bp[1] = {4};
  d.obstacles = 1; d.obstacle_points = bp; d.obstacle = box;
  expect_error(&d, "agent 1 at (5, 5) is inside obstacle 0");
  d.obstacles = 0;
  /* a wall closing the room's right part: the door behind it is unreachable */
  const double shut[4] = {8, 0, 8, 10};
  d.walls = 1; d.wall = shut;
  expect_error(&d, "cannot reach any door");
  const double doors2[8] = {10, 4, 10, 6, 0, 4, 0, 6};
  d.doors = 2; d.door = doors2;
  expect_error(&d, "door 0 (from (10, 4) to (10, 6)) cannot be reached by any agent");
  d.walls = 0; d.doors = 1; d.door = door;
  d.clearance = 0.3;
  expect_error(&d, "the clearance 0.3 exceeds agent 0's radius 0.25");
  d.clearance = 0.25;
  const double narrow[4] = {10, 4, 10, 4.5};
  d.door = narrow;
  expect_error(&d, "door 0 (from (10, 4) to (10, 4.5)) is 0.5 wide: no wider than twice the clearance 0.25");
  d.door = door; d.clearance = 0;
  d.speed = 0;
  expect_error(&d, "desired speed");
  d.speed = 1;
  /* rooms that are not simple polygons: a bow tie (edges 0 and 2 cross at
   * (5, 5)), a vertex on a far edge (edges 0 and 3 touch at (5, 0)), an
   * edge folding back over its neighbour (edges 1 and 2 overlap on
   * [(10, 0), (12, 0)]); the simple ones beside them pass */
  const double bowtie[8] = {0, 0, 10, 10, 10, 0, 0, 10};
  const double touch[10] = {0, 0, 10, 0, 10, 10, 0, 10, 5, 0};
  const double fold[10] = {0, 0, 14, 0, 10, 0, 10, 10, 0, 10};
  const double bq[2] = {2, 8.5}, br[1] = {0.25}, bdoor[4] = {0, 7, 0, 9};
  cup_crowd_desc b = {.agents = 1, .q0 = bq, .radius = br, .room_points = 4, .room = bowtie, .doors = 1,
                      .door = bdoor, .speed = 1};
  expect_error(&b, "the room is not a simple polygon: its edges 0, from (0, 0) to (10, 10), and 2, from (10, 0) "
               "to (0, 10), cross");
  b.room_points = 5; b.room = touch;
  expect_error(&b, "its edges 0, from (0, 0) to (10, 0), and 3, from (0, 10) to (5, 0), cross");
  b.room = fold;
  expect_error(&b, "its edges 0, from (0, 0) to (14, 0), and 1, from (14, 0) to (10, 0), cross");
  d.obstacles = 1;
  const double tie[8] = {4, 4, 4, 6, 6, 4, 6, 6};
  d.obstacle = tie;
  q[2] = 8; q[3] = 8;
  expect_error(&d, "obstacle 0 is not a simple polygon: its edges 1, from (4, 6) to (6, 4), and 3");
  d.obstacle = box;
  char err[CUP_ERRMSG_LEN];
  cup_crowd *c = NULL;
  assert_int_equal(cup_crowd_create(&c, &d, 0.05, err), CUP_OK);   /* the same with a square obstacle */
  assert_null(cup_crowd_warning(c));
  cup_crowd_free(&c);
}

/* A door passes a disk of radius r exactly when it is at least 2 r wide:
 * one narrower than the smallest agent's diameter is warned of, naming the
 * door and that agent; at 2 r_min it is not (issue 27). */
static void test_impassable_door(void **state) {
  (void)state;
  const double room[8] = {0, 0, 10, 0, 10, 10, 0, 10};
  double q[4] = {2, 2, 5, 5}, r[2] = {0.3, 0.25}, door[8] = {10, 4, 10, 4.49, 0, 4, 0, 6};
  cup_crowd_desc d = {.agents = 2, .q0 = q, .radius = r, .room_points = 4, .room = room, .doors = 1,
                      .door = door, .speed = 1};
  char err[CUP_ERRMSG_LEN];
  cup_crowd *c = NULL;
  assert_int_equal(cup_crowd_create(&c, &d, 0.05, err), CUP_OK);
  assert_non_null(cup_crowd_warning(c));
  assert_string_equal(cup_crowd_warning(c), "door 0 (from (10, 4) to (10, 4.49)) is 0.49 wide, narrower than the "
                      "smallest agent (agent 1, diameter 0.5): no agent can pass it; it is the only door: no agent "
                      "can leave");
  cup_crowd_free(&c);
  door[3] = 4.5;                                   /* 2 r_min: passable */
  assert_int_equal(cup_crowd_create(&c, &d, 0.05, err), CUP_OK);
  assert_null(cup_crowd_warning(c));
  cup_crowd_free(&c);
  door[3] = 4.3;                                   /* a second door, wide enough */
  d.doors = 2;
  assert_int_equal(cup_crowd_create(&c, &d, 0.05, err), CUP_OK);
  assert_non_null(cup_crowd_warning(c));
  assert_non_null(strstr(cup_crowd_warning(c), "door 0 (from (10, 4) to (10, 4.3)) is 0.3 wide"));
  assert_null(strstr(cup_crowd_warning(c), "no agent can leave"));
  cup_crowd_free(&c);
}

int main(void) {
  const struct CMUnitTest tests[] = {
    cmocka_unit_test(test_distance_field),
    cmocka_unit_test(test_door_ends),
    cmocka_unit_test(test_alone),
    cmocka_unit_test(test_clearance_round_the_edge),
    cmocka_unit_test(test_head_on),
    cmocka_unit_test(test_missed_contacts),
    cmocka_unit_test(test_evacuation_checked),
    cmocka_unit_test(test_exits_notched_room),
    cmocka_unit_test(test_errors),
    cmocka_unit_test(test_impassable_door),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

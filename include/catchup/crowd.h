/* catchup/crowd.h — crowd motion (Maury and Venel): N disks in a room walk
 * towards its doors at a desired speed and never overlap, a state-dependent
 * sweeping process
 *     q' in -N(C(q); q) + U(q),   C(q) = {q : |q_i - q_j| >= r_i + r_j, q_i clear of the walls},
 * stepped by the catching-up algorithm on the linearized set: each step
 * projects q_k + h U(q_k) onto
 *     {y : e_ij . (y_i - y_j) >= r_i + r_j  (pairs within a margin of contact),
 *          n_iw . (y_i - p_iw) >= r_i       (walls within the margin)},
 * e_ij = (q_i - q_j)/|q_i - q_j|, p_iw the point of wall w nearest to q_i and
 * n_iw the unit vector from it to q_i. Each linearized row implies its true
 * constraint, so a projection certified to eta leaves no overlap beyond
 * about eta. U_i = -speed grad D / |grad D| at q_i, D the geodesic distance
 * to the nearest door around walls and obstacles (fast marching on a grid).
 * An agent whose centre leaves the room (through a door) has evacuated: from
 * then on it has no rows and no velocity, and its exit time is recorded.
 * docs/crowd.md. */
#ifndef CATCHUP_CROWD_H
#define CATCHUP_CROWD_H

#include "catchup/export.h"
#include "catchup/integrator.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cup_crowd cup_crowd;

/** A room, its doors and obstacles, and the agents. Coordinates in metres
 *  (any unit: the model is scale-free), points as (x, y) pairs. Everything
 *  is copied. */
typedef struct cup_crowd_desc {
  int agents;                /**< N >= 1 */
  const double *q0;          /**< 2N: the agents' centres at t = 0 */
  const double *radius;      /**< N radii > 0 */
  int room_points;           /**< vertices of the room, a simple polygon (>= 3) */
  const double *room;        /**< 2 per vertex; its edges are walls but where a door lies */
  int doors;                 /**< exits, >= 1 */
  const double *door;        /**< 4 per door (x0, y0, x1, y1): a segment of one edge of the room */
  int obstacles;             /**< polygons inside the room (columns, pillars) */
  const int *obstacle_points;/**< vertices of each obstacle (>= 3 each) */
  const double *obstacle;    /**< 2 per vertex, the obstacles one after the other */
  int walls;                 /**< extra wall segments inside the room (a corridor's walls) */
  const double *wall;        /**< 4 per segment (x0, y0, x1, y1) */
  double speed;              /**< desired speed > 0 */
  double grid;               /**< step of the distance grid (0: min radius / 2) */
  double margin;             /**< a pair or a wall gets a row when its gap is below this
                                  (0: the larger of 4 speed h, h the step, and the mean radius:
                                  agents pushed by others move faster than speed) */
  double reach;              /**< pairs with a gap below this are announced as patterns
                                  to come (cup_rowbuf_expect; 0: 1.5 margin) */
  /* clearance (issue 17): the desired direction of an agent's centre */
  double clearance;          /**< the desired direction is the shortest way out for a centre
                                  kept this far from walls and obstacles (walls grown by it,
                                  doors shrunk by it at each end); at most the smallest
                                  radius. 0: the point-agent field of Maury and Venel (and
                                  cromosim), where an agent sliding along the wall beside a
                                  door slows to a stop at the door's edge (docs/crowd.md) */
} cup_crowd_desc;

/** Check and build: the walls (room edges less the doors, obstacle edges,
 *  the extra walls), the distance to the doors on the grid, the desired
 *  directions. Errors name what is wrong: "agent 17 at (3.2, 11) is outside
 *  the room", "agents 12 and 40 overlap by 0.03", "agent 5 overlaps wall 3
 *  (the room's edge 3, from (0, 0) to (10, 0)) by 0.1", "door 2 (from (.., ..)
 *  to (.., ..)) does not lie on an edge of the room", "door 1 ... cannot be
 *  reached by any agent", "agent 9 at (..) cannot reach any door". On
 *  failure *c is NULL. h is the integrator's step (T/n), used for the
 *  default margin. */
CUP_API int cup_crowd_create(cup_crowd **c, const cup_crowd_desc *d, double h, char *errmsg);
CUP_API void cup_crowd_free(cup_crowd **c);
/** What the crowd's creation found suspect but allowed, or NULL: a door
 *  narrower than the smallest agent's diameter ("door 0 (from (10, 4) to
 *  (10, 4.4)) is 0.4 wide, narrower than the smallest agent (agent 3,
 *  diameter 0.5): no agent can pass it; it is the only door: no agent can
 *  leave"). catchup-run prints it before the run and keeps it in the
 *  file's attribute `warnings`. */
CUP_API const char *cup_crowd_warning(const cup_crowd *c);
CUP_API int cup_crowd_agents(const cup_crowd *c);          /**< N */
CUP_API const double *cup_crowd_q0(const cup_crowd *c);    /**< the start (2N), as given */
CUP_API const double *cup_crowd_radii(const cup_crowd *c); /**< the radii (N) */
/** The process (state q in R^2N, a state-dependent polyset with identity
 *  metric, f the desired velocity through its exact integral), valid while
 *  c lives. Run it with cup_integrator_create_process and the explicit
 *  scheme; one run at a time per crowd (its exit times are the run's). */
CUP_API const cup_process_desc *cup_crowd_process(const cup_crowd *c);
/** The agents' exit times (N entries): the first t_k at which the centre
 *  was out of the room; NaN while inside. Reset when a run starts. */
CUP_API const double *cup_crowd_exit_times(const cup_crowd *c);
/** Agents inside the room at the last step the process took. */
CUP_API int cup_crowd_inside(const cup_crowd *c);
/** The smallest gap (as cup_crowd_min_gap) at the state x_k from which the
 *  last step's rows were built, found while building them: the overlap the
 *  step before left (at most about sqrt 2 eta of that step). */
CUP_API double cup_crowd_gap(const cup_crowd *c);
/** The rows (contacts and walls within the margin) of the last step. */
CUP_API int cup_crowd_rows(const cup_crowd *c);
/** Contacts (pairs and agent-wall) the last step's rows missed: beyond the
 *  margin at x_k, overlapping at the step's first answer (an agent closed
 *  more than the margin in one step). The step added their rows and was
 *  projected again; 0 in a step that missed none. */
CUP_API int cup_crowd_added(const cup_crowd *c);
/** The distance to the nearest door around the walls (bilinear on the
 *  grid; INFINITY where no door can be reached). */
CUP_API double cup_crowd_door_distance(const cup_crowd *c, double x, double y);
/** The desired velocity at (x, y): speed times the unit direction that
 *  descends the door distance (u, 2 entries; 0 where it is undefined). */
CUP_API void cup_crowd_desired_velocity(const cup_crowd *c, double x, double y, double *u);
/** The wall segments (4 per segment: x0, y0, x1, y1), for plots and checks. */
CUP_API int cup_crowd_walls(const cup_crowd *c, const double **seg);
/** The smallest gap of the state q (2N): min over pairs of agents inside
 *  of |q_i - q_j| - r_i - r_j and over agents and walls of the distance to
 *  the wall - r_i (found with the cell list, pairs within reach). */
CUP_API double cup_crowd_min_gap(cup_crowd *c, const double *q);

#ifdef __cplusplus
}
#endif
#endif

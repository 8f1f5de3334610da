/* scene_crowd — the `crowd:` key of a scene: a room, doors, obstacles,
 * walls, agents (listed or placed at random), speed and grid, into a
 * cup_crowd (catchup/crowd.h) whose process the scene runs. h is the step
 * T / n (the crowd's default margin depends on it). docs/crowd.md. Internal
 * to the library. */
#ifndef CUP_SCENE_CROWD_H
#define CUP_SCENE_CROWD_H

#include "scene_read.h"

int scene_read_crowd(rd *r, const st_node *map, double h, cup_crowd **out);

#endif

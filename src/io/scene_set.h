/* scene_set — the general sweeping process of a scene: the `set:` key (a
 * ball, ellipsoid, half-space, polyset or polyset-and-ball, with centre,
 * radius and offsets as numbers or signals: waveforms, sums of them,
 * piecewise-linear tables) and the `f:` key (A x + b(t), and the named
 * nonlinear forms cubic and towards). Every signal becomes one component of
 * the process's input u(t). docs/scene-format.md. Internal to the library. */
#ifndef CUP_SCENE_SET_H
#define CUP_SCENE_SET_H

#include "scene_read.h"

typedef struct scene_process scene_process;

/* Read set: (at kset/set) and f: (root's, may be absent) into *P; each
 * signal is read by component (scene.c's reader of input components). */
int scene_read_process(rd *r, const st_node *root, const st_node *kset, const st_node *set,
                       scene_component_fn component, scene_process **P);
void scene_process_free(scene_process **P);
const cup_process_desc *scene_process_desc(const scene_process *P);
const cup_input *scene_process_input(const scene_process *P);

#endif

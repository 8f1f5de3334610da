/* scene_steady — the scene key steady_state: (docs/steady-state.md): the
 * steady-state solve's options, the signals measured over the period and
 * the elements whose power (and efficiency) is measured. */
#ifndef CUP_SCENE_STEADY_H
#define CUP_SCENE_STEADY_H

#include "scene_read.h"

typedef struct scene_steady {
  int enabled;
  cup_scene_steady pub;
  const char **list;   /* measure, then power (the texts live in the scene's tree... copied: owned) */
  char **own;
} scene_steady;

/* steady_state: true, false or a mapping of its keys; measure: and power:
 * are checked against the netlist (signals and elements that exist), not
 * probed: the program adds them after its own probes. */
int scene_read_steady(rd *r, const st_node *root, cup_netlist *nl, scene_steady *s);
void scene_steady_free(scene_steady *s);

#endif

/* scene_shape — a KEY=VALUE override names the shape its user wants, so
 * the scene's value of another shape gives way (an st_reshape_fn for
 * st_apply_override): `circuit` and `lcs` replace each other; output.samples=2
 * replaces output: {every: 1} (one mode at a time); projector.max_iter=50
 * turns projector: fista into {method: fista, max_iter: 50}; tol.abs=1e-9
 * replaces tol: 1e-6 (tol.rel is then 0 unless set too); lcs.A.file=a.mtx
 * replaces an inline A (and every matrix, F and x0 the same); input....type=pwl
 * drops the fields the old waveform had and the new one does not take.
 * And netlist.R1={100/13} is SPICE, not YAML (scene_verbatim).
 * Internal to the library. */
#ifndef CUP_SCENE_SHAPE_H
#define CUP_SCENE_SHAPE_H

#include "catchup/input.h"
#include "scene_tree.h"

/* The keys of an input term mapping, by waveform (CUP_WAVE_LIST order). */
#define SCENE_WAVE_KEYS 9
extern const char *const scene_wave_keys[CUP_WAVE_COUNT][SCENE_WAVE_KEYS];

int scene_reshape(st_node **slot, const char *path, const char *seg, const st_node *val, int k);
/* An st_verbatim_fn: netlist.NAME=VALUE (an element or a .param, not
 * file, text, name or probe) takes VALUE as SPICE text. */
int scene_verbatim(const char *key);

#endif

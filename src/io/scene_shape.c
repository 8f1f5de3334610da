/* scene_shape — what a scene override means when the scene's value has
 * another shape (scene_shape.h). */
#include <ctype.h>
#include <string.h>
#include "catchup.h"
#include "scene_shape.h"

/* The keys of a term mapping, by waveform (CUP_WAVE_LIST order). */
const char *const scene_wave_keys[CUP_WAVE_COUNT][SCENE_WAVE_KEYS] = {
  {"type", "value", NULL},
  {"type", "amplitude", "frequency", "phase", NULL},
  {"type", "amplitude", "frequency", "phase", NULL},
  {"type", "points", NULL},
  {"type", "value", "value2", "delay", "rise", "fall", "width", "period", NULL},
  {"type", "amplitude", "frequency", "phase", "delay", "damping", NULL}};

/* Keys whose value is a matrix or a vector: inline numbers or {file: ...}. */
static int inline_or_file(const char *path) {
  static const char *const keys[] = {"x0", "lcs.A", "lcs.B", "lcs.C", "lcs.D", "lcs.E", "lcs.F", "lcs.G", "lcs.P", NULL};
  for (int k = 0; keys[k]; k++)
    if (!strcmp(path, keys[k])) return 1;
  return 0;
}

static int replace_by_map(st_node **slot, int k) {
  st_node *m = st_new_map(k);
  if (!m) return CUP_ERR_NOMEM;
  st_free(*slot);
  *slot = m;
  return CUP_OK;
}

int scene_reshape(st_node **slot, const char *path, const char *seg, const st_node *val, int k) {
  st_node *nd = *slot;
  if (!*path && nd->kind == ST_MAP) {
    static const char *const models[] = {"circuit", "lcs", "netlist"};
    for (int a = 0; a < 3; a++)
      for (int b = 0; b < 3; b++)
        if (a != b && !strcmp(seg, models[a])) st_map_remove(nd, models[b]);
    return CUP_OK;
  }
  if (!strcmp(path, "netlist") && nd->kind == ST_SCALAR) {   /* netlist.R1=2: {file: ..., R1: 2} */
    st_node *m = st_new_map(k);
    if (!m || st_map_put(m, "file", nd, k)) { st_free(m); return CUP_ERR_NOMEM; }
    *slot = m;
    return CUP_OK;
  }
  if (!strcmp(path, "output") && (nd->kind != ST_MAP || nd->len != 1 || strcmp(nd->key[0]->text, seg)))
    return replace_by_map(slot, k);
  if (!strcmp(path, "tol") && nd->kind != ST_MAP) return replace_by_map(slot, k);
  if (!strcmp(path, "projector") && nd->kind == ST_SCALAR) {
    st_node *m = st_new_map(k);
    if (!m || st_map_put(m, "method", nd, k)) { st_free(m); return CUP_ERR_NOMEM; }
    *slot = m;
    return CUP_OK;
  }
  if (inline_or_file(path) && nd->kind != ST_MAP && !isdigit((unsigned char)seg[0]))
    return replace_by_map(slot, k);
  int wave = val && val->kind == ST_SCALAR ? cup_wave_parse(val->text) : -1;
  if (!strncmp(path, "input", 5) && nd->kind == ST_MAP && !strcmp(seg, "type") && wave >= 0) {
    const st_node *bad;
    while ((bad = st_unknown_key(nd, scene_wave_keys[wave]))) st_map_remove(nd, bad->text);
  }
  return CUP_OK;
}

int scene_verbatim(const char *key) {
  static const char *const own[] = {"file", "text", "name", "probe", NULL};
  if (strncmp(key, "netlist.", 8) || strchr(key + 8, '.')) return 0;
  for (int i = 0; own[i]; i++)
    if (!strcmp(key + 8, own[i])) return 0;
  return 1;
}

/* scene_steady — the scene key steady_state: (scene_steady.h,
 * docs/steady-state.md). */
#define _POSIX_C_SOURCE 200809L
#include <limits.h>
#include <strings.h>
#include "scene_steady.h"
#include "model/netlist_impl.h"

void scene_steady_free(scene_steady *s) {
  if (!s) return;
  int n = s->pub.nmeasure + s->pub.npower;
  for (int k = 0; s->own && k < n; k++) free(s->own[k]);
  free(s->own);
  free(s->list);
  memset(s, 0, sizeof *s);
}

/* A word or a list of them into own[*n ...] (duplicates kept once). */
static int words(rd *r, const st_node *nd, const char *key, scene_steady *s, int cap, int *n,
                 const char **first) {
  int cnt = nd->kind == ST_SEQ ? nd->len : 1;
  for (int k = 0; k < cnt; k++) {
    const st_node *it = nd->kind == ST_SEQ ? nd->item[k] : nd;
    char kk[KEY_LEN];
    const char *w = NULL;
    int st = string(r, it, nd->kind == ST_SEQ ? joini(kk, key, k) : key, &w);
    if (st) return st;
    int seen = 0;
    for (int j = 0; j < *n; j++) seen |= !strcasecmp(first[j], w);
    if (seen) continue;
    if (*n >= cap) return fail(r, CUP_ERR_PARSE, it, key, "too many entries (at most %d)", cap);
    char *c = strdup(w);
    if (!c) return CUP_ERR_NOMEM;
    s->own[s->pub.nmeasure + s->pub.npower] = c;
    first[(*n)++] = c;
  }
  return CUP_OK;
}

/* An element of the netlist (for power: and efficiency:). */
static int element(rd *r, const st_node *it, const char *key, const cup_netlist *nl, const char *name) {
  const char *a, *b;
  char msg[CUP_ERRMSG_LEN];
  if (cup_netlist_element_nodes(nl, name, &a, &b, msg)) return fail(r, CUP_ERR_PARSE, it, key, "%s", msg);
  return CUP_OK;
}

static int lists(rd *r, const st_node *map, const cup_netlist *nl, scene_steady *s) {
  const st_node *nd, *kn;
  char key[KEY_LEN];
  int cap = 64, st = CUP_OK;
  if (!(s->own = calloc(2 * (size_t)cap, sizeof *s->own)) || !(s->list = calloc(2 * (size_t)cap, sizeof *s->list)))
    return CUP_ERR_NOMEM;
  static const char *const need_nl[] = {"measure", "power", "efficiency", NULL};
  for (int k = 0; need_nl[k] && !nl; k++)
    if (opt(map, need_nl[k]) && st_get(map, need_nl[k], &kn))
      return fail(r, CUP_ERR_PARSE, kn, join(key, "steady_state", need_nl[k]),
                  "needs a netlist: (its signals and elements by name)");
  if ((nd = opt(map, "measure"))) {
    st = words(r, nd, "steady_state.measure", s, cap, &s->pub.nmeasure, s->list);
    for (int k = 0; !st && k < s->pub.nmeasure; k++) {
      char msg[CUP_ERRMSG_LEN];
      if (nl_probe_check(nl, s->list[k], msg, sizeof msg)) st = fail(r, CUP_ERR_PARSE, nd, "steady_state.measure", "%s", msg);
    }
  }
  const char **pw = s->list + cap;
  s->pub.eff_out = s->pub.eff_in = -1;
  if (!st && (nd = opt(map, "power"))) {
    st = words(r, nd, "steady_state.power", s, cap, &s->pub.npower, pw);
    for (int k = 0; !st && k < s->pub.npower; k++) st = element(r, nd, "steady_state.power", nl, pw[k]);
  }
  if (!st && (nd = opt(map, "efficiency"))) {
    if (nd->kind != ST_SEQ || nd->len != 2)
      return fail(r, CUP_ERR_PARSE, nd, "steady_state.efficiency", "expected [OUTPUT, INPUT]: the element that takes "
                  "the power and the source that delivers it (efficiency: [RL, V1])");
    int before = s->pub.npower;
    st = words(r, nd, "steady_state.efficiency", s, cap, &s->pub.npower, pw);
    for (int k = before; !st && k < s->pub.npower; k++) st = element(r, nd, "steady_state.efficiency", nl, pw[k]);
    for (int k = 0; !st && k < s->pub.npower; k++) {
      if (!strcasecmp(pw[k], nd->item[0]->text)) s->pub.eff_out = k;
      if (!strcasecmp(pw[k], nd->item[1]->text)) s->pub.eff_in = k;
    }
    if (!st && s->pub.eff_out == s->pub.eff_in)
      st = fail(r, CUP_ERR_PARSE, nd, "steady_state.efficiency", "the output and the input are the same element");
  }
  /* the measure texts first, then the power names, contiguous for the public view */
  if (!st) memmove(s->list + s->pub.nmeasure, pw, sizeof *pw * (size_t)s->pub.npower);
  s->pub.measure = s->list;
  s->pub.power = s->list + s->pub.nmeasure;
  return st;
}

int scene_read_steady(rd *r, const st_node *root, cup_netlist *nl, scene_steady *s) {
  static const char *const known[] = {"enabled", "period", "samples", "tol", "max_iter", "map_tol", "fd_step",
                                      "warmup_periods", "harmonics", "fallback", "measure", "power", "efficiency",
                                      NULL};
  const st_node *map = opt(root, "steady_state"), *nd;
  memset(s, 0, sizeof *s);
  double nl_period = 0;
  int nl_asks = nl && cup_netlist_steady_state(nl, &nl_period);
  if (!map && !nl_asks) return CUP_OK;
  cup_scene_steady *p = &s->pub;
  cup_pss_options_default(&p->pss);
  p->samples = 2001;
  p->harmonics = 10;
  p->fallback = 1;
  p->eff_out = p->eff_in = -1;
  p->pss.period = nl_period;                     /* .options steadystate / steadyperiod=T: the key overrides */
  s->enabled = nl_asks;
  if (!map) return CUP_OK;
  if (map->kind == ST_SCALAR) return boolean(r, map, "steady_state", &s->enabled);
  int st = need_map(r, map, "steady_state", "true, false or a mapping of keys such as period and measure");
  if (!st) st = check_keys(r, map, "steady_state", known);
  s->enabled = 1;
  long v;
  if (!st && (nd = opt(map, "enabled"))) st = boolean(r, nd, "steady_state.enabled", &s->enabled);
  if (!st && (nd = opt(map, "period"))) st = number_min(r, nd, "steady_state.period", 0, 1, &p->pss.period);
  if (!st && (nd = opt(map, "samples"))) st = integer(r, nd, "steady_state.samples", 3, 100000000, &p->samples);
  if (!st && (nd = opt(map, "tol"))) st = number_min(r, nd, "steady_state.tol", 0, 1, &p->pss.tol);
  if (!st && (nd = opt(map, "map_tol"))) st = number_min(r, nd, "steady_state.map_tol", 0, 0, &p->pss.map_tol);
  if (!st && (nd = opt(map, "fd_step"))) st = number_min(r, nd, "steady_state.fd_step", 0, 1, &p->pss.fd_step);
  if (!st && (nd = opt(map, "max_iter")) && !(st = integer(r, nd, "steady_state.max_iter", 1, CUP_PSS_MAX_ITER, &v)))
    p->pss.max_iter = (int)v;
  if (!st && (nd = opt(map, "warmup_periods")) &&
      !(st = integer(r, nd, "steady_state.warmup_periods", 0, INT_MAX, &v)))
    p->pss.warmup_periods = (int)v;
  if (!st && (nd = opt(map, "harmonics")) && !(st = integer(r, nd, "steady_state.harmonics", 0, 1000, &v)))
    p->harmonics = (int)v;
  if (!st && 2L * p->harmonics >= p->samples - 1)
    st = fail(r, CUP_ERR_PARSE, map, "steady_state.harmonics", "%d harmonics need more than %d samples a period "
              "(samples: %ld)", p->harmonics, 2 * p->harmonics + 1, p->samples);
  if (!st && (nd = opt(map, "fallback"))) st = boolean(r, nd, "steady_state.fallback", &p->fallback);
  if (!st) st = lists(r, map, nl, s);
  return st;
}

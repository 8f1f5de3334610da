/* scene_netlist — the scene key `netlist:` (docs/netlist.md): a netlist file
 * (or its text) as the scene's model, with element and .param values set
 * from the scene, and the signals to record:
 *
 *     netlist: rectifier.cir
 *     netlist: {file: rectifier.cir, R1: 2k, vin: 5, probe: [v(out), i(D1)]}
 *     netlist: {text: "...", name: rect.cir}
 *
 * so that a sweep variant's `set: {netlist.R1: 2}` varies any value. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include <math.h>
#include "integrator/freestep.h"
#include "model/input_impl.h"
#include "model/lcs_impl.h"
#include "projector/choose.h"
#include "set/polyset_impl.h"
#include "scene_netlist.h"
#include "netlist_lex.h"
#include "read_text.h"
#include "util/path.h"

static int is_word(const char *k, const char *const *words) {
  for (int i = 0; words[i]; i++)
    if (!strcmp(k, words[i])) return 1;
  return 0;
}

/* Every key of the mapping but file, text, name and probe: NAME=VALUE. */
static int collect_sets(const st_src *src, const st_node *map, char ***sets, int *nsets, char *errmsg) {
  static const char *const own[] = {"file", "text", "name", "probe", NULL};
  *sets = calloc((size_t)map->len + 1, sizeof(char *));
  if (!*sets) return CUP_ERR_NOMEM;
  for (int k = 0; k < map->len; k++) {
    const char *key = map->key[k]->text;
    if (is_word(key, own)) continue;
    const st_node *v = map->item[k];
    char dotted[160];
    snprintf(dotted, sizeof dotted, "netlist.%.140s", key);
    if (v->kind != ST_SCALAR || st_is_null(v))
      return st_error(errmsg, CUP_ERR_PARSE, src, v, dotted, "expected a value for the element or .param %.60s "
                      "(a number such as 2.2k, or a source such as 'SIN(0 5 50)')", key);
    size_t len = strlen(key) + strlen(v->text) + 2;
    char *s = malloc(len);
    if (!s) return CUP_ERR_NOMEM;
    snprintf(s, len, "%s=%s", key, v->text);
    (*sets)[(*nsets)++] = s;
  }
  return CUP_OK;
}

/* A message located in the netlist passes as it is; one about a set gets
 * the place of the scene's value that made it (a line, or an override). */
static int netlist_fail(const st_src *src, const st_node *at, const st_node *map, int st, const char *msg,
                        const char *file, char *errmsg) {
  size_t n = strlen(file);
  if (!strncmp(msg, file, n) && msg[n] == ':' && msg[n + 1] >= '0' && msg[n + 1] <= '9') {
    if (errmsg) snprintf(errmsg, CUP_ERRMSG_LEN, "%s", msg);
    return st;
  }
  const char *set = strstr(msg, "set '");
  if (set && map && map->kind == ST_MAP) {
    set += 5;
    size_t len = strcspn(set, "=");
    for (int k = 0; k < map->len; k++)
      if (strlen(map->key[k]->text) == len && !strncmp(map->key[k]->text, set, len)) at = map->item[k];
  }
  return st_error(errmsg, st, src, at, "netlist", "%s", msg);
}

static int string_of(const st_src *src, const st_node *nd, const char *key, const char **out, char *errmsg) {
  char b[64];
  if (!nd || nd->kind != ST_SCALAR || st_is_null(nd))
    return st_error(errmsg, CUP_ERR_PARSE, src, nd, key, "expected a string (got %s)", st_looks(nd, b, sizeof b));
  *out = nd->text;
  return CUP_OK;
}

/* probe: a signal or a list of them, each added to the netlist. */
static int read_probes(const st_src *src, const st_node *nd, cup_netlist *nl, char *errmsg) {
  int n = nd->kind == ST_SEQ ? nd->len : 1;
  for (int k = 0; k < n; k++) {
    const st_node *it = nd->kind == ST_SEQ ? nd->item[k] : nd;
    const char *sig = NULL;
    char key[32], lib[CUP_ERRMSG_LEN];
    snprintf(key, sizeof key, nd->kind == ST_SEQ ? "netlist.probe.%d" : "netlist.probe", k);
    int st = string_of(src, it, key, &sig, errmsg);
    if (st) return st;
    if ((st = cup_netlist_probe(nl, sig, lib)) < 0) return st_error(errmsg, st, src, it, key, "%s", lib);
  }
  return CUP_OK;
}

int scene_netlist_read(const st_src *src, const char *dir, const st_node *knode, const st_node *val,
                       cup_netlist **out, file_list *files, char *errmsg) {
  const st_node *fnode = val, *tnode = NULL, *nnode = NULL, *pnode = NULL;
  char **sets = NULL;
  int nsets = 0, st = CUP_OK;
  if (val->kind == ST_MAP) {
    fnode = st_get(val, "file", NULL);
    tnode = st_get(val, "text", NULL);
    nnode = st_get(val, "name", NULL);
    pnode = st_get(val, "probe", NULL);
    if (!fnode == !tnode)
      return st_error(errmsg, CUP_ERR_PARSE, src, val, "netlist", "give the netlist as file: or as text:, "
                      "one of them");
    st = collect_sets(src, val, &sets, &nsets, errmsg);
  }
  const char *file = NULL, *text = NULL, *name = NULL;
  char *path = NULL, lib[CUP_ERRMSG_LEN] = "";
  if (!st && fnode) st = string_of(src, fnode, fnode == val ? "netlist" : "netlist.file", &file, errmsg);
  if (!st && tnode) st = string_of(src, tnode, "netlist.text", &text, errmsg);
  if (!st && nnode) st = string_of(src, nnode, "netlist.name", &name, errmsg);
  if (!st && file && !(path = path_join(dir, file))) st = CUP_ERR_NOMEM;
  if (!st) {
    const char *shown = path ? path : name ? name : "netlist";
    st = path ? netlist_load_files(out, path, (const char *const *)sets, nsets, files, lib)
              : netlist_load_string_files(out, text, shown, (const char *const *)sets, nsets, files, lib);
    if (st) st = netlist_fail(src, fnode ? fnode : knode, val, st, lib, shown, errmsg);
  }
  if (!st && pnode) st = read_probes(src, pnode, *out, errmsg);
  if (st && *out) cup_netlist_free(out);
  for (int k = 0; k < nsets; k++) free(sets[k]);
  free(sets);
  free(path);
  return st;
}

/* Can the adaptive scheme run this netlist? Dense (the projector's exact
 * small-set path, which the adaptive and theta schemes' LCPs are),
 * a passive network (B = P^-1 C^T), an input its exosystem holds, states
 * plus generator states within the exponential's limit. */
static int adaptive_fits(const cup_netlist *nl) {
  const cup_lcs *L = cup_netlist_lcs(nl);
  const cup_polyset *K = cup_lcs_polyset(L);
  const cup_input *u = cup_netlist_input(nl);
  if (!proj_small_lcp(K, NULL) || L->keep_B || (u && input_gen_check(u, "adaptive", NULL))) return 0;
  return K->n + input_gen_dim(u, NULL, NULL) + 1 <= CUP_EXPONENTIAL_MAX_DIM;
}

void scene_netlist_sampling(const cup_netlist *nl, cup_integrator_options *o) {
  double tstep, tstop, tstart = 0, tmax = 0;
  if (!cup_netlist_tran(nl, &tstep, &tstop)) return;
  cup_netlist_tran_window(nl, &tstart, &tmax);
  double span = o->T - tstart, S = span > 0 ? floor(span / tstep + 0.5) + 1 : 2;
  o->output = CUP_OUTPUT_SAMPLES;
  o->output_t0 = span > 0 ? tstart : 0;
  o->output_samples = S < 2 ? 2 : S > 9007199254740992.0 ? 9007199254740992L : (long)S;
}

/* SPICE's meaning (docs/netlist.md): .tran TSTEP TSTOP TSTART TMAX gives T,
 * the output every TSTEP from TSTART, and the longest step; the adaptive
 * scheme runs to the tolerances of .options; n = TSTOP / TSTEP only for a
 * circuit the adaptive scheme cannot run (a fixed-step scheme chosen by the
 * user needs its own n or h, scene.c). */
void scene_netlist_options(const cup_netlist *nl, cup_integrator_options *o) {
  double tstep, tstop, tstart = 0, tmax = 0;
  if (cup_netlist_tran(nl, &tstep, &tstop)) {
    cup_netlist_tran_window(nl, &tstart, &tmax);
    o->T = tstop;
    double n = tstop / tstep;
    o->n = n < 1 ? 1 : n > 9007199254740992.0 ? 9007199254740992L : (long)(n + 0.5);
    o->hmax = tmax;
    scene_netlist_sampling(nl, o);
  }
  /* RELTOL relative, ABSTOL (currents) and VNTOL (voltages) absolute,
   * CHGTOL (charge) over the largest capacitance as a voltage; one tol on
   * the max norm of the state takes the smallest absolute part of the
   * kinds of state present */
  double reltol, abstol, vntol, chgtol, cmax = 0;
  cup_netlist_tolerances(nl, &reltol, &abstol, &vntol, &chgtol);
  if (isnan(reltol)) reltol = CUP_NETLIST_RELTOL;
  if (isnan(abstol)) abstol = CUP_NETLIST_ABSTOL;
  if (isnan(vntol)) vntol = CUP_NETLIST_VNTOL;
  if (isnan(chgtol)) chgtol = CUP_NETLIST_CHGTOL;
  const cup_lcs *L = cup_netlist_lcs(nl);
  const cup_polyset *K = cup_lcs_polyset(L);
  int inductors = 0, capacitors = 0;
  for (int j = 0; j < K->n; j++) {
    const char *name = cup_netlist_state_name(nl, j);
    if (name[0] == 'i') inductors = 1;
    else capacitors = 1;
    /* P = diag(L, C): a capacitor's entry is its capacitance */
    if (name[0] == 'v' && K->pkind == CUP_METRIC_DIAGONAL) cmax = fmax(cmax, K->pd[j]);
  }
  double atol = INFINITY;
  if (inductors) atol = fmin(atol, abstol);
  if (capacitors) atol = fmin(atol, fmin(vntol, cmax > 0 ? chgtol / cmax : INFINITY));
  o->tol_rel = reltol;
  o->tol_abs = isfinite(atol) ? atol : abstol;
  /* the adaptive scheme where it can run the circuit; else the theta
   * scheme (second order, every circuit within its dense limits), the
   * stable implicit scheme while it is dense enough, the explicit one
   * beyond, at n = TSTOP / TSTEP */
  o->scheme = adaptive_fits(nl) ? CUP_SCHEME_ADAPTIVE
              : proj_small_lcp(K, NULL) ? CUP_SCHEME_THETA
              : K->n <= CUP_IMPLICIT_MAX_DIM ? CUP_SCHEME_IMPLICIT : CUP_SCHEME_EXPLICIT;
}

/* scene — scene files (YAML) into an LCS, its input, x0 and the integrator
 * options (docs/scene-format.md). The document is copied into a tree that
 * keeps positions (scene_tree.c), overrides are spliced in, and the tree is
 * read key by key here; every error names FILE:LINE:COL and the dotted key
 * (or the override it came from). Nothing heavy is computed. */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <float.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "util/linalg.h"
#include "util/names.h"
#include "mtx.h"
#include "scene_read.h"
#include "scene_set.h"
#include "scene_crowd.h"
#include "scene_shape.h"
#include "scene_tree.h"
#include "read_text.h"
#include "scene_netlist.h"
#include "util/path.h"
#include "scene_steady.h"
#include "model/input_impl.h"

struct cup_scene {
  char *name;
  cup_lcs *lcs;
  scene_process *proc;          /* a general process (set:, f:) instead of an LCS */
  cup_crowd *crowd;             /* or a crowd (crowd:) */
  cup_netlist *nl;              /* netlist: the model (its LCS and input) */
  cup_input *u;                 /* NULL when p = 0; read from the time origin on */
  cup_input *u_written;         /* the input as written while the time origin is not 0 */
  double *x0;
  cup_integrator_options opt;
  char *eps_spec, *eta_spec;    /* as written */
  char *text;                   /* the document after overrides */
  file_list files;          /* every file read: the scene's, its Matrix Market files, its netlist's */
  long max_steps;               /* the key max_steps: the most steps a fixed-step run may take */
  int circuit;                  /* the model is circuit: (its states have names) */
  int steps_given;              /* the scene gave n or h (a netlist's .tran gives neither) */
  scene_steady steady;          /* steady_state: */
};

/* The choice lists' words, NULL-terminated, for suggestions (CUP_*_LIST). */
#define WORD4_(e, v, name, doc) name,
#define WORD5_(e, v, name, form, doc) name,
static const char *const scheme_names[] = {CUP_SCHEME_LIST(WORD4_) NULL};
static const char *const method_names[] = {CUP_PROJ_METHOD_LIST(WORD4_) NULL};
static const char *const output_names[] = {CUP_OUTPUT_LIST(WORD5_) NULL};
static const char *const wave_names[] = {CUP_WAVE_LIST(WORD4_) NULL};
#undef WORD4_
#undef WORD5_

/* ---- the model: circuit or lcs ------------------------------------------- */

static int read_circuit(rd *r, const st_node *knode, const st_node *map, cup_lcs **L) {
  static const char *const known[] = {"R1", "R2", "R3", "L2", "L3", "C4", "G", NULL};
  char key[KEY_LEN], lib[CUP_ERRMSG_LEN];
  cup_circuit c = {0};
  double *v[6] = {&c.R1, &c.R2, &c.R3, &c.L2, &c.L3, &c.C4};
  int st = need_map(r, map, "circuit", "a mapping with R1, R2, R3, L2, L3, C4 and optionally G");
  if (!st) st = check_keys(r, map, "circuit", known);
  for (int k = 0; k < 6 && !st; k++) {        /* resistances >= 0; inductances, capacitance > 0 */
    const st_node *nd;
    st = need(r, map, "circuit", known[k], &nd);
    if (!st) st = number_min(r, nd, join(key, "circuit", known[k]), 0, k >= 3, v[k]);
  }
  const st_node *g = st ? NULL : opt(map, "G");
  if (g) {
    double *gv;
    st = vector(r, g, "circuit.G", 2, "g1, g2", &gv);
    if (!st) { c.G[0] = gv[0]; c.G[1] = gv[1]; free(gv); }
  }
  if (!st && (st = cup_lcs_circuit(L, &c, lib))) st = fail(r, st, knode, "circuit", "%s", lib);
  return st;
}

/* The matrices of an lcs, owned until the LCS has copied them. */
typedef struct lcs_parts {
  mat A, B, C, D, E, G, P;
  double *F, *Pdiag;
  const st_node *Pnode;
} lcs_parts;

static void parts_free(lcs_parts *q) {
  mat_free(&q->A); mat_free(&q->B); mat_free(&q->C);
  mat_free(&q->D); mat_free(&q->E); mat_free(&q->G); mat_free(&q->P);
  free(q->F); free(q->Pdiag);
}

/* An optional matrix key of the lcs mapping, with its expected rows. */
static int lcs_matrix(rd *r, const st_node *map, const char *k, mat *M) {
  char key[KEY_LEN];
  const st_node *nd = opt(map, k);
  return nd ? matrix(r, nd, join(key, "lcs", k), M) : CUP_OK;
}

/* p is the number of columns of E or G; both given must agree. */
static int input_dim(rd *r, const lcs_parts *q, int n, int m, int *p) {
  char why[48];
  *p = q->E.a.p ? q->E.a.ncol : q->G.a.p ? q->G.a.ncol : 0;
  snprintf(why, sizeof why, "n = %d from C's columns, p = %d", n, *p);
  if (q->E.a.p && q->E.a.nrow != n) return matrix_dims(r, &q->E, "lcs.E", n, *p, why);
  snprintf(why, sizeof why, "m = %d from C's rows, p = %d from %s", m, *p, q->E.a.p ? "E's columns" : "G");
  if (q->G.a.p) return matrix_dims(r, &q->G, "lcs.G", m, *p, why);
  return CUP_OK;
}

/* Errors of cup_lcs_create point at the key that caused them. */
static int lcs_fail(rd *r, int st, const char *lib, const st_node *knode, const lcs_parts *q) {
  if ((st == CUP_ERR_NOT_SPD || st == CUP_ERR_LINALG) && q->Pnode)
    return fail(r, st, q->Pnode, "lcs.P", "%s", lib);
  if (st == CUP_ERR_PB_CT && q->B.at) return fail(r, st, q->B.at, "lcs.B", "%s", lib);
  if (q->D.at && !strncmp(lib, "D ", 2)) return fail(r, st, q->D.at, "lcs.D", "%s", lib);
  return fail(r, st, knode, "lcs", "%s", lib);
}

static int read_lcs(rd *r, const st_node *knode, const st_node *map, cup_lcs **L) {
  static const char *const known[] = {"A", "B", "C", "D", "E", "F", "G", "P", "pb_tol", NULL};
  char why[64], lib[CUP_ERRMSG_LEN];
  lcs_parts q = {0};
  cup_lcs_desc d = {0};
  const st_node *nd;
  int n = 0, m = 0;
  int st = need_map(r, map, "lcs", "a mapping with the matrices A, B, C, D, E, F, G, P");
  if (!st) st = check_keys(r, map, "lcs", known);
  if (!st) st = need(r, map, "lcs", "C", &nd);
  if (!st) st = matrix(r, nd, "lcs.C", &q.C);
  if (!st) { n = q.C.a.ncol; m = q.C.a.nrow; snprintf(why, sizeof why, "n x n, n = %d from C's columns", n); }
  if (!st) st = lcs_matrix(r, map, "A", &q.A);
  if (!st && q.A.a.p) st = matrix_dims(r, &q.A, "lcs.A", n, n, why);
  if (!st) st = lcs_matrix(r, map, "B", &q.B);
  if (!st && q.B.a.p) snprintf(why, sizeof why, "n x m = C's columns x C's rows");
  if (!st && q.B.a.p) st = matrix_dims(r, &q.B, "lcs.B", n, m, why);
  if (!st) st = lcs_matrix(r, map, "E", &q.E);
  if (!st) st = lcs_matrix(r, map, "G", &q.G);
  if (!st) st = lcs_matrix(r, map, "D", &q.D);
  if (!st && q.D.a.p) st = matrix_dims(r, &q.D, "lcs.D", m, m, "m x m, m = C's rows");
  if (!st) st = input_dim(r, &q, n, m, &d.p);
  if (!st && (nd = opt(map, "F"))) {
    snprintf(why, sizeof why, "m = %d from C's rows", m);
    st = vector(r, nd, "lcs.F", m, why, &q.F);
  }
  if (!st) {
    snprintf(why, sizeof why, "n = %d from C's columns", n);
    q.Pnode = opt(map, "P");
    st = read_metric(r, q.Pnode, "lcs.P", n, why, &q.P, &q.Pdiag, &d.P);
  }
  if (!st && (nd = opt(map, "pb_tol"))) st = number_min(r, nd, "lcs.pb_tol", 0, 0, &d.pb_tol);
  if (!st) {
    d.n = n; d.m = m; d.F = q.F;
    d.A = mat_view(&q.A); d.B = mat_view(&q.B); d.C = mat_view(&q.C);
    d.E = mat_view(&q.E); d.G = mat_view(&q.G); d.D = mat_view(&q.D);
    if ((st = cup_lcs_create(L, &d, lib))) st = lcs_fail(r, st, lib, knode, &q);
  }
  parts_free(&q);
  return st;
}

static int read_model(rd *r, const st_node *root, cup_scene *S) {
  const st_node *kc, *kl, *kn;
  const st_node *c = st_get(root, "circuit", &kc), *l = st_get(root, "lcs", &kl), *nl = st_get(root, "netlist", &kn);
  if (!!c + !!l + !!nl > 1) {
    const st_node *k2 = c && l ? (kc->line > kl->line ? kc : kl) : nl && (c || l) ? kn : kc;
    return fail(r, CUP_ERR_PARSE, k2, k2->text, "give one model, circuit, lcs or netlist, not two");
  }
  S->circuit = c != NULL;
  if (c) return read_circuit(r, kc, c, &S->lcs);
  if (l) return read_lcs(r, kl, l, &S->lcs);
  if (nl) return scene_netlist_read(&r->src, r->dir, kn, nl, &S->nl, r->files, r->errmsg);
  return fail(r, CUP_ERR_PARSE, root, "circuit/lcs/netlist/set", "missing: the scene needs a model, circuit:, "
              "lcs:, netlist:, set: or crowd:");
}

/* ---- the input u(t) ------------------------------------------------------ */


static int read_points(rd *r, const st_node *nd, const char *key, cup_wave *w, double **buf) {
  char k1[KEY_LEN], k2[KEY_LEN], b[64];
  if (nd->kind != ST_SEQ || nd->len == 0)
    return fail(r, CUP_ERR_PARSE, nd, key, "expected a list of [t, value] points (got %s)", st_looks(nd, b, sizeof b));
  *buf = malloc(sizeof(double) * 2 * (size_t)nd->len);
  if (!*buf) return CUP_ERR_NOMEM;
  double *t = *buf, *v = *buf + nd->len;
  for (int k = 0; k < nd->len; k++) {
    const st_node *pt = nd->item[k];
    joini(k1, key, k);
    if (pt->kind != ST_SEQ || pt->len != 2)
      return fail(r, CUP_ERR_PARSE, pt, k1, "expected a point [t, value] (got %s)", st_looks(pt, b, sizeof b));
    int st = number(r, pt->item[0], joini(k2, k1, 0), &t[k]);
    if (!st) st = number(r, pt->item[1], joini(k2, k1, 1), &v[k]);
    if (st) return st;
    if (k > 0 && !(t[k] > t[k - 1]))
      return fail(r, CUP_ERR_PARSE, pt, k1, "times must increase strictly (got %g after %g)", t[k], t[k - 1]);
  }
  w->npoints = nd->len;
  w->t = t;
  w->v = v;
  return CUP_OK;
}

/* The fields of a sine or square term. */
static int read_wave(rd *r, const st_node *map, const char *key, cup_wave *w) {
  char k1[KEY_LEN];
  const st_node *nd;
  int st = need(r, map, key, "amplitude", &nd);
  if (!st) st = number(r, nd, join(k1, key, "amplitude"), &w->amplitude);
  if (!st) st = need(r, map, key, "frequency", &nd);
  if (!st) st = number_min(r, nd, join(k1, key, "frequency"), 0, 0, &w->frequency);
  if (!st && (nd = opt(map, "phase"))) st = number(r, nd, join(k1, key, "phase"), &w->phase);
  return st;
}

/* A pulse's values (required) and times, a damped sine's delay and damping
 * (each 0 unless given; times >= 0). */
static int read_spice_wave(rd *r, const st_node *map, const char *key, cup_wave *w) {
  char k1[KEY_LEN];
  const st_node *nd;
  int pulse = w->kind == CUP_WAVE_PULSE, st = CUP_OK;
  const char *const pk[] = {"value", "value2", "delay", "rise", "fall", "width", "period"};
  double *pv[] = {&w->value, &w->value2, &w->delay, &w->rise, &w->fall, &w->width, &w->period};
  const char *const dk[] = {"delay", "damping"};
  double *dv[] = {&w->delay, &w->damping};
  int count = pulse ? 7 : 2;
  for (int k = 0; k < count && !st; k++) {
    const char *name = pulse ? pk[k] : dk[k];
    double *v = pulse ? pv[k] : dv[k];
    int required = pulse && k < 2, any_sign = required || (!pulse && k == 1);
    if (required) st = need(r, map, key, name, &nd);
    else if (!(nd = opt(map, name))) continue;
    if (!st) st = any_sign ? number(r, nd, join(k1, key, name), v) : number_min(r, nd, join(k1, key, name), 0, 0, v);
  }
  return st;
}

static int read_term_map(rd *r, const st_node *map, const char *key, cup_input *u, int j) {
  char k1[KEY_LEN], hint[ST_HINT_LEN], lib[CUP_ERRMSG_LEN];
  const st_node *tn = NULL, *nd = NULL;
  const char *type = "";
  int st = need(r, map, key, "type", &tn);
  if (!st) st = string(r, tn, join(k1, key, "type"), &type);
  if (st) return st;
  int kind = cup_wave_parse(type);
  if (kind < 0)
    return fail(r, CUP_ERR_PARSE, tn, k1, "unknown input type '%.40s' (%s)", type,
                st_suggest(hint, sizeof hint, type, wave_names));
  cup_wave w = {0};
  double *buf = NULL;
  w.kind = (cup_wave_kind)kind;
  st = check_keys(r, map, key, scene_wave_keys[kind]);
  if (!st && kind == CUP_WAVE_CONSTANT) {
    st = need(r, map, key, "value", &nd);
    if (!st) st = number(r, nd, join(k1, key, "value"), &w.value);
  }
  if (!st && (kind == CUP_WAVE_SINE || kind == CUP_WAVE_SQUARE || kind == CUP_WAVE_DAMPED_SINE))
    st = read_wave(r, map, key, &w);
  if (!st && (kind == CUP_WAVE_PULSE || kind == CUP_WAVE_DAMPED_SINE)) st = read_spice_wave(r, map, key, &w);
  if (!st && kind == CUP_WAVE_PWL) {
    st = need(r, map, key, "points", &nd);
    if (!st) st = read_points(r, nd, join(k1, key, "points"), &w, &buf);
  }
  if (!st && (st = cup_input_add(u, j, &w, lib))) st = fail(r, st, map, key, "%s", lib);
  free(buf);
  return st;
}

/* A term: a number (a constant) or a mapping with a type. */
static int read_term(rd *r, const st_node *nd, const char *key, cup_input *u, int j) {
  char b[64];
  if (nd->kind == ST_MAP) return read_term_map(r, nd, key, u, j);
  if (nd->kind == ST_SCALAR && !st_is_null(nd)) {
    cup_wave w = {0};
    char lib[CUP_ERRMSG_LEN];
    w.kind = CUP_WAVE_CONSTANT;
    int st = number(r, nd, key, &w.value);
    if (!st && (st = cup_input_add(u, j, &w, lib))) st = fail(r, st, nd, key, "%s", lib);
    return st;
  }
  return fail(r, CUP_ERR_PARSE, nd, key, "expected an input term: a number or a mapping with a type "
              "(constant, sine, square, pwl, pulse, damped_sine) (got %s)", st_looks(nd, b, sizeof b));
}

/* One component u_j: a term, or a list of terms (their sum). */
static int read_component(rd *r, const st_node *nd, const char *key, cup_input *u, int j) {
  char k1[KEY_LEN];
  if (nd->kind != ST_SEQ) return read_term(r, nd, key, u, j);
  for (int k = 0; k < nd->len; k++) {
    int st = read_term(r, nd->item[k], joini(k1, key, k), u, j);
    if (st) return st;
  }
  return CUP_OK;
}

static int read_input(rd *r, const st_node *root, int p, cup_input **u) {
  char k1[KEY_LEN], lib[CUP_ERRMSG_LEN], b[64];
  const st_node *kn, *nd = st_get(root, "input", &kn);
  if (st_is_null(nd)) nd = NULL;
  *u = NULL;
  if (p == 0)
    return nd ? fail(r, CUP_ERR_DIM, kn, "input", "the model has no input (p = 0: no E or G); remove input") : CUP_OK;
  int st = cup_input_create(u, p, lib);
  if (st) return fail(r, st, kn, "input", "%s", lib);
  if (!nd) return CUP_OK;                      /* u = 0 */
  if (p == 1) return read_component(r, nd, "input", *u, 0);
  if (nd->kind != ST_SEQ)
    return fail(r, CUP_ERR_DIM, nd, "input", "expected a list of %d components, one per input (got %s)", p,
                st_looks(nd, b, sizeof b));
  if (nd->len != p)
    return fail(r, CUP_ERR_DIM, nd, "input", "expected %d components, one per input (p = %d from E/G), got %d",
                p, p, nd->len);
  for (int j = 0; j < p && !st; j++) st = read_component(r, nd->item[j], joini(k1, "input", j), *u, j);
  return st;
}

/* ---- run settings -------------------------------------------------------- */

static int read_schedule(rd *r, const st_node *root, const char *key, const char *dflt, cup_schedule *s,
                         char **spec) {
  char lib[CUP_ERRMSG_LEN], b[64];
  const st_node *nd = opt(root, key);
  if (nd && nd->kind != ST_SCALAR)
    return fail(r, CUP_ERR_PARSE, nd, key, "expected a schedule like \"n^-2.1\" or a number (got %s)",
                st_looks(nd, b, sizeof b));
  const char *text = nd ? nd->text : dflt;
  int st = cup_schedule_parse(text, s, lib);
  if (st) return fail(r, st, nd, key, "%s", lib);
  *spec = strdup(text);
  return *spec ? CUP_OK : CUP_ERR_NOMEM;
}


/* A word from a list, parsed by the library's own parser. */
static int read_word(rd *r, const st_node *nd, const char *key, const char *what, const char *const *names,
                     int (*parse)(const char *), int *out) {
  char hint[ST_HINT_LEN];
  const char *w = "";
  int st = string(r, nd, key, &w);
  if (st) return st;
  *out = parse(w);
  if (*out >= 0) return CUP_OK;
  return fail(r, CUP_ERR_PARSE, nd, key, "unknown %s '%.40s' (%s)", what, w, st_suggest(hint, sizeof hint, w, names));
}

static int read_projector(rd *r, const st_node *nd, cup_projector_options *po) {
  static const char *const known[] = {"method", "max_iter", NULL};
  int method = po->method, st;
  if (nd->kind != ST_MAP) {
    st = read_word(r, nd, "projector", "projector method", method_names, cup_proj_method_parse, &method);
    po->method = (cup_proj_method)method;
    return st;
  }
  const st_node *v;
  st = check_keys(r, nd, "projector", known);
  if (!st && (v = opt(nd, "method"))) {
    st = read_word(r, v, "projector.method", "projector method", method_names, cup_proj_method_parse, &method);
    po->method = (cup_proj_method)method;
  }
  long it = 0;
  if (!st && (v = opt(nd, "max_iter")) && !(st = integer(r, v, "projector.max_iter", 1, INT_MAX, &it)))
    po->max_iter = (int)it;
  return st;
}

/* output: one of CUP_OUTPUT_LIST's forms, a word ("final") or a mapping with
 * one key ("{every: K}"). */
static int read_output(rd *r, const st_node *nd, cup_integrator_options *o) {
#define FORM_(e, v, name, form, doc) form,
  static const char *const forms[] = {CUP_OUTPUT_LIST(FORM_) NULL};
#undef FORM_
  const char *words[CUP_OUTPUT_COUNT + 1], *keys[CUP_OUTPUT_COUNT + 1];
  int nw = 0, nk = 0;
  for (int k = 0; k < CUP_OUTPUT_COUNT; k++) {
    if (forms[k][0] == '{') keys[nk++] = output_names[k];
    else words[nw++] = output_names[k];
  }
  words[nw] = keys[nk] = NULL;
  char b[64], hint[ST_HINT_LEN], expected[160];
  words_join(expected, sizeof expected, forms, "or");
  int kind = nd->kind == ST_SCALAR && !nd->quoted ? cup_output_parse(nd->text) : -1;
  if (kind >= 0 && forms[kind][0] != '{') { o->output = (cup_output_kind)kind; return CUP_OK; }
  if (nd->kind == ST_SCALAR)
    return fail(r, CUP_ERR_PARSE, nd, "output", "expected %s (got '%.40s'; %s)", expected, nd->text,
                st_suggest(hint, sizeof hint, nd->text, words));
  if (nd->kind != ST_MAP || nd->len != 1)
    return fail(r, CUP_ERR_PARSE, nd, "output", "expected %s (got %s)", expected,
                nd->kind == ST_MAP ? "a mapping with more than one key" : st_looks(nd, b, sizeof b));
  int st = check_keys(r, nd, "output", keys);
  const st_node *v = nd->item[0];
  kind = cup_output_parse(nd->key[0]->text);
  if (!st && kind == CUP_OUTPUT_EVERY) {
    o->output = CUP_OUTPUT_EVERY;
    st = integer(r, v, "output.every", 1, LONG_MAX, &o->output_every);
  } else if (!st && kind == CUP_OUTPUT_TOL) {
    o->output = CUP_OUTPUT_TOL;
    st = number_min(r, v, "output.tol", 0, 1, &o->output_tol);
  } else if (!st) {
    o->output = CUP_OUTPUT_SAMPLES;
    st = integer(r, v, "output.samples", 2, LONG_MAX, &o->output_samples);
  }
  return st;
}

/* Scheme, projector, output (all optional). */
static int read_method(rd *r, const st_node *root, cup_integrator_options *o) {
  const st_node *nd;
  int st = CUP_OK, scheme;
  if ((nd = opt(root, "scheme")) &&
      !(st = read_word(r, nd, "scheme", "scheme", scheme_names, cup_scheme_parse, &scheme)))
    o->scheme = (cup_scheme)scheme;
  if (!st && (nd = opt(root, "theta"))) {
    st = number_min(r, nd, "theta", 0, 0, &o->theta);
    if (!st && !(o->theta <= 1)) st = fail(r, CUP_ERR_PARSE, nd, "theta", "must be in [0, 1] (got %g)", o->theta);
  }
  if (!st && (nd = opt(root, "projector"))) st = read_projector(r, nd, &o->proj);
  if (!st && (nd = opt(root, "output"))) st = read_output(r, nd, o);
  return st;
}

/* The adaptive scheme's keys: tol (its error target on x: one number for
 * both the absolute and the relative part, or {abs, rel}) and
 * max_event_rate; and estimate (the fixed-step schemes' step doubling). */
static int read_tolerance(rd *r, const st_node *root, cup_integrator_options *o) {
  static const char *const known[] = {"abs", "rel", NULL};
  const st_node *nd, *v;
  int st = CUP_OK;
  if ((nd = opt(root, "tol")) && nd->kind == ST_MAP) {
    st = check_keys(r, nd, "tol", known);
    o->tol_abs = o->tol_rel = 0;
    if (!st && (v = opt(nd, "abs"))) st = number_min(r, v, "tol.abs", 0, 0, &o->tol_abs);
    if (!st && (v = opt(nd, "rel"))) st = number_min(r, v, "tol.rel", 0, 0, &o->tol_rel);
    if (!st && !(o->tol_abs > 0 || o->tol_rel > 0))
      st = fail(r, CUP_ERR_PARSE, nd, "tol", "abs or rel must be > 0");
  } else if (nd && !(st = number_min(r, nd, "tol", 0, 1, &o->tol_abs))) {
    o->tol_rel = o->tol_abs;
  }
  if (!st && nd && o->tol_abs == 0 && o->tol_rel < 16 * DBL_EPSILON)
    st = fail(r, CUP_ERR_PARSE, nd, "tol", "rel = %g with abs = 0 is below what double precision can "
              "deliver (16 eps = %.2g)", o->tol_rel, 16 * DBL_EPSILON);
  if (!st && (nd = opt(root, "max_event_rate")))
    st = number_min(r, nd, "max_event_rate", 0, 1, &o->max_event_rate);
  if (!st && (nd = opt(root, "hmax"))) st = number_min(r, nd, "hmax", 0, 1, &o->hmax);
  if (!st && (nd = opt(root, "estimate"))) st = boolean(r, nd, "estimate", &o->estimate);
  return st;
}

/* The adaptive scheme chooses its own steps: n is optional for it. */
static int is_adaptive(const st_node *root) {
  const st_node *nd = opt(root, "scheme");
  return nd && nd->kind == ST_SCALAR && cup_scheme_parse(nd->text) == CUP_SCHEME_ADAPTIVE;
}

/* T, n (or the step h) and the tolerance schedules. */
static int read_times(rd *r, const st_node *root, cup_scene *S) {
  const st_node *nd, *hn = opt(root, "h");
  cup_integrator_options *o = &S->opt;
  int tran = S->nl && cup_netlist_tran(S->nl, NULL, NULL);   /* .tran gives T (and the output) */
  int st = CUP_OK;
  if (!tran || opt(root, "T")) {
    st = need(r, root, "", "T", &nd);
    if (!st) st = number_min(r, nd, "T", 0, 1, &o->T);
    if (!st && tran) scene_netlist_sampling(S->nl, o);
  }
  if (!st && hn && opt(root, "n"))
    st = fail(r, CUP_ERR_PARSE, hn, "h", "give n or h, not both (n = T / h, rounded up)");
  if (!st && hn) {
    double h;
    st = number_min(r, hn, "h", 0, 1, &h);
    double n = ceil(o->T / h * (1 - 1e-12));   /* a step of at most h; T / h itself when it divides */
    if (!st && !(n <= 9007199254740992.0))
      st = fail(r, CUP_ERR_PARSE, hn, "h", "T / h = %g steps is more than 2^53", n);
    if (!st) o->n = n < 1 ? 1 : (long)n;
    S->steps_given = 1;
  } else if (!st && (!tran || opt(root, "n")) && !(is_adaptive(root) && !opt(root, "n"))) {
    st = need(r, root, "", "n", &nd);
    /* 2^53: every integer up to it is exact in a double */
    if (!st) st = integer(r, nd, "n", 1, 9007199254740992L, &o->n);
    S->steps_given = 1;
  }
  if (!st) st = read_schedule(r, root, "eps", "n^-2.1", &o->eps, &S->eps_spec);
  if (!st) st = read_schedule(r, root, "eta", "n^-1.05", &o->eta, &S->eta_spec);
  return st;
}

/* A netlist's .tran TSTEP is the output's spacing, not a step: a fixed-step
 * scheme the scene chooses for a circuit the adaptive scheme runs needs its
 * own n or h, and n or h without a scheme chooses theta (docs/netlist.md). */
static int netlist_steps(rd *r, const st_node *root, cup_scene *S, cup_scheme fallback) {
  if (S->nl && S->steps_given && fallback == CUP_SCHEME_ADAPTIVE && !opt(root, "scheme"))
    S->opt.scheme = CUP_SCHEME_THETA;
  if (!S->nl || S->steps_given || S->opt.scheme == CUP_SCHEME_ADAPTIVE || fallback != CUP_SCHEME_ADAPTIVE ||
      !cup_netlist_tran(S->nl, NULL, NULL))
    return CUP_OK;
  const st_node *nd = opt(root, "scheme");
  return fail(r, CUP_ERR_PARSE, nd ? nd : root, "n", "the %s scheme needs n or h: the netlist's .tran TSTEP is "
              "the output's spacing, not a step (give n: N or h: STEP; catchup-run --n N or --h STEP)",
              cup_scheme_name(S->opt.scheme));
}

/* T, n, the schedules and x0. */
static int read_run(rd *r, const st_node *root, int dim, cup_scene *S) {
  char why[48];
  const st_node *nd;
  int st = read_times(r, root, S);
  if (!st && (nd = opt(root, "x0"))) {
    snprintf(why, sizeof why, "n = %d, the state dimension", dim);
    st = vector(r, nd, "x0", dim, why, &S->x0);
  } else if (!st && !(S->x0 = calloc((size_t)dim, sizeof(double)))) {
    st = CUP_ERR_NOMEM;
  } else if (!st && S->nl) {
    memcpy(S->x0, cup_netlist_x0(S->nl), sizeof(double) * (size_t)dim);
  }
  return st;
}

/* The name, or the file's stem ("examples/paper-fig2.yaml" -> "paper-fig2"). */
static int read_name(rd *r, const st_node *root, cup_scene *S) {
  const st_node *nd = opt(root, "name");
  const char *name = "";
  if (nd) {
    int st = string(r, nd, "name", &name);
    if (st) return st;
    S->name = strdup(name);
  } else {
    S->name = path_stem(r->src.file);
  }
  return S->name ? CUP_OK : CUP_ERR_NOMEM;
}

/* set: (and f:) instead of circuit: or lcs:, whose motion is written in
 * place: no input: key. */
static int read_general(rd *r, const st_node *root, cup_scene *S) {
  const st_node *kset, *kin = NULL, *set = st_get(root, "set", &kset);
  const char *other = opt(root, "circuit") ? "circuit" : opt(root, "lcs") ? "lcs"
                    : opt(root, "netlist") ? "netlist" : NULL;
  if (other)
    return fail(r, CUP_ERR_PARSE, kset, "set", "give one model, %s or set, not both", other);
  if (opt(root, "input") && st_get(root, "input", &kin))
    return fail(r, CUP_ERR_PARSE, kin, "input", "a set: scene writes its signals in place (the set's centre, "
                "radius, offsets; f's b and target); input: is for circuit: or lcs:");
  return scene_read_process(r, root, kset, set, read_component, &S->proc);
}

/* crowd: instead of a model; the agents give x0. */
static int read_crowd(rd *r, const st_node *root, cup_scene *S) {
  static const char *const others[] = {"circuit", "lcs", "netlist", "set", "f", "input", "x0", NULL};
  const st_node *kc, *k, *map = st_get(root, "crowd", &kc);
  for (int i = 0; others[i]; i++)
    if (opt(root, others[i]) && st_get(root, others[i], &k))
      return fail(r, CUP_ERR_PARSE, k, others[i], "a crowd: scene has no %s: (the agents give x0; "
                  "the desired velocity is f)", others[i]);
  int st = read_times(r, root, S);
  if (!st) st = scene_read_crowd(r, map, S->opt.T / (double)S->opt.n, &S->crowd);
  int n = st ? 0 : 2 * cup_crowd_agents(S->crowd);
  if (!st && !(S->x0 = malloc(sizeof(double) * (size_t)n))) st = CUP_ERR_NOMEM;
  if (!st) memcpy(S->x0, cup_crowd_q0(S->crowd), sizeof(double) * (size_t)n);
  return st;
}

static int read_scene(rd *r, const st_node *root, cup_scene *S) {
  static const char *const known[] = {"name", "circuit", "lcs", "netlist", "set", "f", "crowd", "input", "x0",
                                      "T", "n", "h", "eps", "eta", "scheme", "theta", "projector", "output", "tol",
                                      "max_event_rate", "hmax", "estimate", "max_steps", "steady_state", NULL};
  const st_node *kf, *ki, *nd;
  int st = need_map(r, root, NULL, "a mapping of keys such as circuit, input, T and n");
  if (!st) st = check_keys(r, root, "", known);
  cup_integrator_options_default(&S->opt);
  S->max_steps = CUP_MAX_STEPS_DEFAULT;
  if (!st && (nd = opt(root, "max_steps"))) st = integer(r, nd, "max_steps", 1, LONG_MAX, &S->max_steps);
  if (!st && opt(root, "crowd")) {
    const st_node *ks;
    if (opt(root, "steady_state") && st_get(root, "steady_state", &ks))
      return fail(r, CUP_ERR_PARSE, ks, "steady_state", "a crowd has no periodic steady state");
    st = read_crowd(r, root, S);
    if (!st) st = read_method(r, root, &S->opt);
    if (!st) st = read_tolerance(r, root, &S->opt);
    if (!st) st = read_name(r, root, S);
    return st;
  }
  if (!st && opt(root, "set")) {
    st = read_general(r, root, S);
  } else if (!st && opt(root, "f") && st_get(root, "f", &kf)) {
    st = fail(r, CUP_ERR_PARSE, kf, "f", "f: goes with set: (an LCS's f is A x + E u, in lcs:)");
  } else if (!st) {
    st = read_model(r, root, S);
    if (!st && S->nl && st_get(root, "input", &ki))
      st = fail(r, CUP_ERR_PARSE, ki, "input", "a netlist's sources are its input: set them in the netlist "
                "(netlist.V1: 'SIN(0 5 50)')");
    else if (!st && !S->nl)
      st = read_input(r, root, cup_lcs_inputs(S->lcs), &S->u);
  }
  if (!st && S->nl) scene_netlist_options(S->nl, &S->opt);
  cup_scheme netlist_scheme = S->opt.scheme;
  if (!st) st = read_run(r, root, cup_scene_dim(S), S);
  if (!st) st = read_method(r, root, &S->opt);
  if (!st) st = read_tolerance(r, root, &S->opt);
  if (!st) st = netlist_steps(r, root, S, netlist_scheme);
  if (!st) st = read_name(r, root, S);
  if (!st) st = scene_read_steady(r, root, S->nl, &S->steady);
  return st;
}

/* ---- public -------------------------------------------------------------- */

/* files: what was read so far (the scene file itself), moved into the
 * scene, or freed. */
static int load(cup_scene **s, const char *text, size_t len, const char *name, const char *dir,
                const char *const *ovr, int nov, file_list *files, char *errmsg) {
  rd r = {{name, ovr}, dir, errmsg, files};
  st_node *root = NULL;
  cup_scene *S = NULL;
  int st = st_parse(&root, text, len, &r.src, -1, NULL, errmsg);
  for (int k = 0; k < nov && !st; k++) st = st_apply_override(&root, &r.src, k, scene_reshape, scene_verbatim, errmsg);
  if (!st && !(S = calloc(1, sizeof *S))) st = CUP_ERR_NOMEM;
  if (!st) st = read_scene(&r, root, S);
  if (S) {
    S->files = *files;
    memset(files, 0, sizeof *files);
  }
  file_list_free(files);
  if (!st && !(S->text = st_emit(root))) st = CUP_ERR_NOMEM;
  st_free(root);
  if (st == CUP_ERR_NOMEM) fail_fmt(errmsg, st, "%s: out of memory while loading the scene", name);
  if (st) { cup_scene_free(&S); return st; }
  *s = S;
  return CUP_OK;
}

static int check_args(cup_scene **s, const void *src, const char *const *list, int n, char *errmsg) {
  if (s) *s = NULL;
  return load_args("scene", "override", s != NULL, src, list, n, errmsg);
}

int cup_scene_load_string(cup_scene **s, const char *text, const char *name, const char *dir,
                          const char *const *overrides, int n_overrides, char *errmsg) {
  int st = check_args(s, text, overrides, n_overrides, errmsg);
  if (st) return st;
  file_list files = {0};
  return load(s, text, strlen(text), name ? name : "<string>", dir, overrides, n_overrides, &files, errmsg);
}

int cup_scene_load(cup_scene **s, const char *path, const char *const *overrides, int n_overrides,
                   char *errmsg) {
  int st = check_args(s, path, overrides, n_overrides, errmsg);
  char *text = NULL, *dir = NULL;
  size_t len = 0;
  file_list files = {0};
  if (!st) st = read_text(path, &text, &len, &files, errmsg);
  if (!st) st = path_dir(path, &dir);
  if (!st) st = load(s, text, len, path, dir, overrides, n_overrides, &files, errmsg);
  file_list_free(&files);
  free(text);
  free(dir);
  return st;
}

void cup_scene_free(cup_scene **s) {
  if (!s || !*s) return;
  cup_scene *S = *s;
  free(S->name);
  cup_lcs_free(&S->lcs);
  scene_process_free(&S->proc);
  cup_crowd_free(&S->crowd);
  cup_input_free(&S->u);
  cup_input_free(&S->u_written);
  cup_netlist_free(&S->nl);
  free(S->x0);
  free(S->eps_spec);
  free(S->eta_spec);
  free(S->text);
  file_list_free(&S->files);
  scene_steady_free(&S->steady);
  free(S);
  *s = NULL;
}

const cup_scene_steady *cup_scene_steady_state(const cup_scene *s) {
  return s && s->steady.enabled ? &s->steady.pub : NULL;
}

const char *cup_scene_name(const cup_scene *s) { return s ? s->name : NULL; }
const cup_lcs *cup_scene_lcs(const cup_scene *s) { return !s ? NULL : s->nl ? cup_netlist_lcs(s->nl) : s->lcs; }
const cup_input *cup_scene_input(const cup_scene *s) {
  return !s ? NULL : s->proc ? scene_process_input(s->proc) : s->nl ? cup_netlist_input(s->nl) : s->u;
}
cup_netlist *cup_scene_netlist(const cup_scene *s) { return s ? s->nl : NULL; }
const cup_process_desc *cup_scene_process(const cup_scene *s) {
  return !s ? NULL : s->crowd ? cup_crowd_process(s->crowd) : scene_process_desc(s->proc);
}
cup_crowd *cup_scene_crowd(const cup_scene *s) { return s ? s->crowd : NULL; }
int cup_scene_dim(const cup_scene *s) {
  return !s ? 0 : s->crowd ? 2 * cup_crowd_agents(s->crowd) : s->proc ? scene_process_desc(s->proc)->n
                                                                     : cup_lcs_dim(cup_scene_lcs(s));
}

int cup_scene_integrator(const cup_scene *s, const cup_integrator_options *o, cup_integrator **I,
                         char *errmsg) {
  if (!I) return fail_fmt(errmsg, CUP_ERR_ARG, "scene: output pointer is NULL");
  *I = NULL;
  if (!s) return fail_fmt(errmsg, CUP_ERR_ARG, "scene: scene is NULL");
  if (!o) o = &s->opt;
  if (s->proc || s->crowd) return cup_integrator_create_process(I, cup_scene_process(s), o, errmsg);
  cup_switching sw;
  if (s->nl && cup_netlist_switching(s->nl, &sw))
    return cup_integrator_create_switched(I, &sw, cup_scene_input(s), o, errmsg);
  return cup_integrator_create(I, cup_scene_lcs(s), cup_scene_input(s), o, errmsg);
}
int cup_scene_set_time_origin(cup_scene *s, double t0, char *errmsg) {
  if (!s || !(t0 >= 0) || !isfinite(t0))
    return fail_fmt(errmsg, CUP_ERR_ARG, "scene: time origin: no scene, or t0 = %g not finite and >= 0", t0);
  if (s->nl) return cup_netlist_set_time_origin(s->nl, t0, errmsg);
  if ((s->proc || s->crowd) && t0 != 0)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED, "%s: a time origin t0 = %g for a set: or crowd: scene (its input "
                    "cannot be moved)", s->name, t0);
  return input_origin(&s->u, &s->u_written, t0, errmsg);
}

int cup_scene_steady_phase(cup_scene *s, double period, double *T, double *t0, char *errmsg) {
  int st = cup_scene_set_time_origin(s, 0, errmsg);   /* the sources as written */
  *T = period;
  *t0 = 0;
  if (!st && !cup_scene_input(s) && !(period > 0))
    return fail_fmt(errmsg, CUP_ERR_ARG, "the scene has no input to take the period from: give steady_state.period "
                    "(catchup-run --period)");
  if (!st) st = cup_input_steady_phase(cup_scene_input(s), period, T, t0, errmsg);
  if (!st) st = cup_scene_set_time_origin(s, *t0, errmsg);
  return st;
}

const double *cup_scene_x0(const cup_scene *s) { return s ? s->x0 : NULL; }
const cup_integrator_options *cup_scene_options(const cup_scene *s) { return s ? &s->opt : NULL; }
const char *cup_scene_eps_spec(const cup_scene *s) { return s ? s->eps_spec : NULL; }
const char *cup_scene_eta_spec(const cup_scene *s) { return s ? s->eta_spec : NULL; }
const char *cup_scene_text(const cup_scene *s) { return s ? s->text : NULL; }
const file_list *scene_file_list(const cup_scene *s) { return s ? &s->files : NULL; }
int cup_scene_check_output(const cup_scene *s, const char *path, char *errmsg) {
  if (!s || !path) return fail_fmt(errmsg, CUP_ERR_ARG, "scene: NULL argument");
  return file_list_check_output(&s->files, path, errmsg);
}
int cup_scene_file_count(const cup_scene *s) { return s ? s->files.n : 0; }
long cup_scene_max_steps(const cup_scene *s) { return s ? s->max_steps : CUP_MAX_STEPS_DEFAULT; }
const char *cup_scene_file(const cup_scene *s, int k) {
  return s && k >= 0 && k < s->files.n ? s->files.e[k].path : NULL;
}
const char *cup_scene_file_sha256(const cup_scene *s, int k) {
  return s && k >= 0 && k < s->files.n ? s->files.e[k].sha256 : NULL;
}

/* The paper's circuit (Sec. 7): x1 is the time integral of the current
 * through C4 (its charge), x2 that current (L3's, in series), x3 L2's. */
int cup_scene_state_label(const cup_scene *s, int j, char *name, unsigned long size, const char **unit) {
  static const char *const circ[3] = {"q(C4)", "i(L3)", "i(L2)"}, *const circ_unit[3] = {"C", "A", "A"};
  if (!s || !name || size == 0 || j < 0 || j >= cup_scene_dim(s)) return CUP_ERR_ARG;
  const char *u = "1";
  if (s->nl) {
    const char *nm = cup_netlist_state_name(s->nl, j);
    snprintf(name, size, "%s", nm);
    u = nm[0] == 'i' ? "A" : "V";      /* a netlist's states: inductor currents, capacitor voltages */
  } else if (s->crowd) {
    snprintf(name, size, "%c%d", j % 2 ? 'y' : 'x', j / 2);
    u = "m";
  } else if (s->circuit && j < 3) {
    snprintf(name, size, "%s", circ[j]);
    u = circ_unit[j];
  } else {
    snprintf(name, size, "x%d", j + 1);
  }
  if (unit) *unit = u;
  return CUP_OK;
}

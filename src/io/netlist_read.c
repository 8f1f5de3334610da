/* netlist_read — SPICE-subset netlists (.cir/.sp) into the circuit
 * description of model/netlist_desc.h, then into an LCS (model/netlist.c).
 * The subset and its errors are documented in docs/netlist.md: R, L, C,
 * independent V and I sources (DC, SIN, PULSE, PWL), ideal diodes,
 * .tran, .param, .ic, .model NAME D, .probe/.save/.print, .end; anything
 * else is refused by name ("not supported"), never guessed. This file
 * reads the control lines and runs the passes over the cards; the element
 * cards are read by netlist_elem.c. */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include "catchup.h"
#include "netlist_elem.h"
#include "netlist_subckt.h"
#include "read_text.h"
#include "model/netlist_desc.h"
#include "model/netlist_impl.h"

/* ---- .model and .param (read first) ------------------------------------------ */

static int read_model(rd *r, int card) {
  int n = r->x.card[card].n;
  const nx_tok *cmd = TOK(r, card, 0);
  if (n < 3) return nx_fail(&r->x, CUP_ERR_PARSE, cmd, ".model", "expected '.model NAME D'");
  const nx_tok *name = TOK(r, card, 1), *type = TOK(r, card, 2);
  if (name->kind != NX_WORD) return nx_fail(&r->x, CUP_ERR_PARSE, name, ".model", "expected a model name");
  if (nx_is(type, "sw") || nx_is(type, "csw")) {  /* parameters read with the switches that use it */
    if (nx_hash_get(&r->models, name->s) >= 0)
      return nx_fail(&r->x, CUP_ERR_PARSE, name, name->s, "model defined twice");
    return nx_hash_put(&r->models, name->s, card) ? nr_nomem(r) : CUP_OK;
  }
  if (!nx_is(type, "d"))
    return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, type, name->s, "model type '%.20s' is not supported (ideal "
                   "diodes: '.model %.40s D'; switches: SW, CSW)", type->s, name->s);
  for (int k = 3; k < n; k++)
    if (TOK(r, card, k)->kind != NX_LP && TOK(r, card, k)->kind != NX_RP)
      return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, TOK(r, card, k), name->s, "diode model parameters are not "
                     "supported ('%.20s'): catchup's diodes are ideal; write '.model %.40s D'",
                     TOK(r, card, k)->s, name->s);
  if (nx_hash_get(&r->models, name->s) >= 0)
    return nx_fail(&r->x, CUP_ERR_PARSE, name, name->s, "model defined twice");
  return nx_hash_put(&r->models, name->s, card) ? nr_nomem(r) : CUP_OK;
}

static int read_param(rd *r, int card) {
  int n = r->x.card[card].n;
  nx *x = &r->x;
  for (int k = 1; k < n;) {
    const nx_tok *name = TOK(r, card, k);
    if (name->kind != NX_WORD || !(isalpha((unsigned char)name->s[0]) || name->s[0] == '_'))
      return nx_fail(x, CUP_ERR_PARSE, name, ".param", "expected NAME=VALUE (got '%.40s')", name->s);
    if (k + 2 >= n || TOK(r, card, k + 1)->kind != NX_EQ)
      return nx_fail(x, CUP_ERR_PARSE, name, name->s, "expected %s=VALUE", name->s);
    if (nx_hash_get(&x->parh, name->s) >= 0)
      return nx_fail(x, CUP_ERR_PARSE, name, name->s, "parameter defined twice");
    if (la_grow(&x->par, &x->cappar, x->npar, sizeof *x->par, 16)) return nr_nomem(r);
    nx_param *p = &x->par[x->npar];
    memset(p, 0, sizeof *p);
    if (!(p->name = strdup(name->s))) return nr_nomem(r);
    p->value = *TOK(r, card, k + 2);
    if (nx_hash_put(&x->parh, name->s, x->npar++)) return nr_nomem(r);
    k += 3;
  }
  return CUP_OK;
}

/* ---- control lines ----------------------------------------------------------- */

/* .tran TSTEP TSTOP [TSTART [TMAX]] [UIC]: TSTEP is the output's spacing,
 * TSTART where the output begins, TMAX the longest step (docs/netlist.md). */
static int read_tran(rd *r, int card) {
  int n = r->x.card[card].n;
  const nx_tok *cmd = TOK(r, card, 0), *at[4] = {NULL};
  nl_circuit *c = r->c;
  if (c->has_tran) return nx_fail(&r->x, CUP_ERR_PARSE, cmd, ".tran", "given twice (line %d)", c->tran_line);
  if (n < 3) return nx_fail(&r->x, CUP_ERR_PARSE, cmd, ".tran", "expected '.tran TSTEP TSTOP'");
  double v[4] = {0, 0, 0, 0};
  int nv = 0, st = CUP_OK;
  for (int k = 1; k < n && !st; k++) {
    const nx_tok *t = TOK(r, card, k);
    if (nx_is(t, "uic")) continue;               /* initial conditions are always used */
    if (nv == 4) return nx_fail(&r->x, CUP_ERR_PARSE, t, ".tran", "too many values");
    at[nv] = t;
    st = nx_value(&r->x, t, ".tran", &v[nv++]);
  }
  if (st) return st;
  if (nv < 2) return nx_fail(&r->x, CUP_ERR_PARSE, cmd, ".tran", "expected '.tran TSTEP TSTOP'");
  if (!(v[0] > 0) || !(v[1] > 0))
    return nx_fail(&r->x, CUP_ERR_PARSE, cmd, ".tran", "TSTEP = %g and TSTOP = %g must be > 0", v[0], v[1]);
  if (nv > 2 && !(v[2] >= 0 && v[2] < v[1]))
    return nx_fail(&r->x, CUP_ERR_PARSE, at[2], ".tran", "TSTART = %g must be in [0, TSTOP = %g)", v[2], v[1]);
  if (nv > 3 && !(v[3] > 0))
    return nx_fail(&r->x, CUP_ERR_PARSE, at[3], ".tran", "TMAX = %g must be > 0", v[3]);
  c->has_tran = 1;
  c->tstep = v[0];
  c->tstop = v[1];
  c->tstart = v[2];
  c->tmax = v[3];
  c->tran_line = cmd->line;
  c->tran_col = cmd->col;
  return CUP_OK;
}

/* .options NAME[=VALUE] ...: RELTOL, ABSTOL, VNTOL and CHGTOL set the
 * adaptive scheme's tolerances (docs/netlist.md), catchup's STEADYSTATE and
 * STEADYPERIOD=T ask for the periodic steady state (docs/steady-state.md);
 * SPICE's other options tune its own numerics and are accepted and ignored. */
static int read_options(rd *r, int card) {
  static const char *const known[] = {"reltol", "abstol", "vntol", "chgtol", NULL};
  nl_circuit *c = r->c;
  double *slot[] = {&c->reltol, &c->abstol, &c->vntol, &c->chgtol};
  int n = r->x.card[card].n;
  for (int k = 1; k < n; k++) {
    const nx_tok *t = TOK(r, card, k);
    int which = -1;
    for (int q = 0; known[q]; q++)
      if (nx_is(t, known[q])) which = q;
    int valued = k + 2 < n && TOK(r, card, k + 1)->kind == NX_EQ;
    if (nx_is(t, "steadystate") || nx_is(t, "steadyperiod")) {   /* catchup's: docs/steady-state.md */
      c->steady = 1;
      if (nx_is(t, "steadystate")) continue;
      int st = valued ? nx_value(&r->x, TOK(r, card, k + 2), ".options", &c->steady_period) :
               nx_fail(&r->x, CUP_ERR_PARSE, t, ".options", "expected steadyperiod=T");
      if (!st && !(c->steady_period > 0 && isfinite(c->steady_period)))
        st = nx_fail(&r->x, CUP_ERR_PARSE, TOK(r, card, k + 2), ".options", "steadyperiod = %g must be > 0",
                     c->steady_period);
      if (st) return st;
      k += 2;
      continue;
    }
    if (which < 0) {                             /* another SPICE option: its value, if any, skipped */
      if (valued) k += 2;
      continue;
    }
    if (!valued) return nx_fail(&r->x, CUP_ERR_PARSE, t, ".options", "expected %s=VALUE", known[which]);
    double v;
    int st = nx_value(&r->x, TOK(r, card, k + 2), ".options", &v);
    if (st) return st;
    if (!(v > 0) || !isfinite(v) || (which == 0 && !(v < 1)))
      return nx_fail(&r->x, CUP_ERR_PARSE, TOK(r, card, k + 2), ".options", "%s = %g must be %s", known[which], v,
                     which == 0 ? "in (0, 1)" : "finite and > 0");
    *slot[which] = v;
    k += 2;
  }
  return CUP_OK;
}

/* .ic v(NODE)=VALUE ...: nodes are looked up once every element is read. */
static int read_ic(rd *r, int card) {
  int n = r->x.card[card].n;
  nl_circuit *c = r->c;
  for (int k = 1; k < n; k += 6) {
    const nx_tok *t = TOK(r, card, k);
    if (k + 5 >= n)
      return nx_fail(&r->x, CUP_ERR_PARSE, t, ".ic", "expected v(NODE)=VALUE");
    if (!nx_is(t, "v") || TOK(r, card, k + 1)->kind != NX_LP || TOK(r, card, k + 2)->kind != NX_WORD ||
        TOK(r, card, k + 3)->kind != NX_RP || TOK(r, card, k + 4)->kind != NX_EQ)
      return nx_fail(&r->x, CUP_ERR_PARSE, t, ".ic", "expected v(NODE)=VALUE (got '%.40s')", t->s);
    if (la_grow(&c->ic, &r->capic, c->nic, sizeof *c->ic, 8)) return nr_nomem(r);
    nl_ic *ic = &c->ic[c->nic];
    const nx_tok *nd = TOK(r, card, k + 2);
    ic->line = nd->line;
    ic->col = nd->col;
    ic->node = nr_is_ground(nd->s) ? 0 : -1 - (int)(nd - r->x.tok);   /* resolved later */
    int st = nx_value(&r->x, TOK(r, card, k + 5), ".ic", &ic->v);
    if (st) return st;
    c->nic++;
  }
  return CUP_OK;
}

static int add_probe(rd *r, const nx_tok *at, const char *text) {
  nl_circuit *c = r->c;
  if (la_grow(&c->probe, &r->capprobe, c->nprobe, sizeof *c->probe, 8)) return nr_nomem(r);
  nl_probe *p = &c->probe[c->nprobe];
  if (!(p->text = strdup(text))) return nr_nomem(r);
  p->line = at->line;
  p->col = at->col;
  c->nprobe++;
  return CUP_OK;
}

/* .probe/.save/.print/.plot [tran] v(N) v(N1,N2) i(ELEM) ... | all */
static int read_probes(rd *r, int card) {
  int n = r->x.card[card].n;
  const nx_tok *cmd = TOK(r, card, 0);
  for (int k = 1; k < n;) {
    const nx_tok *t = TOK(r, card, k);
    if (k == 1 && nx_is(t, "tran")) { k++; continue; }
    if (nx_is(t, "all")) { r->c->probe_all = 1; k++; continue; }
    int two = k + 4 < n && TOK(r, card, k + 3)->kind == NX_WORD && TOK(r, card, k + 4)->kind == NX_RP;
    int len = two ? 5 : 4;                        /* v ( a [b] ): the comma is a blank */
    if (!(nx_is(t, "v") || nx_is(t, "i")) || k + len > n || TOK(r, card, k + 1)->kind != NX_LP ||
        TOK(r, card, k + 2)->kind != NX_WORD || TOK(r, card, k + len - 1)->kind != NX_RP ||
        (two && nx_is(t, "i")))
      return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, t, cmd->s, "'%.40s' is not supported (expected v(NODE), "
                     "v(NODE1,NODE2), i(ELEMENT) or all)", t->s);
    char text[256];
    if (two)
      snprintf(text, sizeof text, "%s(%s,%s)", t->s, TOK(r, card, k + 2)->s, TOK(r, card, k + 3)->s);
    else
      snprintf(text, sizeof text, "%s(%s)", t->s, TOK(r, card, k + 2)->s);
    int st = add_probe(r, t, text);
    if (st) return st;
    k += len;
  }
  return CUP_OK;
}

static int read_control(rd *r, int card) {
  static const char *const ignored[] = {".title", ".temp", ".width", NULL};
  static const char *const refused[] = {".func", ".global",
                                        ".ac", ".dc", ".op", ".noise", ".tf", ".four", ".meas", ".measure",
                                        ".sens", ".pz", ".disto", ".nodeset", ".csparam", ".if", ".else",
                                        ".elseif", ".endif", ".savecurrents", ".model_x", NULL};
  const nx_tok *cmd = TOK(r, card, 0);
  const char *w = cmd->s;
  if (!strcasecmp(w, ".tran")) return read_tran(r, card);
  if (!strcasecmp(w, ".options") || !strcasecmp(w, ".option") || !strcasecmp(w, ".opt")) return read_options(r, card);
  if (!strcasecmp(w, ".ic")) return read_ic(r, card);
  if (!strcasecmp(w, ".probe") || !strcasecmp(w, ".save") || !strcasecmp(w, ".print") || !strcasecmp(w, ".plot"))
    return read_probes(r, card);
  if (!strcasecmp(w, ".param") || !strcasecmp(w, ".model")) return CUP_OK;   /* read first */
  for (int k = 0; ignored[k]; k++)
    if (!strcasecmp(w, ignored[k])) return CUP_OK;
  for (int k = 0; refused[k]; k++)
    if (!strcasecmp(w, refused[k]))
      return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, cmd, w, "not supported (catchup reads R, L, C, V, I, D, E, F, "
                     "G, H, K, S, W, X, .tran, .param, .ic, .model NAME D|SW|CSW, .subckt, .include, .lib, .probe/.save/.print, "
                     ".options and .end)");
  return nx_fail(&r->x, CUP_ERR_PARSE, cmd, w, "unknown control line");
}

/* ---- the cards --------------------------------------------------------------- */

static int read_element(rd *r, int card) {
  static const char *const what[26] = {
    ['a' - 'a'] = "XSPICE code models (A)", ['b' - 'a'] = "behavioural sources (B)",
    ['j' - 'a'] = "JFETs (J)", ['m' - 'a'] = "MOSFETs (M)",
    ['o' - 'a'] = "transmission lines (O)", ['q' - 'a'] = "bipolar transistors (Q)",
    ['t' - 'a'] = "transmission lines (T)",
    ['u' - 'a'] = "RC lines (U)", ['y' - 'a'] = "transmission lines (Y)",
    ['z' - 'a'] = "MESFETs (Z)"};
  const nx_tok *t = TOK(r, card, 0);
  if (t->kind != NX_WORD)
    return nx_fail(&r->x, CUP_ERR_PARSE, t, NULL, "expected an element or a control line (got '%s')", t->s);
  int c = nx_card_type(&r->x, r->x.card[card]);
  switch (c) {
    case 'r': return nr_read_passive(r, card, NL_R);
    case 'l': return nr_read_passive(r, card, NL_L);
    case 'c': return nr_read_passive(r, card, NL_C);
    case 'v': return nr_read_source(r, card, NL_V);
    case 'i': return nr_read_source(r, card, NL_I);
    case 'd': return nr_read_diode(r, card);
    case 'e': return nr_read_controlled(r, card, NL_E);
    case 'f': return nr_read_controlled(r, card, NL_F);
    case 'g': return nr_read_controlled(r, card, NL_G);
    case 'h': return nr_read_controlled(r, card, NL_H);
    case 'k': return nr_read_coupling(r, card);
    case 's': return nr_read_switch(r, card, NL_S);
    case 'w': return nr_read_switch(r, card, NL_W);
    case '.': return read_control(r, card);
  }
  if (c >= 'a' && c <= 'z' && what[c - 'a'])
    return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, t, t->s, "%s are not supported (R, L, C, V, I, ideal diodes D, "
                   "E, F, G, H, K, switches S and W, and X are)", what[c - 'a']);
  return nx_fail(&r->x, CUP_ERR_PARSE, t, t->s, "unknown element type '%c' (R, L, C, V, I, D, E, F, G, H, K, S, W "
                 "and X are supported)", c);
}

/* First pass: .end, .control blocks, .param and .model (used anywhere). */
static int first_pass(rd *r) {
  nx *x = &r->x;
  r->end = x->ncard;
  if (!(r->skip = calloc((size_t)x->ncard + 1, 1))) return nr_nomem(r);
  for (int k = 0; k < x->ncard; k++) {
    const nx_tok *t = TOK(r, k, 0);
    if (nx_is(t, ".end")) { r->end = k; break; }
    if (nx_is(t, ".control")) {
      int j = k + 1;
      while (j < x->ncard && !nx_is(TOK(r, j, 0), ".endc")) j++;
      if (j == x->ncard) return nx_fail(x, CUP_ERR_PARSE, t, ".control", "no .endc closes it");
      memset(r->skip + k, 1, (size_t)(j - k + 1));
      k = j;
      continue;
    }
    int st = nx_is(t, ".param") ? read_param(r, k) : nx_is(t, ".model") ? read_model(r, k) : CUP_OK;
    if (st) return st;
  }
  return CUP_OK;
}

/* Sets: NAME=VALUE for a .param (replaced now) or an element (later).
 * Every value is split into tokens here, before any element is read, so
 * that no token moves while the elements point at them. */
static int apply_sets(rd *r) {
  nx *x = &r->x;
  size_t ns = (size_t)x->nsets + 1;
  if (!(r->set_used = calloc(ns, sizeof(int))) || !(r->set_first = calloc(ns, sizeof(int))) ||
      !(r->set_n = calloc(ns, sizeof(int))))
    return nr_nomem(r);
  for (int k = 0; k < x->nsets; k++) {
    nx_tok at = {NX_WORD, NULL, 0, 0, k, 0, 0};
    const char *s = x->sets[k], *eq = strchr(s, '=');
    if (!eq || eq == s) return nx_fail(x, CUP_ERR_ARG, &at, NULL, "expected NAME=VALUE");
    char name[128];
    size_t n = (size_t)(eq - s);
    while (n && isspace((unsigned char)s[n - 1])) n--;
    if (n >= sizeof name) return nx_fail(x, CUP_ERR_ARG, &at, NULL, "name too long");
    memcpy(name, s, n);
    name[n] = '\0';
    int st = nx_lex_value(x, k, eq + 1, &r->set_first[k], &r->set_n[k]);
    if (st) return st;
    int p = nx_hash_get(&x->parh, name);
    if (p >= 0) {
      if (r->set_n[k] != 1) return nx_fail(x, CUP_ERR_PARSE, &at, name, "expected one value");
      x->par[p].value = x->tok[r->set_first[k]];
      r->set_used[k] = 1;
    } else if (nx_hash_put(&r->setnames, name, k)) {
      return nr_nomem(r);
    }
  }
  return CUP_OK;
}

static int resolve_ic(rd *r) {
  nl_circuit *c = r->c;
  for (int k = 0; k < c->nic; k++) {
    if (c->ic[k].node >= 0) continue;
    const nx_tok *t = &r->x.tok[-1 - c->ic[k].node];
    int node = nx_hash_get(&r->nodes, t->s);
    if (node < 0) return nx_fail(&r->x, CUP_ERR_PARSE, t, ".ic", "no node named '%.40s'", t->s);
    c->ic[k].node = node;
  }
  return CUP_OK;
}

/* The files read, each once, for the formulation's messages and the list
 * that cup_netlist_file gives. */
static int copy_files(rd *r) {
  nl_circuit *c = r->c;
  if (!(c->files = calloc((size_t)r->x.nfiles + 1, sizeof(char *)))) return nr_nomem(r);
  for (int f = 0; f < r->x.nfiles; f++)
    if (!(c->files[c->nfiles++] = strdup(r->x.files[f].path))) return nr_nomem(r);
  return CUP_OK;
}

static int read_cards(rd *r) {
  nl_circuit *c = r->c;
  if (!(c->node = calloc(1, sizeof *c->node)) || !(c->node_line = calloc(1, sizeof(int))) ||
      !(c->node_col = calloc(1, sizeof(int))))
    return nr_nomem(r);
  c->nnodes = 1;                                   /* ground */
  int st = nx_structure(&r->x);
  if (!st) st = first_pass(r);
  if (!st) st = apply_sets(r);
  if (!st && (st = nx_flatten(&r->x)) == CUP_OK) {   /* the cards are now the flattened ones */
    r->end = r->x.ncard;
    free(r->skip);
    if (!(r->skip = calloc((size_t)r->x.ncard + 1, 1))) st = nr_nomem(r);
  }
  if (!st) st = copy_files(r);
  for (int k = 0; k < r->end && !st; k++)
    if (!r->skip[k]) st = read_element(r, k);
  if (!st) st = resolve_ic(r);
  if (!st) st = nr_resolve_refs(r);
  for (int k = 0; k < r->x.nsets && !st; k++)
    if (!r->set_used[k]) {
      nx_tok at = {NX_WORD, NULL, 0, 0, k, 0, 0};
      st = nx_fail(&r->x, CUP_ERR_ARG, &at, NULL, "no element or .param of that name");
    }
  if (!st && c->nelem == 0) st = nx_fail(&r->x, CUP_ERR_PARSE, NULL, NULL, "no elements (line 1 is the title)");
  if (!st && !c->node[0])
    st = nx_fail(&r->x, CUP_ERR_PARSE, NULL, NULL, "no ground: no element connects to node 0 (or gnd)");
  return st;
}


/* ---- public ------------------------------------------------------------------ */

static int load(cup_netlist **out, const char *text, size_t len, const char *name,
                const char *const *sets, int nsets, file_list *files, char *errmsg) {
  nl_circuit c = {0};
  c.reltol = c.abstol = c.vntol = c.chgtol = NAN;  /* .options not given */
  rd r = {0};
  r.x.file = name;
  r.x.read_list = files;
  r.x.sets = sets;
  r.x.nsets = nsets;
  r.x.errmsg = errmsg;
  r.c = &c;
  int st = (c.file = strdup(name)) ? CUP_OK : nr_nomem(&r);
  if (!st && nx_add_file(&r.x, name, -1, 0) < 0) st = nr_nomem(&r);
  if (!st) st = nx_lex_file(&r.x, 0, text, len, 1);
  if (!st) st = read_cards(&r);
  if (!st) st = c.nswitch ? nl_switched_formulate(out, &c, errmsg) : netlist_formulate(out, &c, errmsg);
  if (!st && !((*out)->source = strndup(text, len))) {
    cup_netlist_free(out);
    st = nr_nomem(&r);
  }
  nl_circuit_free(&c);
  nx_free(&r.x);
  nx_hash_free(&r.nodes); nx_hash_free(&r.elems); nx_hash_free(&r.models); nx_hash_free(&r.setnames);
  free(r.skip);
  free(r.set_used); free(r.set_first); free(r.set_n);
  return st;
}

static int check_args(cup_netlist **out, const void *src, const char *const *list, int n, char *errmsg) {
  if (out) *out = NULL;
  return load_args("netlist", "set", out != NULL, src, list, n, errmsg);
}

int netlist_load_string_files(cup_netlist **out, const char *text, const char *name, const char *const *sets,
                              int nsets, file_list *files, char *errmsg) {
  int st = check_args(out, text, sets, nsets, errmsg);
  return st ? st : load(out, text, strlen(text), name ? name : "<string>", sets, nsets, files, errmsg);
}

int cup_netlist_load_string(cup_netlist **out, const char *text, const char *name,
                            const char *const *sets, int nsets, char *errmsg) {
  return netlist_load_string_files(out, text, name, sets, nsets, NULL, errmsg);
}

int netlist_load_files(cup_netlist **out, const char *path, const char *const *sets, int nsets,
                       file_list *files, char *errmsg) {
  int st = check_args(out, path, sets, nsets, errmsg);
  char *text = NULL;
  size_t len = 0;
  if (!st) st = read_text(path, &text, &len, files, errmsg);
  if (!st) st = load(out, text, len, path, sets, nsets, files, errmsg);
  free(text);
  return st;
}

int cup_netlist_load(cup_netlist **out, const char *path, const char *const *sets, int nsets, char *errmsg) {
  return netlist_load_files(out, path, sets, nsets, NULL, errmsg);
}

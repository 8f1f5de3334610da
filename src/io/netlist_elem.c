/* netlist_elem — the element cards of a netlist (R, L, C, V, I, D, E, F,
 * G, H, K, S, W) into the circuit description, and the names that F, H, W
 * and K refer to, resolved once every element is read; netlist_read.c
 * reads the control lines and runs the passes. The subset and its errors
 * are documented in docs/netlist.md. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include "catchup.h"
#include "netlist_elem.h"
#include "util/linalg.h"

int nr_nomem(rd *r) { return nx_fail(&r->x, CUP_ERR_NOMEM, NULL, NULL, "out of memory"); }

/* ---- nodes and elements ------------------------------------------------------ */

int nr_is_ground(const char *s) { return !strcmp(s, "0") || !strcasecmp(s, "gnd"); }

static int node_of(rd *r, const nx_tok *t, const char *elem, int *out) {
  nl_circuit *c = r->c;
  if (t->kind != NX_WORD) return nx_fail(&r->x, CUP_ERR_PARSE, t, elem, "expected a node name (got '%s')", t->s);
  if (strchr(t->s, '/'))
    return nx_fail(&r->x, CUP_ERR_PARSE, t, elem, "node name '%.40s': '/' is not allowed (it would split "
                   "the HDF5 signal name)", t->s);
  if (nr_is_ground(t->s)) {
    if (!c->node[0] && !(c->node[0] = strdup(t->s))) return nr_nomem(r);
    if (!c->node_line[0]) { c->node_line[0] = t->line; c->node_col[0] = t->col; }
    *out = 0;
    return CUP_OK;
  }
  int k = nx_hash_get(&r->nodes, t->s);
  if (k >= 0) { *out = k; return CUP_OK; }
  k = c->nnodes;
  if ((k & (k - 1)) == 0) {                        /* grow at powers of two */
    size_t cap = 2 * (size_t)k;
    char **nn = realloc(c->node, cap * sizeof *nn);
    if (nn) c->node = nn;
    int *nl = realloc(c->node_line, cap * sizeof *nl);
    if (nl) c->node_line = nl;
    int *nc = realloc(c->node_col, cap * sizeof *nc);
    if (nc) c->node_col = nc;
    if (!nn || !nl || !nc) return nr_nomem(r);
  }
  if (!(c->node[k] = strdup(t->s)) || nx_hash_put(&r->nodes, t->s, k)) return nr_nomem(r);
  c->node_line[k] = t->line;
  c->node_col[k] = t->col;
  c->nnodes++;
  *out = k;
  return CUP_OK;
}

static int new_elem(rd *r, nl_kind kind, const nx_tok *name, nl_elem **out) {
  nl_circuit *c = r->c;
  int prev = nx_hash_get(&r->elems, name->s);
  if (prev >= 0)
    return nx_fail(&r->x, CUP_ERR_PARSE, name, name->s, "duplicate element name (first at line %d)",
                   c->elem[prev].line);
  if (la_grow(&c->elem, &r->capelem, c->nelem, sizeof *c->elem, 32)) return nr_nomem(r);
  nl_elem *e = &c->elem[c->nelem];
  memset(e, 0, sizeof *e);
  e->kind = kind;
  e->file = name->file;
  e->line = name->line;
  e->col = name->col;
  if (!(e->name = strdup(name->s)) || nx_hash_put(&r->elems, name->s, c->nelem)) { free(e->name); return nr_nomem(r); }
  c->nelem++;
  *out = e;
  return CUP_OK;
}

/* A new two-terminal element from card's first three tokens (name, nodes),
 * the card holding at least min_n tokens ("expected 'NAME operands'"). */
static int open_elem(rd *r, int card, nl_kind kind, int min_n, const char *operands, nl_elem **out) {
  const nx_tok *name = TOK(r, card, 0);
  int st = new_elem(r, kind, name, out);
  if (!st && r->x.card[card].n < min_n)
    return nx_fail(&r->x, CUP_ERR_PARSE, name, name->s, "expected '%s %s'", name->s, operands);
  if (!st) st = node_of(r, TOK(r, card, 1), name->s, &(*out)->a);
  if (!st) st = node_of(r, TOK(r, card, 2), name->s, &(*out)->b);
  return st;
}

/* The set that replaces this element's value, if any: 1 and its tokens. */
static int set_tokens(rd *r, const char *name, int *first, int *n) {
  int k = nx_hash_get(&r->setnames, name);
  if (k < 0) return 0;
  r->set_used[k] = 1;
  *first = r->set_first[k];
  *n = r->set_n[k];
  return 1;
}

/* An element with no value: a set naming it is refused, saying why. */
static int refuse_set(rd *r, const char *name, const char *why) {
  int sfirst, sn;
  return set_tokens(r, name, &sfirst, &sn) ? nx_fail(&r->x, CUP_ERR_ARG, NULL, name, "%s", why) : CUP_OK;
}

/* ---- R, L, C ----------------------------------------------------------------- */

static const char *kind_word(nl_kind k) {
  static const char *const w[] = {"resistance", "inductance", "capacitance"};
  return k <= NL_C ? w[k] : "value";
}

int nr_read_passive(rd *r, int card, nl_kind kind) {
  int n = r->x.card[card].n;
  const nx_tok *name = TOK(r, card, 0);
  nl_elem *e;
  int st = open_elem(r, card, kind, 4, "NODE1 NODE2 VALUE", &e);
  if (st) return st;
  int sfirst, sn, k = 4;
  int set = set_tokens(r, name->s, &sfirst, &sn);
  const nx_tok *vt = TOK(r, card, 3);
  if (set) {
    if (sn != 1) return nx_fail(&r->x, CUP_ERR_PARSE, sn ? &r->x.tok[sfirst] : name, name->s, "expected one value");
    vt = &r->x.tok[sfirst];
  }
  st = nx_value(&r->x, vt, name->s, &e->value);
  if (!st && !(e->value > 0))
    return nx_fail(&r->x, CUP_ERR_PARSE, vt, name->s, "bad value: %s must be > 0 (got %g)", kind_word(kind), e->value);
  while (!st && k < n) {
    const nx_tok *t = TOK(r, card, k);
    if (kind != NL_R && nx_is(t, "ic")) {
      if (k + 2 >= n || TOK(r, card, k + 1)->kind != NX_EQ)
        return nx_fail(&r->x, CUP_ERR_PARSE, t, name->s, "expected IC=VALUE");
      st = nx_value(&r->x, TOK(r, card, k + 2), name->s, &e->ic);
      e->has_ic = 1;
      k += 3;
    } else {
      return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, t, name->s, "'%.40s' is not supported here (%s)", t->s,
                     kind == NL_R ? "a resistor takes NODE1 NODE2 VALUE" : "only IC=value may follow the value");
    }
  }
  return st;
}

/* ---- sources ----------------------------------------------------------------- */

static int looks_value(rd *r, const nx_tok *t) {
  double v;
  return t->kind == NX_EXPR || (t->kind == NX_WORD && (nx_number(t->s, &v) || nx_param_find(&r->x, t, t->s) >= 0));
}

/* PULSE's TR or TF written `jump` (not a .param of that name): an edge of
 * no duration, where SPICE reads 0 as TSTEP. */
static int is_jump(rd *r, const nx_tok *t) {
  return t->kind == NX_WORD && nx_is(t, "jump") && !looks_value(r, t);
}

/* The arguments of SIN/PULSE/PWL: "(a b c)" or "a b c" up to the next word
 * that is not a value; for PULSE (jumps not NULL) TR and TF may be `jump`,
 * a bit each in *jumps (by position) with the value 0. */
static int fn_args(rd *r, const nx_tok *t, int n, int *k, const char *elem, const char *fn, double *v,
                   int max, int *count, unsigned *jumps) {
  int paren = *k < n && t[*k].kind == NX_LP;
  if (paren) (*k)++;
  *count = 0;
  while (*k < n && t[*k].kind != NX_RP && (paren || looks_value(r, &t[*k]) || (jumps && is_jump(r, &t[*k])))) {
    if (*count == max)
      return nx_fail(&r->x, CUP_ERR_PARSE, &t[*k], elem, "%s takes at most %d values", fn, max);
    if (is_jump(r, &t[*k])) {
      if (!jumps || (*count != NL_PULSE_TR && *count != NL_PULSE_TF))
        return nx_fail(&r->x, CUP_ERR_PARSE, &t[*k], elem, "%s: 'jump' stands only for PULSE's rise or fall "
                       "time TR, TF (an edge of no duration)", fn);
      *jumps |= 1u << *count;
      v[(*count)++] = 0;
      (*k)++;
      continue;
    }
    if (t[*k].kind == NX_EQ || (t[*k].kind == NX_WORD && !looks_value(r, &t[*k])))
      return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, &t[*k], elem, "%s: '%.40s' is not supported (only values)", fn, t[*k].s);
    int st = nx_value(&r->x, &t[*k], elem, &v[(*count)++]);
    if (st) return st;
    (*k)++;
  }
  if (paren) {
    if (*k >= n) return nx_fail(&r->x, CUP_ERR_PARSE, &t[n - 1], elem, "%s( is not closed", fn);
    (*k)++;
  }
  return CUP_OK;
}

static int read_pwl(rd *r, const nx_tok *at, const char *elem, nl_source *s, const double *v, int count) {
  if (count < 2 || count % 2)
    return nx_fail(&r->x, CUP_ERR_PARSE, at, elem, "PWL needs pairs of time and value (got %d values)", count);
  s->npts = count / 2;
  s->t = malloc(sizeof(double) * (size_t)s->npts);
  s->v = malloc(sizeof(double) * (size_t)s->npts);
  if (!s->t || !s->v) return nr_nomem(r);
  for (int i = 0; i < s->npts; i++) {
    s->t[i] = v[2 * i];
    s->v[i] = v[2 * i + 1];
    if (i > 0 && !(s->t[i] > s->t[i - 1]))
      return nx_fail(&r->x, CUP_ERR_PARSE, at, elem, "PWL times must increase (point %d: %g after %g)",
                     i + 1, s->t[i], s->t[i - 1]);
    if (s->t[i] < 0) return nx_fail(&r->x, CUP_ERR_PARSE, at, elem, "PWL time %g is negative", s->t[i]);
  }
  return CUP_OK;
}

/* V or I: [[DC] value] [AC mag [phase]] [SIN(...) | PULSE(...) | PWL(...)]. */
static int source_spec(rd *r, const nx_tok *t, int n, const char *elem, nl_source *s) {
  static const char *const unsupported[] = {"exp", "sffm", "am", "trnoise", "trrandom", "external",
                                            "distof1", "distof2", "portnum", "z0", NULL};
  int have_dc = 0, have_fn = 0;
  double *v = NULL;
  int st = CUP_OK;
  for (int k = 0; k < n && !st;) {
    const nx_tok *w = &t[k];
    if (nx_is(w, "dc")) {
      if (++k >= n) { st = nx_fail(&r->x, CUP_ERR_PARSE, w, elem, "DC needs a value"); break; }
      st = nx_value(&r->x, &t[k++], elem, &s->dc);
      have_dc = 1;
    } else if (nx_is(w, "ac")) {                   /* small-signal only: no effect on .tran */
      k++;
      for (int j = 0; j < 2 && k < n && looks_value(r, &t[k]); j++) k++;
    } else if (nx_is(w, "sin") || nx_is(w, "pulse") || nx_is(w, "pwl")) {
      if (have_fn) { st = nx_fail(&r->x, CUP_ERR_PARSE, w, elem, "more than one transient function"); break; }
      have_fn = 1;
      s->fn = nx_is(w, "sin") ? NL_FN_SIN : nx_is(w, "pulse") ? NL_FN_PULSE : NL_FN_PWL;
      int max = s->fn == NL_FN_SIN ? 6 : s->fn == NL_FN_PULSE ? 7 : n, count = 0;
      if (!(v = malloc(sizeof(double) * (size_t)(max + 1)))) { st = nr_nomem(r); break; }
      k++;
      st = fn_args(r, t, n, &k, elem, w->s, v, max, &count, s->fn == NL_FN_PULSE ? &s->jumps : NULL);
      if (!st && s->fn == NL_FN_PWL) st = read_pwl(r, w, elem, s, v, count);
      if (!st && s->fn != NL_FN_PWL) {
        if (count < 2)
          st = nx_fail(&r->x, CUP_ERR_PARSE, w, elem, "%s needs at least 2 values (got %d)", w->s, count);
        memcpy(s->p, v, sizeof(double) * (size_t)count);
        s->np = count;
      }
    } else if (w->kind == NX_WORD) {
      for (int j = 0; unsupported[j]; j++)
        if (nx_is(w, unsupported[j]))
          st = nx_fail(&r->x, CUP_ERR_UNSUPPORTED, w, elem, "source function %s is not supported "
                       "(DC, SIN, PULSE and PWL are)", w->s);
      if (st) break;
      if (!looks_value(r, w) || have_dc)
        st = nx_fail(&r->x, CUP_ERR_PARSE, w, elem, "unexpected '%.40s' (expected DC, AC, SIN, PULSE, PWL "
                     "or a value)", w->s);
      else
        st = nx_value(&r->x, &t[k++], elem, &s->dc);
      have_dc = 1;
    } else if (w->kind == NX_EXPR && !have_dc) {
      st = nx_value(&r->x, &t[k++], elem, &s->dc);
      have_dc = 1;
    } else {
      st = nx_fail(&r->x, CUP_ERR_PARSE, w, elem, "unexpected '%.40s'", w->s);
    }
  }
  free(v);
  return st;
}

int nr_read_source(rd *r, int card, nl_kind kind) {
  const nx_tok *name = TOK(r, card, 0);
  nl_elem *e;
  int st = open_elem(r, card, kind, 3, "N+ N- [spec]", &e);
  if (st) return st;
  int sfirst, sn;
  if (set_tokens(r, name->s, &sfirst, &sn)) return source_spec(r, &r->x.tok[sfirst], sn, name->s, &e->src);
  return source_spec(r, TOK(r, card, 3), r->x.card[card].n - 3, name->s, &e->src);
}

/* ---- diodes and models ------------------------------------------------------- */

int nr_read_diode(rd *r, int card) {
  int n = r->x.card[card].n;
  const nx_tok *name = TOK(r, card, 0);
  nl_elem *e;
  int st = open_elem(r, card, NL_D, 3, "ANODE CATHODE [MODEL]", &e);
  if (!st) st = refuse_set(r, name->s, "a diode is ideal: it has no value to set");
  if (st) return st;
  if (n >= 4) {
    const nx_tok *m = TOK(r, card, 3);
    if (m->kind != NX_WORD || looks_value(r, m))
      return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, m, name->s, "'%.40s' is not supported (a diode takes ANODE "
                     "CATHODE [MODEL]; area factors are not)", m->s);
    int mc = nx_hash_get(&r->models, m->s);
    if (mc < 0 || !nx_is(TOK(r, mc, 2), "d"))
      return nx_fail(&r->x, CUP_ERR_PARSE, m, name->s, "model '%.40s' is not %s (an ideal diode needs "
                     "'.model %.40s D' or no model)", m->s, mc < 0 ? "defined" : "a diode model", m->s);
  }
  if (n >= 5)
    return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, TOK(r, card, 4), name->s, "'%.40s' is not supported (a diode "
                   "takes ANODE CATHODE [MODEL])", TOK(r, card, 4)->s);
  return CUP_OK;
}

/* ---- controlled sources and coupled inductors -------------------------------- */

/* One value from the card at token k, or from the set that names the
 * element; nothing may follow it. */
/* POLY, VALUE= and the like (nonlinear or frequency-domain forms) at token k. */
static int nonlinear_form(rd *r, int card, int k, const char *operands) {
  static const char *const kw[] = {"poly", "value", "table", "laplace", "vol", "cur", "freq", NULL};
  const nx_tok *name = TOK(r, card, 0), *t = TOK(r, card, k);
  for (int j = 0; kw[j]; j++)
    if (nx_is(t, kw[j]))
      return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, t, name->s, "%s is not supported (linear controlled sources "
                     "only: '%s %s')", t->s, name->s, operands);
  return CUP_OK;
}

static int read_gain(rd *r, int card, int k, const char *operands, double *v) {
  int n = r->x.card[card].n, sfirst, sn;
  const nx_tok *name = TOK(r, card, 0);
  if (n <= k) return nx_fail(&r->x, CUP_ERR_PARSE, name, name->s, "expected '%s %s'", name->s, operands);
  const nx_tok *vt = TOK(r, card, k);
  int st = nonlinear_form(r, card, k, operands);
  if (st) return st;
  if (set_tokens(r, name->s, &sfirst, &sn)) {
    if (sn != 1) return nx_fail(&r->x, CUP_ERR_PARSE, sn ? &r->x.tok[sfirst] : name, name->s, "expected one value");
    vt = &r->x.tok[sfirst];
  }
  st = nx_value(&r->x, vt, name->s, v);
  if (!st && n > k + 1)
    st = nx_fail(&r->x, CUP_ERR_UNSUPPORTED, TOK(r, card, k + 1), name->s, "'%.40s' is not supported here "
                 "(expected '%s %s')", TOK(r, card, k + 1)->s, name->s, operands);
  return st;
}

/* E, G: N+ N- NC+ NC- GAIN; F, H: N+ N- VNAME GAIN (the controlling
 * element is looked up once every element is read). */
int nr_read_controlled(rd *r, int card, nl_kind kind) {
  const nx_tok *name = TOK(r, card, 0);
  int voltage = kind == NL_E || kind == NL_G;
  const char *operands = voltage ? "N+ N- NC+ NC- GAIN" : "N+ N- VNAME GAIN";
  nl_elem *e;
  int st = r->x.card[card].n > 3 ? nonlinear_form(r, card, 3, operands) : CUP_OK;
  if (!st) st = open_elem(r, card, kind, voltage ? 6 : 5, operands, &e);
  if (st) return st;
  if (voltage) {
    st = node_of(r, TOK(r, card, 3), name->s, &e->ca);
    if (!st) st = node_of(r, TOK(r, card, 4), name->s, &e->cb);
  } else {
    const nx_tok *v = TOK(r, card, 3);
    if (v->kind != NX_WORD) return nx_fail(&r->x, CUP_ERR_PARSE, v, name->s, "expected the controlling element's name");
    e->ctrl = -1 - (int)(v - r->x.tok);         /* resolved later */
  }
  if (!st) st = read_gain(r, card, voltage ? 5 : 4, operands, &e->value);
  return st;
}

/* K L1 L2 k: the inductors are looked up once every element is read. */
int nr_read_coupling(rd *r, int card) {
  nl_circuit *c = r->c;
  const nx_tok *name = TOK(r, card, 0);
  int prev = nx_hash_get(&r->elems, name->s);
  if (prev >= 0)
    return nx_fail(&r->x, CUP_ERR_PARSE, name, name->s, "duplicate element name (first at line %d)", c->elem[prev].line);
  for (int j = 0; j < c->ncoup; j++)   /* K cards are not elements: their names are checked here */
    if (!strcasecmp(c->coup[j].name, name->s))
      return nx_fail(&r->x, CUP_ERR_PARSE, name, name->s, "duplicate coupling name (first at line %d)", c->coup[j].line);
  if (r->x.card[card].n < 4) return nx_fail(&r->x, CUP_ERR_PARSE, name, name->s, "expected '%s L1 L2 k'", name->s);
  if (la_grow(&c->coup, &r->capcoup, c->ncoup, sizeof *c->coup, 8)) return nr_nomem(r);
  nl_coupling *k = &c->coup[c->ncoup];
  memset(k, 0, sizeof *k);
  if (!(k->name = strdup(name->s))) return nr_nomem(r);
  c->ncoup++;
  k->file = name->file;
  k->line = name->line;
  k->col = name->col;
  if (!strcasecmp(TOK(r, card, 1)->s, TOK(r, card, 2)->s))
    return nx_fail(&r->x, CUP_ERR_PARSE, TOK(r, card, 2), name->s, "an inductor coupled to itself");
  for (int j = 1; j <= 2; j++) {
    const nx_tok *l = TOK(r, card, j);
    if (l->kind != NX_WORD || (l->s[0] != 'l' && l->s[0] != 'L'))
      return nx_fail(&r->x, CUP_ERR_PARSE, l, name->s, "expected an inductor's name (got '%.40s')", l->s);
    *(j == 1 ? &k->l1 : &k->l2) = -1 - (int)(l - r->x.tok);
  }
  int st = read_gain(r, card, 3, "L1 L2 k", &k->k);
  const nx_tok *kt = TOK(r, card, 3);
  if (!st && !(fabs(k->k) < 1))
    return nx_fail(&r->x, CUP_ERR_PARSE, kt, name->s, fabs(k->k) == 1
                   ? "k = %g is not supported: a perfect coupling (an ideal transformer) has a singular "
                     "inductance matrix, which gives no energy metric; use |k| < 1 such as 0.999 (the leakage "
                     "inductance is then (1 - k^2) L) or model the transformer's leakage with a series inductor"
                   : "k = %g is out of range: a coupling coefficient needs |k| < 1", k->k);
  return st;
}

/* ---- switches ----------------------------------------------------------------- */

/* The parameters of an SW (S) or CSW (W) model, as ngspice names them:
 * VT VH (IT IH) RON ROFF, with or without parentheses. RON and ROFF not
 * given are 0: an ideal switch (a short, an open). */
static int switch_model(rd *r, int mc, const nx_tok *at, nl_elem *e) {
  int n = r->x.card[mc].n, current = e->kind == NL_W;
  const nx_tok *mname = TOK(r, mc, 1);
  static const char *const vnames[] = {"vt", "vh", "ron", "roff"}, *const inames[] = {"it", "ih", "ron", "roff"};
  const char *const *names = current ? inames : vnames;
  if (!nx_is(TOK(r, mc, 2), current ? "csw" : "sw"))
    return nx_fail(&r->x, CUP_ERR_PARSE, at, e->name, "model '%.40s' is not a%s model (%s takes '.model %.40s %s(%s)')",
                   mname->s, current ? " CSW" : "n SW", current ? "W" : "S", mname->s, current ? "CSW" : "SW",
                   current ? "IT= IH= RON= ROFF=" : "VT= VH= RON= ROFF=");
  double *dst[4] = {&e->vt, &e->vh, &e->ron, &e->roff};
  for (int k = 3; k < n; k++) {
    const nx_tok *t = TOK(r, mc, k);
    if (t->kind == NX_LP || t->kind == NX_RP) continue;
    int j = 0;
    while (j < 4 && !nx_is(t, names[j])) j++;
    if (j == 4 || t->kind != NX_WORD)
      return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, t, mname->s, "'%.20s' is not a parameter of a %s model (%s %s "
                     "%s %s)", t->s, current ? "CSW" : "SW", names[0], names[1], names[2], names[3]);
    if (k + 2 >= n || TOK(r, mc, k + 1)->kind != NX_EQ)
      return nx_fail(&r->x, CUP_ERR_PARSE, t, mname->s, "expected %s=VALUE", t->s);
    int st = nx_value(&r->x, TOK(r, mc, k + 2), mname->s, dst[j]);
    if (st) return st;
    if (j >= 2 && !(*dst[j] > 0))
      return nx_fail(&r->x, CUP_ERR_PARSE, TOK(r, mc, k + 2), mname->s, "bad value: %s must be > 0 (got %g; "
                     "leave it out for an ideal switch)", names[j], *dst[j]);
    k += 2;
  }
  return CUP_OK;
}

/* S N+ N- NC+ NC- MODEL [ON|OFF]; W N+ N- VCTRL MODEL [ON|OFF] (the
 * controlling element is looked up once every element is read). */
int nr_read_switch(rd *r, int card, nl_kind kind) {
  const nx_tok *name = TOK(r, card, 0);
  int voltage = kind == NL_S, n = r->x.card[card].n, k = voltage ? 5 : 4;
  const char *operands = voltage ? "N+ N- NC+ NC- MODEL [ON|OFF]" : "N+ N- VCTRL MODEL [ON|OFF]";
  nl_elem *e;
  int st = open_elem(r, card, kind, k + 1, operands, &e);
  if (st) return st;
  r->c->nswitch++;
  e->init = -1;
  st = refuse_set(r, name->s, "a switch has no value to set (set its model's parameters through .param)");
  if (st) return st;
  if (voltage) {
    st = node_of(r, TOK(r, card, 3), name->s, &e->ca);
    if (!st) st = node_of(r, TOK(r, card, 4), name->s, &e->cb);
    if (!st && e->ca == e->cb)
      return nx_fail(&r->x, CUP_ERR_PARSE, TOK(r, card, 4), name->s, "no control path: both control nodes are "
                     "'%.40s', so the control voltage is always 0", TOK(r, card, 4)->s);
  } else {
    const nx_tok *v = TOK(r, card, 3);
    if (v->kind != NX_WORD) return nx_fail(&r->x, CUP_ERR_PARSE, v, name->s, "expected the controlling element's name");
    e->ctrl = -1 - (int)(v - r->x.tok);         /* resolved later */
  }
  if (st) return st;
  const nx_tok *m = TOK(r, card, k++);
  int mc = m->kind == NX_WORD ? nx_hash_get(&r->models, m->s) : -1;
  if (mc < 0)
    return nx_fail(&r->x, CUP_ERR_PARSE, m, name->s, "model '%.40s' is not defined (a switch needs '.model %.40s "
                   "%s(...)')", m->s, m->s, voltage ? "SW" : "CSW");
  st = switch_model(r, mc, m, e);
  if (st) return st;
  if (k < n && (nx_is(TOK(r, card, k), "on") || nx_is(TOK(r, card, k), "off"))) e->init = nx_is(TOK(r, card, k++), "on");
  if (k < n)
    return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, TOK(r, card, k), name->s, "'%.40s' is not supported here (expected "
                   "'%s %s')", TOK(r, card, k)->s, name->s, operands);
  return CUP_OK;
}

/* The names that F, H, W and K refer to, once every element is read. */
int nr_resolve_refs(rd *r) {
  nl_circuit *c = r->c;
  for (int e = 0; e < c->nelem; e++) {
    nl_elem *el = &c->elem[e];
    if ((el->kind != NL_F && el->kind != NL_H && el->kind != NL_W) || el->ctrl >= 0) continue;
    const nx_tok *t = &r->x.tok[-1 - el->ctrl];
    el->ctrl = nx_hash_get(&r->elems, t->s);
    if (el->ctrl < 0)
      return nx_fail(&r->x, CUP_ERR_PARSE, t, el->name, "%sno element named '%.40s' (the controlling current "
                     "flows through it)", el->kind == NL_W ? "no control path: " : "", t->s);
    int ck = c->elem[el->ctrl].kind;
    if (ck == NL_S || ck == NL_W)
      return nx_fail(&r->x, CUP_ERR_UNSUPPORTED, t, el->name, "a switch's current (%.40s) does not control "
                     "others here (any other element's can)", t->s);
  }
  for (int q = 0; q < c->ncoup; q++) {
    nl_coupling *k = &c->coup[q];
    for (int j = 0; j < 2; j++) {
      int *l = j ? &k->l2 : &k->l1;
      const nx_tok *t = &r->x.tok[-1 - *l];
      *l = nx_hash_get(&r->elems, t->s);
      if (*l < 0 || c->elem[*l].kind != NL_L)
        return nx_fail(&r->x, CUP_ERR_PARSE, t, k->name, "no inductor named '%.40s'", t->s);
    }
    nx_tok at = {NX_WORD, NULL, k->line, k->col, -1, k->file, 0};
    for (int p = 0; p < q; p++)
      if ((c->coup[p].l1 == k->l1 && c->coup[p].l2 == k->l2) || (c->coup[p].l1 == k->l2 && c->coup[p].l2 == k->l1))
        return nx_fail(&r->x, CUP_ERR_PARSE, &at, k->name, "%s and %s are already coupled by %s",
                       c->elem[k->l1].name, c->elem[k->l2].name, c->coup[p].name);
  }
  return CUP_OK;
}

/* netlist_read — SPICE-subset netlists (.cir/.sp) into the circuit
 * description of model/netlist_desc.h, then into an LCS (model/netlist.c).
 * The subset and its errors are documented in docs/netlist.md: R, L, C,
 * independent V and I sources (DC, SIN, PULSE, PWL), ideal diodes,
 * .tran, .param, .ic, .model NAME D, .probe/.save/.print, .end; anything
 * else is refused by name ("not supported"), never guessed. */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include "catchup.h"
#include "netlist_lex.h"
#include "netlist_subckt.h"
#include "read_text.h"
#include "model/netlist_desc.h"
#include "model/netlist_impl.h"

typedef struct rd {
  nx x;
  nl_circuit *c;
  nx_hash nodes, elems, models, setnames;
  int end;                  /* cards 0 .. end-1 are read (.end stops) */
  unsigned char *skip;      /* cards inside .control ... .endc */
  int *set_used, *set_first, *set_n;   /* per set: used, its value's tokens */
  int capelem, capic, capprobe, capcoup;
} rd;

#define TOK(r_, c_, k_) (&(r_)->x.tok[(r_)->x.card[c_].first + (k_)])

static int nomem(rd *r) { return nx_fail(&r->x, CUP_ERR_NOMEM, NULL, NULL, "out of memory"); }

/* ---- nodes and elements ------------------------------------------------------ */

static int is_ground(const char *s) { return !strcmp(s, "0") || !strcasecmp(s, "gnd"); }

static int node_of(rd *r, const nx_tok *t, const char *elem, int *out) {
  nl_circuit *c = r->c;
  if (t->kind != NX_WORD) return nx_fail(&r->x, CUP_ERR_PARSE, t, elem, "expected a node name (got '%s')", t->s);
  if (strchr(t->s, '/'))
    return nx_fail(&r->x, CUP_ERR_PARSE, t, elem, "node name '%.40s': '/' is not allowed (it would split "
                   "the HDF5 signal name)", t->s);
  if (is_ground(t->s)) {
    if (!c->node[0] && !(c->node[0] = strdup(t->s))) return nomem(r);
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
    if (!nn || !nl || !nc) return nomem(r);
  }
  if (!(c->node[k] = strdup(t->s)) || nx_hash_put(&r->nodes, t->s, k)) return nomem(r);
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
  if (cup_grow(&c->elem, &r->capelem, c->nelem, sizeof *c->elem, 32)) return nomem(r);
  nl_elem *e = &c->elem[c->nelem];
  memset(e, 0, sizeof *e);
  e->kind = kind;
  e->file = name->file;
  e->line = name->line;
  e->col = name->col;
  if (!(e->name = strdup(name->s)) || nx_hash_put(&r->elems, name->s, c->nelem)) { free(e->name); return nomem(r); }
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

static int read_passive(rd *r, int card, nl_kind kind) {
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
  if (!s->t || !s->v) return nomem(r);
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
      if (!(v = malloc(sizeof(double) * (size_t)(max + 1)))) { st = nomem(r); break; }
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

static int read_source(rd *r, int card, nl_kind kind) {
  const nx_tok *name = TOK(r, card, 0);
  nl_elem *e;
  int st = open_elem(r, card, kind, 3, "N+ N- [spec]", &e);
  if (st) return st;
  int sfirst, sn;
  if (set_tokens(r, name->s, &sfirst, &sn)) return source_spec(r, &r->x.tok[sfirst], sn, name->s, &e->src);
  return source_spec(r, TOK(r, card, 3), r->x.card[card].n - 3, name->s, &e->src);
}

/* ---- diodes and models ------------------------------------------------------- */

static int read_diode(rd *r, int card) {
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
static int read_controlled(rd *r, int card, nl_kind kind) {
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
static int read_coupling(rd *r, int card) {
  nl_circuit *c = r->c;
  const nx_tok *name = TOK(r, card, 0);
  int prev = nx_hash_get(&r->elems, name->s);
  if (prev >= 0)
    return nx_fail(&r->x, CUP_ERR_PARSE, name, name->s, "duplicate element name (first at line %d)", c->elem[prev].line);
  for (int j = 0; j < c->ncoup; j++)   /* K cards are not elements: their names are checked here */
    if (!strcasecmp(c->coup[j].name, name->s))
      return nx_fail(&r->x, CUP_ERR_PARSE, name, name->s, "duplicate coupling name (first at line %d)", c->coup[j].line);
  if (r->x.card[card].n < 4) return nx_fail(&r->x, CUP_ERR_PARSE, name, name->s, "expected '%s L1 L2 k'", name->s);
  if (cup_grow(&c->coup, &r->capcoup, c->ncoup, sizeof *c->coup, 8)) return nomem(r);
  nl_coupling *k = &c->coup[c->ncoup];
  memset(k, 0, sizeof *k);
  if (!(k->name = strdup(name->s))) return nomem(r);
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
static int read_switch(rd *r, int card, nl_kind kind) {
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
static int resolve_refs(rd *r) {
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

static int read_model(rd *r, int card) {
  int n = r->x.card[card].n;
  const nx_tok *cmd = TOK(r, card, 0);
  if (n < 3) return nx_fail(&r->x, CUP_ERR_PARSE, cmd, ".model", "expected '.model NAME D'");
  const nx_tok *name = TOK(r, card, 1), *type = TOK(r, card, 2);
  if (name->kind != NX_WORD) return nx_fail(&r->x, CUP_ERR_PARSE, name, ".model", "expected a model name");
  if (nx_is(type, "sw") || nx_is(type, "csw")) {  /* parameters read with the switches that use it */
    if (nx_hash_get(&r->models, name->s) >= 0)
      return nx_fail(&r->x, CUP_ERR_PARSE, name, name->s, "model defined twice");
    return nx_hash_put(&r->models, name->s, card) ? nomem(r) : CUP_OK;
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
  return nx_hash_put(&r->models, name->s, card) ? nomem(r) : CUP_OK;
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
    if (cup_grow(&x->par, &x->cappar, x->npar, sizeof *x->par, 16)) return nomem(r);
    nx_param *p = &x->par[x->npar];
    memset(p, 0, sizeof *p);
    if (!(p->name = strdup(name->s))) return nomem(r);
    p->value = *TOK(r, card, k + 2);
    if (nx_hash_put(&x->parh, name->s, x->npar++)) return nomem(r);
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
    if (cup_grow(&c->ic, &r->capic, c->nic, sizeof *c->ic, 8)) return nomem(r);
    nl_ic *ic = &c->ic[c->nic];
    const nx_tok *nd = TOK(r, card, k + 2);
    ic->line = nd->line;
    ic->col = nd->col;
    ic->node = is_ground(nd->s) ? 0 : -1 - (int)(nd - r->x.tok);   /* resolved later */
    int st = nx_value(&r->x, TOK(r, card, k + 5), ".ic", &ic->v);
    if (st) return st;
    c->nic++;
  }
  return CUP_OK;
}

static int add_probe(rd *r, const nx_tok *at, const char *text) {
  nl_circuit *c = r->c;
  if (cup_grow(&c->probe, &r->capprobe, c->nprobe, sizeof *c->probe, 8)) return nomem(r);
  nl_probe *p = &c->probe[c->nprobe];
  if (!(p->text = strdup(text))) return nomem(r);
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
    case 'r': return read_passive(r, card, NL_R);
    case 'l': return read_passive(r, card, NL_L);
    case 'c': return read_passive(r, card, NL_C);
    case 'v': return read_source(r, card, NL_V);
    case 'i': return read_source(r, card, NL_I);
    case 'd': return read_diode(r, card);
    case 'e': return read_controlled(r, card, NL_E);
    case 'f': return read_controlled(r, card, NL_F);
    case 'g': return read_controlled(r, card, NL_G);
    case 'h': return read_controlled(r, card, NL_H);
    case 'k': return read_coupling(r, card);
    case 's': return read_switch(r, card, NL_S);
    case 'w': return read_switch(r, card, NL_W);
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
  if (!(r->skip = calloc((size_t)x->ncard + 1, 1))) return nomem(r);
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
    return nomem(r);
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
      return nomem(r);
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
  if (!(c->files = calloc((size_t)r->x.nfiles + 1, sizeof(char *)))) return nomem(r);
  for (int f = 0; f < r->x.nfiles; f++)
    if (!(c->files[c->nfiles++] = strdup(r->x.files[f].path))) return nomem(r);
  return CUP_OK;
}

static int read_cards(rd *r) {
  nl_circuit *c = r->c;
  if (!(c->node = calloc(1, sizeof *c->node)) || !(c->node_line = calloc(1, sizeof(int))) ||
      !(c->node_col = calloc(1, sizeof(int))))
    return nomem(r);
  c->nnodes = 1;                                   /* ground */
  int st = nx_structure(&r->x);
  if (!st) st = first_pass(r);
  if (!st) st = apply_sets(r);
  if (!st && (st = nx_flatten(&r->x)) == CUP_OK) {   /* the cards are now the flattened ones */
    r->end = r->x.ncard;
    free(r->skip);
    if (!(r->skip = calloc((size_t)r->x.ncard + 1, 1))) st = nomem(r);
  }
  if (!st) st = copy_files(r);
  for (int k = 0; k < r->end && !st; k++)
    if (!r->skip[k]) st = read_element(r, k);
  if (!st) st = resolve_ic(r);
  if (!st) st = resolve_refs(r);
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
                const char *const *sets, int nsets, cup_file_list *files, char *errmsg) {
  nl_circuit c = {0};
  c.reltol = c.abstol = c.vntol = c.chgtol = NAN;  /* .options not given */
  rd r = {0};
  r.x.file = name;
  r.x.read_list = files;
  r.x.sets = sets;
  r.x.nsets = nsets;
  r.x.errmsg = errmsg;
  r.c = &c;
  int st = (c.file = strdup(name)) ? CUP_OK : nomem(&r);
  if (!st && nx_add_file(&r.x, name, -1, 0) < 0) st = nomem(&r);
  if (!st) st = nx_lex_file(&r.x, 0, text, len, 1);
  if (!st) st = read_cards(&r);
  if (!st) st = c.nswitch ? nl_switched_formulate(out, &c, errmsg) : cup_netlist_formulate(out, &c, errmsg);
  if (!st && !((*out)->source = strndup(text, len))) {
    cup_netlist_free(out);
    st = nomem(&r);
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
  return cup_load_args("netlist", "set", out != NULL, src, list, n, errmsg);
}

int cup_netlist_load_string_files(cup_netlist **out, const char *text, const char *name, const char *const *sets,
                                  int nsets, cup_file_list *files, char *errmsg) {
  int st = check_args(out, text, sets, nsets, errmsg);
  return st ? st : load(out, text, strlen(text), name ? name : "<string>", sets, nsets, files, errmsg);
}

int cup_netlist_load_string(cup_netlist **out, const char *text, const char *name,
                            const char *const *sets, int nsets, char *errmsg) {
  return cup_netlist_load_string_files(out, text, name, sets, nsets, NULL, errmsg);
}

int cup_netlist_load_files(cup_netlist **out, const char *path, const char *const *sets, int nsets,
                           cup_file_list *files, char *errmsg) {
  int st = check_args(out, path, sets, nsets, errmsg);
  char *text = NULL;
  size_t len = 0;
  if (!st) st = cup_read_text(path, &text, &len, files, errmsg);
  if (!st) st = load(out, text, len, path, sets, nsets, files, errmsg);
  free(text);
  return st;
}

int cup_netlist_load(cup_netlist **out, const char *path, const char *const *sets, int nsets, char *errmsg) {
  return cup_netlist_load_files(out, path, sets, nsets, NULL, errmsg);
}

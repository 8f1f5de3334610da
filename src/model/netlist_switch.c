/* netlist_switch — switches (S, W; docs/netlist.md, "Switches"). A switch
 * configuration is a circuit of its own: a closed ideal switch a short (a
 * voltage port of value 0), an open one an open (a current port of value
 * 0), RON and ROFF resistors. Each configuration is formulated the first
 * time it occurs and kept, over the same state (inductor currents,
 * capacitor voltages), inputs and diode rows as every other.
 *
 * Index problems that a switch makes are constraints on the state: a
 * closed switch that closes a loop of capacitors becomes a row "its
 * voltage is 0" whose multiplier is the loop's current (a current port),
 * an inductor cutset that an open switch leaves gets a row "the cut's
 * current is 0" whose multiplier is the cut's voltage (a voltage port
 * across it). With B_Q = P^-1 C_Q^T (the network is reciprocal) the
 * P-orthogonal projector onto {C_Q x = 0},
 *     Pi = I - P^-1 C_Q^T (C_Q P^-1 C_Q^T)^-1 C_Q,
 * eliminates them: x' = Pi (A x + E u) + Pi B zeta, w = C Pi x + ..., an
 * LCS with P (Pi B) = (C Pi)^T, every scheme's. The state keeps to the
 * constraints once on them, and the jump into the configuration is x <- Pi x:
 * the projection in the energy metric, which conserves the charge of a
 * capacitor loop and the flux of an inductor cut. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "catchup/netlist.h"
#include "netlist_impl.h"
#include "input_impl.h"

#define NL_TOPO_MAX 64     /* configurations kept (a converter has a handful) */
#define NL_TAB_TERMS 6     /* read_piece's table: a class reading up to 6 terms (a full bridge's 4 gates) */

typedef struct nl_topo {
  uint64_t cfg;            /* bit k: switch k closed */
  cup_netlist *sub;        /* its netlist (LCS, signals); topo[0]'s is the netlist itself */
  double *Pi;              /* n x n, column-major: the jump onto its constraints (nq > 0) */
  double *ctl;             /* nsw x (n + p + m_sub), row-major: each switch's control */
  /* the controls' nonzeros (ctl_sparse): the searches evaluate them, and
   * only the input terms they read, some thousand times a run */
  int *cp, *ci;            /* nsw + 1 starts, columns (in x, u, zeta) */
  double *cx;              /* ... their values */
  int *uterm, nuterm;      /* the input's terms whose component a control reads (all: zeta's rows read u) */
  int reads_z;             /* a control reads zeta */
  int state_gated;         /* a control depends on the state or the diodes */
  int memo;                /* its input is topo[0]'s, term by term: the memos hold for it (memo_reset) */
  int steps;               /* the terms read are constants and jump PULSEs: between two breaks of
                              the input, u(t) and the controls from it are one value */
  uint64_t by_state;       /* bit k: switch k's does (gated_by_state, for changes) */
  int ctl_class;           /* > 0: configurations of one class have the same controls, of t alone
                              (same_controls): settle's rule holds in the one it moves to; 0: none */
  int succ;                /* the configuration settle last moved to from it (a hint: its cfg is checked) */
} nl_topo;

struct nl_switched {
  nl_circuit c;            /* the circuit as read (owned) */
  int nsw;
  int *sw;                 /* the switches' elements */
  int ntopo;
  nl_topo topo[NL_TOPO_MAX];
  long formed;             /* configurations formulated */
  int nclass;              /* the control classes given out (nl_topo's ctl_class) */
  int cur;                 /* the configuration in force (signals) */
  double *ut;              /* p: u(t) */
  double *zf;              /* scratch: a configuration's zeta with multipliers */
  double *thr;             /* 2 nsw: each switch's VT + |VH| and VT - |VH| (rule) */
  /* the searches' memos of topo[0]'s input, term by term (nl_topo.memo):
   * a switched run asks each piece's end and a few times around it, and
   * at a converter's corner one gate moves while the others hold */
  int nmemo;               /* its terms */
  input_break_memo *bmemo; /* each one's next break */
  double *vmemo;           /* 4 each: its value on [from, hi) (input_term_piece), from, hi, value, and a
                              jump PULSE's period there (spice_jump_pulse_j; else NaN) */
  /* the controls a search read last (changes), where its terms' pieces
   * overlap: the next piece's first check reads them again */
  int cvm_class;           /* their configurations' control class (0: none held) */
  double cvm_lo, cvm_hi, *cvm;
  uint64_t cvm_from, cvm_to; /* the rule's last answer from them: cvm_from gave cvm_to */
  double read_lo, read_hi; /* the last read_terms': where its terms' memos all hold */
  /* a class's controls by which of its terms are off their value (read_piece) */
  int tab_class;           /* the class they are (0: none) */
  double *tab;             /* 2^NL_TAB_TERMS x nsw */
  uint64_t tab_ok;         /* bit key: its row holds */
  uint64_t tab_from[1 << NL_TAB_TERMS], tab_to[1 << NL_TAB_TERMS];   /* the rule's last answer on it */
  int linear;              /* every source is DC, PULSE or PWL: the input is linear between breakpoints */
  double t0;               /* the time origin: each configuration's sources from t0 on (nl_input_origin) */
  /* the switching time the last search found (a configuration with no
   * switch the circuit gates) and the configuration the rule gave there:
   * the settle that follows it, at that time, takes it (once) */
  int memo_ok, memo_topo;
  double memo_t;
  uint64_t memo_cfg, last_cfg;   /* ... and the rule's at the last check (changes) */
  /* a controller from code (cup_netlist_set_controller): it alone sets the gates, at t = k ts */
  cup_gate_fn gate_fn;
  void *gate_ctx;
  double gate_ts;
  int *gate;               /* nsw */
};

/* t's sampling instant k if t is one (within 1e-9 ts), else -1. */
static long instant(const nl_switched *S, double t) {
  double k = floor(t / S->gate_ts + 0.5);
  return fabs(t - k * S->gate_ts) <= 1e-9 * S->gate_ts ? (long)k : -1;
}

/* ---- a configuration's circuit ---------------------------------------------------- */

static int find(int *uf, int v) {
  while (uf[v] != v) v = uf[v] = uf[uf[v]];
  return v;
}

/* Element e of kind D (eq) or Z appended to d (names owned by d from
 * c->nelem on). */
static int append(nl_circuit *d, nl_kind kind, int eq, int a, int b, const char *base, const char *suffix, int at) {
  nl_elem *e = &d->elem[d->nelem];
  memset(e, 0, sizeof *e);
  size_t len = strlen(base) + strlen(suffix) + 1;
  if (!(e->name = malloc(len))) return CUP_ERR_NOMEM;
  snprintf(e->name, len, "%s%s", base, suffix);
  e->kind = kind; e->eq = eq; e->a = a; e->b = b;
  e->file = d->elem[at].file; e->line = d->elem[at].line; e->col = d->elem[at].col;
  d->nelem++;
  return CUP_OK;
}

/* The part of the circuit with node v that nothing but current ports joins
 * to ground's: a constraint across its inductor (or current source), or, if
 * only open switches reach it, its potential pinned to ground's (it floats:
 * nothing depends on it). */
static int close_cut(nl_circuit *d, int *uf, int v) {
  int rv = find(uf, v), pick = -1;
  static const nl_kind pref[5] = {NL_L, NL_I, NL_F, NL_G, NL_O};
  for (int g = 0; g < 5 && pick < 0; g++)
    for (int e = 0; e < d->nelem && pick < 0; e++) {
      const nl_elem *el = &d->elem[e];
      if (el->kind == pref[g] && (find(uf, el->a) == rv) != (find(uf, el->b) == rv)) pick = e;
    }
  int st = pick >= 0 && d->elem[pick].kind != NL_O
             ? append(d, NL_D, NL_EQ_CUT, d->elem[pick].a, d->elem[pick].b, d->elem[pick].name, "#cut", pick)
             : append(d, NL_Z, NL_EQ_NONE, v, 0, d->node[v] ? d->node[v] : "?", "#ground", 0);
  if (!st) uf[rv] = find(uf, 0);
  return st;
}

/* Configuration cfg's circuit into d: switches replaced, loop constraints
 * in place of the closed switches that close a loop of voltage ports, cut
 * constraints appended. The order of the formulation's own checks
 * (netlist_graph.c) is followed, so that it finds what this found. */
static int derive(const nl_switched *S, uint64_t cfg, nl_circuit *d) {
  const nl_circuit *c = &S->c;
  *d = *c;
  d->derived = 1;
  d->nprobe = 0; d->probe = NULL; d->probe_all = 0;
  d->elem = calloc((size_t)c->nelem + (size_t)c->nnodes + 1, sizeof(nl_elem));
  int *uf = malloc(sizeof(int) * (size_t)c->nnodes);
  if (!d->elem || !uf) { free(uf); return CUP_ERR_NOMEM; }
  for (int e = 0, k = 0; e < c->nelem; e++) {
    nl_elem *el = &d->elem[e];
    *el = c->elem[e];
    if (el->kind != NL_S && el->kind != NL_W) continue;
    int on = (int)(cfg >> k++ & 1u);
    el->value = on ? el->ron : el->roff;
    el->kind = el->value > 0 ? NL_R : on ? NL_Z : NL_O;
  }
  for (int v = 0; v < c->nnodes; v++) uf[v] = v;
  for (int e = 0; e < c->nelem; e++) {
    nl_elem *el = &d->elem[e];
    if (el->kind == NL_C || el->kind == NL_V || el->kind == NL_E || el->kind == NL_H) uf[find(uf, el->a)] = find(uf, el->b);
  }
  for (int e = 0; e < c->nelem; e++) {            /* a closed switch that closes a loop: a row */
    nl_elem *el = &d->elem[e];
    if (el->kind != NL_Z) continue;
    if (find(uf, el->a) == find(uf, el->b)) { el->kind = NL_D; el->eq = NL_EQ_LOOP; }
    else uf[find(uf, el->a)] = find(uf, el->b);
  }
  for (int e = 0; e < c->nelem; e++)
    if (d->elem[e].kind == NL_R) uf[find(uf, d->elem[e].a)] = find(uf, d->elem[e].b);
  for (int e = 0; e < c->nelem; e++)
    if (d->elem[e].kind == NL_D && d->elem[e].eq == NL_EQ_NONE) uf[find(uf, d->elem[e].a)] = find(uf, d->elem[e].b);
  int st = CUP_OK;
  for (int v = 1; v < c->nnodes && !st; v++)
    if (find(uf, v) != find(uf, 0)) st = close_cut(d, uf, v);
  free(uf);
  return st;
}

static void derived_free(const nl_circuit *c, nl_circuit *d) {
  for (int e = c->nelem; d->elem && e < d->nelem; e++) free(d->elem[e].name);
  free(d->elem);
}

/* ---- configurations ---------------------------------------------------------------- */

/* 1 if switch k's control in configuration tp depends on the state or the diodes. */
static int gated_by_state(const nl_topo *tp, int k) {
  int n = tp->sub->n, p = tp->sub->p, nv = n + p + tp->sub->m;
  const double *row = tp->ctl + (size_t)k * nv;
  for (int j = 0; j < nv; j++)
    if (row[j] != 0 && (j < n || j >= n + p)) return 1;
  return 0;
}

static void ctl_free(nl_topo *tp) {
  free(tp->ctl); free(tp->cp); free(tp->ci); free(tp->cx); free(tp->uterm);
  tp->ctl = tp->cx = NULL;
  tp->cp = tp->ci = tp->uterm = NULL;
}

/* The controls' rows by their nonzeros, and the input terms they read. */
static int ctl_sparse(const nl_switched *S, nl_topo *tp) {
  const cup_netlist *sub = tp->sub;
  int n = sub->n, p = sub->p, nv = n + p + sub->m, k = 0;
  const cup_input *u = sub->u;
  int nterms = p && u && !u->fn ? u->nterms : 0;
  tp->cp = malloc(sizeof(int) * ((size_t)S->nsw + 1));
  tp->ci = malloc(sizeof(int) * ((size_t)S->nsw * nv + 1));
  tp->cx = malloc(sizeof(double) * ((size_t)S->nsw * nv + 1));
  tp->uterm = malloc(sizeof(int) * ((size_t)nterms + 1));
  unsigned char *reads = calloc((size_t)p + 1, 1);
  if (!tp->cp || !tp->ci || !tp->cx || !tp->uterm || !reads) { free(reads); return CUP_ERR_NOMEM; }
  for (int w = 0; w < S->nsw; w++) {
    tp->cp[w] = k;
    for (int j = 0; j < nv; j++) {
      double v = tp->ctl[(size_t)w * nv + j];
      if (v == 0) continue;
      tp->ci[k] = j;
      tp->cx[k++] = v;
      if (j >= n + p) tp->reads_z = 1;
      else if (j >= n) reads[j - n] = 1;
    }
  }
  tp->cp[S->nsw] = k;
  tp->nuterm = 0;
  for (int q = 0; q < nterms; q++)
    if (reads[u->terms[q].comp] || (tp->reads_z && sub->zrow)) tp->uterm[tp->nuterm++] = q;
  tp->steps = !p || (u && !u->fn);
  for (int q = 0; q < tp->nuterm; q++) {
    const input_term *w = &u->terms[tp->uterm[q]];
    if (w->kind != CUP_WAVE_CONSTANT && !input_jump_pulse(w)) tp->steps = 0;
  }
  free(reads);
  return CUP_OK;
}

/* Configuration cfg formulated into topo (its netlist, LCS, jump, controls). */
static int form(nl_switched *S, cup_netlist **subp, uint64_t cfg, nl_topo *tp, char *errmsg) {
  const nl_circuit *c = &S->c;
  nl_circuit d;
  int st = derive(S, cfg, &d);
  if (st) { derived_free(c, &d); return nl_switch_nomem(c, errmsg); }
  cup_netlist *sub = NULL;
  double *Pi = NULL;
  st = netlist_formulate(&sub, &d, errmsg);
  if (!st) { sub->nelem_user = c->nelem; st = nl_switch_reduce(sub, c, &d, &Pi, errmsg); }
  if (!st && S->t0 != 0) st = nl_input_origin(sub, S->t0, errmsg);   /* formed after the origin was set */
  tp->cfg = cfg;
  tp->Pi = Pi;
  int nv = sub ? sub->n + sub->p + sub->m : 0;
  tp->ctl = !st ? calloc((size_t)S->nsw * nv + 1, sizeof(double)) : NULL;
  if (!st && !tp->ctl) st = nl_switch_nomem(c, errmsg);
  for (int k = 0; k < S->nsw && !st; k++) {       /* each switch's control over (x, u, zeta) */
    const nl_elem *el = &c->elem[S->sw[k]];
    double *row = tp->ctl + (size_t)k * nv;
    st = el->kind == NL_S ? nl_signal_row(sub, 'v', el->ca, el->cb, row) : nl_signal_row(sub, 'i', el->ctrl, -1, row);
    if (st) st = nl_switch_nomem(c, errmsg);
  }
  tp->sub = sub;                                   /* (gated_by_state reads it) */
  for (int k = 0; !st && k < S->nsw; k++)
    if (gated_by_state(tp, k)) tp->by_state |= (uint64_t)1 << k;
  tp->state_gated = tp->by_state != 0;
  if (!st && ctl_sparse(S, tp)) st = nl_switch_nomem(c, errmsg);
  derived_free(c, &d);
  if (st) {
    cup_netlist_free(&sub);
    free(tp->Pi);
    ctl_free(tp);
    tp->sub = NULL; tp->Pi = NULL;
    return st;
  }
  S->formed++;
  *subp = sub;
  return CUP_OK;
}

/* 1 if two inputs' terms are the same waveform, bit for bit. */
static int same_term(const input_term *a, const input_term *b) {
  if (a->comp != b->comp || a->kind != b->kind || a->np != b->np) return 0;
  const double fa[] = {a->value, a->amp, a->omega, a->phase, a->delay, a->damping, a->value2, a->rise, a->fall,
                       a->width, a->period};
  const double fb[] = {b->value, b->amp, b->omega, b->phase, b->delay, b->damping, b->value2, b->rise, b->fall,
                       b->width, b->period};
  size_t np = a->np > 0 ? (size_t)a->np : 0;
  return !memcmp(fa, fb, sizeof fa) && (!np || (!memcmp(a->t, b->t, np * sizeof *a->t) &&
                                                !memcmp(a->v, b->v, np * sizeof *a->v)));
}

/* 1 if configurations a and b read their switches' controls from the
 * input alone (built-in waveforms: no state, no multiplier), by the same
 * rows and the same terms: at any t the same values, bit for bit. */
static int same_controls(const nl_switched *S, const nl_topo *a, const nl_topo *b) {
  const cup_netlist *sa = a->sub, *sb = b->sub;
  if (a->state_gated || b->state_gated || a->reads_z || b->reads_z) return 0;
  if (sa->n != sb->n || sa->p != sb->p || (sa->p && (!sa->u || !sb->u || sa->u->fn || sb->u->fn))) return 0;
  if (memcmp(a->cp, b->cp, sizeof(int) * ((size_t)S->nsw + 1)) || a->nuterm != b->nuterm) return 0;
  size_t nz = (size_t)a->cp[S->nsw];
  if (memcmp(a->ci, b->ci, sizeof(int) * nz) || memcmp(a->cx, b->cx, sizeof(double) * nz)) return 0;
  for (int q = 0; q < a->nuterm; q++)
    if (a->uterm[q] != b->uterm[q] || !same_term(&sa->u->terms[a->uterm[q]], &sb->u->terms[b->uterm[q]])) return 0;
  return 1;
}

/* Configuration tp's control class: that of a configuration formed before
 * with the same controls, else a new one (0 when they read more than t). */
static void control_class(nl_switched *S, nl_topo *tp) {
  tp->ctl_class = 0;
  if (!same_controls(S, tp, tp)) return;
  for (int k = 0; k < S->ntopo; k++)
    if (&S->topo[k] != tp && S->topo[k].ctl_class && same_controls(S, &S->topo[k], tp)) {
      tp->ctl_class = S->topo[k].ctl_class;
      return;
    }
  tp->ctl_class = ++S->nclass;
}

/* 1 if configuration tp's input is topo[0]'s, term by term, bit for bit:
 * the memos' values and breaks are its own. */
static int reads_memo(const nl_switched *S, const nl_topo *tp) {
  const cup_input *a = S->topo[0].sub->u, *b = tp->sub->u;
  if (!S->bmemo || !a || !b || a->fn || b->fn || a->nterms != S->nmemo || b->nterms != S->nmemo) return 0;
  for (int k = 0; k < a->nterms; k++)
    if (!same_term(&a->terms[k], &b->terms[k])) return 0;
  return 1;
}

/* The memos emptied (they hold for no time) and who reads them, after
 * topo[0] or the sources changed. */
static void memo_reset(nl_switched *S) {
  if (!S->bmemo) return;
  memset(S->bmemo, 0, sizeof *S->bmemo * (size_t)S->nmemo);
  memset(S->vmemo, 0, sizeof *S->vmemo * 4 * (size_t)S->nmemo);
  for (int k = 0; k < S->nmemo; k++) S->vmemo[4 * (size_t)k + 3] = NAN;
  S->cvm_class = 0;
  S->tab_class = 0;
  for (int k = 0; k < S->ntopo; k++) S->topo[k].memo = reads_memo(S, &S->topo[k]);
}

/* Term k's memo (vmemo) on the piece that holds t, taken afresh when t is past it. */
static inline const double *term_at(nl_switched *S, const input_term *w, int k, double t) {
  double *c = S->vmemo + 4 * (size_t)k;
  if (!(t >= c[0] && t < c[1])) {
    c[0] = t;
    /* a gate's pieces one after another: the next from the last's period */
    if (t == c[1] && !isnan(c[3])) c[2] = spice_jump_pulse_next(w, t, &c[3], &c[1]);
    else if (input_jump_pulse(w)) c[2] = spice_jump_pulse_j(w, t, &c[3], &c[1]);
    else c[2] = input_term_piece(w, t, &c[1]);
  }
  return c;
}

/* u(t) into S->ut from the terms configuration tp's controls read (ut's
 * other entries 0), input_eval_terms' sums: with the memos, each term's
 * value while t is in the piece it was taken on. */
static void read_terms(nl_switched *S, const nl_topo *tp, double t) {
  const cup_input *u = tp->sub->u;
  if (!tp->memo) {
    input_eval_terms(u, tp->uterm, tp->nuterm, t, S->ut);
    return;
  }
  double lo = -INFINITY, hi = INFINITY;
  la_zero_few(S->ut, u->p);                        /* (a converter's few: memset's call cost more) */
  for (int q = 0; q < tp->nuterm; q++) {
    int k = tp->uterm[q];
    const double *c = term_at(S, &u->terms[k], k, t);
    S->ut[u->terms[k].comp] += c[2];
    if (c[0] > lo) lo = c[0];
    if (c[1] < hi) hi = c[1];
  }
  S->read_lo = lo;                                 /* where every term read holds (t among them) */
  S->read_hi = hi;
}

/* controls' sums with x and zeta NULL (u's part alone) from u(t) in S->ut. */
static void controls_u(const nl_switched *S, const nl_topo *tp, double *cv) {
  int n = tp->sub->n, p = tp->sub->p;
  for (int k = 0; k < S->nsw; k++) {
    double su = 0;
    for (int q = tp->cp[k]; q < tp->cp[k + 1]; q++) {
      unsigned j = (unsigned)(tp->ci[q] - n);
      if (j < (unsigned)p) su += tp->cx[q] * S->ut[j];
    }
    cv[k] = 0.0 + su + 0.0;
  }
}

/* 1 if a and b are the same double, bit for bit. */
static inline int same_bits(double a, double b) {
  uint64_t x, y;
  memcpy(&x, &a, sizeof x);
  memcpy(&y, &b, sizeof y);
  return x == y;
}

/* The controls of configuration tp's class on the pieces of its terms
 * that hold at b (read_terms, then controls_u: a search's), into S->cvm,
 * and those pieces' span into cvm_lo, cvm_hi. Its terms are constants and
 * PULSEs with jump edges (steps), each piece's value the term's value or
 * value2: the controls are a function of which terms are off their value,
 * kept for each such key (tab) the first time it occurs, the same sums.
 * The key (-1: none, more terms than the table's). */
static int read_piece(nl_switched *S, const nl_topo *tp, double b) {
  const cup_input *u = tp->sub->u;
  if (tp->nuterm > NL_TAB_TERMS || !S->tab) {
    read_terms(S, tp, b);
    controls_u(S, tp, S->cvm);
    S->cvm_lo = S->read_lo;
    S->cvm_hi = S->read_hi;
    return -1;
  }
  if (S->tab_class != tp->ctl_class) {
    S->tab_class = tp->ctl_class;
    S->tab_ok = 0;
  }
  double lo = -INFINITY, hi = INFINITY;
  unsigned key = 0;
  for (int q = 0; q < tp->nuterm; q++) {
    int k = tp->uterm[q];
    const double *c = term_at(S, &u->terms[k], k, b);
    key |= (unsigned)!same_bits(c[2], u->terms[k].value) << q;
    if (c[0] > lo) lo = c[0];
    if (c[1] < hi) hi = c[1];
  }
  double *row = S->tab + (size_t)key * (size_t)S->nsw;
  if (!(S->tab_ok >> key & 1)) {
    read_terms(S, tp, b);                          /* (the pieces at b: held, as just read) */
    controls_u(S, tp, row);
    S->tab_ok |= (uint64_t)1 << key;
    S->tab_from[key] = S->tab_to[key] = UINT64_MAX;   /* (no configuration: bit 63 is no switch) */
  }
  for (int k = 0; k < S->nsw; k++) S->cvm[k] = row[k];
  S->cvm_lo = lo;
  S->cvm_hi = hi;
  return (int)key;
}

/* The configuration's index, formed now if it is new. */
static int topo_of(cup_netlist *nl, uint64_t cfg, int *out, char *errmsg) {
  nl_switched *S = nl->sw;
  for (int k = 0; k < S->ntopo; k++)
    if (S->topo[k].cfg == cfg) { *out = k; return CUP_OK; }
  if (S->ntopo == NL_TOPO_MAX)
    return nl_fail(&S->c, -1, errmsg, CUP_ERR_UNSUPPORTED, "more than %d switch configurations", NL_TOPO_MAX);
  nl_topo *tp = &S->topo[S->ntopo];
  memset(tp, 0, sizeof *tp);
  int st = form(S, &tp->sub, cfg, tp, errmsg);
  for (int k = 0; !st && k < nl->nsig; k++) {     /* the signals recorded, in the same order */
    int q = nl_probe_next(tp->sub, nl->sig_name[k], errmsg);
    if (q != k) st = q < 0 ? q : nl_fail(&S->c, -1, errmsg, CUP_ERR_ARG, "signal order differs");
  }
  if (st) {
    if (tp->sub) cup_netlist_free(&tp->sub);
    free(tp->Pi);
    ctl_free(tp);
    return st;
  }
  control_class(S, tp);
  tp->memo = reads_memo(S, tp);
  *out = S->ntopo++;
  return CUP_OK;
}

/* Each switch's control at t in configuration tp (x, zeta may be NULL: 0),
 * over the controls' nonzeros and the input terms they read (ctl_sparse):
 * the dense rows' sums less terms that are exactly 0, bit for bit. */
static int controls(nl_switched *S, const nl_topo *tp, double t, const double *x, const double *zeta, double *cv) {
  cup_netlist *sub = tp->sub;
  int n = sub->n, p = sub->p, m = sub->m;
  const cup_input *u = sub->u;
  if (p && (!u || u->fn)) {
    if (cup_input_eval(u, t, S->ut)) return CUP_ERR_CALLBACK;
  } else if (p) {
    read_terms(S, tp, t);                          /* the terms read */
  }
  const double *z = zeta;
  if (sub->zrow && tp->reads_z) {
    for (int r = 0; r < m; r++) {
      int k = sub->zrow[r];
      if (k >= 0) { S->zf[r] = zeta ? zeta[k] : 0; continue; }
      const double *l = sub->Lam + (size_t)(-1 - k) * (size_t)(n + p + sub->mr);
      S->zf[r] = (x ? la_dot(l, x, n) : 0) + la_dot(l + n, S->ut, p) + (zeta ? la_dot(l + n + p, zeta, sub->mr) : 0);
    }
    z = S->zf;
  }
  if (!x && !z) {                                  /* a search's: u's part alone (the others 0) */
    controls_u(S, tp, cv);
    return CUP_OK;
  }
  for (int k = 0; k < S->nsw; k++) {
    double sx = 0, su = 0, sz = 0;
    for (int q = tp->cp[k]; q < tp->cp[k + 1]; q++) {
      int j = tp->ci[q];
      if (j < n) sx += x ? tp->cx[q] * x[j] : 0;
      else if (j < n + p) su += tp->cx[q] * S->ut[j - n];
      else sz += z ? tp->cx[q] * z[j - n - p] : 0;
    }
    cv[k] = (x ? sx : 0) + su + (z ? sz : 0);
  }
  return CUP_OK;
}

/* 1 if the controls a search read last (changes' cvm) are configuration
 * tp's at t: its class's, t in the pieces of their terms they were read on
 * (every configuration of a class reads the same sums of the same terms). */
static int held(const nl_switched *S, const nl_topo *tp, double t) {
  return tp->steps && tp->memo && tp->ctl_class && tp->ctl_class == S->cvm_class && t >= S->cvm_lo && t < S->cvm_hi;
}

/* ngspice's rule: on above VT + |VH|, off below VT - |VH| (S->thr), else as before. */
static uint64_t rule(const nl_switched *S, uint64_t cfg, const double *cv) {
  for (int k = 0; k < S->nsw; k++) {
    if (cv[k] > S->thr[2 * k]) cfg |= (uint64_t)1 << k;
    else if (cv[k] < S->thr[2 * k + 1]) cfg &= ~((uint64_t)1 << k);
  }
  return cfg;
}

/* The configuration in force from t on, from the one before: the rule
 * applied until it holds (a switch may move another's control). */
static int settle(cup_netlist *nl, int *topo, double t, const double *x, const double *zeta, char *errmsg) {
  nl_switched *S = nl->sw;
  double cv[64];
  if (S->gate_fn) {                                /* a controller: its gates at its instants, held between */
    if (instant(S, t) < 0) return CUP_OK;
    for (int k = 0; k < S->nsw; k++) S->gate[k] = (int)(S->topo[*topo].cfg >> k & 1u);
    if (S->gate_fn(t, x, S->nsw, S->gate, S->gate_ctx))
      return nl_fail(&S->c, -1, errmsg, CUP_ERR_CALLBACK, "t = %.17g: the controller callback failed", t);
    uint64_t cfg = 0;
    for (int k = 0; k < S->nsw; k++)
      if (S->gate[k]) cfg |= (uint64_t)1 << k;
    return topo_of(nl, cfg, topo, errmsg);
  }
  int memo = S->memo_ok && S->memo_topo == *topo && S->memo_t == t;
  int read = 0;                                    /* the control class the rule was last applied with */
  S->memo_ok = 0;
  if (memo) {                                      /* the loop's first pass and, the class held, its last */
    const nl_topo *tp = &S->topo[*topo], *to = &S->topo[tp->succ];
    if (tp->ctl_class && to->cfg == S->memo_cfg && to->ctl_class == tp->ctl_class && S->memo_cfg != tp->cfg) {
      *topo = tp->succ;
      return CUP_OK;
    }
  }
  for (int pass = 0; pass <= S->nsw + 1; pass++) {
    /* the configuration the rule gave reads the same controls: the rule,
     * applied to its own result with the same values, gives it again */
    if (read && S->topo[*topo].ctl_class == read) return CUP_OK;
    read = S->topo[*topo].ctl_class;
    const nl_topo *tp = &S->topo[*topo];
    uint64_t next = S->memo_cfg;                   /* the search's at t: the same controls (they read no state) */
    if (pass == 0 && memo) {
    } else if (held(S, tp, t)) {                   /* the controls the searches read last, the same sums */
      next = tp->cfg == S->cvm_from || tp->cfg == S->cvm_to ? S->cvm_to : rule(S, tp->cfg, S->cvm);
    } else {
      if (controls(S, tp, t, x, zeta, cv))
        return nl_fail(&S->c, -1, errmsg, CUP_ERR_CALLBACK, "the input u(t) failed at t = %g", t);
      next = rule(S, tp->cfg, cv);
    }
    if (next == tp->cfg) return CUP_OK;
    int from = *topo, succ = tp->succ;             /* a converter moves between the same few, in turn */
    if (S->topo[succ].cfg == next) { *topo = succ; continue; }
    int st = topo_of(nl, next, topo, errmsg);
    if (st) return st;
    S->topo[from].succ = *topo;
  }
  return nl_fail(&S->c, -1, errmsg, CUP_ERR_UNSUPPORTED, "the switches do not settle at t = %g: each "
                 "configuration turns another's control past its threshold (a loop of switches with no "
                 "hysteresis)", t);
}


/* 1 if, from configuration tp, a switch of one kind (by_state: those the
 * circuit gates, else those the sources alone gate) changes at s, state x. */
static int changes(nl_switched *S, const nl_topo *tp, double s, const double *x, int by_state, double *cv) {
  /* controls of t alone (a class) from terms constant on pieces: one value
   * where the pieces they were read on overlap, for every configuration
   * of the class */
  int cls = !x && !by_state && tp->steps && tp->memo ? tp->ctl_class : 0;
  if (cls && cls == S->cvm_class && s >= S->cvm_lo && s < S->cvm_hi) {
    /* the rule's answer from them, known for the configuration it was
     * applied to and for the one it gave (applied to its own result, the
     * rule gives it again) */
    if (tp->cfg == S->cvm_from || tp->cfg == S->cvm_to) {
      S->last_cfg = S->cvm_to;
      return S->last_cfg != tp->cfg;
    }
    for (int k = 0; k < S->nsw; k++) cv[k] = S->cvm[k];
  } else {
    S->cvm_class = 0;
    if (controls(S, tp, s, x, NULL, cv)) return -1;
    if (cls) {
      for (int k = 0; k < S->nsw; k++) S->cvm[k] = cv[k];
      S->cvm_class = cls;
      S->cvm_lo = S->read_lo;
      S->cvm_hi = S->read_hi;
    }
  }
  for (int k = 0; k < S->nsw; k++)
    if ((int)(tp->by_state >> k & 1u) != by_state) cv[k] = S->c.elem[S->sw[k]].vt;   /* at VT: as before */
  S->last_cfg = rule(S, tp->cfg, cv);
  if (cls) {
    S->cvm_from = tp->cfg;
    S->cvm_to = S->last_cfg;
  }
  return S->last_cfg != tp->cfg;
}

/* next_switch from a time in the pieces the controls of configuration
 * topo's class were read on last (cvm), the rule giving topo there: the
 * pieces one after another, each read at its start, up to the first whose
 * rule moves topo, the switching time its start. What the search below
 * finds (its check just before a piece's end reads the piece the controls
 * were read on; at the end, they are read afresh), by the same reads. */
static int next_piece(nl_switched *S, int topo, double tmax, double *tnext) {
  const nl_topo *tp = &S->topo[topo];
  uint64_t cfg = tp->cfg;
  for (double b = S->cvm_hi; b <= tmax; b = S->cvm_hi) {
    int key = read_piece(S, tp, b);                /* (controls' with x and zeta NULL, of built-in terms) */
    S->cvm_from = cfg;
    if (key >= 0 && (S->tab_from[key] == cfg || S->tab_to[key] == cfg)) {
      S->cvm_to = S->tab_to[key];                  /* (a steady converter's: each period the same) */
    } else {
      S->cvm_to = rule(S, cfg, S->cvm);
      if (key >= 0) S->tab_from[key] = cfg, S->tab_to[key] = S->cvm_to;
    }
    S->last_cfg = S->cvm_to;
    if (S->cvm_to != cfg) {
      *tnext = b;
      S->memo_ok = 1;                              /* (a class's controls read no state) */
      S->memo_topo = topo;
      S->memo_t = b;
      S->memo_cfg = S->cvm_to;
      return CUP_OK;
    }
  }
  return CUP_OK;
}

/* The first time in (t, tmax] at which a source-gated switch of
 * configuration topo changes (tmax if none): the input's pieces checked at
 * their ends when every source is DC, PULSE or PWL (linear pieces), else
 * sampled 16 times each; the crossing bisected to the last bit; a jump edge
 * switches at its time. */
static int next_switch(cup_netlist *nl, int topo, double t, double tmax, double *tnext) {
  nl_switched *S = nl->sw;
  const nl_topo *tp = &S->topo[topo];
  double cv[64], a = t;
  uint64_t cfg = tp->cfg;
  *tnext = tmax;
  if (S->gate_fn) {                                /* the controller's next instant (k ts, not accumulated) */
    long k = instant(S, t);
    double next = (double)(k >= 0 ? k + 1 : (long)floor(t / S->gate_ts) + 1) * S->gate_ts;
    if (next < tmax) *tnext = next;
    return CUP_OK;
  }
  /* controls of t alone read from terms constant on pieces (changes' class):
   * they hold to the end of the pieces the last check read them on, a
   * corner of one of those terms, which the input's next break cannot pass
   * (the other terms' breaks, across which the controls hold, are passed
   * over; a switched run's window asks the input's next break itself) */
  int cls = S->linear && tp->steps && tp->memo ? tp->ctl_class : 0;
  if (cls && held(S, tp, t) && S->cvm_to == cfg)    /* (the rule, applied to its own result, gives it again) */
    return next_piece(S, topo, tmax, tnext);
  while (a < tmax) {
    const cup_input *in = tp->sub->u;
    double b = cls && cls == S->cvm_class && a >= S->cvm_lo && a < S->cvm_hi ? S->cvm_hi
               : !in ? tmax : tp->memo ? input_next_break_memo(in, S->bmemo, S->nmemo, a) : cup_input_next_break(in, a);
    if (!(b <= tmax)) b = tmax;
    double lo = a, hi = -1;
    /* linear pieces: the rule is monotone along one, so its end decides (just
     * before b, clear of the input's rounding of its own breakpoints, then b
     * itself: a jump edge switches there; bisection finds the last bit) */
    int samples = S->linear ? 2 : 16;
    for (int j = 1; j <= samples && hi < 0; j++) {
      double s = j == samples ? b : S->linear ? b - (b - a) * 1e-9 : a + (b - a) * j / 16;
      if (!(s > lo)) continue;
      int ch = changes(S, tp, s, NULL, 0, cv);
      if (ch < 0) return CUP_ERR_CALLBACK;
      if (ch) hi = s, cfg = S->last_cfg; else lo = s;
    }
    if (hi >= 0) {
      /* a jump edge rounds apart from its breakpoint by an ulp or a few
       * (the source's corner delay + P j + knot against the breakpoint's
       * own sum): at the piece's end b, or just below it; or just after
       * the piece's start, the breakpoint below the corner where the value
       * jumps (the crossing then lies inside the piece, as a ramp's does).
       * One check an ulp on that side, then bisection for the rest: the
       * same crossing, the rule being monotone along the piece. */
      int at_end = hi == b;
      /* the controls' terms constant on [a, b) (steps) and no change at lo
       * inside it: none at any time below b, the crossing is b itself (what
       * the check an ulp below and the bisection would find) */
      int found = tp->steps && at_end && lo > a;
      for (int u = 0; u < 4 && !found; u++) {
        double p = at_end ? nextafter(hi, lo) : nextafter(lo, hi);
        if (!(p > lo && p < hi)) break;
        int ch = changes(S, tp, p, NULL, 0, cv);
        if (ch < 0) return CUP_ERR_CALLBACK;
        if (ch) hi = p, cfg = S->last_cfg; else lo = p;
        if (at_end != ch) break;                   /* the other side of the crossing: found */
      }
      for (int it = 0; !found && it < 200 && hi > lo && nextafter(lo, hi) < hi; it++) {
        double mid = lo + (hi - lo) / 2;
        int ch = changes(S, tp, mid, NULL, 0, cv);
        if (ch < 0) return CUP_ERR_CALLBACK;
        if (ch) hi = mid, cfg = S->last_cfg; else lo = mid;
      }
      *tnext = hi;
      S->memo_ok = !tp->state_gated;               /* (a state-gated switch's control is settle's to read) */
      S->memo_topo = topo;
      S->memo_t = hi;
      S->memo_cfg = cfg;
      return CUP_OK;
    }
    a = b;
  }
  return CUP_OK;
}

/* ---- the hook the integrator calls (integrator.h, cup_switching) ------------------- */

static int op_settle(void *ctx, int *topo, double t, const double *x, const double *zeta, char *errmsg) {
  cup_netlist *nl = ctx;
  int st = settle(nl, topo, t, x, zeta, errmsg);
  if (!st) nl->sw->cur = *topo;
  return st;
}

static int op_next(void *ctx, int topo, double t, double tmax, double *tnext) {
  return next_switch(ctx, topo, t, tmax, tnext);
}

static const cup_lcs *op_lcs(void *ctx, int topo) {
  cup_netlist *nl = ctx;
  return nl->sw->topo[topo].sub->L;
}

static void op_jump(void *ctx, int topo, double *x) {
  cup_netlist *nl = ctx;
  nl_switched *S = nl->sw;
  const double *Pi = S->topo[topo].Pi;
  int n = nl->n;
  S->cur = topo;
  if (!Pi) return;
  double *y = S->zf + S->c.nelem + 1;              /* n entries past the multipliers' room */
  for (int i = 0; i < n; i++) {
    double s = 0;
    for (int j = 0; j < n; j++) s += Pi[i + (size_t)j * n] * x[j];
    y[i] = s;
  }
  la_copy(x, y, n);
}

static int op_crossed(void *ctx, int topo, double t, const double *x) {
  cup_netlist *nl = ctx;
  double cv[64];
  if (nl->sw->gate_fn) return 0;
  return changes(nl->sw, &nl->sw->topo[topo], t, x, 1, cv);
}

static int op_state_gated(void *ctx, int topo) {
  cup_netlist *nl = ctx;
  return !nl->sw->gate_fn && nl->sw->topo[topo].state_gated;
}

int cup_netlist_switching(cup_netlist *nl, cup_switching *ops) {
  if (!nl || !nl->sw || !ops) return 0;
  *ops = (cup_switching){.ctx = nl, .settle = op_settle, .next = op_next, .lcs = op_lcs, .jump = op_jump,
                         .state_gated = op_state_gated, .crossed = op_crossed};
  return 1;
}

int cup_netlist_switch_count(const cup_netlist *nl) { return nl && nl->sw ? nl->sw->nsw : 0; }

int cup_netlist_set_controller(cup_netlist *nl, double ts, cup_gate_fn fn, void *ctx, char *errmsg) {
  if (!nl) return fail_fmt(errmsg, CUP_ERR_ARG, "controller: NULL netlist");
  if (!nl->sw) return fail_fmt(errmsg, CUP_ERR_ARG, "controller: %s has no switch to gate", nl->file);
  if (fn && !(ts > 0 && isfinite(ts)))
    return fail_fmt(errmsg, CUP_ERR_ARG, "controller: the sampling period %g must be finite and > 0", ts);
  nl_switched *S = nl->sw;
  if (fn && S->t0 != 0) return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED, "controller: %s has a time origin", nl->file);
  if (fn && !S->gate && !(S->gate = calloc((size_t)S->nsw + 1, sizeof(int))))
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "out of memory");
  S->gate_fn = fn;
  S->gate_ctx = ctx;
  S->gate_ts = ts;
  return CUP_OK;
}

long cup_netlist_configurations_formed(const cup_netlist *nl) { return nl && nl->sw ? nl->sw->formed : 0; }

/* ---- the netlist with switches ------------------------------------------------------ */

static cup_netlist *sw_current(cup_netlist *nl) { return nl->sw->topo[nl->sw->cur].sub; }

static int sw_probe(cup_netlist *nl, int k, char *errmsg) {
  nl_switched *S = nl->sw;
  for (int j = 1; j < S->ntopo; j++) {
    int q = cup_netlist_probe(S->topo[j].sub, nl->sig_name[k], errmsg);
    if (q < 0) return q;
    if (q != k) return nl_fail(&S->c, -1, errmsg, CUP_ERR_ARG, "signal order differs");
  }
  return k;
}

static void sw_free(nl_switched **Sp) {
  nl_switched *S = *Sp;
  if (!S) return;
  for (int k = 0; k < S->ntopo; k++) {
    if (k > 0) cup_netlist_free(&S->topo[k].sub);  /* topo[0]'s is the netlist itself */
    free(S->topo[k].Pi);
    ctl_free(&S->topo[k]);
  }
  nl_circuit_free(&S->c);
  free(S->sw); free(S->ut); free(S->zf); free(S->gate); free(S->thr); free(S->cvm); free(S->bmemo); free(S->vmemo);
  free(S->tab);
  free(S);
  *Sp = NULL;
}

/* A switch's control must be a voltage or a current of the circuit. */
static int check_controls(const nl_circuit *c, int e, char *errmsg) {
  const nl_elem *el = &c->elem[e];
  if (el->kind == NL_W) return CUP_OK;             /* the reader found its element */
  for (int k = 0; k < 2; k++) {
    int v = k ? el->cb : el->ca, used = v == 0;
    for (int f = 0; f < c->nelem && !used; f++) used = f != e && (c->elem[f].a == v || c->elem[f].b == v);
    if (!used)
      return nl_fail(c, e, errmsg, CUP_ERR_PARSE, "no control path: control node '%s' is not connected to "
                     "any element (it has no voltage to sense)", c->node[v]);
  }
  return CUP_OK;
}

/* Every configuration's sources from t0 on, and those formed later (a
 * controller's instants k ts stay on the sources' clock: refused). */
static int sw_origin(cup_netlist *nl, double t0, char *errmsg) {
  nl_switched *S = nl->sw;
  if (S->gate_fn && t0 != 0)                       /* its instants k ts would move with the clock */
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED, "%s: a controller with a time origin t0 = %g", nl->file, t0);
  for (int k = 0; k < S->ntopo; k++) {
    int st = nl_input_origin(S->topo[k].sub, t0, errmsg);
    if (st) {                                      /* the inputs now differ: no control class holds */
      for (int j = 0; j < S->ntopo; j++) S->topo[j].ctl_class = 0;
      memo_reset(S);
      return st;
    }
  }
  S->t0 = t0;
  memo_reset(S);
  return CUP_OK;
}

static const nl_sw_hooks hooks = {sw_free, sw_current, sw_probe, sw_origin};

int nl_switched_formulate(cup_netlist **out, nl_circuit *c, char *errmsg) {
  nl_switched *S = calloc(1, sizeof *S);
  if (!S) return nl_switch_nomem(c, errmsg);
  S->c = *c;
  memset(c, 0, sizeof *c);
  c = &S->c;
  int st = CUP_OK;
  if (c->nswitch > 63) st = nl_fail(c, -1, errmsg, CUP_ERR_UNSUPPORTED, "more than 63 switches");
  S->sw = malloc(sizeof(int) * ((size_t)c->nswitch + 1));
  if (!st && !S->sw) st = nl_switch_nomem(c, errmsg);
  for (int e = 0; !st && e < c->nelem; e++)
    if (c->elem[e].kind == NL_S || c->elem[e].kind == NL_W) {
      st = check_controls(c, e, errmsg);
      S->sw[S->nsw++] = e;
    }
  S->linear = 1;
  for (int e = 0; e < c->nelem; e++)
    if ((c->elem[e].kind == NL_V || c->elem[e].kind == NL_I) && c->elem[e].src.fn == NL_FN_SIN) S->linear = 0;
  uint64_t cfg = 0;                                /* ON/OFF as written, else off, until the controls say */
  for (int k = 0; !st && k < S->nsw; k++)
    if (c->elem[S->sw[k]].init == 1) cfg |= (uint64_t)1 << k;
  cup_netlist *nl = NULL;
  if (!st) st = form(S, &nl, cfg, &S->topo[0], errmsg);
  if (st) { sw_free(&S); return st; }
  S->topo[0].sub = nl;
  S->ntopo = 1;
  control_class(S, &S->topo[0]);
  nl->sw = S;
  nl->hooks = &hooks;
  S->ut = calloc((size_t)nl->p + 1, sizeof(double));
  S->zf = calloc((size_t)nl->m + (size_t)c->nelem + (size_t)nl->n + 2, sizeof(double));
  S->thr = malloc(sizeof(double) * (2 * (size_t)S->nsw + 1));
  S->cvm = malloc(sizeof(double) * ((size_t)S->nsw + 1));
  S->tab = malloc(sizeof(double) * ((size_t)S->nsw << NL_TAB_TERMS));
  S->nmemo = nl->u && !nl->u->fn ? nl->u->nterms : 0;
  S->bmemo = S->nmemo ? malloc(sizeof *S->bmemo * (size_t)S->nmemo) : NULL;
  S->vmemo = S->nmemo ? malloc(sizeof *S->vmemo * 4 * (size_t)S->nmemo) : NULL;
  if (!S->ut || !S->zf || !S->thr || !S->cvm || !S->tab || (S->nmemo && (!S->bmemo || !S->vmemo)))
    st = nl_switch_nomem(c, errmsg);
  for (int k = 0; !st && k < S->nsw; k++) {
    const nl_elem *el = &c->elem[S->sw[k]];
    double h = fabs(el->vh);
    S->thr[2 * k] = el->vt + h;
    S->thr[2 * k + 1] = el->vt - h;
  }
  if (!st) memo_reset(S);
  int topo = 0;                                    /* the state at t = 0 from the controls at t = 0 */
  if (!st) st = settle(nl, &topo, 0, nl->x0, NULL, errmsg);
  if (!st && topo != 0) {                          /* that configuration is the netlist's */
    nl_topo t0 = S->topo[0];
    S->topo[0] = S->topo[topo];
    S->topo[topo] = t0;
    nl->sw = NULL;
    nl->hooks = NULL;
    nl = S->topo[0].sub;
    nl->sw = S;
    nl->hooks = &hooks;
    memo_reset(S);                                 /* (for the new topo[0]'s input) */
  }
  /* The lines' probes are the switched netlist's, whichever configuration it
   * is (a derived one has none): cup_netlist_probe_default reads them there,
   * else a switched netlist recorded every signal whatever its .probe said */
  if (!st && nl_copy_probes(nl, c)) st = nl_switch_nomem(c, errmsg);
  if (st) { cup_netlist_free(&nl); return st; }    /* frees S and every configuration */
  *out = nl;
  return CUP_OK;
}

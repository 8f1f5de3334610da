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
#include "netlist_switch_impl.h"

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
  d->names_lent = c->nelem;                        /* (sw_free frees S->c after every configuration) */
  d->no_warning = S->created;
  d->nprobe = 0; d->probe = NULL; d->probe_all = 0;
  /* (not zeroed: the circuit's elements are copied over, append clears each one after) */
  d->elem = malloc(sizeof(nl_elem) * ((size_t)c->nelem + (size_t)c->nnodes + 1));
  int small[256], *uf = scratch_take(small, sizeof small, sizeof(int) * (size_t)c->nnodes, 0);
  if (!d->elem || !uf) { scratch_free(uf, small); return CUP_ERR_NOMEM; }
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
  scratch_free(uf, small);
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
  free(tp->ctl);                                   /* (cx, cp, ci and uterm in its block: form) */
  tp->ctl = tp->cx = NULL;
  tp->cp = tp->ci = tp->uterm = NULL;
}

/* The controls' rows by their nonzeros, and the input terms they read (into form's block). */
static int ctl_sparse(const nl_switched *S, nl_topo *tp) {
  const cup_netlist *sub = tp->sub;
  int n = sub->n, p = sub->p, nv = n + p + sub->m, k = 0;
  const cup_input *u = sub->u;
  int nterms = p && u && !u->fn ? u->nterms : 0;
  unsigned char rsmall[256], *reads = scratch_take(rsmall, sizeof rsmall, (size_t)p + 1, 1);
  if (!reads) return CUP_ERR_NOMEM;
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
  scratch_free(reads, rsmall);
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
  /* the sources as written are the circuit's in every configuration: the first one's copied */
  const cup_netlist *first = S->ntopo ? S->topo[0].sub : NULL;
  st = nl_formulate(&sub, &d, first ? (first->u_written ? first->u_written : first->u) : NULL, errmsg);
  if (!st) { sub->nelem_user = c->nelem; st = nl_switch_reduce(sub, c, &d, &Pi, errmsg); }
  if (!st && S->t0 != 0) st = nl_input_origin(sub, S->t0, errmsg);   /* formed after the origin was set */
  tp->cfg = cfg;
  tp->Pi = Pi;
  int nv = sub ? sub->n + sub->p + sub->m : 0;
  /* the controls (zeroed) and their nonzeros (ctl_sparse: cx, cp, ci, the
   * input terms they read) in one block: five allocations a configuration were */
  size_t nz = (size_t)S->nsw * nv + 1;
  int nterms = sub && sub->p && sub->u && !sub->u->fn ? sub->u->nterms : 0;
  tp->ctl = !st ? malloc(sizeof(double) * 2 * nz + sizeof(int) * ((size_t)S->nsw + 1 + nz + (size_t)nterms + 1)) : NULL;
  if (!st && !tp->ctl) st = nl_switch_nomem(c, errmsg);
  if (!st) {
    memset(tp->ctl, 0, sizeof(double) * nz);
    tp->cx = tp->ctl + nz;
    tp->cp = (int *)(tp->cx + nz);
    tp->ci = tp->cp + S->nsw + 1;
    tp->uterm = tp->ci + nz;
  }
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
  S->vgen++;                                       /* (every memo moved: read_piece's walk reads them all) */
  S->cvm_class = 0;
  S->tab_class = 0;
  for (int k = 0; k < S->ntopo; k++) S->topo[k].memo = reads_memo(S, &S->topo[k]), S->topo[k].quiet = 0;
  S->quiet_ok = 0;
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
    int q = nl_probe_next(tp->sub, nl->sig_name[k], k < NL_SIG_AT ? &S->sig_at[k] : NULL, errmsg);
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

/* The configuration in force from t on, from the one before: the rule
 * applied until it holds (a switch may move another's control). */
static int settle(cup_netlist *nl, int *topo, double t, const double *x, const double *zeta, char *errmsg) {
  nl_switched *S = nl->sw;
  double cv[64];
  if (S->gate_fn) {                                /* a controller: its gates at its instants, held between */
    if (nl_sw_instant(S, t) < 0) return CUP_OK;
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
    uint64_t next;
    if (pass == 0 && memo)                         /* the search's at t: the same controls (they read no state) */
      next = S->memo_cfg;
    else if (nl_sw_held(S, tp, t))                 /* the controls the searches read last, the same sums */
      next = tp->cfg == S->cvm_from || tp->cfg == S->cvm_to ? S->cvm_to : nl_sw_rule(S, tp->cfg, S->cvr);
    else if (nl_sw_controls(S, tp, t, x, zeta, cv))
      return nl_fail(&S->c, -1, errmsg, CUP_ERR_CALLBACK, "the input u(t) failed at t = %g", t);
    else
      next = nl_sw_rule(S, tp->cfg, cv);
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


/* ---- the hook the integrator calls (integrator.h, cup_switching) ------------------- */

static int op_settle(void *ctx, int *topo, double t, const double *x, const double *zeta, char *errmsg) {
  cup_netlist *nl = ctx;
  int st = settle(nl, topo, t, x, zeta, errmsg);
  if (!st) nl->sw->cur = *topo;
  return st;
}

static int op_next(void *ctx, int topo, double t, double tmax, double *tnext) {
  return nl_sw_next(ctx, topo, t, tmax, tnext);
}

static int op_quiet(void *ctx, int topo, const cup_input *u, double t, double tnext) {
  return nl_sw_quiet(ctx, topo, u, t, tnext);
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
  return nl_sw_changes(nl->sw, &nl->sw->topo[topo], t, x, 1, cv);
}

static int op_state_gated(void *ctx, int topo) {
  cup_netlist *nl = ctx;
  return !nl->sw->gate_fn && nl->sw->topo[topo].state_gated;
}

static int op_moves(void *ctx, int topo) {
  cup_netlist *nl = ctx;
  return nl->sw->topo[topo].Pi != NULL;            /* (op_jump's test) */
}

int cup_netlist_switching(cup_netlist *nl, cup_switching *ops) {
  if (!nl || !nl->sw || !ops) return 0;
  *ops = (cup_switching){.ctx = nl, .settle = op_settle, .next = op_next, .lcs = op_lcs, .jump = op_jump,
                         .state_gated = op_state_gated, .crossed = op_crossed, .moves = op_moves,
                         .quiet = op_quiet};
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

static int sw_probe(cup_netlist *nl, int k, const nl_probe_at *at, char *errmsg) {
  nl_switched *S = nl->sw;
  if (k < NL_SIG_AT) S->sig_at[k] = *at;           /* (each configuration's: topo_of's) */
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
  S->cvr = S->cvm;
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
  S->created = 1;                                  /* (topo[0] is the netlist's for good) */
  *out = nl;
  return CUP_OK;
}

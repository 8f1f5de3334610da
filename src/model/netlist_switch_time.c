/* netlist_switch_time — the switching times of switches the sources alone
 * gate (docs/netlist.md, "Switches"; docs/design.md, "Switched circuits"):
 * each switch's control in a configuration, read from the input terms it
 * reads (their pieces kept, one after another), the search for the first
 * time the rule moves a configuration, and for a configuration whose
 * controls are a class's of constants and jump PULSEs, that search piece
 * after piece from the last switching time. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdint.h>
#include <string.h>
#include "catchup.h"
#include "netlist_switch_impl.h"

/* Term k's memo (vmemo) on the piece that holds t, taken afresh when t is past it. */
static inline const double *term_at(nl_switched *S, const input_term *w, int k, double t) {
  double *c = S->vmemo + 4 * (size_t)k;
  if (!(t >= c[0] && t < c[1])) {
    S->vgen++;                                     /* (read_piece's walk: a memo moved) */
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
 * that hold at b (read_terms, then controls_u: a search's), at S->cvr,
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
    S->cvr = S->cvm;
    S->cvm_lo = S->read_lo;
    S->cvm_hi = S->read_hi;
    return -1;
  }
  if (S->tab_class != tp->ctl_class) {
    S->tab_class = tp->ctl_class;
    S->tab_ok = 0;
    S->walk_ok = 0;                                /* (and after memo_reset, which empties tab_class) */
  }
  double lo = -INFINITY, hi = INFINITY;
  unsigned key = 0;
  if (!S->walk_ok) {                               /* the class's terms, where the loop below finds them */
    for (int q = 0; q < tp->nuterm; q++) {
      int k = tp->uterm[q];
      S->walk_c[q] = S->vmemo + 4 * (size_t)k;
      S->walk_v[q] = u->terms[k].value;
      S->walk_k[q] = k;
    }
    S->walk_ok = 1;
    S->walk_inc = 0;
  }
  if (S->walk_inc && S->walk_gen == S->vgen && b >= S->walk_lo) {
    /* no memo moved since the last walk, whose pieces all start at or
     * before b: a term's piece holds b unless it ends there or before, and
     * one that moves on starts at b, the latest start; the others' bits
     * and starts are the last walk's (the same key and lo as the loop
     * below finds, hi the same min in the same order) */
    key = S->walk_key;
    lo = S->walk_lo;
    for (int q = 0; q < tp->nuterm; q++) {
      const double *c = S->walk_c[q];
      if (!(b < c[1])) {
        c = term_at(S, &u->terms[S->walk_k[q]], S->walk_k[q], b);
        key = (key & ~(1u << q)) | (unsigned)!same_bits(c[2], S->walk_v[q]) << q;
        lo = b;
      }
      if (c[1] < hi) hi = c[1];
    }
  } else {
    for (int q = 0; q < tp->nuterm; q++) {
      const double *c = S->walk_c[q];
      if (!(b >= c[0] && b < c[1])) c = term_at(S, &u->terms[S->walk_k[q]], S->walk_k[q], b);   /* (term_at's test, once) */
      key |= (unsigned)!same_bits(c[2], S->walk_v[q]) << q;
      if (c[0] > lo) lo = c[0];
      if (c[1] < hi) hi = c[1];
    }
  }
  S->walk_inc = 1;
  S->walk_key = key;
  S->walk_lo = lo;
  S->walk_gen = S->vgen;                           /* (read_terms below moves none: every piece holds b) */
  double *row = S->tab + (size_t)key * (size_t)S->nsw;
  if (!(S->tab_ok >> key & 1)) {
    read_terms(S, tp, b);                          /* (the pieces at b: held, as just read) */
    controls_u(S, tp, row);
    S->tab_ok |= (uint64_t)1 << key;
    S->tab_from[key] = S->tab_to[key] = UINT64_MAX;   /* (no configuration: bit 63 is no switch) */
  }
  S->cvr = row;                                    /* (its row itself: rewritten only for another class) */
  S->cvm_lo = lo;
  S->cvm_hi = hi;
  return (int)key;
}

/* Each switch's control at t in configuration tp (x, zeta may be NULL: 0),
 * over the controls' nonzeros and the input terms they read (ctl_sparse):
 * the dense rows' sums less terms that are exactly 0, bit for bit. */
int nl_sw_controls(nl_switched *S, const nl_topo *tp, double t, const double *x, const double *zeta, double *cv) {
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

/* 1 if, from configuration tp, a switch of one kind (by_state: those the
 * circuit gates, else those the sources alone gate) changes at s, state x. */
int nl_sw_changes(nl_switched *S, const nl_topo *tp, double s, const double *x, int by_state, double *cv) {
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
    for (int k = 0; k < S->nsw; k++) cv[k] = S->cvr[k];
  } else {
    S->cvm_class = 0;
    if (nl_sw_controls(S, tp, s, x, NULL, cv)) return -1;
    if (cls) {
      for (int k = 0; k < S->nsw; k++) S->cvm[k] = cv[k];
      S->cvr = S->cvm;
      S->cvm_class = cls;
      S->cvm_lo = S->read_lo;
      S->cvm_hi = S->read_hi;
    }
  }
  for (int k = 0; k < S->nsw; k++)
    if ((int)(tp->by_state >> k & 1u) != by_state) cv[k] = S->c.elem[S->sw[k]].vt;   /* at VT: as before */
  S->last_cfg = nl_sw_rule(S, tp->cfg, cv);
  if (cls) {
    S->cvm_from = tp->cfg;
    S->cvm_to = S->last_cfg;
  }
  return S->last_cfg != tp->cfg;
}

/* nl_sw_next from a time in the pieces the controls of configuration
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
      S->cvm_to = nl_sw_rule(S, cfg, S->cvr);
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

/* 1 if every term of configuration tp's input is a constant or a jump
 * PULSE its controls read: then the input breaks only where those terms'
 * pieces end (next_piece's walk). Not a PULSE with value2 == value (its
 * breaks are pulse_break's, not spice_jump_break's), nor one whose top
 * reaches within 1e-6 of its period (the top's end of the period before
 * may round past the next start: spice_jump_break looks there, the
 * pieces do not). */
static int quiet_terms(const nl_topo *tp) {
  const cup_input *u = tp->sub->u;
  if (!tp->steps || !u || u->fn) return 0;
  for (int k = 0, q = 0; k < u->nterms; k++) {
    const input_term *w = &u->terms[k];
    int read = q < tp->nuterm && tp->uterm[q] == k;
    q += read;
    if (w->kind == CUP_WAVE_CONSTANT) continue;
    if (!read || !input_jump_pulse(w) || w->value2 == w->value) return 0;
    if (w->period > 0 && !(w->rise + w->width < w->period * (1 - 1e-6))) return 0;
  }
  return 1;
}

/* nl_sw_next's search piece after piece from t, where no class's walk
 * (next_piece) holds (apart: the common window's call saves no registers
 * for it). */
static __attribute__((noinline)) int search(nl_switched *S, int topo, int cls, double t, double tmax, double *tnext) {
  const nl_topo *tp = &S->topo[topo];
  double cv[64], a = t;
  uint64_t cfg = tp->cfg;
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
      int ch = nl_sw_changes(S, tp, s, NULL, 0, cv);
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
        int ch = nl_sw_changes(S, tp, p, NULL, 0, cv);
        if (ch < 0) return CUP_ERR_CALLBACK;
        if (ch) hi = p, cfg = S->last_cfg; else lo = p;
        if (at_end != ch) break;                   /* the other side of the crossing: found */
      }
      for (int it = 0; !found && it < 200 && hi > lo && nextafter(lo, hi) < hi; it++) {
        double mid = lo + (hi - lo) / 2;
        int ch = nl_sw_changes(S, tp, mid, NULL, 0, cv);
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

/* The first time in (t, tmax] at which a source-gated switch of
 * configuration topo changes (tmax if none): the input's pieces checked at
 * their ends when every source is DC, PULSE or PWL (linear pieces), else
 * sampled 16 times each; the crossing bisected to the last bit; a jump edge
 * switches at its time. */
int nl_sw_next(cup_netlist *nl, int topo, double t, double tmax, double *tnext) {
  nl_switched *S = nl->sw;
  const nl_topo *tp = &S->topo[topo];
  *tnext = tmax;
  S->quiet_ok = 0;
  if (S->gate_fn) {                                /* the controller's next instant (k ts, not accumulated) */
    long k = nl_sw_instant(S, t);
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
  if (cls && nl_sw_held(S, tp, t) && S->cvm_to == tp->cfg) {  /* (the rule, applied to its own result, gives it again) */
    /* the controls' terms hold on [t, hi): a switching at hi, or tmax
     * below it, has none of their breaks before it, nor any of the
     * input's when its other terms are constants (nl_sw_quiet) */
    double hi = S->cvm_hi;
    int st = next_piece(S, topo, tmax, tnext);
    nl_topo *tq = &S->topo[topo];
    if (!tq->quiet) tq->quiet = 1 + quiet_terms(tq);
    if (*tnext <= hi && tq->quiet == 2) {
      S->quiet_ok = 1;
      S->quiet_topo = topo;
      S->quiet_t = t;
      S->quiet_to = *tnext;
    }
    return st;
  }
  return search(S, topo, cls, t, tmax, tnext);
}

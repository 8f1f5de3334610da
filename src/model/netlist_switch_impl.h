/* netlist_switch_impl.h — a netlist with switches' layout (netlist_switch.c:
 * its configurations, formed on first use, and the hooks the integrator
 * calls; netlist_switch_time.c: the switching times of source-gated
 * switches, the controls read piece after piece). Private to src/model. */
#ifndef CATCHUP_NETLIST_SWITCH_IMPL_H
#define CATCHUP_NETLIST_SWITCH_IMPL_H
#include <math.h>
#include <stdint.h>
#include "netlist_impl.h"
#include "input_impl.h"

#define NL_TOPO_MAX 64     /* configurations kept (a converter has a handful) */
#define NL_TAB_TERMS 6     /* read_piece's table: a class reading up to 6 terms (a full bridge's 4 gates) */
#define NL_SIG_AT 64       /* signals whose element or nodes a run finds by name once (topo_of) */

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
  uint64_t by_state;       /* bit k: switch k's does (gated_by_state, for nl_sw_changes) */
  int ctl_class;           /* > 0: configurations of one class have the same controls, of t alone
                              (same_controls): settle's rule holds in the one it moves to; 0: none */
  int succ;                /* the configuration settle last moved to from it (a hint: its cfg is checked) */
  int quiet;               /* 2: every term of its input is a constant or a jump PULSE its controls read
                              (nl_sw_quiet), 1: not, 0: not known yet (memo_reset) */
} nl_topo;

struct nl_switched {
  nl_circuit c;            /* the circuit as read (owned) */
  int nsw;
  int *sw;                 /* the switches' elements */
  int ntopo;
  nl_topo topo[NL_TOPO_MAX];
  long formed;             /* configurations formulated */
  int created;             /* the netlist is made: a configuration formed now is not topo[0] (its
                              diode loops' warning, which nobody reads, not computed) */
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
  /* the controls a search read last (nl_sw_changes), where its terms' pieces
   * overlap: the next piece's first check reads them again */
  int cvm_class;           /* their configurations' control class (0: none held) */
  double cvm_lo, cvm_hi, *cvm;
  const double *cvr;       /* them: cvm, or read_piece's row of tab (not copied) */
  uint64_t cvm_from, cvm_to; /* the rule's last answer from them: cvm_from gave cvm_to */
  double read_lo, read_hi; /* the last read_terms': where its terms' memos all hold */
  /* a class's controls by which of its terms are off their value (read_piece) */
  int tab_class;           /* the class they are (0: none) */
  double *tab;             /* 2^NL_TAB_TERMS x nsw */
  uint64_t tab_ok;         /* bit key: its row holds */
  uint64_t tab_from[1 << NL_TAB_TERMS], tab_to[1 << NL_TAB_TERMS];   /* the rule's last answer on it */
  /* the terms tab_class's controls read, in uterm's order (read_piece's
   * loop, once a window: a full bridge's 4 gates) */
  int walk_ok;             /* they are tab_class's (reset with it) */
  double *walk_c[NL_TAB_TERMS];   /* each one's memo (vmemo) */
  double walk_v[NL_TAB_TERMS];    /* ... its value (the key's bit: off it) */
  int walk_k[NL_TAB_TERMS];       /* ... its index in the input */
  /* the last walk's key and its pieces' start (the latest of their
   * starts), while no memo has moved since (vgen, bumped at each move of
   * one): the next walk moves on only the pieces that end at its time */
  uint64_t vgen, walk_gen;
  int walk_inc;            /* walk_key and walk_lo are walk_gen's (0: not yet, or reset with walk_ok) */
  unsigned walk_key;
  double walk_lo;
  int linear;              /* every source is DC, PULSE or PWL: the input is linear between breakpoints */
  double t0;               /* the time origin: each configuration's sources from t0 on (nl_input_origin) */
  /* the switching time the last search found (a configuration with no
   * switch the circuit gates) and the configuration the rule gave there:
   * the settle that follows it, at that time, takes it (once) */
  int memo_ok, memo_topo;
  double memo_t;
  uint64_t memo_cfg, last_cfg;   /* ... and the rule's at the last check (nl_sw_changes) */
  /* the last search's (topo, t -> tnext) when its input, topo[0]'s, has no
   * breakpoint in (t, tnext) (cup_switching's quiet, nl_sw_quiet) */
  int quiet_ok, quiet_topo;
  double quiet_t, quiet_to;
  /* a controller from code (cup_netlist_set_controller): it alone sets the gates, at t = k ts */
  cup_gate_fn gate_fn;
  void *gate_ctx;
  double gate_ts;
  int *gate;               /* nsw */
  /* the recorded signals' elements and nodes, as the netlist's probe found
   * them by name (sw_probe), the same in each configuration (nl_probe_next) */
  nl_probe_at sig_at[NL_SIG_AT];
};

/* t's sampling instant k if t is one (within 1e-9 ts), else -1. */
static inline long nl_sw_instant(const nl_switched *S, double t) {
  double k = floor(t / S->gate_ts + 0.5);
  return fabs(t - k * S->gate_ts) <= 1e-9 * S->gate_ts ? (long)k : -1;
}

/* 1 if the controls a search read last (nl_sw_changes' cvm) are configuration
 * tp's at t: its class's, t in the pieces of their terms they were read on
 * (every configuration of a class reads the same sums of the same terms). */
static inline int nl_sw_held(const nl_switched *S, const nl_topo *tp, double t) {
  return tp->steps && tp->memo && tp->ctl_class && tp->ctl_class == S->cvm_class && t >= S->cvm_lo && t < S->cvm_hi;
}

/* ngspice's rule: on above VT + |VH|, off below VT - |VH| (S->thr), else as before. */
static inline uint64_t nl_sw_rule(const nl_switched *S, uint64_t cfg, const double *cv) {
  for (int k = 0; k < S->nsw; k++) {
    if (cv[k] > S->thr[2 * k]) cfg |= (uint64_t)1 << k;
    else if (cv[k] < S->thr[2 * k + 1]) cfg &= ~((uint64_t)1 << k);
  }
  return cfg;
}

/* Each switch's control at t in configuration tp (netlist_switch_time.c). */
int nl_sw_controls(nl_switched *S, const nl_topo *tp, double t, const double *x, const double *zeta, double *cv);
/* cup_switching's quiet: 1 if u, the netlist's input, has no breakpoint in
 * (t, tnext), nl_sw_next's last answer in topo from t (its walk noted it). */
static inline int nl_sw_quiet(const cup_netlist *nl, int topo, const cup_input *u, double t, double tnext) {
  const nl_switched *S = nl->sw;
  return S->quiet_ok && u == nl->u && topo == S->quiet_topo && t == S->quiet_t && tnext == S->quiet_to;
}
/* 1 if a switch of one kind changes at s from configuration tp, 0 if not, < 0 on error. */
int nl_sw_changes(nl_switched *S, const nl_topo *tp, double s, const double *x, int by_state, double *cv);
/* The first time in (t, tmax] at which a source-gated switch of configuration topo changes. */
int nl_sw_next(cup_netlist *nl, int topo, double t, double tmax, double *tnext);

#endif

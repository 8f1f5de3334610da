/* Internal layout of cup_netlist and the formulation's steps (netlist.c,
 * netlist_graph.c, netlist_signal.c). The formulation (docs/netlist.md):
 *
 * Ports. Capacitors, voltage sources and the diodes whose current the state
 * fixes ("fixed" diodes) are voltage ports; inductors, current sources and
 * the other ("free") diodes are current ports; resistors are the network
 * between them. A diode is fixed when it alone joins two parts of the
 * circuit that capacitors, voltage sources, resistors and the diodes fixed
 * before it leave apart (it sits in a cutset of current ports).
 *
 * The hybrid matrix. Voltage ports form a forest (a loop of them is an index
 * problem); each tree is a supernode whose node potentials are its root's
 * plus port voltages along the tree (tau). With Lap the resistors'
 * Laplacian over the supernodes (ground's removed; it is SPD exactly when no
 * cutset of current ports exists), K = [Z_V, A_I] their coupling to the
 * ports and T_R, T_I the tree paths of resistors and current ports,
 *     (i_V, v_I) = H (v_V, j_I),   X = L^-1 Pi K  (L L^T = Pi Lap Pi^T),
 *     H = [ -T_R G T_R^T + X_V^T X_V    -T_I + X_V^T X_I ]
 *         [  T_I^T - X_I^T X_V          -X_I^T X_I       ],
 * in the element convention (v and i of a port both from its first node to
 * its second). Then P = diag(L, C) and P x' = H's state rows, and a diode's
 * row is w = i (fixed: zeta = -v) or w = -v (free: zeta = i). */
#ifndef CUP_NETLIST_IMPL_H
#define CUP_NETLIST_IMPL_H

#include <cholmod.h>
#include "catchup/netlist.h"
#include "util/block.h"
#include "util/linalg.h"
#include "netlist_desc.h"
#include "signal_map.h"

/* Which LCS variable a port's value is: the state, an input, a zeta, or
 * (NL_VAR_CTL) a controlled source's output, a linear function of the
 * others once the controlled sources are eliminated (netlist_ctl.c). */
enum { NL_VAR_X, NL_VAR_U, NL_VAR_Z, NL_VAR_CTL, NL_VAR_NONE };   /* NONE: a closed switch's 0 V */

typedef struct nl_port {
  int elem;           /* the element */
  int var, index;     /* NL_VAR_* and its index in x, u or zeta */
  int sign;           /* port value = sign * that variable (-1: a fixed diode's -zeta) */
} nl_port;

/* A switch configuration's circuit as formulated (dense, column-major),
 * before its constraint rows are eliminated (netlist_reduce.c); with no
 * constraint row there is nothing to eliminate: the formulation's sparse
 * parts are its LCS as they are, kept instead (the dense ones NULL). */
typedef struct nl_raw {
  double *A, *B, *C, *D, *E, *G, *P;   /* n x n, n x m, m x n, m x m, n x p, m x p, n x n */
  int keep_B;                          /* controlled sources: B as formed, not P^-1 C^T */
  int sparse;                          /* no constraint row: part, pdiag and Pc hold it */
  la_sparse part[6];                   /* A, B, C, D, E, G (CSC, no zero stored) */
  la_sparse Pc;                        /* P with coupled inductors (Pc.p NULL: diagonal, pdiag) */
  double *pdiag;                       /* n */
} nl_raw;

typedef struct nl_switched nl_switched;

/* A signal's element or nodes in a netlist (nl_probe_next, the hooks' probe). */
typedef struct nl_probe_at {
  char kind;               /* 'v' or 'i'; 0: not found yet */
  int x, y;                /* the node (y: the second, or -1) or the element */
} nl_probe_at;

/* What the netlist's own functions ask of netlist_switch.c (a table, so that
 * the formulation does not depend on it: it depends on the formulation). */
typedef struct nl_sw_hooks {
  void (*free)(nl_switched **S);
  cup_netlist *(*current)(cup_netlist *nl);              /* the configuration in force */
  int (*probe)(cup_netlist *nl, int k, const nl_probe_at *at, char *errmsg);   /* signal k (of the element or
                                                         nodes at) added to every configuration */
  int (*origin)(cup_netlist *nl, double t0, char *errmsg);   /* every configuration's sources from t0 */
} nl_sw_hooks;

struct cup_netlist {
  char *warning;      /* a loop of ideal diodes (nl_diode_loops, CUP_ERRMSG_LEN), or NULL: allocated
                         when there is one (each switch configuration's netlist cleared 12 KB) */
  cup_lcs *L;
  cup_input *u;       /* NULL when p = 0; the sources from the time origin t0 on */
  cup_input *u_written;   /* the sources as written, when t0 != 0 (u is then its shift) */
  double t0;          /* the time origin (cup_netlist_set_time_origin): u(t) = the sources at t0 + t */
  double *x0;
  int has_tran;
  double tstep, tstop, tstart, tmax;
  double reltol, abstol, vntol, chgtol;   /* .options, NAN when not given */
  int steady;         /* .options steadystate: asked for, with steady_period (0: the sources') */
  double steady_period;
  int n, m, p, nL, nC;
  /* the circuit, for names and signals */
  char *file;
  char *source;       /* the netlist text as read (before sets), for provenance */
  int nfiles;
  char **files;       /* every file read, each once */
  int nnodes, nelem;
  char **node;        /* (in files' block) */
  nl_elem *elem;      /* copies (names owned; no sources) */
  int *eport;         /* element -> port, -1 for resistors */
  int *evar;          /* element -> index in x (L, C), u (V, I) or zeta (D) */
  char **state_name, **row_name;
  int *row_fixed;     /* per diode row (in row_name's block) */
  int *input_elem;    /* per input: its source element */
  int nprobe, probe_all;
  char **probe_text;  /* the netlist's .probe/.save/.print signals */
  /* ports and the voltage-port forest */
  int nv, ni;         /* voltage ports 0..nv-1, current ports nv..nv+ni-1 */
  nl_port *port;
  int *parent, *pport, *depth, *snode;   /* per node; snode -1: ground's tree */
  int nctl;           /* controlled sources (E, F, G, H), ports of var NL_VAR_CTL */
  int *ctl_elem;      /* per controlled source: its element */
  double *zmap;       /* nctl x (nv + ni), row-major: each one's output as a combination
                         of the other ports' values (its own columns zero) */
  la_sparse Pinv;    /* n x n, the inverse of P on coupled inductors' blocks only (K) */
  int *coupled;       /* per state: 1 if in a coupled block (its P^-1 column is in Pinv) */
  signed char *psign; /* phi(node) = phi(parent) + psign * v(pport) */
  int ns;             /* supernodes other than ground's */
  cholmod_common *cm; /* CHOLMOD's, started with ns > 0 alone (nl_hybrid), else NULL: inline it
                         was 2.7 KB of each switch configuration's netlist, zeroed and started for
                         none of the converters' (ns = 0) */
  cholmod_factor *Lf; /* Lap = L L^T (ns > 0) */
  cholmod_sparse *K;  /* ns x (nv + ni) */
  la_sparse H;       /* (nv + ni) x (nv + ni), CSC */
  /* signals: sparse rows over (x, u, zeta) */
  int nsig, capsig, signnz, capnnz;
  char **sig_name;
  int *sig_ptr, *sig_idx;   /* (in sig_name's block, sig_val's) */
  double *sig_val;
  int sig_u, sig_seen;    /* the signals read u (directly or through a constraint's multiplier),
                             as found when there were sig_seen of them (cup_netlist_signals) */
  double *vals, *dense;   /* a sample's (x, u, zeta) side by side (n + p + m), and n + p + m + supernodes of scratch */
  double u_lo, u_hi;      /* vals' u is u(t) for every t in [u_lo, u_hi) (sig_input) */
  double *ucache;         /* per input term, 3 doubles: a piecewise constant term's value v on [lo, hi)
                             (lo, hi, v; lo = hi: none), for the signals' samples (sig_input) */
  int ucache_n;           /* ... terms it has room for; after them (lo, hi, u[0..p-1]): the whole u(t) on
                             [lo, hi) when every term is constant or cached (sig_input) */
  const cup_netlist *uref;   /* a switched netlist: the configuration whose terms its ucache holds, */
  double uref_t0;            /* ... at that one's time origin, */
  int ugen;                  /* ... and the generation of that choice (sig_ucache) */
  int ushare;                /* a configuration: +-ugen when its terms were found (not) uref's, */
  double ushare_t0;          /* ... at its time origin then */
  double *prow;           /* nv + ni: a signal's row over the ports (in dense's block, as vals) */
  signal_map smap;        /* the signals' rows as one dense map over (x, u, zeta of the LCS), folded */
  double *smap_rows;      /* ... (nl_signal_map; smap.ns = 0: not built for the signals there are) */
  /* switches (netlist_switch.c) */
  nl_switched *sw;        /* the netlist with switches: its configurations, or NULL */
  const nl_sw_hooks *hooks;   /* ... and what its own functions ask of them */
  nl_raw *raw;            /* a configuration's circuit: the formulation before its reduction (freed after it) */
  int nelem_user;         /* elements written (a configuration's circuit appends constraints) */
  int names_lent;         /* > 0: the names of nodes, files and the first names_lent elements are
                             the switched netlist's circuit's (nl_circuit.names_lent): not freed;
                             nor its row names, which are its elements' (name_variables) */
  int mr;                 /* a configuration's diode rows (m counts its constraint rows too) */
  int *zrow;              /* m: each row's diode row (>= 0) or constraint -1 - q; NULL: none */
  int nq;                 /* constraint rows */
  double *Lam;            /* nq x (n + p + mr), row-major: the constraints' multipliers */
};

/* The netlist's .probe/.save/.print lines (c's) as nl's own: the texts
 * cup_netlist_probe_default probes (CUP_ERR_NOMEM, nl keeping what it got). */
int nl_copy_probes(cup_netlist *nl, const nl_circuit *c);

/* nl's own sources read from t0 on (u the shift of the sources as written,
 * kept in u_written; t0 = 0: as written again). */
int nl_input_origin(cup_netlist *nl, double t0, char *errmsg);

/* Triplets, each with a bound on the magnitude of what was summed into it. */
typedef struct nl_coo {
  int n, cap;
  int *i, *j;
  double *x, *mag;
} nl_coo;
int nl_coo_add(nl_coo *t, int i, int j, double x, double mag);
/* CSC with duplicates summed; an entry at or below 256 eps times its
 * magnitude bound is dropped (it cancelled to rounding; mag 0: exact zeros). */
int nl_coo_to_csc(const nl_coo *t, int nrow, int ncol, la_sparse *out);
void nl_coo_free(nl_coo *t);

/* "FILE:LINE:COL: ELEM: message" for element e (-1: FILE: message). */
int nl_fail(const nl_circuit *c, int e, char *errmsg, int status, const char *fmt, ...)
  __attribute__((format(printf, 5, 6)));

/* Classify the diodes, build the forest and the ports; index problems,
 * dangling nodes and shorted elements are errors here. */
int nl_topology(cup_netlist *nl, const nl_circuit *c, char *errmsg);
/* A loop of ideal diodes with no resistance, whose current is not unique:
 * two diodes between the same nodes, or diodes all in one direction around
 * a loop; named in nl->warning (file:line:col of its first element). */
int nl_diode_loops(cup_netlist *nl, const nl_circuit *c);
/* The hybrid matrix H (and Lap's factor and K, kept for signals). */
int nl_hybrid(cup_netlist *nl, const nl_circuit *c, char *errmsg);
/* tau(a) - tau(b) as (port, coefficient) pairs into buf (at most
 * depth(a) + depth(b) of them); returns their number. */
int nl_path(const cup_netlist *nl, int a, int b, int *port, double *coef);

/* Rows over the ports (nv + ni dense): node v's potential times coef, and
 * element e's current (from its first node to its second), added in. */
int nl_prow_node(cup_netlist *nl, int v, double coef, double *prow);
int nl_prow_current(cup_netlist *nl, int e, double *prow);
/* Eliminate the controlled sources: their outputs in terms of the other
 * ports (zmap) and H's columns with them substituted; a singular loop of
 * controlled sources is an error naming them. */
int nl_controlled(cup_netlist *nl, const nl_circuit *c, char *errmsg);
/* K: the inductance matrix's blocks, checked positive definite, into
 * P (sparse, when any K) and Pinv. */
int nl_coupling_metric(cup_netlist *nl, const nl_circuit *c, la_sparse *P, char *errmsg);

/* Signal `name` (canonical: another configuration's sig_name) appended to
 * sub's table, as cup_netlist_probe would, but neither formatted again nor
 * looked for among those sub has: the caller records a configuration's
 * signals in the order of the netlist's, whose names are unique. Returns
 * its index or a status < 0. at, when not NULL: the element or nodes the
 * name names, found by name on the first call (at->kind 0: not yet) and
 * kept there for the next, in another configuration of the same circuit
 * (each has the circuit's nodes and elements in its order, its own
 * constraints after them: netlist_switch.c's derive), which reads no
 * name again. */
int nl_probe_next(cup_netlist *sub, const char *name, nl_probe_at *at, char *errmsg);
/* 0 if text is a valid probe of this circuit, else a message into msg. */
int nl_probe_check(const cup_netlist *nl, const char *text, char *msg, size_t size);

/* The formulation of a parsed circuit (netlist.c); the reader calls it. */
int netlist_formulate(cup_netlist **out, const nl_circuit *c, char *errmsg);
/* ... with u, when not NULL, its input as written (its sources' terms):
 * copied, not built again (a switch configuration's, netlist_switch.c). */
int nl_formulate(cup_netlist **out, const nl_circuit *c, const cup_input *u, char *errmsg);

/* ---- switches (netlist_switch.c, netlist_reduce.c) ---- */
/* A circuit with switches: its configuration at t = 0 formulated as the
 * netlist, the circuit kept (moved out of *c) to form the others. */
int nl_switched_formulate(cup_netlist **out, nl_circuit *c, char *errmsg);
/* netlist_reduce.c: "out of memory while forming a switch configuration",
 * as c's error; and configuration sub, formulated from the circuit d that
 * c derives, reduced: its diode rows first, the constraint rows a switch
 * makes eliminated by the P-projector (*Pi: n x n, malloc'd; left NULL
 * when there are none), the LCS formed over the rest. */
int nl_switch_nomem(const nl_circuit *c, char *errmsg);
int nl_switch_reduce(cup_netlist *sub, const nl_circuit *c, const nl_circuit *d, double **Pi, char *errmsg);
/* build_lcs for a configuration's circuit: the parts kept dense in nl->raw,
 * or, with no constraint row, moved there as they are (their owners then
 * hold none; netlist.c). */
int nl_raw_store(cup_netlist *nl, la_sparse *const parts[6], double **pdiag, la_sparse *Pc, int sparse);
/* nl->raw freed (netlist.c). */
void nl_raw_free(cup_netlist *nl);
/* A row over (x, u, zeta) of signal kind 'v' (nodes a, b; b < 0: ground) or
 * 'i' (element a), into row (n + p + m). */
int nl_signal_row(cup_netlist *nl, char kind, int a, int b, double *row);

#endif

/* netlist_desc — a circuit as the netlist reader (io/netlist_read.c) hands
 * it to the formulation (netlist.c): nodes, elements with their values
 * already evaluated, sources, initial conditions, .tran and probes, each
 * with the place it was written, so that the formulation's errors can name
 * file, line, column and element. Internal to the library. */
#ifndef CUP_NETLIST_DESC_H
#define CUP_NETLIST_DESC_H

/* Element kinds, in the order the formulation groups them; E, F, G, H are
 * the linear controlled sources (VCVS, CCCS, VCCS, CCVS). S and W are
 * switches (voltage- and current-controlled), which the formulation never
 * sees: each switch configuration becomes a circuit of its own
 * (netlist_switch.c) where a closed ideal switch is NL_Z, a short (a
 * voltage port of value 0), an open one NL_O (a current port of value 0),
 * and RON, ROFF are resistors. */
typedef enum nl_kind { NL_R, NL_L, NL_C, NL_V, NL_I, NL_D, NL_E, NL_F, NL_G, NL_H, NL_S, NL_W, NL_Z, NL_O } nl_kind;

/* A diode row that is a switch configuration's constraint on the state
 * (nl_elem.eq): NL_EQ_LOOP, a closed switch that closes a loop of
 * capacitors (a current port whose current is the loop's, its voltage held
 * at 0); NL_EQ_CUT, across a cutset of inductors that an open switch leaves
 * (a voltage port whose voltage is the cut's, its current held at 0). */
enum { NL_EQ_NONE, NL_EQ_LOOP, NL_EQ_CUT };

/* An independent source's transient function (SPICE syntax). */
typedef enum nl_fn { NL_FN_DC, NL_FN_SIN, NL_FN_PULSE, NL_FN_PWL } nl_fn;

enum { NL_SIN_VO, NL_SIN_VA, NL_SIN_FREQ, NL_SIN_TD, NL_SIN_THETA, NL_SIN_PHASE };
enum { NL_PULSE_V1, NL_PULSE_V2, NL_PULSE_TD, NL_PULSE_TR, NL_PULSE_TF, NL_PULSE_PW, NL_PULSE_PER };

typedef struct nl_source {
  nl_fn fn;
  double dc;          /* DC value: the source's value for NL_FN_DC */
  double p[7];        /* SIN: VO VA FREQ TD THETA PHASE(degrees); PULSE: V1 V2 TD TR TF PW PER */
  int np;             /* number of parameters written (SPICE defaults fill the rest) */
  unsigned jumps;     /* PULSE: bit NL_PULSE_TR, NL_PULSE_TF: written `jump`, an edge of no duration */
  int npts;           /* PWL: points */
  double *t, *v;      /* PWL: times (strictly increasing) and values */
} nl_source;

typedef struct nl_elem {
  nl_kind kind;
  char *name;         /* as written ("R1"); names compare case-insensitively */
  int a, b;           /* nodes (0: ground): R, L, C, D from a to b; V, I, E-H: a = n+, b = n- */
  double value;       /* R: ohms, L: henries, C: farads; E-H: the gain */
  int ca, cb;         /* E, G, S: the controlling nodes nc+, nc- */
  int ctrl;           /* F, H, W: the element whose current controls (its current from its
                         first node to its second, as SPICE's V's branch current) */
  int has_ic;         /* L, C: IC= given */
  double vt, vh;      /* S, W: threshold and hysteresis (on above vt + |vh|, off below vt - |vh|) */
  double ron, roff;   /* S, W: on and off resistances, 0 when not given (ideal: a short, an open) */
  int init;           /* S, W: ON or OFF written on the card: 1 or 0; -1 not written */
  int eq;             /* D: NL_EQ_* (a derived circuit's constraint row), else NL_EQ_NONE */
  double ic;          /* L: initial current, C: initial voltage */
  nl_source src;      /* V, I */
  int file;           /* c->files[file] holds it */
  int line, col;      /* where the element's name is written */
} nl_elem;

/* K: two inductors coupled, M = k sqrt(L1 L2), |k| < 1 (several K on one
 * inductor couple it pairwise with each). */
typedef struct nl_coupling {
  char *name;
  int l1, l2;         /* the inductors (element indices) */
  double k;
  int file, line, col;
} nl_coupling;

typedef struct nl_ic {
  int node;
  double v;
  int line, col;
} nl_ic;

typedef struct nl_probe {
  char *text;         /* "v(out)", "i(D1)", "v(a,b)", as written */
  int line, col;
} nl_probe;

typedef struct nl_circuit {
  char *file;         /* name used in messages (files[0]) */
  int nfiles;
  char **files;       /* every file read: the netlist, then its .include/.lib files in the
                         order they were first read */
  int nnodes;         /* nodes 0 .. nnodes-1; 0 is ground ("0" or "gnd") */
  char **node;        /* names as first written */
  int *node_line, *node_col;   /* first place each node is written */
  int nelem;
  nl_elem *elem;
  int ncoup;
  nl_coupling *coup;  /* K cards */
  int has_tran;
  double tstep, tstop, tstart, tmax;   /* tstart, tmax 0 when not given */
  int tran_line, tran_col;
  double reltol, abstol, vntol, chgtol;   /* .options: NAN when not given */
  int steady;         /* .options steadystate (or steadyperiod=T): the periodic steady state asked for */
  double steady_period;                   /* its period, 0: the sources' */
  int nic;
  nl_ic *ic;          /* .ic v(node)=value */
  int nprobe;
  nl_probe *probe;    /* .probe/.save/.print lines, in order */
  int probe_all;      /* .save all / .probe all */
  int nswitch;        /* S and W elements */
  int derived;        /* a switch configuration's circuit (netlist_switch.c): constraint rows
                         (eq) allowed, dangling nodes allowed, inert diodes kept */
  int names_lent;     /* a derived circuit: the names of its first names_lent elements, of its
                         nodes and files are the switched netlist's circuit's (netlist_switch.c's
                         S->c), freed with the switched netlist after every configuration's
                         netlist: netlist_formulate lends them on */
  int no_warning;     /* a derived circuit formed in the run: no diode loops' warning (only the
                         switched netlist's own, its topo[0]'s, is read: cup_netlist_warning) */
} nl_circuit;

void nl_circuit_free(nl_circuit *c);

#endif

/* catchup/netlist.h — circuits from SPICE-subset netlists (.cir/.sp):
 * R, L, C, independent V and I sources (DC, SIN, PULSE, PWL), ideal
 * diodes, linear controlled sources (E, F, G, H), coupled inductors (K),
 * subcircuits (X, .subckt) and .include/.lib, formulated by modified nodal analysis as an LCS
 *     x' = A x + B zeta + E u(t),   0 <= zeta _|_ C x + D zeta + G u(t) >= 0
 * with x = (inductor currents, capacitor voltages) in netlist order, u the
 * sources' values in netlist order, one complementarity row per diode, and
 * P = diag(L, C), the energy metric. A diode whose current is fixed by the
 * state (in series with an inductor) gives a row with zeta = its reverse
 * voltage and D = 0; any other diode a row with zeta = its current, and D
 * (the resistance it sees) is then nonzero. The reader, the formulation and
 * the signals are described in docs/netlist.md. */
#ifndef CATCHUP_NETLIST_H
#define CATCHUP_NETLIST_H

#include "catchup/export.h"
#include "catchup/lcs.h"
#include "catchup/input.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cup_netlist cup_netlist;

/** Read and formulate a netlist. sets (may be NULL) are "NAME=VALUE"
 *  strings applied before anything is evaluated: NAME is an element
 *  ("R1=2k", "V1=SIN(0 5 50)") or a .param ("vin=5"). Every error names
 *  file:line:column and the element in errmsg (CUP_ERRMSG_LEN bytes). */
CUP_API int cup_netlist_load(cup_netlist **nl, const char *path, const char *const *sets, int nsets,
                             char *errmsg);
/** The same from text; `name` is used in messages in place of a file name. */
CUP_API int cup_netlist_load_string(cup_netlist **nl, const char *text, const char *name,
                                    const char *const *sets, int nsets, char *errmsg);
CUP_API void cup_netlist_free(cup_netlist **nl);
/** What the formulation found suspect but allowed, or NULL: a loop of
 *  ideal diodes with no resistance, whose current is not unique (two
 *  diodes between the same two nodes, or diodes all in one direction around
 *  a loop), named with file:line:column of its first element ("c.cir:3:1:
 *  D1: D1 and D2 are ideal diodes in anti-parallel between nodes 'a' and
 *  'b', ..."). The run takes one of the solutions. catchup-run prints it
 *  before the run and keeps it in the file's attribute `warnings`. */
CUP_API const char *cup_netlist_warning(const cup_netlist *nl);

/** The LCS (owned by the netlist). */
CUP_API const cup_lcs *cup_netlist_lcs(const cup_netlist *nl);
/** The sources as an input u(t) (p components); NULL when there is none. */
CUP_API const cup_input *cup_netlist_input(const cup_netlist *nl);
/** x(0) from IC= on L and C and .ic v(node)=...; zero otherwise. */
CUP_API const double *cup_netlist_x0(const cup_netlist *nl);
/** .tran TSTEP TSTOP: 1 and the values if the netlist has one, else 0.
 *  As in SPICE, TSTEP is the output's spacing, not a step (docs/netlist.md). */
CUP_API int cup_netlist_tran(const cup_netlist *nl, double *tstep, double *tstop);
/** .tran's TSTART (where the output begins) and TMAX (the longest step), 0
 *  where not given: 1 if the netlist has a .tran, else 0. */
CUP_API int cup_netlist_tran_window(const cup_netlist *nl, double *tstart, double *tmax);
/** .options RELTOL, ABSTOL, VNTOL, CHGTOL as given, NAN where not: 1 if any
 *  is given, else 0 (docs/netlist.md: how they map onto the adaptive
 *  scheme's tol). */
CUP_API int cup_netlist_tolerances(const cup_netlist *nl, double *reltol, double *abstol, double *vntol, double *chgtol);

/** Read the sources from time t0 >= 0 on: the netlist's input (and every
 *  switch configuration's, formed or to come: their gates, signals and
 *  E u) becomes the sources as written at t0 + t (term by term), so that
 *  a run from t = 0 is the circuit's from t0. The steady state's period map
 *  starts at the phase cup_input_steady_phase gives (docs/steady-state.md).
 *  t0 = 0: as written again. Make integrators after this call: they keep
 *  the input they were made with. CUP_ERR_UNSUPPORTED for t0 != 0 and a
 *  controller (cup_netlist_set_controller: its instants k ts are on the
 *  sources' clock). */
CUP_API int cup_netlist_set_time_origin(cup_netlist *nl, double t0, char *errmsg);

/** .options steadystate (or steadyperiod=T): 1 if the netlist asks for its
 *  periodic steady state (docs/steady-state.md), with the period (0: the
 *  sources') into period; 0 otherwise. */
CUP_API int cup_netlist_steady_state(const cup_netlist *nl, double *period);
/** The files the netlist was read from: 0 is the netlist itself, then each
 *  file its .include and .lib cards read (paths joined to the including
 *  file's folder, each once, in the order first read); NULL out of range.
 *  Tools that write outputs can refuse to overwrite any of them, and hash
 *  them all to know what a run read. */
CUP_API int cup_netlist_file_count(const cup_netlist *nl);
CUP_API const char *cup_netlist_file(const cup_netlist *nl, int k);

/** Names of the state ("i(L1)", "v(C1)"), the rows (the diodes, "D1") and
 *  the inputs (the sources, "V1"); NULL out of range. */
CUP_API const char *cup_netlist_state_name(const cup_netlist *nl, int j);
/** The netlist's text as it was read (before any `sets`), for provenance. */
CUP_API const char *cup_netlist_source(const cup_netlist *nl);
CUP_API const char *cup_netlist_row_name(const cup_netlist *nl, int i);
CUP_API const char *cup_netlist_input_name(const cup_netlist *nl, int j);
/** 1 if the current of diode row i is fixed by the state (zeta_i is its
 *  reverse voltage, row of D zero), 0 if zeta_i is its current. */
CUP_API int cup_netlist_row_fixed(const cup_netlist *nl, int i);

/** Add a signal to record: "v(NODE)", "v(NODE1,NODE2)" or "i(ELEMENT)"
 *  (case-insensitive); "all" adds every node voltage and element current.
 *  Returns its index (>= 0) or an error with errmsg. Adding one twice
 *  returns the first index. */
CUP_API int cup_netlist_probe(cup_netlist *nl, const char *signal, char *errmsg);
/** The probes the netlist itself asks for (.probe/.save/.print); when it
 *  asks for none, every signal if the circuit has at most `limit` of them. */
CUP_API int cup_netlist_probe_default(cup_netlist *nl, int limit, char *errmsg);
CUP_API int cup_netlist_signal_count(const cup_netlist *nl);
/** Canonical name: "v(out)", "v(a,b)", "i(D1)" (node and element names as
 *  first written in the netlist). */
CUP_API const char *cup_netlist_signal_name(const cup_netlist *nl, int k);
/** Its unit: "V" for a voltage v(...), "A" for a current i(...). */
CUP_API const char *cup_netlist_signal_unit(const cup_netlist *nl, int k);
/** The recorded signals at time t for state x and complementarity
 *  variables zeta (m entries; NULL: 0), into out (signal_count entries).
 *  Each is linear: S_x x + S_u u(t) + S_zeta zeta. Allocates nothing. */
CUP_API int cup_netlist_signals(cup_netlist *nl, double t, const double *x, const double *zeta, double *out);
/** The nodes of element `element` (case-insensitive), a its first and b its
 *  second (owned by the netlist): its voltage is v(a,b) and its current
 *  i(element) flows from a to b through it, so that v(a,b) i(element) is
 *  the power it absorbs (a source delivering power absorbs a negative one).
 *  CUP_ERR_ARG naming the element when there is none. */
CUP_API int cup_netlist_element_nodes(const cup_netlist *nl, const char *element, const char **a, const char **b,
                                      char *errmsg);

/** Switches (S, W): how many the netlist has. */
CUP_API int cup_netlist_switch_count(const cup_netlist *nl);
/** 1 and the netlist's switched LCS in *sw if it has switches, else 0.
 *  The netlist's own LCS (cup_netlist_lcs) is the configuration at t = 0,
 *  and its signals are the configuration's in force (the last settled or
 *  jumped into). */
CUP_API int cup_netlist_switching(cup_netlist *nl, cup_switching *sw);
/** A digital controller: called at its sampling instants t = k ts (k =
 *  0, 1, ...; each computed as k ts) with the state x there (n entries,
 *  before any jump) and gate[] (nswitch entries, the switches in netlist
 *  order, 1 closed) holding the gates in force; it writes the gates to hold
 *  until its next instant. Return nonzero to stop the run (an error naming
 *  the time). Callable from Fortran (bind(C)). */
typedef int (*cup_gate_fn)(double t, const double *x, int nswitch, int *gate, void *ctx);
/** Let fn set the switches' gates every ts (their models' thresholds are
 *  then not used; RON and ROFF still are); fn NULL gives them back to their
 *  controls. Every scheme steps to each instant (a fixed-step scheme splits
 *  the step that holds it, as at a switching time). */
CUP_API int cup_netlist_set_controller(cup_netlist *nl, double ts, cup_gate_fn fn, void *ctx, char *errmsg);
/** Switch configurations formulated so far (each once). */
CUP_API long cup_netlist_configurations_formed(const cup_netlist *nl);

#ifdef __cplusplus
}
#endif
#endif

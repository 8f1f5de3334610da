/* signal_map — the signals of a netlist's configuration in force as one
 * dense map over an LCS run's (x, u, zeta): what cup_netlist_signals sums
 * row by row (a configuration's constraint multipliers folded in), for a
 * scheme that knows x, u and zeta as linear functions of its own state (the
 * adaptive scheme's samples inside a step, integrator/record.h) to compose
 * once per active set and evaluate per sample. Internal to the library and
 * its apps (netlist_signal.c builds it). */
#ifndef CUP_SIGNAL_MAP_H
#define CUP_SIGNAL_MAP_H

#include "catchup.h"

typedef struct signal_map {
  const void *key;          /* the configuration whose rows these are: the same key and ns, the same rows */
  const double *rows;       /* ns x (n + p + m), row-major: signal k = rows_k . (x, u, zeta) */
  int ns, n, p, m;          /* m: the LCS's rows (zeta as cup_integrator_zeta gives it) */
  const cup_input *u;       /* the input whose components the u columns are */
} signal_map;

/* The map of nl's configuration in force (built the first time it is asked
 * for, and again when a probe was added), or NULL (no signals, no memory). */
const signal_map *nl_signal_map(cup_netlist *nl);

/* 1 if a and b are the same input (the same object, or the same terms in
 * the same components, bit for bit), else 0. */
int nl_same_input(const cup_input *a, const cup_input *b);

#endif

/* netlist_subckt — a netlist's structure (netlist_subckt.c): .include and
 * .lib spliced in, .end and .control blocks dropped, .subckt definitions
 * set aside; then X instances flattened into plain cards with hierarchical
 * names. Internal to io/netlist_read.c. */
#ifndef CUP_NETLIST_SUBCKT_H
#define CUP_NETLIST_SUBCKT_H

#include "netlist_lex.h"

/* Replace x's cards (the netlist's, split by nx_lex_file) by the top-level
 * cards in reading order, included files read and split on the way. */
int nx_structure(nx *x);
/* Replace every X card by its instance's cards (after .param and sets are
 * in place: instance parameters are evaluated here). */
int nx_flatten(nx *x);

#endif

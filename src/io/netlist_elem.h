/* netlist_elem — the reader's state and the element cards
 * (netlist_elem.c): R, L, C, V, I, D, E, F, G, H, K, S and W read into the
 * circuit description, and the names they refer to resolved. Internal to
 * io/netlist_read.c, which reads the control lines and runs the passes. */
#ifndef CUP_NETLIST_ELEM_H
#define CUP_NETLIST_ELEM_H

#include "netlist_lex.h"
#include "model/netlist_desc.h"

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

/* "out of memory", as every failed allocation of the reader says it. */
int nr_nomem(rd *r);
/* Node 0: "0" or "gnd" (any case). */
int nr_is_ground(const char *s);

/* The element card `card`, by its letter (read_element, netlist_read.c). */
int nr_read_passive(rd *r, int card, nl_kind kind);      /* R, L, C */
int nr_read_source(rd *r, int card, nl_kind kind);       /* V, I */
int nr_read_diode(rd *r, int card);                      /* D */
int nr_read_controlled(rd *r, int card, nl_kind kind);   /* E, F, G, H */
int nr_read_coupling(rd *r, int card);                   /* K */
int nr_read_switch(rd *r, int card, nl_kind kind);       /* S, W */
/* The names that F, H, W and K refer to, once every element is read. */
int nr_resolve_refs(rd *r);

#endif

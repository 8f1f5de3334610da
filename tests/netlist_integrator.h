/* A netlist's integrator under options o, switched when the netlist has
 * switches (its cup_switching), else on its LCS; it must be made (the
 * tests that run the example netlists: test_outtol.c,
 * test_first_record.c). Needs cmocka.h before it. */
#ifndef CUP_NETLIST_INTEGRATOR_H
#define CUP_NETLIST_INTEGRATOR_H

#include "catchup.h"

static inline cup_integrator *netlist_integrator(cup_netlist *nl, const cup_integrator_options *o) {
  char err[CUP_ERRMSG_LEN] = "";
  cup_integrator *I = NULL;
  cup_switching sw;
  int st = cup_netlist_switching(nl, &sw) ? cup_integrator_create_switched(&I, &sw, cup_netlist_input(nl), o, err)
                                          : cup_integrator_create(&I, cup_netlist_lcs(nl), cup_netlist_input(nl), o, err);
  if (st) fail_msg("%s", err);
  return I;
}

#endif

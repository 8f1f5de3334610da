/* netlist_power — an element's terminals by name, for its power
 * v(a, b) i(E) (catchup/netlist.h): a new file beside the formulation's,
 * which it only reads. */
#define _POSIX_C_SOURCE 200809L
#include <strings.h>
#include "catchup.h"
#include "netlist_impl.h"
#include "util/fail.h"

int cup_netlist_element_nodes(const cup_netlist *nl, const char *element, const char **a, const char **b,
                              char *errmsg) {
  if (!nl || !element || !a || !b) return fail_fmt(errmsg, CUP_ERR_ARG, "element nodes: NULL argument");
  for (int e = 0; e < nl->nelem; e++)
    if (!strcasecmp(nl->elem[e].name, element)) {
      *a = nl->node[nl->elem[e].a];
      *b = nl->node[nl->elem[e].b];
      return CUP_OK;
    }
  return fail_fmt(errmsg, CUP_ERR_ARG, "no element named '%.60s' in %s", element, nl->file);
}

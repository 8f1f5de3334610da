/* scene_netlist — the scene key `netlist:` (scene_netlist.c). Internal. */
#ifndef CUP_SCENE_NETLIST_H
#define CUP_SCENE_NETLIST_H

#include "catchup/netlist.h"
#include "catchup/integrator.h"
#include "scene_tree.h"

struct file_list;

/* The netlist named by val (a file name relative to dir, or a mapping with
 * file or text, name, probe and NAME: VALUE sets); errors name the scene's
 * place or the netlist's line. */
int scene_netlist_read(const st_src *src, const char *dir, const st_node *knode, const st_node *val,
                       cup_netlist **out, struct file_list *files, char *errmsg);
/* The tolerances a netlist's .options defaults to (docs/netlist.md):
 * SPICE's, but for RELTOL (SPICE's 1e-3 is loose for a max norm over
 * currents and voltages alike; the adaptive scheme costs little more). */
#define CUP_NETLIST_RELTOL 1e-6
#define CUP_NETLIST_ABSTOL 1e-12
#define CUP_NETLIST_VNTOL 1e-6
#define CUP_NETLIST_CHGTOL 1e-14

/* What SPICE means: from .tran T = TSTOP, samples every TSTEP from TSTART,
 * hmax = TMAX, n = TSTOP / TSTEP (for the fixed-step scheme a circuit
 * too large for the adaptive one falls back to); tol from .options; the
 * adaptive scheme where it can run the circuit, else theta (dense),
 * implicit or explicit. */
void scene_netlist_options(const cup_netlist *nl, cup_integrator_options *o);
/* The samples every TSTEP from TSTART to o->T (after T is overridden). */
void scene_netlist_sampling(const cup_netlist *nl, cup_integrator_options *o);

#endif

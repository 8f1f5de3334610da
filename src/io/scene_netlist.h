/* scene_netlist — the scene key `netlist:` (scene_netlist.c). Internal. */
#ifndef CUP_SCENE_NETLIST_H
#define CUP_SCENE_NETLIST_H

#include "catchup/netlist.h"
#include "catchup/integrator.h"
#include "scene_tree.h"

struct cup_file_list;

/* The netlist named by val (a file name relative to dir, or a mapping with
 * file or text, name, probe and NAME: VALUE sets); errors name the scene's
 * place or the netlist's line. */
int scene_netlist_read(const st_src *src, const char *dir, const st_node *knode, const st_node *val,
                       cup_netlist **out, struct cup_file_list *files, char *errmsg);
/* T and n from .tran (when it has one), and the scheme a circuit defaults
 * to: theta when it fits the dense limits, else implicit or explicit. */
void scene_netlist_options(const cup_netlist *nl, cup_integrator_options *o);

#endif

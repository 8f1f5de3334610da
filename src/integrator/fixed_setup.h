/* fixed_setup — the fixed-step schemes' hooks of the scheme table (scheme.h)
 * that do not run: set-up, free, state, zeta, their part of a checkpoint.
 * Their workspace is a fixed_ws (fixed_impl.h). Internal to the library. */
#ifndef CUP_FIXED_SETUP_H
#define CUP_FIXED_SETUP_H

#include "scheme.h"

int fixed_create(cup_integrator *I, const scheme_model *md, void **ws, char *errmsg);
void fixed_free(void *ws);
const double *fixed_state(const void *ws);
void fixed_grid(const void *ws, scheme_grid *g);
int fixed_zeta(void *ws, double *zeta);
int fixed_saves(const void *ws);
int fixed_stopped(const void *ws, cup_run_info *info);
void fixed_checkpoint(void *ws, ckpt *c);

#endif

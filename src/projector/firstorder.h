/* firstorder — the paper's projected gradient on the dual and FISTA with
 * restart (firstorder.c): the methods pg and fista, and their iteration,
 * which the dense active set also runs in bursts (activeset.c). */
#ifndef CUP_FIRSTORDER_H
#define CUP_FIRSTORDER_H

#include "proj_ws.h"

/* Four m-vectors of scratch (the iteration swaps wm with p->lam). */
typedef struct fo_ws { double *wm, *wm2, *wm3, *wm4; } fo_ws;

/* Its vectors, from the projector's block (proj_ws.h's two passes). */
void proj_fo_lay_out(cup_projector *p, proj_carve *a, fo_ws *w);

/* Starts from p->lam, b = s(x) in p->b; fills p->lam (>= 0) and p->y = z
 * with certificates in info; stops after `budget` iterations. Returns a
 * status. */
int proj_firstorder(cup_projector *p, fo_ws *w, const double *x, int accelerated, int budget,
                    cup_proj_info *info);

extern const proj_method *const proj_pg;
extern const proj_method *const proj_fista;

#endif

/* dual_factor — the regularized dual Newton matrix of the sparse exact path,
 *     M~(F, delta) = M_FF + delta I on the free rows F, identity elsewhere,
 *     M = C P^-1 C^T,
 * factored and solved without allocating. Two forms:
 *  - diagonal P: M itself (sparse, formed once, its upper triangle); the
 *    LDL^T of M_FF alone, at a cost set by the free rows rather than by M,
 *    in a room for the factor of all of M, or where that would be large
 *    (crowds of 10^3 disks and more) of twice M, laid out for a set of
 *    rows that holds F: every row when that fits, else F and the last
 *    layout's rows, else F alone, with CG for a free set whose factor does
 *    not fit; rows inside the layout join and leave F row by row (CHOLMOD
 *    rowadd/rowdel) when that costs less than refactoring;
 *  - sparse P: the quasi-definite KKT matrix [P C_F^T; C_F -delta I],
 *    refactored by CHOLMOD (M would be dense), stored upper.
 * Both are symmetrically permuted once (AMD), so that factors use the
 * natural ordering without allocating. */
#ifndef CUP_DUAL_FACTOR_H
#define CUP_DUAL_FACTOR_H

#include "set/polyset_impl.h"

typedef struct dfact dfact;

/* room: -1 automatic; else the room of the M form's factor in entries,
 * solves by CG on free sets whose factor does not fit (tests use it to run
 * every path). */
int dfact_create(dfact **f, const cup_polyset *K, int updates, long room, char *errmsg);
void dfact_free(dfact **f);
/* Make the factor that of M~(act, delta); counts refactorizations and row
 * updates. Returns CUP_OK or CUP_ERR_LINALG. */
int dfact_factor(dfact *f, const unsigned char *act, double delta,
                 int *refactorizations, int *row_updates);
/* v <- M~^-1 v (m entries; rows outside F come back unchanged). */
void dfact_solve(dfact *f, double *v);
/* The values of K's C changed in place (same pattern; diagonal metric, the
 * M form): recompute M's values, so that the next dfact_factor is a
 * numeric factorization on the same symbolic analysis. Allocation-free. */
void dfact_revalue(dfact *f);
/* 1: the current factor is solved by CG (it outgrew the packed room). */
int dfact_by_cg(const dfact *f);
/* The smallest regularization, relative to the scale of M. */
double dfact_delta_min(const dfact *f);

#endif

/* catchup/lcs.h — linear complementarity systems (paper, Sec. 7)
 *     x' = A x + B zeta + E u(t),   0 <= zeta  _|_  C x + G u(t) + F >= 0,
 * with an SPD P such that P B = C^T. In x coordinates the catching-up step
 * is the P-metric projection onto K(t) = {x : C x + G u(t) + F >= 0}. */
#ifndef CATCHUP_LCS_H
#define CATCHUP_LCS_H

#include "catchup/export.h"
#include "catchup/sparse.h"
#include "catchup/polyset.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cup_lcs cup_lcs;

/** The matrices of an LCS. A matrix with ncol = 0 (all fields zero) is
 *  absent: A = 0, no B check, E = 0, G = 0. Everything is copied. */
typedef struct cup_lcs_desc {
  int n;           /**< state dimension */
  int m;           /**< complementarity rows */
  int p;           /**< input dimension (0: no input) */
  cup_csc A;       /**< n x n drift */
  cup_csc B;       /**< n x m; checked against P B = C^T */
  cup_csc C;       /**< m x n */
  cup_csc E;       /**< n x p */
  const double *F; /**< m entries, or NULL for 0 */
  cup_csc G;       /**< m x p: K moves with u when nonzero */
  cup_metric P;    /**< the metric (kind IDENTITY: P = I) */
  double pb_tol;   /**< relative tolerance of ||P B - C^T||; 0 means 1e-12 */
  /* D != 0 (netlist diodes whose current the state does not fix): */
  cup_csc D;       /**< m x m: 0 <= zeta _|_ C x + D zeta + G u + F >= 0; absent or
                        zero: D = 0. With D != 0, B is required and is not checked
                        against P B = C^T (P is then only the norm of certificates),
                        and only the theta and adaptive schemes run the LCS */
  const char *const *row_names; /**< m names of the rows for messages (the diodes), or NULL */
  int keep_B;      /**< 1: B is kept as given and not checked against P B = C^T,
                        D = 0 or not: a nonreciprocal network (a circuit with
                        controlled sources) whose B is not P^-1 C^T in the metric
                        P. Not a sweeping process, as with D != 0; D is then not
                        checked positive semidefinite either (an active network's
                        need not be): each theta step's LCP, M = h C W B + D,
                        is solved or its failure reported */
} cup_lcs_desc;

/** Validate and copy. Fails with CUP_ERR_PB_CT and a message naming the
 *  largest entry of P B - C^T when the check fails, CUP_ERR_DIM for sizes. */
CUP_API int cup_lcs_create(cup_lcs **L, const cup_lcs_desc *d, char *errmsg);
CUP_API void cup_lcs_free(cup_lcs **L);

CUP_API int cup_lcs_dim(const cup_lcs *L);
CUP_API int cup_lcs_rows(const cup_lcs *L);
CUP_API int cup_lcs_inputs(const cup_lcs *L);
/** The set {x : C x + F >= 0} with metric P (offset moved by G u(t)). */
CUP_API const cup_polyset *cup_lcs_polyset(const cup_lcs *L);
/** 1 if G is absent or zero: K does not move. */
CUP_API int cup_lcs_fixed_set(const cup_lcs *L);
/** 1 if the LCS is not a sweeping process: D has a nonzero entry (the
 *  theta and adaptive schemes run it), or B was kept as given (keep_B:
 *  theta only). */
CUP_API int cup_lcs_has_D(const cup_lcs *L);

/** The paper's circuit (Sec. 7, after Acary-Brogliato Ex. 2.52): R1, R2, R3
 *  >= 0, L2, L3, C4 > 0, and g = G (2 entries, NULL for 0). Builds A, B, C,
 *  E, P = diag(1, L3, L2) as in the paper. */
typedef struct cup_circuit {
  double R1, R2, R3, L2, L3, C4;
  double G[2];
} cup_circuit;
CUP_API int cup_lcs_circuit(cup_lcs **L, const cup_circuit *c, char *errmsg);

/** A switched LCS: a family of LCS over one state (x), input (u) and rows,
 *  one per configuration of its switches, each with the jump into it (the
 *  projection onto its constraints in the metric P). Configurations are
 *  numbered as they are formed (0: the one at t = 0); a netlist with S or
 *  W elements gives one (cup_netlist_switching), and an integrator made
 *  with it (cup_integrator_create_switched) runs each configuration's LCS
 *  between the switchings, stepping to them. */
typedef struct cup_switching {
  void *ctx;
  /** The configuration in force from t on, from *topo in force before t
   *  (hysteresis), at state x and multipliers zeta (NULL: 0); formed on its
   *  first occurrence (allocation then only). 0 or an error into errmsg. */
  int (*settle)(void *ctx, int *topo, double t, const double *x, const double *zeta, char *errmsg);
  /** The first time in (t, tmax] at which a switch gated by the sources
   *  alone changes in configuration topo (tmax if none). */
  int (*next)(void *ctx, int topo, double t, double tmax, double *tnext);
  /** Its LCS (owned by ctx). */
  const struct cup_lcs *(*lcs)(void *ctx, int topo);
  /** x onto its constraints (in place): the jump into it. */
  void (*jump)(void *ctx, int topo, double *x);
  /** 1 if a switch's control in it depends on the state or the diodes. */
  int (*state_gated)(void *ctx, int topo);
  /** 1 if a switch the circuit gates leaves configuration topo at time t,
   *  state x (its control past the threshold), 0 if not, < 0 on error. */
  int (*crossed)(void *ctx, int topo, double t, const double *x);
  /** Optional (NULL: every jump may move x): 0 if jump leaves every x as
   *  it is in configuration topo (no constraint of its own), else 1. */
  int (*moves)(void *ctx, int topo);
  /** Optional (NULL: never known): 1 if the input u has no breakpoint in
   *  (t, tnext), tnext next's last answer, in configuration topo from t
   *  (a switched run's window then asks the input for none), else 0. */
  int (*quiet)(void *ctx, int topo, const struct cup_input *u, double t, double tnext);
} cup_switching;

#ifdef __cplusplus
}
#endif
#endif

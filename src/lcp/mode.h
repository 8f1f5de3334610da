/* mode — the theta step's matrices by mode, cached: for a support J of
 * zeta (a bit per row), the kernel of D_JJ that set_mode finds (step.c's
 * kernel_of) and the H, M, Ms and row scales that build_hm makes of it. A
 * bridge moves between a few modes, commutation after commutation; each
 * change of mode then copies what it found the first time instead of
 * eliminating D_JJ and forming C H + D again. Both are functions of J
 * alone (D, C, W B, h and theta are fixed at init), so a copy is the same
 * bits. Allocation-free after lcp_modes_init. */
#ifndef CUP_LCP_MODE_H
#define CUP_LCP_MODE_H

/* Modes kept. */
#define LCP_MODES 8

typedef struct lcp_mode {
  int n, m;                 /* states, rows */
  unsigned long long J;     /* the support */
  int state;                /* 0 empty, 1 the kernel, 2 the kernel and the matrices */
  int nk, lam_sparse;       /* the kernel's columns; build_hm's lam_sparse */
  int *kc;                  /* m: the kernel's free columns */
  double *Z;                /* m x m: its vectors */
  double *H, *M, *Ms, *rsc; /* n x m, m x m, m x m, m: build_hm's */
} lcp_mode;

typedef struct lcp_modes {
  int n, m, next;           /* states, rows; the entry to replace next */
  lcp_mode md[LCP_MODES];
  double *mem;
  int *imem;
} lcp_modes;

/* 0, or 1 when out of memory (lcp_modes_free releases what was taken). */
int lcp_modes_init(lcp_modes *c, int n, int m);
void lcp_modes_free(lcp_modes *c);
/* The entry of the support J: the cached one, or an empty one claimed for
 * it (the oldest replaced). */
lcp_mode *lcp_modes_get(lcp_modes *c, unsigned long long J);
/* build_hm's H, M, Ms, row scales (n x m, m x m, m x m, m) and lam_sparse
 * into the entry (to = 1) or out of it (to = 0). */
void lcp_mode_copy(lcp_mode *E, double *H, double *M, double *Ms, double *rsc, int *lam_sparse, int to);

#endif

/* proj_ws — the internal layout of cup_projector and the workspaces of its
 * methods: types only, the lowest header of the projector, included by the
 * certificates (certify.h) and through them by every method and the
 * dispatcher. */
#ifndef CUP_PROJ_WS_H
#define CUP_PROJ_WS_H

#include <stdint.h>
#include <cholmod.h>
#include "catchup/projector.h"
#include "set/polyset_impl.h"

#define CUP_DENSE_CACHE 4

/* A cached dense pivoted Cholesky of M_AA for one active set A (m <= 64). */
typedef struct dense_fact {
  uint64_t mask;      /* the active set; 0 = unused slot */
  int k, rank;        /* |A| and numerical rank */
  int *idx;           /* A's rows, increasing (k) */
  int *perm;          /* pivot order (k) */
  double *l;          /* k x k factor */
  unsigned stamp;     /* for least-recently-used replacement */
} dense_fact;

/* Iterate and scratch of one projected-Newton solve (newton.c). */
typedef struct pn_ws {
  double *lam, *y, *s, *gam;        /* iterate: lambda, y(lambda), slack, rounding */
  double *y2, *s2, *gam2;           /* line-search trial */
  double *d, *lt, *snap, *keep;     /* m each (snap: the main solve's only) */
  unsigned char *act, *prev;        /* free set, and the previous one */
  int *idx;                         /* m: the line search's rows that can reach their bound */
} pn_ws;

/* The sparse exact path (newton.c): the dual factor and the iterates
 * of the main and the inward-anchor solves. */
typedef struct newton_ws {
  struct cup_dfact *df;
  pn_ws pmain;          /* the projection (lam, y, s, gam shared with the projector) */
  pn_ws pin;            /* the inward anchor's solve */
  double *gin, *bin;    /* shifted offset and its slack at z, for the inward solve */
  double *tau, *rhs;    /* slack targets of the finishing solve; a dual vector */
  double delta_peak;    /* largest Levenberg parameter of the last projection's steps */
  int stieltjes;        /* M = C P^-1 C^T has no positive off-diagonal (diagonal P); -1 unknown */
} newton_ws;

struct cup_projector {
  const cup_polyset *K;
  cup_projector_options opt;
  int n, m;
  void *block;          /* every vector below, in one allocation (projector.c: lay_out) */
  size_t block_bytes;
  double *g;            /* current offset */
  double gscale;        /* max_i |g_i| / ||c_i||_{P^-1} */
  int empty_row;        /* a zero row of C with g_i < 0 (K empty), or -1 */
  double *lam;          /* multipliers of the last projection */
  double *lam_warm;     /* warm start (kept across skips) */
  double *lam_fista;    /* FISTA's own iterate across bursts of a fallback; this and the */
                        /* m scratch below (to act): dense sets and first-order methods only */
  int has_fista;
  double *b;            /* s(x) = C x + g at the point being projected */
  double *s, *gam;      /* slack and its rounding bound at the candidate z */
  double *sv, *gamv;    /* the same at a trial feasible point v */
  double *y, *u;        /* candidate z = x + u, u = P^-1 C^T lambda */
  double *y2, *s2, *gam2;      /* the next iterate's (first-order methods) */
  double *v, *s_v;      /* exactly feasible point found by certification, its slack */
  int has_v;
  double *anchor, *s_anchor;   /* last certified feasible point, its slack */
  int anchor_ok;        /* anchor is feasible for the current offset */
  double *user_pt, *s_user;    /* options.feasible_point, its slack */
  int user_ok;
  double *origin;       /* zeros (n): an anchor with slack g whenever g > 0 */
  int origin_ok;        /* every g_i > 0 */
  double *inward, *s_inward;   /* inward point from the exact method, its slack */
  int has_inward;
  void (*make_inward)(cup_projector *);  /* builds it on demand, or NULL */
  double *farkas;       /* Farkas certificate y >= 0 */
  double *wn, *wn2;     /* n scratch */
  double *wm, *wm2, *wm3, *wm4; /* m scratch */
  int *iwm;             /* m scratch */
  unsigned char *act, *act2;    /* m flags */
  /* dense path */
  dense_fact cache[CUP_DENSE_CACHE];
  unsigned stamp;
  double *dwork;        /* m*m + m scratch */
  /* small dense sets, auto: the dual LCP solved exactly (lcp/step.c, W = I, h = 1) */
  struct cup_lcp_step *small;
  /* sparse Newton */
  newton_ws *nw;
  /* statistics of the current call */
  int iters, facts, updates;
};

#endif

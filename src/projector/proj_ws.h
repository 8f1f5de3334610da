/* proj_ws — the shared layout of cup_projector and the table every
 * projection method fills: types only (and the carving of the projector's
 * one block), the lowest header of the projector, included by the
 * certificates (certify.h) and through them by every method and the
 * dispatcher. What belongs to one method (its scratch, a factor, an LCP)
 * is that method's own workspace, declared in its file; what every method
 * and the certificates share (the candidate and its slack, the multipliers,
 * the anchors, the scale) is here. */
#ifndef CUP_PROJ_WS_H
#define CUP_PROJ_WS_H

#include <stddef.h>
#ifdef __SANITIZE_ADDRESS__
#include <sanitizer/asan_interface.h>
#endif
#include "catchup/projector.h"
#include "set/polyset_impl.h"
#include "util/ckpt.h"

/* The projector's vectors live in one block, carved in two passes over the
 * same lay-out functions (the dispatcher's and each method's): the first
 * (base NULL) sums the sizes and hands out NULL, the second hands out the
 * pieces. One allocation instead of about forty: on small sets (the paper
 * circuit's, 3 x 2) a third of the projector's heap was malloc's minimum
 * chunk and header per vector. Under ASan each piece is followed by a
 * poisoned gap, so that an overrun into the next vector is still caught. */
#ifdef __SANITIZE_ADDRESS__
#define CUP_CARVE_GAP 32
#else
#define CUP_CARVE_GAP 0
#endif
typedef struct proj_carve { char *base; size_t used; } proj_carve;

static inline void *proj_carve_piece(proj_carve *a, size_t count, size_t size) {
  size_t at = a->used, bytes = (count ? count : 1) * size;
  a->used += (bytes + CUP_CARVE_GAP + 15) & ~(size_t)15;    /* 16-byte aligned pieces */
  if (!a->base) return NULL;
#ifdef __SANITIZE_ADDRESS__
  ASAN_POISON_MEMORY_REGION(a->base + at + bytes, a->used - at - bytes);
#endif
  return a->base + at;
}

typedef struct proj_method proj_method;

/* A method as the projector holds it: its table, its workspace, and where
 * in the projector's slots the method it falls back to sits (-1: none). */
typedef struct proj_slot {
  const proj_method *m;
  void *ws;
  int fallback;
} proj_slot;

/* The most methods a projector sets up: the chosen one, the one it falls
 * back to, and the exact stand-in of an inexact one. */
#define PROJ_SLOTS 3

struct cup_projector {
  const cup_polyset *K;
  cup_projector_options opt;
  int n, m;
  void *block;          /* every vector, the methods' included, in one allocation */
  size_t block_bytes;
  double *g;            /* current offset */
  double gscale;        /* max_i |g_i| / ||c_i||_{P^-1} */
  int empty_row;        /* a zero row of C with g_i < 0 (K empty), or -1 */
  double *lam;          /* multipliers of the last projection */
  double *lam_warm;     /* warm start (kept across skips) */
  double *b;            /* s(x) = C x + g at the point being projected */
  double *s, *gam;      /* slack and its rounding bound at the candidate z */
  double *sv, *gamv;    /* the same at a trial feasible point v */
  double *y, *u;        /* candidate z = x + u, u = P^-1 C^T lambda */
  double *y2, *s2, *gam2;      /* a trial iterate's (the methods swap them with y, s, gam) */
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
  void (*make_inward)(cup_projector *, void *);  /* builds it on demand (the running method's), or NULL */
  void *inward_ws;      /* ... with that method's workspace */
  double *farkas;       /* Farkas certificate y >= 0 */
  double *wn, *wn2;     /* n scratch */
  unsigned char *act2;  /* m flags: the rows of an inward anchor */
  proj_slot slot[PROJ_SLOTS];   /* the methods set up (proj_choose), each once */
  int nslots;
  int method;           /* the slot cup_project runs (-1: none, a sparse set without rows) */
  int exact;            /* the slot proj_exact runs */
  const proj_slot *run; /* the slot running now (method's, or exact's in proj_exact) */
  int (*project)(cup_projector *, const proj_slot *, const double *, double *, cup_proj_info *);
                        /* ... its project hook, or the shared course (course.c) */
  /* statistics of the current call */
  int iters, facts, updates;
};

/* A projection method, as GSL's step types and OSQP's linear-system
 * solvers are: one file fills one table and exports a pointer to it; the
 * dispatcher (projector.c) calls through the table and never names a
 * method, and choose.c's registry picks one by `takes`. Every hook gets the
 * method's own workspace ws (NULL until lay_out or create made one). */
struct proj_method {
  const char *name;
  /* its answers are the projection to rounding: proj_exact runs it */
  int exact;
  /* set up beside an inexact method as its exact stand-in (cheap: vectors of the block only) */
  int standby;
  /* the method taking what this one declines (answer returns 0), or NULL */
  const proj_method *const *fallback;
  /* 1 when it is the method for K with the options o */
  int (*takes)(const cup_polyset *K, const cup_projector_options *o);
  /* its vectors from the projector's block (both passes: a = sizes then pieces); NULL: none */
  void (*lay_out)(cup_projector *p, proj_carve *a, void **ws);
  /* what it needs beyond the block (a factorization, an LCP): allocates; NULL: nothing */
  int (*create)(cup_projector *p, void **ws, char *errmsg);
  void (*free)(cup_projector *p, void *ws);
  /* C's values changed in place (projector_revalue); NULL: nothing depends on them */
  void (*revalue)(cup_projector *p, void *ws);
  /* forget a warm start of its own (cup_projector_reset); NULL: none */
  void (*reset)(cup_projector *p, void *ws);
  /* its state between projections, to or from a checkpoint; NULL: none */
  void (*checkpoint)(cup_projector *p, void *ws, ckpt *c);
  /* the whole projection of x as cup_project makes it (s: its slot, info
   * may be NULL), for a method that answers most points itself and leaves
   * the rest to its fallback (course.h: proj_start, proj_course); NULL: the
   * shared course with solve */
  int (*project)(cup_projector *p, const proj_slot *s, const double *x, double *z, cup_proj_info *info);
  /* inside the shared course, x not in K and b = s(x) in p->b: fills p->lam
   * (>= 0) and p->y = z with certificates in info; returns a status. NULL
   * for a method with its own project */
  int (*solve)(cup_projector *p, void *ws, const double *x, cup_proj_info *info);
};

/* The workspace of method m in p, or NULL when p did not set m up. */
static inline void *proj_ws_of(const cup_projector *p, const proj_method *m) {
  for (int k = 0; k < p->nslots; k++)
    if (p->slot[k].m == m) return p->slot[k].ws;
  return NULL;
}

/* A method's lay_out writes its workspace's fields through this pointer:
 * the workspace itself in the second pass, a scratch copy in the first. */
#define PROJ_WS_CARVE(a, ws, type, scratch) \
  ((ws) = proj_carve_piece((a), 1, sizeof(type)), (ws) ? (type *)(ws) : (scratch))

#endif

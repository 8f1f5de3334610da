/* statepoly — the state-dependent polyset C(t, x_k) = {y : C y + g >= 0}
 * with rows from the user's callback at every step (set/rowpool.h).
 *
 * While every row finds a slot of its pattern in the pool, the step writes
 * the new values in place: the polyset's C and C^T, its row norms and
 * Lipschitz bound, the projector's dual matrix C P^-1 C^T on the same
 * symbolic analysis (the next factorization is numeric only), the warm start
 * of the rows that persist (a row that went off drops its multiplier). No
 * allocation. A row of a new pattern rebuilds the pool, its polyset and its
 * projector (a new symbolic analysis, allocations), carrying the warm start
 * over slot by slot.
 *
 * A callback may number the state its own way (rowbuf_order: a crowd
 * along a space-filling curve): the pool, its polyset and projector are
 * then in that numbering, a projection gathers x into it and scatters the
 * answer back, and a new numbering renumbers the pool's patterns and
 * rebuilds (the warm start follows the patterns, hence the contacts). */
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "setproj_impl.h"

static int init(cup_setproj *sp, char *errmsg) {
  if (rowbuf_init(&sp->rb, sp->n, 64, 256) || rowpool_init(&sp->pool, sp->n))
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "state polyset: out of memory");
  return CUP_OK;
}

static void free_pool(cup_setproj *sp) {
  rowbuf_free(&sp->rb);
  rowpool_free(&sp->pool);
  cup_projector_free(&sp->proj);
  cup_polyset_free(&sp->PK);
  free(sp->cpos);
  free(sp->rework);
  free(sp->perm);
  free(sp->pmap);
  sp->cpos = NULL;
  sp->rework = NULL;
  sp->perm = sp->pmap = NULL;
}

/* The pool's pattern as CSC with this step's values (0 for slots not in use)
 * and offsets (1: never active); work: NULL, or revalue's work holding a
 * vector to start the Lipschitz bound from (polyset_create_ex). */
static int pool_polyset(cup_setproj *sp, cup_polyset **K, double *work, char *errmsg) {
  const row_pool *P = &sp->pool;
  const cup_rowbuf *rb = &sp->rb;
  int n = sp->n, m = P->m, nnz = P->nnz;
  int *cp = calloc((size_t)n + 1, sizeof(int)), *ri = malloc(sizeof(int) * ((size_t)nnz + 1));
  double *vx = malloc(sizeof(double) * ((size_t)nnz + 1)), *g = malloc(sizeof(double) * ((size_t)m + 1)), *pd = NULL;
  int st = cp && ri && vx && g ? CUP_OK : fail_fmt(errmsg, CUP_ERR_NOMEM, "state polyset: out of memory");
  if (!st) {
    for (int e = 0; e < nnz; e++) cp[P->col[e] + 1]++;
    for (int j = 0; j < n; j++) cp[j + 1] += cp[j];
    int *next = sp->cpos;                    /* cursor per column, then the positions */
    for (int s = 0; s < m; s++) {
      int r = P->row_of[s];
      g[s] = r >= 0 ? rb->off[r] : 1;
      for (int e = P->ptr[s]; e < P->ptr[s + 1]; e++) {
        int j = P->col[e], q = cp[j] + next[j]++;
        ri[q] = s;
        vx[q] = r >= 0 ? rb->val[rb->ptr[r] + e - P->ptr[s]] : 0;
        sp->cpos[n + e] = q;
      }
    }
    cup_metric metric = {sp->S->K->pkind, sp->S->K->pd, {0}, 0};
    if (sp->ordered && metric.kind == CUP_METRIC_DIAGONAL) {   /* P's diagonal in the pool's numbering */
      pd = malloc(sizeof(double) * (size_t)n);
      if (!pd) st = fail_fmt(errmsg, CUP_ERR_NOMEM, "state polyset: out of memory");
      for (int k = 0; !st && k < n; k++) pd[k] = sp->S->K->pd[sp->perm[k]];
      metric.diag = pd;
    }
    cup_csc view = {m, n, cp, ri, vx};
    if (!st) st = polyset_create_ex(K, &view, g, &metric, 1, work, errmsg);
  }
  free(cp); free(ri); free(vx); free(g); free(pd);
  return st;
}

/* A new pool: polyset, projector, warm start slot by slot. Allocates. */
static int rebuild(cup_setproj *sp) {
  char err[CUP_ERRMSG_LEN] = "";
  row_pool *P = &sp->pool;
  int old_m = sp->PK ? sp->PK->m : 0;
  if (rowpool_rebuild(P, &sp->rb, sp->step)) return setproj_fail(sp, CUP_ERR_NOMEM, "state polyset: out of memory");
  int n = sp->n, m = P->m;
  /* cpos holds n column cursors, then one position per pool entry */
  int *cpos = realloc(sp->cpos, sizeof(int) * ((size_t)n + (size_t)P->nnz + 1));
  double *g = realloc(sp->g, sizeof(double) * ((size_t)m + 1));
  double *rw = malloc(sizeof(double) * (2 * (size_t)m + (size_t)n + 1));
  if (cpos) sp->cpos = cpos;
  if (g) sp->g = g;
  if (!cpos || !g || !rw) {
    free(rw);
    return setproj_fail(sp, CUP_ERR_NOMEM, "state polyset: out of memory");
  }
  /* the last bound's vector slot by slot (0 for a new slot), to start the
   * new set's bound from: a set built cold bounds twice cold, at its
   * creation and at its first revalue */
  int warm = sp->PK && sp->PK->cw_warm;
  for (int s = 0; warm && s < m; s++) {
    int o = P->old_of[s];
    rw[s] = o >= 0 && o < old_m ? sp->rework[o] : 0;
  }
  free(sp->rework);
  sp->rework = rw;
  memset(sp->cpos, 0, sizeof(int) * (size_t)n);
  cup_polyset *K = NULL;
  cup_projector *p = NULL;
  cup_projector_options po = sp->opt;
  double *fp = NULL;                         /* the user's feasible point in the pool's numbering */
  if (sp->ordered && po.feasible_point && (fp = malloc(sizeof(double) * (size_t)n)))
    for (int k = 0; k < n; k++) fp[k] = po.feasible_point[sp->perm[k]];
  int st = sp->ordered && po.feasible_point && !fp ? fail_fmt(err, CUP_ERR_NOMEM, "out of memory")
                                                   : pool_polyset(sp, &K, warm ? rw : NULL, err);
  if (fp) po.feasible_point = fp;
  if (!st) st = cup_projector_create(&p, K, &po, err);
  free(fp);
  if (st) {
    cup_projector_free(&p);
    cup_polyset_free(&K);
    return setproj_fail(sp, st, "state polyset: %s", err);
  }
  for (int s = 0; s < m && sp->proj; s++) {
    int o = P->old_of[s];
    if (o >= 0 && o < old_m && K->rownorm[s] > 0) p->lam_warm[s] = sp->proj->lam_warm[o];
  }
  cup_projector_free(&sp->proj);
  cup_polyset_free(&sp->PK);
  sp->proj = p;
  sp->PK = K;
  sp->m = m;
  sp->rebuilds++;
  for (int s = 0; s < m; s++) sp->g[s] = K->g0[s];
  return CUP_OK;
}

/* Same slots: this step's values in place. */
static void revalue(cup_setproj *sp) {
  const row_pool *P = &sp->pool;
  const cup_rowbuf *rb = &sp->rb;
  cup_polyset *K = sp->PK;
  const int *pos = sp->cpos + sp->n;
  for (int s = 0; s < P->m; s++) {
    int r = P->row_of[s], base = K->Ct.p[s];
    for (int e = P->ptr[s], k = 0; e < P->ptr[s + 1]; e++, k++) {
      double v = r >= 0 ? rb->val[rb->ptr[r] + k] : 0;
      K->C.x[pos[e]] = v;
      K->Ct.x[base + k] = v;
    }
    sp->g[s] = r >= 0 ? rb->off[r] : 1;
  }
  polyset_revalue(K, sp->rework);
  projector_revalue(sp->proj);
}

/* The callback's new numbering (NULL: the state's): the pool's patterns
 * follow it (column k, x[perm_old[k]], becomes the new numbering's column
 * for the same coordinate). Allocates the first time only. */
static int renumber(cup_setproj *sp) {
  int n = sp->n;
  const int *pnew = sp->rb.perm;
  if (!sp->perm) {
    sp->perm = malloc(sizeof(int) * (size_t)n);
    sp->pmap = malloc(sizeof(int) * (size_t)n);
    if (!sp->perm || !sp->pmap) return CUP_ERR_NOMEM;
    for (int k = 0; k < n; k++) sp->perm[k] = k;
  }
  for (int k = 0; k < n; k++) sp->pmap[pnew ? pnew[k] : k] = k;         /* the new inverse */
  for (int k = 0; k < n; k++) sp->perm[k] = sp->pmap[sp->perm[k]];     /* old column -> new */
  rowpool_renumber(&sp->pool, sp->perm);
  for (int k = 0; k < n; k++) sp->perm[k] = pnew ? pnew[k] : k;
  sp->ordered = pnew != NULL;
  sp->perm_gen = sp->rb.perm_gen;
  return CUP_OK;
}

/* The projection, in the callback's numbering if it gave one. */
static int project_ordered(cup_setproj *sp, const double *x, double *z, cup_proj_info *info) {
  if (!sp->ordered || !sp->proj) return cup_project(sp->proj, x, z, info);
  const int *perm = sp->perm;
  for (int k = 0; k < sp->n; k++) sp->xs[k] = x[perm[k]];
  int st = cup_project(sp->proj, sp->xs, sp->zk, info);
  if (st >= 0)                               /* on an error z is unchanged */
    for (int k = 0; k < sp->n; k++) z[perm[k]] = sp->zk[k];
  return st;
}

static int project(cup_setproj *sp, const double *x, double *z, cup_proj_info *info) {
  return setproj_polyset_outcome(sp, project_ordered(sp, x, z, info), info);
}

/* The rows at (t, x) into the pool: a new step (advance) or the same one
 * again (a recheck added rows; the pool's patterns do not age). */
static int place_rows(cup_setproj *sp, double t, const double *x, int advance) {
  const cup_set *S = sp->S;
  sp->step += advance;
  rowbuf_clear(&sp->rb);
  int rc = S->rows(t, x, &sp->rb, S->rows_ctx);
  if (rc) return setproj_fail(sp, CUP_ERR_CALLBACK, "the rows callback failed (returned %d)", rc);
  if (sp->rb.status == CUP_ERR_NOMEM) return setproj_fail(sp, CUP_ERR_NOMEM, "rows: %s", sp->rb.message);
  if (sp->rb.status) return setproj_fail(sp, CUP_ERR_CALLBACK, "the rows callback gave a bad %s", sp->rb.message);
  sp->rows_now = sp->rb.m;
  int renumbered = 0;
  if (sp->rb.perm ? !sp->ordered || sp->rb.perm_gen != sp->perm_gen : sp->ordered) {
    if (renumber(sp)) return setproj_fail(sp, CUP_ERR_NOMEM, "state polyset: out of memory");
    renumbered = 1;
  }
  int missing = rowpool_match(&sp->pool, &sp->rb, sp->step);
  if (missing < 0) return setproj_fail(sp, CUP_ERR_NOMEM, "state polyset: out of memory");
  if (missing > 0 || !sp->proj || renumbered) {
    int st = rebuild(sp);
    if (st && renumbered) cup_projector_free(&sp->proj);   /* in the old numbering: rebuild next time */
    if (st) return st;
  } else {
    revalue(sp);
  }
  return cup_projector_set_offset(sp->proj, sp->g);
}

/* Rows at (t, x) from the callback, into the pool's polyset and projector. */
static int place(cup_setproj *sp, double t, const double *u, const double *x) {
  (void)u;
  if (!x) return setproj_fail(sp, CUP_ERR_ARG, "a state-dependent set needs the state x");
  return place_rows(sp, t, x, 1);
}

/* The set's recheck of the answer z of the step from x at t (set_impl.h): 1
 * when it missed rows, which are then built again at (t, x) within the same
 * step; 0 when it missed none (or has no recheck); an error status. */
static int recheck(cup_setproj *sp, double t, const double *x, const double *z) {
  const cup_set *S = sp->S;
  if (!S->recheck || !sp->proj) return 0;
  int rc = S->recheck(t, x, z, S->rows_ctx);
  if (rc == CUP_ERR_NOMEM) return setproj_fail(sp, rc, "state polyset: out of memory rechecking the rows");
  if (rc < 0) return setproj_fail(sp, CUP_ERR_CALLBACK, "the recheck of the rows failed (returned %d)", rc);
  if (rc == 0) return 0;
  int st = place_rows(sp, t, x, 0);
  return st ? st : 1;
}

const setproj_kind setproj_state_polyset = {.create = init, .free = free_pool, .place = place, .project = project,
                                            .recheck = recheck};

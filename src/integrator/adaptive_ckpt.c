/* adaptive_ckpt — the event-driven scheme's part of a checkpoint
 * (integrator.h; checkpoint.c writes the header): whether the last run
 * stopped where it can resume, the status the stop replaced, and what a
 * step carries to the next, both ways (util/ckpt.h). */
#include <string.h>
#include "catchup.h"
#include "adaptive.h"
#include "adaptive_impl.h"
#include "projector/projector.h"

int adaptive_stopped(const adaptive_ws *A) { return A->stop->phase != AD_STOP_NONE; }

int adaptive_refused(const adaptive_ws *A) { return A->stop->phase == AD_STOP_SAMPLE || A->stop->phase == AD_STOP_DENSE; }

void adaptive_unstop(const adaptive_ws *A, cup_run_info *info) {
  info->status = A->stop->status;
  memcpy(info->message, A->stop->message, sizeof info->message);
}

/* Everything a step carries to the next: the stopped run's scalars, x and
 * its error, the accumulation ring, the LCPs' and the projector's warm
 * starts, and the kept active sets with their exponentials' step lengths
 * (which ad_flow takes from the cache, or computes another way). */
void adaptive_checkpoint(adaptive_ws *A, ckpt *c) {
  ad_stop *s = A->stop;
  ad_run *R = &s->R;
  size_t N = sizeof(double) * (size_t)A->n, M = (size_t)A->m;
  CUP_CKPT_IO(c, s->phase); CUP_CKPT_IO(c, s->md); CUP_CKPT_IO(c, s->pinned1);
  CUP_CKPT_IO(c, R->t); CUP_CKPT_IO(c, R->tb); CUP_CKPT_IO(c, R->steps); CUP_CKPT_IO(c, R->next_sample);
  CUP_CKPT_IO(c, R->est_max); CUP_CKPT_IO(c, R->r2); CUP_CKPT_IO(c, R->rloc); CUP_CKPT_IO(c, R->h_cb);
  CUP_CKPT_IO(c, R->floor_warned); CUP_CKPT_IO(c, R->tend); CUP_CKPT_IO(c, R->ev0); CUP_CKPT_IO(c, R->after_event);
  ckpt_io(c, A->x, N);
  ckpt_io(c, A->e, N);
  CUP_CKPT_IO(c, s->carry);
  if (s->carry) {                                /* the step's end that the next one starts from */
    if (c->saving && s->md >= 0)                 /* (every row's threshold: ad_events_both's made some) */
      ad_events_thresholds(A, &A->modes[s->md], A->yb, A->tb);
    CUP_CKPT_IO(c, A->carried);
    ckpt_io(c, A->yb, sizeof(double) * (size_t)A->na);
    ckpt_io(c, A->gb, sizeof(double) * M);
    ckpt_io(c, A->tb, sizeof(double) * M);
    ckpt_io(c, A->db, sizeof(double) * M);
  }
  if (s->phase == AD_STOP_SAMPLE && R->steps == 0) ckpt_io(c, A->xok, N);   /* x0's sample: x0 as given */
  if (s->phase == AD_STOP_DENSE) {               /* the refused sample's states, the step's projection */
    struct ad_pend *p = &A->pend;
    size_t NA = sizeof(double) * (size_t)A->na;
    CUP_CKPT_IO(c, s->pi);
    CUP_CKPT_IO(c, p->active); CUP_CKPT_IO(c, p->md); CUP_CKPT_IO(c, p->seg2); CUP_CKPT_IO(c, p->md2);
    CUP_CKPT_IO(c, p->k); CUP_CKPT_IO(c, p->t_end); CUP_CKPT_IO(c, p->t2a); CUP_CKPT_IO(c, p->t2b);
    ckpt_io(c, p->zy, NA);
    ckpt_io(c, p->de, NA);
    ckpt_io(c, p->y2, NA);
    ckpt_io(c, p->e2, N);
    if (A->o.output == CUP_OUTPUT_TOL) {         /* (the refused point's piece: adaptive_outtol.c) */
      CUP_CKPT_IO(c, p->ta); CUP_CKPT_IO(c, p->tr); CUP_CKPT_IO(c, p->with_t0); CUP_CKPT_IO(c, p->with_yb);
      CUP_CKPT_IO(c, p->taylor);
      ckpt_io(c, p->opk, N);
    }
  }
  if (A->o.output == CUP_OUTPUT_TOL) ckpt_io(c, A->opeak, N);   /* output tol's scales */
  ckpt_io(c, A->zeno, sizeof(double) * AD_ZENO_RING); ckpt_io(c, A->zeno_row, sizeof(int) * AD_ZENO_RING); CUP_CKPT_IO(c, A->nzeno); CUP_CKPT_IO(c, A->clock);
  ckpt_io(c, A->lcp.lam, sizeof(double) * M);
  ckpt_io(c, A->lcp.prev, M);
  if (A->has_D) {                                /* the jump's LCP (2 m) warm-starts too */
    ckpt_io(c, A->jlcp.lam, sizeof(double) * 2 * M);
    ckpt_io(c, A->jlcp.prev, 2 * M);
    ckpt_io(c, A->jseed, M);
    CUP_CKPT_IO(c, A->jfrom); CUP_CKPT_IO(c, A->jto); CUP_CKPT_IO(c, A->njump);   /* (its sets tried first) */
    if (!c->saving && A->njump < 0) c->bad = 1;  /* (an index of jump_keep's) */
  }
  lcp_step_checkpoint(&A->proj, c);
  projector_checkpoint(A->projector, c);
  if (!c->saving) A->slots_lost = 0;
  for (int k = 0; k < AD_MODES; k++) {
    ad_mode *md = &A->modes[k];
    uint64_t mask = md->mask;
    long stamp = md->stamp, cstamp[AD_CACHE];
    double hc[AD_CACHE];
    memcpy(hc, md->hc, sizeof hc);
    memcpy(cstamp, md->cstamp, sizeof cstamp);
    CUP_CKPT_IO(c, mask); CUP_CKPT_IO(c, stamp); CUP_CKPT_IO(c, hc); CUP_CKPT_IO(c, cstamp);
    if (!c->saving && !c->bad) ad_mode_restore(A, k, mask, stamp, hc, cstamp);
  }
}

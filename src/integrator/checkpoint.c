/* checkpoint — a stopped run as a byte blob and back (integrator.h). The
 * driver's part is here: a header naming the build and the configuration,
 * and the run's statistics. Each scheme writes its own part through its
 * table (scheme.h): the fixed-step schemes' (fixed_setup.c: where the run
 * stopped, x_k, the projector's part in projector.c, the LCP step's in
 * lcp/step.c), the adaptive scheme's (adaptive_ckpt.c). Every part is one
 * function that reads or writes its fields in one order (util/ckpt.h), so
 * that the size, the save and the restore cannot disagree. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include "catchup.h"
#include "integrator_impl.h"
#include "util/linalg.h"

static const char magic[8] = "cupckpt";
enum { VERSION = 7 };   /* 3: the adaptive scheme keeps 10 active sets (AD_MODES) and, with D, a step's end;
                           4: and the sets its jump's LCP was solved at (AD_JUMPS);
                           5: implicit and exponential, the splitting check's sums;
                           6: output tol (the fingerprint's output_tol, a refused point's piece);
                           7: and that piece's end and middle choices (with_yb, taylor) */

/* What a blob belongs to: restored only into an integrator of the same
 * build (sizes and byte order) and configuration. */
typedef struct fingerprint {
  int32_t endian, sizes, version, scheme, n, m, p, method, output, estimate, f_order, warm_start, theta_step;
  int64_t steps, every, samples;
  double T, h, eps_n, eta_n, theta, tol_abs, tol_rel, max_event_rate, lipschitz, hmax, output_t0, output_tol;
} fingerprint;

static void fingerprint_of(const cup_integrator *I, fingerprint *f) {
  const cup_integrator_options *o = &I->o;
  memset(f, 0, sizeof *f);
  f->endian = 0x01020304;
  f->sizes = (int32_t)(sizeof(long) << 16 | sizeof(double) << 8 | sizeof(int));
  f->version = VERSION;
  f->scheme = (int32_t)o->scheme;
  f->n = I->n; f->m = I->m; f->p = I->p;
  f->method = (int32_t)o->proj.method;
  f->output = (int32_t)o->output;
  f->estimate = o->estimate;
  f->f_order = o->f_order;
  f->warm_start = o->proj.warm_start;
  scheme_grid g = {0, 0, 0, 0};
  if (I->sch->grid) I->sch->grid(I->ws, &g);
  f->theta_step = g.theta_step;
  f->steps = o->n; f->every = o->output_every; f->samples = o->output_samples;
  f->T = o->T; f->h = g.h; f->eps_n = g.eps_n; f->eta_n = g.eta_n; f->theta = o->theta;
  f->tol_abs = o->tol_abs; f->tol_rel = o->tol_rel; f->max_event_rate = o->max_event_rate;
  f->lipschitz = o->proj.lipschitz;
  f->hmax = o->hmax;
  f->output_t0 = o->output_t0;
  f->output_tol = o->output == CUP_OUTPUT_TOL ? o->output_tol : 0;
}

/* The first field that differs, named in errmsg; CUP_OK when none. */
static int same_run(const fingerprint *a, const fingerprint *b, char *errmsg) {
#define CK_INT(f, name) if (a->f != b->f) return fail_fmt(errmsg, CUP_ERR_ARG, "the checkpoint is of another run: " \
  "%s = %lld there, %lld here", name, (long long)a->f, (long long)b->f);
#define CK_DBL(f, name) if (memcmp(&a->f, &b->f, sizeof a->f)) return fail_fmt(errmsg, CUP_ERR_ARG, \
  "the checkpoint is of another run: %s = %.17g there, %.17g here", name, a->f, b->f);
  if (a->endian != b->endian || a->sizes != b->sizes)
    return fail_fmt(errmsg, CUP_ERR_ARG, "the checkpoint was written on another kind of machine");
  CK_INT(version, "its format version") CK_INT(scheme, "scheme") CK_INT(n, "the state dimension")
  CK_INT(m, "the rows") CK_INT(p, "the inputs") CK_INT(method, "projector.method") CK_INT(output, "output")
  CK_INT(estimate, "estimate") CK_INT(f_order, "f_order") CK_INT(warm_start, "projector.warm_start")
  CK_INT(theta_step, "the exact LCP step") CK_INT(steps, "n") CK_INT(every, "output.every")
  CK_INT(samples, "output.samples") CK_DBL(T, "T") CK_DBL(h, "h") CK_DBL(eps_n, "eps_n") CK_DBL(eta_n, "eta_n")
  CK_DBL(theta, "theta") CK_DBL(tol_abs, "tol_abs") CK_DBL(tol_rel, "tol_rel")
  CK_DBL(max_event_rate, "max_event_rate") CK_DBL(lipschitz, "projector.lipschitz") CK_DBL(hmax, "hmax")
  CK_DBL(output_t0, "output_t0") CK_DBL(output_tol, "output.tol")
#undef CK_INT
#undef CK_DBL
  return CUP_OK;
}

static void io_info(ckpt *c, cup_run_info *i) {
  CUP_CKPT_IO(c, i->status); CUP_CKPT_IO(c, i->step); CUP_CKPT_IO(c, i->t); CUP_CKPT_IO(c, i->projected);
  CUP_CKPT_IO(c, i->skipped); CUP_CKPT_IO(c, i->not_certified); CUP_CKPT_IO(c, i->dual_iterations);
  CUP_CKPT_IO(c, i->factorizations); CUP_CKPT_IO(c, i->max_eps_cert); CUP_CKPT_IO(c, i->max_eta_cert);
  CUP_CKPT_IO(c, i->eps_target); CUP_CKPT_IO(c, i->eta_target); CUP_CKPT_IO(c, i->h_rho);
  CUP_CKPT_IO(c, i->samples); CUP_CKPT_IO(c, i->message); CUP_CKPT_IO(c, i->set_rebuilds);
  CUP_CKPT_IO(c, i->max_rows); CUP_CKPT_IO(c, i->err_est); CUP_CKPT_IO(c, i->events);
  CUP_CKPT_IO(c, i->rejected);
}

/* The run's state after the header, both ways. */
static void io_state(cup_integrator *I, ckpt *c, cup_run_info *info) {
  io_info(c, info);
  I->sch->checkpoint(I->ws, c);
}

/* The scheme keeps what a checkpoint needs (a set other than a polyset
 * keeps state of its own, a switched run one integrator a configuration). */
static int saves(const cup_integrator *I) {
  return I->sch->checkpoint && (!I->sch->saves || I->sch->saves(I->ws));
}

/* Header and state into c (a counting stream when c->buf is NULL). */
static int save(const cup_integrator *Ic, const cup_run_info *run, ckpt *c) {
  cup_integrator *I = (cup_integrator *)Ic;      /* saving only reads it */
  if (!I) return CUP_ERR_ARG;
  if (!saves(I)) return CUP_ERR_UNSUPPORTED;
  cup_run_info info = run ? *run : (cup_run_info){0};
  if (!I->sch->stopped(I->ws, &info)) return CUP_ERR_ARG;   /* info: the status the stop replaced */
  fingerprint f;
  fingerprint_of(I, &f);
  ckpt_io(c, (void *)magic, sizeof magic);
  CUP_CKPT_IO(c, f);
  io_state(I, c, &info);
  return c->bad ? CUP_ERR_ARG : CUP_OK;
}

long cup_integrator_checkpoint_size(const cup_integrator *I) {
  ckpt c = {NULL, 0, 0, 1, 0};
  int st = save(I, NULL, &c);
  return st ? st : (long)c.len;
}

int cup_integrator_checkpoint_save(const cup_integrator *I, const cup_run_info *info, void *buf,
                                   unsigned long size) {
  if (!buf || !info) return CUP_ERR_ARG;
  ckpt c = {buf, 0, size, 1, 0};
  return save(I, info, &c);
}

int cup_integrator_checkpoint_restore(cup_integrator *I, const void *buf, unsigned long size, char *errmsg) {
  if (!I || !buf) return fail_fmt(errmsg, CUP_ERR_ARG, "checkpoint: NULL argument");
  if (!saves(I))
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED, "checkpoint: a run of this kind of set (or with switches) cannot "
                    "be resumed");
  ckpt c = {(unsigned char *)buf, 0, size, 0, 0};
  char m[sizeof magic];
  fingerprint have, want;
  ckpt_io(&c, m, sizeof m);
  CUP_CKPT_IO(&c, have);
  if (c.bad || memcmp(m, magic, sizeof m))
    return fail_fmt(errmsg, CUP_ERR_ARG, "not a catchup checkpoint (%lu bytes)", size);
  fingerprint_of(I, &want);
  int st = same_run(&have, &want, errmsg);
  if (st) return st;
  if (!I->restored_info && !(I->restored_info = malloc(sizeof *I->restored_info)))
    return fail_fmt(errmsg, CUP_ERR_NOMEM, "checkpoint: out of memory");
  io_state(I, &c, I->restored_info);
  if (c.bad || c.len != size)
    return fail_fmt(errmsg, CUP_ERR_ARG, "the checkpoint is %lu bytes, a run like this one's is %zu: cut short, "
                    "or of another build", size, c.len);
  I->restored = 1;
  return CUP_OK;
}

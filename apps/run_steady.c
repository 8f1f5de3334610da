/* run_steady — catchup-run --steady-state (run_steady.h, docs/steady-state.md):
 * solved as a steady-state sweep's task is (io/scene_pss.h), the period
 * then catchup-run's own run (streamed to its file with its signals and
 * events), its samples measured as a task's are (pss_measure). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include "run_steady.h"
#include "analysis/pss_run.h"
#include "io/scene_pss.h"

enum { MSG = 2 * CUP_ERRMSG_LEN };

struct run_steady {
  const cup_scene_steady *req;
  cup_pss *r;
  cup_pss_info info;
  int asked, solved;        /* solved: the run is one period from the steady state */
  char message[MSG];        /* why there is no steady state, or "" */
  int n, ns;                /* state dimension, the run's signals */
  cup_netlist *nl;
  int nm, *mi;              /* measured: signal indices (nl), or state columns (mi NULL) */
  int *pv, *pc;             /* power: each element's v(a,b) and i(E) signal */
  long N, k;                /* samples expected and recorded */
  double *t, *x, *sig;      /* N x n, N x ns */
  pss_jumps jumps;          /* the period's switchings and events (its run's integrator notes them) */
  /* the measurements: nm rows, harmonics + 1 columns; power per element */
  cup_measure *me;
  double *amp, *phase, *power, efficiency;
};

run_steady *run_steady_new(const cup_scene *scene) {
  const cup_scene_steady *req = cup_scene_steady_state(scene);
  if (!req) return NULL;
  run_steady *s = calloc(1, sizeof *s);
  if (!s) return NULL;
  s->req = req;
  s->n = cup_scene_dim(scene);
  s->efficiency = NAN;
  s->info.max_multiplier = NAN;
  return s;
}

void run_steady_free(run_steady **sp) {
  if (!sp || !*sp) return;
  run_steady *s = *sp;
  cup_pss_free(&s->r);
  free(s->mi); free(s->pv); free(s->pc);
  free(s->t); free(s->x); free(s->sig);
  free(s->me); free(s->amp); free(s->phase); free(s->power);
  pss_jumps_free(&s->jumps);
  free(s);
  *sp = NULL;
}

int run_steady_probes(run_steady *s, cup_netlist *nl, char *err, size_t size) {
  const cup_scene_steady *q = s->req;
  char e2[CUP_ERRMSG_LEN];
  s->nl = nl;
  int own = cup_netlist_signal_count(nl);       /* the run's own signals: measured when none is named */
  s->nm = q->nmeasure ? q->nmeasure : own;
  s->mi = calloc((size_t)s->nm + 1, sizeof *s->mi);
  s->pv = calloc((size_t)q->npower + 1, sizeof *s->pv);
  s->pc = calloc((size_t)q->npower + 1, sizeof *s->pc);
  if (!s->mi || !s->pv || !s->pc) return snprintf(err, size, "out of memory"), 1;
  for (int k = 0; k < s->nm; k++) {
    s->mi[k] = q->nmeasure ? cup_netlist_probe(nl, q->measure[k], e2) : k;
    if (s->mi[k] < 0) return snprintf(err, size, "steady_state.measure: %s", e2), 1;
  }
  for (int k = 0; k < q->npower; k++)
    if (pss_probe_power(nl, q->power[k], &s->pv[k], &s->pc[k], e2))
      return snprintf(err, size, "steady_state.power: %s", e2), 1;
  return 0;
}

/* No steady state: the transient instead (0, a warning in err) or an error. */
static int no_steady(run_steady *s, int st, const char *why, char *err, size_t size) {
  s->info.status = st;
  snprintf(s->message, sizeof s->message, "%s", why);
  if (s->req->fallback) {
    snprintf(err, size, "steady state: %s: %s; the transient instead (steady_state.fallback: false makes this an "
             "error)", cup_status_name(st), why);
    return 0;
  }
  snprintf(err, size, "steady state: %s: %s", cup_status_name(st), why);
  return 1;
}

int run_steady_solve(run_steady *s, cup_scene *scene, cup_integrator_options *o, char *err, size_t size) {
  char e2[MSG] = "";
  s->asked = 1;
  cup_integrator_options period;
  int stage;                                     /* (the message says which) */
  int st = scene_pss_solve(scene, o, &s->r, &s->info.period, &s->info.t0, &period, &stage, e2);
  double t0 = s->info.t0;
  if (s->r) cup_pss_get_info(s->r, &s->info);
  s->info.t0 = t0;
  if (st < 0 || !s->r) return no_steady(s, st, s->r ? s->info.message : e2, err, size);
  snprintf(s->message, sizeof s->message, "%s", s->info.message);
  s->solved = 1;
  *o = period;                                   /* the run: one period from the steady state */
  s->N = s->req->samples;
  s->ns = s->nl ? cup_netlist_signal_count(s->nl) : 0;
  s->t = calloc((size_t)s->N, sizeof *s->t);
  s->x = calloc((size_t)s->N * (size_t)s->n, sizeof *s->x);
  s->sig = calloc((size_t)s->N * (size_t)(s->ns + 1), sizeof *s->sig);
  if (!s->t || !s->x || !s->sig || pss_jumps_init(&s->jumps, s->info.period, s->N))
    return snprintf(err, size, "out of memory for the period's samples"), 1;
  return 0;
}

int run_steady_integrator(run_steady *s, cup_scene *scene, const cup_integrator_options *o, cup_integrator **I,
                          char *errmsg) {
  if (!s || !s->solved) return cup_scene_integrator(scene, o, I, errmsg);
  return scene_pss_period_integrator(scene, o, &s->jumps, I, errmsg);
}

double run_steady_t0(const run_steady *s) { return s && s->solved ? s->info.t0 : 0; }

const double *run_steady_x0(const run_steady *s, const double *scene_x0) {
  return s && s->solved ? cup_pss_x0(s->r) : scene_x0;
}

void run_steady_record(run_steady *s, double t, const double *x, const double *sig) {
  if (!s->solved || s->k >= s->N) return;
  s->t[s->k] = t;
  memcpy(s->x + (size_t)s->k * s->n, x, sizeof(double) * (size_t)s->n);
  if (sig && s->ns) memcpy(s->sig + (size_t)s->k * s->ns, sig, sizeof(double) * (size_t)s->ns);
  s->k++;
}

/* ---- measurements ---- */

static const char *measured_name(const run_steady *s, int j, char *buf, size_t size, const cup_scene *scene,
                                 const char **unit) {
  if (s->nl) {
    *unit = cup_netlist_signal_unit(s->nl, s->mi[j]);
    return cup_netlist_signal_name(s->nl, s->mi[j]);
  }
  cup_scene_state_label(scene, j, buf, size, unit);
  return buf;
}

/* Each measured signal's figures and harmonics, each element's power. */
static int measure(run_steady *s) {
  int H = s->req->harmonics, nm = s->nl ? s->nm : s->n, np = s->req->npower;
  char e2[CUP_ERRMSG_LEN];
  s->me = calloc((size_t)nm + 1, sizeof *s->me);
  s->amp = calloc(((size_t)nm + 1) * (size_t)(H + 1), sizeof *s->amp);
  s->phase = calloc(((size_t)nm + 1) * (size_t)(H + 1), sizeof *s->phase);
  s->power = calloc((size_t)np + 1, sizeof *s->power);
  double *w = calloc((size_t)s->N, sizeof *w);
  int st = !s->me || !s->amp || !s->phase || !s->power || !w ? CUP_ERR_NOMEM : CUP_OK;
  pss_figures f = {nm, s->nl ? s->mi : NULL, H, np, s->pv, s->pc, s->req->eff_out, s->req->eff_in, s->me, s->amp,
                       s->phase, s->power, s->efficiency, NULL, 0, 0, 0};
  pss_jumps_finish(&s->jumps, &f);
  if (!st) st = s->nl ? pss_measure(s->sig, s->N, s->ns, &f, w, e2) : pss_measure(s->x, s->N, s->n, &f, w, e2);
  s->efficiency = f.efficiency;
  free(w);
  return st;
}

/* ---- /steady_state ---- */

static int array(cup_h5run *w, const char *name, int rank, long d0, long d1, const double *v, const char *units,
                 const char *what, const char *const *dims) {
  long d[2] = {d0, d1};
  int st = cup_h5run_array(w, name, rank, d, v);
  if (dims) st = cup_status_merge(st, cup_h5run_dims(w, name, dims));
  return cup_status_merge(st, cup_h5run_describe(w, name, units, what));
}

/* "V, A, V": the units of the measured signals (one when all agree). */
static char *units_of(const run_steady *s, const cup_scene *scene, int nm) {
  size_t len = 1, cap = 8 * (size_t)nm + 16;
  char *u = malloc(cap), buf[128];
  const char *first = NULL, *unit;
  int same = 1;
  if (!u) return NULL;
  u[0] = '\0';
  for (int j = 0; j < nm; j++) {
    measured_name(s, j, buf, sizeof buf, scene, &unit);
    if (!first) first = unit;
    same &= !strcmp(first, unit);
    if (len + strlen(unit) + 3 > cap) break;
    len += (size_t)snprintf(u + len - 1, cap - len + 1, "%s%s", j ? ", " : "", unit);
  }
  if (same && first) snprintf(u, cap, "%s", first);
  return u;
}

static int write_measures(run_steady *s, cup_h5run *w, const cup_scene *scene) {
  int H = s->req->harmonics, nm = s->nl ? s->nm : s->n, np = s->req->npower, st = CUP_OK;
  const char **names = calloc((size_t)nm + 1, sizeof *names);
  char (*bufs)[128] = calloc((size_t)nm + 1, sizeof *bufs), *u = units_of(s, scene, nm);
  double *col = calloc((size_t)nm + 1, sizeof *col), *hk = calloc((size_t)H + 1, sizeof *hk);
  if (!names || !bufs || !u || !col || !hk) st = CUP_ERR_NOMEM;
  const char *unit;
  for (int j = 0; !st && j < nm; j++) names[j] = measured_name(s, j, bufs[j], sizeof bufs[j], scene, &unit);
  static const char *const sig[] = {"signal", NULL};
  if (!st && nm) {
    st = cup_h5run_strings(w, "steady_state/measure/signal", nm, names);
    st = cup_status_merge(st, cup_h5run_describe(w, "steady_state/measure/signal", NULL, "the signals measured"));
    static const struct { const char *name, *what; size_t off; } f[] = {
      {"average", "average over the period", offsetof(cup_measure, avg)},
      {"rms", "RMS over the period", offsetof(cup_measure, rms)},
      {"min", "minimum over the period", offsetof(cup_measure, min)},
      {"max", "maximum over the period", offsetof(cup_measure, max)},
      {"peak_to_peak", "peak-to-peak over the period", offsetof(cup_measure, pp)}};
    for (size_t q = 0; q < sizeof f / sizeof f[0]; q++) {
      char path[96];
      for (int j = 0; j < nm; j++) col[j] = *(const double *)((const char *)&s->me[j] + f[q].off);
      snprintf(path, sizeof path, "steady_state/measure/%s", f[q].name);
      st = cup_status_merge(st, array(w, path, 1, nm, 0, col, u, f[q].what, sig));
    }
    for (int j = 0; j < nm; j++) col[j] = s->me[j].thd;
    st = cup_status_merge(st, array(w, "steady_state/measure/thd", 1, nm, 0, col, "1",
                                    "total harmonic distortion sqrt(sum_{k>=2} A_k^2) / A_1 (harmonics up to the order)",
                                    sig));
  }
  if (!st && nm && H > 0) {
    for (int k = 0; k <= H; k++) hk[k] = k;
    static const char *const sh[] = {"signal", "harmonic", NULL};
    st = array(w, "steady_state/measure/harmonic", 1, H + 1, 0, hk, "1", "harmonic order k (frequency k / T)", NULL);
    st = cup_status_merge(st, array(w, "steady_state/measure/amplitude", 2, nm, H + 1, s->amp, u,
                                    "harmonic amplitude A_k: v ~ sum_k A_k cos(2 pi k t / T + phase_k), A_0 the average",
                                    sh));
    st = cup_status_merge(st, array(w, "steady_state/measure/phase", 2, nm, H + 1, s->phase, "rad",
                                    "harmonic phase phase_k (of the cosine, t from the period's start)", sh));
  }
  if (!st && np) {
    static const char *const el[] = {"element", NULL};
    st = cup_h5run_strings(w, "steady_state/power/element", np, s->req->power);
    st = cup_status_merge(st, array(w, "steady_state/power/average", 1, np, 0, s->power, "W",
                                    "average power absorbed, v(a,b) i(E) over the period (a source's delivered "
                                    "power is negative)", el));
  }
  if (!st && s->req->eff_out >= 0)
    st = array(w, "steady_state/efficiency", 1, 1, 0, &s->efficiency, "1",
               "efficiency: the output element's absorbed power over the power the input delivers", NULL);
  free(names); free(bufs); free(u); free(col); free(hk);
  return st;
}

int run_steady_write(run_steady *s, cup_h5run *w, const cup_scene *scene, int run_status) {
  if (!s || !s->asked) return CUP_OK;
  int n = s->n, st = cup_h5run_attr_long(w, "steady_state_status", s->info.status);
  st = cup_status_merge(st, cup_h5run_attr_string(w, "steady_state_status_name", cup_status_name(s->info.status)));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "steady_state_message", s->message));
  st = cup_status_merge(st, cup_h5run_attr_long(w, "steady_state_solved", s->solved));
  double per = s->info.period, it = s->info.iterations, runs = (double)s->info.period_runs;
  st = cup_status_merge(st, array(w, "steady_state/period", 1, 1, 0, &per, "s", "the period T", NULL));
  if (s->info.t0 != 0)                           /* written only where it is not 0: files as before otherwise */
    st = cup_status_merge(st, array(w, "steady_state/t0", 1, 1, 0, &s->info.t0, "s",
                                    "the phase t0 (absent: 0): the sources repeat from t0 on; x0 is the state at t0, /t runs "
                                    "over [t0, t0 + T] of the sources as written", NULL));
  if (!s->r) return st;
  static const char *const sd[] = {"state", NULL};
  st = cup_status_merge(st, array(w, "steady_state/iterations", 1, 1, 0, &it, "1", "Newton steps taken", NULL));
  st = cup_status_merge(st, array(w, "steady_state/period_runs", 1, 1, 0, &runs, "1",
                                  "runs of the period map (the Jacobians' included)", NULL));
  st = cup_status_merge(st, array(w, "steady_state/x0", 1, n, 0, cup_pss_x0(s->r), NULL,
                                  "the steady state x(0) = x(T) (the last iterate when not solved)", sd));
  st = cup_status_merge(st, array(w, "steady_state/residuals", 1, s->info.iterations + 1, 0, cup_pss_residuals(s->r),
                                  NULL, "Newton residual ||Phi(x_k) - x_k||_inf per iterate (the state's units)",
                                  NULL));
  double *re = calloc((size_t)n, sizeof *re), *im = calloc((size_t)n, sizeof *im);
  double *J = calloc((size_t)n * n, sizeof *J);
  if (!re || !im || !J) st = CUP_ERR_NOMEM;
  if (!st && cup_pss_multipliers(s->r, re, im) == CUP_OK) {
    const double *M = cup_pss_monodromy(s->r);
    for (int i = 0; i < n; i++)
      for (int j = 0; j < n; j++) J[(size_t)i * n + j] = M[i + (size_t)j * n];   /* row-major */
    st = cup_status_merge(st, array(w, "steady_state/multipliers_re", 1, n, 0, re, "1",
                                    "Floquet multipliers, real part (by decreasing modulus)", NULL));
    st = cup_status_merge(st, array(w, "steady_state/multipliers_im", 1, n, 0, im, "1",
                                    "Floquet multipliers, imaginary part", NULL));
    st = cup_status_merge(st, array(w, "steady_state/monodromy", 2, n, n, J, "1",
                                    "monodromy matrix dPhi/dx0 (the adaptive tangent with D = 0, else finite differences)", NULL));
  }
  free(re); free(im); free(J);
  if (!st && s->solved && run_status >= 0 && s->k == s->N) {
    st = measure(s);
    if (!st) st = write_measures(s, w, scene);
    if (!st)                                     /* -1: more than 4 a sample, none placed (the warning printed) */
      st = cup_h5run_attr_long(w, "steady_state_measure_jumps", s->jumps.overflow ? -1 : s->jumps.n);
  }
  return st;
}

/* ---- the summary ---- */

void run_steady_report(const run_steady *s, const char *scene, FILE *f) {
  if (!s || !s->asked) return;
  const cup_pss_info *i = &s->info;
  char res[160] = "", mu[200] = "";
  size_t len = 0;
  const double *r = s->r ? cup_pss_residuals(s->r) : NULL;
  for (int k = 0; r && k <= i->iterations && len < sizeof res; k++)
    len += (size_t)snprintf(res + len, sizeof res - len, "%s%.2g", k ? ", " : "", r[k]);
  double *re = calloc((size_t)s->n + 1, sizeof *re), *im = calloc((size_t)s->n + 1, sizeof *im);
  int n = s->n < 8 ? s->n : 8;
  len = 0;
  if (s->r && re && im && cup_pss_multipliers(s->r, re, im) == CUP_OK)
    for (int k = 0; k < n && len < sizeof mu; k++)
      len += im[k] ? (size_t)snprintf(mu + len, sizeof mu - len, "%s%.6g%+.6gi", k ? ", " : "", re[k], im[k])
                   : (size_t)snprintf(mu + len, sizeof mu - len, "%s%.6g", k ? ", " : "", re[k]);
  free(re);
  free(im);
  if (!s->solved) {
    fprintf(f, "catchup-run: %s: steady state: none (%s), after %d Newton steps (residuals %s)%s%s; the transient "
            "was run instead\n", scene, cup_status_name(i->status), i->iterations, res[0] ? res : "-",
            mu[0] ? ", multipliers " : "", mu);
    return;
  }
  char phase[64] = "";
  if (i->t0 != 0) snprintf(phase, sizeof phase, " from t0 = %.6g s (the sources repeat from there)", i->t0);
  fprintf(f, "catchup-run: %s: steady state: period %.6g s%s, %d Newton steps (residuals %s), %ld period runs, "
          "%.3g s; Floquet multipliers %s%s (largest modulus %.6g: %s): %s\n", scene, i->period, phase, i->iterations, res,
          i->period_runs, i->seconds, mu, s->n > 8 ? ", ..." : "", i->max_multiplier,
          i->max_multiplier < 1 - 1e-6 ? "stable" : "not asymptotically stable", cup_status_name(i->status));
  if (!s->me) return;
  int nm = s->nl ? s->nm : s->n;
  for (int j = 0; j < nm && j < 32; j++) {
    char buf[128];
    const char *unit, *name = s->nl ? cup_netlist_signal_name(s->nl, s->mi[j]) : buf;
    if (s->nl) unit = cup_netlist_signal_unit(s->nl, s->mi[j]);
    else snprintf(buf, sizeof buf, "x%d", j + 1), unit = "";
    const cup_measure *m = &s->me[j];
    char thd[32] = "-";
    if (!isnan(m->thd)) snprintf(thd, sizeof thd, "%.4g %%", 100 * m->thd);
    fprintf(f, "catchup-run: %s:   %-14s avg %-11.6g rms %-11.6g min %-11.6g max %-11.6g p-p %-11.6g %s, THD %s\n",
            scene, name, m->avg, m->rms, m->min, m->max, m->pp, unit, thd);
  }
  for (int j = 0; j < s->req->npower; j++)
    fprintf(f, "catchup-run: %s:   power %-8s %.6g W\n", scene, s->req->power[j], s->power[j]);
  if (!isnan(s->efficiency)) fprintf(f, "catchup-run: %s:   efficiency %.6g\n", scene, s->efficiency);
  if (s->jumps.overflow)
    fprintf(f, "catchup-run: warning: %s: more than %ld switchings and events in the period, 4 a sample: the "
            "measurements take no jump at its time (O(h) where a signal jumps; raise steady_state.samples)\n", scene,
            s->jumps.cap);
}

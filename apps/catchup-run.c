/* catchup-run — run one scene; write its trajectory and what ran to HDF5.
 *
 *   catchup-run SCENE.yaml -o OUT.h5 [--n N | --h STEP] [--eps SPEC] [--eta SPEC]
 *               [--scheme NAME] [--projector NAME] [--tol TOL] [--estimate]
 *               [--set key=value]... [--quiet]
 *   catchup-run CIRCUIT.cir -o OUT.h5 [--probe SIGNAL]... [the same options]
 *
 * A netlist (.cir, .sp, .spi, .spice, .net, .ckt) runs as the scene
 * `netlist: CIRCUIT.cir`; its signals (node voltages, branch currents) go
 * to /signals/<name>.
 *
 * Exit status: 0 success (a warning status is reported in one stderr line),
 * 1 scene, run or I/O error, 2 usage error; every failure is one stderr line
 * naming the file, the key and the problem. SIGINT/SIGTERM stop the run at
 * the next sample, the file is closed with everything computed so far and
 * status CUP_ERR_INTERRUPTED, and the program then ends by that signal (so
 * that shells and make see the interruption); a second signal ends it at
 * once. Nothing computed is lost on an error: the samples before it are in
 * the file, closed cleanly with the status attributes. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <sys/stat.h>
#include "catchup.h"
#include "catchup/h5run.h"
#include "crowd_log.h"
#include "run_args.h"
#include "run_plan.h"
#include "run_stop.h"
#include "stop_signal.h"
#include "heap_pad.h"
#include "io/read_text.h"
#include "util/clock.h"
#include "util/path.h"
#include "run_steady.h"
#include "integrator/record.h"
#include "h5/h5run_rows.h"

enum { MSG_LEN = 2 * CUP_ERRMSG_LEN };     /* a path, then a library message, whole */

/* ---- signals: stop_signal (stop_signal.h), which the sink reads ---- */

/* A netlist's signals need zeta of the step that reached x (the diodes'
 * currents and voltages) and u(t): computed here, written beside x. */
typedef struct {
  cup_h5run *w;
  cup_netlist *nl;           /* NULL: no signals */
  const cup_integrator *I;
  double *zeta, *sig;
  run_steady *steady;        /* --steady-state: the period's samples kept for its measurements */
  double t0;                 /* --steady-state: the period's phase; the samples written at t0 + t */
} sink_t;

/* Test hook (docs/run-output.md): CATCHUP_RUN_TEST_SIGNAL=K raises SIGINT
 * at the K-th sample this process writes (0: before the run), as a user's
 * Ctrl-C would arrive there. */
static long hook_at = -1, hook_seen;

static int sink(long k, double t, const double *x, void *ctx) {
  if (hook_at > 0 && ++hook_seen == hook_at) raise(SIGINT);
  if (stop_signal) return 1;
  sink_t *c = ctx;
  if (!c->nl) {
    if (c->steady) run_steady_record(c->steady, c->t0 + t, x, NULL);
    return cup_h5run_sink(k, c->t0 + t, x, c->w);
  }
  const signal_map *map = nl_signal_map(c->nl);   /* (a sample inside a step: from the scheme's own state) */
  if (!map || !integrator_record(c->I, map, c->sig)) {
    cup_integrator_zeta(c->I, c->zeta);
    if (cup_netlist_signals(c->nl, t, x, c->zeta, c->sig) != CUP_OK) return CUP_ERR_CALLBACK;
  }
  if (c->steady) run_steady_record(c->steady, c->t0 + t, x, c->sig);
  return cup_h5run_append(c->w, c->t0 + t, x, c->sig);
}

/* The samples whose signals the scheme computed (integrator_set_put),
 * count of them: what sink does after integrator_record, sample by sample
 * (the test hook, then a stop refuses), without --steady-state (whose
 * samples sink keeps; t0 is 0 here). */
static __attribute__((noinline)) int put_rows(sink_t *c, int count, const double *t, const double *x,
                                              const double *sig, int stride) {
  int j = 0, done = 0;
  if (hook_at <= 0) j = stop_signal ? 0 : count;   /* (no hook: one look at the flag a batch) */
  else
    for (; j < count; j++) {
      if (++hook_seen == hook_at) raise(SIGINT);
      if (stop_signal) break;
    }
  h5run_append_rows(c->w, j, t, x, sig, stride, &done);
  return done;
}

static int put(void *ctx, long k, int count, const double *t, const double *x, const double *sig, int stride) {
  (void)k;
  sink_t *c = ctx;
  if (count == 1 && hook_at <= 0) {              /* (a step's end, as h5run_append_rows' one row) */
    if (stop_signal) return 0;
    return h5run_take_row(c->w, *t, x, sig, stride);   /* (its answer put's: a jump, no frame) */
  }
  return put_rows(c, count, t, x, sig, stride);
}

/* ---- the run ---- */

typedef struct {
  const run_args *args;
  cup_scene *scene;
  cup_integrator_options opts;
  cup_integrator *I;
  cup_h5run *w;
  crowd_log *crowd;          /* a crowd scene's per-step log, or NULL */
  cup_run_info info;
  sink_t sk;
  double wall;               /* seconds in cup_integrator_run */
  double wall_before;        /* --resume: the seconds of the run before its stop */
  int resumable;             /* stopped by a signal, with a checkpoint saved */
  int status;
  char message[MSG_LEN];
  char warnings[2 * MSG_LEN]; /* the model's (model_warnings), one a line */
} run_t;

/* The writer is created after the integrator (a scene that cannot run must
 * not replace the output file): events reach it through the run. */
static int event_sink(double t, int row, int on, void *ctx) {
  const run_t *r = ctx;
  return r->w ? cup_h5run_event(r->sk.t0 + t, row, on, r->w) : 0;
}


/* The schedule as the scene wrote it, or in canonical form if it did not. */
static const char *spec_text(const char *spec, const cup_schedule *s, char *buf, size_t size) {
  if (spec && spec[0]) return spec;
  cup_schedule_format(s, buf, size);
  return buf;
}

/* Joins n strings with ", " (NULL when out of memory). */
static char *join(int n, char *const *v) {
  size_t len = 1;
  for (int j = 0; j < n; j++) len += strlen(v[j]) + 2;
  char *s = malloc(len);
  if (!s) return NULL;
  s[0] = '\0';
  for (int j = 0, w = 0; j < n; j++) w += snprintf(s + w, len - (size_t)w, "%s%s", j ? ", " : "", v[j]);
  return s;
}

/* /x's columns: /state (the names, /x's second dimension), the attribute
 * state_names ("q(C4), i(L3), i(L2)") and /x's units: the one unit of
 * every column, or the columns' units in order ("C, A, A"). */
static int describe_state(run_t *r) {
  cup_h5run *w = r->w;
  int n = cup_scene_dim(r->scene), same = 1, st = CUP_ERR_NOMEM;
  char **names = calloc((size_t)n, sizeof *names), **units = calloc((size_t)n, sizeof *units), *joined = NULL;
  for (int j = 0; names && units && j < n; j++) {
    char buf[128];
    const char *u = "1";
    cup_scene_state_label(r->scene, j, buf, sizeof buf, &u);
    names[j] = strdup(buf);
    units[j] = (char *)u;
    same &= !strcmp(u, units[0]);
    if (!names[j]) goto done;
  }
  if (!names || !units || !(joined = join(n, names))) goto done;
  st = cup_h5run_attr_string(w, "state_names", joined);
  st = cup_status_merge(st, cup_h5run_strings(w, "state", n, (const char *const *)names));
  st = cup_status_merge(st, cup_h5run_describe(w, "state", NULL, "state component: the columns of /x"));
  free(joined);
  joined = same ? NULL : join(n, units);
  if (!same && !joined) { st = CUP_ERR_NOMEM; goto done; }
  st = cup_status_merge(st, cup_h5run_describe(w, "x", same ? units[0] : joined, "state x(t)"));
  st = cup_status_merge(st, cup_h5run_dims(w, "x", (const char *const[]){"t", "state"}));
done:
  for (int j = 0; names && j < n; j++) free(names[j]);
  free(names);
  free(units);
  free(joined);
  return st;
}

/* Self-describing output, in the conventions of netCDF-4 and CF: every
 * dataset has `units` and `long_name`, and /t is the dimension scale of
 * /x's and every signal's first dimension, so that xarray opens the file
 * (engine="h5netcdf") with named dimensions. A netlist's text is kept. */
static int describe_run(run_t *r) {
  cup_h5run *w = r->w;
  int st = cup_h5run_describe(w, "t", "s", "time");
  st = cup_status_merge(st, describe_state(r));
  st = cup_status_merge(st, cup_h5run_dims(w, "events", (const char *const[]){"event"}));
  st = cup_status_merge(st, cup_h5run_describe(w, "events", NULL,
         "changes of the active set (adaptive scheme): t [s], row (0-based), on (1: becomes active)"));
  const cup_netlist *nl = r->sk.nl;
  for (int k = 0; nl && k < cup_netlist_signal_count(nl); k++) {
    char path[300], what[300];
    const char *name = cup_netlist_signal_name(nl, k), *unit = cup_netlist_signal_unit(nl, k);
    snprintf(path, sizeof path, "signals/%.250s", name);
    snprintf(what, sizeof what, "%s %.250s", !strcmp(unit, "V") ? "voltage" : "current", name);
    st = cup_status_merge(st, cup_h5run_dims(w, path, (const char *const[]){"t"}));
    st = cup_status_merge(st, cup_h5run_describe(w, path, unit, what));
  }
  if (cup_scene_netlist(r->scene))
    st = cup_status_merge(st, cup_h5run_attr_string(w, "netlist", cup_netlist_source(cup_scene_netlist(r->scene))));
  return st;
}

/* What ran: written before the run so that even a killed run's file says it.
 * The attribute calls record their first failure in the writer; the status
 * of the last one is enough to know that one failed. */
static int write_provenance(run_t *r) {
  cup_h5run *w = r->w;
  const cup_integrator_options *o = &r->opts;
  char deps[512], h5[64], eps[64], eta[64];
  int n = cup_dependency_versions(deps, sizeof deps);
  cup_h5_version(h5, sizeof h5);
  if (n >= 0 && (size_t)n < sizeof deps) snprintf(deps + n, sizeof deps - (size_t)n, "; %s", h5);
  int st = cup_h5run_attr_long(w, "n", o->n);
  st = cup_status_merge(st, cup_h5run_attr_double(w, "T", o->T));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "eps",
         spec_text(cup_scene_eps_spec(r->scene), &o->eps, eps, sizeof eps)));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "eta",
         spec_text(cup_scene_eta_spec(r->scene), &o->eta, eta, sizeof eta)));
  st = cup_status_merge(st, cup_h5run_attr_double(w, "eps_value", cup_schedule_value(&o->eps, o->n)));
  st = cup_status_merge(st, cup_h5run_attr_double(w, "eta_value", cup_schedule_value(&o->eta, o->n)));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "scheme", cup_scheme_name(o->scheme)));
  st = cup_status_merge(st, cup_h5run_attr_double(w, "tol_abs", o->tol_abs));
  st = cup_status_merge(st, cup_h5run_attr_double(w, "tol_rel", o->tol_rel));
  st = cup_status_merge(st, cup_h5run_attr_long(w, "estimate", o->estimate || o->scheme == CUP_SCHEME_ADAPTIVE));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "projector", cup_proj_method_name(o->proj.method)));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "output", cup_output_name(o->output)));
  if (o->output == CUP_OUTPUT_TOL)                 /* (docs/run-output.md: what the points are within) */
    st = cup_status_merge(st, cup_h5run_attr_double(w, "output_tol", o->output_tol));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "catchup_version", cup_version()));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "dependency_versions", deps));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "scene", cup_scene_text(r->scene)));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "scene_file", r->args->scene));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "scene_name", cup_scene_name(r->scene)));
  char *inputs = file_list_text(scene_file_list(r->scene));   /* for --resume, and sha256sum -c */
  st = cup_status_merge(st, inputs ? cup_h5run_attr_string(w, "inputs_sha256", inputs) : CUP_ERR_NOMEM);
  free(inputs);
  st = cup_status_merge(st, describe_run(r));
  /* Overwritten at the end; what a reader finds if the process was killed. */
  st = cup_status_merge(st, cup_h5run_attr_long(w, "status", CUP_ERR_INTERRUPTED));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "status_name", "running"));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "message",
         "the run did not finish: the process ended before closing the file; "
         "/t and /x hold the samples up to its last flush"));
  return cup_status_merge(st, cup_h5run_flush(w));
}

static int write_results(run_t *r) {
  cup_h5run *w = r->w;
  const cup_run_info *i = &r->info;
  int st = cup_h5run_attr_double(w, "wall_time_s", r->wall_before + r->wall);
  st = cup_status_merge(st, cup_h5run_attr_long(w, "projected", i->projected));
  st = cup_status_merge(st, cup_h5run_attr_long(w, "skipped", i->skipped));
  st = cup_status_merge(st, cup_h5run_attr_long(w, "not_certified", i->not_certified));
  st = cup_status_merge(st, cup_h5run_attr_long(w, "dual_iterations", (long)i->dual_iterations));
  st = cup_status_merge(st, cup_h5run_attr_long(w, "factorizations", i->factorizations));
  st = cup_status_merge(st, cup_h5run_attr_double(w, "max_eps_cert", i->max_eps_cert));
  st = cup_status_merge(st, cup_h5run_attr_double(w, "max_eta_cert", i->max_eta_cert));
  st = cup_status_merge(st, cup_h5run_attr_double(w, "h_rho", i->h_rho));
  st = cup_status_merge(st, cup_h5run_attr_double(w, "err_est", i->err_est));
  st = cup_status_merge(st, cup_h5run_attr_long(w, "events", i->events));
  st = cup_status_merge(st, cup_h5run_attr_long(w, "rejected", i->rejected));
  st = cup_status_merge(st, cup_h5run_attr_long(w, "samples", cup_h5run_count(w)));
  st = cup_status_merge(st, cup_h5run_attr_long(w, "stopped_step", i->step));
  st = cup_status_merge(st, cup_h5run_attr_double(w, "stopped_t", i->t));
  st = cup_status_merge(st, cup_h5run_attr_long(w, "status", r->status));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "status_name", cup_status_name(r->status)));
  st = cup_status_merge(st, cup_h5run_attr_string(w, "warnings", r->warnings));
  return cup_status_merge(st, cup_h5run_attr_string(w, "message", r->message));
}

/* The writer's first failure's words into err (MSG_LEN bytes), "" if none. */
static void writer_words(const cup_h5run *w, char *err) {
  err[0] = '\0';
  if (w) cup_h5run_status(w, err);
}

/* Turn the integrator's status into the run's: a stop requested by the sink
 * is either our signal or a write that failed (the writer knows which). */
static void settle_status(run_t *r, int st) {
  r->status = st;
  snprintf(r->message, sizeof r->message, "%s", r->info.message);
  if (st != CUP_ERR_INTERRUPTED) {
    if (st != CUP_OK && !r->message[0]) snprintf(r->message, sizeof r->message, "%s", cup_status_string(st));
    return;
  }
  if (stop_signal) {
    snprintf(r->message, sizeof r->message, "stopped by %s at step %ld (t = %.17g)",
             stop_signal == SIGINT ? "SIGINT" : "SIGTERM", r->info.step, r->info.t);
  } else if (r->w && cup_h5run_status(r->w, r->message)) {   /* the writer's failure stopped it */
    r->status = CUP_ERR_IO;
  }
}

static int is_netlist(const char *path) {
  static const char *const ext[] = {".cir", ".sp", ".spi", ".spice", ".net", ".ckt"};
  const char *dot = strrchr(path, '.');
  for (size_t k = 0; dot && k < sizeof ext / sizeof ext[0]; k++)
    if (!strcasecmp(dot, ext[k])) return 1;
  return 0;
}

/* A netlist runs as the scene `netlist: {file: NAME}` beside it. */
static int load_scene(run_t *r, char *err) {
  const run_args *a = r->args;
  const char *const *ovr = (const char *const *)a->overrides;
  if (!is_netlist(a->scene)) return cup_scene_load(&r->scene, a->scene, ovr, a->n_overrides, err);
  const char *base = path_base(a->scene);
  size_t len = 2 * strlen(base) + 32;
  char *text = malloc(len), *dir = NULL;
  if (!text || path_dir(a->scene, &dir)) { free(text); return snprintf(err, MSG_LEN, "out of memory"), CUP_ERR_NOMEM; }
  size_t w = (size_t)snprintf(text, len, "netlist: {file: \"");
  for (const char *p = base; *p; p++) {          /* a YAML double-quoted scalar */
    if (*p == '"' || *p == '\\') text[w++] = '\\';
    text[w++] = *p;
  }
  snprintf(text + w, len - w, "\"}\n");
  int st = cup_scene_load_string(&r->scene, text, a->scene, dir, ovr, a->n_overrides, err);
  free(text);
  free(dir);
  return st;
}

/* --probe signals, or the netlist's defaults: checked before the output is
 * touched (declared in /signals by declare_signals). */
static int check_probes(run_t *r, char *err) {
  const run_args *a = r->args;
  cup_netlist *nl = cup_scene_netlist(r->scene);
  char e2[CUP_ERRMSG_LEN];
  if (!nl) {
    if (a->n_probes) snprintf(err, MSG_LEN, "%s: --probe: the scene has no netlist", a->scene);
    return a->n_probes ? EXIT_RUN : 0;
  }
  for (int k = 0; k < a->n_probes; k++)
    if (cup_netlist_probe(nl, a->probes[k], e2) < 0) {
      snprintf(err, MSG_LEN, "%s: --probe: %s", a->scene, e2);
      return EXIT_RUN;
    }
  if (cup_netlist_signal_count(nl) == 0 && cup_netlist_probe_default(nl, 256, e2)) {
    snprintf(err, MSG_LEN, "%s: %s", a->scene, e2);
    return EXIT_RUN;
  }
  if (r->sk.steady && run_steady_probes(r->sk.steady, nl, e2, sizeof e2)) {
    snprintf(err, MSG_LEN, "%s: %s", a->scene, e2);
    return EXIT_RUN;
  }
  int ns = cup_netlist_signal_count(nl), m = cup_lcs_rows(cup_scene_lcs(r->scene));
  r->sk.zeta = calloc((size_t)m + 1, sizeof(double));
  r->sk.sig = calloc((size_t)ns + 1, sizeof(double));
  if (!r->sk.zeta || !r->sk.sig) { snprintf(err, MSG_LEN, "out of memory"); return EXIT_RUN; }
  r->sk.nl = nl;
  nl_signal_map(nl);                               /* (built here, not at the first record; a switched
                                                      netlist's other configurations at their first) */
  return 0;
}

/* The signals' datasets in the output, in the order asked. */
static int declare_signals(run_t *r, char *err) {
  cup_netlist *nl = r->sk.nl;
  if (!nl) return 0;
  int ns = cup_netlist_signal_count(nl);
  const char **names = calloc((size_t)ns + 1, sizeof *names);
  if (!names) { snprintf(err, MSG_LEN, "out of memory"); return EXIT_RUN; }
  for (int k = 0; k < ns; k++) names[k] = cup_netlist_signal_name(nl, k);
  int st = cup_h5run_signals(r->w, ns, names);
  free(names);
  if (st) {
    if (!cup_h5run_status(r->w, err)) snprintf(err, MSG_LEN, "%s", cup_status_string(st));
    return EXIT_RUN;
  }
  return 0;
}

/* Where n came from, for the step limit's message: --n or --h (or --set
 * n=, h=), the scene's n or h, else a netlist's .tran (a circuit the
 * adaptive scheme cannot run falls back to TSTOP / TSTEP steps). */
static void n_source(const run_t *r, char *buf, size_t size) {
  const run_args *a = r->args;
  const cup_netlist *nl = cup_scene_netlist(r->scene);
  double tstep, tstop;
  const char *flag = NULL;
  for (int k = 0; k < a->n_overrides; k++) {
    if (!strncmp(a->overrides[k], "n=", 2)) flag = "--n";
    if (!strncmp(a->overrides[k], "h=", 2)) flag = "--h";
  }
  if (flag) snprintf(buf, size, "%s", flag);
  else if (nl && cup_netlist_tran(nl, &tstep, &tstop) && fabs(tstop / tstep - (double)r->opts.n) < 1)
    snprintf(buf, size, ".tran %g %g asks for T / TSTEP = %.4g", tstep, tstop, tstop / tstep);
  else
    snprintf(buf, size, "the scene's n");
}

/* The run's steps and output are known before its first step: refuse one
 * beyond the step limit or the free space, naming the numbers. */
static int check_plan(run_t *r, char *err) {
  const run_args *a = r->args;
  run_plan p;
  char from[96], msg[MSG_LEN / 2];
  int nsig = r->sk.nl ? cup_netlist_signal_count(r->sk.nl) : 0;
  run_plan_make(&p, &r->opts, cup_scene_dim(r->scene), nsig, cup_scene_crowd(r->scene) ? CROWD_LOG_STEP_BYTES : 0);
  n_source(r, from, sizeof from);
  struct stat sb;                                  /* --resume: what the file holds already */
  if (a->resume && stat(a->out, &sb) == 0) p.bytes = p.bytes > (double)sb.st_size ? p.bytes - (double)sb.st_size : 0;
  if (run_plan_too_long(&p, &r->opts, cup_scene_max_steps(r->scene), from, "--scheme adaptive --tol 1e-6", msg,
                        sizeof msg) ||
      run_plan_no_room(p.bytes, a->out, msg, sizeof msg)) {
    snprintf(err, MSG_LEN, "%s: %s", a->scene, msg);
    return EXIT_RUN;
  }
  return 0;
}

/* --resume: the stopped run's file, reopened and checked (run_stop.c), says
 * "running" again until it closes. */
static int reopen(run_t *r, char *err) {
  run_signals s = {r->sk.nl, r->sk.zeta, r->sk.sig};
  if (run_stop_reopen(r->args->out, r->scene, r->I, &s, &r->w, &r->wall_before, err, MSG_LEN)) return EXIT_RUN;
  r->sk.w = r->w;
  r->sk.I = r->I;
  int st = cup_h5run_attr_long(r->w, "status", CUP_ERR_INTERRUPTED);
  st = cup_status_merge(st, cup_h5run_attr_string(r->w, "status_name", "running"));
  st = cup_status_merge(st, cup_h5run_attr_string(r->w, "message", "the run did not finish: the process ended "
                        "before closing the file; /t and /x hold the samples up to its last flush"));
  if (cup_status_merge(st, cup_h5run_flush(r->w))) {
    writer_words(r->w, err);
    return EXIT_RUN;
  }
  return 0;
}

/* What the model found suspect but allowed (a loop of ideal diodes, a
 * door no agent can pass): one stderr line each before the run, whatever
 * --quiet says, and the file's attribute `warnings`. */
static void model_warnings(run_t *r) {
  const char *w[2] = {cup_crowd_warning(cup_scene_crowd(r->scene)), cup_netlist_warning(cup_scene_netlist(r->scene))};
  size_t len = 0;
  for (int k = 0; k < 2; k++) {
    if (!w[k]) continue;
    const char *scene = r->args->scene;            /* a netlist's own warning names it already */
    if (!strncmp(w[k], scene, strlen(scene)) && w[k][strlen(scene)] == ':') fprintf(stderr, "catchup-run: warning: %s\n", w[k]);
    else fprintf(stderr, "catchup-run: warning: %s: %s\n", scene, w[k]);
    int n = snprintf(r->warnings + len, sizeof r->warnings - len, "%s%s", len ? "\n" : "", w[k]);
    if (n > 0 && len + (size_t)n < sizeof r->warnings) len += (size_t)n;
  }
}

/* --steady-state: solved before the output is touched; the run becomes one
 * period from it (or, with no steady state, the transient: a warning). */
static int steady_solve(run_t *r, char *err) {
  char e2[MSG_LEN] = "";
  cup_integrator_options o = r->opts;
  o.interrupt = (const volatile int *)&stop_signal;
  int rc = run_steady_solve(r->sk.steady, r->scene, &o, e2, sizeof e2);
  if (rc) {
    snprintf(err, MSG_LEN, "%s: %s", r->args->scene, e2);
    return EXIT_RUN;
  }
  if (e2[0]) fprintf(stderr, "catchup-run: warning: %s: %s\n", r->args->scene, e2);
  o.interrupt = r->opts.interrupt;
  r->opts = o;
  r->sk.t0 = run_steady_t0(r->sk.steady);
  return 0;
}

/* Every argument and input is checked before the output is touched; the
 * file is written beside it and replaces it (cup_h5run_commit) only once
 * the run got past its checks: a run that fails them leaves an earlier
 * result as it was. */
static int setup(run_t *r, char *err) {
  const run_args *a = r->args;
  char e2[CUP_ERRMSG_LEN];
  if (load_scene(r, err)) return EXIT_RUN;       /* the message names file:line:column and key */
  if (cup_scene_check_output(r->scene, a->out, e2)) {
    snprintf(err, MSG_LEN, "%s", e2);
    return EXIT_RUN;
  }
  if (cup_scene_steady_state(r->scene) && !(r->sk.steady = run_steady_new(r->scene))) {
    snprintf(err, MSG_LEN, "out of memory");
    return EXIT_RUN;
  }
  if (r->sk.steady && a->resume) {
    snprintf(err, MSG_LEN, "%s: --resume: a steady-state run is not resumable (run it again)", a->scene);
    return EXIT_RUN;
  }
  if (check_probes(r, err)) return EXIT_RUN;
  r->opts = *cup_scene_options(r->scene);
  if (r->sk.steady && steady_solve(r, err)) return EXIT_RUN;
  if (check_plan(r, err)) return EXIT_RUN;
  /* a signal stops the run within 1024 steps even when no sample is due */
  _Static_assert(sizeof(sig_atomic_t) == sizeof(int), "sig_atomic_t is an int here");
  r->opts.interrupt = (const volatile int *)&stop_signal;
  r->opts.on_event = event_sink;
  r->opts.event_ctx = r;
  if (cup_scene_crowd(r->scene)) {
    if (!(r->crowd = crowd_log_create(cup_scene_crowd(r->scene), r->opts.n))) {
      snprintf(err, MSG_LEN, "%s: out of memory for the crowd's per-step log", a->scene);
      return EXIT_RUN;
    }
    r->opts.on_step = crowd_log_step;
    r->opts.step_ctx = r->crowd;
  }
  if (run_steady_integrator(r->sk.steady, r->scene, &r->opts, &r->I, e2)) {
    snprintf(err, MSG_LEN, "%s: %s", a->scene, e2);
    return EXIT_RUN;
  }
  if (a->resume) {
    if (reopen(r, err)) return EXIT_RUN;
    model_warnings(r);
    return 0;
  }
  if (cup_h5run_begin(&r->w, a->out, cup_scene_dim(r->scene), err)) return EXIT_RUN;
  r->sk.w = r->w;
  r->sk.I = r->I;
  if (declare_signals(r, err)) return EXIT_RUN;
  if (write_provenance(r) || (r->crowd && crowd_log_begin(r->crowd, r->w)) || cup_h5run_commit(r->w)) {
    writer_words(r->w, err);
    return EXIT_RUN;
  }
  model_warnings(r);
  return 0;
}

static void run(run_t *r) {
  const char *hook = getenv("CATCHUP_RUN_TEST_SIGNAL");
  if (hook && *hook) hook_at = strtol(hook, NULL, 10);
  if (hook_at == 0) raise(SIGINT);
  if (r->sk.nl && !r->sk.steady && integrator_set_put(r->I, r->sk.nl, put) < 0) {
    settle_status(r, CUP_ERR_NOMEM);
    return;
  }
  double t0 = now_seconds();
  int st = r->args->resume ? cup_integrator_resume(r->I, sink, &r->sk, &r->info)
                           : cup_integrator_run(r->I, run_steady_x0(r->sk.steady, cup_scene_x0(r->scene)), sink,
                                                &r->sk, &r->info);
  r->wall = now_seconds() - t0;
  settle_status(r, st);
}

/* Results, then close; either failing makes an otherwise good run an I/O
 * error (the samples may be incomplete). */
static void finish_file(run_t *r) {
  char err[CUP_ERRMSG_LEN] = "";
  run_signals s = {r->sk.nl, r->sk.zeta, r->sk.sig};
  int wst = r->status == CUP_ERR_INTERRUPTED && stop_signal ? run_stop_save(r->w, r->I, &r->info, &s, &r->resumable)
                                                            : run_stop_clear(r->w);
  wst = cup_status_merge(wst, write_results(r));
  wst = cup_status_merge(wst, run_steady_write(r->sk.steady, r->w, r->scene, r->status));
  if (r->crowd)
    wst = cup_status_merge(wst, crowd_log_write(r->crowd, r->w, r->info.step, cup_integrator_state(r->I)));
  if (wst != CUP_OK && r->status >= 0) {
    r->status = CUP_ERR_IO;
    writer_words(r->w, r->message);
  }
  if (cup_h5run_close(&r->w, err) != CUP_OK && r->status >= 0) {
    r->status = CUP_ERR_IO;
    snprintf(r->message, sizeof r->message, "%s", err);
  }
}

/* An error is one line (plus nothing); a warning (the status, a crowd's
 * overlap beyond eta) is one line each before the summary; the summary is
 * one line unless --quiet. */
static void report(const run_t *r) {
  const run_args *a = r->args;
  const cup_run_info *i = &r->info;
  if (r->status == CUP_ERR_IO) {   /* the message names the output file */
    fprintf(stderr, "catchup-run: %s: %s\n", a->scene, r->message);
    return;
  }
  if (r->status == CUP_ERR_INTERRUPTED && stop_signal) {
    cup_switching sw;
    int switched = r->sk.nl && cup_netlist_switching(r->sk.nl, &sw);
    fprintf(stderr, "catchup-run: %s: %s: %s; %s holds the samples before it and, as its last row (stop_row), "
            "the state there%s\n", a->scene, cup_status_name(r->status), r->message, a->out,
            r->resumable ? ": continue with --resume"
            : switched ? " (this run cannot be resumed: a circuit with switches has no checkpoints; run it again)"
                       : " (this run cannot be resumed: its set is not a polyset)");
    return;
  }
  if (r->status < 0) {
    fprintf(stderr, "catchup-run: %s: %s: %s; the samples before it are in %s\n", a->scene,
            cup_status_name(r->status), r->message, a->out);
    return;
  }
  if (r->status > 0)
    fprintf(stderr, "catchup-run: warning: %s: %s: %s\n", a->scene, cup_status_name(r->status),
            r->message);
  char overlap[320];
  if (r->crowd && crowd_log_overlap(r->crowd, overlap, sizeof overlap))
    fprintf(stderr, "catchup-run: warning: %s: %s\n", a->scene, overlap);
  if (a->quiet) return;
  char how[96], est[48] = "";
  if (r->opts.scheme == CUP_SCHEME_ADAPTIVE)
    snprintf(how, sizeof how, "tol=%.3g/%.3g adaptive, %ld steps, %ld events", r->opts.tol_abs,
             r->opts.tol_rel, i->step, i->events);
  else
    snprintf(how, sizeof how, "n=%ld %s", r->opts.n, cup_scheme_name(r->opts.scheme));
  if (!isnan(i->err_est)) snprintf(est, sizeof est, ", error estimate %.3g", i->err_est);
  fprintf(stderr, "catchup-run: %s -> %s: %s, %ld samples, %ld projected, %ld skipped, "
          "%lld dual iterations, max eps_cert %.3g, max eta_cert %.3g%s, %.3g s: %s\n",
          a->scene, a->out, how, i->samples, i->projected, i->skipped, i->dual_iterations,
          i->max_eps_cert, i->max_eta_cert, est, r->wall, cup_status_name(r->status));
  run_steady_report(r->sk.steady, a->scene, stderr);
  if (r->crowd) {
    char line[160];
    crowd_log_summary(r->crowd, line, sizeof line);
    fprintf(stderr, "catchup-run: %s: %s\n", a->scene, line);
  }
}

static void cleanup(run_t *r) {
  if (r->w) cup_h5run_close(&r->w, NULL);
  free(r->sk.zeta);
  free(r->sk.sig);
  run_steady_free(&r->sk.steady);
  cup_integrator_free(&r->I);
  crowd_log_free(&r->crowd);
  cup_scene_free(&r->scene);
}

/* After a clean stop, end by the signal itself, as the shell expects. */
static int end_by_signal(int sig) {
  signal(sig, SIG_DFL);
  raise(sig);
  return 128 + sig;              /* not reached */
}

int main(int argc, char **argv) {
  heap_pad();                    /* see heap_pad.h */
  run_args args;
  int rc = run_args_parse(&args, argc, argv);
  if (rc >= 0) { run_args_free(&args); return rc; }
  install_handlers();            /* before the output is touched: a signal in the set-up stops the run at once */
  run_t r;
  memset(&r, 0, sizeof r);
  r.args = &args;
  char err[MSG_LEN] = "";
  rc = setup(&r, err);
  if (rc) {
    fprintf(stderr, "catchup-run: %s\n", err);
  } else {
    run(&r);
    finish_file(&r);
    report(&r);
    rc = r.status < 0 ? EXIT_RUN : 0;
  }
  cleanup(&r);
  run_args_free(&args);
  if (r.status == CUP_ERR_INTERRUPTED && stop_signal) return end_by_signal(stop_signal);
  return rc;
}

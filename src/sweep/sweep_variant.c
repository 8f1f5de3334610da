/* sweep_variant — the variants' scenes (sweep.h): their texts after the
 * overrides, the scenes loaded from them, and the checks that the variants
 * can share one results file (the same T, state dimension, signals and
 * steady-state columns). A generated variant beyond its entry's first is
 * lazy: the job that needs its scene loads it from the entry's scene file's
 * text and its own overrides, and checks it against the entry's first,
 * which stood for it until then; rank 0 makes its text (the YAML document
 * after its overrides, for /variants) apart, sw_lazy_texts, which a sweep
 * on several ranks does while the workers start. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "analysis/pss_run.h"
#include "io/read_text.h"
#include "io/scene_shape.h"
#include "io/scene_tree.h"
#include "sweep.h"

/* "SWEEP:LINE:COL: variants.K (NAME): " before a scene's own message. */
static int variant_fail(const sw_sweep *s, int k, int status, char *errmsg, const char *fmt, ...)
  __attribute__((format(printf, 5, 6)));
static int variant_fail(const sw_sweep *s, int k, int status, char *errmsg, const char *fmt, ...) {
  const sw_variant *v = &s->var[k];
  int w = snprintf(errmsg, SW_ERR_LEN, "%s:%d:%d: variants.%d (%s): ", s->path, v->line, v->col, k, v->name);
  va_list ap;
  va_start(ap, fmt);
  if (w >= 0 && w < SW_ERR_LEN) vsnprintf(errmsg + w, (size_t)(SW_ERR_LEN - w), fmt, ap);
  va_end(ap);
  return status;
}

const char *sw_signal_name(const sw_sweep *s, int k) {
  return k >= 0 && k < s->nsig ? cup_netlist_signal_name(cup_scene_netlist(s->var[0].scene), k) : NULL;
}

/* ---- texts ---- */

/* The scene document `text` after the overrides set[0..n), as YAML: what
 * cup_scene_text gives once the scene is loaded, without building it. */
static int text_after(const char *text, size_t len, const sw_variant *v, char **out, char *err) {
  st_src src = {v->scene_file, (const char *const *)v->set};
  st_node *root = NULL;
  int st = st_parse(&root, text, len, &src, -1, NULL, err);
  for (int k = 0; k < v->n_set && !st; k++) st = st_apply_override(&root, &src, k, scene_reshape, scene_verbatim, err);
  if (!st && !(*out = st_emit(root))) st = CUP_ERR_NOMEM;
  st_free(root);
  return st;
}

/* Variant k's text: its scene loaded from its file (its files join the
 * sweep's). A lazy variant's is made later (sw_lazy_texts); its entry's
 * first reads the scene file's text, once, for the jobs that load them. */
static int variant_text(sw_sweep *s, int k, char **text, char *errmsg) {
  sw_variant *v = &s->var[k];
  char err[CUP_ERRMSG_LEN];
  int st;
  if (sw_variant_lazy(s, k)) {
    sw_variant *first = &s->var[v->proto];
    if (first->file_text) return CUP_OK;
    file_list seen = {0};
    size_t len;
    char *bytes = NULL;
    st = read_text(v->scene_file, &bytes, &len, &seen, err);
    file_list_free(&seen);
    if (st) return variant_fail(s, k, st, errmsg, "%s", err);
    if (memchr(bytes, '\0', len)) {           /* it travels and is kept as a string */
      free(bytes);
      return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "%s: holds a NUL byte", v->scene_file);
    }
    if (!(first->file_text = realloc(bytes, len + 1))) { free(bytes); return CUP_ERR_NOMEM; }
    first->file_text[len] = '\0';
    return CUP_OK;
  }
  cup_scene *sc = NULL;
  st = cup_scene_load(&sc, v->scene_file, (const char *const *)v->set, v->n_set, err);
  if (st == CUP_ERR_IO && v->from_base)   /* the base itself is missing: say where it is named */
    return snprintf(errmsg, SW_ERR_LEN, "%s:%d:%d: base: %s", s->path, s->base_line, s->base_col, err), st;
  if (st) return variant_fail(s, k, st, errmsg, "%s", err);
  if (k == 0) s->crowd = cup_scene_crowd(sc) != NULL;   /* crowds have no lazy variants */
  if (!(*text = strdup(cup_scene_text(sc)))) st = CUP_ERR_NOMEM;
  if (!st) st = file_list_merge(&s->files, scene_file_list(sc));   /* its files join the sweep's */
  cup_scene_free(&sc);
  return st;
}

int sw_resolve_scenes(sw_sweep *s, char *errmsg) {
  char **texts = calloc((size_t)s->n_variants, sizeof *texts);
  if (!texts) return CUP_ERR_NOMEM;
  int st = CUP_OK;
  for (int k = 0; k < s->n_variants && !st; k++) st = variant_text(s, k, &texts[k], errmsg);
  if (!st) st = sw_resolve_texts(s, texts, errmsg);
  for (int k = 0; k < s->n_variants; k++) free(texts[k]);
  free(texts);
  return st;
}

int sw_lazy_texts(sw_sweep *s, char *errmsg) {
  for (int k = 0; k < s->n_variants; k++) {
    sw_variant *v = &s->var[k];
    const char *base = s->var[v->proto].file_text;
    if (v->scene_text || !sw_variant_lazy(s, k) || !base) continue;
    char err[CUP_ERRMSG_LEN];
    int st = text_after(base, strlen(base), v, &v->scene_text, err);
    if (st) return variant_fail(s, k, st, errmsg, "%s", err);
  }
  return CUP_OK;
}

int sw_resolve_files(sw_sweep *s, char *errmsg) {
  int st = sw_resolve_scenes(s, errmsg);
  return st ? st : sw_lazy_texts(s, errmsg);
}

/* ---- the checks ---- */

/* The largest n among a variant's tasks (the scene's n when the grid has none). */
static long variant_max_n(const sw_sweep *s, int k) {
  if (!s->len[SW_AXIS_N]) return cup_scene_options(sw_variant_settings(s, k))->n;
  long m = 1;
  for (int j = 0; j < s->len[SW_AXIS_N]; j++) m = s->n[j] > m ? s->n[j] : m;
  return m;
}

/* Variant k's scene sc against variants.0's (k = 0: sets the sweep's T,
 * dimension and kind). */
static int check_shape(sw_sweep *s, int k, const cup_scene *sc, char *errmsg) {
  const cup_integrator_options *o = cup_scene_options(sc);
  int dim = cup_scene_dim(sc), crowd = cup_scene_crowd(sc) != NULL;
  if (k == 0) { s->T = o->T; s->dim = dim; s->crowd = crowd; s->steady = cup_scene_steady_state(sc) != NULL; }
  if (crowd != s->crowd)
    return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "%s, and variants.0 %s: a sweep's variants are all "
                        "crowds or none", crowd ? "a crowd" : "not a crowd", s->crowd ? "is one" : "is not");
  if (o->T != s->T)
    return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "T = %.17g differs from variants.0's T = %.17g: "
                        "the variants share the sample times", o->T, s->T);
  if (dim != s->dim && !crowd)
    return variant_fail(s, k, CUP_ERR_DIM, errmsg, "state dimension %d differs from variants.0's %d", dim, s->dim);
  if (dim > s->dim) s->dim = dim;     /* crowds of N agents: positions padded to the largest */
  return CUP_OK;
}

/* After the variants' scenes are loaded: crowd sweeps take no n axis (the
 * crowd is built for its scene's step), store no positions unless
 * output.samples says so, and have no reference (sweep_crowd.c runs them).
 * Here, not there, so that the sweep file's parser needs no HDF5. */
static int crowd_resolve(sw_sweep *s, char *errmsg) {
  if (s->len[SW_AXIS_N]) {
    snprintf(errmsg, SW_ERR_LEN, "%s: grid.n: a crowd is built for its scene's step T/n (its margins and "
             "exit times): vary n in a variant's set ({n: 4000}) instead", s->path);
    return CUP_ERR_PARSE;
  }
  if (!s->out_given) s->out_samples = 0;     /* positions only when asked: 2N per sample */
  return CUP_OK;
}

/* Steady-state sweeps (sweep_steady.c runs them): the variants' scenes all
 * ask for the steady state or none do; no reference, no trajectories; the
 * signals measured and the elements' v(a,b) and i(E) probed before the
 * sweep's signals are fixed (check_signals), so that they are the same in
 * every variant, at the same indices (k = 0: they become the sweep's). */
static int check_steady(sw_sweep *s, int k, const cup_scene *sc, char *errmsg) {
  const cup_scene_steady *q = cup_scene_steady_state(sc);
  if (!q != !s->steady)
    return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "%s the steady state, and variants.0 %s: a sweep's variants "
                        "all ask for it (steady_state:) or none do", q ? "asks for" : "does not ask for",
                        s->steady ? "does" : "does not");
  if (!q) return CUP_OK;
  cup_netlist *nl = cup_scene_netlist(sc);
  char err[CUP_ERRMSG_LEN];
  int sig[SW_SS_SIGNALS], pv[SW_SS_POWER], pc[SW_SS_POWER];
  if (!nl)
    return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "steady_state: a steady-state sweep measures a netlist's "
                        "signals, and this scene has no netlist");
  if (q->nmeasure < 1 || q->nmeasure > SW_SS_SIGNALS)
    return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "steady_state.measure: a steady-state sweep measures 1 to %d "
                        "signals (got %d), e.g. [v(out), i(L1)]", SW_SS_SIGNALS, q->nmeasure);
  if (q->npower > SW_SS_POWER)
    return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "steady_state.power: at most %d elements (got %d)", SW_SS_POWER,
                        q->npower);
  for (int j = 0; j < q->nmeasure; j++)
    if ((sig[j] = cup_netlist_probe(nl, q->measure[j], err)) < 0)
      return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "steady_state.measure: %s", err);
  for (int j = 0; j < q->npower; j++)
    if (pss_probe_power(nl, q->power[j], &pv[j], &pc[j], err))
      return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "steady_state.power: %s", err);
  if (k == 0) {
    s->ss_nm = q->nmeasure;
    s->ss_np = q->npower;
    memcpy(s->ss_sig, sig, sizeof sig);
    memcpy(s->ss_pv, pv, sizeof pv);
    memcpy(s->ss_pc, pc, sizeof pc);
  }
  if (q->nmeasure != s->ss_nm || q->npower != s->ss_np || memcmp(sig, s->ss_sig, sizeof(int) * (size_t)s->ss_nm) ||
      memcmp(pv, s->ss_pv, sizeof(int) * (size_t)s->ss_np) || memcmp(pc, s->ss_pc, sizeof(int) * (size_t)s->ss_np))
    return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "steady_state: its measure and power lists differ from "
                        "variants.0's: the variants share /steady_state's columns");
  return CUP_OK;
}

/* A netlist sweep records the signals catchup-run would (the scene's or
 * netlist's probes, else every node voltage and element current when at
 * most 256), the same in every variant: they share /runs/signals (k = 0:
 * they become the sweep's). */
static int check_signals(sw_sweep *s, int k, const cup_scene *sc, char *errmsg) {
  cup_netlist *nl = cup_scene_netlist(sc);
  char err[CUP_ERRMSG_LEN];
  if (!nl) {
    if (k > 0 && s->nsig)
      return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "has no netlist, and variants.0 has: the variants "
                          "share /runs/signals");
    return CUP_OK;
  }
  if (cup_netlist_signal_count(nl) == 0 && cup_netlist_probe_default(nl, 256, err))
    return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "%s", err);
  int n = cup_netlist_signal_count(nl);
  if (k == 0) s->nsig = n;
  int same = n == s->nsig;
  for (int j = 0; same && j < n; j++) same = !strcmp(cup_netlist_signal_name(nl, j), sw_signal_name(s, j));
  if (!same)
    return variant_fail(s, k, CUP_ERR_PARSE, errmsg, "its netlist's signals (%d, from %s) differ from "
                        "variants.0's (%d): the variants share /runs/signals", n,
                        n ? cup_netlist_signal_name(nl, 0) : "none", s->nsig);
  return CUP_OK;
}

int sw_resolve_texts(sw_sweep *s, char *const *texts, char *errmsg) {
  for (int k = 0; k < s->n_variants; k++) {
    sw_variant *v = &s->var[k];
    char err[CUP_ERRMSG_LEN];
    cup_scene_free(&v->scene);
    free(v->scene_text);
    v->scene_text = NULL;
    if (sw_variant_lazy(s, k)) continue;      /* variants.0 is not: s->crowd is known before a lazy one */
    if (!(v->scene_text = strdup(texts[k]))) return CUP_ERR_NOMEM;
    int st = cup_scene_load_string(&v->scene, v->scene_text, v->scene_file, v->scene_dir, NULL, 0, err);
    if (st) return variant_fail(s, k, st, errmsg, "%s", err);
    if ((st = check_shape(s, k, v->scene, errmsg))) return st;
  }
  for (int k = 0; k < s->n_variants; k++) {
    long S1 = s->samples - 1;
    if (s->crowd || s->steady || (s->ref_method == SW_REF_ADAPTIVE && !s->ref_check))
      s->var[k].n_ref = 0;                    /* none, or the adaptive scheme chooses its own steps */
    else if (s->ref_n) s->var[k].n_ref = s->ref_n;
    else s->var[k].n_ref = (4 * variant_max_n(s, k) + S1 - 1) / S1 * S1;
  }
  int st = s->crowd ? crowd_resolve(s, errmsg) : CUP_OK;
  for (int k = 0; k < s->n_variants && !st; k++)
    if (s->var[k].scene) st = check_steady(s, k, s->var[k].scene, errmsg);
  if (!st && s->steady && s->out_given && s->out_samples) {
    snprintf(errmsg, SW_ERR_LEN, "%s: output.samples: a steady-state sweep stores no trajectories (its figures are "
             "in /steady_state): leave it out or write 0", s->path);
    st = CUP_ERR_PARSE;
  }
  if (s->steady) s->out_samples = 0;
  s->nsig = 0;
  for (int k = 0; k < s->n_variants && !st; k++)
    if (s->var[k].scene) st = check_signals(s, k, s->var[k].scene, errmsg);
  if (!st) sw_count_tasks(s);
  return st;
}

/* ---- a lazy variant's scene, in its job ---- */

/* What the sweep took from the scene that stood for lazy variant k
 * (sw_task_get's defaults, the step limit, the files read) against its own
 * scene sc; the name of the first that differs, or NULL. */
static const char *differs(const cup_scene *sc, const cup_scene *stood) {
  const cup_integrator_options *a = cup_scene_options(sc), *b = cup_scene_options(stood);
  if (a->n != b->n) return "n";
  if (a->scheme != b->scheme) return "scheme";
  if (a->proj.method != b->proj.method) return "projector";
  if (a->tol_abs != b->tol_abs || a->tol_rel != b->tol_rel) return "tol";
  if (strcmp(cup_scene_eps_spec(sc), cup_scene_eps_spec(stood))) return "eps";
  if (strcmp(cup_scene_eta_spec(sc), cup_scene_eta_spec(stood))) return "eta";
  if (cup_scene_max_steps(sc) != cup_scene_max_steps(stood)) return "max_steps";
  int nf = cup_scene_file_count(sc);
  if (nf != cup_scene_file_count(stood)) return "the files it reads";
  for (int j = 0; j < nf; j++)
    if (strcmp(cup_scene_file(sc, j), cup_scene_file(stood, j)) ||
        strcmp(cup_scene_file_sha256(sc, j), cup_scene_file_sha256(stood, j)))
      return "the files it reads (or what they hold)";
  return NULL;
}

int sw_variant_load(const sw_sweep *s, int k, cup_scene **out, char *errmsg) {
  const sw_variant *v = &s->var[k];
  sw_sweep probe = *s;                     /* the checks compare against s; k > 0 never writes to it */
  char err[CUP_ERRMSG_LEN];
  cup_scene *sc = NULL;
  *out = NULL;
  const char *base = s->var[v->proto].file_text;     /* the scene file, then the variant's overrides */
  int st = cup_scene_load_string(&sc, base, v->scene_file, v->scene_dir, (const char *const *)v->set, v->n_set, err);
  if (st) return variant_fail(s, k, st, errmsg, "%s", err), st;
  const char *what = differs(sc, sw_variant_settings(s, k));
  if (what)
    st = variant_fail(s, k, CUP_ERR_PARSE, errmsg, "its %s differs from %s's, which the sweep's tasks took for every "
                      "variant of their entry: write such variants out, or vary n, scheme, projector and tol in the "
                      "sweep's grid:",
                      what, s->var[v->proto].name);
  if (!st) st = check_shape(&probe, k, sc, errmsg);
  if (!st) st = check_steady(&probe, k, sc, errmsg);
  if (!st) st = check_signals(&probe, k, sc, errmsg);
  if (st) cup_scene_free(&sc);
  *out = sc;
  return st;
}

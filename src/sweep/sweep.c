/* sweep — the sweep file (docs/sweep-format.md) and its tasks in a fixed
 * order; one job's computation is in sweep_run.c. The file is read through
 * the scene loader's tree and readers (io/scene_tree.c, io/scene_read.h),
 * so every error names FILE:LINE:COL and the dotted key; a variant's scene
 * is loaded by the scene loader itself, with the variant's `set` entries as
 * overrides. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "io/scene_read.h"
#include "io/sha256.h"
#include "sweep.h"
#include "sweep_gen.h"
#include "util/path.h"

static const char *const axis_names[SW_NAXES + 1] = {"n", "eps", "eta", "scheme", "projector", "tol", NULL};
enum { MAX_WORDS = 16 };

/* The library's names, NULL-terminated ("explicit", "implicit", ...): a
 * scheme or projector added to the library is a sweep axis value at once. */
static const char *const *names_of(const char *(*name)(int), const char **buf) {
  int k = 0;
  for (; k < MAX_WORDS - 1 && strcmp(name(k), "unknown") != 0; k++) buf[k] = name(k);
  buf[k] = NULL;
  return buf;
}

/* The scene's readers (io/scene_read.h: fail, check_keys, opt, need_map,
 * string, integer, number_min) with a reader of no folder and no file list
 * (rd.dir, rd.files: the variants' scenes are loaded by the scene loader
 * itself). st_error writes at most CUP_ERRMSG_LEN bytes, which is what we
 * want for the sweep file's own messages; nested scene messages use
 * SW_ERR_LEN. What the sweep says its own way: */

/* A name or a file: a string, not empty. */
static int word(rd *p, const st_node *nd, const char *key, const char **out) {
  char b[64];
  if (nd->kind == ST_SCALAR && !st_is_null(nd) && !nd->text[0])
    return fail(p, CUP_ERR_PARSE, nd, key, "expected a word or a string (got %s)", st_looks(nd, b, sizeof b));
  return string(p, nd, key, out);
}

/* A plain finite number, or a message that names what was expected ("an
 * integer"), for a quoted number and an infinity too. */
static int plain_number(rd *p, const st_node *nd, const char *key, const char *what) {
  char b[64];
  double v;
  if (nd->kind == ST_SCALAR && !nd->quoted && !st_is_null(nd) && st_number(nd->text, &v) && isfinite(v))
    return CUP_OK;
  return fail(p, CUP_ERR_PARSE, nd, key, "expected %s (got %s)", what, st_looks(nd, b, sizeof b));
}

/* An integer in [lo, hi]; 1e6 is accepted (an exact integer in a double). */
static int count(rd *p, const st_node *nd, const char *key, long lo, long hi, long *out) {
  int st = plain_number(p, nd, key, "an integer");
  return st ? st : integer(p, nd, key, lo, hi, out);
}

/* A number > 0 (the adaptive scheme's tol). */
static int positive(rd *p, const st_node *nd, const char *key, double *out) {
  int st = plain_number(p, nd, key, "a number");
  return st ? st : number_min(p, nd, key, 0, 1, out);
}

/* ---- grid ---------------------------------------------------------------- */

/* A scalar is a one-element list. */
static int axis_items(rd *p, const st_node *nd, const char *key, const st_node *const **items, int *len) {
  static const st_node *one[1];
  if (nd->kind == ST_MAP) return fail(p, CUP_ERR_PARSE, nd, key, "expected a value or a list of values (got a mapping)");
  if (nd->kind == ST_SCALAR) { one[0] = nd; *items = one; *len = 1; return CUP_OK; }
  if (nd->len == 0) return fail(p, CUP_ERR_PARSE, nd, key, "empty list: give at least one value (or leave the axis out)");
  *items = (const st_node *const *)nd->item;
  *len = nd->len;
  return CUP_OK;
}

static int read_word_item(rd *p, const st_node *nd, const char *key, const char *what,
                          const char *const *names, int *out) {
  char hint[ST_HINT_LEN], b[64];
  if (nd->kind != ST_SCALAR || st_is_null(nd))
    return fail(p, CUP_ERR_PARSE, nd, key, "expected a %s name (got %s)", what, st_looks(nd, b, sizeof b));
  for (int k = 0; names[k]; k++)
    if (!strcmp(nd->text, names[k])) { *out = k; return CUP_OK; }
  return fail(p, CUP_ERR_PARSE, nd, key, "unknown %s '%.40s' (%s)", what, nd->text,
              st_suggest(hint, sizeof hint, nd->text, names));
}

static int read_schedule_item(rd *p, const st_node *nd, const char *key, char **out) {
  char b[64], lib[CUP_ERRMSG_LEN];
  cup_schedule sch;
  if (nd->kind != ST_SCALAR || st_is_null(nd))
    return fail(p, CUP_ERR_PARSE, nd, key, "expected a schedule like \"n^-2.1\" or a number (got %s)",
                st_looks(nd, b, sizeof b));
  if (cup_schedule_parse(nd->text, &sch, lib) != CUP_OK) return fail(p, CUP_ERR_PARSE, nd, key, "%s", lib);
  if (strlen(nd->text) >= SW_SPEC_LEN)
    return fail(p, CUP_ERR_PARSE, nd, key, "schedule text longer than %d characters", SW_SPEC_LEN - 1);
  *out = strdup(nd->text);
  return *out ? CUP_OK : CUP_ERR_NOMEM;
}

static int read_axis(rd *p, sw_sweep *s, int a, const st_node *nd) {
  char key[64];
  const char *words[MAX_WORDS];
  const st_node *const *items = NULL;
  int len = 0, st = axis_items(p, nd, axis_names[a], &items, &len);
  if (st) return st;
  s->len[a] = len;
  if (a == SW_AXIS_N) s->n = calloc((size_t)len, sizeof *s->n);
  else if (a == SW_AXIS_EPS) s->eps = calloc((size_t)len, sizeof *s->eps);
  else if (a == SW_AXIS_ETA) s->eta = calloc((size_t)len, sizeof *s->eta);
  else if (a == SW_AXIS_SCHEME) s->scheme = calloc((size_t)len, sizeof *s->scheme);
  else if (a == SW_AXIS_TOL) s->tol = calloc((size_t)len, sizeof *s->tol);
  else s->projector = calloc((size_t)len, sizeof *s->projector);
  for (int k = 0; k < len && !st; k++) {
    if (nd->kind == ST_SEQ) snprintf(key, sizeof key, "grid.%s.%d", axis_names[a], k);
    else snprintf(key, sizeof key, "grid.%s", axis_names[a]);
    switch (a) {
      case SW_AXIS_N:
        st = s->n ? count(p, items[k], key, 1, 9007199254740992L, &s->n[k]) : CUP_ERR_NOMEM;
        break;
      case SW_AXIS_EPS:
        st = s->eps ? read_schedule_item(p, items[k], key, &s->eps[k]) : CUP_ERR_NOMEM;
        break;
      case SW_AXIS_ETA:
        st = s->eta ? read_schedule_item(p, items[k], key, &s->eta[k]) : CUP_ERR_NOMEM;
        break;
      case SW_AXIS_SCHEME:
        st = s->scheme ? read_word_item(p, items[k], key, "scheme", names_of(cup_scheme_name, words),
                                        &s->scheme[k]) : CUP_ERR_NOMEM;
        break;
      case SW_AXIS_TOL:
        st = s->tol ? positive(p, items[k], key, &s->tol[k]) : CUP_ERR_NOMEM;
        break;
      default:
        st = s->projector ? read_word_item(p, items[k], key, "projector", names_of(cup_proj_method_name, words),
                                           &s->projector[k]) : CUP_ERR_NOMEM;
    }
  }
  return st;
}

/* zip: [eps, eta] (one group) or [[eps, eta], [scheme, projector]]. */
static int read_zip_group(rd *p, sw_sweep *s, const st_node *nd, const char *key, int g) {
  char k2[64];
  if (nd->kind != ST_SEQ || nd->len < 2)
    return fail(p, CUP_ERR_PARSE, nd, key, "expected a list of at least two axis names, e.g. [eps, eta]");
  int first = -1;
  for (int k = 0; k < nd->len; k++) {
    snprintf(k2, sizeof k2, "%s.%d", key, k);
    int a, st = read_word_item(p, nd->item[k], k2, "axis", axis_names, &a);
    if (st) return st;
    if (s->zip[a] >= 0) return fail(p, CUP_ERR_PARSE, nd->item[k], k2, "axis '%s' is zipped twice", axis_names[a]);
    if (!s->len[a]) return fail(p, CUP_ERR_PARSE, nd->item[k], k2, "axis '%s' is not in the grid", axis_names[a]);
    if (first < 0) first = a;
    else if (s->len[a] != s->len[first])
      return fail(p, CUP_ERR_PARSE, nd->item[k], k2, "zipped axes need equal lengths: %s has %d values, %s has %d",
                  axis_names[first], s->len[first], axis_names[a], s->len[a]);
    s->zip[a] = g;
  }
  return CUP_OK;
}

static int read_zip(rd *p, sw_sweep *s, const st_node *nd) {
  if (nd->kind == ST_SEQ && nd->len > 0 && nd->item[0]->kind == ST_SEQ) {
    char key[32];
    int st = CUP_OK;
    for (int g = 0; g < nd->len && !st; g++) {
      snprintf(key, sizeof key, "grid.zip.%d", g);
      st = read_zip_group(p, s, nd->item[g], key, g);
    }
    return st;
  }
  return read_zip_group(p, s, nd, "grid.zip", 0);
}

static int read_grid(rd *p, sw_sweep *s, const st_node *root) {
  static const char *const known[] = {"n", "eps", "eta", "scheme", "projector", "tol", "zip", NULL};
  for (int a = 0; a < SW_NAXES; a++) s->zip[a] = -1;
  const st_node *g = opt(root, "grid"), *nd;
  if (!g) return CUP_OK;
  int st = need_map(p, g, "grid", "a mapping of axes (n, eps, eta, scheme, projector, tol, zip)");
  if (!st) st = check_keys(p, g, "grid", known);
  for (int a = 0; a < SW_NAXES && !st; a++)
    if ((nd = opt(g, axis_names[a]))) st = read_axis(p, s, a, nd);
  if (!st && (nd = opt(g, "zip"))) st = read_zip(p, s, nd);
  return st;
}

/* ---- variants ------------------------------------------------------------ */

/* "key=value" with the value written back as YAML. */
static char *override_text(const char *key, const st_node *v) {
  char *val = NULL;
  if (v->kind == ST_SCALAR && !v->quoted) {
    val = strdup(v->text);
  } else if (v->kind == ST_SCALAR) {       /* single-quoted: ' doubles */
    size_t n = strlen(v->text), w = 0;
    val = malloc(2 * n + 3);
    if (val) {
      val[w++] = '\'';
      for (size_t i = 0; i < n; i++) {
        if (v->text[i] == '\'') val[w++] = '\'';
        val[w++] = v->text[i];
      }
      val[w++] = '\'';
      val[w] = '\0';
    }
  } else {
    val = st_emit(v);
  }
  if (!val) return NULL;
  size_t len = strlen(key) + strlen(val) + 2;
  char *s = malloc(len);
  if (s) snprintf(s, len, "%s=%s", key, val);
  free(val);
  if (s) {                                 /* st_emit ends with a newline */
    size_t n = strlen(s);
    while (n && (s[n - 1] == '\n' || s[n - 1] == ' ')) s[--n] = '\0';
  }
  return s;
}

/* Entry k of variants: into v; its name unlike those of the nprev variants before it. */
static int read_variant(rd *p, sw_sweep *s, const st_node *nd, int k, const char *base, sw_variant *v, long nprev) {
  static const char *const known[] = {"name", "scene", "set", SW_GEN_KEYS, NULL};
  char key[64], k2[160];
  v->line = nd->line;
  v->col = nd->col;
  snprintf(key, sizeof key, "variants.%d", k);
  int st = need_map(p, nd, key, "a mapping with name and optionally scene and set");
  if (!st) st = check_keys(p, nd, key, known);
  if (st) return st;
  const st_node *x = opt(nd, "name");
  const char *name = NULL, *scene = base;
  snprintf(k2, sizeof k2, "%s.name", key);
  if (!x) return fail(p, CUP_ERR_PARSE, nd, k2, "missing (required)");
  if ((st = word(p, x, k2, &name))) return st;
  if (strlen(name) >= SW_NAME_LEN)
    return fail(p, CUP_ERR_PARSE, x, k2, "longer than %d characters", SW_NAME_LEN - 1);
  for (long j = 0; j < nprev; j++)
    if (!strcmp(s->var[j].name, name))
      return fail(p, CUP_ERR_PARSE, x, k2, "'%s' is also the name of variants.%ld", name, j);
  if (!(v->name = strdup(name))) return CUP_ERR_NOMEM;
  if ((x = opt(nd, "scene"))) {
    snprintf(k2, sizeof k2, "%s.scene", key);
    if ((st = word(p, x, k2, &scene))) return st;
  } else if (!base) {
    return fail(p, CUP_ERR_PARSE, nd, key, "no scene: give base: at the top or scene: in this variant");
  } else {
    v->from_base = 1;
  }
  if (!(v->scene_file = path_join(s->dir, scene))) return CUP_ERR_NOMEM;
  if ((st = path_dir(v->scene_file, &v->scene_dir))) return st;
  if ((x = opt(nd, "set"))) {
    snprintf(k2, sizeof k2, "%s.set", key);
    if ((st = need_map(p, x, k2, "a mapping of dotted scene keys to values, e.g. {circuit.R1: 2}"))) return st;
    if (!(v->set = calloc((size_t)x->len + 1, sizeof *v->set))) return CUP_ERR_NOMEM;
    for (int j = 0; j < x->len; j++) {
      if (!(v->set[j] = override_text(x->key[j]->text, x->item[j]))) return CUP_ERR_NOMEM;
      v->n_set = j + 1;
    }
  }
  return CUP_OK;
}

static void variant_free(sw_variant *v) {
  free(v->name);
  free(v->scene_file);
  free(v->scene_dir);
  for (int j = 0; j < v->n_set; j++) free(v->set[j]);
  free(v->set);
  free(v->scene_text);
  free(v->file_text);
  cup_scene_free(&v->scene);
}

/* The variants entry e generates from its template t (name, scene, set). */
static int expand(rd *p, const st_node *e, const char *key, const sw_variant *t, sw_variant *out, long count) {
  sw_gen_variant *g = calloc((size_t)count, sizeof *g);
  if (!g) return CUP_ERR_NOMEM;
  int st = sw_gen_expand(p, e, key, t->name, SW_NAME_LEN, t->set, t->n_set, g, count);
  for (long j = 0; j < count; j++) {       /* each takes what it was given, whatever happened */
    sw_variant *v = &out[j];
    v->name = g[j].name, v->set = g[j].set, v->n_set = g[j].n_set;
    v->line = t->line, v->col = t->col, v->from_base = t->from_base;
    if (!st && (!(v->scene_file = strdup(t->scene_file)) || (t->scene_dir && !(v->scene_dir = strdup(t->scene_dir)))))
      st = CUP_ERR_NOMEM;
  }
  free(g);
  return st;
}

static int by_name(const void *a, const void *b) {
  return strcmp((*(const sw_variant *const *)a)->name, (*(const sw_variant *const *)b)->name);
}

/* Generated names ("NAME.J") may meet a written one: every name once. */
static int unique_names(rd *p, const sw_sweep *s, const st_node *nd) {
  const sw_variant **v = malloc(sizeof *v * (size_t)(s->n_variants + 1));
  if (!v) return CUP_ERR_NOMEM;
  for (int k = 0; k < s->n_variants; k++) v[k] = &s->var[k];
  qsort(v, (size_t)s->n_variants, sizeof *v, by_name);
  int st = CUP_OK;
  for (int k = 1; k < s->n_variants && !st; k++)
    if (!strcmp(v[k]->name, v[k - 1]->name))
      st = fail(p, CUP_ERR_PARSE, nd, "variants", "two variants are named '%s' (a generated name is the entry's "
                "name, a dot and its index)", v[k]->name);
  free(v);
  return st;
}

static int read_variants(rd *p, sw_sweep *s, const st_node *root) {
  const st_node *kb, *b = st_get(root, "base", &kb), *nd = opt(root, "variants");
  const char *base = NULL;
  int st = CUP_OK;
  if (b && !st_is_null(b) && (st = word(p, b, "base", &base))) return st;
  if (base) { s->base_line = b->line; s->base_col = b->col; }
  if (!nd) return fail(p, CUP_ERR_PARSE, root, "variants", "missing (required): a list of at least one variant, "
                       "e.g. [{name: case1}]");
  if (nd->kind != ST_SEQ || nd->len == 0)
    return fail(p, CUP_ERR_PARSE, nd, "variants", "expected a list of at least one variant (a mapping with name)");
  long total = 0, *count = calloc((size_t)nd->len, sizeof *count);
  char key[64];
  if (!count) return CUP_ERR_NOMEM;
  for (int k = 0; k < nd->len && !st; k++) {        /* what each entry generates (1: itself) */
    snprintf(key, sizeof key, "variants.%d", k);
    st = need_map(p, nd->item[k], key, "a mapping with name and optionally scene and set");
    if (!st) st = sw_gen_count(p, nd->item[k], key, &count[k]);
    total += count[k];
    if (!st && total > SW_GEN_MAX) st = fail(p, CUP_ERR_PARSE, nd->item[k], key, "more than %ld variants", SW_GEN_MAX);
  }
  if (!st && !(s->var = calloc((size_t)total, sizeof *s->var))) st = CUP_ERR_NOMEM;
  long at = 0;
  for (int k = 0; k < nd->len && !st; k++) {
    const st_node *e = nd->item[k];
    int generated = opt(e, "grid") || opt(e, "zip") || opt(e, "sample");
    sw_variant t = {0};
    s->n_variants = (int)(at + count[k]);         /* freed by sw_free, whatever happens */
    st = read_variant(p, s, e, k, base, generated ? &t : &s->var[at], at);
    snprintf(key, sizeof key, "variants.%d", k);
    if (!st && generated) st = expand(p, e, key, &t, &s->var[at], count[k]);
    if (generated) variant_free(&t);
    for (long j = 0; j < count[k]; j++) s->var[at + j].proto = (int)at;   /* the entry's first stands for it */
    at += count[k];
  }
  free(count);
  if (!st) st = unique_names(p, s, nd);
  return st;
}

/* ---- reference and output -------------------------------------------------- */

static int read_reference(rd *p, sw_sweep *s, const st_node *root) {
  static const char *const known[] = {"samples", "n", "method", "check", NULL};
  static const char *const methods[] = {"richardson", "adaptive", NULL};
  static const char *const checks[] = {"none", "richardson", NULL};
  const st_node *r = opt(root, "reference"), *x;
  s->samples = 1001;
  s->ref_n = 0;
  s->ref_method = SW_REF_RICHARDSON;
  int st = CUP_OK;
  if (!r) return st;
  if ((st = need_map(p, r, "reference", "a mapping with samples, n and method"))) return st;
  if ((st = check_keys(p, r, "reference", known))) return st;
  if ((x = opt(r, "method")) && (st = read_word_item(p, x, "reference.method", "reference method", methods,
                                                     &s->ref_method))) return st;
  if ((x = opt(r, "check")) && (st = read_word_item(p, x, "reference.check", "reference check", checks,
                                                    &s->ref_check))) return st;
  if (x && s->ref_check && s->ref_method != SW_REF_ADAPTIVE)
    return fail(p, CUP_ERR_PARSE, x, "reference.check", "checks the adaptive reference against the Richardson "
                "limit: it needs method: adaptive");
  if ((x = opt(r, "samples")) && (st = count(p, x, "reference.samples", 2, 1000001, &s->samples))) return st;
  if ((x = opt(r, "n")) && !(x->kind == ST_SCALAR && !x->quoted && !strcmp(x->text, "auto"))) {
    if ((st = count(p, x, "reference.n", 1, 4503599627370496L, &s->ref_n))) return st;
    if (s->ref_n % (s->samples - 1))
      return fail(p, CUP_ERR_PARSE, x, "reference.n", "must be a multiple of samples - 1 = %ld (got %ld), "
                  "so that the reference's grid holds every sample time; or write auto", s->samples - 1, s->ref_n);
  }
  return st;
}

static int read_output(rd *p, sw_sweep *s, const st_node *root) {
  static const char *const known[] = {"samples", NULL};
  const st_node *o = opt(root, "output"), *x;
  s->out_samples = s->samples;
  int st = CUP_OK;
  if (!o) return st;
  if ((st = need_map(p, o, "output", "a mapping with samples"))) return st;
  if ((st = check_keys(p, o, "output", known))) return st;
  s->out_given = opt(o, "samples") != NULL;
  if ((x = opt(o, "samples")) && !(st = count(p, x, "output.samples", 0, 1000001, &s->out_samples)) &&
      s->out_samples != 0 && s->out_samples != s->samples)
    return fail(p, CUP_ERR_PARSE, x, "output.samples", "must be 0 (no trajectories) or reference.samples = %ld "
                "(trajectories are stored at the common sample times), got %ld", s->samples, s->out_samples);
  return st;
}

/* ---- public: parse and resolve ---------------------------------------------- */

static int read_sweep(rd *p, sw_sweep *s, const st_node *root) {
  static const char *const known[] = {"name", "base", "grid", "variants", "reference", "output", NULL};
  int st = need_map(p, root, NULL, "a mapping with base, grid and variants");
  if (!st) st = check_keys(p, root, "", known);
  const st_node *x;
  const char *name = NULL;
  if (!st && (x = opt(root, "name")) && !(st = word(p, x, "name", &name)) && !(s->name = strdup(name)))
    st = CUP_ERR_NOMEM;
  if (!st) st = read_grid(p, s, root);
  if (!st) st = read_reference(p, s, root);
  if (!st) st = read_output(p, s, root);
  if (!st) st = read_variants(p, s, root);
  return st;
}

int sw_parse(sw_sweep **out, const char *text, size_t len, const char *path, char *errmsg) {
  *out = NULL;
  if (errmsg) errmsg[0] = '\0';
  sw_sweep *s = calloc(1, sizeof *s);
  if (!s) return CUP_ERR_NOMEM;
  rd p = {{path, NULL}, NULL, errmsg, NULL};
  st_node *root = NULL;
  s->path = strdup(path);
  s->text = malloc(len + 1);
  int st = s->path && s->text ? path_dir(path, &s->dir) : CUP_ERR_NOMEM;
  if (!st) {
    memcpy(s->text, text, len);
    s->text[len] = '\0';
    sha256_hex(text, len, s->sha256);
    st = st_parse(&root, text, len, &p.src, -1, NULL, errmsg);
  }
  if (!st) st = read_sweep(&p, s, root);
  if (!st && !s->name && !(s->name = path_stem(path))) st = CUP_ERR_NOMEM;
  st_free(root);
  if (st == CUP_ERR_NOMEM && errmsg) snprintf(errmsg, SW_ERR_LEN, "%s: out of memory", path);
  if (st) { sw_free(&s); return st; }
  *out = s;
  return CUP_OK;
}

int sw_load(sw_sweep **s, const char *path, char *errmsg) {
  *s = NULL;
  char *buf = NULL;
  size_t n = 0;
  file_list files = {0};
  int rt = read_text(path, &buf, &n, &files, errmsg);   /* errmsg: SW_ERR_LEN >= CUP_ERRMSG_LEN */
  if (rt) return rt;
  int st = sw_parse(s, buf, n, path, errmsg);
  if (!st) (*s)->files = files;
  else file_list_free(&files);
  free(buf);
  return st;
}

/* Axis a leads its zip group (or is not zipped). */
static int leads(const sw_sweep *s, int a) {
  for (int b = 0; b < a; b++)
    if (s->zip[a] >= 0 && s->zip[b] == s->zip[a]) return 0;
  return 1;
}

int sw_variant_lazy(const sw_sweep *s, int k) { return !s->crowd && s->var[k].proto != k; }

const cup_scene *sw_variant_settings(const sw_sweep *s, int k) {
  return s->var[k].scene ? s->var[k].scene : s->var[s->var[k].proto].scene;
}

void sw_count_tasks(sw_sweep *s) {
  s->per_variant = 1;
  for (int a = 0; a < SW_NAXES; a++)          /* a zip group counts once */
    if (s->len[a] && leads(s, a)) s->per_variant *= s->len[a];
  s->n_tasks = s->per_variant * s->n_variants;
}

void sw_free(sw_sweep **ps) {
  if (!ps || !*ps) return;
  sw_sweep *s = *ps;
  for (int k = 0; k < s->n_variants; k++) variant_free(&s->var[k]);
  free(s->var);
  for (int k = 0; k < s->len[SW_AXIS_EPS]; k++) free(s->eps[k]);
  for (int k = 0; k < s->len[SW_AXIS_ETA]; k++) free(s->eta[k]);
  free(s->n); free(s->eps); free(s->eta); free(s->scheme); free(s->projector); free(s->tol);
  free(s->path); free(s->dir); free(s->text); free(s->name);
  file_list_free(&s->files);
  free(s);
  *ps = NULL;
}

/* ---- tasks ------------------------------------------------------------------ */

double sw_max_error(const double *traj, const double *ref, long count) {
  double e = 0;
  for (long j = 0; j < count; j++) {
    double d = fabs(traj[j] - ref[j]);
    if (isnan(d)) return NAN;
    if (d > e) e = d;
  }
  return e;
}

int sw_task_get(const sw_sweep *s, long id, sw_task *t) {
  if (id < 0 || id >= s->n_tasks) return CUP_ERR_ARG;
  memset(t, 0, sizeof *t);
  t->id = id;
  t->variant = (int)(id / s->per_variant);
  long local = id % s->per_variant;
  int d[SW_NAXES] = {0};
  for (int a = SW_NAXES - 1; a >= 0; a--)    /* the last axis varies fastest */
    if (s->len[a] && leads(s, a)) {
      d[a] = (int)(local % s->len[a]);
      local /= s->len[a];
    }
  for (int a = 0; a < SW_NAXES; a++)
    if (s->zip[a] >= 0 && !leads(s, a))
      for (int b = 0; b < a; b++)
        if (s->zip[b] == s->zip[a]) { d[a] = d[b]; break; }
  const cup_scene *sc = sw_variant_settings(s, t->variant);
  const cup_integrator_options *o = cup_scene_options(sc);
  t->n = s->len[SW_AXIS_N] ? s->n[d[SW_AXIS_N]] : o->n;
  t->eps = s->len[SW_AXIS_EPS] ? s->eps[d[SW_AXIS_EPS]] : cup_scene_eps_spec(sc);
  t->eta = s->len[SW_AXIS_ETA] ? s->eta[d[SW_AXIS_ETA]] : cup_scene_eta_spec(sc);
  t->scheme = s->len[SW_AXIS_SCHEME] ? s->scheme[d[SW_AXIS_SCHEME]] : (int)o->scheme;
  t->projector = s->len[SW_AXIS_PROJECTOR] ? s->projector[d[SW_AXIS_PROJECTOR]] : (int)o->proj.method;
  t->tol_abs = s->len[SW_AXIS_TOL] ? s->tol[d[SW_AXIS_TOL]] : o->tol_abs;
  t->tol_rel = s->len[SW_AXIS_TOL] ? s->tol[d[SW_AXIS_TOL]] : o->tol_rel;
  if (cup_schedule_parse(t->eps, &t->eps_s, NULL) || cup_schedule_parse(t->eta, &t->eta_s, NULL))
    return CUP_ERR_PARSE;
  return CUP_OK;
}

/* Seconds per step relative to the explicit scheme with the default
 * projector, measured on the paper's circuit (~0.12 us a step), and a fixed
 * part for set-up (~10 us). Schemes and projectors not listed count 1;
 * crowds count by their agents. */
double sw_job_cost(const sw_sweep *s, long job) {
  static const double scheme_f[] = {1.0, 1.0, 1.1, 0.8}, proj_f[] = {1.0, 1.0, 1.3, 1.2};
  const double setup = 100;
  if (job < s->n_variants && (s->crowd || s->steady)) return 0;   /* a crowd's reference computes nothing */
  /* a steady state: a few Newton steps of n + 1 period runs, and its period
   * sampled (about 0.2 ms on a buck, BENCHMARKS.md) */
  if (s->steady) return 2000;
  if (job < s->n_variants && s->ref_method == SW_REF_ADAPTIVE)
    return 8.0 * (double)s->samples + 10 * setup + (s->ref_check ? 3.0 * ((double)s->var[job].n_ref + setup) : 0);
  if (job < s->n_variants) return 3.0 * ((double)s->var[job].n_ref + setup);
  sw_task t;
  if (sw_task_get(s, job - s->n_variants, &t)) return 0;
  double fs = t.scheme >= 0 && t.scheme < (int)(sizeof scheme_f / sizeof *scheme_f) ? scheme_f[t.scheme] : 1;
  double fp = t.projector >= 0 && t.projector < (int)(sizeof proj_f / sizeof *proj_f) ? proj_f[t.projector] : 1;
  /* the adaptive scheme takes about one step per sample time, ~4 units each */
  if (t.scheme == CUP_SCHEME_ADAPTIVE) return 4.0 * (double)s->samples + 10 * setup;
  /* a crowd's step costs about 0.7 us an agent (BENCHMARKS.md, "Crowds"):
   * counted as the circuit's, 1000 agents made a 20 ms batch of 180 tasks
   * of a second each, sent to one rank */
  if (s->crowd) return ((double)t.n + setup) * 3.5 * (double)cup_scene_dim(sw_variant_settings(s, t.variant));
  return ((double)t.n + setup) * fs * fp;
}

typedef struct { double cost; long job; } keyed;

static int by_cost(const void *a, const void *b) {
  const keyed *x = a, *y = b;
  if (x->cost != y->cost) return x->cost > y->cost ? -1 : 1;
  return (x->job > y->job) - (x->job < y->job);
}

/* Tasks go out in blocks of consecutive ids, largest first: a block grows
 * along the ids while its costs stay within SW_BLOCK_SPREAD of each other,
 * and the blocks are ordered by their largest cost. The big tasks still
 * start first and the small ones make the tail, as with a plain sort by cost
 * (the estimates are rougher than that factor anyway), but a batch of small
 * tasks is then mostly one range of ids, which rank 0 writes at once. */
void sw_schedule(const sw_sweep *s, long *out) {
  long V = s->n_variants, N = s->n_tasks, nb = 0;
  keyed *k = malloc(sizeof *k * (size_t)(V + N));
  keyed *block = malloc(sizeof *block * (size_t)(N + 1));
  long *first = malloc(sizeof *first * (size_t)(N + 1));
  if (!k || !block || !first) {              /* order only affects speed */
    for (long j = 0; j < V + N; j++) out[j] = j;
    free(k); free(block); free(first);
    return;
  }
  for (long j = 0; j < V + N; j++) k[j] = (keyed){sw_job_cost(s, j), j};
  qsort(k, (size_t)V, sizeof *k, by_cost);
  for (long j = 0; j < V; j++) out[j] = k[j].job;
  for (long t = 0; t < N; nb++) {           /* block nb: its largest cost, its index */
    double lo = k[V + t].cost, hi = lo;
    first[nb] = t;
    for (t++; t < N; t++) {
      double c = k[V + t].cost, l = fmin(lo, c), h = fmax(hi, c);
      if (h > SW_BLOCK_SPREAD * l) break;
      lo = l;
      hi = h;
    }
    block[nb] = (keyed){hi, nb};
  }
  first[nb] = N;
  qsort(block, (size_t)nb, sizeof *block, by_cost);
  long at = V;
  for (long b = 0; b < nb; b++)
    for (long t = first[block[b].job]; t < first[block[b].job + 1]; t++) out[at++] = V + t;
  free(k);
  free(block);
  free(first);
}

/* ---- grid text ---------------------------------------------------------------- */

typedef struct { char *s; size_t len, cap; } sbuf;

__attribute__((format(printf, 2, 3)))
static void sb_printf(sbuf *b, const char *fmt, ...) {
  va_list ap;
  for (;;) {
    if (!b->s) return;
    va_start(ap, fmt);
    int w = vsnprintf(b->s + b->len, b->cap - b->len, fmt, ap);
    va_end(ap);
    if (w < 0) return;
    if ((size_t)w < b->cap - b->len) { b->len += (size_t)w; return; }
    char *ns = realloc(b->s, b->cap = 2 * b->cap + (size_t)w);
    if (!ns) { free(b->s); b->s = NULL; return; }
    b->s = ns;
  }
}

char *sw_grid_text(const sw_sweep *s) {
  sbuf b = {malloc(256), 0, 256};
  if (b.s) b.s[0] = '\0';
  for (int a = 0; a < SW_NAXES; a++) {
    sb_printf(&b, "%s%s: ", a ? "; " : "", axis_names[a]);
    if (!s->len[a]) { sb_printf(&b, "from each variant's scene"); continue; }
    sb_printf(&b, "[");
    for (int k = 0; k < s->len[a]; k++) {
      const char *sep = k ? ", " : "";
      if (a == SW_AXIS_N) sb_printf(&b, "%s%ld", sep, s->n[k]);
      else if (a == SW_AXIS_EPS) sb_printf(&b, "%s\"%s\"", sep, s->eps[k]);
      else if (a == SW_AXIS_ETA) sb_printf(&b, "%s\"%s\"", sep, s->eta[k]);
      else if (a == SW_AXIS_SCHEME) sb_printf(&b, "%s%s", sep, cup_scheme_name(s->scheme[k]));
      else if (a == SW_AXIS_TOL) sb_printf(&b, "%s%g", sep, s->tol[k]);
      else sb_printf(&b, "%s%s", sep, cup_proj_method_name(s->projector[k]));
    }
    sb_printf(&b, "]");
  }
  for (int g = 0; g < SW_NAXES; g++) {
    int first = 1;
    for (int a = 0; a < SW_NAXES; a++)
      if (s->zip[a] == g) { sb_printf(&b, "%s%s", first ? "; zip: [" : ", ", axis_names[a]); first = 0; }
    if (!first) sb_printf(&b, "]");
  }
  sb_printf(&b, "; tasks: %ld variants x %ld = %ld (variant-major, then n, eps, eta, scheme, projector, tol; "
            "the last varies fastest)", (long)s->n_variants, s->per_variant, s->n_tasks);
  return b.s;
}

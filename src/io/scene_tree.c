/* scene_tree — a YAML document as a small tree with positions, overrides
 * spliced into it, and the tree written back as YAML (for provenance). */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>
#include "catchup/status.h"
#include "catchup/sparse.h"
#include "scene_tree.h"

/* Aliases can make a document recursive (&a [*a]) or exponentially large
 * ("billion laughs"): both stop here with a message instead of a crash. */
#define ST_MAX_DEPTH 64
#define ST_MAX_NODES (1L << 21)

/* ---- messages ------------------------------------------------------------ */

int st_verror(char *errmsg, int status, const st_src *src, const st_node *at,
              const char *key, const char *fmt, va_list ap) {
  if (!errmsg) return status;
  size_t cap = CUP_ERRMSG_LEN;
  int w;
  if (at && at->origin >= 0 && src->ovr)
    w = snprintf(errmsg, cap, "override '%s': ", src->ovr[at->origin]);
  else if (at)
    w = snprintf(errmsg, cap, "%s:%d:%d: ", src->file, at->line, at->col);
  else
    w = snprintf(errmsg, cap, "%s: ", src->file);
  if (w >= 0 && (size_t)w < cap && key && *key)
    w += snprintf(errmsg + w, cap - (size_t)w, "%s: ", key);
  if (w >= 0 && (size_t)w < cap) vsnprintf(errmsg + w, cap - (size_t)w, fmt, ap);
  for (char *c = errmsg; *c; c++)            /* one line, always */
    if (*c == '\n' || *c == '\r') *c = ' ';
  return status;
}

int st_error(char *errmsg, int status, const st_src *src, const st_node *at,
             const char *key, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  st_verror(errmsg, status, src, at, key, fmt, ap);
  va_end(ap);
  return status;
}

/* ---- nodes --------------------------------------------------------------- */

static st_node *node_new(st_kind kind, int line, int col, int origin) {
  st_node *nd = calloc(1, sizeof *nd);
  if (nd) { nd->kind = kind; nd->line = line; nd->col = col; nd->origin = origin; }
  return nd;
}

static st_node *scalar_new(const char *text, size_t len, int quoted, int line, int col, int origin) {
  st_node *nd = node_new(ST_SCALAR, line, col, origin);
  if (!nd) return NULL;
  nd->text = malloc(len + 1);
  if (!nd->text) { free(nd); return NULL; }
  memcpy(nd->text, text, len);
  nd->text[len] = '\0';
  nd->quoted = quoted;
  return nd;
}

void st_free(st_node *nd) {
  if (!nd) return;
  for (int k = 0; k < nd->len; k++) {
    st_free(nd->item[k]);
    if (nd->key) st_free(nd->key[k]);
  }
  free(nd->item);
  free(nd->key);
  free(nd->text);
  free(nd);
}

/* Append an item (SEQ) or an entry (MAP; key is then non-NULL). */
static int node_push(st_node *nd, st_node *key, st_node *item) {
  if (nd->len == nd->cap) {
    int cap = nd->cap ? 2 * nd->cap : 4;
    st_node **ni = realloc(nd->item, sizeof *ni * (size_t)cap);
    if (!ni) return CUP_ERR_NOMEM;
    nd->item = ni;
    if (nd->kind == ST_MAP) {
      st_node **nk = realloc(nd->key, sizeof *nk * (size_t)cap);
      if (!nk) return CUP_ERR_NOMEM;
      nd->key = nk;
    }
    nd->cap = cap;
  }
  if (nd->kind == ST_MAP) nd->key[nd->len] = key;
  nd->item[nd->len++] = item;
  return CUP_OK;
}

static int map_find(const st_node *map, const char *key) {
  for (int k = 0; map && map->kind == ST_MAP && k < map->len; k++)
    if (strcmp(map->key[k]->text, key) == 0) return k;
  return -1;
}

const st_node *st_get(const st_node *map, const char *key, const st_node **keynode) {
  int k = map_find(map, key);
  if (keynode) *keynode = k >= 0 ? map->key[k] : NULL;
  return k >= 0 ? map->item[k] : NULL;
}

int st_is_null(const st_node *nd) {
  if (!nd || nd->kind != ST_SCALAR || nd->quoted) return 0;
  const char *t = nd->text;
  return !*t || !strcmp(t, "~") || !strcmp(t, "null") || !strcmp(t, "Null") || !strcmp(t, "NULL");
}

/* YAML 1.2 core schema numbers in decimal: [-+]?(digits[.digits*]|.digits)
 * [eE[-+]digits], and [-+].inf / .nan in their three spellings. */
int st_number(const char *s, double *out) {
  const char *p = s + (*s == '-' || *s == '+');
  if (!strcmp(p, ".inf") || !strcmp(p, ".Inf") || !strcmp(p, ".INF")) {
    *out = *s == '-' ? -INFINITY : INFINITY;
    return 1;
  }
  if (p == s && (!strcmp(s, ".nan") || !strcmp(s, ".NaN") || !strcmp(s, ".NAN"))) {
    *out = NAN;
    return 1;
  }
  int digits = 0;
  while (isdigit((unsigned char)*p)) { p++; digits++; }
  if (*p == '.') for (p++; isdigit((unsigned char)*p); p++) digits++;
  if (!digits) return 0;
  if (*p == 'e' || *p == 'E') {
    p += 1 + (p[1] == '-' || p[1] == '+');
    if (!isdigit((unsigned char)*p)) return 0;
    while (isdigit((unsigned char)*p)) p++;
  }
  if (*p) return 0;
  *out = strtod(s, NULL);
  return 1;
}

/* ---- key suggestions ------------------------------------------------------ */

/* Optimal string alignment distance, case-insensitive (R1 vs r1 is 0). */
static int osa_distance(const char *a, const char *b) {
  int la = (int)strlen(a), lb = (int)strlen(b);
  if (la > 30 || lb > 30) return 99;
  int d[32][32];
  for (int i = 0; i <= la; i++) d[i][0] = i;
  for (int j = 0; j <= lb; j++) d[0][j] = j;
  for (int i = 1; i <= la; i++)
    for (int j = 1; j <= lb; j++) {
      int c = tolower((unsigned char)a[i - 1]) != tolower((unsigned char)b[j - 1]);
      int v = d[i - 1][j - 1] + c;
      if (d[i - 1][j] + 1 < v) v = d[i - 1][j] + 1;
      if (d[i][j - 1] + 1 < v) v = d[i][j - 1] + 1;
      if (i > 1 && j > 1 && tolower((unsigned char)a[i - 1]) == tolower((unsigned char)b[j - 2]) &&
          tolower((unsigned char)a[i - 2]) == tolower((unsigned char)b[j - 1]) && d[i - 2][j - 2] + 1 < v)
        v = d[i - 2][j - 2] + 1;
      d[i][j] = v;
    }
  return d[la][lb];
}

/* The closest of `known` to `word` if it is close enough to be a typo. */
static const char *closest(const char *word, const char *const *known) {
  const char *best = NULL;
  int bd = 3;
  for (int k = 0; known[k]; k++) {
    int d = osa_distance(word, known[k]);
    if (d < bd && d < (int)strlen(known[k])) { bd = d; best = known[k]; }
  }
  return best;
}

const st_node *st_unknown_key(const st_node *map, const char *const *known) {
  for (int k = 0; k < map->len; k++) {
    int ok = 0;
    for (int j = 0; known[j] && !ok; j++) ok = strcmp(map->key[k]->text, known[j]) == 0;
    if (!ok) return map->key[k];
  }
  return NULL;
}

const char *st_looks(const st_node *nd, char *buf, size_t n) {
  if (st_is_null(nd)) return "nothing";
  if (nd->kind == ST_SEQ) return nd->len ? "a list" : "an empty list";
  if (nd->kind == ST_MAP) return "a mapping";
  snprintf(buf, n, "'%.40s'", nd->text);
  return buf;
}

const char *st_suggest(char *buf, size_t n, const char *word, const char *const *known) {
  const char *c = closest(word, known);
  if (c) { snprintf(buf, n, "did you mean '%s'?", c); return buf; }
  size_t w = (size_t)snprintf(buf, n, "expected one of");
  for (int k = 0; known[k] && w < n; k++)
    w += (size_t)snprintf(buf + w, n - w, "%s %s", k ? "," : "", known[k]);
  return buf;
}

/* ---- libyaml document -> tree -------------------------------------------- */

typedef struct conv {
  yaml_document_t *doc;
  const st_src *src;
  int origin;
  const char *key;
  long count;
  char *errmsg;
} conv;

static int conv_node(conv *c, yaml_node_t *yn, int depth, st_node **out);

static int conv_fail(conv *c, const yaml_node_t *yn, const char *msg) {
  st_node at = {0};
  at.line = (int)yn->start_mark.line + 1;
  at.col = (int)yn->start_mark.column + 1;
  at.origin = c->origin;
  return st_error(c->errmsg, CUP_ERR_PARSE, c->src, &at, c->key, "%s", msg);
}

static int conv_scalar(conv *c, yaml_node_t *yn, st_node *nd) {
  const char *v = (const char *)yn->data.scalar.value;
  size_t len = yn->data.scalar.length;
  if (memchr(v, '\0', len)) return conv_fail(c, yn, "a scalar contains a NUL character");
  nd->text = malloc(len + 1);
  if (!nd->text) return CUP_ERR_NOMEM;
  memcpy(nd->text, v, len);
  nd->text[len] = '\0';
  nd->quoted = yn->data.scalar.style != YAML_PLAIN_SCALAR_STYLE;
  return CUP_OK;
}

static int conv_seq(conv *c, yaml_node_t *yn, int depth, st_node *nd) {
  for (yaml_node_item_t *it = yn->data.sequence.items.start; it < yn->data.sequence.items.top; it++) {
    st_node *item = NULL;
    int st = conv_node(c, yaml_document_get_node(c->doc, *it), depth + 1, &item);
    if (!st && node_push(nd, NULL, item)) st = CUP_ERR_NOMEM;
    if (st) { st_free(item); return st; }
  }
  return CUP_OK;
}

static int conv_map(conv *c, yaml_node_t *yn, int depth, st_node *nd) {
  for (yaml_node_pair_t *pr = yn->data.mapping.pairs.start; pr < yn->data.mapping.pairs.top; pr++) {
    yaml_node_t *yk = yaml_document_get_node(c->doc, pr->key);
    if (yk->type != YAML_SCALAR_NODE) return conv_fail(c, yk, "mapping keys must be plain words, not lists or mappings");
    st_node *k = NULL, *v = NULL;
    int st = conv_node(c, yk, depth + 1, &k);
    if (!st && map_find(nd, k->text) >= 0) {
      const char *outer = c->key;               /* the key text names it */
      c->key = k->text;
      st = conv_fail(c, yk, "duplicate key: given twice in the same mapping");
      c->key = outer;
    }
    if (!st) st = conv_node(c, yaml_document_get_node(c->doc, pr->value), depth + 1, &v);
    if (!st && node_push(nd, k, v)) st = CUP_ERR_NOMEM;
    if (st) { st_free(k); st_free(v); return st; }
  }
  return CUP_OK;
}

static int conv_node(conv *c, yaml_node_t *yn, int depth, st_node **out) {
  *out = NULL;
  if (depth > ST_MAX_DEPTH) return conv_fail(c, yn, "nested too deeply (a recursive alias?)");
  if (++c->count > ST_MAX_NODES)
    return conv_fail(c, yn, "document too large (aliases expand to over 2 million nodes); "
                            "put large matrices in Matrix Market files");
  st_kind kind = yn->type == YAML_MAPPING_NODE ? ST_MAP : yn->type == YAML_SEQUENCE_NODE ? ST_SEQ : ST_SCALAR;
  st_node *nd = node_new(kind, (int)yn->start_mark.line + 1, (int)yn->start_mark.column + 1, c->origin);
  if (!nd) return CUP_ERR_NOMEM;
  int st = kind == ST_SCALAR ? conv_scalar(c, yn, nd)
         : kind == ST_SEQ    ? conv_seq(c, yn, depth, nd)
                             : conv_map(c, yn, depth, nd);
  if (st) { st_free(nd); return st; }
  *out = nd;
  return CUP_OK;
}

/* libyaml's problem and its context as one message at the problem's mark. */
static int tab_indented(const char *text, size_t len, size_t line) {
  size_t i = 0;
  for (size_t l = 0; l < line && i < len; i++)
    if (text[i] == '\n') l++;
  for (; i < len && (text[i] == ' ' || text[i] == '\t'); i++)
    if (text[i] == '\t') return 1;
  return 0;
}

static int syntax_error(const yaml_parser_t *ps, const char *text, size_t len, const st_src *src,
                        int origin, const char *key, char *errmsg) {
  if (ps->error == YAML_MEMORY_ERROR) return CUP_ERR_NOMEM;
  st_node at = {0};
  at.line = (int)ps->problem_mark.line + 1;
  at.col = (int)ps->problem_mark.column + 1;
  at.origin = origin;
  const char *problem = ps->problem ? ps->problem : "malformed YAML";
  /* libyaml only says "found character that cannot start any token" */
  const char *hint = !strstr(problem, "tab") && tab_indented(text, len, ps->problem_mark.line)
                         ? " (a tab in the indentation: YAML indents with spaces only)" : "";
  char where[96] = "";
  if (origin >= 0) snprintf(where, sizeof where, " at column %d", at.col);
  if (ps->context)
    return st_error(errmsg, CUP_ERR_PARSE, src, &at, key, "YAML syntax error: %s%s%s (%s at %d:%d)",
                    problem, hint, where, ps->context, (int)ps->context_mark.line + 1,
                    (int)ps->context_mark.column + 1);
  return st_error(errmsg, CUP_ERR_PARSE, src, &at, key, "YAML syntax error: %s%s%s", problem, hint, where);
}

/* A second document after the first is refused: a scene is one document. */
static int check_single(yaml_parser_t *ps, const char *text, size_t len, const st_src *src,
                        int origin, const char *key, char *errmsg) {
  yaml_document_t doc2;
  if (!yaml_parser_load(ps, &doc2)) return syntax_error(ps, text, len, src, origin, key, errmsg);
  yaml_node_t *r2 = yaml_document_get_root_node(&doc2);
  int st = CUP_OK;
  if (r2) {
    st_node at = {0};
    at.line = (int)r2->start_mark.line + 1;
    at.col = (int)r2->start_mark.column + 1;
    at.origin = origin;
    st = st_error(errmsg, CUP_ERR_PARSE, src, &at, key, "a second YAML document; a scene is one document");
  }
  yaml_document_delete(&doc2);
  return st;
}

int st_parse(st_node **root, const char *text, size_t len, const st_src *src, int origin,
             const char *key, char *errmsg) {
  *root = NULL;
  yaml_parser_t ps;
  yaml_document_t doc;
  if (!yaml_parser_initialize(&ps)) return CUP_ERR_NOMEM;
  yaml_parser_set_input_string(&ps, (const unsigned char *)text, len);
  if (!yaml_parser_load(&ps, &doc)) {
    int st = syntax_error(&ps, text, len, src, origin, key, errmsg);
    yaml_parser_delete(&ps);
    return st;
  }
  yaml_node_t *yr = yaml_document_get_root_node(&doc);
  int st = CUP_OK;
  if (yr) {
    conv c = {&doc, src, origin, key, 0, errmsg};
    st = conv_node(&c, yr, 0, root);
  } else {
    *root = scalar_new("", 0, 0, 1, 1, origin);
    if (!*root) st = CUP_ERR_NOMEM;
  }
  yaml_document_delete(&doc);
  if (!st) st = check_single(&ps, text, len, src, origin, key, errmsg);
  yaml_parser_delete(&ps);
  if (st) { st_free(*root); *root = NULL; }
  return st;
}

/* ---- overrides ----------------------------------------------------------- */

/* A 0-based sequence index written in decimal digits only, or -1. */
static int parse_index(const char *s) {
  if (!*s || strlen(s) > 9) return -1;
  for (const char *p = s; *p; p++)
    if (!isdigit((unsigned char)*p)) return -1;
  return atoi(s);
}

static int ovr_fail(char *errmsg, const st_src *src, int k, const char *path, const char *fmt, ...)
  __attribute__((format(printf, 5, 6)));
static int ovr_fail(char *errmsg, const st_src *src, int k, const char *path, const char *fmt, ...) {
  st_node at = {0};
  at.origin = k;
  va_list ap;
  va_start(ap, fmt);
  st_verror(errmsg, CUP_ERR_PARSE, src, &at, path, fmt, ap);
  va_end(ap);
  return CUP_ERR_PARSE;
}

st_node *st_new_map(int origin) { return node_new(ST_MAP, 0, 0, origin); }

int st_map_put(st_node *map, const char *key, st_node *val, int origin) {
  st_node *k = scalar_new(key, strlen(key), 0, 0, 0, origin);
  if (!k || node_push(map, k, val)) { st_free(k); return CUP_ERR_NOMEM; }
  return CUP_OK;
}

void st_map_remove(st_node *map, const char *key) {
  int k = map_find(map, key);
  if (k < 0) return;
  st_free(map->key[k]);
  st_free(map->item[k]);
  for (int j = k + 1; j < map->len; j++) {
    map->key[j - 1] = map->key[j];
    map->item[j - 1] = map->item[j];
  }
  map->len--;
}

/* Put `val` at `seg` of `parent`: a mapping gets the key (added if absent),
 * a sequence must already have the index. *slot receives the node now there
 * (for walking on). val NULL walks: it creates an empty mapping when the key
 * is absent and leaves an existing value in place. */
static int put(st_node *parent, const char *seg, st_node *val, int k_ovr, st_node **slot,
               const st_src *src, const char *path, char *errmsg) {
  if (parent->kind == ST_MAP) {
    int k = map_find(parent, seg);
    if (k >= 0 && !val) { *slot = parent->item[k]; return CUP_OK; }
    if (k >= 0) { st_free(parent->item[k]); parent->item[k] = val; *slot = val; return CUP_OK; }
    st_node *key = scalar_new(seg, strlen(seg), 0, 0, 0, k_ovr);
    st_node *v = val ? val : node_new(ST_MAP, 0, 0, k_ovr);
    if (!key || !v || node_push(parent, key, v)) {
      st_free(key);
      if (!val) st_free(v);
      return CUP_ERR_NOMEM;
    }
    *slot = v;
    return CUP_OK;
  }
  if (parent->kind == ST_SEQ) {
    int i = parse_index(seg);
    if (i < 0 || i >= parent->len)
      return ovr_fail(errmsg, src, k_ovr, path, "no such item: the list has %d item%s, counted from 0",
                      parent->len, parent->len == 1 ? "" : "s");
    if (val) { st_free(parent->item[i]); parent->item[i] = val; }
    *slot = parent->item[i];
    return CUP_OK;
  }
  return ovr_fail(errmsg, src, k_ovr, path, "cannot go into '%.60s', which is a single value", parent->text);
}

/* Split "a.b.0=value" at the first '=' and walk the dotted key, splicing the
 * parsed value in at the end. Intermediate mapping keys that are absent are
 * created, so "output.every=10" works when the file has no output. */
int st_apply_override(st_node **root, const st_src *src, int k, st_reshape_fn reshape, st_verbatim_fn verbatim,
                      char *errmsg) {
  const char *o = src->ovr[k];
  st_node at = {0};
  at.origin = k;
  const char *eq = o ? strchr(o, '=') : NULL;
  if (!eq) return st_error(errmsg, CUP_ERR_PARSE, src, &at, NULL, "expected KEY=VALUE");
  size_t klen = (size_t)(eq - o);
  while (klen && isspace((unsigned char)o[klen - 1])) klen--;
  while (klen && isspace((unsigned char)*o)) { o++; klen--; }
  if (!klen) return st_error(errmsg, CUP_ERR_PARSE, src, &at, NULL, "empty key before '='");
  char *key = malloc(klen + 1), *walk = malloc(klen + 1);
  if (!key || !walk) { free(key); free(walk); return CUP_ERR_NOMEM; }
  memcpy(key, o, klen);
  key[klen] = '\0';
  memcpy(walk, key, klen + 1);
  st_node *val = NULL;
  int st = CUP_OK;
  if (verbatim && verbatim(key)) {
    const char *v = eq + 1;
    size_t vlen = strlen(v);
    while (vlen && isspace((unsigned char)*v)) { v++; vlen--; }
    while (vlen && isspace((unsigned char)v[vlen - 1])) vlen--;
    if (!(val = scalar_new(v, vlen, 1, 0, 0, k))) st = CUP_ERR_NOMEM;
  } else {
    st = st_parse(&val, eq + 1, strlen(eq + 1), src, k, key, errmsg);
  }
  if (!st && (*root)->kind != ST_MAP)
    st = st_error(errmsg, CUP_ERR_PARSE, src, &at, key, "the document is not a mapping");
  st_node **slot = root;                     /* where the node we are in hangs */
  char *seg = walk;
  while (!st) {
    char *dot = strchr(seg, '.');
    if (dot) *dot = '\0';
    if (!*seg) { st = st_error(errmsg, CUP_ERR_PARSE, src, &at, key, "empty part in the dotted key"); break; }
    char here[CUP_ERRMSG_LEN];                 /* the key of *slot ("" for the document) */
    snprintf(here, sizeof here, "%.*s", seg > walk ? (int)(seg - walk - 1) : 0, key);
    if (reshape && (st = reshape(slot, here, seg, dot ? NULL : val, k))) break;
    char path[CUP_ERRMSG_LEN];                 /* the key up to here, for messages */
    snprintf(path, sizeof path, "%.*s", (int)(seg + strlen(seg) - walk), key);
    st_node *cur = *slot, *next = NULL;
    st = put(cur, seg, dot ? NULL : val, k, &next, src, path, errmsg);
    if (st || !dot) break;
    slot = cur->kind == ST_MAP ? &cur->item[map_find(cur, seg)] : &cur->item[parse_index(seg)];
    seg = dot + 1;
  }
  if (!st) val = NULL;                       /* now owned by the tree */
  st_free(val);
  free(key);
  free(walk);
  return st;
}

/* ---- tree -> YAML text --------------------------------------------------- */

typedef struct outbuf { char *s; size_t len, cap; int fail; } outbuf;

static int out_write(void *data, unsigned char *buf, size_t size) {
  outbuf *o = data;
  if (o->len + size + 1 > o->cap) {
    size_t cap = o->cap ? o->cap : 1024;
    while (cap < o->len + size + 1) cap *= 2;
    char *ns = realloc(o->s, cap);
    if (!ns) { o->fail = 1; return 0; }
    o->s = ns;
    o->cap = cap;
  }
  memcpy(o->s + o->len, buf, size);
  o->len += size;
  o->s[o->len] = '\0';
  return 1;
}

static int plain_number(const st_node *nd) {
  double v;
  return nd->kind == ST_SCALAR && !nd->quoted && st_number(nd->text, &v);
}

/* Strings keep their quotes (so "1" stays a string); plain scalars stay
 * plain (so numbers and nulls stay what they were). */
static int emit_scalar(yaml_emitter_t *em, const st_node *nd) {
  yaml_event_t ev;
  int q = nd->quoted;
  if (!yaml_scalar_event_initialize(&ev, NULL, NULL, (yaml_char_t *)nd->text, (int)strlen(nd->text),
                                    !q, q, q ? YAML_DOUBLE_QUOTED_SCALAR_STYLE : YAML_PLAIN_SCALAR_STYLE))
    return 0;
  return yaml_emitter_emit(em, &ev);
}

static int emit_node(yaml_emitter_t *em, const st_node *nd) {
  yaml_event_t ev;
  if (nd->kind == ST_SCALAR) return emit_scalar(em, nd);
  if (nd->kind == ST_SEQ) {
    int flow = nd->len > 0;                   /* rows of numbers read best as [a, b, c] */
    for (int k = 0; k < nd->len && flow; k++) flow = plain_number(nd->item[k]);
    if (!yaml_sequence_start_event_initialize(&ev, NULL, NULL, 1,
                                              flow ? YAML_FLOW_SEQUENCE_STYLE : YAML_BLOCK_SEQUENCE_STYLE) ||
        !yaml_emitter_emit(em, &ev))
      return 0;
    for (int k = 0; k < nd->len; k++)
      if (!emit_node(em, nd->item[k])) return 0;
    return yaml_sequence_end_event_initialize(&ev) && yaml_emitter_emit(em, &ev);
  }
  if (!yaml_mapping_start_event_initialize(&ev, NULL, NULL, 1, YAML_BLOCK_MAPPING_STYLE) ||
      !yaml_emitter_emit(em, &ev))
    return 0;
  for (int k = 0; k < nd->len; k++)
    if (!emit_scalar(em, nd->key[k]) || !emit_node(em, nd->item[k])) return 0;
  return yaml_mapping_end_event_initialize(&ev) && yaml_emitter_emit(em, &ev);
}

char *st_emit(const st_node *root) {
  yaml_emitter_t em;
  yaml_event_t ev;
  outbuf o = {0};
  if (!yaml_emitter_initialize(&em)) return NULL;
  yaml_emitter_set_output(&em, out_write, &o);
  yaml_emitter_set_unicode(&em, 1);
  yaml_emitter_set_width(&em, -1);           /* never fold long scalars */
  int ok = yaml_stream_start_event_initialize(&ev, YAML_UTF8_ENCODING) && yaml_emitter_emit(&em, &ev) &&
           yaml_document_start_event_initialize(&ev, NULL, NULL, NULL, 1) && yaml_emitter_emit(&em, &ev) &&
           emit_node(&em, root) &&
           yaml_document_end_event_initialize(&ev, 1) && yaml_emitter_emit(&em, &ev) &&
           yaml_stream_end_event_initialize(&ev) && yaml_emitter_emit(&em, &ev) &&
           yaml_emitter_flush(&em);
  yaml_emitter_delete(&em);
  if (!ok || o.fail) { free(o.s); return NULL; }
  return o.s;
}

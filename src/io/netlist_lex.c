/* netlist_lex — see netlist_lex.h. */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include "catchup.h"
#include "util/linalg.h"
#include "netlist_lex.h"

/* ---- errors ------------------------------------------------------------------ */

static const char *file_name(const nx *x, int f);
static void where_from(const nx *x, const nx_tok *at, char *buf, size_t cap);

int nx_fail(nx *x, int status, const nx_tok *at, const char *what, const char *fmt, ...) {
  char *buf = x->errmsg;
  if (!buf) return status;
  size_t cap = CUP_ERRMSG_LEN;
  int w;
  if (!at)
    w = snprintf(buf, cap, "%s: ", x->file);
  else if (at->origin >= 0 && at->origin < x->nsets)
    w = snprintf(buf, cap, "%s: set '%.60s': ", x->file, x->sets[at->origin]);
  else
    w = snprintf(buf, cap, "%s:%d:%d: ", file_name(x, at->file), at->line, at->col);
  if (w >= 0 && (size_t)w < cap && what) w += snprintf(buf + w, cap - (size_t)w, "%s: ", what);
  va_list ap;
  va_start(ap, fmt);
  fail_vfmt_at(buf, w, status, fmt, ap);
  va_end(ap);
  if (at && at->origin < 0) where_from(x, at, buf, cap);
  return status;
}

static const char *file_name(const nx *x, int f) { return f > 0 && f < x->nfiles ? x->files[f].path : x->file; }

/* " (in instance X1.X2 of rc, X2 at sub.lib:4:1, X1 at main.cir:7:1;
 * included from main.cir:3)": how the token came to be read. */
static void where_from(const nx *x, const nx_tok *at, char *buf, size_t cap) {
  size_t len = strlen(buf);
  int inst = at->inst, file = at->file, first = 1;
  for (int i = inst; i > 0 && i <= x->ninst && len + 1 < cap; i = x->inst[i - 1].parent) {
    const nx_inst *in = &x->inst[i - 1];
    const char *leaf = strrchr(in->path, '.');
    len += (size_t)snprintf(buf + len, cap - len, "%s%s at %s:%d:%d", first ? " (in instance " : ", ",
                            leaf ? leaf + 1 : in->path, file_name(x, in->file), in->line, in->col);
    first = 0;
    file = in->file;
  }
  if (len + 1 < cap && file > 0 && file < x->nfiles && x->files[file].from_file >= 0)
    len += (size_t)snprintf(buf + len, cap - len, "%sincluded from %s:%d", first ? " (" : "; ",
                            file_name(x, x->files[file].from_file), x->files[file].from_line), first = 0;
  if (!first && len + 1 < cap) snprintf(buf + len, cap - len, ")");
}

/* ---- names ------------------------------------------------------------------- */

static unsigned long hash_lower(const char *s) {
  unsigned long h = 1469598103934665603ul;                  /* FNV-1a */
  for (; *s; s++) h = (h ^ (unsigned char)tolower((unsigned char)*s)) * 1099511628211ul;
  return h;
}

static int slot_of(const nx_hash *h, const char *name) {
  int mask = h->cap - 1;
  for (int i = (int)(hash_lower(name) & (unsigned long)mask);; i = (i + 1) & mask)
    if (!h->key[i] || !strcasecmp(h->key[i], name)) return i;
}

int nx_hash_get(const nx_hash *h, const char *name) {
  if (!h->cap) return -1;
  int i = slot_of(h, name);
  return h->key[i] ? h->val[i] : -1;
}

static int grow(nx_hash *h) {
  nx_hash g = {h->cap ? 2 * h->cap : 64, 0, NULL, NULL};
  g.key = calloc((size_t)g.cap, sizeof *g.key);
  g.val = calloc((size_t)g.cap, sizeof *g.val);
  if (!g.key || !g.val) { free(g.key); free(g.val); return CUP_ERR_NOMEM; }
  for (int i = 0; i < h->cap; i++)
    if (h->key[i]) {
      int j = slot_of(&g, h->key[i]);
      g.key[j] = h->key[i];
      g.val[j] = h->val[i];
      g.used++;
    }
  free(h->key);
  free(h->val);
  *h = g;
  return CUP_OK;
}

int nx_hash_put(nx_hash *h, const char *name, int val) {
  if (2 * (h->used + 1) > h->cap && grow(h)) return CUP_ERR_NOMEM;
  int i = slot_of(h, name);
  if (!h->key[i]) {
    if (!(h->key[i] = strdup(name))) return CUP_ERR_NOMEM;
    for (char *p = h->key[i]; *p; p++) *p = (char)tolower((unsigned char)*p);
    h->used++;
  }
  h->val[i] = val;
  return CUP_OK;
}

void nx_hash_free(nx_hash *h) {
  for (int i = 0; i < h->cap; i++) free(h->key[i]);
  free(h->key);
  free(h->val);
  memset(h, 0, sizeof *h);
}

int nx_card_type(const nx *x, nx_card c) {
  return c.type ? c.type : c.n ? tolower((unsigned char)x->tok[c.first].s[0]) : 0;
}

int nx_is(const nx_tok *t, const char *w) { return t->kind == NX_WORD && !strcasecmp(t->s, w); }

/* ---- lines into tokens ------------------------------------------------------- */

static int push_tok(nx *x, nx_kind kind, const char *s, size_t len, int line, int col, int origin) {
  if (la_grow(&x->tok, &x->captok, x->ntok, sizeof *x->tok, 256)) return CUP_ERR_NOMEM;
  char *copy = strndup(s, len);
  if (!copy) return CUP_ERR_NOMEM;
  x->tok[x->ntok++] = (nx_tok){kind, copy, line, col, origin, x->cur_file, 0};
  return CUP_OK;
}

static int push_card(nx *x) {
  if (la_grow(&x->card, &x->capcard, x->ncard, sizeof *x->card, 64)) return CUP_ERR_NOMEM;
  x->card[x->ncard++] = (nx_card){x->ntok, 0, 0};
  return CUP_OK;
}

static int is_sep(int c) { return c == ' ' || c == '\t' || c == '\r' || c == ',' || c == '\f' || c == '\v'; }
static int is_special(int c) { return c == '(' || c == ')' || c == '=' || c == '{' || c == '}' || c == '\'' || c == ';'; }

/* The tokens of one line (s, len bytes, no newline), from column c0. A
 * ';' or a '$' after a blank ends the line (comments). */
static int lex_tokens(nx *x, const char *s, size_t len, size_t c0, int line, int origin) {
  nx_tok here = {NX_WORD, NULL, line, 0, origin, x->cur_file, 0};
  for (size_t i = c0; i < len;) {
    unsigned char c = (unsigned char)s[i];
    here.col = (int)i + 1;
    if (is_sep(c)) { i++; continue; }
    if (c == ';' || (c == '$' && (i == 0 || is_sep((unsigned char)s[i - 1])))) break;
    if (c < 0x20 || c == 0x7f)
      return nx_fail(x, CUP_ERR_PARSE, &here, NULL, "unexpected control character 0x%02x", c);
    int st = CUP_OK;
    if (c == '(' || c == ')' || c == '=') {
      st = push_tok(x, c == '(' ? NX_LP : c == ')' ? NX_RP : NX_EQ, s + i, 1, line, (int)i + 1, origin);
      i++;
    } else if (c == '{' || c == '\'') {
      char close = c == '{' ? '}' : '\'';
      size_t j = i + 1;
      while (j < len && s[j] != close && s[j] != '\0') j++;
      if (j >= len || s[j] != close)
        return nx_fail(x, CUP_ERR_PARSE, &here, NULL, "expression opened by %c is not closed on this line", c);
      st = push_tok(x, NX_EXPR, s + i + 1, j - i - 1, line, (int)i + 1, origin);
      i = j + 1;
    } else if (c == '}') {
      return nx_fail(x, CUP_ERR_PARSE, &here, NULL, "'}' without '{'");
    } else {
      size_t j = i;
      while (j < len && !is_sep((unsigned char)s[j]) && !is_special((unsigned char)s[j]) &&
             (unsigned char)s[j] >= 0x20 && s[j] != 0x7f)
        j++;
      st = push_tok(x, NX_WORD, s + i, j - i, line, (int)i + 1, origin);
      i = j;
    }
    if (st) return nx_fail(x, st, NULL, NULL, "out of memory");
    if (origin < 0 && x->ncard) x->card[x->ncard - 1].n = x->ntok - x->card[x->ncard - 1].first;
  }
  return CUP_OK;
}

int nx_add_file(nx *x, const char *path, int from_file, int from_line) {
  if (la_grow(&x->files, &x->capfiles, x->nfiles, sizeof *x->files, 4)) return -1;
  char *copy = strdup(path);
  if (!copy) return -1;
  x->files[x->nfiles] = (nx_file){copy, from_file, from_line};
  return x->nfiles++;
}

int nx_lex_file(nx *x, int file, const char *text, size_t len, int title) {
  int line = 0;
  x->cur_file = file;
  for (size_t pos = 0; pos < len;) {
    size_t end = pos;
    while (end < len && text[end] != '\n') end++;
    const char *s = text + pos;
    size_t n = end - pos;
    pos = end + 1;
    if (++line == 1 && title) continue;           /* the title line (SPICE) */
    size_t i = 0;
    while (i < n && is_sep((unsigned char)s[i])) i++;
    if (i == n || s[i] == '*' || s[i] == ';') continue;
    nx_tok here = {NX_WORD, NULL, line, (int)i + 1, -1, x->cur_file, 0};
    if (s[i] == '+') {
      if (!x->ncard) return nx_fail(x, CUP_ERR_PARSE, &here, NULL, "'+' continues a line, but there is none before it");
      int st = lex_tokens(x, s, n, i + 1, line, -1);
      if (st) return st;
      continue;
    }
    if (push_card(x)) return nx_fail(x, CUP_ERR_NOMEM, NULL, NULL, "out of memory");
    int st = lex_tokens(x, s, n, i, line, -1);
    if (st) return st;
    if (!x->card[x->ncard - 1].n) x->ncard--;     /* a line holding only a comment */
  }
  return CUP_OK;
}

int nx_lex_value(nx *x, int k, const char *text, int *first, int *n) {
  *first = x->ntok;
  int st = lex_tokens(x, text, strlen(text), 0, 0, k);
  *n = x->ntok - *first;
  return st;
}

void nx_free(nx *x) {
  for (int i = 0; i < x->ntok; i++) free(x->tok[i].s);
  free(x->tok);
  free(x->card);
  for (int i = 0; i < x->npar; i++) free(x->par[i].name);
  free(x->par);
  nx_hash_free(&x->parh);
  for (int i = 0; i < x->nfiles; i++) free(x->files[i].path);
  free(x->files);
  for (int i = 0; i < x->ninst; i++) { free(x->inst[i].path); nx_hash_free(&x->inst[i].parh); }
  free(x->inst);
  for (int i = 0; i < x->nsub; i++) free(x->sub[i].body);
  free(x->sub);
  nx_hash_free(&x->subh);
  memset(x, 0, sizeof *x);
}

/* ---- numbers ----------------------------------------------------------------- */

/* SPICE's scale factors; letters after them are units and ignored. */
static double suffix_scale(const char *s, const char **end) {
  static const struct { const char *w; double f; } sfx[] = {
    {"meg", 1e6}, {"mil", 25.4e-6}, {"t", 1e12}, {"g", 1e9}, {"k", 1e3}, {"m", 1e-3},
    {"u", 1e-6}, {"n", 1e-9}, {"p", 1e-12}, {"f", 1e-15}};
  double f = 1;
  for (size_t k = 0; k < sizeof sfx / sizeof sfx[0]; k++)
    if (!strncasecmp(s, sfx[k].w, strlen(sfx[k].w))) { f = sfx[k].f; s += strlen(sfx[k].w); break; }
  while (isalpha((unsigned char)*s)) s++;
  *end = s;
  return f;
}

/* A number at s: [+-] digits [. digits] [e [+-] digits] [suffix [units]].
 * Returns the characters used (0: not a number). */
static size_t scan_number(const char *s, double *v) {
  const char *p = s;
  if (*p == '+' || *p == '-') p++;
  const char *d0 = p;
  while (isdigit((unsigned char)*p)) p++;
  int digits = (int)(p - d0);
  if (*p == '.') {
    p++;
    const char *d1 = p;
    while (isdigit((unsigned char)*p)) p++;
    digits += (int)(p - d1);
  }
  if (!digits) return 0;
  if ((*p == 'e' || *p == 'E') &&
      (isdigit((unsigned char)p[1]) || ((p[1] == '+' || p[1] == '-') && isdigit((unsigned char)p[2])))) {
    p += 2;
    while (isdigit((unsigned char)*p)) p++;
  }
  char buf[128];
  size_t n = (size_t)(p - s);
  if (n >= sizeof buf) return 0;
  memcpy(buf, s, n);
  buf[n] = '\0';
  double mant = strtod(buf, NULL);
  const char *end;
  double f = suffix_scale(p, &end);
  *v = mant * f;
  return (size_t)(end - s);
}

int nx_number(const char *s, double *v) {
  size_t n = scan_number(s, v);
  return n > 0 && s[n] == '\0';
}

/* ---- expressions ------------------------------------------------------------- */

typedef struct ex {
  nx *x;
  const nx_tok *at;
  const char *what;
  const char *p;
  int depth;
} ex;

static int param_value(nx *x, int k, const nx_tok *use, double *v);

static void skip_blank(ex *e) { while (*e->p == ' ' || *e->p == '\t') e->p++; }

static int ex_fail(ex *e, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int ex_fail(ex *e, const char *fmt, ...) {
  char msg[CUP_ERRMSG_LEN];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return nx_fail(e->x, CUP_ERR_PARSE, e->at, e->what, "%s", msg);
}

static int ex_sum(ex *e, double *v);

typedef struct { const char *name; double (*fn)(double); } ex_fn;
static const ex_fn functions[] = {{"sqrt", sqrt}, {"abs", fabs}, {"exp", exp}, {"ln", log},
                                  {"log", log}, {"log10", log10}, {"sin", sin}, {"cos", cos},
                                  {"tan", tan}, {"atan", atan}};

static int ex_ident(ex *e, double *v) {
  const char *s = e->p;
  while (isalnum((unsigned char)*e->p) || *e->p == '_') e->p++;
  char name[64];
  size_t n = (size_t)(e->p - s);
  if (n >= sizeof name) return ex_fail(e, "name '%.40s...' is too long", s);
  memcpy(name, s, n);
  name[n] = '\0';
  skip_blank(e);
  if (*e->p == '(') {
    for (size_t k = 0; k < sizeof functions / sizeof functions[0]; k++)
      if (!strcasecmp(name, functions[k].name)) {
        e->p++;
        int st = ex_sum(e, v);
        if (st) return st;
        skip_blank(e);
        if (*e->p != ')') return ex_fail(e, "expected ')' after the argument of %s()", name);
        e->p++;
        *v = functions[k].fn(*v);
        return CUP_OK;
      }
    return ex_fail(e, "unknown function '%s' (sqrt, abs, exp, ln, log10, sin, cos, tan, atan)", name);
  }
  if (!strcasecmp(name, "pi")) { *v = 3.141592653589793238462643383279502884; return CUP_OK; }
  int k = nx_param_find(e->x, e->at, name);
  if (k < 0) return ex_fail(e, "unknown parameter '%s' (no .param defines it)", name);
  return param_value(e->x, k, e->at, v);
}

static int ex_atom(ex *e, double *v) {
  skip_blank(e);
  if (++e->depth > 64) return ex_fail(e, "expression nested too deeply");
  int st;
  if (*e->p == '(') {
    e->p++;
    st = ex_sum(e, v);
    skip_blank(e);
    if (!st && *e->p != ')') st = ex_fail(e, "expected ')'");
    if (!st) e->p++;
  } else if (*e->p == '-' || *e->p == '+') {
    int neg = *e->p++ == '-';
    st = ex_atom(e, v);
    if (neg) *v = -*v;
  } else if (isdigit((unsigned char)*e->p) || (*e->p == '.' && isdigit((unsigned char)e->p[1]))) {
    size_t n = scan_number(e->p, v);
    st = n ? CUP_OK : ex_fail(e, "bad number at '%.20s'", e->p);
    e->p += n;
  } else if (isalpha((unsigned char)*e->p) || *e->p == '_') {
    st = ex_ident(e, v);
  } else {
    st = *e->p ? ex_fail(e, "unexpected '%.1s' in the expression", e->p)
               : ex_fail(e, "the expression ends too early");
  }
  e->depth--;
  return st;
}

static int ex_power(ex *e, double *v) {
  int st = ex_atom(e, v);
  skip_blank(e);
  if (st || !(*e->p == '^' || (e->p[0] == '*' && e->p[1] == '*'))) return st;
  e->p += *e->p == '^' ? 1 : 2;
  double w;
  if (++e->depth > 64) return ex_fail(e, "expression nested too deeply");
  st = ex_power(e, &w);
  e->depth--;
  if (!st) *v = pow(*v, w);
  return st;
}

static int ex_product(ex *e, double *v) {
  int st = ex_power(e, v);
  for (skip_blank(e); !st && (*e->p == '*' || *e->p == '/') && e->p[1] != '*'; skip_blank(e)) {
    char op = *e->p++;
    double w;
    st = ex_power(e, &w);
    if (!st && op == '/' && w == 0) return ex_fail(e, "division by zero");
    if (!st) *v = op == '*' ? *v * w : *v / w;
  }
  return st;
}

static int ex_sum(ex *e, double *v) {
  int st = ex_product(e, v);
  for (skip_blank(e); !st && (*e->p == '+' || *e->p == '-'); skip_blank(e)) {
    char op = *e->p++;
    double w;
    st = ex_product(e, &w);
    if (!st) *v = op == '+' ? *v + w : *v - w;
  }
  return st;
}

static int eval(nx *x, const nx_tok *t, const char *what, double *v) {
  ex e = {x, t, what, t->s, 0};
  int st = ex_sum(&e, v);
  skip_blank(&e);
  if (!st && *e.p) st = ex_fail(&e, "unexpected '%.20s' after the expression", e.p);
  return st;
}

int nx_param_find(const nx *x, const nx_tok *at, const char *name) {
  if (at && at->inst > 0 && at->inst <= x->ninst) {
    int k = nx_hash_get(&x->inst[at->inst - 1].parh, name);
    if (k >= 0) return k;
  }
  return nx_hash_get(&x->parh, name);
}

/* A .param's value, evaluated once, on first use (so that sets replace
 * them before anything reads them); a cycle is an error. */
static int param_value(nx *x, int k, const nx_tok *use, double *v) {
  nx_param *p = &x->par[k];
  if (p->state == 2) { *v = p->v; return CUP_OK; }
  if (p->state == 1)
    return nx_fail(x, CUP_ERR_PARSE, use, p->name, "the .param refers to itself (a cycle of parameters)");
  p->state = 1;
  int st = nx_value(x, &p->value, p->name, &p->v);
  p->state = st ? 0 : 2;
  *v = p->v;
  return st;
}

int nx_value(nx *x, const nx_tok *t, const char *what, double *v) {
  int st;
  if (t->kind == NX_EXPR) {
    st = eval(x, t, what, v);
  } else if (t->kind != NX_WORD) {
    return nx_fail(x, CUP_ERR_PARSE, t, what, "expected a value (got '%s')", t->s);
  } else if (nx_number(t->s, v)) {
    st = CUP_OK;
  } else {
    int k = nx_param_find(x, t, t->s);
    if (k < 0)
      return nx_fail(x, CUP_ERR_PARSE, t, what, "bad value '%.40s': expected a number such as 4.7k, 10u "
                     "or 1meg, a .param name, or {expression}", t->s);
    st = param_value(x, k, t, v);
  }
  if (!st && !isfinite(*v))
    return nx_fail(x, CUP_ERR_NONFINITE, t, what, "bad value '%.40s': not finite (%g)", t->s, *v);
  return st;
}

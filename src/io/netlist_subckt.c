/* netlist_subckt — the netlist's structure before its elements are read:
 * .include and .lib (files spliced in where they are named, paths relative
 * to the including file), .end and .control blocks, .subckt definitions
 * set aside, and then X instances flattened into plain cards with
 * hierarchical names (ngspice's: node "x1.out", element "x1.r1"; pins are
 * the caller's nodes, ground stays ground). Every token keeps the file,
 * line and column it was written at and the instance it was copied into,
 * so that an error names both (netlist_lex.c, nx_fail). See
 * docs/netlist.md. */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include "catchup.h"
#include "util/linalg.h"
#include "netlist_lex.h"
#include "netlist_subckt.h"
#include "read_text.h"

#define MAX_DEPTH 64      /* includes within includes, instances within instances */

typedef struct cards {
  nx_card *c;
  int n, cap;
} cards;

static int push(nx *x, cards *out, nx_card c) {
  if (la_grow(&out->c, &out->cap, out->n, sizeof *out->c, 64))
    return nx_fail(x, CUP_ERR_NOMEM, NULL, NULL, "out of memory");
  out->c[out->n++] = c;
  return CUP_OK;
}

static const nx_tok *tok(const nx *x, nx_card c, int k) { return &x->tok[c.first + k]; }

/* ---- .include and .lib --------------------------------------------------------- */

static int walk(nx *x, int c0, int c1, cards *out, int depth);

/* The path a .include or .lib names, relative to the folder of the file
 * that names it (absolute paths as they are). */
static int join_path(nx *x, const nx_tok *t, char *buf, size_t size) {
  const char *name = t->s;
  size_t n = strlen(name);
  if (n >= 2 && name[0] == '"' && name[n - 1] == '"') { name++; n -= 2; }
  if (n == 0 || (t->kind != NX_WORD && t->kind != NX_EXPR))
    return nx_fail(x, CUP_ERR_PARSE, t, NULL, "expected a file name");
  const char *from = x->files[t->file].path, *slash = strrchr(from, '/');
  int w = name[0] == '/' || !slash ? snprintf(buf, size, "%.*s", (int)n, name)
                                   : snprintf(buf, size, "%.*s/%.*s", (int)(slash - from), from, (int)n, name);
  if (w < 0 || (size_t)w >= size) return nx_fail(x, CUP_ERR_PARSE, t, NULL, "file name too long");
  return CUP_OK;
}

/* Read and split the file named at t; its cards are appended to x->card
 * (*c0 .. *c1). A file already being read further up is a cycle. */
static int lex_included(nx *x, const nx_tok *t, int depth, int *c0, int *c1) {
  char path[PATH_MAX], why[CUP_ERRMSG_LEN];
  int st = join_path(x, t, path, sizeof path);
  if (st) return st;
  if (depth >= MAX_DEPTH) return nx_fail(x, CUP_ERR_PARSE, t, path, "files included %d deep (a cycle?)", depth);
  for (int f = t->file; f >= 0; f = x->files[f].from_file)
    if (!strcmp(x->files[f].path, path))
      return nx_fail(x, CUP_ERR_PARSE, t, path, "the file includes itself (through %s)", x->files[t->file].path);
  char *text = NULL;
  size_t len = 0;
  struct stat sb;
  if (stat(path, &sb) == 0 && !S_ISREG(sb.st_mode))   /* /dev/zero, a FIFO, a folder: never read */
    return nx_fail(x, CUP_ERR_IO, t, NULL, "cannot read '%s' (%s): not a regular file", t->s, path);
  if (read_text(path, &text, &len, x->read_list, why)) {
    const char *reason = strstr(why, ": ");       /* "PATH: cannot open: why" */
    return nx_fail(x, CUP_ERR_IO, t, NULL, "cannot read '%s' (%s)%s", t->s, path, reason ? reason : "");
  }
  int file = nx_add_file(x, path, t->file, t->line), saved = x->cur_file;
  *c0 = x->ncard;
  st = file < 0 ? nx_fail(x, CUP_ERR_NOMEM, NULL, NULL, "out of memory") : nx_lex_file(x, file, text, len, 0);
  x->cur_file = saved;
  *c1 = x->ncard;
  free(text);
  return st;
}

/* The card after the block opened at card k and closed by `close`. */
static int block_end(nx *x, int k, int c1, const char *close, const char *open, int *end) {
  *end = c1;
  for (int j = k + 1; j < c1; j++)
    if (nx_is(tok(x, x->card[j], 0), close)) { *end = j; return CUP_OK; }
  return nx_fail(x, CUP_ERR_PARSE, tok(x, x->card[k], 0), open, "no %s closes it", close);
}

/* .lib FILE SECTION: the cards of `.lib SECTION` ... `.endl` in FILE. */
static int lib_section(nx *x, nx_card card, int depth, cards *out) {
  const nx_tok *cmd = tok(x, card, 0), *sec = tok(x, card, 2);
  if (card.n != 3) return nx_fail(x, CUP_ERR_PARSE, cmd, ".lib", "expected '.lib FILE SECTION' (or '.lib SECTION' "
                                  "... '.endl' in a library)");
  int c0, c1, st = lex_included(x, tok(x, card, 1), depth, &c0, &c1);
  for (int k = c0; !st && k < c1; k++) {
    nx_card c = x->card[k];
    if (!nx_is(tok(x, c, 0), ".lib") || c.n != 2 || strcasecmp(tok(x, c, 1)->s, sec->s)) continue;
    int end = c1;
    st = block_end(x, k, c1, ".endl", ".lib", &end);
    return st ? st : walk(x, k + 1, end, out, depth + 1);
  }
  return st ? st : nx_fail(x, CUP_ERR_PARSE, sec, ".lib", "no section '%.40s' in %s", sec->s,
                           x->files[x->nfiles - 1].path);
}

/* A .subckt definition, cards k .. end (the .ends); .model cards in it are
 * hoisted to the top level (models are global). */
static int define(nx *x, int k, int end, cards *out) {
  nx_card head = x->card[k];
  const nx_tok *cmd = tok(x, head, 0);
  if (head.n < 2 || tok(x, head, 1)->kind != NX_WORD)
    return nx_fail(x, CUP_ERR_PARSE, cmd, ".subckt", "expected '.subckt NAME NODES... [params: NAME=VALUE ...]'");
  const nx_tok *name = tok(x, head, 1);
  int prev = nx_hash_get(&x->subh, name->s);
  if (prev >= 0)
    return nx_fail(x, CUP_ERR_PARSE, name, name->s, "subcircuit defined twice (first at %s:%d)",
                   x->files[tok(x, x->sub[prev].head, 0)->file].path, tok(x, x->sub[prev].head, 0)->line);
  if (la_grow(&x->sub, &x->capsub, x->nsub, sizeof *x->sub, 8)) return nx_fail(x, CUP_ERR_NOMEM, NULL, NULL, "out of memory");
  nx_sub *s = &x->sub[x->nsub];
  *s = (nx_sub){head, NULL, 0};
  if (nx_hash_put(&x->subh, name->s, x->nsub++)) return nx_fail(x, CUP_ERR_NOMEM, NULL, NULL, "out of memory");
  cards body = {0};
  int st = CUP_OK;
  for (int j = k + 1; j < end && !st; j++) {
    const nx_tok *t = tok(x, x->card[j], 0);
    if (nx_is(t, ".subckt"))
      st = nx_fail(x, CUP_ERR_UNSUPPORTED, t, ".subckt", "a definition inside another (%s) is not supported: define "
                   "it at the top level", name->s);
    else if (nx_is(t, ".include") || nx_is(t, ".inc") || nx_is(t, ".lib"))
      st = nx_fail(x, CUP_ERR_UNSUPPORTED, t, t->s, "not supported inside .subckt (include the file at the top "
                   "level)");
    else
      st = push(x, nx_is(t, ".model") ? out : &body, x->card[j]);
  }
  x->sub[x->nsub - 1].body = body.c;
  x->sub[x->nsub - 1].nbody = body.n;
  return st;
}

/* Cards c0 .. c1 - 1 of one file (or section) into out, in order. */
static int walk(nx *x, int c0, int c1, cards *out, int depth) {
  for (int k = c0; k < c1; k++) {
    nx_card card = x->card[k];
    const nx_tok *t = tok(x, card, 0);
    int st = CUP_OK, end = c1;
    if (nx_is(t, ".end")) return CUP_OK;
    if (nx_is(t, ".control")) {
      st = block_end(x, k, c1, ".endc", ".control", &end);
      k = end;
    } else if (nx_is(t, ".include") || nx_is(t, ".inc")) {
      int a, b;
      if (card.n != 2) return nx_fail(x, CUP_ERR_PARSE, t, t->s, "expected '%s FILE'", t->s);
      st = lex_included(x, tok(x, card, 1), depth, &a, &b);
      if (!st) st = walk(x, a, b, out, depth + 1);
    } else if (nx_is(t, ".lib") && card.n == 2) {  /* a section's definition: read only when named */
      st = block_end(x, k, c1, ".endl", ".lib", &end);
      k = end;
    } else if (nx_is(t, ".lib")) {
      st = lib_section(x, card, depth, out);
    } else if (nx_is(t, ".subckt")) {
      st = block_end(x, k, c1, ".ends", ".subckt", &end);
      if (!st) st = define(x, k, end, out);
      k = end;
    } else if (nx_is(t, ".ends") || nx_is(t, ".endl") || nx_is(t, ".endc")) {
      st = nx_fail(x, CUP_ERR_PARSE, t, t->s, "without %s before it", nx_is(t, ".ends") ? ".subckt"
                   : nx_is(t, ".endl") ? ".lib SECTION" : ".control");
    } else {
      st = push(x, out, card);
    }
    if (st) return st;
  }
  return CUP_OK;
}

/* A pass's result: the new card list takes the place of x's on success
 * (st = CUP_OK) and is dropped on a failure, which is returned. */
static int replace_cards(nx *x, cards *out, int st) {
  if (st) { free(out->c); return st; }
  free(x->card);
  x->card = out->c;
  x->ncard = out->n;
  x->capcard = out->cap;
  return CUP_OK;
}

int nx_structure(nx *x) {
  cards out = {0};
  int st = walk(x, 0, x->ncard, &out, 0);
  return replace_cards(x, &out, st);
}

/* ---- instances ------------------------------------------------------------------ */

/* Where a card's NAME=VALUE list starts ("params:" or a word then '='):
 * the card's n if it has none. */
static int params_start(const nx *x, nx_card c, int from) {
  for (int k = from; k < c.n; k++) {
    const nx_tok *t = tok(x, c, k);
    if (nx_is(t, "params:") || (k + 1 < c.n && t->kind == NX_WORD && tok(x, c, k + 1)->kind == NX_EQ)) return k;
  }
  return c.n;
}

static int is_ground(const char *s) { return !strcmp(s, "0") || !strcasecmp(s, "gnd"); }

/* A new token: a copy of t in instance inst with text s. */
static int copy_tok(nx *x, const nx_tok *t, const char *s, int inst) {
  nx_tok c = *t;                                  /* t may move with x->tok: copied first */
  if (la_grow(&x->tok, &x->captok, x->ntok, sizeof *x->tok, 256)) return CUP_ERR_NOMEM;
  char *dup = strdup(s);
  if (!dup) return CUP_ERR_NOMEM;
  c.s = dup;
  c.inst = inst;
  x->tok[x->ntok++] = c;
  return CUP_OK;
}

/* The node written at token t of a body card in instance inst: a pin is
 * the caller's node, ground is ground, any other "PATH.name". */
static void node_name(const nx *x, int inst, const nx_tok *t, const nx_card *xcard, char *buf, size_t size) {
  const nx_inst *in = &x->inst[inst - 1];
  nx_card head = x->sub[in->sub].head;
  int np = params_start(x, head, 2) - 2;
  if (is_ground(t->s)) { snprintf(buf, size, "%s", t->s); return; }
  for (int k = 0; k < np; k++)
    if (!strcasecmp(tok(x, head, 2 + k)->s, t->s)) { snprintf(buf, size, "%s", tok(x, *xcard, 1 + k)->s); return; }
  snprintf(buf, size, "%s.%s", in->path, t->s);
}

/* Which tokens of a card of type `type` are nodes (1) or element names (2). */
static int role(const nx *x, nx_card c, int type, int k) {
  static const char *const kw[] = {"poly", "value", "table", "laplace", "vol", "cur", "freq", NULL};
  const nx_tok *t = tok(x, c, k);
  if (t->kind != NX_WORD || k == 0) return 0;
  for (int j = 0; kw[j]; j++)
    if (nx_is(t, kw[j])) return 0;
  switch (type) {
    case 'r': case 'l': case 'c': case 'd': case 'v': case 'i': return k <= 2;
    case 'e': case 'g': case 's': return k <= 4;
    case 'w': return k <= 2 ? 1 : k == 3 ? 2 : 0;
    case 'f': case 'h': return k <= 2 ? 1 : k == 3 ? 2 : 0;
    case 'k': return k <= 2 ? 2 : 0;
    case 'x': return k < params_start(x, c, 1) - 1;
  }
  return 0;
}

/* Body card c copied into instance inst with its names made hierarchical. */
static int copy_card(nx *x, int inst, nx_card c, const nx_card *xcard, nx_card *out) {
  int type = nx_card_type(x, c);
  const char *path = x->inst[inst - 1].path;
  *out = (nx_card){x->ntok, c.n, (char)type};
  for (int k = 0; k < c.n; k++) {
    char buf[512];
    const nx_tok *t = tok(x, c, k);
    int r = role(x, c, type, k);
    if (k == 0 && type != '.') snprintf(buf, sizeof buf, "%s.%s", path, t->s);
    else if (r == 1) node_name(x, inst, t, xcard, buf, sizeof buf);
    else if (r == 2) snprintf(buf, sizeof buf, "%s.%s", path, t->s);
    else snprintf(buf, sizeof buf, "%s", t->s);
    if (copy_tok(x, &x->tok[c.first + k], buf, inst)) return nx_fail(x, CUP_ERR_NOMEM, NULL, NULL, "out of memory");
  }
  return CUP_OK;
}

/* name=value into instance inst's parameters (evaluated now, at t's scope). */
static int set_param(nx *x, int inst, const nx_tok *name, const nx_tok *value) {
  double v;
  int st = nx_value(x, value, name->s, &v);
  if (st) return st;
  if (la_grow(&x->par, &x->cappar, x->npar, sizeof *x->par, 16)) return nx_fail(x, CUP_ERR_NOMEM, NULL, NULL, "out of memory");
  nx_param *p = &x->par[x->npar];
  memset(p, 0, sizeof *p);
  if (!(p->name = strdup(name->s))) return nx_fail(x, CUP_ERR_NOMEM, NULL, NULL, "out of memory");
  p->value = *value;
  p->state = 2;
  p->v = v;
  if (nx_hash_put(&x->inst[inst - 1].parh, name->s, x->npar++)) return nx_fail(x, CUP_ERR_NOMEM, NULL, NULL, "out of memory");
  return CUP_OK;
}

/* The parameters of a new instance: the definition's defaults (evaluated
 * in the instance, so that b={2*a} sees a) unless the X card gives a value
 * (evaluated where the X card is), and the body's .param cards. */
static int instance_params(nx *x, int inst, nx_card xc, int xp) {
  const nx_sub *s = &x->sub[x->inst[inst - 1].sub];
  nx_card head = s->head;
  int hp = params_start(x, head, 2);
  for (int k = xp + nx_is(tok(x, xc, xp < xc.n ? xp : 0), "params:"); k < xc.n; k += 3) {
    const nx_tok *n = tok(x, xc, k);
    if (k + 2 >= xc.n || tok(x, xc, k + 1)->kind != NX_EQ)
      return nx_fail(x, CUP_ERR_PARSE, n, tok(x, xc, 0)->s, "expected NAME=VALUE (got '%.40s')", n->s);
    int found = 0;
    for (int j = hp + nx_is(tok(x, head, hp < head.n ? hp : 0), "params:"); j + 2 < head.n && !found; j += 3)
      found = !strcasecmp(tok(x, head, j)->s, n->s);
    if (!found)
      return nx_fail(x, CUP_ERR_PARSE, n, tok(x, xc, 0)->s, "subcircuit '%s' has no parameter '%.40s'",
                     tok(x, head, 1)->s, n->s);
    int st = set_param(x, inst, n, tok(x, xc, k + 2));
    if (st) return st;
  }
  for (int j = hp + nx_is(tok(x, head, hp < head.n ? hp : 0), "params:"); j < head.n; j += 3) {
    const nx_tok *n = tok(x, head, j);
    if (j + 2 >= head.n || tok(x, head, j + 1)->kind != NX_EQ)
      return nx_fail(x, CUP_ERR_PARSE, n, tok(x, head, 1)->s, "expected NAME=VALUE (got '%.40s')", n->s);
    if (nx_hash_get(&x->inst[inst - 1].parh, n->s) >= 0) continue;   /* given by the X card */
    nx_tok d = *tok(x, head, j + 2);
    d.inst = inst;
    int st = set_param(x, inst, n, &d);
    if (st) return st;
  }
  for (int b = 0; b < s->nbody; b++) {           /* .param in the body: local, in order */
    nx_card c = s->body[b];
    if (!nx_is(tok(x, c, 0), ".param")) continue;
    for (int k = 1; k < c.n; k += 3) {
      const nx_tok *n = tok(x, c, k);
      if (k + 2 >= c.n || tok(x, c, k + 1)->kind != NX_EQ)
        return nx_fail(x, CUP_ERR_PARSE, n, ".param", "expected NAME=VALUE (got '%.40s')", n->s);
      nx_tok d = *tok(x, c, k + 2);
      d.inst = inst;
      int st = set_param(x, inst, n, &d);
      if (st) return st;
    }
  }
  return CUP_OK;
}

static int expand(nx *x, nx_card xc, int parent, cards *out, int depth);

/* The body of instance inst into out (X cards in it expanded in turn). */
static int body(nx *x, int inst, nx_card xc, cards *out, int depth) {
  const nx_sub *s = &x->sub[x->inst[inst - 1].sub];
  for (int b = 0; b < s->nbody; b++) {
    nx_card c = s->body[b], copy;
    const nx_tok *t = tok(x, c, 0);
    if (nx_is(t, ".param")) continue;
    if (t->s[0] == '.')
      return nx_fail(x, CUP_ERR_UNSUPPORTED, t, t->s, "not supported inside .subckt (elements, .param and "
                     ".model are)");
    int type = nx_card_type(x, c);
    int st = copy_card(x, inst, c, &xc, &copy);
    if (!st) st = type == 'x' ? expand(x, copy, inst, out, depth + 1) : push(x, out, copy);
    if (st) return st;
  }
  return CUP_OK;
}

/* X card xc (in instance parent, 0 at the top) into its flattened cards. */
static int expand(nx *x, nx_card xc, int parent, cards *out, int depth) {
  const nx_tok *name = tok(x, xc, 0);
  int xp = params_start(x, xc, 1);
  if (xp < 2) return nx_fail(x, CUP_ERR_PARSE, name, name->s, "expected '%s NODES... SUBCKT [params: NAME=VALUE "
                             "...]'", name->s);
  const nx_tok *sn = tok(x, xc, xp - 1);
  int sub = nx_hash_get(&x->subh, sn->s);
  if (sub < 0) return nx_fail(x, CUP_ERR_PARSE, sn, name->s, "subcircuit '%.40s' is not defined", sn->s);
  int pins = params_start(x, x->sub[sub].head, 2) - 2;
  if (xp - 2 != pins)
    return nx_fail(x, CUP_ERR_PARSE, name, name->s, "subcircuit '%s' has %d pin%s, the instance gives %d node%s",
                   sn->s, pins, pins == 1 ? "" : "s", xp - 2, xp - 2 == 1 ? "" : "s");
  for (int i = parent; i > 0; i = x->inst[i - 1].parent)
    if (x->inst[i - 1].sub == sub)
      return nx_fail(x, CUP_ERR_PARSE, sn, name->s, "subcircuit '%s' calls itself (through instance %s)", sn->s,
                     x->inst[parent - 1].path);
  if (depth >= MAX_DEPTH) return nx_fail(x, CUP_ERR_PARSE, name, name->s, "instances nested %d deep", depth);
  if (la_grow(&x->inst, &x->capinst, x->ninst, sizeof *x->inst, 8)) return nx_fail(x, CUP_ERR_NOMEM, NULL, NULL, "out of memory");
  nx_inst *in = &x->inst[x->ninst];
  memset(in, 0, sizeof *in);
  in->path = strdup(name->s);                     /* copy_card made it hierarchical already */
  in->parent = parent;
  in->file = name->file; in->line = name->line; in->col = name->col;
  in->sub = sub;
  int inst = ++x->ninst;
  if (!in->path) return nx_fail(x, CUP_ERR_NOMEM, NULL, NULL, "out of memory");
  int st = instance_params(x, inst, xc, xp);
  return st ? st : body(x, inst, xc, out, depth);
}

int nx_flatten(nx *x) {
  int any = 0;
  for (int k = 0; k < x->ncard && !any; k++) any = nx_card_type(x, x->card[k]) == 'x';
  if (!any) return CUP_OK;
  cards out = {0};
  int st = CUP_OK;
  for (int k = 0; k < x->ncard && !st; k++) {
    nx_card c = x->card[k];
    st = nx_card_type(x, c) == 'x' ? expand(x, c, 0, &out, 0) : push(x, &out, c);
  }
  return replace_cards(x, &out, st);
}

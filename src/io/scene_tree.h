/* The scene loader's YAML tree: libyaml's document copied into small nodes
 * that keep their position and their origin (the file, or the k-th
 * override), so that overrides can be spliced in before the document is
 * interpreted and every error can still say where its value came from.
 * Internal to the library. */
#ifndef CUP_SCENE_TREE_H
#define CUP_SCENE_TREE_H

#include <stdarg.h>
#include <stddef.h>

typedef enum st_kind { ST_SCALAR, ST_SEQ, ST_MAP } st_kind;

typedef struct st_node st_node;
struct st_node {
  st_kind kind;
  int line, col;      /* 1-based position in the file (origin -1) */
  int origin;         /* -1: the file; k >= 0: override k */
  int quoted;         /* SCALAR: quoted or block style, so always a string */
  char *text;         /* SCALAR: the value (NUL-free, NUL-terminated) */
  int len, cap;       /* SEQ: items; MAP: entries */
  st_node **item;     /* SEQ: the items; MAP: the values */
  st_node **key;      /* MAP: the keys (scalars, distinct) */
};

/* Where nodes come from, for messages. */
typedef struct st_src {
  const char *file;          /* name used in messages */
  const char *const *ovr;    /* the override strings ("key=value") */
} st_src;

/* Format "FILE:LINE:COL: KEY: message" (or "override 'K=V': KEY: message"
 * when `at` came from an override) into errmsg (CUP_ERRMSG_LEN bytes, may be
 * NULL). key may be NULL. Returns status. */
int st_error(char *errmsg, int status, const st_src *src, const st_node *at,
             const char *key, const char *fmt, ...) __attribute__((format(printf, 6, 7)));
int st_verror(char *errmsg, int status, const st_src *src, const st_node *at,
              const char *key, const char *fmt, va_list ap);

/* Parse one YAML document (text of len bytes) into *root; every node gets
 * `origin`. An empty document gives a null scalar. key names the text in
 * messages (NULL for the file). */
int st_parse(st_node **root, const char *text, size_t len, const st_src *src, int origin,
             const char *key, char *errmsg);

/* An override names the shape its user wants: before it walks into `seg`
 * of the node at *slot (whose dotted key is `path`, "" for the document;
 * `val` is the new value when seg is the last part, else NULL), the reader
 * may replace *slot or edit it (output: {every: 1} with output.samples=2
 * becomes {samples: 2}). Nodes it adds get origin k. Returns a status. */
typedef int (*st_reshape_fn)(st_node **slot, const char *path, const char *seg, const st_node *val, int k);

/* 1 when the value of an override of `key` is its text as written (a
 * string scalar, trimmed), not YAML: a netlist's SPICE expression such as
 * {100/13}, which YAML would read as a mapping. */
typedef int (*st_verbatim_fn)(const char *key);

/* Apply src->ovr[k] ("dotted.key=value") to the document; reshape and
 * verbatim may be NULL. */
int st_apply_override(st_node **root, const st_src *src, int k, st_reshape_fn reshape, st_verbatim_fn verbatim,
                      char *errmsg);

/* Building blocks for a reshape: an empty mapping; append key: val to a
 * mapping (val is then owned by it); drop a key (absent: nothing). */
st_node *st_new_map(int origin);
int st_map_put(st_node *map, const char *key, st_node *val, int origin);
void st_map_remove(st_node *map, const char *key);

/* The document as block-style YAML (numeric rows in flow style); NULL when
 * out of memory. Reparsing gives the same tree up to positions. */
char *st_emit(const st_node *root);

void st_free(st_node *nd);

/* The value of `key` in a mapping (NULL if absent); *keynode (may be NULL)
 * receives the key node. */
const st_node *st_get(const st_node *map, const char *key, const st_node **keynode);
/* A plain scalar spelled as YAML null: "", "~", "null", "Null", "NULL". */
int st_is_null(const st_node *nd);
/* "did you mean 'x'?" when word is a likely typo of one of the NULL-terminated
 * known words, else "expected one of a, b, c"; into buf (n bytes). */
const char *st_suggest(char *buf, size_t n, const char *word, const char *const *known);
/* Room for st_suggest's "expected one of" and a list of the library's own
 * words (the scene's 22 keys take about 200 characters), whole. */
#define ST_HINT_LEN 512
/* The first key of a mapping that is not among the NULL-terminated known
 * words, or NULL when all are known. */
const st_node *st_unknown_key(const st_node *map, const char *const *known);
/* How a node looks, for "expected X (got Y)": "nothing", "a list", "an empty
 * list", "a mapping" or the scalar quoted (up to 40 characters, into buf). */
const char *st_looks(const st_node *nd, char *buf, size_t n);
/* Parse a plain scalar as a YAML number (decimal, exponent, .inf, .nan). */
int st_number(const char *s, double *out);

#endif

/* netlist_lex — the SPICE netlist reader's tokens, names and values:
 * physical lines into cards (title line, '*' comments, ';' and ' $ '
 * comments, '+' continuations), cards into tokens with their place, names
 * hashed case-insensitively, numbers with engineering suffixes, and .param
 * expressions. Internal to the netlist reader (io/netlist_read.c,
 * netlist_elem.c). */
#ifndef CUP_NETLIST_LEX_H
#define CUP_NETLIST_LEX_H

#include <stdarg.h>
#include <stddef.h>

struct file_list;
struct cup_netlist;
/* cup_netlist_load and _load_string recording the files they read in files
 * (read_text.h; may be NULL): the scene's netlist: key loads through these. */
int netlist_load_files(struct cup_netlist **out, const char *path, const char *const *sets, int nsets,
                       struct file_list *files, char *errmsg);
int netlist_load_string_files(struct cup_netlist **out, const char *text, const char *name,
                              const char *const *sets, int nsets, struct file_list *files, char *errmsg);

typedef enum nx_kind { NX_WORD, NX_LP, NX_RP, NX_EQ, NX_EXPR } nx_kind;
typedef struct nx nx;

typedef struct nx_tok {
  nx_kind kind;
  char *s;            /* WORD: the text; EXPR: the expression inside {} or '' */
  int line, col;      /* 1-based; line 0: a value given by a set (origin >= 0) */
  int origin;         /* -1: the file; k >= 0: set k ("NAME=VALUE") */
  int file;           /* x->files[file] holds it (0: the netlist) */
  int inst;           /* 0, or 1 + the subcircuit instance it was copied into (x->inst) */
} nx_tok;

typedef struct nx_card {
  int first, n;       /* tokens first .. first + n - 1 */
  char type;          /* 0: the first token's first letter says; else a copy's element type
                         (its name "x1.r1" no longer starts with it) */
} nx_card;

/* The card's element type: 'r', 'x', '.', ... (lowercase). */
int nx_card_type(const nx *x, nx_card c);

/* A .subckt definition: its header card (.subckt NAME pins... [params])
 * and its body, as cards into x->tok. */
typedef struct nx_sub {
  nx_card head;
  nx_card *body;
  int nbody;
} nx_sub;

/* Case-insensitive name -> index table (open addressing). */
typedef struct nx_hash {
  int cap, used;
  char **key;         /* lowercase copies */
  int *val;
} nx_hash;

int nx_hash_get(const nx_hash *h, const char *name);          /* -1 if absent */
int nx_hash_put(nx_hash *h, const char *name, int val);       /* CUP_OK or CUP_ERR_NOMEM */
void nx_hash_free(nx_hash *h);

typedef struct nx_param {
  char *name;
  nx_tok value;       /* WORD or EXPR */
  int state;          /* 0 unevaluated, 1 evaluating, 2 done */
  double v;
} nx_param;

/* A file read: the netlist or an included one, and where it was included. */
typedef struct nx_file {
  char *path;         /* as opened (relative paths joined to the including file's folder) */
  int from_file;      /* -1: the netlist itself */
  int from_line;
} nx_file;

/* A subcircuit instance: its hierarchical name and the X card that made it. */
typedef struct nx_inst {
  char *path;         /* "x1.x2" (lowercase) */
  int parent;         /* 0, or 1 + the enclosing instance */
  int file, line, col;  /* the X card */
  int sub;            /* its definition: x->sub[sub] */
  nx_hash parh;       /* its parameters: name -> x->par index (evaluated) */
} nx_inst;

/* Everything the reader keeps while it works. */
struct nx {
  const char *file;
  struct file_list *read_list;  /* the load's files read (read_text.h), or NULL: every file
                                       this reader opens (an .include, a .lib) goes through
                                       read_text with it */
  const char *const *sets;   /* "NAME=VALUE" */
  int nsets;
  char *errmsg;
  nx_tok *tok;
  int ntok, captok;
  nx_card *card;
  int ncard, capcard;
  nx_param *par;
  int npar, cappar;
  nx_hash parh;
  int cur_file;       /* the file being split into cards */
  int nfiles, capfiles;
  nx_file *files;     /* files[0]: the netlist; then .include/.lib files */
  int ninst, capinst;
  nx_inst *inst;      /* subcircuit instances (netlist_subckt.c) */
  int nsub, capsub;
  nx_sub *sub;        /* .subckt definitions */
  nx_hash subh;       /* name -> sub index */
};

/* "FILE:LINE:COL: WHAT: message" (or "FILE: set 'S': WHAT: message" for a
 * token from a set) into x->errmsg; returns status. `at` may be NULL (then
 * FILE: WHAT: message), `what` may be NULL. */
int nx_fail(nx *x, int status, const nx_tok *at, const char *what, const char *fmt, ...)
  __attribute__((format(printf, 5, 6)));

/* Split text (len bytes) of file x->files[file] into cards, appended; line 1
 * is the title and is skipped when `title` (the netlist, not an included
 * file). */
int nx_lex_file(nx *x, int file, const char *text, size_t len, int title);
/* Record a file read (path copied); its index, or -1 out of memory. */
int nx_add_file(nx *x, const char *path, int from_file, int from_line);
/* The parameter `name` as seen from token at: its subcircuit instance's
 * parameters first, then the .param table; an index into x->par or -1. */
int nx_param_find(const nx *x, const nx_tok *at, const char *name);
/* Tokens of a set's value (set k), appended; *first and *n receive them. */
int nx_lex_value(nx *x, int k, const char *text, int *first, int *n);
void nx_free(nx *x);

/* 1 if the token is the word w (case-insensitive). */
int nx_is(const nx_tok *t, const char *w);
/* A value: a number with an engineering suffix (f p n u m k meg g t, mil;
 * trailing unit letters ignored: "10uF"), a .param name, or an expression
 * ({...} or '...'). Finite or an error naming what. */
int nx_value(nx *x, const nx_tok *t, const char *what, double *v);
/* The same for a plain number only (no parameters): 1 if t is one. */
int nx_number(const char *s, double *v);

#endif

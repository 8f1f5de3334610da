/* scene_set — see scene_set.h. */
#define _POSIX_C_SOURCE 200809L
#include "scene_set.h"
#include "util/linalg.h"

/* Where a signal's component of u goes. */
typedef enum { SIG_CENTER, SIG_RADIUS, SIG_OFFSET, SIG_B, SIG_TARGET } sig_kind;

typedef struct signal {
  const st_node *nd;
  char key[KEY_LEN];
  sig_kind kind;
  int index;             /* entry of the centre, offset, b or target */
} signal;

/* The named nonlinear terms of f (docs/scene-format.md, "f"). */
typedef struct named_f {
  int n;
  double *cubic;         /* n coefficients, or NULL: f_i -= c_i x_i^3 */
  int towards;           /* f += speed (target(t) - x) / max(|target - x|, slow) */
  double speed, slow;
  int *target_of;        /* n components of u giving the target */
  const cup_input *u;
  double *ubuf;          /* p: u(t) while f is evaluated */
} named_f;

struct scene_process {
  cup_set *set;
  cup_input *u;          /* one component per signal; NULL without any */
  int n, p;
  signal *sig;
  int nsig, capsig;
  mat A, C, Q, Pm;
  double *Pdiag;
  int *Ep, *Ei;          /* E: n x p, b's components */
  double *Ex;
  named_f nf;
  cup_process_desc desc;
};

static const char *const set_words[] = {"ball", "ellipsoid", "halfspace", "polyset", "intersection", NULL};

void scene_process_free(scene_process **Pp) {
  if (!Pp || !*Pp) return;
  scene_process *P = *Pp;
  cup_set_free(&P->set);
  cup_input_free(&P->u);
  free(P->sig);
  mat_free(&P->A); mat_free(&P->C); mat_free(&P->Q); mat_free(&P->Pm);
  free(P->Pdiag); free(P->Ep); free(P->Ei); free(P->Ex);
  free(P->nf.cubic); free(P->nf.target_of); free(P->nf.ubuf);
  free(P);
  *Pp = NULL;
}

const cup_process_desc *scene_process_desc(const scene_process *P) { return P ? &P->desc : NULL; }
const cup_input *scene_process_input(const scene_process *P) { return P ? P->u : NULL; }

/* ---- signals: a number, or a waveform (or a sum of them) through u ------------- */

static int is_number(const st_node *nd) {
  double v;
  return nd->kind == ST_SCALAR && !nd->quoted && !st_is_null(nd) && st_number(nd->text, &v);
}

static int add_signal(scene_process *P, const st_node *nd, const char *key, sig_kind kind, int index) {
  if (P->nsig == P->capsig) {
    int c = 2 * P->capsig + 8;
    signal *s = realloc(P->sig, sizeof(signal) * (size_t)c);
    if (!s) return CUP_ERR_NOMEM;
    P->sig = s;
    P->capsig = c;
  }
  signal *s = &P->sig[P->nsig++];
  s->nd = nd;
  snprintf(s->key, sizeof s->key, "%s", key);
  s->kind = kind;
  s->index = index;
  return CUP_OK;
}

/* A scalar that may move: a number into *value, else a signal (always a
 * signal when `always`, a number then being a constant term of it). */
static int scalar(rd *r, scene_process *P, const st_node *nd, const char *key, sig_kind kind, int index,
                  int always, double *value) {
  char b[64];
  if (value) *value = 0;
  if (!always && is_number(nd)) return number(r, nd, key, value);
  if (nd->kind == ST_MAP || nd->kind == ST_SEQ || is_number(nd)) return add_signal(P, nd, key, kind, index);
  return fail(r, CUP_ERR_PARSE, nd, key, "expected a number or a signal: a waveform like {type: sine, "
              "amplitude: 1, frequency: 1}, {type: pwl, points: [[t, v], ...]}, or a list of them (got %s)",
              st_looks(nd, b, sizeof b));
}

/* A list of `want` scalars (want < 0: its length is n, returned). */
static int scalars(rd *r, scene_process *P, const st_node *nd, const char *key, sig_kind kind, int *want,
                   int always, double **values) {
  char k1[KEY_LEN], b[64];
  if (nd->kind != ST_SEQ || nd->len == 0)
    return fail(r, CUP_ERR_PARSE, nd, key, "expected a list of numbers or signals, one per %s (got %s)",
                kind == SIG_OFFSET ? "row" : "coordinate", st_looks(nd, b, sizeof b));
  if (*want < 0) *want = nd->len;
  if (nd->len != *want)
    return fail(r, CUP_ERR_DIM, nd, key, "expected %d entries (%s), got %d", *want,
                kind == SIG_OFFSET ? "the rows of C" : "the dimension n", nd->len);
  if (values && !(*values = calloc((size_t)*want + 1, sizeof(double)))) return CUP_ERR_NOMEM;
  for (int k = 0; k < nd->len; k++) {
    int st = scalar(r, P, nd->item[k], joini(k1, key, k), kind, k, always, values ? &(*values)[k] : NULL);
    if (st) return st;
  }
  return CUP_OK;
}

/* u: one component per signal, each read as an input component. */
static int make_input(rd *r, scene_process *P, const st_node *at, scene_component_fn component) {
  char lib[CUP_ERRMSG_LEN];
  P->p = P->nsig;
  if (!P->p) return CUP_OK;
  int st = cup_input_create(&P->u, P->p, lib);
  if (st) return fail(r, st, at, "set", "%s", lib);
  for (int j = 0; j < P->p && !st; j++) st = component(r, P->sig[j].nd, P->sig[j].key, P->u, j);
  return st;
}

/* The 0/1 matrix (rows x p) that puts the components of kind into their
 * entries, as CSC arrays (owned by the caller); NULL arrays when none. */
static int selection(const scene_process *P, sig_kind kind, int rows, int **cp, int **ri, double **vx,
                     cup_csc *view) {
  int p = P->p, count = 0;
  *cp = NULL; *ri = NULL; *vx = NULL;
  *view = (cup_csc){0};
  for (int j = 0; j < p; j++) count += P->sig[j].kind == kind;
  if (!count) return CUP_OK;
  *cp = calloc((size_t)p + 1, sizeof(int));
  *ri = malloc(sizeof(int) * (size_t)count);
  *vx = malloc(sizeof(double) * (size_t)count);
  if (!*cp || !*ri || !*vx) return CUP_ERR_NOMEM;
  for (int j = 0, q = 0; j < p; j++) {
    if (P->sig[j].kind == kind) { (*ri)[q] = P->sig[j].index; (*vx)[q++] = 1; }
    (*cp)[j + 1] = q;
  }
  *view = (cup_csc){rows, p, *cp, *ri, *vx};
  return CUP_OK;
}

/* ---- set: ------------------------------------------------------------------------ */

typedef struct set_fields {
  double *center, *offset, radius, normal_b;
  const st_node *knode;
} set_fields;

static int ball_part(rd *r, scene_process *P, const st_node *map, const char *key, int *n, set_fields *f) {
  char k1[KEY_LEN];
  const st_node *nd;
  int st = need(r, map, key, "center", &nd);
  if (!st) st = scalars(r, P, nd, join(k1, key, "center"), SIG_CENTER, n, 0, &f->center);
  if (!st) st = need(r, map, key, "radius", &nd);
  if (!st) st = scalar(r, P, nd, join(k1, key, "radius"), SIG_RADIUS, 0, 0, &f->radius);
  return st;
}

static int rows_part(rd *r, scene_process *P, const st_node *map, const char *key, int *n, int *m,
                     set_fields *f) {
  char k1[KEY_LEN];
  const st_node *nd;
  int st = need(r, map, key, "C", &nd);
  if (!st) st = matrix(r, nd, join(k1, key, "C"), &P->C);
  if (st) return st;
  *n = P->C.a.ncol;
  *m = P->C.a.nrow;
  if ((nd = opt(map, "offset"))) return scalars(r, P, nd, join(k1, key, "offset"), SIG_OFFSET, m, 0, &f->offset);
  return (f->offset = calloc((size_t)*m + 1, sizeof(double))) ? CUP_OK : CUP_ERR_NOMEM;
}

static int halfspace_part(rd *r, scene_process *P, const st_node *map, const char *key, int *n, set_fields *f) {
  char k1[KEY_LEN];
  const st_node *nd;
  double *a = NULL;
  char b[64];
  int st = need(r, map, key, "normal", &nd);
  if (!st && (nd->kind != ST_SEQ || nd->len == 0))
    return fail(r, CUP_ERR_PARSE, nd, join(k1, key, "normal"), "expected a list of numbers, the normal a "
                "of {a . x + b >= 0} (got %s)", st_looks(nd, b, sizeof b));
  if (!st) st = vector(r, nd, join(k1, key, "normal"), nd->len, "the dimension n", &a);
  if (!st) {
    *n = nd->len;
    st = mtx_from_dense(&P->C.a, 1, *n, a, 1, 1);
  }
  free(a);
  if (!st && (nd = opt(map, "offset"))) st = scalar(r, P, nd, join(k1, key, "offset"), SIG_OFFSET, 0, 0, &f->normal_b);
  if (!st && !(f->offset = malloc(sizeof(double)))) st = CUP_ERR_NOMEM;
  if (!st) f->offset[0] = f->normal_b;
  return st;
}

static const char *const *kind_keys(int kind) {
  static const char *const ball[] = {"center", "radius", "P", NULL};
  static const char *const ellipsoid[] = {"center", "radius", "Q", "P", NULL};
  static const char *const halfspace[] = {"normal", "offset", "P", NULL};
  static const char *const polyset[] = {"C", "offset", "P", NULL};
  static const char *const both[] = {"C", "offset", "center", "radius", "P", NULL};
  switch (kind) {
    case CUP_SET_BALL: return ball;
    case CUP_SET_ELLIPSOID: return ellipsoid;
    case CUP_SET_HALFSPACE: return halfspace;
    case CUP_SET_POLYSET: return polyset;
    default: return both;
  }
}

/* The fields of one kind; n (and m) from them. */
static int set_parts(rd *r, scene_process *P, int kind, const st_node *map, const char *key, int *n, int *m,
                     set_fields *f, cup_metric *metric) {
  char k1[KEY_LEN], why[48];
  int st = need_map(r, map, key, "a mapping of the set's fields");
  if (!st) st = check_keys(r, map, key, kind_keys(kind));
  if (st) return st;
  *n = -1;
  *m = 0;
  if (kind == CUP_SET_POLYSET || kind == CUP_SET_INTERSECTION) st = rows_part(r, P, map, key, n, m, f);
  if (!st && kind == CUP_SET_HALFSPACE) {
    *m = 1;
    st = halfspace_part(r, P, map, key, n, f);
  }
  if (!st && (kind == CUP_SET_BALL || kind == CUP_SET_ELLIPSOID || kind == CUP_SET_INTERSECTION))
    st = ball_part(r, P, map, key, n, f);
  const st_node *nd;
  snprintf(why, sizeof why, "n = %d", *n);
  if (!st && kind == CUP_SET_ELLIPSOID) {
    st = need(r, map, key, "Q", &nd);
    if (!st) st = matrix(r, nd, join(k1, key, "Q"), &P->Q);
    if (!st) st = matrix_dims(r, &P->Q, k1, *n, *n, why);
  }
  if (!st) st = read_metric(r, opt(map, "P"), join(k1, key, "P"), *n, why, &P->Pm, &P->Pdiag, metric);
  return st;
}

/* The set's description from its fields and the signals' selections. */
static int build_set(rd *r, scene_process *P, int kind, int n, int m, set_fields *f, cup_metric *metric,
                     const st_node *knode) {
  char lib[CUP_ERRMSG_LEN];
  int *gp = NULL, *gi = NULL, *cp = NULL, *ci = NULL;
  double *gx = NULL, *cx = NULL, *gr = NULL;
  cup_set_desc d = {.kind = (cup_set_kind)kind, .n = n, .P = *metric, .C = mat_view(&P->C), .F = f->offset,
                    .center = f->center, .radius = f->radius, .Q = mat_view(&P->Q)};
  int st = selection(P, SIG_OFFSET, m, &gp, &gi, &gx, &d.G);
  if (!st) st = selection(P, SIG_CENTER, n, &cp, &ci, &cx, &d.Gc);
  for (int j = 0; !st && j < P->p; j++)
    if (P->sig[j].kind == SIG_RADIUS) {
      if (!gr && !(gr = calloc((size_t)P->p, sizeof(double)))) st = CUP_ERR_NOMEM;
      if (gr) gr[j] = 1;
    }
  if (!st) {
    d.gr = gr;
    d.p = P->p;
    if ((st = cup_set_create(&P->set, &d, lib))) st = fail(r, st, knode, "set", "%s", lib);
  }
  free(gp); free(gi); free(gx); free(cp); free(ci); free(cx); free(gr);
  return st;
}

/* ---- f: ------------------------------------------------------------------------------ */

static int named_rhs(double t, const double *x, double *out, void *ctx) {
  const named_f *F = ctx;
  int n = F->n;
  for (int i = 0; i < n; i++) out[i] = F->cubic ? -F->cubic[i] * x[i] * x[i] * x[i] : 0;
  if (!F->towards) return 0;
  if (cup_input_eval(F->u, t, F->ubuf)) return 1;
  double d2 = 0;
  for (int i = 0; i < n; i++) {
    double d = F->ubuf[F->target_of[i]] - x[i];
    d2 += d * d;
  }
  double d = sqrt(d2), s = d > 0 ? F->speed / fmax(d, F->slow) : 0;
  for (int i = 0; i < n; i++) out[i] += s * (F->ubuf[F->target_of[i]] - x[i]);
  return 0;
}

static int read_towards(rd *r, scene_process *P, const st_node *map, int n) {
  static const char *const known[] = {"target", "speed", "slow", NULL};
  const st_node *nd;
  int want = n;
  int st = need_map(r, map, "f.towards", "a mapping with target and speed (and slow)");
  if (!st) st = check_keys(r, map, "f.towards", known);
  if (!st) st = need(r, map, "f.towards", "target", &nd);
  if (!st) st = scalars(r, P, nd, "f.towards.target", SIG_TARGET, &want, 1, NULL);
  if (!st) st = need(r, map, "f.towards", "speed", &nd);
  if (!st) st = number_min(r, nd, "f.towards.speed", 0, 0, &P->nf.speed);
  if (!st && (nd = opt(map, "slow"))) st = number_min(r, nd, "f.towards.slow", 0, 0, &P->nf.slow);
  P->nf.towards = 1;
  return st;
}

/* f's keys that add signals (b, towards' target) come before make_input;
 * A and cubic after. */
static int read_f_signals(rd *r, scene_process *P, const st_node *f, int n) {
  static const char *const known[] = {"A", "b", "cubic", "towards", NULL};
  const st_node *nd;
  int want = n;
  int st = need_map(r, f, "f", "a mapping of A, b, cubic, towards");
  if (!st) st = check_keys(r, f, "f", known);
  if (!st && (nd = opt(f, "b"))) st = scalars(r, P, nd, "f.b", SIG_B, &want, 1, NULL);
  if (!st && (nd = opt(f, "towards"))) st = read_towards(r, P, nd, n);
  return st;
}

static int read_f_rest(rd *r, scene_process *P, const st_node *f, int n) {
  char why[48];
  const st_node *nd;
  int st = CUP_OK;
  snprintf(why, sizeof why, "n x n, n = %d from the set", n);
  if ((nd = opt(f, "A"))) {
    st = matrix(r, nd, "f.A", &P->A);
    if (!st) st = matrix_dims(r, &P->A, "f.A", n, n, why);
  }
  if (!st && (nd = opt(f, "cubic"))) {
    snprintf(why, sizeof why, "n = %d from the set", n);
    st = vector(r, nd, "f.cubic", n, why, &P->nf.cubic);
  }
  named_f *F = &P->nf;
  F->n = n;
  F->u = P->u;
  if (!st && F->towards) {
    F->target_of = malloc(sizeof(int) * (size_t)n);
    F->ubuf = malloc(sizeof(double) * ((size_t)P->p + 1));
    if (!F->target_of || !F->ubuf) return CUP_ERR_NOMEM;
    for (int j = 0; j < P->p; j++)
      if (P->sig[j].kind == SIG_TARGET) F->target_of[P->sig[j].index] = j;
  }
  cup_csc E;
  if (!st) st = selection(P, SIG_B, n, &P->Ep, &P->Ei, &P->Ex, &E);
  if (!st) {
    P->desc.A = mat_view(&P->A);
    P->desc.E = E;
    if (F->cubic || F->towards) { P->desc.f = named_rhs; P->desc.f_ctx = F; }
  }
  return st;
}

/* ---- the whole ---------------------------------------------------------------------- */

static int read_set_key(rd *r, const st_node *set, int *kind, const st_node **map, char *key) {
  char hint[ST_HINT_LEN], b[64];
  if (set->kind != ST_MAP || set->len != 1)
    return fail(r, CUP_ERR_PARSE, set, "set", "expected a mapping with one key, the kind of set: ball, "
                "ellipsoid, halfspace, polyset or intersection (got %s)",
                set->kind == ST_MAP ? "a mapping with more than one key" : st_looks(set, b, sizeof b));
  const char *word = set->key[0]->text;
  *kind = cup_set_kind_parse(word);
  if (*kind == CUP_SET_ORACLE || *kind == CUP_SET_STATE_POLYSET)
    return fail(r, CUP_ERR_PARSE, set->key[0], join(key, "set", word), "this kind of set is given by a "
                "callback: use the C or Fortran API (cup_set_create)");
  if (*kind < 0)
    return fail(r, CUP_ERR_PARSE, set->key[0], join(key, "set", word), "unknown kind of set (%s)",
                st_suggest(hint, sizeof hint, word, set_words));
  *map = set->item[0];
  join(key, "set", word);
  return CUP_OK;
}

int scene_read_process(rd *r, const st_node *root, const st_node *kset, const st_node *set,
                       scene_component_fn component, scene_process **out) {
  char key[KEY_LEN];
  *out = NULL;
  scene_process *P = calloc(1, sizeof *P);
  if (!P) return CUP_ERR_NOMEM;
  set_fields f = {0};
  cup_metric metric;
  const st_node *map = NULL, *fn = opt(root, "f");
  int kind = 0, n = 0, m = 0;
  int st = read_set_key(r, set, &kind, &map, key);
  if (!st) st = set_parts(r, P, kind, map, key, &n, &m, &f, &metric);
  if (!st && fn) st = read_f_signals(r, P, fn, n);
  if (!st) st = make_input(r, P, kset, component);
  if (!st) st = build_set(r, P, kind, n, m, &f, &metric, kset);
  P->n = n;
  if (!st && fn) st = read_f_rest(r, P, fn, n);
  free(f.center);
  free(f.offset);
  if (st) { scene_process_free(&P); return st; }
  P->desc.n = n;
  P->desc.p = P->p;
  P->desc.C = P->set;
  P->desc.u = P->u;
  *out = P;
  return CUP_OK;
}

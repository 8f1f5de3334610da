/* netlist_signal — node voltages and element currents as linear functions
 * of (x, u, zeta), built once per probe (one solve with the resistors'
 * factor per node) and evaluated per sample without allocating. A node's
 * potential is its supernode's, phi_S = -(Lap^-1 K e)_S, plus the port
 * voltages along its tree (tau); a voltage or current port's other
 * quantity is its row of H. */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include "catchup.h"
#include "catchup/netlist.h"
#include "netlist_impl.h"
#include "input_impl.h"
#include "signal_map.h"

static int nvar(const cup_netlist *nl) { return nl->n + nl->p + nl->m; }
static int nports(const cup_netlist *nl) { return nl->nv + nl->ni; }

/* Port q's value (times coef) into the dense row over (x, u, zeta); a
 * controlled source's output through its row of zmap. */
static void add_port(const cup_netlist *nl, int q, double coef, double *row) {
  const nl_port *pt = &nl->port[q];
  if (pt->var == NL_VAR_CTL) {
    const double *z = nl->zmap + (size_t)pt->index * (size_t)nports(nl);
    for (int j = 0; j < nports(nl); j++)
      if (z[j] != 0) add_port(nl, j, coef * z[j], row);   /* zmap's columns of controlled ports are 0 */
    return;
  }
  if (pt->var == NL_VAR_NONE) return;            /* a closed switch's voltage: 0 */
  int off = pt->var == NL_VAR_X ? 0 : pt->var == NL_VAR_U ? nl->n : nl->n + nl->p;
  row[off + pt->index] += coef * pt->sign;
}

/* Row q of H (port q's current if a voltage port, voltage if a current port). */
static void add_h_row(const cup_netlist *nl, int q, double coef, double *prow) {
  for (int j = 0; j < nl->H.ncol; j++)
    for (int k = nl->H.p[j]; k < nl->H.p[j + 1]; k++)
      if (nl->H.i[k] == q) prow[j] += coef * nl->H.x[k];
}

int nl_prow_node(cup_netlist *nl, int v, double coef, double *prow) {
  for (int w = v; nl->parent[w] >= 0; w = nl->parent[w]) prow[nl->pport[w]] += coef * nl->psign[w];
  int s = nl->snode[v];
  if (s < 0) return CUP_OK;
  cholmod_dense *b = cholmod_zeros((size_t)nl->ns, 1, CHOLMOD_REAL, nl->cm);
  if (!b) return CUP_ERR_NOMEM;
  ((double *)b->x)[s] = 1;
  cholmod_dense *y = cholmod_solve(CHOLMOD_A, nl->Lf, b, nl->cm);
  cholmod_free_dense(&b, nl->cm);
  if (!y) return CUP_ERR_NOMEM;
  const double *yv = y->x;
  const int *Kp = nl->K->p, *Ki = nl->K->i;
  const double *Kx = nl->K->x;
  for (int j = 0; j < (int)nl->K->ncol; j++) {
    double acc = 0;
    for (int k = Kp[j]; k < Kp[j + 1]; k++) acc += yv[Ki[k]] * Kx[k];
    if (acc != 0) prow[j] -= coef * acc;
  }
  cholmod_free_dense(&y, nl->cm);
  return CUP_OK;
}

int nl_prow_current(cup_netlist *nl, int e, double *prow) {
  const nl_elem *el = &nl->elem[e];
  int q = nl->eport[e];
  if (el->kind == NL_R) {
    int st = nl_prow_node(nl, el->a, 1 / el->value, prow);
    return st ? st : nl_prow_node(nl, el->b, -1 / el->value, prow);
  }
  if (q >= nl->nv) prow[q] += 1;                  /* a current port: its own value */
  else add_h_row(nl, q, 1, prow);                 /* a voltage port: its row of H */
  return CUP_OK;
}

/* A row over the ports into one over (x, u, zeta). */
static void to_vars(const cup_netlist *nl, const double *prow, double *row) {
  for (int q = 0; q < nports(nl); q++)
    if (prow[q] != 0) add_port(nl, q, prow[q], row);
}

/* ---- the table of signals ----------------------------------------------------- */

static int append(cup_netlist *nl, char *name, const double *row) {
  int nv = nvar(nl), nz = 0;
  for (int k = 0; k < nv; k++) nz += row[k] != 0;
  /* the names with the pointers, the values with the indices: one block
   * each (a switched run's configurations fill their tables in its run:
   * four reallocs a configuration were) */
  if (nl->nsig + 1 >= nl->capsig) {
    int cap = nl->capsig ? 2 * nl->capsig : 16;
    char **nn = malloc(sizeof *nn * (size_t)cap + sizeof(int) * ((size_t)cap + 1));
    if (!nn) return CUP_ERR_NOMEM;
    int *np = (int *)(nn + cap);
    np[0] = 0;
    if (nl->capsig) {
      memcpy(nn, nl->sig_name, sizeof *nn * (size_t)nl->nsig);
      memcpy(np, nl->sig_ptr, sizeof *np * ((size_t)nl->nsig + 1));
    }
    free(nl->sig_name);
    nl->sig_name = nn, nl->sig_ptr = np;
    nl->capsig = cap;
  }
  if (nl->signnz + nz > nl->capnnz) {
    int cap = 2 * (nl->signnz + nz) + 64;
    double *nx = malloc((sizeof *nx + sizeof(int)) * (size_t)cap);
    if (!nx) return CUP_ERR_NOMEM;
    int *ni = (int *)(nx + cap);
    if (nl->signnz) {
      memcpy(nx, nl->sig_val, sizeof *nx * (size_t)nl->signnz);
      memcpy(ni, nl->sig_idx, sizeof *ni * (size_t)nl->signnz);
    }
    free(nl->sig_val);
    nl->sig_val = nx, nl->sig_idx = ni;
    nl->capnnz = cap;
  }
  for (int k = 0; k < nv; k++)
    if (row[k] != 0) { nl->sig_idx[nl->signnz] = k; nl->sig_val[nl->signnz++] = row[k]; }
  nl->sig_name[nl->nsig++] = name;
  nl->sig_ptr[nl->nsig] = nl->signnz;
  return CUP_OK;
}

static int find_node(const cup_netlist *nl, const char *s, size_t len) {
  for (int v = 0; v < nl->nnodes; v++)
    if (strlen(nl->node[v]) == len && !strncasecmp(nl->node[v], s, len)) return v;
  if ((len == 1 && s[0] == '0') || (len == 3 && !strncasecmp(s, "gnd", 3))) return 0;
  return -1;
}

static int find_elem(const cup_netlist *nl, const char *s, size_t len) {
  for (int e = 0; e < nl->nelem; e++)
    if (strlen(nl->elem[e].name) == len && !strncasecmp(nl->elem[e].name, s, len)) return e;
  if (len > 2 && s[1] == '.') {                   /* ngspice's "r.x1.r1" for the subcircuit's "x1.r1" */
    static const char letter[] = "rlcvidefghswss";   /* by nl_kind (a switch's parts: s) */
    int e = find_elem(nl, s + 2, len - 2);
    if (e >= 0 && tolower((unsigned char)s[0]) == letter[nl->elem[e].kind]) return e;
  }
  return -1;
}

/* "v(a)", "v(a,b)" or "i(e)" into its parts; 0 if it is none of them. */
static int split(const char *s, char *kind, const char **a, size_t *la, const char **b, size_t *lb) {
  while (isspace((unsigned char)*s)) s++;
  *kind = (char)tolower((unsigned char)*s);
  if ((*kind != 'v' && *kind != 'i')) return 0;
  s++;
  while (isspace((unsigned char)*s)) s++;
  if (*s++ != '(') return 0;
  const char *close = strchr(s, ')');
  if (!close) return 0;
  for (const char *t = close + 1; *t; t++)
    if (!isspace((unsigned char)*t)) return 0;
  const char *comma = memchr(s, ',', (size_t)(close - s));
  const char *end1 = comma ? comma : close;
  while (s < end1 && isspace((unsigned char)*s)) s++;
  const char *e1 = end1;
  while (e1 > s && isspace((unsigned char)e1[-1])) e1--;
  *a = s; *la = (size_t)(e1 - s);
  *b = NULL; *lb = 0;
  if (comma) {
    const char *s2 = comma + 1;
    while (s2 < close && isspace((unsigned char)*s2)) s2++;
    const char *e2 = close;
    while (e2 > s2 && isspace((unsigned char)e2[-1])) e2--;
    *b = s2; *lb = (size_t)(e2 - s2);
    if (!*lb) return 0;
  }
  return *la > 0 && !(*kind == 'i' && comma);
}

static char *canonical(char kind, const char *a, const char *b) {
  size_t len = strlen(a) + (b ? strlen(b) + 1 : 0) + 4;
  char *s = malloc(len);
  if (!s) return NULL;
  if (b) snprintf(s, len, "%c(%s,%s)", kind, a, b);
  else snprintf(s, len, "%c(%s)", kind, a);
  return s;
}

/* The signal (kind, x, y) appended under name (owned, freed on failure). */
static int probe_row(cup_netlist *nl, char kind, int x, int y, char *name, char *errmsg) {
  double *row = nl->dense, *prow = nl->prow;
  memset(row, 0, sizeof(double) * (size_t)nvar(nl));
  memset(prow, 0, sizeof(double) * (size_t)nports(nl));
  int st = kind == 'i' ? nl_prow_current(nl, x, prow) : nl_prow_node(nl, x, 1, prow);
  if (!st && y >= 0) st = nl_prow_node(nl, y, -1, prow);
  if (!st) to_vars(nl, prow, row);
  if (!st) st = append(nl, name, row);
  if (st) { free(name); return fail_fmt(errmsg, st, "out of memory"); }
  return nl->nsig - 1;
}

static int probe_one(cup_netlist *nl, char kind, int x, int y, char *errmsg) {
  const char *a = kind == 'i' ? nl->elem[x].name : nl->node[x], *b = y >= 0 ? nl->node[y] : NULL;
  char *name = canonical(kind, a, b);
  if (!name) return fail_fmt(errmsg, CUP_ERR_NOMEM, "out of memory");
  for (int k = 0; k < nl->nsig; k++)
    if (!strcmp(nl->sig_name[k], name)) { free(name); return k; }
  return probe_row(nl, kind, x, y, name, errmsg);
}

static int scratch(cup_netlist *nl, char *errmsg) {
  /* dense, vals and prow in one block that dense owns (a switched run
   * makes one a configuration: two callocs and two frees less) */
  if (!nl->dense) {
    size_t nv = (size_t)nvar(nl) + 1;
    if (!(nl->dense = calloc(2 * nv + (size_t)nports(nl) + 1, sizeof(double))))
      return fail_fmt(errmsg, CUP_ERR_NOMEM, "out of memory");
    nl->vals = nl->dense + nv;
    nl->prow = nl->vals + nv;
  }
  int nt = nl->u && !nl->u->fn ? nl->u->nterms : 0, jumps = 0;
  for (int k = 0; k < nt; k++) jumps += input_jump_pulse(&nl->u->terms[k]);
  if (!nl->ucache && jumps) {                      /* (none: cup_input_eval, as quick) */
    if (!(nl->ucache = calloc(3 * (size_t)nt + 2 + (size_t)nl->p, sizeof(double))))
      return fail_fmt(errmsg, CUP_ERR_NOMEM, "out of memory");
    nl->ucache_n = nt;
  }
  return CUP_OK;
}

/* Each signal as cup_netlist_probe records it: through the hooks too, so
 * that a switched netlist's configurations formed already record it (they
 * were left without, and a sample in one of them kept the signals of the
 * last sample before it). */
static int probe_all(cup_netlist *nl, char *errmsg) {
  int st = CUP_OK, ne = nl->nelem_user ? nl->nelem_user : nl->nelem;
  for (int v = 1; v < nl->nnodes && st >= 0; v++) {
    st = probe_one(nl, 'v', v, -1, errmsg);
    if (st >= 0 && nl->hooks) st = nl->hooks->probe(nl, st, &(nl_probe_at){'v', v, -1}, errmsg);
  }
  for (int e = 0; e < ne && st >= 0; e++) {
    st = probe_one(nl, 'i', e, -1, errmsg);
    if (st >= 0 && nl->hooks) st = nl->hooks->probe(nl, st, &(nl_probe_at){'i', e, -1}, errmsg);
  }
  return st < 0 ? st : CUP_OK;
}

int nl_probe_check(const cup_netlist *nl, const char *text, char *msg, size_t size) {
  char kind;
  const char *a, *b;
  size_t la, lb;
  if (!split(text, &kind, &a, &la, &b, &lb))
    return snprintf(msg, size, "'%.60s' is not a signal (expected v(NODE), v(NODE1,NODE2) or i(ELEMENT))", text), 1;
  if ((kind == 'i' ? find_elem(nl, a, la) : find_node(nl, a, la)) < 0)
    return snprintf(msg, size, "'%.60s': no %s named '%.*s'", text, kind == 'i' ? "element" : "node",
                    (int)(la < 60 ? la : 60), a), 1;
  if (b && find_node(nl, b, lb) < 0)
    return snprintf(msg, size, "'%.60s': no node named '%.*s'", text, (int)(lb < 60 ? lb : 60), b), 1;
  return 0;
}

int cup_netlist_probe(cup_netlist *nl, const char *signal, char *errmsg) {
  if (!nl || !signal) return fail_fmt(errmsg, CUP_ERR_ARG, "netlist probe: NULL argument");
  int st = scratch(nl, errmsg);
  if (st) return st;
  const char *t = signal;
  while (isspace((unsigned char)*t)) t++;
  if (!strcasecmp(t, "all")) return probe_all(nl, errmsg);
  char kind;
  const char *a, *b;
  size_t la, lb;
  if (!split(signal, &kind, &a, &la, &b, &lb))
    return fail_fmt(errmsg, CUP_ERR_ARG, "probe '%.60s': expected v(NODE), v(NODE1,NODE2), i(ELEMENT) or all",
                    signal);
  int x = kind == 'i' ? find_elem(nl, a, la) : find_node(nl, a, la), y = b ? find_node(nl, b, lb) : -1;
  if (x < 0)
    return fail_fmt(errmsg, CUP_ERR_ARG, "probe '%.60s': no %s named '%.*s' in %s", signal,
                    kind == 'i' ? "element" : "node", (int)(la < 60 ? la : 60), a, nl->file);
  if (b && y < 0)
    return fail_fmt(errmsg, CUP_ERR_ARG, "probe '%.60s': no node named '%.*s' in %s", signal,
                    (int)(lb < 60 ? lb : 60), b, nl->file);
  if (kind == 'i' && nl->nelem_user && x >= nl->nelem_user) x = -1;   /* a configuration's own constraint */
  if (x < 0)
    return fail_fmt(errmsg, CUP_ERR_ARG, "probe '%.60s': no element named '%.*s' in %s", signal,
                    (int)(la < 60 ? la : 60), a, nl->file);
  int k = probe_one(nl, kind, x, y, errmsg);
  return k >= 0 && nl->hooks ? nl->hooks->probe(nl, k, &(nl_probe_at){kind, x, y}, errmsg) : k;
}

int nl_probe_next(cup_netlist *sub, const char *name, nl_probe_at *at, char *errmsg) {
  char kind;
  const char *a, *b;
  size_t la, lb;
  int x = -1, y = -1;
  if (!sub->hooks && !scratch(sub, errmsg) && at && at->kind) {
    kind = at->kind, x = at->x, y = at->y;
  } else if (!sub->hooks && !scratch(sub, errmsg) && split(name, &kind, &a, &la, &b, &lb)) {
    x = kind == 'i' ? find_elem(sub, a, la) : find_node(sub, a, la);
    y = b ? find_node(sub, b, lb) : -1;
    if ((b && y < 0) || (kind == 'i' && sub->nelem_user && x >= sub->nelem_user)) x = -1;
    if (at && x >= 0) *at = (nl_probe_at){kind, x, y};
  }
  if (x < 0) return cup_netlist_probe(sub, name, errmsg);   /* (its message, or its answer) */
  char *own = strdup(name);
  if (!own) return fail_fmt(errmsg, CUP_ERR_NOMEM, "out of memory");
  return probe_row(sub, kind, x, y, own, errmsg);
}

int cup_netlist_probe_default(cup_netlist *nl, int limit, char *errmsg) {
  if (!nl) return fail_fmt(errmsg, CUP_ERR_ARG, "netlist probe: NULL netlist");
  int st = scratch(nl, errmsg);
  for (int k = 0; k < nl->nprobe && !st; k++) {
    int r = cup_netlist_probe(nl, nl->probe_text[k], errmsg);
    st = r < 0 ? r : CUP_OK;
  }
  if (!st && (nl->probe_all || (!nl->nprobe && nl->nnodes - 1 + nl->nelem <= limit))) st = probe_all(nl, errmsg);
  return st;
}

int cup_netlist_signal_count(const cup_netlist *nl) { return nl ? nl->nsig : 0; }

const char *cup_netlist_signal_name(const cup_netlist *nl, int k) {
  return nl && k >= 0 && k < nl->nsig ? nl->sig_name[k] : NULL;
}

const char *cup_netlist_signal_unit(const cup_netlist *nl, int k) {
  const char *name = cup_netlist_signal_name(nl, k);
  return !name ? NULL : name[0] == 'v' ? "V" : name[0] == 'i' ? "A" : "1";
}

/* zeta over a configuration's rows into v + n + p: its diodes' and its
 * constraints' multipliers, Lam (x, u, zeta) (u at v + n). (Out of line,
 * as reads_u: inlined, cup_netlist_signals saved their registers at every
 * sample of every netlist.) */
static __attribute__((noinline)) void zeta_full(const cup_netlist *nl, const double *x, const double *zeta, double *v) {
  int n = nl->n, p = nl->p, mr = nl->mr, nv = n + p + mr;
  double *z = v + n + p;
  for (int r = 0; r < nl->m; r++) {
    int k = nl->zrow[r];
    if (k >= 0) { z[r] = zeta ? zeta[k] : 0; continue; }
    const double *l = nl->Lam + (size_t)(-1 - k) * (size_t)nv;
    double acc = la_dot(l, x, n) + la_dot(l + n, v + n, p);
    if (zeta) acc += la_dot(l + n + p, zeta, mr);
    z[r] = acc;
  }
}

int nl_signal_row(cup_netlist *nl, char kind, int a, int b, double *row) {
  int st = scratch(nl, NULL);
  if (st) return st;
  memset(row, 0, sizeof(double) * (size_t)nvar(nl));
  memset(nl->prow, 0, sizeof(double) * (size_t)nports(nl));
  st = kind == 'i' ? nl_prow_current(nl, a, nl->prow) : nl_prow_node(nl, a, 1, nl->prow);
  if (!st && kind == 'v' && b >= 0) st = nl_prow_node(nl, b, -1, nl->prow);
  if (!st) to_vars(nl, nl->prow, row);
  return st;
}

/* Whether a signal reads u: a column of u, or a constraint's multiplier
 * (zeta_full's rows -1 - q hold Lam's u part). */
static __attribute__((noinline)) int reads_u(const cup_netlist *nl) {
  int n = nl->n, p = nl->p;
  for (int q = 0; q < nl->sig_ptr[nl->nsig]; q++) {
    int i = nl->sig_idx[q];
    if ((i >= n && i < n + p) || (i >= n + p && nl->zrow && nl->zrow[i - n - p] < 0)) return 1;
  }
  return 0;
}

/* Whether inputs a and b have the same terms in the same components, their
 * constants and jump edged PULSEs (spice_jump_pulse reads these fields
 * alone) the same, bit for bit: what sig_input keeps of one holds for the
 * other. */
static int same_pieces(const cup_input *a, const cup_input *b) {
  if (a->p != b->p || a->nterms != b->nterms) return 0;
  for (int k = 0; k < a->nterms; k++) {
    const input_term *x = &a->terms[k], *y = &b->terms[k];
    if (x->comp != y->comp || x->kind != y->kind || input_jump_pulse(x) != input_jump_pulse(y)) return 0;
    if (x->kind == CUP_WAVE_CONSTANT && x->value != y->value) return 0;
    if (input_jump_pulse(x) && (x->delay != y->delay || x->period != y->period || x->width != y->width ||
                          x->value != y->value || x->value2 != y->value2))
      return 0;
  }
  return 1;
}

/* The cache of configuration nl's samples: the switched netlist's own
 * (root's), shared by the configurations whose terms are those of the
 * first one that asked (uref; checked once each, again after a time
 * origin moved either), so that a converter's pieces, each in another
 * configuration, find their gates' values still there (the full bridge's
 * records at its own steps missed all 4 gates every time); else nl's own
 * (none for the switched netlist itself as a configuration: its own is
 * the shared one). */
static __attribute__((noinline)) double *sig_ucache_check(cup_netlist *root, cup_netlist *nl) {
  if (!root->ucache || root->ucache_n != nl->ucache_n || root->p != nl->p) return nl == root ? NULL : nl->ucache;
  if (!root->uref || root->uref->t0 != root->uref_t0) {   /* the first, or uref's sources moved */
    memset(root->ucache, 0, sizeof(double) * (3 * (size_t)root->ucache_n + 2 + (size_t)root->p));
    root->uref = nl;
    root->uref_t0 = nl->t0;
    root->ugen++;
  }
  if ((nl->ushare != root->ugen && nl->ushare != -root->ugen) || nl->ushare_t0 != nl->t0) {
    nl->ushare = same_pieces(nl->u, root->uref->u) ? root->ugen : -root->ugen;
    nl->ushare_t0 = nl->t0;
  }
  return nl->ushare > 0 ? root->ucache : nl == root ? NULL : nl->ucache;   /* (root's own is the shared one) */
}

static double *sig_ucache(cup_netlist *root, cup_netlist *nl) {
  if (!root->hooks) return nl->ucache;
  const cup_netlist *r = root->uref;
  if (r && nl->ushare == root->ugen && r->t0 == root->uref_t0 && nl->t0 == nl->ushare_t0) return root->ucache;
  return sig_ucache_check(root, nl);
}

/* u(t) for the signals: cup_input_eval's sums (each component from 0, its
 * terms in order), a PULSE with jump edges (rise and fall 0) read from
 * the cache (sig_ucache) while t is in the piece it was evaluated in
 * (spice_jump_pulse: the value and where it ends, bit for bit
 * pulse_value's), so a converter's gates are evaluated once a piece rather
 * than at each of its samples (about 70 instructions a gate and sample).
 * When every term is constant or such a PULSE, the sums themselves are
 * kept for the piece all of them hold on, and read back whole. Not
 * inlined: inside cup_netlist_signals it cost every netlist 16
 * instructions a sample. */
static __attribute__((noinline)) int sig_input(cup_netlist *root, cup_netlist *nl, double t, double *out) {
  const cup_input *u = nl->u;
  nl->u_hi = -INFINITY;                                    /* (out is nl's vals' u: see below) */
  if (!u || u->fn || nl->ucache_n != u->nterms) return cup_input_eval(u, t, out);
  double *cache = sig_ucache(root, nl), hi = INFINITY;
  if (!cache) return cup_input_eval(u, t, out);
  double *whole = cache + 3 * (size_t)u->nterms;
  int p = u->p;
  if (t >= whole[0] && t < whole[1]) {
    la_copy_few(out, whole + 2, p);
    nl->u_lo = whole[0];
    nl->u_hi = whole[1];
    return CUP_OK;
  }
  la_zero_few(out, p);
  for (int k = 0; k < u->nterms; k++) {
    const input_term *w = &u->terms[k];
    double *c = cache + 3 * (size_t)k, v;
    if (t >= c[0] && t < c[1]) v = c[2];
    else if (w->kind == CUP_WAVE_CONSTANT) {
      out[w->comp] += w->value;                            /* (input_term_value's, without the call) */
      continue;
    } else if (!input_jump_pulse(w)) {
      v = input_term_value(w, t);
      hi = -INFINITY;                                      /* no sums kept */
    } else {
      c[0] = t;
      c[2] = v = spice_jump_pulse(w, t, &c[1]);
    }
    if (!(c[1] >= hi)) hi = c[1];                          /* (never past a NaN) */
    out[w->comp] += v;
  }
  whole[0] = nl->u_lo = t;
  whole[1] = nl->u_hi = hi;
  la_copy_few(whole + 2, out, p);
  return CUP_OK;
}

/* u(t) as cup_input_eval sums it (each component from 0, its terms in
 * order), a constant's and a sine's value in place rather than through
 * input_term_value, and no libc call to clear out: the precision
 * rectifier's SIN is a constant and a sine (84 of a sample's instructions
 * through the call, 52 in place, sin itself aside). */
static int sig_terms(const cup_input *u, double t, double *out) {
  if (!u || u->fn) return cup_input_eval(u, t, out);
  const input_term *w = u->terms, *end = w + u->nterms;
  la_zero_few(out, u->p);
  for (; w < end; w++) {
    double v = w->kind == CUP_WAVE_CONSTANT ? w->value
               : w->kind == CUP_WAVE_SINE   ? input_sine_value(w, t)
                                            : input_term_value(w, t);
    out[w->comp] += v;
  }
  return CUP_OK;
}

/* The signals' sparse rows over (x, u, zeta) gathered side by side in
 * nl->vals first: the same terms in the same order as a row read from
 * three places (no zeta: zeros, 0 times an entry as before). u(t) only
 * when a signal reads it (the six-pulse rectifier's 4 signals do not: 3
 * sines a sample, a fifth of its samples' instructions). */
int cup_netlist_signals(cup_netlist *nl, double t, const double *x, const double *zeta, double *out) {
  if (!nl || !x || (!out && nl->nsig)) return CUP_ERR_ARG;
  if (!nl->nsig) return CUP_OK;
  cup_netlist *root = nl;
  if (nl->hooks) nl = nl->hooks->current(nl);
  int n = nl->n, p = nl->p, m = nl->m;
  double *v = nl->vals;
  la_copy_few(v, x, n);
  if (nl->sig_seen != nl->nsig) {
    nl->sig_u = reads_u(nl);
    nl->sig_seen = nl->nsig;
  }
  if (p && nl->sig_u) {
    if (!nl->ucache) {
      if (sig_terms(nl->u, t, v + n)) return CUP_ERR_CALLBACK;
    } else if (!(t >= nl->u_lo && t < nl->u_hi) && sig_input(root, nl, t, v + n))   /* (else the last sample's u holds) */
      return CUP_ERR_CALLBACK;
  }
  if (nl->zrow) zeta_full(nl, x, zeta, v);
  else if (zeta) la_copy_few(v + n + p, zeta, m);
  else la_zero_few(v + n + p, m);
  const int *ptr = nl->sig_ptr, *idx = nl->sig_idx;
  const double *val = nl->sig_val;
  for (int k = 0; k < nl->nsig; k++) {
    double acc = 0;
    for (int q = ptr[k]; q < ptr[k + 1]; q++) acc += val[q] * v[idx[q]];
    out[k] = acc;
  }
  return CUP_OK;
}

/* ---- the signals as one map (signal_map.h) ---------------------------------------- */

/* nl's signal rows dense over (x, u, zeta of the LCS): a configuration's
 * constraint rows (zrow < 0) by their rows of Lam, as zeta_full sums them. */
static void fold_rows(const cup_netlist *nl, double *rows, int nc) {
  int n = nl->n, p = nl->p, nv = n + p + (nl->zrow ? nl->mr : nl->m);
  for (int k = 0; k < nl->nsig; k++) {
    double *r = rows + (size_t)k * nc;
    for (int q = nl->sig_ptr[k]; q < nl->sig_ptr[k + 1]; q++) {
      int i = nl->sig_idx[q], zr = i - n - p;
      double s = nl->sig_val[q];
      if (zr < 0 || !nl->zrow) r[i] += s;
      else if (nl->zrow[zr] >= 0) r[n + p + nl->zrow[zr]] += s;
      else {
        const double *l = nl->Lam + (size_t)(-1 - nl->zrow[zr]) * (size_t)nv;
        for (int j = 0; j < nv; j++) r[j] += s * l[j];
      }
    }
  }
}

const signal_map *nl_signal_map(cup_netlist *nl) {
  if (!nl || !nl->nsig) return NULL;
  if (nl->hooks) nl = nl->hooks->current(nl);
  if (nl->smap.ns == nl->nsig) return &nl->smap;
  int m = nl->zrow ? nl->mr : nl->m, nc = nl->n + nl->p + m;
  free(nl->smap_rows);
  nl->smap.ns = 0;
  nl->smap_rows = calloc((size_t)nl->nsig * (size_t)nc + 1, sizeof(double));
  if (!nl->smap_rows) return NULL;
  fold_rows(nl, nl->smap_rows, nc);
  nl->smap = (signal_map){.key = nl, .rows = nl->smap_rows, .ns = nl->nsig, .n = nl->n, .p = nl->p, .m = m,
                          .u = nl->u};
  return &nl->smap;
}

int nl_same_input(const cup_input *a, const cup_input *b) {
  if (a == b) return 1;
  if (!a || !b || a->fn || b->fn || a->p != b->p || a->nterms != b->nterms) return 0;
  for (int k = 0; k < a->nterms; k++) {
    const input_term *x = &a->terms[k], *y = &b->terms[k];
    if (x->comp != y->comp || x->kind != y->kind || x->value != y->value || x->amp != y->amp ||
        x->omega != y->omega || x->phase != y->phase || x->delay != y->delay || x->damping != y->damping ||
        x->value2 != y->value2 || x->rise != y->rise || x->fall != y->fall || x->width != y->width ||
        x->period != y->period || x->np != y->np)
      return 0;
    for (int j = 0; j < x->np; j++)
      if (x->t[j] != y->t[j] || x->v[j] != y->v[j]) return 0;
  }
  return 1;
}

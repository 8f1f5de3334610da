/* netlist_graph — the circuit's topology and its hybrid matrix (see
 * netlist_impl.h for the formulation): which diodes are fixed by the state,
 * index problems named by their elements, the forest of voltage ports, and
 * H from one sparse Cholesky factorization of the resistors' Laplacian
 * over the supernodes (CHOLMOD: analyze, factorize, two sparse solves and
 * one sparse product). */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "netlist_impl.h"

int nl_fail(const nl_circuit *c, int e, char *errmsg, int status, const char *fmt, ...) {
  if (!errmsg) return status;
  size_t cap = CUP_ERRMSG_LEN;
  const char *file = e >= 0 && c->files && c->elem[e].file < c->nfiles ? c->files[c->elem[e].file] : c->file;
  int w = e >= 0 ? snprintf(errmsg, cap, "%s:%d:%d: %s: ", file, c->elem[e].line, c->elem[e].col, c->elem[e].name)
                 : snprintf(errmsg, cap, "%s: ", c->file);
  va_list ap;
  va_start(ap, fmt);
  fail_vfmt_at(errmsg, w, status, fmt, ap);
  va_end(ap);
  return status;
}

static int nomem(const nl_circuit *c, char *errmsg) {
  return nl_fail(c, -1, errmsg, CUP_ERR_NOMEM, "out of memory while formulating the circuit");
}

/* ---- union-find ------------------------------------------------------------- */

static int find(int *uf, int v) {
  while (uf[v] != v) v = uf[v] = uf[uf[v]];
  return v;
}

static void unite(int *uf, int a, int b) { uf[find(uf, a)] = find(uf, b); }

/* "A, B and C" (up to about 160 characters, then "..."). */
static void join_names(char *buf, size_t size, const nl_circuit *c, const int *e, int n) {
  size_t len = 0;
  buf[0] = '\0';
  for (int k = 0; k < n && len + 1 < size; k++) {
    if (len > 160) { snprintf(buf + len, size - len, ", ..."); return; }
    len += (size_t)snprintf(buf + len, size - len, "%s%s", k == 0 ? "" : k + 1 < n ? ", " : " and ",
                            c->elem[e[k]].name);
  }
}

/* The path from a to b through the forest made of the elements before
 * `upto` whose kinds are in `kinds` (a bit mask); into path, its length
 * returned (0 if none, -1 out of memory). */
static int forest_path(const nl_circuit *c, unsigned kinds, int upto, int a, int b, int *path) {
  int nn = c->nnodes, len = 0;
  int *prev = malloc(sizeof(int) * (size_t)nn), *via = malloc(sizeof(int) * (size_t)nn);
  int *queue = malloc(sizeof(int) * (size_t)nn);
  if (!prev || !via || !queue) { free(prev); free(via); free(queue); return -1; }
  for (int v = 0; v < nn; v++) prev[v] = -1;
  prev[a] = a;
  int head = 0, tail = 0;
  queue[tail++] = a;
  while (head < tail && prev[b] < 0) {           /* breadth first: small circuits, one error */
    int v = queue[head++];
    for (int e = 0; e < upto; e++) {
      const nl_elem *el = &c->elem[e];
      if (!(kinds >> el->kind & 1u) || el->a == el->b) continue;
      int w = el->a == v ? el->b : el->b == v ? el->a : -1;
      if (w < 0 || prev[w] >= 0) continue;
      prev[w] = v;
      via[w] = e;
      queue[tail++] = w;
    }
  }
  for (int v = b; prev[b] >= 0 && v != a; v = prev[v]) path[len++] = via[v];
  free(prev); free(via); free(queue);
  return len;
}

/* ---- topology --------------------------------------------------------------- */

/* E and G sense v(nc+) - v(nc-): nodes that some element joins to the
 * circuit (a node written only as a control pin has no voltage). */
static int control_nodes(const nl_circuit *c, int e, char *errmsg) {
  const nl_elem *el = &c->elem[e];
  for (int k = 0; k < 2; k++) {
    int v = k ? el->cb : el->ca, used = v == 0;
    for (int f = 0; f < c->nelem && !used; f++) used = c->elem[f].a == v || c->elem[f].b == v;
    if (!used)
      return nl_fail(c, e, errmsg, CUP_ERR_PARSE, "control node '%s' is not connected to any element (an "
                     "undefined node: it has no voltage to sense)", c->node[v]);
  }
  return CUP_OK;
}

static int check_elements(const nl_circuit *c, char *errmsg) {
  int small[512];                                /* (one block, zeroed) */
  int *deg = scratch_take(small, sizeof small, sizeof(int) * 2 * (size_t)c->nnodes, 1);
  int *who = deg ? deg + c->nnodes : NULL;
  if (!deg) return nomem(c, errmsg);
  int st = CUP_OK;
  for (int e = 0; e < c->nelem && !st; e++) {
    const nl_elem *el = &c->elem[e];
    deg[el->a]++; deg[el->b]++;
    who[el->a] = who[el->b] = e;
    if ((el->kind == NL_E || el->kind == NL_G) && !st) st = control_nodes(c, e, errmsg);
    if (el->a != el->b) continue;
    if (el->kind == NL_V || el->kind == NL_E || el->kind == NL_H)
      st = nl_fail(c, e, errmsg, CUP_ERR_PARSE, "short-circuited voltage source: both terminals on node '%s'",
                   c->node[el->a]);
    else if (el->kind == NL_C)
      st = nl_fail(c, e, errmsg, CUP_ERR_PARSE, "both terminals on node '%s': the capacitor's voltage is held "
                   "at 0 (an index problem)", c->node[el->a]);
    else if (el->kind == NL_D)
      st = nl_fail(c, e, errmsg, CUP_ERR_PARSE, "both terminals on node '%s': the diode is shorted",
                   c->node[el->a]);
  }
  for (int v = 1; v < c->nnodes && !st && !c->derived; v++)   /* an open switch may leave one */
    if (deg[v] == 1)
      st = nl_fail(c, who[v], errmsg, CUP_ERR_PARSE, "node '%s' is connected to %s only (a dangling node)",
                   c->node[v], c->elem[who[v]].name);
  scratch_free(deg, small);
  return st;
}

/* Capacitors and voltage sources (E and H too): a loop of them is an index
 * problem. */
static int voltage_loops(const nl_circuit *c, int *uf, char *errmsg) {
  for (int e = 0; e < c->nelem; e++) {
    const nl_elem *el = &c->elem[e];
    if (el->kind != NL_C && el->kind != NL_V && el->kind != NL_E && el->kind != NL_H) continue;
    if (find(uf, el->a) != find(uf, el->b)) { unite(uf, el->a, el->b); continue; }
    int *path = malloc(sizeof(int) * ((size_t)c->nelem + 1));
    if (!path) return nomem(c, errmsg);
    int len = forest_path(c, 1u << NL_C | 1u << NL_V | 1u << NL_E | 1u << NL_H, e, el->a, el->b, path);
    if (len < 0) { free(path); return nomem(c, errmsg); }
    path[len++] = e;
    int caps = 0;
    for (int k = 0; k < len; k++) caps += c->elem[path[k]].kind == NL_C;
    char names[1024];                  /* join_names elides past 160 characters */
    join_names(names, sizeof names, c, path, len);
    free(path);
    return caps ? nl_fail(c, e, errmsg, CUP_ERR_PARSE, "%s form a loop of capacitors and voltage sources "
                          "(an index problem: their voltages are not independent)", names)
                : nl_fail(c, e, errmsg, CUP_ERR_PARSE, "short-circuited voltage sources: %s form a loop", names);
  }
  for (int e = 0; e < c->nelem; e++)            /* closed switches after them (netlist_switch.c made any */
    if (c->elem[e].kind == NL_Z) unite(uf, c->elem[e].a, c->elem[e].b);   /* that closes a loop a row) */
  return CUP_OK;
}

/* Every part of the circuit must reach ground through resistors, voltage
 * ports and fixed diodes; what else joins a part that does not is a cutset
 * of inductors and current sources. */
static int cutsets(const nl_circuit *c, int *uf, char *errmsg) {
  int bad = -1;
  for (int v = 1; v < c->nnodes && bad < 0; v++)
    if (find(uf, v) != find(uf, 0)) bad = v;
  if (bad < 0) return CUP_OK;
  int root = find(uf, bad), n = 0, first = -1;
  int *cut = calloc((size_t)c->nelem + 1, sizeof(int));
  if (!cut) return nomem(c, errmsg);
  for (int e = 0; e < c->nelem; e++) {
    const nl_elem *el = &c->elem[e];
    if ((find(uf, el->a) == root) != (find(uf, el->b) == root)) cut[n++] = e;
    if (first < 0 && (find(uf, el->a) == root || find(uf, el->b) == root)) first = e;
  }
  char names[1024];                    /* join_names elides past 160 characters */
  join_names(names, sizeof names, c, cut, n);
  int st = n ? nl_fail(c, cut[0], errmsg, CUP_ERR_PARSE, "%s form a cutset of inductors and current sources "
                       "(they alone join node '%s' to the rest of the circuit): their currents are not "
                       "independent (an index problem)", names, c->node[bad])
             : nl_fail(c, first, errmsg, CUP_ERR_PARSE, "node '%s' has no path to ground: its part of the "
                       "circuit is floating", c->node[bad]);
  free(cut);
  return st;
}

/* Breadth-first trees of the voltage ports; ground's tree is supernode -1. */
static int build_forest(cup_netlist *nl, const nl_circuit *c, const unsigned char *vport, char *errmsg) {
  int nn = c->nnodes;
  int small[512];                                /* (one block, zeroed) */
  int *start = scratch_take(small, sizeof small, sizeof(int) * ((size_t)nn + 1 + 2 * (size_t)c->nelem + 1 + (size_t)nn + 1), 1);
  if (!start) return nomem(c, errmsg);
  int *adj = start + nn + 1, *queue = adj + 2 * c->nelem + 1;
  for (int e = 0; e < c->nelem; e++)
    if (vport[e]) { start[c->elem[e].a + 1]++; start[c->elem[e].b + 1]++; }
  for (int v = 0; v < nn; v++) start[v + 1] += start[v];
  for (int e = 0; e < c->nelem; e++)
    if (vport[e]) { adj[start[c->elem[e].a]++] = e; adj[start[c->elem[e].b]++] = e; }
  for (int v = nn; v > 0; v--) start[v] = start[v - 1];
  start[0] = 0;
  for (int v = 0; v < nn; v++) nl->parent[v] = -2;
  nl->ns = 0;
  for (int r = 0; r < nn; r++) {
    if (nl->parent[r] != -2) continue;
    int sn = r == 0 ? -1 : nl->ns++, head = 0, tail = 0;
    nl->parent[r] = -1; nl->pport[r] = -1; nl->depth[r] = 0; nl->snode[r] = sn; nl->psign[r] = 0;
    queue[tail++] = r;
    while (head < tail) {
      int v = queue[head++];
      for (int k = start[v]; k < start[v + 1]; k++) {
        const nl_elem *el = &c->elem[adj[k]];
        int w = el->a == v ? el->b : el->a;
        if (nl->parent[w] != -2) continue;
        nl->parent[w] = v;
        nl->pport[w] = nl->eport[adj[k]];
        nl->psign[w] = (signed char)(w == el->a ? 1 : -1);   /* v(port) = phi(a) - phi(b) */
        nl->depth[w] = nl->depth[v] + 1;
        nl->snode[w] = sn;
        queue[tail++] = w;
      }
    }
  }
  scratch_free(start, small);
  return CUP_OK;
}

/* Ports and variables: voltage ports (capacitors, voltage sources, E, H,
 * fixed diodes), then current ports (inductors, current sources, F, G,
 * free diodes), each group in netlist order; x = (inductor currents,
 * capacitor voltages), u = the sources, zeta = the diodes, in netlist
 * order; the controlled sources are numbered in netlist order too. */
static void number_ports(cup_netlist *nl, const nl_circuit *c, const unsigned char *fixed) {
  static const nl_kind order[12] = {NL_C, NL_V, NL_E, NL_H, NL_Z, NL_D, NL_L, NL_I, NL_F, NL_G, NL_O, NL_D};
  int nx_l = 0, nx_c = 0, nu = 0, nz = 0, nk = 0;
  for (int e = 0; e < c->nelem; e++) {
    nl_kind k = c->elem[e].kind;
    if (k == NL_L) nl->nL++;
    if (k == NL_C) nl->nC++;
  }
  for (int e = 0; e < c->nelem; e++) {
    nl_kind k = c->elem[e].kind;
    nl->evar[e] = k == NL_L ? nx_l++ : k == NL_C ? nl->nL + nx_c++ : k == NL_V || k == NL_I ? nu++ : k == NL_D ? nz++
                : k >= NL_E && k <= NL_H ? nk++ : -1;
    if (k >= NL_E && k <= NL_H) nl->ctl_elem[nl->evar[e]] = e;
    nl->eport[e] = -1;
  }
  /* the ports group by group of `order`, netlist order within each: each
   * element's group (-1: none), then a counting sort (12 passes over the
   * elements were some 1.3 k instructions a switch configuration) */
  signed char gof[NL_O + 1];
  for (int g = 0; g <= NL_O; g++) gof[g] = -1;
  for (int g = 11; g >= 0; g--) gof[order[g]] = (signed char)g;   /* (a diode: 5 or 11, by fixed[e] below) */
  int at[13] = {0};
  for (int e = 0; e < c->nelem; e++) {
    nl_kind k = c->elem[e].kind;
    int g = k == NL_D ? (fixed[e] ? 5 : 11) : gof[k];
    if (g >= 0) at[g + 1]++;
  }
  for (int g = 0; g < 12; g++) at[g + 1] += at[g];
  nl->nv = at[6];
  nl->ni = at[12] - at[6];
  for (int e = 0; e < c->nelem; e++) {
    nl_kind k = c->elem[e].kind;
    int g = k == NL_D ? (fixed[e] ? 5 : 11) : gof[k];
    if (g < 0) continue;
    int q = at[g]++;
    nl->eport[e] = q;
    int var = k == NL_L || k == NL_C ? NL_VAR_X : k == NL_D ? NL_VAR_Z : k == NL_Z || k == NL_O ? NL_VAR_NONE
            : k >= NL_E ? NL_VAR_CTL : NL_VAR_U;
    nl->port[q] = (nl_port){e, var, nl->evar[e], k == NL_D && g < 6 ? -1 : 1};
  }
  nl->n = nl->nL + nl->nC;
  nl->p = nu;
  nl->m = nz;
  nl->nctl = nk;
}

int nl_topology(cup_netlist *nl, const nl_circuit *c, char *errmsg) {
  int nn = c->nnodes, ne = c->nelem;
  int st = check_elements(c, errmsg);
  if (st) return st;
  /* the scratch in one block (uf, then fixed and vport zeroed), the
   * netlist's arrays in another that port owns (cup_netlist_free) */
  size_t E = (size_t)ne + 1, N = (size_t)nn;
  int small[512];
  int *uf = scratch_take(small, sizeof small, sizeof(int) * N + 2 * E, 1);
  unsigned char *fixed = uf ? (unsigned char *)(uf + N) : NULL, *vport = fixed ? fixed + E : NULL;
  nl->port = malloc(sizeof(nl_port) * E + sizeof(int) * (3 * E + 4 * N) + N);
  int *iw = nl->port ? (int *)(nl->port + E) : NULL;
  if (iw) {
    nl->eport = iw; nl->evar = iw + E; nl->ctl_elem = iw + 2 * E;
    nl->parent = iw + 3 * E; nl->pport = nl->parent + N; nl->depth = nl->pport + N; nl->snode = nl->depth + N;
    nl->psign = (signed char *)(nl->snode + N);
  }
  if (!uf || !iw) st = nomem(c, errmsg);
  for (int v = 0; !st && v < nn; v++) uf[v] = v;
  if (!st) st = voltage_loops(c, uf, errmsg);
  for (int e = 0; !st && e < ne; e++)
    if (c->elem[e].kind == NL_R) unite(uf, c->elem[e].a, c->elem[e].b);
  for (int e = 0; !st && e < ne; e++) {          /* a diode joining two parts is fixed */
    const nl_elem *el = &c->elem[e];
    if (el->kind != NL_D || el->eq == NL_EQ_LOOP || (el->eq != NL_EQ_CUT && find(uf, el->a) == find(uf, el->b)))
      continue;
    fixed[e] = 1;
    unite(uf, el->a, el->b);
  }
  if (!st) st = cutsets(c, uf, errmsg);
  if (!st) {
    number_ports(nl, c, fixed);
    for (int e = 0; e < ne; e++) vport[e] = nl->eport[e] >= 0 && nl->eport[e] < nl->nv;
    st = build_forest(nl, c, vport, errmsg);
  }
  scratch_free(uf, small);
  return st;
}

/* ---- loops of ideal diodes ---------------------------------------------------- */

/* A diode by its two nodes, the smaller first (parallel diodes sort together). */
typedef struct { int lo, hi, e; } nl_pair;

static int pair_cmp(const void *x, const void *y) {
  const nl_pair *p = x, *q = y;
  if (p->lo != q->lo) return (p->lo > q->lo) - (p->lo < q->lo);
  if (p->hi != q->hi) return (p->hi > q->hi) - (p->hi < q->hi);
  return (p->e > q->e) - (p->e < q->e);
}

/* A directed cycle of diodes (anode to cathode) by depth-first search:
 * its elements into loop, their count returned (0: none, -1: no memory). */
static int directed_cycle(const nl_circuit *c, const int *diode, int nd, int *loop) {
  int nn = c->nnodes, len = 0;
  size_t N = (size_t)nn;                         /* (one block: start, state, adj, via, stack, next) */
  int *start = calloc(5 * N + 2 + (size_t)nd + 1, sizeof(int)), *state = start ? start + N + 1 : NULL;
  int *adj = state ? state + N : NULL, *via = adj ? adj + nd + 1 : NULL;
  int *stack = via ? via + N : NULL, *next = stack ? stack + N + 1 : NULL;
  if (!start) len = -1;
  for (int k = 0; len == 0 && k < nd; k++) start[c->elem[diode[k]].a + 1]++;
  for (int v = 0; len == 0 && v < nn; v++) start[v + 1] += start[v];
  for (int k = 0; len == 0 && k < nd; k++) adj[start[c->elem[diode[k]].a]++] = diode[k];
  for (int v = nn; len == 0 && v > 0; v--) start[v] = start[v - 1];
  if (len == 0) start[0] = 0;
  for (int r = 0; len == 0 && r < nn; r++) {     /* state 0 new, 1 on the stack, 2 done */
    if (state[r]) continue;
    int top = 0;
    stack[top++] = r;
    state[r] = 1;
    next[r] = start[r];
    while (top > 0 && len == 0) {
      int v = stack[top - 1];
      if (next[v] == start[v + 1]) { state[v] = 2; top--; continue; }
      int e = adj[next[v]++], w = c->elem[e].b;
      if (state[w] == 0) { state[w] = 1; via[w] = e; next[w] = start[w]; stack[top++] = w; }
      else if (state[w] == 1) {                  /* back to the stack: the cycle w -> ... -> v -> w */
        loop[len++] = e;
        for (int u = v; u != w; u = c->elem[via[u]].a) loop[len++] = via[u];
      }
    }
  }
  free(start);
  for (int i = 0, j = len - 1; i < j; i++, j--) { int t = loop[i]; loop[i] = loop[j]; loop[j] = t; }
  return len;
}

int nl_diode_loops(cup_netlist *nl, const nl_circuit *c) {
  int nd = 0;
  size_t E = (size_t)c->nelem + 1;               /* (one block: pr, diode, loop) */
  nl_pair *pr = malloc(sizeof(nl_pair) * E + sizeof(int) * (E + (size_t)c->nnodes + 1));
  if (!pr) return CUP_ERR_NOMEM;
  int *diode = (int *)(pr + E), *loop = diode + E;
  for (int e = 0; e < c->nelem; e++) {
    const nl_elem *el = &c->elem[e];
    if (el->kind != NL_D) continue;
    pr[nd] = (nl_pair){el->a < el->b ? el->a : el->b, el->a < el->b ? el->b : el->a, e};
    diode[nd++] = e;
  }
  qsort(pr, (size_t)nd, sizeof *pr, pair_cmp);
  int two[2] = {-1, -1};
  for (int k = 0; k + 1 < nd && two[0] < 0; k++)
    if (pr[k].lo == pr[k + 1].lo && pr[k].hi == pr[k + 1].hi) { two[0] = pr[k].e; two[1] = pr[k + 1].e; }
  char names[CUP_ERRMSG_LEN];
  int st = CUP_OK, len = two[0] < 0 ? directed_cycle(c, diode, nd, loop) : 0;
  if ((two[0] >= 0 || len > 0) && !(nl->warning = malloc(CUP_ERRMSG_LEN))) {
    st = CUP_ERR_NOMEM;
  } else if (two[0] >= 0) {
    const nl_elem *d0 = &c->elem[two[0]];
    int same = d0->a == c->elem[two[1]].a;
    join_names(names, sizeof names, c, two, 2);
    nl_fail(c, two[0], nl->warning, CUP_OK, "%s are ideal diodes %s between nodes '%s' and '%s', a loop with no "
            "resistance: %s is not unique; the run takes one", names, same ? "in parallel" : "in anti-parallel",
            c->node[d0->a], c->node[d0->b],
            same ? "how their current splits when they conduct" : "a current around it");
  } else if (len > 0) {
    join_names(names, sizeof names, c, loop, len);
    nl_fail(c, loop[0], nl->warning, CUP_OK, "%s form a loop of ideal diodes, all in one direction around it, "
            "with no resistance: a current around it is not unique; the run takes one", names);
  } else if (len < 0) {
    st = CUP_ERR_NOMEM;
  }
  free(pr);
  return st;
}

int nl_path(const cup_netlist *nl, int a, int b, int *port, double *coef) {
  int len = 0;
  while (a != b && !(nl->parent[a] < 0 && nl->parent[b] < 0)) {
    if (nl->depth[a] >= nl->depth[b]) {
      port[len] = nl->pport[a]; coef[len++] = nl->psign[a]; a = nl->parent[a];
    } else {
      port[len] = nl->pport[b]; coef[len++] = -nl->psign[b]; b = nl->parent[b];
    }
  }
  return len;
}

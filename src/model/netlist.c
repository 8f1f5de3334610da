/* netlist — a parsed circuit into an LCS (see netlist_impl.h and
 * docs/netlist.md): the topology and the hybrid matrix H come from
 * netlist_graph.c and netlist_hybrid.c; here H's rows become
 *     P x' = H_x (x, u, zeta),  w = S' H_d (x, u, zeta),
 * P = diag(L, C), w = i for a fixed diode, -v for a free one, and the
 * sources become the input u(t). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "catchup/netlist.h"
#include "netlist_impl.h"
#include "input_impl.h"

#define TWO_PI 6.283185307179586476925286766559

/* ---- the LCS ------------------------------------------------------------------ */

typedef struct parts {
  nl_coo A, B, C, D, E, G;
  la_sparse sA, sB, sC, sD, sE, sG;
} parts;

static void parts_free(parts *q) {
  nl_coo_free(&q->A); nl_coo_free(&q->B); nl_coo_free(&q->C);
  nl_coo_free(&q->D); nl_coo_free(&q->E); nl_coo_free(&q->G);
  la_sparse_free(&q->sA); la_sparse_free(&q->sB); la_sparse_free(&q->sC);
  la_sparse_free(&q->sD); la_sparse_free(&q->sE); la_sparse_free(&q->sG);
}

static cup_csc view(const la_sparse *s) {
  return s->nnz || s->ncol ? (cup_csc){s->nrow, s->ncol, s->p, s->i, s->x} : (cup_csc){0, 0, NULL, NULL, NULL};
}

/* H's entry (row port i, column port j) into the LCS matrix it belongs to. */
static int distribute(cup_netlist *nl, parts *q, const double *pdiag, int i, int j, double h) {
  const nl_port *pi = &nl->port[i], *pj = &nl->port[j];
  if (pj->var == NL_VAR_NONE) return CUP_OK;     /* a closed switch's voltage: 0 */
  double v = h * pj->sign;
  if (pi->var == NL_VAR_X) {
    nl_coo *t = pj->var == NL_VAR_X ? &q->A : pj->var == NL_VAR_U ? &q->E : &q->B;
    if (!nl->coupled || !nl->coupled[pi->index]) return nl_coo_add(t, pi->index, pj->index, v / pdiag[pi->index], 0);
    int st = CUP_OK;                              /* a coupled inductor: P^-1's column, the group's rows */
    for (int k = nl->Pinv.p[pi->index]; k < nl->Pinv.p[pi->index + 1] && !st; k++)
      st = nl_coo_add(t, nl->Pinv.i[k], pj->index, nl->Pinv.x[k] * v, fabs(nl->Pinv.x[k] * v));
    return st;
  }
  if (pi->var == NL_VAR_Z) {                      /* w = i (fixed: a voltage port) or -v (free) */
    double s = i < nl->nv ? 1 : -1;
    nl_coo *t = pj->var == NL_VAR_X ? &q->C : pj->var == NL_VAR_U ? &q->G : &q->D;
    return nl_coo_add(t, pi->index, pj->index, s * v, 0);
  }
  return CUP_OK;                                  /* a source's current or voltage: signals only */
}

/* 1 if diode j's column of B or D has an entry. */
static int column_used(const parts *q, int j) {
  for (int k = q->sB.p[j]; k < q->sB.p[j + 1]; k++)
    if (q->sB.x[k] != 0) return 1;
  for (int k = q->sD.p[j]; k < q->sD.p[j + 1]; k++)
    if (q->sD.x[k] != 0) return 1;
  return 0;
}

/* 1 if row i of C or D (or G, with_g) has an entry. */
static int row_used(const parts *q, int i, int with_g) {
  const la_sparse *M[3] = {&q->sC, &q->sD, &q->sG};
  for (int t = 0; t < 2 + with_g; t++)
    for (int k = 0; M[t]->p && k < M[t]->p[M[t]->ncol]; k++)
      if (M[t]->i[k] == i && M[t]->x[k] != 0) return 1;
  return 0;
}

/* A diode row that depends on neither the state nor another diode is
 * fixed by the sources alone: an index problem, named with them. In a
 * switch configuration's circuit a diode whose column is empty (shorted by
 * a closed switch, left hanging by an open one, or put across a source by
 * one) is inert or held off by the source instead: it changes nothing
 * (netlist_switch.c); a source that drives it forward leaves K(t) empty,
 * and the run stops there. */
static int decoupled_rows(const cup_netlist *nl, const nl_circuit *c, const parts *q, char *errmsg) {
  int small[256], *used = scratch_take(small, sizeof small, sizeof(int) * ((size_t)nl->m + 1), 1);
  if (!used) return nl_fail(c, -1, errmsg, CUP_ERR_NOMEM, "out of memory");
  for (int k = 0; k < q->sC.nnz; k++) used[q->sC.i[k]] = 1;
  for (int j = 0; j < q->sD.ncol; j++)
    for (int k = q->sD.p[j]; k < q->sD.p[j + 1]; k++) used[q->sD.i[k]] = used[j] = 1;
  int st = CUP_OK;
  for (int e = 0; e < c->nelem && !st; e++) {
    if (c->elem[e].kind != NL_D || used[nl->evar[e]]) continue;
    int r = nl->evar[e];
    if (c->derived && c->elem[e].eq == NL_EQ_NONE && !column_used(q, r)) continue;   /* inert, or held off */
    char names[160] = "";                        /* (the message's: a configuration's inert diodes need none) */
    size_t len = 0;
    for (int j = 0; j < q->sG.ncol && len < 120; j++)
      for (int k = q->sG.p[j]; k < q->sG.p[j + 1]; k++)
        if (q->sG.i[k] == r)
          len += (size_t)snprintf(names + len, sizeof names - len, "%s%s", len ? ", " : "",
                                  c->elem[nl->input_elem[j]].name);
    if (c->elem[e].eq != NL_EQ_NONE) {
      st = nl_fail(c, e, errmsg, CUP_ERR_PARSE, c->elem[e].eq == NL_EQ_LOOP
                   ? "no path: closed, the switch makes a loop of voltage sources (%s) with no capacitor: "
                     "put a resistor or inductor in the loop"
                   : "no path: open, the switch leaves current sources (%s) alone in a cutset: put a resistor "
                     "across the switch or give the current another path", len ? names : "nothing");
      break;
    }
    st = nl->row_fixed[r]
      ? nl_fail(c, e, errmsg, CUP_ERR_PARSE, "no path: the diode's current is set by %s alone (a cutset of "
                "current sources and diodes): put a resistor or capacitor across it", len ? names : "nothing")
      : nl_fail(c, e, errmsg, CUP_ERR_PARSE, "no path: the diode's voltage is set by %s alone (a loop of "
                "voltage sources and the diode): when it conducts its current is unbounded; put a resistor "
                "or inductor in the loop", len ? names : "nothing");
  }
  scratch_free(used, small);
  return st;
}

/* A diode whose current reaches no state and no other row (it flows
 * through voltage sources and controlled sources alone, e.g. straight
 * across an E's output) cannot be held off: when its row asks for current,
 * nothing bounds it. */
static int idle_columns(const cup_netlist *nl, const nl_circuit *c, const parts *q, char *errmsg) {
  for (int e = 0; e < c->nelem; e++) {
    if (c->elem[e].kind != NL_D) continue;
    int j = nl->evar[e], used = column_used(q, j);
    if (!used && c->derived && c->elem[e].eq == NL_EQ_NONE && !row_used(q, j, 0)) continue;   /* inert */
    if (!used)
      return nl_fail(c, e, errmsg, CUP_ERR_PARSE, "no path: the diode's current flows through voltage sources "
                     "(V, E, H) alone and changes no state: when it conducts its current is unbounded; put a "
                     "resistor or inductor in its loop");
  }
  return CUP_OK;
}

static int build_lcs(cup_netlist *nl, const nl_circuit *c, char *errmsg) {
  if (nl->n == 0)
    return nl_fail(c, -1, errmsg, CUP_ERR_UNSUPPORTED, "the circuit has no inductor or capacitor: there is no "
                   "state to integrate (resistive circuits are not supported)");
  parts q = {0};
  la_sparse Pc = {0};
  double *pdiag = malloc(sizeof(double) * (size_t)nl->n);
  if (!pdiag) return nl_fail(c, -1, errmsg, CUP_ERR_NOMEM, "out of memory");
  int st = nl_coupling_metric(nl, c, &Pc, errmsg);
  if (st) { free(pdiag); return st; }
  for (int e = 0; e < c->nelem && !st; e++)
    if (c->elem[e].kind == NL_L || c->elem[e].kind == NL_C) pdiag[nl->evar[e]] = c->elem[e].value;
  for (int j = 0; j < nl->H.ncol && !st; j++)
    for (int k = nl->H.p[j]; k < nl->H.p[j + 1] && !st; k++) st = distribute(nl, &q, pdiag, nl->H.i[k], j, nl->H.x[k]);
  int n = nl->n, m = nl->m, p = nl->p;
  if (!st) st = nl_coo_to_csc(&q.A, n, n, &q.sA);
  if (!st) st = nl_coo_to_csc(&q.B, n, m, &q.sB);
  if (!st) st = nl_coo_to_csc(&q.C, m, n, &q.sC);
  if (!st) st = nl_coo_to_csc(&q.D, m, m, &q.sD);
  if (!st) st = nl_coo_to_csc(&q.E, n, p, &q.sE);
  if (!st) st = nl_coo_to_csc(&q.G, m, p, &q.sG);
  if (st) { free(pdiag); la_sparse_free(&Pc); parts_free(&q); return nl_fail(c, -1, errmsg, st, "out of memory"); }
  st = decoupled_rows(nl, c, &q, errmsg);
  if (!st) st = idle_columns(nl, c, &q, errmsg);
  if (!st && c->derived) {                        /* a switch configuration: netlist_switch.c reduces it */
    la_sparse *const six[6] = {&q.sA, &q.sB, &q.sC, &q.sD, &q.sE, &q.sG};
    int rows = 0;                                 /* its constraint rows */
    for (int e = 0; e < c->nelem; e++) rows += c->elem[e].kind == NL_D && c->elem[e].eq != NL_EQ_NONE;
    st = nl_raw_store(nl, six, &pdiag, &Pc, !rows);
    if (st) st = nl_fail(c, -1, errmsg, st, "out of memory");
  } else if (!st) {
    cup_lcs_desc d = {0};
    d.n = n; d.m = m; d.p = p;
    d.A = view(&q.sA); d.C = view(&q.sC); d.E = view(&q.sE); d.G = view(&q.sG);
    d.B = view(&q.sB);
    if (q.sD.nnz) d.D = view(&q.sD);
    d.P = Pc.p ? (cup_metric){CUP_METRIC_SPARSE, NULL, view(&Pc), 0}
               : (cup_metric){CUP_METRIC_DIAGONAL, pdiag, {0}, 0};
    d.row_names = (const char *const *)nl->row_name;
    char lib[CUP_ERRMSG_LEN];
    st = cup_lcs_create(&nl->L, &d, lib);
    if (st && nl->nctl && (st == CUP_ERR_PB_CT || q.sD.nnz)) {
      /* controlled sources drive the diodes: B is not P^-1 C^T, or D is not
       * positive semidefinite (an active network); only theta runs it */
      d.keep_B = 1;
      st = cup_lcs_create(&nl->L, &d, lib);
    }
    if (st) st = nl_fail(c, -1, errmsg, st, "%s", lib);
  }
  free(pdiag);
  la_sparse_free(&Pc);
  parts_free(&q);
  return st;
}

/* ---- a switch configuration's parts, dense (netlist_switch.c reduces them) ---------- */

static void dense_into(const la_sparse *s, int nrow, double *a) {
  for (int j = 0; s->p && j < s->ncol; j++)
    for (int k = s->p[j]; k < s->p[j + 1]; k++) a[s->i[k] + (size_t)j * (size_t)nrow] = s->x[k];
}

/* The seven parts in one zeroed block behind the struct (one calloc, not
 * eight: a switched run forms its configurations as it goes); with no
 * constraint row (sparse), the sparse parts, pdiag and Pc moved in. */
int nl_raw_store(cup_netlist *nl, la_sparse *const six[6], double **pdiag, la_sparse *Pc, int sparse) {
  size_t n = (size_t)nl->n, m = (size_t)nl->m, p = (size_t)nl->p;
  size_t size[7] = {n * n, n * m, m * n, m * m, n * p, m * p, n * n}, total = 0;
  for (int k = 0; !sparse && k < 7; k++) total += size[k];
  nl_raw *R = calloc(1, sizeof *R + sizeof(double) * (total + 1));
  if (!R) return CUP_ERR_NOMEM;
  nl->raw = R;
  R->keep_B = nl->nctl > 0;
  R->sparse = sparse;
  if (sparse) {
    for (int k = 0; k < 6; k++) { R->part[k] = *six[k]; memset(six[k], 0, sizeof *six[k]); }
    R->Pc = *Pc;
    memset(Pc, 0, sizeof *Pc);
    R->pdiag = *pdiag;
    *pdiag = NULL;
    return CUP_OK;
  }
  double *at = (double *)(R + 1), **part[7] = {&R->A, &R->B, &R->C, &R->D, &R->E, &R->G, &R->P};
  for (int k = 0; k < 7; k++) { *part[k] = at; at += size[k]; }
  const int nrow[6] = {nl->n, nl->n, nl->m, nl->m, nl->n, nl->m};
  for (int k = 0; k < 6; k++) dense_into(six[k], nrow[k], *part[k]);
  if (Pc->p) dense_into(Pc, nl->n, R->P);
  for (size_t j = 0; !Pc->p && j < n; j++) R->P[j + j * n] = (*pdiag)[j];
  return CUP_OK;
}

void nl_raw_free(cup_netlist *nl) {
  nl_raw *R = nl->raw;
  if (!R) return;
  for (int k = 0; k < 6; k++) la_sparse_free(&R->part[k]);
  la_sparse_free(&R->Pc);
  free(R->pdiag);
  free(R);                                         /* (the dense parts in its block) */
  nl->raw = NULL;
}

/* ---- the input and x0 ------------------------------------------------------------ */

static int add_wave(cup_input *u, int j, const cup_wave *w, const nl_circuit *c, int e, char *errmsg) {
  char lib[CUP_ERRMSG_LEN];
  int st = cup_input_add(u, j, w, lib);
  return st ? nl_fail(c, e, errmsg, st, "%s", lib) : CUP_OK;
}

/* Parameter k of a SIN or PULSE, or SPICE's default when it is omitted or 0
 * (as SPICE3 and ngspice read them: a 0 rise time is TSTEP, not a jump;
 * `jump` written for TR or TF is one). */
static double spice_param(const nl_source *s, int k, double dflt) {
  if (s->jumps >> k & 1) return 0;
  return s->np > k && s->p[k] != 0 ? s->p[k] : dflt;
}

/* SPICE's transient functions as exact waveform terms. */
static int source_terms(cup_netlist *nl, const nl_circuit *c, int e, char *errmsg) {
  const nl_source *s = &c->elem[e].src;
  int j = nl->evar[e];
  if (s->fn == NL_FN_DC) return add_wave(nl->u, j, &(cup_wave){.kind = CUP_WAVE_CONSTANT, .value = s->dc}, c, e, errmsg);
  if (s->fn == NL_FN_PWL)
    return add_wave(nl->u, j, &(cup_wave){.kind = CUP_WAVE_PWL, .npoints = s->npts, .t = s->t, .v = s->v}, c, e, errmsg);
  double tstep = nl->has_tran ? nl->tstep : NAN, tstop = nl->has_tran ? nl->tstop : NAN;
  if (s->fn == NL_FN_SIN) {
    double freq = spice_param(s, NL_SIN_FREQ, 1 / tstop), td = spice_param(s, NL_SIN_TD, 0);
    double theta = spice_param(s, NL_SIN_THETA, 0), phase = spice_param(s, NL_SIN_PHASE, 0) * (TWO_PI / 360);
    if (isnan(freq))
      return nl_fail(c, e, errmsg, CUP_ERR_PARSE, "SIN without FREQ needs .tran (FREQ defaults to 1/TSTOP)");
    int st = add_wave(nl->u, j, &(cup_wave){.kind = CUP_WAVE_CONSTANT, .value = s->p[NL_SIN_VO]}, c, e, errmsg);
    if (st) return st;
    if (td == 0 && theta == 0)
      return add_wave(nl->u, j, &(cup_wave){.kind = CUP_WAVE_SINE, .amplitude = s->p[NL_SIN_VA], .frequency = freq,
                                            .phase = phase}, c, e, errmsg);
    return add_wave(nl->u, j, &(cup_wave){.kind = CUP_WAVE_DAMPED_SINE, .amplitude = s->p[NL_SIN_VA],
                                          .frequency = freq, .phase = phase, .delay = td, .damping = theta},
                    c, e, errmsg);
  }
  cup_wave w = {.kind = CUP_WAVE_PULSE, .value = s->p[NL_PULSE_V1], .value2 = s->p[NL_PULSE_V2],
                .delay = spice_param(s, NL_PULSE_TD, 0), .rise = spice_param(s, NL_PULSE_TR, tstep),
                .fall = spice_param(s, NL_PULSE_TF, tstep), .width = spice_param(s, NL_PULSE_PW, tstop),
                .period = spice_param(s, NL_PULSE_PER, tstop)};
  if (isnan(w.rise) || isnan(w.fall) || isnan(w.width) || isnan(w.period))
    return nl_fail(c, e, errmsg, CUP_ERR_PARSE, "PULSE without TR, TF, PW or PER needs .tran (they default to "
                   "TSTEP and TSTOP)");
  /* PER omitted is TSTOP: a pulse longer than that (PULSE(0 10 1m): PW is
   * TSTOP too) starts no second period before TSTOP, in SPICE as here, so it
   * is one pulse, not a period shorter than rise + width + fall */
  if (spice_param(s, NL_PULSE_PER, 0) == 0 && w.period < w.rise + w.width + w.fall) w.period = 0;
  return add_wave(nl->u, j, &w, c, e, errmsg);
}

/* u, when not NULL: the same sources formed before (nl_formulate). */
static int build_input(cup_netlist *nl, const nl_circuit *c, const cup_input *u, char *errmsg) {
  if (nl->p == 0) return CUP_OK;
  if (u && u->p == nl->p)
    return input_copy(u, &nl->u) ? nl_fail(c, -1, errmsg, CUP_ERR_NOMEM, "out of memory") : CUP_OK;
  char lib[CUP_ERRMSG_LEN];
  int st = cup_input_create(&nl->u, nl->p, lib);
  if (st) return nl_fail(c, -1, errmsg, st, "%s", lib);
  for (int e = 0; e < c->nelem && !st; e++)
    if (c->elem[e].kind == NL_V || c->elem[e].kind == NL_I) st = source_terms(nl, c, e, errmsg);
  return st;
}

/* IC= on L and C; else a capacitor takes .ic v(a) - v(b), nodes without
 * .ic counting as 0. */
static void build_x0(cup_netlist *nl, const nl_circuit *c, double *vic) {
  for (int k = 0; k < c->nic; k++) vic[c->ic[k].node] = c->ic[k].v;
  vic[0] = 0;
  for (int e = 0; e < c->nelem; e++) {
    const nl_elem *el = &c->elem[e];
    if (el->kind == NL_L) nl->x0[nl->evar[e]] = el->has_ic ? el->ic : 0;
    if (el->kind == NL_C) nl->x0[nl->evar[e]] = el->has_ic ? el->ic : vic[el->a] - vic[el->b];
  }
}

/* ---- names ------------------------------------------------------------------------ */

/* "pre(name)" (by copies: snprintf's format walk was 1.3 k instructions a
 * name, twice for each switch configuration formed). */
static char *fmt_name(const char *pre, const char *name) {
  size_t lp = strlen(pre), ln = strlen(name);
  char *s = malloc(lp + ln + 3);
  if (!s) return NULL;
  memcpy(s, pre, lp);
  s[lp] = '(';
  memcpy(s + lp + 1, name, ln);
  s[lp + ln + 1] = ')';
  s[lp + ln + 2] = '\0';
  return s;
}

int nl_copy_probes(cup_netlist *nl, const nl_circuit *c) {
  nl->probe_all = c->probe_all;
  if (c->nprobe && !(nl->probe_text = calloc((size_t)c->nprobe, sizeof(char *)))) return CUP_ERR_NOMEM;
  for (int k = 0; k < c->nprobe; k++, nl->nprobe++)
    if (!(nl->probe_text[k] = strdup(c->probe[k].text))) return CUP_ERR_NOMEM;
  return CUP_OK;
}

static int copy_circuit(cup_netlist *nl, const nl_circuit *c) {
  nl->nnodes = c->nnodes;
  nl->nelem = c->nelem;
  nl->has_tran = c->has_tran;
  nl->tstep = c->tstep;
  nl->tstop = c->tstop;
  nl->tstart = c->tstart;
  nl->tmax = c->tmax;
  nl->reltol = c->reltol;
  nl->abstol = c->abstol;
  nl->vntol = c->vntol;
  nl->chgtol = c->chgtol;
  nl->steady = c->steady;
  nl->steady_period = c->steady_period;
  /* a switch configuration's names are lent (each configuration formed in
   * the run copied some 30, a malloc and a free each) */
  int lend = c->names_lent > 0;
  nl->names_lent = c->names_lent;
  if (!(nl->file = lend ? c->file : strdup(c->file))) return CUP_ERR_NOMEM;
  /* (node in files' block: a calloc and a free less a switch configuration) */
  if (!(nl->files = calloc((size_t)c->nfiles + 1 + (size_t)c->nnodes, sizeof(char *)))) return CUP_ERR_NOMEM;
  for (int f = 0; f < c->nfiles; f++) {
    int seen = 0;
    for (int g = 0; g < nl->nfiles && !seen; g++) seen = !strcmp(nl->files[g], c->files[f]);
    if (!seen && !(nl->files[nl->nfiles++] = lend ? c->files[f] : strdup(c->files[f]))) return CUP_ERR_NOMEM;
  }
  nl->node = nl->files + c->nfiles + 1;
  nl->elem = malloc(sizeof(nl_elem) * ((size_t)c->nelem + 1));   /* (each one copied below) */
  if (!nl->elem) return CUP_ERR_NOMEM;
  static char ground[] = "0";
  for (int v = 0; v < c->nnodes; v++)
    if (!(nl->node[v] = lend ? (c->node[v] ? c->node[v] : ground) : strdup(c->node[v] ? c->node[v] : "0")))
      return CUP_ERR_NOMEM;
  if (nl_copy_probes(nl, c)) return CUP_ERR_NOMEM;
  for (int e = 0; e < c->nelem; e++) {
    nl->elem[e] = c->elem[e];
    memset(&nl->elem[e].src, 0, sizeof nl->elem[e].src);
    if (!(nl->elem[e].name = e < c->names_lent ? c->elem[e].name : strdup(c->elem[e].name))) return CUP_ERR_NOMEM;
  }
  return CUP_OK;
}

static int name_variables(cup_netlist *nl, const nl_circuit *c) {
  /* (input_elem in state_name's block, row_fixed in row_name's: two callocs
   * and two frees less a switch configuration) */
  nl->state_name = calloc(1, sizeof(char *) * ((size_t)nl->n + 1) + sizeof(int) * ((size_t)nl->p + 1));
  nl->row_name = calloc(1, (sizeof(char *) + sizeof(int)) * ((size_t)nl->m + 1));
  nl->input_elem = nl->state_name ? (int *)(nl->state_name + nl->n + 1) : NULL;
  nl->row_fixed = nl->row_name ? (int *)(nl->row_name + nl->m + 1) : NULL;
  if (!nl->state_name || !nl->row_name) return CUP_ERR_NOMEM;
  for (int e = 0; e < c->nelem; e++) {
    const nl_elem *el = &c->elem[e];
    int j = nl->evar[e];
    if (el->kind == NL_L && !(nl->state_name[j] = fmt_name("i", el->name))) return CUP_ERR_NOMEM;
    if (el->kind == NL_C && !(nl->state_name[j] = fmt_name("v", el->name))) return CUP_ERR_NOMEM;
    if (el->kind == NL_D) {
      /* a switch configuration's: its element's name (lent, or its own), not a copy */
      if (!(nl->row_name[j] = nl->names_lent > 0 ? nl->elem[e].name : strdup(el->name))) return CUP_ERR_NOMEM;
      nl->row_fixed[j] = nl->eport[e] < nl->nv;
    }
    if (el->kind == NL_V || el->kind == NL_I) nl->input_elem[j] = e;
  }
  return CUP_OK;
}

int netlist_formulate(cup_netlist **out, const nl_circuit *c, char *errmsg) {
  return nl_formulate(out, c, NULL, errmsg);
}

int nl_formulate(cup_netlist **out, const nl_circuit *c, const cup_input *u, char *errmsg) {
  cup_netlist *nl = calloc(1, sizeof *nl);
  int st = nl ? copy_circuit(nl, c) : CUP_ERR_NOMEM;
  if (!st) st = nl_topology(nl, c, errmsg);
  else st = nl_fail(c, -1, errmsg, st, "out of memory");
  if (!st && !c->no_warning && (st = nl_diode_loops(nl, c))) st = nl_fail(c, -1, errmsg, st, "out of memory");
  if (!st && (st = name_variables(nl, c))) st = nl_fail(c, -1, errmsg, st, "out of memory");
  if (!st) st = nl_hybrid(nl, c, errmsg);
  if (!st) st = nl_controlled(nl, c, errmsg);
  if (!st) st = build_lcs(nl, c, errmsg);
  if (!st) st = build_input(nl, c, u, errmsg);
  /* the nodes' .ic voltages: on the stack for a small circuit (a calloc and a free less a switch configuration) */
  double vsmall[64], *vic = NULL;
  if (!st && (!(nl->x0 = calloc((size_t)nl->n + 1, sizeof(double))) ||
              !(vic = scratch_take(vsmall, sizeof vsmall, sizeof(double) * (size_t)c->nnodes, 1))))
    st = nl_fail(c, -1, errmsg, CUP_ERR_NOMEM, "out of memory");
  if (!st) build_x0(nl, c, vic);
  scratch_free(vic, vsmall);
  char msg[160];
  for (int k = 0; k < c->nprobe && !st; k++)
    if (nl_probe_check(nl, c->probe[k].text, msg, sizeof msg))
      st = fail_fmt(errmsg, CUP_ERR_PARSE, "%s:%d:%d: %s", c->file, c->probe[k].line, c->probe[k].col, msg);
  if (st) { cup_netlist_free(&nl); return st; }
  *out = nl;
  return CUP_OK;
}

/* The reader's description, freed (the reader and netlist_switch.c, which keeps one). */
void nl_circuit_free(nl_circuit *c) {
  if (!c) return;
  for (int k = 0; k < c->nnodes; k++) free(c->node[k]);
  free(c->node); free(c->node_line); free(c->node_col);
  for (int k = 0; k < c->nelem; k++) {
    free(c->elem[k].name);
    free(c->elem[k].src.t);
    free(c->elem[k].src.v);
  }
  free(c->elem);
  for (int k = 0; k < c->ncoup; k++) free(c->coup[k].name);
  free(c->coup);
  free(c->ic);
  for (int k = 0; k < c->nfiles; k++) free(c->files[k]);
  free(c->files);
  for (int k = 0; k < c->nprobe; k++) free(c->probe[k].text);
  free(c->probe);
  free(c->file);
  memset(c, 0, sizeof *c);
}

/* ---- public ------------------------------------------------------------------------ */

void cup_netlist_free(cup_netlist **p) {
  if (!p || !*p) return;
  cup_netlist *nl = *p;
  cup_lcs_free(&nl->L);
  free(nl->warning);
  cup_input_free(&nl->u);
  cup_input_free(&nl->u_written);
  free(nl->x0);
  int lent = nl->names_lent > 0;                 /* (the switched netlist's circuit's names) */
  for (int v = 0; nl->node && !lent && v < nl->nnodes; v++) free(nl->node[v]);   /* (the array in files' block) */
  for (int e = nl->names_lent; nl->elem && e < nl->nelem; e++) free(nl->elem[e].name);
  free(nl->elem);
  for (int j = 0; nl->state_name && j < nl->n; j++) free(nl->state_name[j]);
  for (int j = 0; nl->row_name && !lent && j < nl->m; j++) free(nl->row_name[j]);   /* (lent: the elements') */
  free(nl->state_name); free(nl->row_name);       /* (input_elem and row_fixed in their blocks) */
  free(nl->port);                                  /* (eport, evar, ctl_elem, parent, pport, depth, snode, psign) */
  free(nl->zmap); free(nl->coupled);             /* (prow in dense's block) */
  la_sparse_free(&nl->Pinv);
  if (nl->cm) {
    cholmod_free_factor(&nl->Lf, nl->cm);
    cholmod_free_sparse(&nl->K, nl->cm);
    cholmod_finish(nl->cm);
    free(nl->cm);
  }
  la_sparse_free(&nl->H);
  for (int k = 0; nl->sig_name && k < nl->nsig; k++) free(nl->sig_name[k]);
  free(nl->sig_name); free(nl->sig_val);          /* (sig_ptr, sig_idx in their blocks) */
  free(nl->dense); free(nl->ucache); free(nl->smap_rows);   /* (vals in dense's block) */
  for (int k = 0; k < nl->nprobe; k++) free(nl->probe_text[k]);
  free(nl->probe_text);
  for (int f = 0; nl->files && !lent && f < nl->nfiles; f++) free(nl->files[f]);
  free(nl->files);
  if (!lent) free(nl->file);
  free(nl->source);
  if (nl->hooks) nl->hooks->free(&nl->sw);
  nl_raw_free(nl);
  free(nl->zrow); free(nl->Lam);
  free(nl);
  *p = NULL;
}

int nl_input_origin(cup_netlist *nl, double t0, char *errmsg) {
  char lib[CUP_ERRMSG_LEN];
  int st = t0 == nl->t0 ? CUP_OK : input_origin(&nl->u, &nl->u_written, t0, lib);
  if (st) return fail_fmt(errmsg, st, "%s: the sources from t0 = %.17g: %s", nl->file, t0, lib);
  if (nl->ucache) memset(nl->ucache, 0, sizeof(double) * (3 * (size_t)nl->ucache_n + 2 + (size_t)nl->p));   /* other sources now */
  nl->u_hi = -INFINITY;
  nl->t0 = t0;
  return CUP_OK;
}

int cup_netlist_set_time_origin(cup_netlist *nl, double t0, char *errmsg) {
  if (!nl || !(t0 >= 0) || !isfinite(t0))
    return fail_fmt(errmsg, CUP_ERR_ARG, "time origin: no netlist, or t0 = %g not finite and >= 0", t0);
  return nl->hooks ? nl->hooks->origin(nl, t0, errmsg) : nl_input_origin(nl, t0, errmsg);
}

const cup_lcs *cup_netlist_lcs(const cup_netlist *nl) { return nl ? nl->L : NULL; }
const cup_input *cup_netlist_input(const cup_netlist *nl) { return nl ? nl->u : NULL; }
const double *cup_netlist_x0(const cup_netlist *nl) { return nl ? nl->x0 : NULL; }

int cup_netlist_tran_window(const cup_netlist *nl, double *tstart, double *tmax) {
  if (!nl || !nl->has_tran) return 0;
  if (tstart) *tstart = nl->tstart;
  if (tmax) *tmax = nl->tmax;
  return 1;
}

int cup_netlist_tolerances(const cup_netlist *nl, double *reltol, double *abstol, double *vntol, double *chgtol) {
  const double none = NAN;
  if (reltol) *reltol = nl ? nl->reltol : none;
  if (abstol) *abstol = nl ? nl->abstol : none;
  if (vntol) *vntol = nl ? nl->vntol : none;
  if (chgtol) *chgtol = nl ? nl->chgtol : none;
  return nl && (!isnan(nl->reltol) || !isnan(nl->abstol) || !isnan(nl->vntol) || !isnan(nl->chgtol));
}

int cup_netlist_tran(const cup_netlist *nl, double *tstep, double *tstop) {
  if (!nl || !nl->has_tran) return 0;
  if (tstep) *tstep = nl->tstep;
  if (tstop) *tstop = nl->tstop;
  return 1;
}

const char *cup_netlist_state_name(const cup_netlist *nl, int j) {
  return nl && j >= 0 && j < nl->n ? nl->state_name[j] : NULL;
}
const char *cup_netlist_source(const cup_netlist *nl) { return nl ? nl->source : NULL; }
const char *cup_netlist_warning(const cup_netlist *nl) { return nl && nl->warning && nl->warning[0] ? nl->warning : NULL; }

const char *cup_netlist_row_name(const cup_netlist *nl, int i) {
  return nl && i >= 0 && i < (nl->zrow ? nl->mr : nl->m) ? nl->row_name[i] : NULL;
}
const char *cup_netlist_input_name(const cup_netlist *nl, int j) {
  return nl && j >= 0 && j < nl->p ? nl->elem[nl->input_elem[j]].name : NULL;
}
int cup_netlist_row_fixed(const cup_netlist *nl, int i) {
  return nl && i >= 0 && i < (nl->zrow ? nl->mr : nl->m) ? nl->row_fixed[i] : 0;
}

int cup_netlist_file_count(const cup_netlist *nl) { return nl ? nl->nfiles : 0; }
const char *cup_netlist_file(const cup_netlist *nl, int k) {
  return nl && k >= 0 && k < nl->nfiles ? nl->files[k] : NULL;
}

int cup_netlist_steady_state(const cup_netlist *nl, double *period) {
  if (period) *period = nl ? nl->steady_period : 0;
  return nl && nl->steady;
}

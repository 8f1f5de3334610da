/* adaptive_record — a netlist's signals at the samples inside a step
 * (record.h, adaptive_impl.h's rec): there the mode md is fixed and the
 * sample is its flow state y, so x = X y, u = U w (w: y's input states)
 * and zeta_J = Lc + L y; a signal map over (x, u, zeta) composed with
 * them once per mode is one sparse row a signal over y (plus u(t) itself
 * for a component the exosystem leaves out: a switch's gate, a supply a
 * configuration disconnects, evaluated at the record). In place of
 * cup_integrator_zeta, the input's evaluation (a sine's libm call) and
 * cup_netlist_signals at each sample (about 400 instructions a sample on
 * the precision rectifier). The sums differ from those by rounding: x,
 * u and zeta are not rounded on their own first. */
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "adaptive.h"
#include "adaptive_impl.h"
#include "model/signal_map.h"

/* Room for ns signals in every entry (emptied); 0 or CUP_ERR_NOMEM. */
static int room(adaptive_ws *A, int ns) {
  int na = A->na, p = A->p, ne = AD_MODES + 1;
  size_t ints = (size_t)ns + 1 + (size_t)ns * na + p, dbls = (size_t)ns * na + ns + (size_t)ns * p;
  free(A->rec_block);
  A->rec_ns = 0;
  A->rec_last = NULL;
  A->rec_block = malloc((size_t)ne * (ints * sizeof(int) + dbls * sizeof(double)) + ((size_t)na + p) * sizeof(double));
  if (!A->rec_block) return CUP_ERR_NOMEM;
  double *d = A->rec_block;
  A->rec_acc = d;
  A->rec_u = d + na;
  d += na + p;
  for (int k = 0; k < ne; k++) {
    struct ad_rec *e = &A->rec[k];
    e->X = NULL;
    e->rx = d;
    e->rc = d + (size_t)ns * na;
    e->ux = e->rc + ns;
    d += dbls;
  }
  int *i = (int *)d;
  for (int k = 0; k < ne; k++) {
    A->rec[k].rp = i;
    A->rec[k].rj = i + ns + 1;
    A->rec[k].uc = A->rec[k].rj + (size_t)ns * na;
    i += ints;
  }
  A->rec_ns = ns;
  return CUP_OK;
}

/* S's row k over (x, u, zeta) composed with md's rows into acc (na) and
 * its constant; an input component U leaves out (live_terms: no term of
 * it in E or G) onto e's list, its coefficient in row k of ux. */
static void compose_row(const adaptive_ws *A, const ad_mode *md, const double *row, int k, struct ad_rec *e,
                        double *acc, double *c) {
  int n = A->n, p = A->p, m = A->m, na = A->na, nw = A->nw;
  memset(acc, 0, sizeof(double) * (size_t)na);
  *c = 0;
  for (int q = 0; q < n; q++)
    if (row[q] != 0)
      for (int j = 0; j < na; j++) acc[j] += row[q] * md->X[(size_t)q * na + j];
  for (int q = 0; q < p; q++) {
    double s = row[n + q];
    if (s == 0) continue;
    int held = 0;
    for (int j = 0; j < nw; j++) {
      double uq = A->U[q + (size_t)j * p];
      if (uq != 0) { acc[n + j] += s * uq; held = 1; }
    }
    if (held) continue;
    int j = 0;
    while (j < e->nu && e->uc[j] != q) j++;
    if (j == e->nu) e->uc[e->nu++] = q;
    e->ux[(size_t)k * p + j] = s;
  }
  for (int r = 0; r < m; r++) {
    double s = row[n + p + r];
    if (s == 0 || !md->is_zeta[r]) continue;     /* (zeta_i = 0 off the active set) */
    for (int j = 0; j < na; j++) acc[j] += s * md->L[(size_t)r * na + j];
    *c += s * md->Lc[r];
  }
}

static void compose(adaptive_ws *A, const ad_mode *md, const signal_map *S, struct ad_rec *e) {
  int na = A->na, nc = S->n + S->p + S->m, nz = 0;
  A->rk_rec = NULL;                              /* (e's rows change) */
  e->X = md->X;
  e->mask = md->mask;
  e->key = S->key;
  e->ok = !A->callback && S->n == A->n && S->p == A->p && S->m == A->m && nl_same_input(S->u, A->u);
  e->nu = 0;
  memset(e->ux, 0, sizeof(double) * (size_t)S->ns * (size_t)A->p);
  for (int k = 0; e->ok && k < S->ns; k++) {
    double *acc = A->rec_acc;
    e->rp[k] = nz;
    compose_row(A, md, S->rows + (size_t)k * nc, k, e, acc, &e->rc[k]);
    for (int j = 0; j < na; j++)
      if (acc[j] != 0) { e->rj[nz] = j; e->rx[nz++] = acc[j]; }
  }
  e->rp[S->ns] = nz;
}

/* The entry of md's buffers, composed for md and S (NULL: not composable):
 * past ad_rec_of's look at the last one. */
const struct ad_rec *ad_rec_entry(adaptive_ws *A, const ad_mode *md, const signal_map *S) {
  struct ad_rec *e;
  if ((A->rec_ns != S->ns || !A->rec_block) && room(A, S->ns)) return NULL;   /* (the entries: room's) */
  struct ad_rec *free_e = NULL;
  for (e = A->rec; e < A->rec + AD_MODES + 1; e++) {
    if (e->X == md->X) break;
    if (!e->X && !free_e) free_e = e;
  }
  if (e == A->rec + AD_MODES + 1) e = free_e;    /* (never NULL: a mode's buffers are one of AD_MODES + 1) */
  if (!e) return NULL;
  if (e->X != md->X || e->mask != md->mask || e->key != S->key) compose(A, md, S, e);
  A->rec_last = e;
  return e->ok ? e : NULL;
}

/* The components uc of u(t) at the record's time, added to each row:
 * cup_input_eval's sums, as cup_netlist_signals takes them. */
int ad_rec_inputs(adaptive_ws *A, const struct ad_rec *e, int ns, double *out) {
  if (cup_input_eval(A->u, A->zt, A->rec_u)) return 0;
  int p = A->p;
  for (int k = 0; k < ns; k++) {
    const double *c = e->ux + (size_t)k * p;
    double acc = 0;
    for (int j = 0; j < e->nu; j++) acc += c[j] * A->rec_u[e->uc[j]];
    out[k] += acc;
  }
  return 1;
}

/* (Out of line: a call and a store inlined into dense_loop moved the
 * dense samples' code, 3 instructions a sample more.) */
__attribute__((noinline)) const signal_map *ad_put_map_ask(adaptive_ws *A) {
  return A->put_map ? A->put_map : (A->put_map = nl_signal_map(A->put_nl));
}

int adaptive_set_put(adaptive_ws *A, cup_netlist *nl, record_put_fn put) {
  free(A->put_block);
  A->put_block = NULL;
  A->put = NULL;
  A->put_nl = NULL;
  A->put_map = NULL;
  A->put_ns = 0;
  if (!put || !nl) return 1;
  int ns = cup_netlist_signal_count(nl), n = A->n, na = A->na;
  size_t b = AD_BATCH, slots = (b + 1) * (size_t)na;
  double *d = malloc(sizeof(double) * (b * (size_t)(1 + n + ns + 1) + 2 * slots + 2 * (size_t)ns * (na + 1)));
  if (!d) return CUP_ERR_NOMEM;
  A->put_block = d;
  A->bt = d;
  A->bx = A->bt + b;
  A->bs = A->bx + b * (size_t)n;
  A->best = A->bs + b * (size_t)ns;
  A->by = A->best + b;
  A->be = A->by + slots;
  A->bk = A->be + slots;
  A->bkc = A->bk + (size_t)ns * na;
  A->rk = A->bkc + ns;
  A->rkc = A->rk + (size_t)ns * na;
  A->rk_rec = NULL;
  A->put = put;
  A->put_nl = nl;
  A->put_ns = ns;
  return 1;
}

void adaptive_put_on(adaptive_ws *A, int on) { A->put_off = !on; }

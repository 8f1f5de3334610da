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

/* Signals of y by the dense rows ad_dense_rows made (A->rk, rkc: e's),
 * na and ns constants here, y's in registers: each from its constant,
 * every term in column order, zeros too, as ad_batch_signals' sums
 * (ad_rec_rows' bit for bit: a zero's term is +-0, y finite). */
static inline __attribute__((always_inline)) void signals_of(int na, int ns, const adaptive_ws *A, const double *y,
                                                             double *sig) {
  const double *K = A->rk, *kc = A->rkc;
  double yv[4];
  for (int j = 0; j < na; j++) yv[j] = y[j];
  for (int k = 0; k < ns; k++, K += na) {
    double acc = kc[k];
    for (int j = 0; j < na; j++) acc += K[j] * yv[j];
    sig[k] = acc;
  }
}

/* signals_of for na <= 4 (and ns <= 4: unrolled; a loop over the rows was
 * 20 instructions of the full bridge's 3). */
static void row_signals(const adaptive_ws *A, int na, int ns, double *sig) {
  const double *y = A->zy;
  switch (ns <= 4 ? na * 8 + ns : na * 8) {
#define SIG(NA)                                                                                             \
    case NA * 8 + 1: signals_of(NA, 1, A, y, sig); return;                                                  \
    case NA * 8 + 2: signals_of(NA, 2, A, y, sig); return;                                                  \
    case NA * 8 + 3: signals_of(NA, 3, A, y, sig); return;                                                  \
    case NA * 8 + 4: signals_of(NA, 4, A, y, sig); return;                                                  \
    case NA * 8: signals_of(NA, ns, A, y, sig); return;
    SIG(1) SIG(2) SIG(3) SIG(4)
#undef SIG
  }
}

/* ad_record_y's y (into A->zw and A->zy) for an input of constants alone
 * (their states the same at any time: ad_inputs_on's copy of A->wc) with
 * n and na constants here: ad_lift's sums (ad_lift_sums). (A step's end on the full bridge:
 * the calls of ad_record_y, ad_inputs_on and ad_lift were 110 instructions
 * a row, their sums about 20.) */
static inline __attribute__((always_inline)) void row_const(int n, int na, adaptive_ws *A, const ad_mode *md) {
  int nw = na - n;
  double *w = A->zw, *y = A->zy;
  if (A->one >= 0) w[A->one] = 1;
  for (int c = 0; c < A->nwu; c++) w[c] = A->wc[c];
  ad_lift_sums(n, nw, md->KU, A->x, w, y);
  for (int c = 0; c < nw; c++) y[n + c] = w[c];
}

/* (Out of line: a call and a store inlined into dense_loop moved the
 * dense samples' code, 3 instructions a sample more.) */
__attribute__((noinline)) const signal_map *ad_put_map_ask(adaptive_ws *A) {
  return A->put_map ? A->put_map : (A->put_map = nl_signal_map(A->put_nl));
}

int ad_put_row(adaptive_ws *A, ad_run *R, const double *x) {
  const signal_map *S = ad_put_map(A);
  const ad_mode *md = A->zmd;
  if (!S || S->ns != A->put_ns) return -1;
  const struct ad_rec *e = ad_rec_of(A, md, S);
  if (!e) return -1;
  double *sig = A->bs, t = R->t;
  int ns = S->ns, n = A->n, na = A->na;
  if (na <= 4 && !e->nu) {                       /* (a converter's few states) */
    if (A->rk_rec != e) {
      ad_dense_rows(e, ns, na, A->rk, A->rkc);
      A->rk_rec = e;
    }
    if (!A->nwu || A->w_const) {
      switch (na * 8 + n) {
#define ROW(NA, N) case NA * 8 + N: row_const(N, NA, A, md); break;
        ROW(1, 1) ROW(2, 1) ROW(2, 2) ROW(3, 1) ROW(3, 2) ROW(3, 3) ROW(4, 1) ROW(4, 2) ROW(4, 3) ROW(4, 4)
#undef ROW
      }
    } else if (ad_record_y(A, md)) {
      return -1;                                 /* (a failed input: the sink's, as before) */
    }
    row_signals(A, na, ns, sig);
  } else {
    if (ad_record_y(A, md)) return -1;
    ad_rec_rows(e, ns, A->zy, sig, 1);
    if (e->nu && !ad_rec_inputs(A, e, ns, sig)) return -1;
  }
  return A->put(R->sink_ctx, R->steps, 1, &t, x, sig, 1) != 1;
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

/* adaptive_put — a step's end to integrator_set_put's put with its
 * signals (record.h; offer_x in adaptive_run.c): what catchup-run's sink
 * does with integrator_record's (the entry adaptive_record.c composed, the
 * y ad_record_y gives), the same sums, without the sink's calls a row
 * (nl_signal_map, integrator_record, the scheme's record, switched.c's
 * sw_record: about 100 instructions of the full bridge's 417 a row). With
 * an input of constants and na <= 4, y and the signals unrolled. Allocates
 * nothing. */
#include "catchup.h"
#include "adaptive.h"
#include "adaptive_impl.h"
#include "model/signal_map.h"

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

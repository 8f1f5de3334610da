/* input — u(t) in R^p as sums of built-in waveforms with exact integrals,
 * or a user callback integrated by adaptive GSL quadrature. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_integration.h>
#include "catchup.h"
#include "input_impl.h"
#include "util/linalg.h"

#define TWO_PI 6.283185307179586476925286766559

int cup_input_create(cup_input **out, int p, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "input: output pointer is NULL");
  *out = NULL;
  if (p < 0) return fail_fmt(errmsg, CUP_ERR_DIM, "input: dimension %d < 0", p);
  cup_input *u = calloc(1, sizeof *u);
  if (!u) return fail_fmt(errmsg, CUP_ERR_NOMEM, "input: out of memory");
  u->p = p;
  *out = u;
  return CUP_OK;
}

void cup_input_free(cup_input **up) {
  if (!up || !*up) return;
  cup_input *u = *up;
  for (int k = 0; k < u->nterms; k++) { free(u->terms[k].t); free(u->terms[k].v); }
  free(u->terms);
  free(u);
  *up = NULL;
}

int cup_input_add(cup_input *u, int j, const cup_wave *w, char *errmsg) {
  if (!u || !w) return fail_fmt(errmsg, CUP_ERR_ARG, "input: NULL argument");
  if (j < 0 || j >= u->p)
    return fail_fmt(errmsg, CUP_ERR_DIM, "input: component %d outside [0, %d)", j, u->p);
  input_term t = {0};
  t.comp = j;
  t.kind = w->kind;
  switch (w->kind) {
    case CUP_WAVE_CONSTANT:
      if (!isfinite(w->value)) return fail_fmt(errmsg, CUP_ERR_NONFINITE, "input: constant value is %g", w->value);
      t.value = w->value;
      break;
    case CUP_WAVE_SINE:
    case CUP_WAVE_SQUARE:
      if (!isfinite(w->amplitude) || !isfinite(w->frequency) || !isfinite(w->phase))
        return fail_fmt(errmsg, CUP_ERR_NONFINITE, "input: amplitude %g, frequency %g, phase %g must be finite",
                        w->amplitude, w->frequency, w->phase);
      if (w->frequency < 0)
        return fail_fmt(errmsg, CUP_ERR_ARG, "input: frequency %g must be >= 0", w->frequency);
      if (!isfinite(TWO_PI * w->frequency))
        return fail_fmt(errmsg, CUP_ERR_NONFINITE, "input: frequency %g overflows (2 pi frequency is not finite)",
                        w->frequency);
      t.amp = w->amplitude;
      t.omega = TWO_PI * w->frequency;
      t.phase = w->phase;
      break;
    case CUP_WAVE_PWL:
      if (w->npoints < 1 || !w->t || !w->v)
        return fail_fmt(errmsg, CUP_ERR_ARG, "input: a piecewise-linear table needs at least one point");
      for (int k = 0; k < w->npoints; k++) {
        if (!isfinite(w->t[k]) || !isfinite(w->v[k]))
          return fail_fmt(errmsg, CUP_ERR_NONFINITE, "input: table point %d is (%g, %g)", k, w->t[k], w->v[k]);
        if (k > 0 && !(w->t[k] > w->t[k - 1]))
          return fail_fmt(errmsg, CUP_ERR_ARG, "input: table times must increase (point %d: %g after %g)",
                          k, w->t[k], w->t[k - 1]);
      }
      t.np = w->npoints;
      t.t = malloc(sizeof(double) * (size_t)t.np);
      t.v = malloc(sizeof(double) * (size_t)t.np);
      if (!t.t || !t.v) { free(t.t); free(t.v); return fail_fmt(errmsg, CUP_ERR_NOMEM, "input: out of memory"); }
      memcpy(t.t, w->t, sizeof(double) * (size_t)t.np);
      memcpy(t.v, w->v, sizeof(double) * (size_t)t.np);
      break;
    case CUP_WAVE_PULSE:
    case CUP_WAVE_DAMPED_SINE: {
      int st = spice_term_init(&t, w, errmsg);
      if (st) return st;
      break;
    }
    default:
      return fail_fmt(errmsg, CUP_ERR_ARG, "input: unknown waveform kind %d", (int)w->kind);
  }
  input_term *nt = realloc(u->terms, sizeof(input_term) * ((size_t)u->nterms + 1));
  if (!nt) { free(t.t); free(t.v); return fail_fmt(errmsg, CUP_ERR_NOMEM, "input: out of memory"); }
  u->terms = nt;
  u->terms[u->nterms++] = t;
  return CUP_OK;
}

/* A copy of term t read from t0 on: the same waveform at t0 + s for s >= 0,
 * for any t0 >= 0 (cup_input_steady_phase gives the one from which the term
 * repeats): a phase advanced by omega t0 (mod 2 pi), a PULSE's delay moved
 * back by t0 (into (-period, 0] once spent), a SIN's delay spent into its
 * phase and a damped one's decay into its amplitude, knots moved by -t0, a
 * PWL past its last knot and a single pulse past its end constants. */
static int term_shift(const input_term *t, double t0, input_term *out) {
  *out = *t;
  out->t = out->v = NULL;
  switch (t->kind) {
    case CUP_WAVE_CONSTANT: return CUP_OK;
    case CUP_WAVE_SINE:
    case CUP_WAVE_SQUARE:
      if (t->omega > 0) out->phase = t->phase + fmod(t->omega * t0, TWO_PI);
      return CUP_OK;
    case CUP_WAVE_PWL:
      if (t0 >= t->t[t->np - 1]) {
        *out = (input_term){.comp = t->comp, .kind = CUP_WAVE_CONSTANT, .value = t->v[t->np - 1]};
        return CUP_OK;
      }
      out->t = malloc(sizeof(double) * (size_t)t->np);
      out->v = malloc(sizeof(double) * (size_t)t->np);
      if (!out->t || !out->v) { free(out->t); free(out->v); return CUP_ERR_NOMEM; }
      for (int k = 0; k < t->np; k++) out->t[k] = t->t[k] - t0, out->v[k] = t->v[k];
      return CUP_OK;
    case CUP_WAVE_PULSE: {
      /* a delay at or below 0 leaves v periodic from t = 0 (pulse_value's s >= 0): t0 past the delay
       * is delay - t0 less whole periods, in (-period, 0]; before it, the delay left */
      double P = t->period, d = t->delay - t0;
      if (!(P > 0) && d + t->rise + t->width + t->fall <= 0) {
        *out = (input_term){.comp = t->comp, .kind = CUP_WAVE_CONSTANT, .value = t->value};
        return CUP_OK;
      }
      if (P > 0 && d < 0) {
        d += P * floor(-d / P);
        if (d > 0) d -= P;
      }
      out->delay = d;
      return CUP_OK;
    }
    case CUP_WAVE_DAMPED_SINE:
      if (t0 <= t->delay) { out->delay = t->delay - t0; return CUP_OK; }
      out->delay = 0;
      out->phase = t->phase + fmod(t->omega * (t0 - t->delay), TWO_PI);
      out->amp = t->amp * exp(-t->damping * (t0 - t->delay));   /* the decay spent by t0 (1 undamped) */
      return CUP_OK;
  }
  return CUP_ERR_ARG;
}

int input_shift(const cup_input *u, double t0, cup_input **out, char *errmsg) {
  if (!out) return fail_fmt(errmsg, CUP_ERR_ARG, "input shift: output pointer is NULL");
  *out = NULL;
  if (!u || !(t0 >= 0) || !isfinite(t0))
    return fail_fmt(errmsg, CUP_ERR_ARG, "input shift: no input, or t0 = %g not finite and >= 0", t0);
  if (u->fn && t0 != 0)
    return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED, "input shift: a callback input cannot be read from t0 = %g", t0);
  int st = cup_input_create(out, u->p, errmsg);
  if (st) return st;
  cup_input *v = *out;
  v->fn = u->fn; v->ctx = u->ctx; v->abs_tol = u->abs_tol; v->rel_tol = u->rel_tol;
  v->terms = calloc((size_t)u->nterms + 1, sizeof(input_term));
  for (int k = 0; v->terms && k < u->nterms && !st; k++)
    if (!(st = term_shift(&u->terms[k], t0, &v->terms[k]))) v->nterms = k + 1;
  if (!v->terms || st) {
    cup_input_free(out);
    return fail_fmt(errmsg, st == CUP_ERR_ARG ? st : CUP_ERR_NOMEM, "input shift: %s",
                    st == CUP_ERR_ARG ? "unknown waveform" : "out of memory");
  }
  return CUP_OK;
}

int input_origin(cup_input **u, cup_input **written, double t0, char *errmsg) {
  const cup_input *w = *written ? *written : *u;
  cup_input *v = NULL;
  if (!*u) return CUP_OK;
  if (t0 != 0) {
    int st = input_shift(w, t0, &v, errmsg);
    if (st) return st;
  }
  if (*written) cup_input_free(u);
  else *written = *u;
  *u = v ? v : *written;
  if (!v) *written = NULL;
  return CUP_OK;
}

int input_copy(const cup_input *u, cup_input **out) {
  cup_input *v = *out = calloc(1, sizeof *v);
  if (!v) return CUP_ERR_NOMEM;
  *v = *u;
  v->nterms = 0;
  v->terms = u->nterms ? malloc(sizeof(input_term) * (size_t)u->nterms) : NULL;   /* (NULL with none, as cup_input_add's) */
  for (int k = 0; k < u->nterms && v->terms; k++) {
    input_term t = u->terms[k];
    if (t.np > 0) {
      t.t = malloc(sizeof(double) * (size_t)t.np);
      t.v = malloc(sizeof(double) * (size_t)t.np);
      if (!t.t || !t.v) { free(t.t); free(t.v); break; }
      memcpy(t.t, u->terms[k].t, sizeof(double) * (size_t)t.np);
      memcpy(t.v, u->terms[k].v, sizeof(double) * (size_t)t.np);
    }
    v->terms[v->nterms++] = t;
  }
  if (v->nterms == u->nterms) return CUP_OK;
  cup_input_free(out);
  return CUP_ERR_NOMEM;
}

int cup_input_set_callback(cup_input *u, cup_input_fn fn, void *ctx, double abs_tol, double rel_tol) {
  if (!u || !fn) return CUP_ERR_ARG;
  if (!(abs_tol >= 0) || !(rel_tol >= 0) || (abs_tol == 0 && rel_tol == 0)) return CUP_ERR_ARG;
  u->fn = fn;
  u->ctx = ctx;
  u->abs_tol = abs_tol;
  u->rel_tol = rel_tol;
  return CUP_OK;
}

int cup_input_dim(const cup_input *u) { return u ? u->p : 0; }

int cup_input_is_constant(const cup_input *u) {
  if (!u) return 1;
  if (u->fn) return 0;
  for (int k = 0; k < u->nterms; k++) {
    const input_term *t = &u->terms[k];
    if ((t->kind == CUP_WAVE_SINE || t->kind == CUP_WAVE_SQUARE) && t->amp != 0 && t->omega != 0) return 0;
    if (t->kind == CUP_WAVE_PWL && t->np > 1) return 0;
    if ((t->kind == CUP_WAVE_PULSE || t->kind == CUP_WAVE_DAMPED_SINE) && !spice_term_constant(t)) return 0;
  }
  return 1;
}

/* Index of the PWL segment [t_k, t_{k+1}] holding t (binary search). */
static int pwl_segment(const input_term *w, double t) {
  int lo = 0, hi = w->np - 1;
  while (hi - lo > 1) {
    int mid = (lo + hi) / 2;
    if (w->t[mid] <= t) lo = mid; else hi = mid;
  }
  return lo;
}

static double pwl_value(const input_term *w, double t) {
  if (t <= w->t[0]) return w->v[0];
  if (t >= w->t[w->np - 1]) return w->v[w->np - 1];
  int k = pwl_segment(w, t);
  double s = (t - w->t[k]) / (w->t[k + 1] - w->t[k]);
  return w->v[k] + s * (w->v[k + 1] - w->v[k]);
}

/* Exact integral of the PWL table over [a, b] (a <= b): constant tails plus
 * trapezoids of the linear pieces, each clipped to [a, b]. */
static double pwl_integral(const input_term *w, double a, double b) {
  double t0 = w->t[0], t1 = w->t[w->np - 1], sum = 0;
  if (a < t0) { double e = fmin(b, t0); sum += w->v[0] * (e - a); a = e; }
  if (b > t1) { double s = fmax(a, t1); sum += w->v[w->np - 1] * (b - s); b = s; }
  if (!(b > a)) return sum;
  for (int k = pwl_segment(w, a); k < w->np - 1 && w->t[k] < b; k++) {
    double lo = fmax(a, w->t[k]), hi = fmin(b, w->t[k + 1]);
    if (!(hi > lo)) continue;
    sum += 0.5 * (pwl_value(w, lo) + pwl_value(w, hi)) * (hi - lo);
  }
  return sum;
}

double input_term_value(const input_term *w, double t) {
  switch (w->kind) {
    case CUP_WAVE_CONSTANT: return w->value;
    case CUP_WAVE_SINE: return input_sine_value(w, t);
    case CUP_WAVE_SQUARE: return w->amp * input_sign_sin_q(input_square_q(w, t));
    case CUP_WAVE_PWL: return pwl_value(w, t);
    case CUP_WAVE_PULSE: case CUP_WAVE_DAMPED_SINE: return spice_term_value(w, t);
  }
  return 0;
}

double input_term_piece(const input_term *w, double t, double *hi) {
  if (w->kind == CUP_WAVE_CONSTANT) {
    *hi = INFINITY;
    return w->value;
  }
  if (input_jump_pulse(w)) return spice_jump_pulse(w, t, hi);
  *hi = t;
  return input_term_value(w, t);
}

double input_term_integral(const input_term *w, double a, double b) {
  switch (w->kind) {
    case CUP_WAVE_CONSTANT: return w->value * (b - a);
    case CUP_WAVE_SINE:
      if (w->omega == 0) return w->amp * sin(w->phase) * (b - a);
      /* cos(wa+p) - cos(wb+p) as a product: no cancellation for small b - a */
      return 2 * w->amp / w->omega * sin(0.5 * w->omega * (a + b) + w->phase) *
             sin(0.5 * w->omega * (b - a));
    case CUP_WAVE_SQUARE:
      if (w->omega == 0) return w->amp * input_sign_sin_q(w->phase / M_PI) * (b - a);
      return w->amp * M_PI / w->omega * (input_sign_sin_q_integral(input_square_q(w, b)) -
                                         input_sign_sin_q_integral(input_square_q(w, a)));
    case CUP_WAVE_PWL: return pwl_integral(w, a, b);
    case CUP_WAVE_PULSE: case CUP_WAVE_DAMPED_SINE: return spice_term_integral(w, a, b);
  }
  return 0;
}

int cup_input_eval(const cup_input *u, double t, double *out) {
  if (!u || !out) return CUP_ERR_ARG;
  if (u->fn) {
    if (u->fn(t, out, u->ctx) != 0) return CUP_ERR_CALLBACK;
    for (int j = 0; j < u->p; j++) if (!isfinite(out[j])) return CUP_ERR_CALLBACK;
    return CUP_OK;
  }
  for (int j = 0; j < u->p; j++) out[j] = 0;
  for (int k = 0; k < u->nterms; k++) out[u->terms[k].comp] += input_term_value(&u->terms[k], t);
  return CUP_OK;
}

void input_eval_terms(const cup_input *u, const int *terms, int n, double t, double *out) {
  for (int j = 0; j < u->p; j++) out[j] = 0;
  for (int q = 0; q < n; q++) out[u->terms[terms[q]].comp] += input_term_value(&u->terms[terms[q]], t);
}

/* ---- exosystem ------------------------------------------------------------------ */

int input_term_gen_states(const input_term *t) {
  return t->kind == CUP_WAVE_SINE || t->kind == CUP_WAVE_PWL || t->kind == CUP_WAVE_PULSE ||
         t->kind == CUP_WAVE_DAMPED_SINE ? 2 : 1;
}

/* Before its delay a damped sine is constant, which its generator (a damped
 * rotation) cannot hold. */
int input_gen_check(const cup_input *u, const char *scheme, char *errmsg) {
  for (int k = 0; u && !u->fn && k < u->nterms; k++)
    if (u->terms[k].kind == CUP_WAVE_DAMPED_SINE && u->terms[k].delay > 0)
      return fail_fmt(errmsg, CUP_ERR_UNSUPPORTED, "%s scheme: a damped sine with a delay (input "
                      "term %d) is not supported; use the theta or implicit scheme", scheme, k);
  return CUP_OK;
}

int input_gen_dim(const cup_input *u, const input_gen_rot *rot, int *first_state) {
  int nw = 0;
  if (!u || u->fn) return 0;
  for (int k = 0; k < u->nterms; k++) {
    if (rot && rot[k].base >= 0) {
      if (first_state) first_state[k] = first_state[rot[k].base];
      continue;
    }
    if (first_state) first_state[k] = nw;
    nw += input_term_gen_states(&u->terms[k]);
  }
  return nw;
}

void input_gen_dynamics(const cup_input *u, const input_gen_rot *rot, const int *first_state, double *W, int ld) {
  for (int k = 0; u && !u->fn && k < u->nterms; k++) {
    const input_term *t = &u->terms[k];
    int g = first_state[k];
    if (rot && rot[k].base >= 0) continue;        /* (its base's block) */
    if (t->kind == CUP_WAVE_SINE || t->kind == CUP_WAVE_DAMPED_SINE) {
      double d = t->kind == CUP_WAVE_DAMPED_SINE ? t->damping : 0;
      W[g + (size_t)(g + 1) * ld] = t->omega;     /* s' = om c - d s */
      W[(g + 1) + (size_t)g * ld] = -t->omega;    /* c' = -om s - d c */
      W[g + (size_t)g * ld] = W[(g + 1) + (size_t)(g + 1) * ld] = -d;
    } else if (t->kind == CUP_WAVE_PWL || t->kind == CUP_WAVE_PULSE) {
      W[g + (size_t)(g + 1) * ld] = 1;             /* v' = slope */
    }
  }
}

void input_gen_output(const cup_input *u, const input_gen_rot *rot, const int *first_state, double *U, int ld) {
  for (int k = 0; u && !u->fn && k < u->nterms; k++) {
    int q = u->terms[k].comp, g = first_state[k];
    if (rot && rot[k].base >= 0) {
      U[q + (size_t)g * ld] += rot[k].c;
      U[q + (size_t)(g + 1) * ld] += rot[k].s;
    } else {
      U[q + (size_t)g * ld] += 1;
    }
  }
}

/* Term t's exosystem states at a for a step to b (mid its middle). */
static void gen_term_values(const input_term *t, double a, double mid, double *wk) {
  switch (t->kind) {
    case CUP_WAVE_CONSTANT: wk[0] = t->value; break;
    case CUP_WAVE_SINE: {                          /* (one argument: the compiler's sincos, */
      double x = t->omega * a + t->phase, amp = t->amp;   /* the same bits as sin and cos) */
      wk[0] = amp * sin(x);
      wk[1] = amp * cos(x);
      break;
    }
    case CUP_WAVE_SQUARE: wk[0] = input_term_value(t, mid); break;
    case CUP_WAVE_DAMPED_SINE: {                   /* no delay (input_gen_check) */
      double e = t->amp * exp(-t->damping * a), x = t->omega * a + t->phase;
      wk[0] = e * sin(x);
      wk[1] = e * cos(x);
      break;
    }
    case CUP_WAVE_PULSE:
    case CUP_WAVE_PWL: {
      double va = input_term_value(t, a);
      wk[0] = va;
      wk[1] = mid > a ? (input_term_value(t, mid) - va) / (mid - a) : 0;
      break;
    }
  }
}

void input_gen_values(const cup_input *u, const int *first_state, double a, double b, double *w) {
  double mid = 0.5 * (a + b);
  for (int k = 0; k < u->nterms; k++) gen_term_values(&u->terms[k], a, mid, w + first_state[k]);
}

/* As input_gen_values, a PULSE's and a PWL's inside its table by the line
 * of the piece that holds mid instead (the values they would have had
 * first are not computed: a switched run's windows start a piece each,
 * and those were a tenth of a window's instructions). */
void input_gen_rot_plan(const cup_input *u, input_gen_rot *rot) {
  for (int k = 0; k < u->nterms; k++) {
    const input_term *t = &u->terms[k];
    rot[k] = (input_gen_rot){.base = -1};
    for (int j = 0; t->kind == CUP_WAVE_SINE && j < k; j++) {
      const input_term *b = &u->terms[j];
      if (b->kind != CUP_WAVE_SINE || rot[j].base >= 0 || b->omega != t->omega || b->amp == 0) continue;
      double d = t->phase - b->phase, f = t->amp / b->amp;
      rot[k] = (input_gen_rot){.base = j, .c = f * cos(d), .s = f * sin(d)};
      break;
    }
  }
}

void input_gen_piece(const cup_input *u, const int *first_state, const input_gen_rot *rot, double a, double b,
                     double *w) {
  double mid = 0.5 * (a + b);
  for (int k = 0; k < u->nterms; k++) {
    const input_term *t = &u->terms[k];
    double *wk = w + first_state[k], t0, v0, slope;
    if (rot && rot[k].base >= 0) continue;        /* (its base's states) */
    if (t->kind == CUP_WAVE_PULSE) {
      spice_pulse_line(t, mid, &t0, &v0, &slope);
    } else if (t->kind == CUP_WAVE_PWL && mid > t->t[0] && mid < t->t[t->np - 1]) {
      int j = pwl_segment(t, mid);
      t0 = t->t[j];
      v0 = t->v[j];
      slope = (t->v[j + 1] - t->v[j]) / (t->t[j + 1] - t->t[j]);
    } else {
      gen_term_values(t, a, mid, wk);
      continue;
    }
    wk[0] = v0 + slope * (a - t0);
    wk[1] = slope;
  }
}

int input_gen_from_start(const cup_input *u) {
  for (int k = 0; k < u->nterms; k++) {          /* (gen_term_values: what reads mid) */
    int kind = u->terms[k].kind;
    if (kind != CUP_WAVE_CONSTANT && kind != CUP_WAVE_SINE && kind != CUP_WAVE_DAMPED_SINE) return 0;
  }
  return 1;
}

/* ---- callback quadrature ------------------------------------------------------ */

typedef struct { const cup_input *u; int comp; double *buf; int failed; } quad_ctx;

static double quad_fn(double t, void *vp) {
  quad_ctx *q = vp;
  if (q->failed) return 0;
  if (q->u->fn(t, q->buf, q->u->ctx) != 0 || !isfinite(q->buf[q->comp])) { q->failed = 1; return 0; }
  return q->buf[q->comp];
}

int input_integral_ws(const cup_input *u, double a, double b, double *out,
                      input_quad_ws *ws) {
  if (!u->fn) {
    for (int j = 0; j < u->p; j++) out[j] = 0;
    for (int k = 0; k < u->nterms; k++) out[u->terms[k].comp] += input_term_integral(&u->terms[k], a, b);
    return CUP_OK;
  }
  int st = CUP_OK;
  gsl_error_handler_t *old = gsl_set_error_handler_off();   /* GSL would abort */
  for (int j = 0; j < u->p; j++) {
    quad_ctx q = {u, j, ws->buf, 0};
    gsl_function F = {quad_fn, &q};
    double err = 0;
    int rc = gsl_integration_qag(&F, a, b, u->abs_tol, u->rel_tol, ws->limit,
                                 GSL_INTEG_GAUSS21, ws->w, &out[j], &err);
    if (q.failed) { st = CUP_ERR_CALLBACK; break; }
    if (rc) st = status_merge(st, CUP_WARN_QUADRATURE);
  }
  gsl_set_error_handler(old);
  return st;
}

int input_quad_ws_init(input_quad_ws *ws, int p) {
  ws->limit = 200;
  ws->w = gsl_integration_workspace_alloc(ws->limit);
  ws->buf = malloc(sizeof(double) * ((size_t)p + 1));
  if (!ws->w || !ws->buf) { input_quad_ws_free(ws); return CUP_ERR_NOMEM; }
  return CUP_OK;
}

void input_quad_ws_free(input_quad_ws *ws) {
  if (ws->w) gsl_integration_workspace_free(ws->w);
  free(ws->buf);
  ws->w = NULL;
  ws->buf = NULL;
}

int cup_input_integral(const cup_input *u, double a, double b, double *out) {
  if (!u || !out) return CUP_ERR_ARG;
  if (!u->fn) return input_integral_ws(u, a, b, out, NULL);
  input_quad_ws ws = {0};
  if (input_quad_ws_init(&ws, u->p)) return CUP_ERR_NOMEM;
  int st = input_integral_ws(u, a, b, out, &ws);
  input_quad_ws_free(&ws);
  return st;
}

/* Term w's next break after t (INFINITY if none): cup_input_next_break's
 * share of it. */
static double term_break(const input_term *w, double t) {
  if (w->kind == CUP_WAVE_SQUARE && w->omega > 0 && w->amp != 0) {
    /* jumps at integer q */
    double j = floor(input_square_q(w, t)) + 1;
    double tb = (j * M_PI - w->phase) / w->omega;
    if (!(tb > t)) tb = ((j + 1) * M_PI - w->phase) / w->omega;
    return tb;
  } else if (w->kind == CUP_WAVE_PWL) {
    for (int i = 0; i < w->np; i++)
      if (w->t[i] > t) return w->t[i];
  } else if (w->kind == CUP_WAVE_PULSE || w->kind == CUP_WAVE_DAMPED_SINE) {
    return spice_term_break(w, t);
  }
  return INFINITY;
}

double cup_input_next_break(const cup_input *u, double t) {
  double next = INFINITY;
  if (!u) return next;
  for (int k = 0; k < u->nterms; k++) next = fmin(next, term_break(&u->terms[k], t));
  return next;
}

/* Term w's next break after t, its memo m missed: made afresh. */
static double break_missed(const input_term *w, input_break_memo *m, double t) {
  double b;
  if (input_jump_pulse(w) && w->value2 != w->value) {
    /* a gate's corners one after another: from the last one's period */
    double per = t == m->next ? m->per : 0;
    b = spice_jump_break(w, t, &per);
    *m = (input_break_memo){t, b, per};
  } else {
    b = term_break(w, t);
    /* a square wave's next jump is rounded from q at t: asked afresh */
    *m = (input_break_memo){w->kind == CUP_WAVE_SQUARE ? NAN : t, b, 0};
  }
  return b;
}

/* (The memos' terms first, by the memos alone: a term read only when its
 * memo missed, the one gate whose corner t is at a switched run's window
 * start; the terms past them, as cup_input_next_break. The same terms in
 * the same order: the same minimum.) */
double input_next_break_memo(const cup_input *u, input_break_memo *m, int nm, double t) {
  double next = INFINITY;
  if (!u) return next;
  int n = u->nterms;
  if (nm > n) nm = n;
  for (int k = 0; k < nm; k++) {
    double b = m[k].next;
    if (!(m[k].from <= t && t < b)) b = break_missed(&u->terms[k], &m[k], t);
    if (b < next) next = b;                        /* (fmin's, a NaN b too) */
  }
  for (int k = nm; k < n; k++) {
    double b = term_break(&u->terms[k], t);
    if (b < next) next = b;
  }
  return next;
}

/* Internal layout of cup_input, and quadrature workspace owned by callers
 * (an input is read-only and may be shared; GSL workspaces are not). */
#ifndef CUP_INPUT_IMPL_H
#define CUP_INPUT_IMPL_H

#include <float.h>
#include <math.h>
#include <gsl/gsl_integration.h>
#include "catchup/input.h"
#include "util/lanes.h"
#include "util/linalg.h"

typedef struct input_term {
  int comp;
  cup_wave_kind kind;
  double value, amp, omega, phase;  /* omega = 2 pi frequency */
  int np;
  double *t, *v;
  double delay, damping;                    /* PULSE, DAMPED_SINE */
  double value2, rise, fall, width, period; /* PULSE */
} input_term;

struct cup_input {
  int p;
  int nterms;
  input_term *terms;
  cup_input_fn fn;
  void *ctx;
  double abs_tol, rel_tol;
};

/* One term's next break and the times it is the answer for: a PULSE's
 * corners, a PWL's knots and a damped sine's delay are fixed numbers, so
 * the least of them past t is the least past any t' in [t, next) too
 * (from = NaN: none, asked afresh; {0} holds for no time). */
typedef struct input_break_memo {
  double from, next;
  double per;           /* a jump PULSE's period at from, plus 2 (1: before its delay; 0: none known):
                           the break after next from it (spice_jump_break) */
} input_break_memo;

/* cup_input_next_break(u, t), bit for bit, terms k < nm by their memos
 * m[k] (kept by the caller; each refreshed when t is outside its times):
 * a switched run asks at each piece's start and end, and between two of a
 * converter's corners only the gate whose corner it was moves on. */
double input_next_break_memo(const cup_input *u, input_break_memo *m, int nm, double t);

/* cup_input_next_break's last answer, kept by a caller that asks at the
 * same time twice (the adaptive scheme's records and pieces, ad_next_break),
 * and the first terms' memos for one that asks at each piece's start. */
#define INPUT_BREAK_MEMOS 8
typedef struct input_breaks {
  int ok;
  double t, next;
  input_break_memo term[INPUT_BREAK_MEMOS];
} input_breaks;

typedef struct input_quad_ws {
  gsl_integration_workspace *w;
  size_t limit;
  double *buf;          /* p entries for the callback */
} input_quad_ws;

/* The SPICE source functions (input_spice.c): PULSE and DAMPED_SINE. */
int spice_term_init(input_term *t, const cup_wave *w, char *errmsg);
double spice_term_value(const input_term *t, double tt);
double spice_term_integral(const input_term *t, double a, double b);
double spice_term_break(const input_term *t, double tt);   /* the next corner after tt, or INFINITY */
/* The same for a PULSE with jump edges (rise = fall = 0, value2 != value),
 * bit for bit, and in *per its period at tt (input_break_memo's per). With
 * *per > 0, tt is the break this gave from a time in period *per - 2 (or
 * before the delay, 1): the period moved on from it, without a division. */
double spice_jump_break(const input_term *t, double tt, double *per);
/* A PULSE's piece around mid as the line u = v0 + slope (t - t0) through its
 * corners at the times spice_term_break gives them (t0 the one before
 * mid), with the corners' own values. */
void spice_pulse_line(const input_term *t, double mid, double *t0, double *v0, double *slope);
int spice_term_constant(const input_term *t);
/* A PULSE with rise = fall = 0 at tt, constant on [tt, *hi) (the signals' samples). */
double spice_jump_pulse(const input_term *t, double tt, double *hi);
/* The same, and in *j the period tt is in (-1 before the delay). */
double spice_jump_pulse_j(const input_term *t, double tt, double *j, double *hi);
/* spice_jump_pulse at tt >= delay in period j (pulse_period's, 0 without a
 * period): its value and the piece's end, the least of the top's end and
 * the next period's start (fmin's bits, la_fmin, without the call). */
static inline double spice_jump_piece(const input_term *t, double tt, double j, double *hi) {
  double base = t->delay + t->period * j;
  double c2 = base + (t->rise + t->width), next = t->period > 0 ? t->delay + t->period * (j + 1) : INFINITY;
  if (tt < c2) {
    *hi = la_fmin(c2, next);
    return t->value2;
  }
  *hi = next;
  return t->value;
}
/* The period at a piece's end tt, from the piece's period j: the next one
 * when tt is its start delay + P (j + 1), the sum pulse_period checks, else
 * still j (tt the top's end, below the next start): what pulse_period
 * finds there (its floor is within one of it and corrected by those very
 * sums), without its division. */
static inline double spice_period_after(const input_term *t, double tt, double j) {
  return t->period > 0 && tt == t->delay + t->period * (j + 1) ? j + 1 : j;
}
/* The same at tt = *hi of the piece before it, *j that piece's period (from
 * spice_jump_pulse_j or this), moved on: the pieces one after another (a
 * switched run's gates, a walk inlined in it), bit for bit spice_jump_pulse's. */
static inline double spice_jump_pulse_next(const input_term *t, double tt, double *j, double *hi) {
  if (*j < 0) return spice_jump_pulse_j(t, tt, j, hi);   /* (tt = delay: once a run) */
  *j = spice_period_after(t, tt, *j);
  return spice_jump_piece(t, tt, *j, hi);
}

/* The square wave in units of pi: q = omega t / pi + phase / pi, so that
 * sign(sin(pi q)) jumps at integers q. Deciding the sign from q (not from
 * sin) makes the jump instants exact: sign(0) = 0 there, as in the paper,
 * even where sin(pi q) evaluates to 1e-16. */
static inline double input_square_q(const input_term *w, double t) { return w->omega * t / M_PI + w->phase / M_PI; }

/* q mod 2 in [0, 2) (floor is cheaper than fmod here) */
static inline double input_mod2(double q) { return q - 2.0 * la_floor(0.5 * q); }

/* r = input_mod2(q) within tol of a zero of sin(pi q) */
static inline int input_square_near_zero(double r, double tol) {
  return r <= tol || fabs(r - 1) <= tol || 2 - r <= tol;
}

/* sign(sin(pi q)) from q and r = input_mod2(q) */
static inline double input_sign_sin_qr(double q, double r) {
  double tol = 4 * DBL_EPSILON * (fabs(q) > 1 ? fabs(q) : 1.0);   /* fmax(1, |q|), NaN giving 1 */
  if (input_square_near_zero(r, tol)) return 0;
  return r < 1 ? 1 : -1;
}

static inline double input_sign_sin_q(double q) { return input_sign_sin_qr(q, input_mod2(q)); }

/* Antiderivative of sign(sin(pi q)) in q: a triangle wave between 0 and 1,
 * from r = input_mod2(q). */
static inline double input_triangle_r(double r) { return r <= 1 ? r : 2 - r; }

static inline double input_sign_sin_q_integral(double q) { return input_triangle_r(input_mod2(q)); }

/* The same three, two positions q at a time, bit for bit: r = input_mod2(q)
 * taking floor(q / 2) = *fl when *fl <= q0 / 2 <= q1 / 2 < *fl + 1 (a
 * square wave's floor changes twice a period; q / 2 = 0 goes to la_floor,
 * which keeps the sign of a zero), *fl the last lane's floor after. */
static inline v2d input_mod2_2(v2d q, double *fl) {
  v2d half = 0.5 * q;
  double f = *fl, h0 = half[0], h1 = half[1];
  v2d fv = {f, f};
  if (!(h0 >= f && h0 <= h1 && h1 < f + 1 && h0 != 0)) fv = (v2d){la_floor(h0), la_floor(h1)};
  *fl = fv[1];
  return q - 2.0 * fv;
}

static inline v2d input_sign_sin_qr2(v2d q, v2d r) {
  const v2d one = {1, 1}, two = {2, 2};
  const v2l sign = {(long long)0x8000000000000000ULL, (long long)0x8000000000000000ULL};
  v2d tol = 4 * DBL_EPSILON * v2_max(v2_abs(q), one);
  v2l zero = (r <= tol) | (v2_abs(r - one) <= tol) | (two - r <= tol);
  v2d s = (v2d)((v2l)one | (sign & ~(r < one)));   /* r < 1 ? 1 : -1 */
  return v2_clear(zero, s);
}

/* r <= 1 ? r : 2 - r as min(r, 2 - r): the same for r in [0, 2) (2 - r is
 * exact above 1) and NaN */
static inline v2d input_triangle_r2(v2d r) { return v2_min(r, (v2d){2, 2} - r); }

/* input_mod2 and input_sign_sin_qr of np pairs of positions q that never
 * decrease (a square wave's q at increasing times: omega > 0), bit for bit,
 * per block rather than per position where the block allows: floor, the
 * roundings and fabs on either side of 1 are monotone, so when q / 2 has one
 * floor at both ends (q[0] != 0, so that no zero's sign is in question) it
 * has it throughout, and when both ends' r are clear of the sign's zeros
 * (input_square_near_zero) by the block's largest tolerance and on one side
 * of 1, every r between is too. Returns 1 when one sign holds for the whole
 * block (no jump in it). */
static inline int input_square_block(const v2d *q, int np, v2d *r, v2d *sg) {
  const double first = q[0][0], last = q[np - 1][1], fl = la_floor(0.5 * first);
  if (first != 0 && fl == la_floor(0.5 * last)) {        /* NaN compares unequal */
    const v2d two_fl = 2.0 * (v2d){fl, fl};
    for (int p = 0; p < np; p++) r[p] = q[p] - two_fl;
    const double r0 = r[0][0], r1 = r[np - 1][1];
    const double tol = 4 * DBL_EPSILON * la_max(la_max(fabs(first), fabs(last)), 1.0);
    if (!input_square_near_zero(r0, tol) && !input_square_near_zero(r1, tol) && (r0 < 1) == (r1 < 1)) {
      const double s = r0 < 1 ? 1 : -1;
      for (int p = 0; p < np; p++) sg[p] = (v2d){s, s};
      return 1;
    }
  } else {
    double f = NAN;
    for (int p = 0; p < np; p++) r[p] = input_mod2_2(q[p], &f);
  }
  for (int p = 0; p < np; p++) sg[p] = input_sign_sin_qr2(q[p], r[p]);
  return 0;
}

/* A new input v(t) = u(t0 + t), t >= 0, term by term (phases advanced by
 * omega t0, PULSE and SIN delays spent, PWL knots moved), for t0 at or past
 * the time from which every term repeats (cup_input_steady_phase; a PWL is
 * then constant, a single pulse over). CUP_ERR_UNSUPPORTED for a callback
 * and t0 != 0. */
int input_shift(const cup_input *u, double t0, cup_input **v, char *errmsg);
/* *u read from t0 on (input_shift): *written keeps the input as written
 * while t0 != 0, *u its shift; t0 = 0 puts the written one back. An
 * integrator made with the old *u must be freed first. */
int input_origin(cup_input **u, cup_input **written, double t0, char *errmsg);
/* A copy of u, term by term, bit for bit (CUP_ERR_NOMEM, *v NULL): a switch
 * configuration's sources are its circuit's, the same in each one
 * (netlist_switch.c's form), and building them again was 45 reallocs on the
 * full bridge's 9. */
int input_copy(const cup_input *u, cup_input **v);

/* One term's value at t (its component's share of u(t)). */
double input_term_value(const input_term *w, double t);
/* A SINE term's value (input_term_value's case, inline for the signals'
 * samples: the call and its switch were 30 instructions of each). */
static inline double input_sine_value(const input_term *w, double t) { return w->amp * sin(w->omega * t + w->phase); }
/* 1 for a PULSE with jump edges (rise and fall 0): piecewise constant,
 * its pieces spice_jump_pulse's. */
static inline int input_jump_pulse(const input_term *w) {
  return w->kind == CUP_WAVE_PULSE && w->rise == 0 && w->fall == 0;
}
/* The same, and in *hi the end of the piece [t, *hi) where it holds bit
 * for bit: a constant's forever, a PULSE's with jump edges up to its next
 * corner (spice_jump_pulse); *hi = t, no piece, for other kinds. */
double input_term_piece(const input_term *w, double t, double *hi);
/* cup_input_eval's sums of terms[0 .. n) alone into out (p entries; the
 * others 0): u(t) where only the listed terms are read (a waveform u). */
void input_eval_terms(const cup_input *u, const int *terms, int n, double t, double *out);
/* One term's exact integral over [a, b]. */
double input_term_integral(const input_term *w, double a, double b);

/* The built-in waveforms as the output of a linear exosystem on each interval
 * without breakpoints: w' = W w, u = U w. States per term: constant 1
 * (w' = 0), sine 2 (s' = om c, c' = -om s, the input is s; damped: minus
 * d s, d c), square 1 (piecewise constant), table and pulse 2 (v' = slope). Used by the exponential free
 * step and the adaptive scheme; callbacks have no exosystem. */
int input_term_gen_states(const input_term *t);
/* CUP_ERR_UNSUPPORTED (naming the scheme and the term) for a waveform the
 * exosystem cannot hold: a damped sine with a delay. */
int input_gen_check(const cup_input *u, const char *scheme, char *errmsg);
/* Sines that share a frequency share their states (input_gen_rot_plan):
 * rot[k].base is the earlier undamped sine of term k's frequency whose
 * states term k reads, or -1 (the term has states of its own). Term k's
 * value is then amp_k sin(x + d) = (amp_k / amp_j)(cos d s_j + sin d c_j)
 * of the base j's states s_j = amp_j sin x, c_j = amp_j cos x, d the
 * phases' difference: rot[k].c and .s are those two factors. A three-phase
 * source's three sines are 2 states, not 6 (the six-pulse bridge's flow
 * 4 x 4, not 8 x 8), and a piece costs one sincos a frequency. */
typedef struct input_gen_rot {
  int base;                                 /* the earlier sine's term, or -1 */
  double c, s;                              /* term k's factors on the base's sine and cosine state */
} input_gen_rot;
/* rot[k] for each term of u (nterms entries): a base has amp != 0. */
void input_gen_rot_plan(const cup_input *u, input_gen_rot *rot);
/* Total exosystem states of u (0 for a callback or NULL); first_state[k]
 * (if not NULL, nterms entries) gets the first state of term k, with rot
 * (or NULL: a term's states its own) its base's for a term that shares. */
int input_gen_dim(const cup_input *u, const input_gen_rot *rot, int *first_state);
/* W into the nw x nw block at W (column-major, leading dimension ld),
 * added to what is there: the sine rotations and the table slopes (a
 * block once, with rot). */
void input_gen_dynamics(const cup_input *u, const input_gen_rot *rot, const int *first_state, double *W, int ld);
/* U (p x nw, column-major, leading dimension ld), added to what is there:
 * term k's value from its states, 1 on its first, or with rot its base's
 * two factors. */
void input_gen_output(const cup_input *u, const input_gen_rot *rot, const int *first_state, double *U, int ld);
/* The states on the interval (a, b) (no breakpoint inside), at a: constants,
 * sin/cos at a, the square's value on the open interval (at its midpoint:
 * the jump instants carry no weight), the table's value at a and its slope
 * on (a, b). Taken from the waveform itself, so nothing drifts. */
void input_gen_values(const cup_input *u, const int *first_state, double a, double b, double *w);
/* The same, with a table's or a pulse's states from the line of its piece
 * through the piece's corners (their values at the breakpoints' times):
 * the value at a and the slope of the step's piece are then the ones the
 * piece before and after meet, whatever a and b round to (the adaptive
 * scheme's steps run between breakpoints; a fixed step that straddles a
 * corner needs gen_values' secant instead). With rot, a term that shares
 * its base's states writes none. */
void input_gen_piece(const cup_input *u, const int *first_state, const input_gen_rot *rot, double a, double b,
                     double *w);
/* 1 if u's states on (a, b) are functions of a alone (constants and sines:
 * no square, table or pulse, whose states read the step's middle), so that
 * the states of one piece serve every step from the same a. */
int input_gen_from_start(const cup_input *u);

int input_quad_ws_init(input_quad_ws *ws, int p);
void input_quad_ws_free(input_quad_ws *ws);
/* Integral with a caller-owned workspace (needed only for callbacks). */
int input_integral_ws(const cup_input *u, double a, double b, double *out,
                      input_quad_ws *ws);

#endif

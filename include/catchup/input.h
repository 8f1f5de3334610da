/* catchup/input.h — inputs u(t) in R^p: sums of built-in waveforms with
 * exact integrals, or a user callback integrated by GSL quadrature. */
#ifndef CATCHUP_INPUT_H
#define CATCHUP_INPUT_H

#include "catchup/export.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cup_input cup_input;

/* One list of the waveforms: X(enumerator, value, name (the scene's `type`),
 * what it is). Values are part of the ABI: append, never renumber. */
#define CUP_WAVE_LIST(X)                                                                \
  X(CUP_WAVE_CONSTANT, 0, "constant", "value")                                          \
  X(CUP_WAVE_SINE, 1, "sine", "amplitude * sin(2 pi frequency t + phase)")              \
  X(CUP_WAVE_SQUARE, 2, "square", "amplitude * sign(sin(2 pi frequency t + phase)), sign(0) = 0") \
  X(CUP_WAVE_PWL, 3, "pwl", "piecewise linear through (t_k, v_k); constant outside")            \
  X(CUP_WAVE_PULSE, 4, "pulse", "SPICE PULSE: value until delay, a ramp to value2 in rise, value2 for " \
    "width, a ramp back in fall, value until period repeats it (period 0: once)")                \
  X(CUP_WAVE_DAMPED_SINE, 5, "damped_sine", "SPICE SIN: amplitude e^(-damping (t - delay)) "  \
    "sin(2 pi frequency (t - delay) + phase) after delay, amplitude sin(phase) before")

typedef enum cup_wave_kind {
#define CUP_WAVE_ENUM_(e, v, name, doc) e = v,
  CUP_WAVE_LIST(CUP_WAVE_ENUM_)
#undef CUP_WAVE_ENUM_
} cup_wave_kind;
#define CUP_WAVE_ONE_(e, v, name, doc) +1
/** The number of waveforms: values 0 .. CUP_WAVE_COUNT - 1. */
enum { CUP_WAVE_COUNT = 0 CUP_WAVE_LIST(CUP_WAVE_ONE_) };
#undef CUP_WAVE_ONE_

/** One waveform term; u_j(t) is the sum of the terms added to component j. */
typedef struct cup_wave {
  cup_wave_kind kind;
  double value;          /**< CONSTANT */
  double amplitude;      /**< SINE, SQUARE */
  double frequency;      /**< SINE, SQUARE: cycles per unit time (16 sin(6 pi t): 3) */
  double phase;          /**< SINE, SQUARE: radians */
  int npoints;           /**< PWL: number of points (>= 1), times strictly increasing */
  const double *t;       /**< PWL: times (copied) */
  const double *v;       /**< PWL: values (copied) */
  /* SPICE sources (netlists): */
  double delay;          /**< PULSE, DAMPED_SINE: the waveform starts at t = delay >= 0 */
  double damping;        /**< DAMPED_SINE: decay rate (1/time) after the delay */
  double value2;         /**< PULSE: the pulsed value (value is the initial one) */
  double rise, fall;     /**< PULSE: ramp times >= 0 (0: a jump) */
  double width, period;  /**< PULSE: time at value2; period >= rise + width + fall, or 0: one pulse */
} cup_wave;

/** User input: write u(t) (p entries) into u; return 0, or nonzero to stop
 *  the run with CUP_ERR_CALLBACK. Must be callable from Fortran (bind(C)). */
typedef int (*cup_input_fn)(double t, double *u, void *ctx);

/** The name of a waveform in CUP_WAVE_LIST ("sine", ...); "unknown" otherwise. */
CUP_API const char *cup_wave_name(int kind);
/** A name of CUP_WAVE_LIST -> its value; -1 if unknown. */
CUP_API int cup_wave_parse(const char *name);

/** An input with p components, all zero until terms are added. */
CUP_API int cup_input_create(cup_input **u, int p, char *errmsg);
CUP_API void cup_input_free(cup_input **u);
/** Add a waveform term to component j (0-based). Validates finiteness,
 *  frequency >= 0, PWL times increasing; errmsg names the problem. */
CUP_API int cup_input_add(cup_input *u, int j, const cup_wave *w, char *errmsg);
/** Replace the waveforms by a callback. Integrals use adaptive GSL quadrature
 *  (QAG, 21-point Gauss-Kronrod) per component to the absolute/relative
 *  tolerance given; a step that misses it yields CUP_WARN_QUADRATURE. */
CUP_API int cup_input_set_callback(cup_input *u, cup_input_fn fn, void *ctx,
                                   double abs_tol, double rel_tol);

CUP_API int cup_input_dim(const cup_input *u);
/** 1 if u is constant in time (then integrals are h * u and never recomputed). */
CUP_API int cup_input_is_constant(const cup_input *u);
/** u(t) into out (p entries). */
CUP_API int cup_input_eval(const cup_input *u, double t, double *out);
/** The exact integral of u over [a, b] into out (quadrature for callbacks). */
CUP_API int cup_input_integral(const cup_input *u, double a, double b, double *out);
/** The next time > t at which some term is not smooth (a square-wave jump
 *  or a PWL breakpoint), or INFINITY. Used by the exponential scheme. */
CUP_API double cup_input_next_break(const cup_input *u, double t);

#ifdef __cplusplus
}
#endif
#endif

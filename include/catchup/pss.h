/* catchup/pss.h — the periodic steady state of a circuit driven by a
 * periodic input, by Newton's method on the period map (docs/steady-state.md),
 * its Floquet multipliers, and measurements of one period.
 *
 * The period map Phi takes x(0) to x(T): one run of the integrator over the
 * period (the adaptive scheme at a tight tolerance by default, a fixed-step
 * scheme when asked). The steady state is the x0 with Phi(x0) = x0, found by
 * Newton's method on Phi(x) - x; the Jacobian of Phi (the monodromy matrix)
 * is the adaptive scheme's tangent of its run with D = 0 (the flows of the
 * active sets and the saltation projections at events: exact, no extra
 * run) or, with D != 0 and for the other schemes, finite differences of the period map (n more runs a Newton
 * step), and its eigenvalues are the Floquet multipliers: all inside the
 * unit circle, the orbit attracts (a transient settles on it, the slowest
 * mode by the largest modulus a period); one on or outside it, the orbit is
 * not asymptotically stable (CUP_WARN_UNSTABLE_ORBIT); a multiplier at 1
 * (an undamped mode driven at resonance, a charge no path ever corrects)
 * leaves Phi(x) - x singular: no isolated periodic orbit, and the solve
 * stops with CUP_ERR_NO_STEADY_STATE naming it. Never hangs: at most
 * max_iter Newton steps, each of n + 1 periods at most. */
#ifndef CATCHUP_PSS_H
#define CATCHUP_PSS_H

#include "catchup/export.h"
#include "catchup/input.h"
#include "catchup/lcs.h"
#include "catchup/integrator.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The most Newton steps (the residuals' array). */
#define CUP_PSS_MAX_ITER 100

typedef struct cup_pss_options {
  double period;          /**< T > 0, or 0: the input's common period (cup_input_period) */
  int max_iter;           /**< Newton steps, 1 .. CUP_PSS_MAX_ITER; default 20 */
  double tol;             /**< converged when ||Phi(x) - x||_inf <= tol (||x||_inf + tol_floor); default 1e-10 */
  double tol_floor;       /**< the scale below which the residual is absolute; default 1e-9 */
  double map_tol;         /**< adaptive scheme: the period map's tol_abs and tol_rel (cup_pss_solve);
                               default 1e-12; 0: the integrator options' own */
  double fd_step;         /**< the monodromy's finite differences: step relative to the state; default 1e-6 */
  int warmup_periods;     /**< transient periods from x_guess before Newton; default 0 */
  long samples;           /**< cup_pss_solve: one period of the steady state at this many
                               uniform samples (>= 2), or 0: none; default 0 */
  int jacobian;           /**< the monodromy: CUP_PSS_JACOBIAN_AUTO (default) exact where the scheme
                               carries the map's tangent (the adaptive scheme with D = 0: flows and
                               saltation projections, no extra run), else finite differences;
                               CUP_PSS_JACOBIAN_FD finite differences always */
} cup_pss_options;

/** cup_pss_options.jacobian */
enum { CUP_PSS_JACOBIAN_AUTO = 0, CUP_PSS_JACOBIAN_FD = 1 };

/** What a solve did (the arrays: cup_pss_x0, _residuals, _multipliers, ...). */
typedef struct cup_pss_info {
  int status;             /**< CUP_OK, CUP_WARN_UNSTABLE_ORBIT, or an error (CUP_ERR_NO_STEADY_STATE, a run's) */
  int n;                  /**< state dimension */
  int m;                  /**< complementarity rows (the multipliers zeta of the samples) */
  int iterations;         /**< Newton steps taken (the residuals: iterations + 1 entries) */
  double period;          /**< T */
  double residual;        /**< the last ||Phi(x0) - x0||_inf */
  double max_multiplier;  /**< the largest modulus of a Floquet multiplier (NaN: none computed) */
  long period_runs;       /**< runs of the period map, Jacobians and the trajectory's included */
  long events;            /**< events of the last period run (the adaptive scheme) */
  long samples;           /**< the trajectory's samples (0: none) */
  double seconds;         /**< wall time of the solve */
  char message[CUP_RUN_MSG_LEN]; /**< what went wrong or what to know, whole */
  double t0;              /**< the phase (cup_input_steady_phase): x0 is the state at t0, the
                               period [t0, t0 + T) of the sources as written (cup_pss_solve; 0
                               for cup_pss_solve_map, whose map starts where it was made to) */
  long jumps;             /**< the trajectory's jump times (cup_pss_jumps gives them); -1 when there
                               were more than 4 a sample + 64, none given (the measurements then take the
                               samples alone: O(h) where a signal jumps); 0 with none or no trajectory */
} cup_pss_info;

/** A solve's result (opaque). */
typedef struct cup_pss cup_pss;

CUP_API void cup_pss_options_default(cup_pss_options *o);

/** The common period of the input's waveforms: the least T that is an
 *  integer multiple of every periodic term's period (the ratios within
 *  1e-12 relative, multiples up to 1000). A sine, square wave or PULSE with
 *  a period is periodic; a constant is any period. CUP_ERR_ARG naming the
 *  term when none exists: no periodic term; periods with no common multiple;
 *  a PWL that changes (constant after its last point); a damped or delayed
 *  SIN; a PULSE whose delay makes [0, T) unlike later periods; a callback. */
CUP_API int cup_input_period(const cup_input *u, double *T, char *errmsg);
/** CUP_OK if T is a whole number of the input's common periods (within
 *  1e-9), or the input tells none (a constant, a callback); CUP_ERR_ARG
 *  naming both otherwise, and naming the term when a source does not
 *  repeat from t = 0 (cup_input_period's cases: a PWL that changes, a
 *  damped or delayed SIN, a PULSE delayed past its period's start, no
 *  common period): over such a T the period map is not a period. */
CUP_API int cup_input_period_fits(const cup_input *u, double T, char *errmsg);

/** The steady state's period and phase: period the one asked for (> 0:
 *  it must be a whole number of the sources' common period) or 0 (the
 *  sources' common period, as cup_input_period finds it once every source
 *  repeats); into *T that period and into *t0 the least time from which every source
 *  repeats with period T: 0 unless a source starts otherwise (a PULSE whose
 *  delay lets [0, T) differ from later periods, delay + rise + width + fall
 *  > period: t0 = delay + rise + width + fall - period, or its delay if
 *  less; a delayed SIN: its delay; a PWL that changes: its last knot; a
 *  single pulse: its end). The steady state is the orbit through t0: the
 *  period map runs over [t0, t0 + T): from t = 0 of u read from t0 on.
 *  CUP_ERR_ARG naming the term when there is none (a damped SIN, no common
 *  period, a constant input and no period given, a callback and none). */
CUP_API int cup_input_steady_phase(const cup_input *u, double period, double *T, double *t0, char *errmsg);

/** The steady state of an LCS driven by u: the period from o->period or u;
 *  the period map by the integrator with options io (scheme, tolerances;
 *  T and the output are set here; the adaptive scheme's tolerances are
 *  o->map_tol unless 0), from x_guess (n entries, NULL: 0). On return *r
 *  holds the result, also when the solve failed (its info says why, with
 *  the residuals and multipliers so far); *r is NULL only when the
 *  arguments are wrong or memory runs out (errmsg says which). Returns
 *  the info's status. io->max_wall_seconds bounds the whole solve (the
 *  trajectory included), not each period run: past it the solve stops with
 *  CUP_ERR_TIME_LIMIT. */
CUP_API int cup_pss_solve(cup_pss **r, const cup_lcs *L, const cup_input *u, const cup_integrator_options *io,
                          const double *x_guess, const cup_pss_options *o, char *errmsg);
/** The same on any period map: I, made with options.T = period (any model,
 *  any scheme; output FINAL or NONE is cheapest), run from x to x(T) per
 *  evaluation; n its state dimension. No trajectory (o->samples is
 *  ignored): run I's twin with samples from cup_pss_x0. I's
 *  max_wall_seconds bounds the whole solve, as in cup_pss_solve (I's own
 *  limit is restored on return). */
CUP_API int cup_pss_solve_map(cup_pss **r, cup_integrator *I, int n, double period, const double *x_guess,
                              const cup_pss_options *o, char *errmsg);
CUP_API void cup_pss_free(cup_pss **r);

CUP_API void cup_pss_get_info(const cup_pss *r, cup_pss_info *info);
/** The steady state x0 (n entries): where Newton stopped (the best iterate). */
CUP_API const double *cup_pss_x0(const cup_pss *r);
/** ||Phi(x_k) - x_k||_inf, k = 0 .. iterations (iterations + 1 entries). */
CUP_API const double *cup_pss_residuals(const cup_pss *r);
/** The monodromy matrix dPhi/dx at x0 (n x n, column-major), or NULL if
 *  none was computed (a solve that failed before its first Jacobian). */
CUP_API const double *cup_pss_monodromy(const cup_pss *r);
/** The Floquet multipliers (n each, by decreasing modulus); CUP_ERR_ARG
 *  if the monodromy was not computed. */
CUP_API int cup_pss_multipliers(const cup_pss *r, double *re, double *im);
/** One period of the steady state (cup_pss_solve with o->samples): the
 *  sample times (samples), x (samples x n, row k the state at t[k]) and
 *  zeta (samples x m), each pointer NULL if not wanted. */
CUP_API int cup_pss_trajectory(const cup_pss *r, double *t, double *x, double *zeta);
/** The times inside the trajectory's period (t0, t0 + T), on its samples'
 *  clock and sorted, at which a signal may jump: each break of the sources
 *  (cup_input_next_break: a PULSE's edges and corners, a PWL's knots) and
 *  each event of the adaptive scheme (a diode turning on or off; the
 *  fixed-step schemes report none). Copied into t (NULL: the count only);
 *  returns how many: 0 with no trajectory, none, or more than 4 a sample
 *  + 64 (more than the samples resolve: measure those signals from the
 *  samples alone; cup_pss_info's jumps is -1 then). Each time once. For
 *  cup_measure_period_jumps. */
CUP_API long cup_pss_jumps(const cup_pss *r, double *t);

/* ---- measurements of one period (SPICE's .meas and .four) ---- */

/** Of a signal sampled uniformly over one period, v[k] at t0 + k T / (N - 1),
 *  k = 0 .. N - 1 (v[N-1] closes the period: the periodic trapezoid rule
 *  uses v[0 .. N-2]). Exact for a trigonometric polynomial of degree
 *  below (N - 1) / 2; a kink (a diode turning on) costs O(h^2), a jump
 *  (a diode's current, a capacitor's current at its turn-on) O(h),
 *  h = T / (N - 1) (docs/steady-state.md). cup_measure_period_jumps,
 *  given the period's jump times (cup_pss_jumps), measures a signal that
 *  jumps exactly, as catchup-run --steady-state and the steady-state
 *  sweeps do (docs/steady-state.md, "Signals that jump"). */
typedef struct cup_measure {
  double avg, rms, min, max, pp;  /**< average, RMS, minimum, maximum, peak-to-peak */
  double thd;                     /**< sqrt(sum_{k=2..order} |c_k|^2) / |c_1| (NaN when |c_1| is below
                                       1e-9 of the RMS: no fundamental, a DC output) */
} cup_measure;

/** The measurements of v (N >= 3 samples) and, with order >= 1, its
 *  harmonics k = 0 .. order as amplitudes (amp[k] = 2 |c_k|, amp[0] the
 *  average) and phases (of the cosine: v ~ sum amp_k cos(2 pi k t / T +
 *  phase_k)), each array order + 1 entries or NULL. order < (N - 1) / 2. */
CUP_API int cup_measure_period(const double *v, long N, int order, cup_measure *m, double *amp, double *phase,
                               char *errmsg);
/** cup_measure_period of v sampled at t0 + k T / (N - 1), given the times
 *  jump_t[0 .. nj) (sorted, in [t0, t0 + T]; cup_pss_jumps's) at which it
 *  may jump. If v jumps at one of them (by more than its change over a
 *  sample beside it and 1e-6 of its largest magnitude), it is measured as
 *  the piecewise-linear interpolant of its samples with each jump at its
 *  own time, each side extrapolated from the two samples on its side: the
 *  exact average, RMS, extremes (both sides of a jump), harmonics and THD
 *  of that function, O(h^2) on the smooth pieces and exact for
 *  piecewise-linear signals (a pulse, a switch node, a product v i of the
 *  ideal buck); of several jumps between two samples the first counts.
 *  Otherwise (nj = 0, or no jump there) cup_measure_period's figures, bit
 *  for bit. CUP_ERR_ARG naming the time when one is outside the period or
 *  out of order. */
CUP_API int cup_measure_period_jumps(const double *v, long N, const double *jump_t, long nj, double t0, double T,
                                     int order, cup_measure *m, double *amp, double *phase, char *errmsg);

#ifdef __cplusplus
}
#endif
#endif

/* C side of the Fortran tests: the struct layouts as the C compiler sees
 * them, the static inline cup_status_merge (no symbol to bind), and the
 * paper's case 1 run through the C API directly (the trajectory that the
 * Fortran API must reproduce). */
#include <stddef.h>
#include <string.h>
#include "catchup.h"

#define OFF(T, m) (long)offsetof(T, m)

/* Enumerations are ints in the bind(C) mirrors. */
_Static_assert(sizeof(cup_metric_kind) == sizeof(int), "enum size");
_Static_assert(sizeof(cup_proj_method) == sizeof(int), "enum size");
_Static_assert(sizeof(cup_wave_kind) == sizeof(int), "enum size");
_Static_assert(sizeof(cup_scheme) == sizeof(int), "enum size");
_Static_assert(sizeof(cup_output_kind) == sizeof(int), "enum size");
_Static_assert(sizeof(cup_set_kind) == sizeof(int), "enum size");

static int put(long *out, int cap, const long *v, int n) {
  for (int i = 0; i < n && i < cap; i++) out[i] = v[i];
  return n;
}
#define PUT(...) do { const long v_[] = {__VA_ARGS__}; \
    return put(out, cap, v_, (int)(sizeof v_ / sizeof v_[0])); } while (0)

/* sizeof(struct name), then offsetof every member in declaration order;
 * returns the number of entries (0: unknown name). */
int cupt_layout(const char *name, long *out, int cap) {
  if (!strcmp(name, "cup_csc"))
    PUT(sizeof(cup_csc), OFF(cup_csc, nrow), OFF(cup_csc, ncol), OFF(cup_csc, colptr),
        OFF(cup_csc, rowind), OFF(cup_csc, values));
  if (!strcmp(name, "cup_metric"))
    PUT(sizeof(cup_metric), OFF(cup_metric, kind), OFF(cup_metric, diag), OFF(cup_metric, matrix),
        OFF(cup_metric, lower_only));
  if (!strcmp(name, "cup_projector_options"))
    PUT(sizeof(cup_projector_options), OFF(cup_projector_options, method),
        OFF(cup_projector_options, eps_abs), OFF(cup_projector_options, eps_rel),
        OFF(cup_projector_options, eta_abs), OFF(cup_projector_options, eta_rel),
        OFF(cup_projector_options, max_iter), OFF(cup_projector_options, warm_start),
        OFF(cup_projector_options, return_feasible), OFF(cup_projector_options, lipschitz),
        OFF(cup_projector_options, feasible_point), OFF(cup_projector_options, factor_updates));
  if (!strcmp(name, "cup_proj_info"))
    PUT(sizeof(cup_proj_info), OFF(cup_proj_info, status), OFF(cup_proj_info, method),
        OFF(cup_proj_info, iterations), OFF(cup_proj_info, factorizations),
        OFF(cup_proj_info, skipped), OFF(cup_proj_info, active), OFF(cup_proj_info, scale),
        OFF(cup_proj_info, eps_target), OFF(cup_proj_info, eta_target),
        OFF(cup_proj_info, eps_cert), OFF(cup_proj_info, eta_cert),
        OFF(cup_proj_info, violation), OFF(cup_proj_info, dual_value),
        OFF(cup_proj_info, farkas_gap), OFF(cup_proj_info, farkas_residual),
        OFF(cup_proj_info, row_updates));
  if (!strcmp(name, "cup_wave"))
    PUT(sizeof(cup_wave), OFF(cup_wave, kind), OFF(cup_wave, value), OFF(cup_wave, amplitude),
        OFF(cup_wave, frequency), OFF(cup_wave, phase), OFF(cup_wave, npoints), OFF(cup_wave, t),
        OFF(cup_wave, v), OFF(cup_wave, delay), OFF(cup_wave, damping), OFF(cup_wave, value2),
        OFF(cup_wave, rise), OFF(cup_wave, fall), OFF(cup_wave, width), OFF(cup_wave, period));
  if (!strcmp(name, "cup_lcs_desc"))
    PUT(sizeof(cup_lcs_desc), OFF(cup_lcs_desc, n), OFF(cup_lcs_desc, m), OFF(cup_lcs_desc, p),
        OFF(cup_lcs_desc, A), OFF(cup_lcs_desc, B), OFF(cup_lcs_desc, C), OFF(cup_lcs_desc, E),
        OFF(cup_lcs_desc, F), OFF(cup_lcs_desc, G), OFF(cup_lcs_desc, P),
        OFF(cup_lcs_desc, pb_tol), OFF(cup_lcs_desc, D), OFF(cup_lcs_desc, row_names));
  if (!strcmp(name, "cup_circuit"))
    PUT(sizeof(cup_circuit), OFF(cup_circuit, R1), OFF(cup_circuit, R2), OFF(cup_circuit, R3),
        OFF(cup_circuit, L2), OFF(cup_circuit, L3), OFF(cup_circuit, C4), OFF(cup_circuit, G));
  if (!strcmp(name, "cup_pss_options"))
    PUT(sizeof(cup_pss_options), OFF(cup_pss_options, period), OFF(cup_pss_options, max_iter),
        OFF(cup_pss_options, tol), OFF(cup_pss_options, tol_floor), OFF(cup_pss_options, map_tol),
        OFF(cup_pss_options, fd_step), OFF(cup_pss_options, warmup_periods), OFF(cup_pss_options, samples),
        OFF(cup_pss_options, jacobian));
  if (!strcmp(name, "cup_pss_info"))
    PUT(sizeof(cup_pss_info), OFF(cup_pss_info, status), OFF(cup_pss_info, n), OFF(cup_pss_info, m),
        OFF(cup_pss_info, iterations), OFF(cup_pss_info, period), OFF(cup_pss_info, residual),
        OFF(cup_pss_info, max_multiplier), OFF(cup_pss_info, period_runs), OFF(cup_pss_info, events),
        OFF(cup_pss_info, samples), OFF(cup_pss_info, seconds), OFF(cup_pss_info, message),
        OFF(cup_pss_info, t0), OFF(cup_pss_info, jumps));
  if (!strcmp(name, "cup_measure"))
    PUT(sizeof(cup_measure), OFF(cup_measure, avg), OFF(cup_measure, rms), OFF(cup_measure, min),
        OFF(cup_measure, max), OFF(cup_measure, pp), OFF(cup_measure, thd));
  if (!strcmp(name, "cup_crowd_desc"))
    PUT(sizeof(cup_crowd_desc), OFF(cup_crowd_desc, agents), OFF(cup_crowd_desc, q0), OFF(cup_crowd_desc, radius),
        OFF(cup_crowd_desc, room_points), OFF(cup_crowd_desc, room), OFF(cup_crowd_desc, doors),
        OFF(cup_crowd_desc, door), OFF(cup_crowd_desc, obstacles), OFF(cup_crowd_desc, obstacle_points),
        OFF(cup_crowd_desc, obstacle), OFF(cup_crowd_desc, walls), OFF(cup_crowd_desc, wall),
        OFF(cup_crowd_desc, speed), OFF(cup_crowd_desc, grid), OFF(cup_crowd_desc, margin),
        OFF(cup_crowd_desc, reach), OFF(cup_crowd_desc, clearance));
  if (!strcmp(name, "cup_schedule"))
    PUT(sizeof(cup_schedule), OFF(cup_schedule, coef), OFF(cup_schedule, power));
  if (!strcmp(name, "cup_integrator_options"))
    PUT(sizeof(cup_integrator_options), OFF(cup_integrator_options, scheme),
        OFF(cup_integrator_options, T), OFF(cup_integrator_options, n),
        OFF(cup_integrator_options, eps), OFF(cup_integrator_options, eta),
        OFF(cup_integrator_options, proj), OFF(cup_integrator_options, output),
        OFF(cup_integrator_options, output_every), OFF(cup_integrator_options, output_samples),
        OFF(cup_integrator_options, f), OFF(cup_integrator_options, f_ctx),
        OFF(cup_integrator_options, f_order), OFF(cup_integrator_options, max_wall_seconds),
        OFF(cup_integrator_options, theta), OFF(cup_integrator_options, on_step), OFF(cup_integrator_options, step_ctx),
        OFF(cup_integrator_options, interrupt), OFF(cup_integrator_options, tol_abs),
        OFF(cup_integrator_options, tol_rel), OFF(cup_integrator_options, max_event_rate),
        OFF(cup_integrator_options, on_event), OFF(cup_integrator_options, event_ctx),
        OFF(cup_integrator_options, estimate), OFF(cup_integrator_options, hmax),
        OFF(cup_integrator_options, output_t0), OFF(cup_integrator_options, output_tol));
  if (!strcmp(name, "cup_run_info"))
    PUT(sizeof(cup_run_info), OFF(cup_run_info, status), OFF(cup_run_info, step),
        OFF(cup_run_info, t), OFF(cup_run_info, projected), OFF(cup_run_info, skipped),
        OFF(cup_run_info, not_certified), OFF(cup_run_info, dual_iterations),
        OFF(cup_run_info, factorizations), OFF(cup_run_info, max_eps_cert),
        OFF(cup_run_info, max_eta_cert), OFF(cup_run_info, eps_target),
        OFF(cup_run_info, eta_target), OFF(cup_run_info, h_rho), OFF(cup_run_info, samples),
        OFF(cup_run_info, message), OFF(cup_run_info, set_rebuilds), OFF(cup_run_info, max_rows),
        OFF(cup_run_info, err_est), OFF(cup_run_info, events), OFF(cup_run_info, rejected));
  if (!strcmp(name, "cup_set_desc"))
    PUT(sizeof(cup_set_desc), OFF(cup_set_desc, kind), OFF(cup_set_desc, n), OFF(cup_set_desc, p),
        OFF(cup_set_desc, P), OFF(cup_set_desc, C), OFF(cup_set_desc, F), OFF(cup_set_desc, G),
        OFF(cup_set_desc, center), OFF(cup_set_desc, Gc), OFF(cup_set_desc, radius),
        OFF(cup_set_desc, gr), OFF(cup_set_desc, Q), OFF(cup_set_desc, oracle),
        OFF(cup_set_desc, oracle_ctx), OFF(cup_set_desc, rows), OFF(cup_set_desc, rows_ctx));
  if (!strcmp(name, "cup_process_desc"))
    PUT(sizeof(cup_process_desc), OFF(cup_process_desc, n), OFF(cup_process_desc, p),
        OFF(cup_process_desc, C), OFF(cup_process_desc, u), OFF(cup_process_desc, A),
        OFF(cup_process_desc, E), OFF(cup_process_desc, f), OFF(cup_process_desc, f_ctx),
        OFF(cup_process_desc, f_integral), OFF(cup_process_desc, f_integral_ctx));
  return 0;
}

int cupt_status_merge(int a, int b) { return cup_status_merge(a, b); }

typedef struct { double *t, *X; long cap, count; } store;
static int store_sink(long k, double t, const double *x, void *vp) {
  (void)k;
  store *s = vp;
  if (s->count >= s->cap) return 1;
  s->t[s->count] = t;
  memcpy(s->X + 3 * s->count, x, 3 * sizeof(double));
  s->count++;
  return 0;
}

/* The paper's case 1 (R1=1, R2=2, R3=1, L2=1, L3=2, C4=1; u = 16 sin(6 pi t)
 * - 0.5; x0 = 0; T = 1) with n steps and the tolerance schedules eps, eta
 * ("n^-2.1", "0"), every step stored: t[n+1], X[3 (n+1)] (column-major
 * X(3, n+1) for Fortran). Returns the run status; *count the samples. */
int cupt_case1_c(long n, const char *eps, const char *eta, double *t, double *X, long *count) {
  cup_circuit c = {1, 2, 1, 1, 2, 1, {0, 0}};
  cup_lcs *L = NULL;
  cup_input *u = NULL;
  cup_integrator *I = NULL;
  int st = cup_lcs_circuit(&L, &c, NULL);
  if (!st) st = cup_input_create(&u, 1, NULL);
  cup_wave s = {.kind = CUP_WAVE_SINE, .amplitude = 16, .frequency = 3};
  cup_wave k = {.kind = CUP_WAVE_CONSTANT, .value = -0.5};
  if (!st) st = cup_input_add(u, 0, &s, NULL);
  if (!st) st = cup_input_add(u, 0, &k, NULL);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.n = n;
  o.T = 1;
  if (!st) st = cup_schedule_parse(eps, &o.eps, NULL);
  if (!st) st = cup_schedule_parse(eta, &o.eta, NULL);
  if (!st) st = cup_integrator_create(&I, L, u, &o, NULL);
  store sk = {t, X, n + 1, 0};
  double x0[3] = {0, 0, 0};
  cup_run_info info;
  if (!st) st = cup_integrator_run(I, x0, store_sink, &sk, &info);
  *count = sk.count;
  cup_integrator_free(&I);
  cup_input_free(&u);
  cup_lcs_free(&L);
  return st;
}

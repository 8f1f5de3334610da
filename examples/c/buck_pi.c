/* buck_pi — a digital PI voltage loop closed around the ideal CCM buck
 * (examples/circuits/buck-pi.cir) through cup_netlist_set_controller.
 *
 * The controller is called every ts = Tsw / M (Tsw = 10 us, M = 1000: a
 * duty resolution of 1e-3). At each call it samples v(out) and integrates the error,
 *     xi += ki ts (Vref - v),
 * and at the start of each switching period it latches the duty command
 *     d = clamp(kp (Vref - v) + xi, 0, 1)
 * and turns S1 on; S1 turns off when the sawtooth carrier j / M (j the
 * call's index within the period) passes d. IL steps the load by 1 A
 * halfway (2 ms): from 1 to 2 A at Vref = 5 V.
 *
 * Independent references, checked at the end of each half (the last 50
 * periods before the step and before the end): the integrator forces zero
 * average error, so the mean of the samples of v(out) is Vref; and the
 * inductor's volt-second balance of the lossless buck makes the mean duty
 * Vref / Vin whatever the load.
 *
 *     buck_pi [circuit.cir] [Vref] [periods.csv]
 *             (default examples/circuits/buck-pi.cir, 5 V, no file)
 *
 * Prints one line each 10 switching periods (mean v(out), duty, mean
 * i(L1) over the period) and the checks, writes every period to the CSV
 * file if given (scripts/plot_buck_pi.py draws it); exits 1 if a check fails
 * or the run does. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"

enum { M = 1000, PERIODS = 400, WINDOW = 50 };

typedef struct {
  double vin, vref, kp, ki, ts;
  int iv, ii;             /* state indices of v(C1) = v(out) and i(L1) */
  double xi, d;           /* integrator, latched duty */
  long p;                 /* completed periods */
  double acc_v, acc_i;    /* sums over the current period */
  int on;                 /* closed instants in the current period */
  double vmean[PERIODS], imean[PERIODS], duty[PERIODS];
} pi_ctl;

static double clamp01(double v) { return v < 0 ? 0 : v > 1 ? 1 : v; }

static int pi_gate(double t, const double *x, int nswitch, int *gate, void *ctx) {
  pi_ctl *c = ctx;
  if (nswitch != 1) return 1;
  long k = lround(t / c->ts);
  int j = (int)(k % M);
  if (j == 0 && k > 0 && c->p < PERIODS) {      /* close the period that just ended */
    c->vmean[c->p] = c->acc_v / M;
    c->imean[c->p] = c->acc_i / M;
    c->duty[c->p] = (double)c->on / M;
    c->p++;
    c->acc_v = c->acc_i = 0;
    c->on = 0;
  }
  double v = x[c->iv], e = c->vref - v;
  c->acc_v += v;
  c->acc_i += x[c->ii];
  c->xi = clamp01(c->xi + c->ki * c->ts * e);    /* clamped: no wind-up while saturated */
  if (j == 0) c->d = clamp01(c->kp * e + c->xi);
  gate[0] = (double)j < c->d * M;                /* on from the period's start until the carrier passes d */
  c->on += gate[0];
  return 0;
}

static int state_index(const cup_netlist *nl, int n, const char *name) {
  for (int j = 0; j < n; j++)
    if (!strcmp(cup_netlist_state_name(nl, j), name)) return j;
  return -1;
}

/* The means over periods [p0, p0 + WINDOW) against Vref and Vref / Vin. */
static int check(const pi_ctl *c, long p0, const char *what) {
  double v = 0, d = 0, lo = INFINITY, hi = -INFINITY;
  for (long p = p0; p < p0 + WINDOW; p++) {
    v += c->vmean[p] / WINDOW;
    d += c->duty[p] / WINDOW;
    lo = fmin(lo, c->vmean[p]);
    hi = fmax(hi, c->vmean[p]);
  }
  double ev = fabs(v - c->vref) / c->vref, ed = fabs(d - c->vref / c->vin);
  int ok = ev < 1e-3 && ed < 1.0 / M;
  printf("%s, periods %ld-%ld: mean v(out) %.6f V (Vref %.6f, rel. error %.1e, period means in "
         "[%.4f, %.4f]), mean duty %.5f (Vref/Vin %.5f, |error| %.1e): %s\n",
         what, p0, p0 + WINDOW - 1, v, c->vref, ev, lo, hi, d, c->vref / c->vin, ed, ok ? "ok" : "FAILED");
  return ok;
}

static int write_csv(const pi_ctl *c, const char *path) {
  FILE *f = fopen(path, "w");
  if (!f) {
    perror(path);
    return 1;
  }
  fprintf(f, "period,t_end,vout_mean,duty,iL_mean\n");
  for (long p = 0; p < PERIODS; p++)
    fprintf(f, "%ld,%.9e,%.9f,%.4f,%.9f\n", p, (p + 1) * 10e-6, c->vmean[p], c->duty[p], c->imean[p]);
  if (fclose(f)) {
    perror(path);
    return 1;
  }
  return 0;
}

int main(int argc, char **argv) {
  const char *path = argc > 1 ? argv[1] : "examples/circuits/buck-pi.cir";
  char err[CUP_ERRMSG_LEN] = "";
  cup_netlist *nl = NULL;
  if (cup_netlist_load(&nl, path, NULL, 0, err)) {
    fprintf(stderr, "buck_pi: %s\n", err);
    return 1;
  }
  static pi_ctl c;
  /* LC resonance 5 kHz (Q 1.6 at 5 ohm): the integral crossover Vin ki /
   * 2 pi ~ 1.5 kHz stays below it; kp damps the resonance. */
  c.vin = 12;
  c.vref = argc > 2 ? atof(argv[2]) : 5;
  c.kp = 0.05;
  c.ki = 800;
  c.ts = 10e-6 / M;
  int n = cup_lcs_dim(cup_netlist_lcs(nl));
  c.iv = state_index(nl, n, "v(C1)");
  c.ii = state_index(nl, n, "i(L1)");
  if (c.iv < 0 || c.ii < 0 || cup_netlist_switch_count(nl) != 1 || !(c.vref > 0 && c.vref < c.vin)) {
    fprintf(stderr, "buck_pi: %s: want states v(C1) (across out) and i(L1), one switch, 0 < Vref < 12\n", path);
    cup_netlist_free(&nl);
    return 1;
  }
  if (cup_netlist_set_controller(nl, c.ts, pi_gate, &c, err)) {
    fprintf(stderr, "buck_pi: %s\n", err);
    cup_netlist_free(&nl);
    return 1;
  }
  cup_switching sw;
  cup_netlist_switching(nl, &sw);
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_ADAPTIVE;
  o.T = PERIODS * 10e-6 + c.ts / 2;   /* the instant closing the last period is inside the run */
  o.tol_abs = o.tol_rel = 1e-9;
  o.output = CUP_OUTPUT_NONE;
  cup_integrator *I = NULL;
  cup_run_info info;
  int st = cup_integrator_create_switched(&I, &sw, cup_netlist_input(nl), &o, err);
  if (st) fprintf(stderr, "buck_pi: %s\n", err);
  else if ((st = cup_integrator_run(I, cup_netlist_x0(nl), NULL, NULL, &info)) < 0)
    fprintf(stderr, "buck_pi: %s\n", info.message);
  cup_integrator_free(&I);
  cup_netlist_free(&nl);
  if (st < 0 || c.p != PERIODS) {
    if (st >= 0) fprintf(stderr, "buck_pi: %ld periods recorded, want %d\n", c.p, PERIODS);
    return 1;
  }
  if (argc > 3 && write_csv(&c, argv[3])) return 1;
  printf("# period  t_end[s]  mean_v(out)[V]  duty  mean_i(L1)[A]\n");
  for (long p = 0; p < PERIODS; p += 10)
    printf("%6ld  %.6e  %.6f  %.2f  %.6f\n", p, (p + 1) * 10e-6, c.vmean[p], c.duty[p], c.imean[p]);
  int ok = check(&c, PERIODS / 2 - WINDOW, "before the load step") & check(&c, PERIODS - WINDOW, "after the load step");
  return ok ? 0 : 1;
}

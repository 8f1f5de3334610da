/* libFuzzer harness for the netlist reader and formulation
 * (cup_netlist_load_string).
 *
 * An input is a netlist's text. It is loaded without sets and with one of
 * a few fixed sets (elements and .params that the seeds define, and ones
 * they do not); a netlist that loads has every signal probed and evaluated
 * at a state of ones, and a small one is run for a few steps by the theta
 * scheme and, where catchup-run would choose it, for a short time by the
 * adaptive one at the tolerances of its .options (RELTOL, ABSTOL, VNTOL,
 * CHGTOL) and the TMAX of its .tran (scene_netlist_options). Every failure must be an error code with a one-line
 * message naming the input, *nl NULL after it; ASan, UBSan and
 * LeakSanitizer catch the rest. Build and run: README.md, "Fuzzing". */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "scene_netlist.h"
#include "fuzz_text.h"

static const char *const sets[4][3] = {
  {"R1=2k", "C1=1u", "vin=5"},
  {"V1=SIN(0 5 50)", "D1=1", "Rs=0"},
  {"L1={1m*2}", "R9=1", "u0=-1"},
  {"V1=PULSE(0 1 1m 0 0 2m 5m)", "RL=1meg", "C1=1e999"},
};

static void check_message(int st, const char *err) {
  if (st >= 0) return;
  /* one line, naming the input (or, for an error in a file it includes, that file: "PATH:LINE:COL: ...") */
  if (!err[0] || strchr(err, '\n') || (strncmp(err, "fuzz.cir", 8) && !strstr(err, ":"))) abort();
}

/* A run with options o (a switched circuit's through its configurations):
 * it stops with a message, or its creation fails with one line. */
static void run_with(cup_netlist *nl, const cup_integrator_options *o) {
  char err[CUP_ERRMSG_LEN] = "";
  cup_integrator *I = NULL;
  cup_switching sw; /* switches: each configuration formed as it occurs */
  int made = cup_netlist_switching(nl, &sw) ? cup_integrator_create_switched(&I, &sw, cup_netlist_input(nl), o, err)
                                            : cup_integrator_create(&I, cup_netlist_lcs(nl), cup_netlist_input(nl), o, err);
  if (made == CUP_OK) {
    cup_run_info info;
    cup_integrator_run(I, cup_netlist_x0(nl), NULL, NULL, &info);
    if (info.status < 0 && !info.message[0]) abort();
    cup_integrator_free(&I);
  } else if (!err[0] || strchr(err, '\n')) {
    abort();
  }
}

/* Signals at a state of ones, and a few steps of the default scheme. */
static void exercise(cup_netlist *nl) {
  char err[CUP_ERRMSG_LEN] = "";
  const cup_lcs *L = cup_netlist_lcs(nl);
  int n = cup_lcs_dim(L), m = cup_lcs_rows(L);
  if (cup_netlist_probe(nl, "all", err) < 0) check_message(-1, err);
  int ns = cup_netlist_signal_count(nl);
  double *x = malloc(sizeof(double) * ((size_t)n + 1)), *z = malloc(sizeof(double) * ((size_t)m + 1));
  double *out = malloc(sizeof(double) * ((size_t)ns + 1));
  if (x && z && out) {
    for (int j = 0; j < n; j++) x[j] = 1;
    for (int i = 0; i < m; i++) z[i] = 1;
    cup_netlist_signals(nl, 0.5, x, z, out);
  }
  free(x); free(z); free(out);
  if (n > 16 || m > 16) return;
  cup_integrator_options o;
  cup_integrator_options_default(&o);
  o.scheme = CUP_SCHEME_THETA;
  o.n = 4;
  o.T = 1e-3;
  o.output = CUP_OUTPUT_NONE;
  o.proj.max_iter = 200;
  run_with(nl, &o);
  /* the scheme, tol, samples and TMAX catchup-run takes from .tran and
   * .options (scene_netlist_options: the adaptive scheme where it fits, D
   * != 0 too), over a short time with a wall-time cap */
  double tstart = 0, tmax = 0;
  cup_netlist_tran_window(nl, &tstart, &tmax);
  if (!(tstart >= 0) || !(tmax >= 0)) abort();
  cup_integrator_options_default(&o);
  scene_netlist_options(nl, &o);
  if (!(o.tol_abs > 0) || !(o.tol_rel > 0) || !(o.hmax >= 0)) abort();
  if (o.scheme != CUP_SCHEME_ADAPTIVE) return;
  o.T = o.T > 0 ? fmin(o.T, 1e-4) : 1e-4;
  o.output = CUP_OUTPUT_SAMPLES;
  o.output_t0 = 0;
  o.output_samples = 5;
  o.max_wall_seconds = 0.5;
  run_with(nl, &o);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = fuzz_text(data, size);
  if (!text) return 0;
  cup_netlist *nl = NULL;
  char err[CUP_ERRMSG_LEN] = "";
  int st = cup_netlist_load_string(&nl, text, "fuzz.cir", NULL, 0, err);
  check_message(st, err);
  if (st == CUP_OK) exercise(nl);
  else if (nl) abort();                          /* a failed load leaves NULL */
  cup_netlist_free(&nl);
  unsigned sel = size ? data[size / 2] % 4 : 0;
  st = cup_netlist_load_string(&nl, text, "fuzz.cir", sets[sel], 3, err);
  check_message(st, err);
  if (st != CUP_OK && nl) abort();
  cup_netlist_free(&nl);
  free(text);
  return 0;
}

/* paper — the paper's circuit (Sec. 7, Fig. 2, R = L = C = 1, tested in
 * its two cases): the LCS and the input of each case, built through the
 * public API only, for the benchmarks (catchup-bench) and the tests: one
 * copy. Header only. Case 1: u(t) = 16 sin(6 pi t) - 0.5 and F = 0; case 2:
 * a unit square wave of 2 Hz and F = (0, 1). */
#ifndef CUP_BENCH_PAPER_H
#define CUP_BENCH_PAPER_H

#include "catchup.h"

/* The input of case cas (1 or 2); NULL when out of memory. */
static inline cup_input *paper_input(int cas) {
  cup_input *u = NULL;
  if (cup_input_create(&u, 1, NULL)) return NULL;
  if (cas == 1) {
    cup_wave s = {.kind = CUP_WAVE_SINE, .amplitude = 16, .frequency = 3};
    cup_wave c = {.kind = CUP_WAVE_CONSTANT, .value = -0.5};
    cup_input_add(u, 0, &s, NULL);
    cup_input_add(u, 0, &c, NULL);
  } else {
    cup_wave q = {.kind = CUP_WAVE_SQUARE, .amplitude = 1, .frequency = 2};
    cup_input_add(u, 0, &q, NULL);
  }
  return u;
}

/* The LCS of case cas into *L; the status, with its message in errmsg (may
 * be NULL). */
static inline int paper_lcs(cup_lcs **L, int cas, char *errmsg) {
  cup_circuit c = {1, 2, 1, 1, 2, 1, {0, cas == 2 ? 1 : 0}};
  *L = NULL;
  return cup_lcs_circuit(L, &c, errmsg);
}

#endif

/* The exact reference of an example circuit (tests/pwl_circuits.h) on a
 * uniform grid, for the scripts (scripts/bench-converters):
 *
 *   pwl_ref_dump NAME [T [SAMPLES]]      (T: the netlist's TSTOP; 10001 samples)
 *
 * prints "t x_0 x_1 ..." per line (%.17g), and on stderr the pieces,
 * events and jumps. */
#include <stdio.h>
#include "pwl_circuits.h"

int main(int argc, char **argv) {
  static pr_circuit c;
  double y0[PR_Y], T;
  if (argc < 2 || pc_example(argv[1], &c, y0, &T)) {
    fprintf(stderr, "usage: pwl_ref_dump NAME [T [SAMPLES]] (NAME: an example of tests/pwl_circuits.h)\n");
    return 2;
  }
  if (argc > 2) T = atof(argv[2]);
  long ns = argc > 3 ? atol(argv[3]) : 10001;
  pr_traj tr;
  int st = pr_solve(&c, y0, T, &tr);
  if (st) { fprintf(stderr, "pwl_ref_dump: %s: no topology continues (%d)\n", argv[1], st); return 1; }
  fprintf(stderr, "%s: %d pieces, %d events, %d jumps\n", argv[1], tr.nseg, tr.events, tr.jumps);
  for (long k = 0; k < ns; k++) {
    double t = ns > 1 ? T * k / (ns - 1) : T, x[PR_Y];
    pr_eval(&tr, t, x);
    printf("%.17g", t);
    for (int i = 0; i < c.n; i++) printf(" %.17g", x[i]);
    printf("\n");
  }
  pr_free(&tr);
  return 0;
}

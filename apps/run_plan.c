/* run_plan — see run_plan.h. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include "catchup/h5run.h"
#include "h5/h5util.h"
#include "run_plan.h"

enum { OVERHEAD = 1 << 16 };    /* attributes, the scene's text, metadata: well under 64 KiB */

void run_plan_make(run_plan *p, const cup_integrator_options *o, int dim, int nsig, double per_step) {
  int adaptive = o->scheme == CUP_SCHEME_ADAPTIVE;
  double n = (double)o->n;
  p->steps = adaptive ? NAN : o->estimate ? 1.5 * n : n;
  switch (o->output) {
    case CUP_OUTPUT_EVERY:
      p->samples = adaptive ? NAN : floor(n / (double)o->output_every) + 1 + (o->n % o->output_every != 0);
      break;
    case CUP_OUTPUT_SAMPLES: p->samples = (double)o->output_samples; break;
    case CUP_OUTPUT_FINAL: p->samples = 1; break;
    case CUP_OUTPUT_TOL: p->samples = NAN; break;  /* (the points the waveform needs: not known before) */
    default: p->samples = 0; break;
  }
  p->samples += 1;                                 /* a stop's flagged row */
  p->bytes = p->samples * 8.0 * (dim + 1 + nsig) + (adaptive ? 0 : n * per_step) + OVERHEAD;
}

int run_plan_too_long(const run_plan *p, const cup_integrator_options *o, long max_steps, const char *n_from,
                      const char *adaptive, char *msg, size_t size) {
  if (!(p->steps > (double)max_steps)) return 0;
  snprintf(msg, size, "n = %.4g steps (%s) exceed the limit of %ld (--max-steps, the scene key max_steps): "
           "take fewer steps, or the adaptive scheme with an error target (%s), and store fewer samples "
           "(output.samples)", (double)o->n, n_from, max_steps, adaptive);
  return 1;
}

int run_plan_no_room(double bytes, const char *out, char *msg, size_t size) {
  double avail = 0;                                /* NaN bytes, or a device that reports no size: */
  if (!h5_space_short(out, 1, bytes, &avail)) return 0;   /* checked as the file grows */
  snprintf(msg, size, "the output needs about %.4g MiB and %u MiB kept free beside it, and the device of %s has "
           "%.4g MiB free: store fewer samples (output.samples, output.every) or write elsewhere",
           bytes / 1048576, CUP_H5_SPACE_MARGIN >> 20, out, avail / 1048576);
  return 1;
}

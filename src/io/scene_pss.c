/* scene_pss — a scene's steady state, solved the one way catchup-run and
 * the steady-state sweeps solve it (scene_pss.h). */
#include <stddef.h>
#include "catchup.h"
#include "scene_pss.h"
#include "analysis/pss_run.h"

int scene_pss_solve(cup_scene *s, const cup_integrator_options *o, cup_pss **r, double *T, double *t0,
                    cup_integrator_options *period, int *stage, char *errmsg) {
  const cup_scene_steady *q = cup_scene_steady_state(s);
  *r = NULL;
  *stage = SCENE_PSS_PHASE;
  int st = cup_scene_steady_phase(s, q->pss.period, T, t0, errmsg);   /* the sources from t0 on */
  if (st) return st;
  *stage = SCENE_PSS_SETUP;
  cup_integrator_options mo;                      /* the period map: the run's, over one period */
  pss_map_options(o, cup_scene_options(s)->T, *T, q->pss.map_tol, &mo);
  mo.on_step = NULL;
  cup_integrator *I = NULL;
  st = cup_scene_integrator(s, &mo, &I, errmsg);
  if (!st) {
    *stage = SCENE_PSS_NEWTON;
    st = cup_pss_solve_map(r, I, cup_scene_dim(s), *T, cup_scene_x0(s), &q->pss, errmsg);
  }
  cup_integrator_free(&I);
  if (st < 0) {
    cup_scene_set_time_origin(s, 0, NULL);       /* no steady state: the sources as written */
    return st;
  }
  *period = mo;                                   /* one period, as accurate as the steady state */
  period->output = CUP_OUTPUT_SAMPLES;
  period->output_samples = q->samples;
  period->output_t0 = 0;
  return st;
}

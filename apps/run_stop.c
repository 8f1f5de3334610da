/* run_stop — see run_stop.h. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "io/read_text.h"
#include "run_stop.h"

int run_stop_save(cup_h5run *w, const cup_integrator *I, const cup_run_info *info, const run_signals *s,
                  int *resumable) {
  *resumable = 0;
  long size = cup_integrator_checkpoint_size(I);
  int st = CUP_OK;
  if (size > 0) {
    void *blob = malloc((size_t)size);
    st = blob ? cup_integrator_checkpoint_save(I, info, blob, (unsigned long)size) : CUP_ERR_NOMEM;
    if (!st) st = cup_h5run_put_checkpoint(w, blob, (unsigned long)size);
    *resumable = st == CUP_OK;
    free(blob);
  }
  /* the state where it stopped, flagged: its signals with zeta of the step
   * that reached it (zeros for the adaptive scheme, whose multipliers are
   * taken at output times) */
  const double *x = cup_integrator_state(I);
  long row = cup_h5run_count(w);
  int ast = CUP_OK;
  if (s->nl) {
    cup_integrator_zeta(I, s->zeta);
    ast = cup_netlist_signals(s->nl, info->t, x, s->zeta, s->sig);
  }
  if (!ast) ast = cup_h5run_append(w, info->t, x, s->nl ? s->sig : NULL);
  if (!ast) ast = cup_h5run_attr_long(w, "stop_row", row);
  return cup_status_merge(st, ast);
}

int run_stop_clear(cup_h5run *w) {
  return cup_status_merge(cup_h5run_drop_checkpoint(w), cup_h5run_drop_attr(w, "stop_row"));
}

/* The file continues this run: the same scene text (overrides included)
 * and the same bytes in every file read (by position, so that another
 * working folder does not matter). */
static int same_run(cup_h5run *w, const char *out, const cup_scene *sc, char *err, size_t size) {
  char *text = NULL, *inputs = NULL;
  int st = CUP_OK;
  if (cup_h5run_get_string(w, "scene", &text) || cup_h5run_get_string(w, "inputs_sha256", &inputs)) {
    snprintf(err, size, "%s: cannot resume: it does not say what it ran (no scene or inputs_sha256 attribute)", out);
    st = CUP_ERR_ARG;
  } else if (strcmp(text, cup_scene_text(sc))) {
    snprintf(err, size, "%s: cannot resume: it ran another scene (the scene file or the overrides changed: its "
             "attribute scene holds what it ran)", out);
    st = CUP_ERR_ARG;
  } else {
    int w0 = snprintf(err, size, "%s: cannot resume: ", out);
    if (file_list_compare(scene_file_list(sc), inputs, "the file", err + w0, size - (size_t)w0)) st = CUP_ERR_ARG;
    else err[0] = '\0';
  }
  free(text);
  free(inputs);
  return st;
}

int run_stop_reopen(const char *out, const cup_scene *sc, cup_integrator *I, const run_signals *s, cup_h5run **w,
                    double *wall, char *err, size_t size) {
  if (cup_integrator_checkpoint_size(I) == CUP_ERR_UNSUPPORTED)   /* before the file is touched: it never holds one */
    return snprintf(err, size, "%s: cannot resume: it has no checkpoint: a run of this kind keeps none (a crowd "
                    "or another set that is not a polyset, or a circuit with switches): run it again without "
                    "--resume", out), CUP_ERR_UNSUPPORTED;
  int nsig = s->nl ? cup_netlist_signal_count(s->nl) : 0;
  const char **names = calloc((size_t)nsig + 1, sizeof *names);
  char e2[CUP_ERRMSG_LEN];
  if (!names) return snprintf(err, size, "%s: out of memory", out), CUP_ERR_NOMEM;
  for (int k = 0; k < nsig; k++) names[k] = cup_netlist_signal_name(s->nl, k);
  int st = cup_h5run_open(w, out, cup_scene_dim(sc), nsig, names, e2);
  free(names);
  if (st) return snprintf(err, size, "%s", e2), st;
  if ((st = same_run(*w, out, sc, err, size))) return st;
  void *blob = NULL;
  unsigned long bytes = 0;
  long rows = 0, events = 0;
  st = cup_h5run_get_checkpoint(*w, &blob, &bytes, &rows, &events);
  if (st) {
    snprintf(err, size, "%s: cannot resume: it has no checkpoint (the run finished, failed, or was killed "
             "before it could save one): run without --resume", out);
    return st;
  }
  st = cup_integrator_checkpoint_restore(I, blob, bytes, e2);
  free(blob);
  if (st) return snprintf(err, size, "%s: cannot resume: %s", out, e2), st;
  if (cup_h5run_get_double(*w, "wall_time_s", wall)) *wall = 0;
  st = cup_h5run_truncate(*w, rows, events);
  if (!st) st = cup_h5run_drop_attr(*w, "stop_row");
  if (st) {                                      /* the writer's words */
    e2[0] = '\0';
    cup_h5run_status(*w, e2);
    snprintf(err, size, "%s", e2);
  }
  return st;
}

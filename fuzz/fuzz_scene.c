/* libFuzzer harness for the scene loader (cup_scene_load_string).
 *
 * An input is YAML text, optionally followed by a line "#%mtx" and the text
 * of a Matrix Market file, which is written to a private directory as
 * f.mtx (so that `{file: f.mtx}` in the YAML reads it: the Matrix Market
 * reader is fuzzed too). Each input is loaded without overrides and then
 * with one of a few fixed override sets; a scene that loads is re-loaded
 * from its cup_scene_text() (the round trip must load), and a small one is
 * run for two steps with a capped projector. The same text is also parsed
 * as a catchup-sweep file (sw_parse; the base scenes are not read). Build
 * and run: README.md,
 * "Numerical robustness" / "Fuzzing". Every failure must be an error code
 * with a one-line message; ASan, UBSan and LeakSanitizer catch the rest. */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "catchup.h"
#include "sweep.h"
#include "fuzz_text.h"

static char dir[] = "/tmp/cup_fuzz_XXXXXX";
static char mtx_path[64];

static const char *const overrides[5][4] = {
  {"n=7", "x0=[0, 1, 0]", "circuit.R1=2", "output.every=3"},
  {"input.0.amplitude=8", "eps=1e-6", "lcs.A.1.2=0.25", "scheme = implicit"},
  {"lcs.F=[.nan]", "T.x=1", "name='x: \"y\"'", "input=[1, 2]"},
  {"projector={method: pg, max_iter: 5}", "output={samples: 3}", "x0={file: f.mtx}", "lcs.P=identity"},
  {"set.ball.radius=-1", "f.A=[[1]]", "set.ball.center.0={type: pwl, points: [[0, 0]]}", "f.towards.speed=2"},
};

static void cleanup(void) {
  unlink(mtx_path);
  rmdir(dir);
}

int LLVMFuzzerInitialize(int *argc, char ***argv) {
  (void)argc; (void)argv;
  if (!mkdtemp(dir)) abort();
  snprintf(mtx_path, sizeof mtx_path, "%s/f.mtx", dir);
  atexit(cleanup);
  return 0;
}

static void check_message(int st, const char *err) {
  if (st >= 0) return;
  if (!err[0] || strchr(err, '\n')) abort();     /* a one-line message, always */
}

/* Two steps of a small loaded scene: the numerics must fail cleanly too. */
static void run_briefly(const char *text, const char *d) {
  static const char *const cap[] = {"n=2", "T=1", "output=final",
                                    "projector={method: auto, max_iter: 200}"};
  cup_scene *s = NULL;
  char err[CUP_ERRMSG_LEN] = "";
  if (cup_scene_load_string(&s, text, "run.yaml", d, cap, 4, err) != CUP_OK) return;
  const cup_lcs *L = cup_scene_lcs(s);
  if (cup_scene_dim(s) <= 16 && (!L || cup_lcs_rows(L) <= 16)) {   /* an LCS or a set: scene */
    cup_integrator *I = NULL;
    if (cup_scene_integrator(s, NULL, &I, err) == CUP_OK) {
      cup_run_info info;
      cup_integrator_run(I, cup_scene_x0(s), NULL, NULL, &info);
      if (info.status < 0 && !info.message[0]) abort();
      cup_integrator_free(&I);
    } else {
      check_message(-1, err);
    }
  }
  cup_scene_free(&s);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  char *text = fuzz_text(data, size);
  if (!text) return 0;
  const char *d = "/nonexistent";
  char *mtx = strstr(text, "\n#%mtx\n");
  unlink(mtx_path);
  if (mtx) {
    *mtx = '\0';
    mtx += 7;
    FILE *f = fopen(mtx_path, "w");
    if (f) { fputs(mtx, f); fclose(f); }
    d = dir;
  }
  cup_scene *s = NULL;
  char err[CUP_ERRMSG_LEN] = "";
  int st = cup_scene_load_string(&s, text, "fuzz.yaml", d, NULL, 0, err);
  check_message(st, err);
  if (st == CUP_OK) {
    cup_scene *t = NULL;                           /* the round trip loads */
    char err2[CUP_ERRMSG_LEN] = "";
    if (cup_scene_load_string(&t, cup_scene_text(s), "fuzz.yaml", d, NULL, 0, err2) != CUP_OK) abort();
    cup_scene_free(&t);
    cup_scene_free(&s);
    run_briefly(text, d);
  }
  if (s) abort();                                  /* a failed load leaves NULL */
  unsigned sel = size ? data[size / 2] % 5 : 0;
  st = cup_scene_load_string(&s, text, "fuzz.yaml", d, overrides[sel], 4, err);
  check_message(st, err);
  cup_scene_free(&s);
  {                                                /* the same input as a sweep file */
    sw_sweep *w = NULL;
    char werr[SW_ERR_LEN] = "";
    st = sw_parse(&w, text, strlen(text), "fuzz-sweep.yaml", werr);
    check_message(st, werr);
    if (st == CUP_OK) {
      char *grid = sw_grid_text(w);
      free(grid);
    } else if (w) {
      abort();                                     /* a failed parse leaves NULL */
    }
    sw_free(&w);
  }
  free(text);
  return 0;
}

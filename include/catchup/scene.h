/* catchup/scene.h — scene files (YAML): an LCS (or the paper's circuit as a
 * parameterised family) and its input, a general sweeping process (a moving
 * set and f) or a crowd (catchup/crowd.h); x0, T, n, tolerances, scheme,
 * projector and output. The format is documented in docs/scene-format.md
 * (crowds: docs/crowd.md). Every error names
 * file:line:column and the key. */
#ifndef CATCHUP_SCENE_H
#define CATCHUP_SCENE_H

#include "catchup/export.h"
#include "catchup/integrator.h"
#include "catchup/crowd.h"
#include "catchup/netlist.h"
#include "catchup/pss.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cup_scene cup_scene;

/** Load a scene. overrides (may be NULL) are "dotted.key=value" strings
 *  applied to the document before it is read, value parsed as YAML
 *  ("circuit.R1=2", "n=1000", "input.0.amplitude=8", "x0=[0, 1, 0]"). Matrix
 *  Market files named in the scene are found relative to its directory. */
CUP_API int cup_scene_load(cup_scene **s, const char *path, const char *const *overrides,
                           int n_overrides, char *errmsg);
/** The same from text; `name` is used in messages in place of a file name
 *  and `dir` (may be NULL: the working directory) to find Matrix Market files. */
CUP_API int cup_scene_load_string(cup_scene **s, const char *text, const char *name, const char *dir,
                                  const char *const *overrides, int n_overrides, char *errmsg);
CUP_API void cup_scene_free(cup_scene **s);

CUP_API const char *cup_scene_name(const cup_scene *s);          /**< the `name` key, or the file stem */
CUP_API const cup_lcs *cup_scene_lcs(const cup_scene *s);           /**< NULL for a set: scene */
/** The general process of a set: scene (set and f; NULL for an LCS scene). */
CUP_API const cup_process_desc *cup_scene_process(const cup_scene *s);
/** The crowd of a crowd: scene (NULL otherwise); it belongs to the scene.
 *  Its process is cup_scene_process's, its x0 the agents' centres. */
CUP_API cup_crowd *cup_scene_crowd(const cup_scene *s);
/** The state dimension, for either kind of scene. */
CUP_API int cup_scene_dim(const cup_scene *s);
/** An integrator for the scene's model, an LCS or a process, with options o
 *  (NULL: the scene's). One integrator of a set: scene with f: towards at a
 *  time (its f keeps a buffer in the scene). */
CUP_API int cup_scene_integrator(const cup_scene *s, const cup_integrator_options *o, cup_integrator **I,
                                 char *errmsg);
CUP_API const cup_input *cup_scene_input(const cup_scene *s);    /**< NULL when p = 0; a set: scene's signals */
CUP_API const double *cup_scene_x0(const cup_scene *s);          /**< n entries */
/** T, n, eps, eta, scheme, projector, output from the file. */
CUP_API const cup_integrator_options *cup_scene_options(const cup_scene *s);
CUP_API const char *cup_scene_eps_spec(const cup_scene *s);      /**< as written, e.g. "n^-2.1" */
CUP_API const char *cup_scene_eta_spec(const cup_scene *s);
/** The default of the scene key max_steps: a fixed-step run of more steps
 *  is refused by catchup-run and catchup-sweep before its first step (a
 *  netlist's `.tran 1f 1k` asks for 10^18). 10^9 steps take under a minute
 *  on the paper's circuit, the cheapest there is (10^8: 4.2-5.1 s, output:
 *  final, on a shared 2-core machine), and hours on most others. */
#define CUP_MAX_STEPS_DEFAULT 1000000000L
/** The scene's max_steps (CUP_MAX_STEPS_DEFAULT when it has none). */
CUP_API long cup_scene_max_steps(const cup_scene *s);
/** The document after overrides, as YAML text (for provenance attributes). */
CUP_API const char *cup_scene_text(const cup_scene *s);
/** The files the scene was read from, in the order first read, each once:
 *  the scene file (none for cup_scene_load_string), the Matrix Market
 *  files it names, its netlist and what that includes. k in [0, count). */
CUP_API int cup_scene_file_count(const cup_scene *s);
/** File k's path as it was opened (NULL for k out of range). */
CUP_API const char *cup_scene_file(const cup_scene *s, int k);
/** The SHA-256 (64 lowercase hex digits) of the bytes of file k that were
 *  read: what the scene holds, whatever the file says now. */
CUP_API const char *cup_scene_file_sha256(const cup_scene *s, int k);
/** CUP_ERR_ARG, with a message naming both, when the output path names one
 *  of the scene's files: the same path once resolved (path need not exist),
 *  or the same file (device and inode, now or when it was read: hard links,
 *  symbolic links). CUP_OK otherwise. For a program's -o, before it writes. */
CUP_API int cup_scene_check_output(const cup_scene *s, const char *path, char *errmsg);
/** The name and unit of state component j (0-based), for files and plots:
 *  the paper's circuit "q(C4)" (C), "i(L3)", "i(L2)" (A); a netlist's
 *  "i(L1)" (A), "v(C1)" (V); a crowd's "x0", "y0", "x1", ... (m); any other
 *  model "x1", "x2", ... with unit "1" (the model's own units). */
CUP_API int cup_scene_state_label(const cup_scene *s, int j, char *name, unsigned long size, const char **unit);
/** The scene's netlist when its model is `netlist:` (NULL otherwise), owned
 *  by the scene; its LCS and input are the scene's. Signals are added to it
 *  (cup_netlist_probe), so it is not const. */
CUP_API cup_netlist *cup_scene_netlist(const cup_scene *s);

/** The steady-state request: the key steady_state: (docs/steady-state.md). */
typedef struct cup_scene_steady {
  cup_pss_options pss;   /**< period (0: the sources' common period), tol, max_iter, map_tol,
                              fd_step, warmup_periods (its samples: the field below) */
  long samples;          /**< the period's samples written (default 2001) */
  int harmonics;         /**< the harmonics' and THD's order (default 10; 0: none) */
  int fallback;          /**< 1 (default): when there is no steady state, run the transient */
  int nmeasure;          /**< the netlist signals measured ("v(out)", checked against the netlist);
                              0: every recorded signal (or, without a netlist, every state) */
  const char *const *measure;
  int npower;            /**< netlist elements whose average power v(a,b) i(E) is measured */
  const char *const *power;        /**< their names */
  int eff_out, eff_in;   /**< efficiency = P(power[eff_out]) / -P(power[eff_in]), the output's
                              absorbed power over the power the input delivers; -1: none */
} cup_scene_steady;

/** Read the scene's sources from t0 >= 0 on (cup_netlist_set_time_origin,
 *  phases and delays moved): integrators made after this run from t0 of the sources
 *  as written; 0 puts them back. CUP_ERR_UNSUPPORTED for t0 != 0 and a
 *  set: or crowd: scene. */
CUP_API int cup_scene_set_time_origin(cup_scene *s, double t0, char *errmsg);
/** The steady state's period and phase (cup_input_steady_phase of the
 *  sources as written; period the one asked for, or 0: the sources') into
 *  *T and *t0, and the time origin set to t0: the period map is a run from
 *  t = 0 of an integrator made after this call. */
CUP_API int cup_scene_steady_phase(cup_scene *s, double period, double *T, double *t0, char *errmsg);

/** The scene's steady-state request, or NULL when it asks for none. */
CUP_API const cup_scene_steady *cup_scene_steady_state(const cup_scene *s);

#ifdef __cplusplus
}
#endif
#endif

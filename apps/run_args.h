/* run_args — catchup-run's command line (run_args.c): the flags parsed and
 * checked, their values as the scene's overrides ("key=value"). */
#ifndef CUP_RUN_ARGS_H
#define CUP_RUN_ARGS_H

enum { EXIT_RUN = 1, EXIT_USAGE = 2 };

typedef struct {
  const char *scene, *out;
  char **overrides;          /* "key=value", owned, in command-line order */
  int n_overrides;
  const char **probes;       /* --probe values (argv's) */
  int n_probes;
  int quiet, resume;
} run_args;

/* Parse argv into a (release it with run_args_free whatever this returns).
 * Returns -1 to go on, else the exit status: 0 after --help or --version
 * (printed to stdout), EXIT_USAGE after a usage error (one stderr line). */
int run_args_parse(run_args *a, int argc, char **argv);
void run_args_free(run_args *a);

#endif

/* run_args — catchup-run's command line: its --help text, the flags
 * checked one by one (a typo is a usage error naming the flag, exit 2, not a
 * scene error), the value flags turned into the scene's overrides in
 * command-line order, --version. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"
#include "catchup/h5run.h"
#include "run_args.h"

/* "a, b, c or d" from a choice list of the library (CUP_*_LIST). */
static const char *names_or(char *buf, size_t size, const char *(*name)(int), int count) {
  size_t len = 0;
  buf[0] = '\0';
  for (int k = 0; k < count && len < size; k++)
    len += (size_t)snprintf(buf + len, size - len, "%s%s", k == 0 ? "" : k + 1 < count ? ", " : " or ", name(k));
  return buf;
}

static void print_usage(void) {
  char schemes[160], methods[160];
  printf("usage: catchup-run SCENE.yaml -o OUT.h5 [--n N | --h STEP] [--eps SPEC] [--eta SPEC]\n"
         "                   [--scheme NAME] [--projector NAME] [--tol TOL] [--estimate]\n"
         "                   [--max-steps N] [--set key=value]... [--resume] [--quiet]\n"
         "                   [--steady-state [--period T]]\n"
         "       catchup-run CIRCUIT.cir -o OUT.h5 [--probe SIGNAL]... [the same options]\n"
         "  -o, --output OUT.h5  HDF5 file to write (/t, /x, /events and attributes); replaced\n"
         "  --probe SIGNAL       a netlist's v(NODE), v(NODE1,NODE2), i(ELEMENT) or all, into\n"
         "                       /signals (repeatable; default: the netlist's .probe lines, or\n"
         "                       every signal of a circuit with at most 256)\n"
         "  --n N                number of steps of a fixed-step scheme (scene key n)\n"
         "  --h STEP             or its step: n = T / STEP rounded up (scene key h)\n"
         "  --eps SPEC           eps_n schedule, e.g. n^-2.1 or 1e-8 (scene key eps)\n"
         "  --eta SPEC           eta_n schedule, e.g. n^-1.05 (scene key eta)\n"
         "  --scheme NAME        %s (scene key scheme)\n"
         "  --projector NAME     %s (scene key projector.method)\n"
         "  --tol TOL            adaptive scheme: error target on x, absolute and relative (scene key tol)\n"
         "  --estimate           fixed-step schemes: estimate the error by step doubling (scene key estimate)\n"
         "  --max-steps N        refuse a fixed-step run of more than N steps (scene key max_steps;\n"
         "                       default %ld)\n"
         "  --set key=value      set any scene key (dotted path, value in YAML), repeatable\n"
         "  --steady-state       the periodic steady state: one period from it, its Floquet multipliers and\n"
         "                       measurements (scene key steady_state; docs/steady-state.md)\n"
         "  --period T           its period (scene key steady_state.period; default: the sources')\n"
         "  --resume             continue OUT.h5, stopped by SIGINT/SIGTERM, with the same scene,\n"
         "                       inputs and options, to the same trajectory bit for bit\n"
         "  --quiet              no summary line (warnings and errors are still printed)\n"
         "  -h, --help           this text;  --version  the library versions\n",
         names_or(schemes, sizeof schemes, cup_scheme_name, CUP_SCHEME_COUNT),
         names_or(methods, sizeof methods, cup_proj_method_name, CUP_PROJ_METHOD_COUNT), CUP_MAX_STEPS_DEFAULT);
}

__attribute__((format(printf, 1, 2)))
static int usage_error(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fputs("catchup-run: ", stderr);
  vfprintf(stderr, fmt, ap);
  fputs(" (catchup-run --help for usage)\n", stderr);
  va_end(ap);
  return EXIT_USAGE;
}

static int add_override(run_args *a, const char *key, const char *value) {
  size_t len = strlen(key) + strlen(value) + 2;
  char *s = malloc(len);
  if (!s) return usage_error("out of memory");
  snprintf(s, len, "%s%s", key, value);
  a->overrides[a->n_overrides++] = s;
  return 0;
}

/* Check a flag's value before it reaches the scene, so that a typo is a
 * usage error naming the flag rather than a scene error. */
static int check_value(const char *flag, const char *v) {
  char err[CUP_ERRMSG_LEN] = "";
  cup_schedule sch;
  char *end = NULL;
  if (strcmp(flag, "--n") == 0) {
    /* as the scene's n: "1e7" is accepted when it is an exact integer */
    double n = strtod(v, &end);
    if (end == v || *end || !(n >= 1) || n > 9007199254740992.0 || n != floor(n))
      return usage_error("--n '%s': not a positive integer", v);
  } else if (strcmp(flag, "--eps") == 0 || strcmp(flag, "--eta") == 0) {
    if (cup_schedule_parse(v, &sch, err) != CUP_OK) return usage_error("%s: %s", flag, err);
  } else if (strcmp(flag, "--scheme") == 0) {
    if (cup_scheme_parse(v) < 0)
      return usage_error("--scheme '%s': unknown scheme (%s)", v,
                         names_or(err, sizeof err, cup_scheme_name, CUP_SCHEME_COUNT));
  } else if (strcmp(flag, "--projector") == 0) {
    if (cup_proj_method_parse(v) < 0)
      return usage_error("--projector '%s': unknown projector (%s)", v,
                         names_or(err, sizeof err, cup_proj_method_name, CUP_PROJ_METHOD_COUNT));
  } else if (strcmp(flag, "--h") == 0) {
    double h = strtod(v, &end);
    if (end == v || *end || !(h > 0) || !(h < 1e300)) return usage_error("--h '%s': not a positive number", v);
  } else if (strcmp(flag, "--tol") == 0 || strcmp(flag, "--period") == 0) {
    double tol = strtod(v, &end);
    if (end == v || *end || !(tol > 0) || !(tol < 1e300))
      return usage_error("%s '%s': not a positive number", flag, v);
  } else if (strcmp(flag, "--max-steps") == 0) {
    double n = strtod(v, &end);
    if (end == v || *end || !(n >= 1) || n > 9.2e18 || n != floor(n))
      return usage_error("--max-steps '%s': not a positive integer", v);
  } else if (strcmp(flag, "--set") == 0) {
    const char *eq = strchr(v, '=');
    if (!eq || eq == v) return usage_error("--set '%s': expected key=value", v);
  }
  return 0;
}

/* The scene key each value flag sets; --set passes key=value through. */
static const struct { const char *flag, *key; } value_flags[] = {
  {"--n", "n="}, {"--h", "h="}, {"--eps", "eps="}, {"--eta", "eta="}, {"--scheme", "scheme="},
  {"--projector", "projector.method="}, {"--tol", "tol="}, {"--max-steps", "max_steps="}, {"--set", ""},
  {"--period", "steady_state.period="},
  {"-o", NULL},
  {"--output", NULL},
};

/* Split "--flag=value" or take the value from the next argument. */
static int flag_value(int argc, char **argv, int *i, const char *flag, const char **v) {
  const char *arg = argv[*i], *eq = strchr(arg, '=');
  if (eq && strncmp(arg, "--", 2) == 0) { *v = eq + 1; return 0; }
  if (*i + 1 >= argc) return usage_error("%s needs a value", flag);
  *v = argv[++*i];
  return 0;
}

static int parse_one(run_args *a, int argc, char **argv, int *i) {
  const char *arg = argv[*i];
  size_t flen = strncmp(arg, "--", 2) == 0 ? strcspn(arg, "=") : strlen(arg);
  for (size_t f = 0; f < sizeof value_flags / sizeof value_flags[0]; f++) {
    if (strlen(value_flags[f].flag) != flen || strncmp(arg, value_flags[f].flag, flen) != 0)
      continue;
    const char *v = NULL;
    char flag[24];
    snprintf(flag, sizeof flag, "%.*s", (int)flen, arg);
    int rc = flag_value(argc, argv, i, flag, &v);
    if (!rc && value_flags[f].key) rc = check_value(flag, v);
    if (rc) return rc;
    if (!value_flags[f].key) { a->out = v; return 0; }
    return add_override(a, value_flags[f].key, v);
  }
  if (strncmp(arg, "--probe", 7) == 0 && (arg[7] == '\0' || arg[7] == '=')) {
    const char *v = NULL;
    int rc = flag_value(argc, argv, i, "--probe", &v);
    if (!rc) a->probes[a->n_probes++] = v;
    return rc;
  }
  if (strcmp(arg, "--quiet") == 0 || strcmp(arg, "-q") == 0) { a->quiet = 1; return 0; }
  if (strcmp(arg, "--resume") == 0) { a->resume = 1; return 0; }
  if (strcmp(arg, "--estimate") == 0) return add_override(a, "estimate=", "true");
  if (strcmp(arg, "--steady-state") == 0) return add_override(a, "steady_state.enabled=", "true");
  if (arg[0] == '-' && arg[1]) return usage_error("unknown option '%s'", arg);
  if (a->scene) return usage_error("one scene per run: '%s' after '%s'", arg, a->scene);
  a->scene = arg;
  return 0;
}

void run_args_free(run_args *a) {
  for (int i = 0; i < a->n_overrides; i++) free(a->overrides[i]);
  free(a->overrides);
  free(a->probes);
}

static int print_versions(void) {
  char deps[256], h5[64];
  cup_dependency_versions(deps, sizeof deps);
  cup_h5_version(h5, sizeof h5);
  printf("catchup-run %s (%s; %s)\n", cup_version(), deps, h5);
  return 0;
}

int run_args_parse(run_args *a, int argc, char **argv) {
  memset(a, 0, sizeof *a);
  a->overrides = calloc((size_t)argc + 1, sizeof *a->overrides);
  a->probes = calloc((size_t)argc + 1, sizeof *a->probes);
  if (!a->overrides || !a->probes) return usage_error("out of memory");
  for (int i = 1; i < argc; i++) {
    if (strcmp(argv[i], "-h") == 0 || strcmp(argv[i], "--help") == 0) {
      print_usage();
      return 0;
    }
    if (strcmp(argv[i], "--version") == 0) return print_versions();
    int rc = parse_one(a, argc, argv, &i);
    if (rc) return rc;
  }
  if (!a->scene) return usage_error("no scene file given");
  if (!a->out) return usage_error("no output file given: -o OUT.h5");
  return -1;
}

/* Helpers of the tests that run catchup-run as a program and read its HDF5
 * file back (test_catchup_run.c, test_stress_cli.c). The includer defines
 * CLI_TMPDIR_TEMPLATE (a mkdtemp template) and CUP_CATCHUP_RUN, and
 * includes cmocka.h and hdf5.h first; make_tmpdir/remove_tmpdir
 * (tmpdir.h) are the group set-up and tear-down. */
#ifndef CUP_TEST_CLIUTIL_H
#define CUP_TEST_CLIUTIL_H

#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <sys/types.h>
#include <sys/wait.h>
#include "tmpdir.h"
#include "h5read.h"   /* reading the file */

static const char *tmp_path(const char *name) {
  static char buf[4][256];
  static int next;
  char *p = buf[next++ % 4];
  snprintf(p, 256, "%s/%s", tmpdir, name);
  return p;
}

/* text written to the file name in the test's folder; its path (tmp_path's) */
static inline const char *tmp_text(const char *name, const char *text) {
  const char *path = tmp_path(name);
  FILE *fp = fopen(path, "w");
  assert_non_null(fp);
  fputs(text, fp);
  fclose(fp);
  return path;
}

/* ---- running the program ---- */

typedef struct {
  int exited, code, sig;     /* exit code, or the signal that ended it */
  char err[4096];            /* its stderr */
  char out[4096];            /* its stdout */
  int lines;                 /* lines on stderr */
} result;

static void sleep_s(double s) {
  struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
  while (nanosleep(&ts, &ts) != 0) {}
}

/* Run catchup-run with the NULL-terminated arguments; if signal_after > 0,
 * send sig after that many seconds. */
static result run_cli(const char *const *args, double signal_after, int sig) {
  result r;
  memset(&r, 0, sizeof r);
  char errfile[256], outfile[256];             /* not tmp_path's ring: callers hold its paths */
  snprintf(errfile, sizeof errfile, "%s/stderr.txt", tmpdir);
  snprintf(outfile, sizeof outfile, "%s/stdout.txt", tmpdir);
  const char *argv[32] = {CUP_CATCHUP_RUN};
  for (int i = 0; args[i] && i < 30; i++) argv[i + 1] = args[i];
  fflush(NULL);
  pid_t pid = fork();
  if (pid < 0) skip();
  if (pid == 0) {
    int fd = open(errfile, O_WRONLY | O_CREAT | O_TRUNC, 0600), fo = open(outfile, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    dup2(fd, 2);
    dup2(fo, 1);
    execv(CUP_CATCHUP_RUN, (char *const *)argv);
    _exit(127);
  }
  if (signal_after > 0) {
    sleep_s(signal_after);
    kill(pid, sig);
  }
  int st = 0;
  assert_int_equal(waitpid(pid, &st, 0), pid);
  r.exited = WIFEXITED(st);
  r.code = r.exited ? WEXITSTATUS(st) : -1;
  r.sig = WIFSIGNALED(st) ? WTERMSIG(st) : 0;
  FILE *f = fopen(errfile, "r");
  assert_non_null(f);
  size_t n = fread(r.err, 1, sizeof r.err - 1, f);
  r.err[n] = '\0';
  fclose(f);
  for (size_t i = 0; i < n; i++) r.lines += r.err[i] == '\n';
  f = fopen(outfile, "r");
  assert_non_null(f);
  n = fread(r.out, 1, sizeof r.out - 1, f);
  r.out[n] = '\0';
  fclose(f);
  return r;
}

#endif

/* A test program's scratch directory: the includer defines
 * CLI_TMPDIR_TEMPLATE (a mkdtemp template, "/tmp/cup_NAME_XXXXXX") and
 * passes make_tmpdir/remove_tmpdir to cmocka_run_group_tests as the group's
 * set-up and tear-down. */
#ifndef CUP_TEST_TMPDIR_H
#define CUP_TEST_TMPDIR_H

#include <stdio.h>
#include <stdlib.h>

static char tmpdir[] = CLI_TMPDIR_TEMPLATE;

static int make_tmpdir(void **state) {
  (void)state;
  return mkdtemp(tmpdir) ? 0 : -1;
}

static int remove_tmpdir(void **state) {
  (void)state;
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
  return system(cmd) == 0 ? 0 : -1;
}

#endif

/* mpi_singleton — see mpi_singleton.h. */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <mpi.h>
#include "mpi_singleton.h"

static char base[4096];    /* singleton_prepare's directory ("" when none was made) */

static int launched(void) {
  static const char *const by[] = {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_FD"};
  for (size_t k = 0; k < sizeof by / sizeof by[0]; k++)
    if (getenv(by[k])) return 1;
  return 0;
}

void singleton_prepare(void) {
  if (launched() || getenv("OMPI_MCA_ess_singleton_isolated") || getenv("OMPI_MCA_orte_tmpdir_base")) return;
  const char *tmp = getenv("TMPDIR");
  if (!tmp || !*tmp) tmp = "/tmp";
  int len = snprintf(base, sizeof base, "%s/catchup-sweep.XXXXXX", tmp);
  if (len < 0 || (size_t)len >= sizeof base || !mkdtemp(base)) {
    base[0] = '\0';        /* no directory of its own: the default singleton, as before */
    return;
  }
  setenv("OMPI_MCA_orte_tmpdir_base", base, 1);
  setenv("OMPI_MCA_ess_singleton_isolated", "1", 1);
}

/* Empty directories under dir removed, depth first (Open MPI's session
 * tree: ompi.<host>.<uid>/jf.0/...), then dir if it is empty too. */
static void remove_empty(const char *dir, int depth) {
  DIR *d = depth < 8 ? opendir(dir) : NULL;
  if (d) {
    struct dirent *e;
    char sub[4096];
    while ((e = readdir(d)))
      if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..") &&
          snprintf(sub, sizeof sub, "%s/%s", dir, e->d_name) < (int)sizeof sub)
        remove_empty(sub, depth + 1);
    closedir(d);
  }
  rmdir(dir);              /* fails, and keeps it, unless it is an empty directory */
}

void singleton_cleanup(void) {
  if (base[0]) remove_empty(base, 0);
}

_Noreturn void singleton_abort(int code) {
  if (!base[0]) {
    MPI_Abort(MPI_COMM_WORLD, code);
    exit(code);            /* (MPI_Abort does not return) */
  }
  /* An isolated singleton is the whole job: nothing to kill, and MPI_Abort
   * would end the process before its directory could be removed. */
  fflush(stdout);
  fflush(stderr);
  MPI_Finalize();
  singleton_cleanup();
  exit(code);
}

/* Outside consumer: the installed header and library agree on the version,
 * and a status string comes back from the library. Exit 0 on success. */
#include <stdio.h>
#include <string.h>
#include <catchup.h>

int main(void) {
  char deps[256];
  if (strcmp(cup_version(), CUP_VERSION_STRING) != 0) {
    fprintf(stderr, "header %s but library %s\n", CUP_VERSION_STRING, cup_version());
    return 1;
  }
  if (strcmp(cup_status_name(CUP_ERR_EMPTY_SET), "CUP_ERR_EMPTY_SET") != 0) return 2;
  cup_dependency_versions(deps, sizeof deps);
  if (strncmp(deps, "catchup ", 8) != 0 || !strstr(deps, "CHOLMOD")) return 3;
  printf("consumer linked catchup %s (%s)\n", cup_version(), deps);
  return 0;
}

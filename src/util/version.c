/* Library and dependency versions, for provenance in output files. */
#include <stdio.h>
#include <cholmod.h>
#include <gsl/gsl_version.h>
#include <yaml.h>
#include "catchup.h"

const char *cup_version(void) { return CUP_VERSION_STRING; }

int cup_dependency_versions(char *buf, unsigned long size) {
  int v[3] = {0, 0, 0};
  cholmod_version(v);   /* the linked library, not the header we compiled with */
  return snprintf(buf, size, "catchup %s; CHOLMOD %d.%d.%d; GSL %s; libyaml %s",
                  CUP_VERSION_STRING, v[0], v[1], v[2], gsl_version,
                  yaml_get_version_string());
}

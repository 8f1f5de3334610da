/* Outside consumer of catchup::catchup_h5: writes a two-sample run into the
 * directory given as argv[1], without any HDF5 header or find_package(HDF5). */
#include <stdio.h>
#include <string.h>
#include <catchup.h>
#include <catchup/h5run.h>

int main(int argc, char **argv) {
  char path[512], err[CUP_ERRMSG_LEN], ver[64];
  snprintf(path, sizeof path, "%s/consumer.h5", argc > 1 ? argv[1] : ".");
  cup_h5run *w = NULL;
  double x[2] = {1, 2};
  if (cup_h5run_create(&w, path, 2, err) != CUP_OK) { fprintf(stderr, "%s\n", err); return 1; }
  if (cup_h5run_sink(0, 0.0, x, w) || cup_h5run_sink(1, 0.5, x, w)) return 2;
  if (cup_h5run_attr_string(w, "catchup_version", cup_version()) != CUP_OK) return 3;
  if (cup_h5run_close(&w, err) != CUP_OK) { fprintf(stderr, "%s\n", err); return 4; }
  cup_h5_version(ver, sizeof ver);
  if (strncmp(ver, "HDF5 ", 5) != 0) return 5;
  printf("consumer wrote %s with %s\n", path, ver);
  return 0;
}

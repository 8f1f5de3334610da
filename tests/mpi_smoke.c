/* MPI smoke test: every rank links the same library and the collective
 * result matches its closed form. Exit code 0 on success on every rank. */
#include <mpi.h>
#include <stdio.h>
#include <string.h>
#include "catchup.h"

int main(int argc, char **argv) {
  int rank, size, fail = 0, anyfail = 0;
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);

  /* Sum of ranks: closed form size*(size-1)/2. */
  long mine = rank, sum = 0;
  MPI_Allreduce(&mine, &sum, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  if (sum != (long)size * (size - 1) / 2) fail = 1;

  /* Every rank runs the same library version as rank 0. */
  char ver[32] = {0};
  snprintf(ver, sizeof ver, "%s", cup_version());
  char root[32];
  memcpy(root, ver, sizeof ver);
  MPI_Bcast(root, (int)sizeof root, MPI_CHAR, 0, MPI_COMM_WORLD);
  if (strcmp(root, ver) != 0 || strcmp(ver, CUP_VERSION_STRING) != 0) fail = 1;

  MPI_Allreduce(&fail, &anyfail, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (rank == 0)
    printf("mpi_smoke: %d ranks, catchup %s: %s\n", size, ver, anyfail ? "FAILED" : "ok");
  MPI_Finalize();
  return anyfail;
}

/* mpi_singleton — catchup-sweep started without a launcher (an Open MPI
 * singleton: `catchup-sweep S.yaml -o R.h5`), made safe from two faults of
 * Open MPI 4.1's singleton mode. */
#ifndef CUP_MPI_SINGLETON_H
#define CUP_MPI_SINGLETON_H

/* Before MPI_Init. Without a launcher (none of the variables mpirun, srun
 * or hydra give a rank: OMPI_COMM_WORLD_SIZE, PMIX_RANK, PMI_RANK, PMI_FD)
 * and unless the user set either variable:
 * - OMPI_MCA_ess_singleton_isolated=1. By default a singleton forks a
 *   daemon as its PMIx server, and at MPI_Finalize an event from it can
 *   reach the progress thread after the component that handles it
 *   (mca_pmix_ext3x.so) was unloaded: a segfault (status 139) or a
 *   corrupted heap (134) after the sweep's work and messages were done
 *   (13 in about 9100 runs of the bad sweep files at a load of 10-16; the
 *   cores show the faulting address in that component's text). A sweep
 *   never spawns, so it needs no daemon.
 * - OMPI_MCA_orte_tmpdir_base, a directory of its own (mkdtemp in TMPDIR
 *   or /tmp). An isolated singleton names its session directory jf.0 in
 *   the shared <tmp>/ompi.<host>.<uid>: two at once removed each other's
 *   ("File exists", "No such file" in MPI_Init).
 * A launched rank is left alone: its session directory is the launcher's. */
void singleton_prepare(void);

/* After MPI_Finalize: the directory of singleton_prepare removed, with the
 * empty directories Open MPI left in it (nothing that holds a file). */
void singleton_cleanup(void);

/* MPI_Abort(MPI_COMM_WORLD, code), except in the isolated singleton of
 * singleton_prepare: there the job is this one process, so it finalizes,
 * removes its directory and exits with code (MPI_Abort would leave the
 * directory behind). Does not return. */
_Noreturn void singleton_abort(int code);

#endif

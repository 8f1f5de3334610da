/* file_in_use — is a results file held open by another process? HDF5 1.10
 * takes an flock on every file it opens (shared for a reader, exclusive for
 * a writer) but creates with O_TRUNC before it locks, so creating over a
 * file that another catchup-sweep or catchup-run is still writing would
 * empty that run's file before the lock fails. The writers ask this first. */
#ifndef CUP_FILE_IN_USE_H
#define CUP_FILE_IN_USE_H

#include <errno.h>
#include <fcntl.h>
#include <unistd.h>
#include <sys/file.h>

/* 1 when another process holds a lock on path; 0 when none does, or the
 * file does not exist or cannot be opened (the create then says why). */
static inline int cup_file_in_use(const char *path) {
  int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  int busy = flock(fd, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  close(fd);                                   /* also drops our own lock */
  return busy;
}

#endif

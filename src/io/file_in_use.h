/* file_in_use — replacing a results file safely. Is it held open by
 * another process? HDF5 1.10 takes an flock on every file it opens (shared
 * for a reader, exclusive for a writer) but creates with O_TRUNC before it
 * locks, so creating over a file that another catchup-sweep or catchup-run
 * is still writing would empty that run's file before the lock fails. The
 * writers ask this first, and write a fresh sibling (cup_staged_name) that
 * they rename over the file once the run got past its checks. */
#ifndef CUP_FILE_IN_USE_H
#define CUP_FILE_IN_USE_H

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
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

/* A new empty sibling of path no one else has, PATH.partXXXXXX (malloc'd;
 * the umask applies, as to any new file). NULL with errno when the folder
 * takes no new file (read-only, full, missing). */
static inline char *cup_staged_name(const char *path) {
  size_t n = strlen(path) + 16;
  char *s = malloc(n);
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  unsigned r = (unsigned)getpid() * 2654435761u ^ (unsigned)ts.tv_nsec;
  for (int tries = 0; s && tries < 100; tries++, r = r * 1103515245u + 12345u) {
    snprintf(s, n, "%s.part%06x", path, (r >> 4) & 0xffffffu);
    int fd = open(s, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) { close(fd); return s; }
    if (errno != EEXIST) break;
  }
  int e = errno;
  free(s);
  errno = e;
  return NULL;
}

#endif

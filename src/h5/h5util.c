/* h5util — see h5util.h. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <libgen.h>
#include <sys/file.h>
#include <sys/statvfs.h>
#include "catchup/h5run.h"
#include "h5util.h"

static herr_t innermost(unsigned n, const H5E_error2_t *e, void *out) {
  h5_detail *d = out;
  if (n == 0 && e->desc) snprintf(d->desc, sizeof d->desc, "%s", e->desc);
  if (e->min_num == H5E_CANTLOCKFILE) d->locked = 1;
  return 0;
}

void h5_error_detail(h5_detail *d, int system) {
  d->desc[0] = '\0';
  d->locked = 0;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, innermost, d);
  const char *key = "error message = '";
  char *s = system ? strstr(d->desc, key) : NULL;
  if (s) {
    s += strlen(key);
    char *end = strchr(s, '\'');
    if (end) *end = '\0';
    memmove(d->desc, s, strlen(s) + 1);
  }
  if (!d->desc[0]) snprintf(d->desc, sizeof d->desc, "HDF5 call failed");
}

hid_t h5_file_access(int unbuffered) {
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl >= 0 && (H5Pset_libver_bounds(fapl, H5F_LIBVER_EARLIEST, H5F_LIBVER_V18) < 0 ||
                    H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG) < 0 ||
                    (unbuffered && H5Pset_sieve_buf_size(fapl, 0) < 0))) {
    H5Pclose(fapl);
    return H5I_INVALID_HID;
  }
  return fapl;
}

hid_t h5_vlen_str(void) {
  hid_t t = H5Tcopy(H5T_C_S1);
  if (t >= 0 && (H5Tset_size(t, H5T_VARIABLE) < 0 || H5Tset_cset(t, H5T_CSET_UTF8) < 0)) {
    H5Tclose(t);
    return H5I_INVALID_HID;
  }
  return t;
}

int h5_space_short(const char *path, int folder, double need, double *avail) {
  char *copy = folder ? strdup(path) : NULL;
  struct statvfs v;
  int known = (!folder || copy) && statvfs(folder ? dirname(copy) : path, &v) == 0 && v.f_blocks != 0;
  free(copy);
  double free_bytes = known ? (double)v.f_bavail * (double)v.f_frsize : 0;
  if (avail) *avail = free_bytes;
  return known && need + (double)CUP_H5_SPACE_MARGIN > free_bytes;
}

int h5_file_in_use(const char *path) {
  int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return 0;
  int busy = flock(fd, LOCK_EX | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  close(fd);                                   /* also drops our own lock */
  return busy;
}

char *h5_staged_name(const char *path) {
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

/* h5util — what every HDF5 writer of catchup shares: the run writer
 * (h5run*.c) and the sweep's results file (src/sweep/sweep_h5*.c). HDF5
 * silenced while we call it, and its innermost error kept for our own
 * message; the file access both use; the free space kept on a file's
 * device; and replacing a file safely. Internal (hidden in catchup_h5).
 *
 * Replacing a file: is it held open by another process? HDF5 1.10 takes
 * an flock on every file it opens (shared for a reader, exclusive for a
 * writer) but creates with O_TRUNC before it locks, so creating over a
 * file that another catchup-sweep or catchup-run is still writing would
 * empty that run's file before the lock fails. The writers ask
 * h5_file_in_use first, and write a fresh sibling (h5_staged_name) that
 * they rename over the file once the run got past its checks. */
#ifndef CUP_H5UTIL_H
#define CUP_H5UTIL_H

#include <stddef.h>
#include <hdf5.h>
#include "catchup.h"

/* HDF5 must not print, and must not stay silenced after us. */
typedef struct { H5E_auto2_t fn; void *data; } quiet_t;

static inline quiet_t quiet_begin(void) {
  quiet_t q = {NULL, NULL};
  H5Eget_auto2(H5E_DEFAULT, &q.fn, &q.data);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  return q;
}

static inline void quiet_end(quiet_t q) { H5Eset_auto2(H5E_DEFAULT, q.fn, q.data); }

/* Why the last HDF5 call failed: the innermost description on the error
 * stack (the most specific one), and whether a file lock was refused. */
enum { H5_DETAIL_LEN = CUP_ERRMSG_LEN / 2 };   /* a description names the file: whole */
typedef struct { char desc[H5_DETAIL_LEN]; int locked; } h5_detail;

/* Read it right after the failed call: any later HDF5 call (even H5Pclose)
 * clears the stack. With `system`, a failed open()'s description is cut to
 * the system's message in it ("No such file or directory"), all a user
 * needs; "HDF5 call failed" when the stack says nothing. */
void h5_error_detail(h5_detail *d, int system);

/* The file access of the writers: the 1.8 format (superblock version <= 2,
 * without the version-3 "open for writing" flag, so that a killed writer's
 * file opens as is, without h5clear), and a strong close (H5Fclose really
 * closes, whatever is still open inside). With `unbuffered`, no sieve
 * buffer: raw writes reach the operating system when H5Dwrite returns, in
 * our order. H5I_INVALID_HID on failure. */
hid_t h5_file_access(int unbuffered);

/* A variable-length UTF-8 string type (h5py reads str). */
hid_t h5_vlen_str(void);

/* The free space a writer keeps: 1 when the device that holds path (with
 * `folder`: the folder path goes into, for a file not written yet) has less
 * than need + CUP_H5_SPACE_MARGIN bytes free; *avail (may be NULL) gets what
 * it has. 0 when it has room, when it does not report sizes (f_blocks = 0:
 * never "full"), when it cannot be asked, or when need is NaN (not known:
 * checked as the file grows). HDF5 1.10 cannot close a file once a write
 * failed for lack of space (the file is left corrupt and the library
 * crashes at exit), so the writers stop while HDF5 can still close. */
int h5_space_short(const char *path, int folder, double need, double *avail);

/* 1 when another process holds a lock on path; 0 when none does, or the
 * file does not exist or cannot be opened (the create then says why). */
int h5_file_in_use(const char *path);

/* A new empty sibling of path no one else has, PATH.partXXXXXX (malloc'd;
 * the umask applies, as to any new file). NULL with errno when the folder
 * takes no new file (read-only, full, missing). */
char *h5_staged_name(const char *path);

#endif

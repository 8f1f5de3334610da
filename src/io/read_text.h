/* read_text — a whole file into memory, the list of the files a load read,
 * and the argument checks the readers of scene files and netlists share.
 * Internal to the library. */
#ifndef CUP_READ_TEXT_H
#define CUP_READ_TEXT_H

#include <stddef.h>

/* The files one load read (a scene, the Matrix Market files and the netlist
 * it names, what a netlist includes; a sweep file and its scenes' files),
 * in the order first read, each once: its path as opened, the SHA-256 of
 * the bytes that were parsed (not of the file as it may be now), and its
 * identity (st_dev, st_ino) when read. catchup-run refuses an output that is
 * one of them; --resume refuses a run whose files changed since. Every
 * reader of a file goes through read_text with the load's list, so that
 * a new kind of file read (an .include) is on it without more code. */
typedef struct file_entry {
  char *path;
  char sha256[65];
  unsigned long long dev, ino;
} file_entry;

typedef struct file_list {
  int n, cap;
  file_entry *e;
} file_list;

void file_list_free(file_list *l);
struct cup_scene;
/* A loaded scene's list (scene.c). */
const file_list *scene_file_list(const struct cup_scene *s);
/* Append what src lists (a loaded scene's files to a sweep's) that l does
 * not hold yet. CUP_OK or CUP_ERR_NOMEM. */
int file_list_merge(file_list *l, const file_list *src);

/* CUP_ERR_ARG with "OUT is FILE, which the run reads (...)" in errmsg when
 * the output path out names one of l's files: the same path once resolved
 * (realpath of its folder, then its name: out need not exist), or the same
 * file (st_dev, st_ino) now or when it was read (hard links, a file renamed
 * over). CUP_OK otherwise. Call before anything is written to out. */
int file_list_check_output(const file_list *l, const char *out, char *errmsg);

/* The list as text, one line per file in sha256sum's format ("HASH  PATH",
 * a newline or backslash in a path escaped as \n, \\), for a results
 * file's attribute `inputs_sha256` (sha256sum -c checks the files against
 * it). malloc'd; NULL without memory. */
char *file_list_text(const file_list *l);
/* The files of l against `stored` (file_list_text of the files an
 * earlier run read), file by file in the order read: CUP_ERR_ARG with
 * "FILE changed since WHAT was made (SHA-256 ... then, ... now)" (or a file
 * read now and not then, or one then and not now) in errmsg (size bytes). */
int file_list_compare(const file_list *l, const char *stored, const char *what, char *errmsg,
                      size_t size);

/* The bytes of path into *text (malloc'd; not NUL-terminated beyond len)
 * and *len, recorded in files (may be NULL). CUP_ERR_IO ("PATH: cannot
 * open: reason") or CUP_ERR_NOMEM with the message in errmsg
 * (CUP_ERRMSG_LEN bytes, may be NULL). */
int read_text(const char *path, char **text, size_t *len, file_list *files, char *errmsg);

/* The arguments common to the loaders (what: "scene" or "netlist"; item:
 * what the list holds, "override" or "set"): CUP_ERR_ARG with a message when
 * the output pointer is absent (has_out 0), src (a path or text) is NULL, or
 * the list of n items is inconsistent or holds a NULL. Clears errmsg. */
int load_args(const char *what, const char *item, int has_out, const void *src,
              const char *const *list, int n, char *errmsg);

#endif

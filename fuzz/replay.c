/* replay — a main for a libFuzzer harness without libFuzzer: each file
 * named, and each file in each folder named, is passed once to
 * LLVMFuzzerTestOneInput. The normal (gcc) build replays the netlist seeds
 * through fuzz_netlist.c this way (tests/CMakeLists.txt,
 * fuzz_netlist_replay), so that CI checks them without clang; the harness
 * aborts on what it finds wrong.
 *   replay PATH...   (exit 0, or 2 when a path cannot be read) */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int one_file(const char *path, long *count) {
  FILE *f = fopen(path, "rb");
  if (!f) { fprintf(stderr, "replay: cannot read '%s'\n", path); return 2; }
  uint8_t *buf = malloc((1 << 16) + 1);
  size_t n = buf ? fread(buf, 1, (1 << 16) + 1, f) : 0;
  fclose(f);
  if (!buf) { fprintf(stderr, "replay: out of memory\n"); return 2; }
  LLVMFuzzerTestOneInput(buf, n);
  free(buf);
  (*count)++;
  return 0;
}

static int cmp(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* A folder's regular files, in name order (the same order on every run). */
static int one_dir(const char *dir, long *count) {
  DIR *d = opendir(dir);
  if (!d) { fprintf(stderr, "replay: cannot read folder '%s'\n", dir); return 2; }
  char **names = NULL;
  size_t nn = 0, cap = 0;
  struct dirent *e;
  int st = 0;
  while (!st && (e = readdir(d))) {
    if (e->d_name[0] == '.') continue;
    size_t len = strlen(dir) + strlen(e->d_name) + 2;
    char *p = malloc(len);
    if (nn == cap) {
      cap = cap ? 2 * cap : 64;
      char **g = realloc(names, cap * sizeof *names);
      if (!g) { free(p); st = 2; break; }
      names = g;
    }
    if (!p) { st = 2; break; }
    snprintf(p, len, "%s/%s", dir, e->d_name);
    names[nn++] = p;
  }
  closedir(d);
  if (st) fprintf(stderr, "replay: out of memory\n");
  if (names) qsort(names, nn, sizeof *names, cmp);
  for (size_t k = 0; k < nn; k++) {
    struct stat sb;
    if (!st && stat(names[k], &sb) == 0 && S_ISREG(sb.st_mode)) st = one_file(names[k], count);
    free(names[k]);
  }
  free(names);
  return st;
}

int main(int argc, char **argv) {
  long count = 0;
  for (int a = 1; a < argc; a++) {
    struct stat sb;
    if (stat(argv[a], &sb) != 0) { fprintf(stderr, "replay: no such path '%s'\n", argv[a]); return 2; }
    int st = S_ISDIR(sb.st_mode) ? one_dir(argv[a], &count) : one_file(argv[a], &count);
    if (st) return st;
  }
  printf("replay: %ld inputs passed\n", count);
  return count > 0 ? 0 : 2;
}

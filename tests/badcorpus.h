/* The malformed-input corpus check shared by test_scene and test_netlist:
 * every file in a folder with a given ending names its expected error on
 * its first line after a marker ("# expect: " for scenes, "* expect: " for
 * netlists), and loading it must fail with a one-line message containing
 * that text and leave the output pointer NULL. Needs cmocka.h included
 * before this header. */
#ifndef CUP_BADCORPUS_H
#define CUP_BADCORPUS_H

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "catchup.h"

/* Loads path; returns the status, writes the message to err and sets
 * *out_null to whether the output pointer is NULL afterwards (and frees what
 * was loaded on success). */
typedef int (*bad_loader)(const char *path, char err[CUP_ERRMSG_LEN], int *out_null);

static int bad_cmp_str(const void *a, const void *b) {
  return strcmp(*(char *const *)a, *(char *const *)b);
}

/* The text after the marker on the first line, or NULL. */
static char *bad_expected_error(const char *path, const char *marker) {
  FILE *f = fopen(path, "r");
  if (!f) return NULL;
  char line[512] = "";
  char *ok = fgets(line, sizeof line, f);
  fclose(f);
  size_t m = strlen(marker);
  if (!ok || strncmp(line, marker, m) != 0) return NULL;
  size_t n = strlen(line);
  while (n > m && (line[n - 1] == '\n' || line[n - 1] == '\r' || line[n - 1] == ' ')) line[--n] = '\0';
  return strdup(line + m);
}

/* Checks every file in dir ending in ext; prints each failure and returns
 * how many files were checked, *failures how many failed. */
static int bad_corpus_check(const char *dir, const char *ext, const char *marker,
                            bad_loader load, int *failures) {
  DIR *d = opendir(dir);
  *failures = 0;
  if (!d) { print_error("cannot open %s\n", dir); *failures = 1; return 0; }
  char *names[256];
  int count = 0;
  size_t le = strlen(ext);
  for (struct dirent *e; (e = readdir(d)) != NULL;) {
    size_t n = strlen(e->d_name);
    if (n > le && !strcmp(e->d_name + n - le, ext) && count < 256) names[count++] = strdup(e->d_name);
  }
  closedir(d);
  qsort(names, (size_t)count, sizeof names[0], bad_cmp_str);
  for (int k = 0; k < count; k++) {
    char path[1024], err[CUP_ERRMSG_LEN] = "";
    snprintf(path, sizeof path, "%s/%s", dir, names[k]);
    char *want = bad_expected_error(path, marker);
    int out_null = 1;
    int st = load(path, err, &out_null);
    const char *why = !want ? "no expected-error first line"
                    : st == CUP_OK ? "loaded without error"
                    : !out_null ? "output not NULL after a failure"
                    : strchr(err, '\n') ? "message has a newline"
                    : !strstr(err, want) ? "message differs" : NULL;
    if (why) {
      print_error("%s: %s\n  expected: %s\n  got:      %s\n", names[k], why, want ? want : "", err);
      (*failures)++;
    }
    free(want);
    free(names[k]);
  }
  return count;
}

#endif

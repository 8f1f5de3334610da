/* fuzz_text — the fuzzer's bytes as a C string the loaders can read, for
 * both harnesses (fuzz_scene.c, fuzz_netlist.c): one copy. */
#ifndef CUP_FUZZ_TEXT_H
#define CUP_FUZZ_TEXT_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* data[0..size) with a terminating NUL, to be freed; NULL when longer than
 * 64 KiB (no loader's input is that long) or out of memory. */
static inline char *fuzz_text(const uint8_t *data, size_t size) {
  if (size > (1 << 16)) return NULL;
  char *text = malloc(size + 1);
  if (!text) return NULL;
  memcpy(text, data, size);
  text[size] = '\0';
  return text;
}

#endif

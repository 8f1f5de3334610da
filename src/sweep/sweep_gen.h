/* sweep_gen — variants generated from one entry of a sweep's variants:
 * (docs/sweep-format.md, "Generated variants"): a grid of values per key
 * (their cartesian product), lists zipped elementwise, and a Latin
 * hypercube sample of ranges (seeded: the same file gives the same
 * variants on every rank and every run, so --resume keeps working). Each
 * generated variant is the entry's scene with its set: overrides, then one
 * override per generated key. Below sweep.c, which reads the rest. */
#ifndef CUP_SWEEP_GEN_H
#define CUP_SWEEP_GEN_H

#include "io/scene_read.h"

#define SW_GEN_MAX 1000000L   /* variants one entry may generate */

/* How many variants the entry nd (key "variants.K") makes: 1 without
 * grid:, zip: or sample:, else their product; checks those keys (located
 * errors). */
int sw_gen_count(rd *p, const st_node *nd, const char *key, long *count);
/* A generated variant: its name and overrides ("key=value"), owned. */
typedef struct sw_gen_variant {
  char *name;
  char **set;
  int n_set;
} sw_gen_variant;
/* Fills out[0..count) (zeroed by the caller): names "NAME.J" (shorter than
 * name_len with their NUL, else a located error), overrides set[0..n_set)
 * (copied) then the generated ones. */
int sw_gen_expand(rd *p, const st_node *nd, const char *key, const char *name, size_t name_len, char *const *set,
                  int n_set, sw_gen_variant *out, long count);
/* The entry's keys beyond name, scene and set. */
#define SW_GEN_KEYS "grid", "zip", "sample"

#endif

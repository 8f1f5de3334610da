/* names — see names.h. */
#include <stdio.h>
#include <string.h>
#include "catchup.h"
#include "names.h"

const char *name_of(const char *const *names, int count, int v) {
  return v >= 0 && v < count ? names[v] : "unknown";
}

int value_of(const char *const *names, int count, const char *name) {
  for (int v = 0; name && v < count; v++)
    if (!strcmp(name, names[v])) return v;
  return -1;
}

char *words_join(char *buf, unsigned long n, const char *const *words, const char *conj) {
  size_t len = 0;
  if (!n) return buf;
  buf[0] = '\0';
  for (int k = 0; words[k]; k++) {
    const char *sep = k == 0 ? "" : words[k + 1] ? ", " : " ";
    int w = snprintf(buf + len, n - len, "%s%s%s%s", sep, k > 0 && !words[k + 1] ? conj : "",
                     k > 0 && !words[k + 1] ? " " : "", words[k]);
    if (w < 0 || (size_t)w >= n - len) break;
    len += (size_t)w;
  }
  return buf;
}

#define NAME4_(e, v, name, doc) [v] = name,
#define NAME5_(e, v, name, form, doc) [v] = name,
static const char *const schemes[CUP_SCHEME_COUNT] = {CUP_SCHEME_LIST(NAME4_)};
static const char *const methods[CUP_PROJ_METHOD_COUNT] = {CUP_PROJ_METHOD_LIST(NAME4_)};
static const char *const outputs[CUP_OUTPUT_COUNT] = {CUP_OUTPUT_LIST(NAME5_)};
static const char *const waves[CUP_WAVE_COUNT] = {CUP_WAVE_LIST(NAME4_)};

const char *cup_scheme_name(int s) { return name_of(schemes, CUP_SCHEME_COUNT, s); }
int cup_scheme_parse(const char *name) { return value_of(schemes, CUP_SCHEME_COUNT, name); }
const char *cup_proj_method_name(int m) { return name_of(methods, CUP_PROJ_METHOD_COUNT, m); }
int cup_proj_method_parse(const char *name) { return value_of(methods, CUP_PROJ_METHOD_COUNT, name); }
const char *cup_output_name(int o) { return name_of(outputs, CUP_OUTPUT_COUNT, o); }
int cup_output_parse(const char *name) { return value_of(outputs, CUP_OUTPUT_COUNT, name); }
const char *cup_wave_name(int w) { return name_of(waves, CUP_WAVE_COUNT, w); }
int cup_wave_parse(const char *name) { return value_of(waves, CUP_WAVE_COUNT, name); }

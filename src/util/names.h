/* names — the words of the public choice lists (CUP_SCHEME_LIST,
 * CUP_PROJ_METHOD_LIST, CUP_OUTPUT_LIST, CUP_WAVE_LIST) to values and back,
 * so that every parser and message is made from the one list. */
#ifndef CUP_NAMES_H
#define CUP_NAMES_H


/* names[v] for 0 <= v < count, else "unknown". */
const char *name_of(const char *const *names, int count, int v);
/* The v with names[v] equal to name, else -1 (name NULL: -1). */
int value_of(const char *const *names, int count, const char *name);

/* The NULL-terminated words as "a, b, c or d" (conj "or"/"and") into buf
 * (n bytes, truncated to fit); returns buf. */
char *words_join(char *buf, unsigned long n, const char *const *words, const char *conj);

#endif

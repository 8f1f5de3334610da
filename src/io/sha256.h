/* sha256 — FIPS 180-4 SHA-256 of a byte string, for provenance (the sweep
 * file's hash in a results file). Public-domain style, no dependency. */
#ifndef CUP_SHA256_H
#define CUP_SHA256_H

#include <stddef.h>

/* hex receives 64 lowercase hex digits and a NUL (65 bytes). */
void sha256_hex(const void *data, size_t len, char hex[65]);

#endif

/* ckpt — the byte stream of a checkpoint (cup_integrator_checkpoint_*):
 * each part of the state is written and read by one function per module
 * that calls ckpt_io for every field, in the same order both ways, so
 * that saving and restoring cannot drift apart. A stream with no buffer
 * only counts (the size); reading past its end, or writing past its room,
 * marks it bad and reads zeros. Native layout: a checkpoint is resumed by
 * the same build on the same machine (its header says which). */
#ifndef CUP_CKPT_H
#define CUP_CKPT_H

#include <stddef.h>
#include <string.h>

typedef struct ckpt {
  unsigned char *buf;       /* NULL: count only */
  size_t len, cap;          /* bytes through so far; room in buf */
  int saving;               /* 1: memory -> buf; 0: buf -> memory */
  int bad;                  /* ran past the end */
} ckpt;

/* n bytes at v to the stream (saving) or from it (restoring). */
static inline void ckpt_io(ckpt *c, void *v, size_t n) {
  if (n == 0) return;
  if (c->buf && c->len + n > c->cap) {
    c->bad = 1;
    if (!c->saving) memset(v, 0, n);
  } else if (c->buf) {
    if (c->saving) memcpy(c->buf + c->len, v, n);
    else memcpy(v, c->buf + c->len, n);
  }
  c->len += n;
}

#define CUP_CKPT_IO(c, field) ckpt_io((c), &(field), sizeof(field))

#endif

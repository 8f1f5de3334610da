/* h5run_rows — the run writer's data path (include/catchup/h5run.h,
 * h5run_rows.h): the row buffers, rows and events appended, handed to HDF5
 * a chunk at a time and flushed by the clock, and the first HDF5 failure,
 * which stops it (set_error, h5run.c's too); the file, its datasets and
 * attributes are h5run.c's.
 *
 * Crash safety without SWMR: the file uses the 1.8-compatible format
 * (superblock version <= 2, which has no "open for writing" flag, so a killed
 * writer's file opens as is, without h5clear). HDF5 only promises a
 * consistent file after H5Fflush; the file on disk is the file as of the last
 * completed H5Fflush, which runs at least once per FLUSH_SECONDS while
 * samples arrive, on cup_h5run_flush and on close. Whole chunks are handed to
 * HDF5 as the buffer fills, between flushes. H5Fflush does not fsync: a
 * machine crash (not a process crash) may lose more. */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <hdf5.h>
#include "catchup.h"
#include "catchup/h5run.h"
#include "h5run_impl.h"
#include "h5run_rows.h"
#include "util/clock.h"

#define CACHE_BYTES (1u << 20)  /* HDF5's default chunk cache, per dataset */
#define FLUSH_SECONDS 1.0

/* ---- errors: HDF5 must not print, and must not stay silenced after us ---- */

/* An HDF5 call failed. Record "h5run: cannot <op> '<path>': <detail>" unless
 * an earlier failure is already recorded (the first one explains the rest),
 * and stop the writer: HDF5 1.10 may crash if used further on a file it
 * failed to write, so after this only close is attempted. */
int set_error(cup_h5run *w, int status, const char *op) {
  w->h5_failed = 1;
  if (w->data_status == CUP_OK) w->data_status = status;
  if (!w->errmsg[0]) {
    h5_detail d;
    h5_error_detail(&d, 1);                /* a failed open(): the system's message */
    snprintf(w->errmsg, sizeof w->errmsg, "h5run: cannot %s '%s': %s", op, w->path, d.desc);
    w->err_status = status;
  }
  H5Eclear2(H5E_DEFAULT);
  return status;
}

/* ---- the data path ---- */

/* The file's doubles are little-endian (H5T_IEEE_F64LE): a chunk in
 * memory is the chunk on disk where the machine's are too. */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
enum { DIRECT_CHUNKS = 1 };
#else
enum { DIRECT_CHUNKS = 0 };
#endif

/* Extend d to at + rows rows and write buf into rows [at, at + rows). A
 * whole chunk (rows = chunk from a chunk boundary: the buffer full) goes
 * to the file as it is (H5Dwrite_chunk): by H5Dwrite HDF5 made, zeroed
 * and filled a chunk of its cache with it first, about 100 000
 * instructions a dataset and chunk (the full bridge's 28 datasets: 700
 * instructions a sample). The same bytes in the same chunk either way. */
static herr_t append(hid_t d, int rank, hsize_t at, hsize_t rows, hsize_t cols, hsize_t chunk,
                     const double *buf) {
  hsize_t ext[2] = {at + rows, cols}, start[2] = {at, 0}, count[2] = {rows, cols};
  if (H5Dset_extent(d, ext) < 0) return -1;
  if (DIRECT_CHUNKS && rows == chunk && at % chunk == 0)
    return H5Dwrite_chunk(d, H5P_DEFAULT, 0, start, sizeof(double) * (size_t)(rows * cols), buf);
  hid_t fs = H5Dget_space(d);
  hid_t ms = H5Screate_simple(rank, count, NULL);
  herr_t r = -1;
  if (fs >= 0 && ms >= 0 && H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) >= 0)
    r = H5Dwrite(d, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, buf);
  hid_t err = keep_stack(r < 0);
  if (ms >= 0) H5Sclose(ms);
  if (fs >= 0) H5Sclose(fs);
  restore_stack(err);
  return r;
}

/* Append the buffered events to /events. */
static herr_t append_events(cup_h5run *w) {
  hsize_t ext[1] = {w->ewritten + w->enbuf}, start[1] = {w->ewritten}, count[1] = {w->enbuf};
  if (H5Dset_extent(w->dset_e, ext) < 0) return -1;
  hid_t fs = H5Dget_space(w->dset_e);
  hid_t ms = H5Screate_simple(1, count, NULL);
  herr_t r = -1;
  if (fs >= 0 && ms >= 0 && H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, NULL, count, NULL) >= 0)
    r = H5Dwrite(w->dset_e, w->etype_mem, ms, fs, w->exfer, w->ebuf);
  hid_t err = keep_stack(r < 0);
  if (ms >= 0) H5Sclose(ms);
  if (fs >= 0) H5Sclose(fs);
  restore_stack(err);
  if (r >= 0) { w->ewritten += w->enbuf; w->enbuf = 0; }
  return r;
}

/* Hand the buffered rows to HDF5 (no flush). Any failure is sticky: the sink
 * then refuses samples so that the run stops. Running short of space stops
 * the data after these rows, with HDF5 still able to flush and close. */
static int write_buffer(cup_h5run *w) {
  if (w->data_status != CUP_OK) return w->data_status;
  if (w->enbuf) {
    w->unflushed += 13.0 * (double)w->enbuf;
    quiet_t q = quiet_begin();
    if (append_events(w) < 0) set_error(w, CUP_ERR_IO, "append rows to /events in");
    quiet_end(q);
    if (w->h5_failed) return w->data_status;
  }
  if (w->nbuf == 0) return w->data_status;
  quiet_t q = quiet_begin();
  if (append(w->dset_x, 2, w->written, w->nbuf, (hsize_t)w->dim, w->chunk_rows, w->xbuf) < 0)
    set_error(w, CUP_ERR_IO, "append rows to /x in");
  for (int k = 0; k < w->nsig && !w->h5_failed; k++)     /* before /t: a reader takes len(/t) rows */
    if (append(w->dset_s[k], 1, w->written, w->nbuf, 1, w->chunk_rows, w->sbuf + (size_t)k * w->chunk_rows) < 0)
      set_error(w, CUP_ERR_IO, "append rows to /signals in");
  if (!w->h5_failed && append(w->dset_t, 1, w->written, w->nbuf, 1, w->chunk_rows, w->tbuf) < 0)
    set_error(w, CUP_ERR_IO, "append rows to /t in");
  quiet_end(q);
  if (w->h5_failed) return w->data_status;
  w->written += w->nbuf;
  w->unflushed += 8.0 * (double)w->nbuf * (double)(w->dim + 1 + w->nsig);
  w->nbuf = 0;
  /* What HDF5 holds in its chunk caches (at most one per dataset: with a
   * netlist's signals, tens of MiB) reaches the disk only at the next
   * flush, so the check counts it on top of the margin: on a 20 MiB tmpfs
   * the margin was otherwise eaten by the caches, and with 30 signals the
   * disk filled up and the close crashed. */
  double cached = (double)CACHE_BYTES * (3 + w->nsig);
  if (h5_space_short(w->path, 0, w->unflushed < cached ? w->unflushed : cached, NULL)) {
    if (!w->errmsg[0])
      snprintf(w->errmsg, sizeof w->errmsg, "h5run: stopped writing '%s' after %llu rows: "
               "less than %u MiB left on its device", w->path,
               (unsigned long long)w->written, CUP_H5_SPACE_MARGIN >> 20);
    if (!w->err_status) w->err_status = CUP_ERR_IO;
    w->data_status = CUP_ERR_IO;
  }
  return w->data_status;
}

/* Flushes even after the data stopped for lack of space, so that the rows
 * and attributes written so far reach the file; not after HDF5 failed. */
int cup_h5run_flush(cup_h5run *w) {
  if (!w) return CUP_ERR_ARG;
  if (w->h5_failed) return w->data_status;
  int st = write_buffer(w);
  if (w->h5_failed) return st;
  quiet_t q = quiet_begin();
  if (H5Fflush(w->file, H5F_SCOPE_LOCAL) < 0) set_error(w, CUP_ERR_IO, "flush");
  else w->unflushed = 0;
  quiet_end(q);
  w->last_flush = tick_seconds();
  return w->data_status;
}

/* Rows until the next chunk boundary: after a flush of a partial buffer the
 * next writes realign, so that HDF5 receives whole chunks. (chunk_rows is a
 * power of 2, chunk_rows_for: a mask, not a division a row.) */
static hsize_t room(const cup_h5run *w) {
  return w->chunk_rows - (w->written & (w->chunk_rows - 1));
}

/* The clock at every row cost the precision rectifier's 3001 samples
 * about 24 us of their 0.26 ms (8 ns and 20 instructions a row): it is
 * read every tick_every rows, doubled while those rows took less than
 * TICK_FAST and back to 1 once they take longer, so that a flush is late
 * by at most TICK_ROWS_MAX rows (docs/run-output.md). */
enum { TICK_ROWS_MAX = 16 };
#define TICK_FAST (FLUSH_SECONDS / 64)

static __attribute__((noinline)) int tick(cup_h5run *w) {
  double now = tick_seconds();
  if (now - w->last_tick < TICK_FAST) {
    if (w->tick_every < TICK_ROWS_MAX) w->tick_every *= 2;
  } else w->tick_every = 1;
  w->tick_left = w->tick_every;
  w->last_tick = now;
  if (now - w->last_flush >= FLUSH_SECONDS) return cup_h5run_flush(w);
  if (w->nbuf >= room(w)) return write_buffer(w);
  return CUP_OK;
}

/* Row nbuf of the buffer: t, x and the signals (into their columns; sig's
 * k-th at sig + k ss), then the clock every tick_every rows and the chunk
 * once full. */
static inline int put_row(cup_h5run *w, double t, const double *x, const double *sig, size_t ss, int wide) {
  hsize_t r = w->nbuf, rows = w->chunk_rows;
  int dim = w->dim, nsig = w->nsig;
  w->tbuf[r] = t;
  double *xb = w->xbuf + r * (hsize_t)dim, *sb = w->sbuf + r;
  if (wide) memcpy(xb, x, sizeof(double) * (size_t)dim);
  else
    switch (dim) {                               /* (1 to 4: no loop) */
      case 4: xb[3] = x[3]; /* fall through */
      case 3: xb[2] = x[2]; /* fall through */
      case 2: xb[1] = x[1]; /* fall through */
      default: xb[0] = x[0];
    }
  switch (nsig) {                                /* (a converter's few: no loop) */
    case 4: sb[3 * rows] = sig[3 * ss]; /* fall through */
    case 3: sb[2 * rows] = sig[2 * ss]; /* fall through */
    case 2: sb[rows] = sig[ss]; /* fall through */
    case 1: sb[0] = sig[0]; /* fall through */
    case 0: break;
    default:
      for (int k = 0; k < nsig; k++, sb += rows) *sb = sig[(size_t)k * ss];
  }
  w->nbuf = r + 1;
  if (--w->tick_left <= 0) return tick(w);
  if (w->nbuf >= room(w)) return write_buffer(w);
  return CUP_OK;
}

/* (Out of line: memcpy's call in the few entries' path made it save and
 * restore six registers.) */
static __attribute__((noinline)) int put_row_wide(cup_h5run *w, double t, const double *x, const double *sig,
                                                  size_t ss) {
  return put_row(w, t, x, sig, ss, 1);
}

/* The row buffers are taken at the first row, not with the writer: by
 * then HDF5 has made the file and freed its buffers (two 1 MiB ones for
 * the strings' conversion), and where the program keeps freed memory
 * (catchup-run, apps/heap_pad.h) the rows go into pages already touched:
 * the full bridge's 1600 rows faulted 20 fresh pages in the run (1.7 us
 * each), the precision rectifier's 10. */
static __attribute__((noinline)) int take_buffers(cup_h5run *w) {
  size_t rows = (size_t)w->chunk_rows;
  w->tbuf = malloc(sizeof(double) * rows);
  w->xbuf = malloc(sizeof(double) * rows * (size_t)w->dim);
  if (w->nsig) w->sbuf = malloc(sizeof(double) * rows * (size_t)w->nsig);
  if (w->tbuf && w->xbuf && (!w->nsig || w->sbuf)) return CUP_OK;
  if (!w->errmsg[0])
    snprintf(w->errmsg, sizeof w->errmsg, "h5run: '%s': out of memory for the rows' buffers (%zu bytes)", w->path,
             sizeof(double) * rows * (size_t)(1 + w->dim + w->nsig));
  if (!w->err_status) w->err_status = CUP_ERR_NOMEM;
  return w->data_status = CUP_ERR_NOMEM;
}

/* Full chunks go to HDF5 as they fill; H5Fflush runs only once a second.
 * A kill can damage the file only while H5Fflush rewrites metadata in place
 * (B-tree nodes, object headers, in HDF5's order, not ours). Flushing after
 * every chunk put a fast run inside that window most of the time (1 of 40
 * kills left /t and /x of different lengths); once a second keeps it to a
 * fraction of a millisecond per second, and rows reach a reader through a
 * completed H5Fflush either way. A few entries of x are copied in a loop
 * (memcpy's call was about 16 instructions a row for the converters' 1 to
 * 3); a row of the precision rectifier took 109 instructions, now 82. */
int cup_h5run_append(cup_h5run *w, double t, const double *x, const double *sig) {
  if (!w || !x || (w->nsig && !sig)) return CUP_ERR_ARG;
  if (w->data_status != CUP_OK) return w->data_status;
  if (!w->tbuf && take_buffers(w) != CUP_OK) return w->data_status;
  return w->dim > 4 ? put_row_wide(w, t, x, sig, 1) : put_row(w, t, x, sig, 1, 0);
}

/* h5run_take_row's first row, a failed writer's and a wide one: out of line
 * (a row's path saved 5 registers and a frame for take_buffers' call). */
static __attribute__((noinline)) int take_row_cold(cup_h5run *w, double t, const double *x, const double *sig,
                                                   size_t ss) {
  if (w->data_status != CUP_OK) return 0;
  if (!w->tbuf && take_buffers(w) != CUP_OK) return 0;
  return (w->dim > 4 ? put_row_wide(w, t, x, sig, ss) : put_row(w, t, x, sig, ss, 0)) == CUP_OK;
}

int h5run_take_row(cup_h5run *w, double t, const double *x, const double *sig, int stride) {
  size_t ss = (size_t)stride;
  if (w->data_status != CUP_OK || !w->tbuf || w->dim > 4) return take_row_cold(w, t, x, sig, ss);
  return put_row(w, t, x, sig, ss, 0) == CUP_OK;
}

/* Whole runs of rows up to the next look at the clock or the chunk's end,
 * whichever is first: there tick or write_buffer, as put_row does after
 * that row (the same rows written, flushed and failed; a column's copy a
 * run of rows rather than a call a row: the signals come by columns, as
 * the buffer holds them; by rows, their transposition was 6 instructions
 * a value, 55 k of the precision rectifier's 3001 samples). */
int h5run_append_rows(cup_h5run *w, int count, const double *t, const double *x, const double *sig, int stride,
                      int *done) {
  if (done) *done = 0;
  if (!w || count < 0 || !done || (count && (!t || !x || (w->nsig && (!sig || stride < count))))) return CUP_ERR_ARG;
  int dim = w->dim, nsig = w->nsig;
  hsize_t rows = w->chunk_rows;
  if (count && !w->tbuf && w->data_status == CUP_OK && take_buffers(w) != CUP_OK) return w->data_status;
  while (*done < count) {
    if (w->data_status != CUP_OK) return w->data_status;
    hsize_t r = w->nbuf, m = room(w) - r;
    if (m > (hsize_t)(count - *done)) m = (hsize_t)(count - *done);
    hsize_t tl = w->tick_left > 0 ? (hsize_t)w->tick_left : 1;   /* (the row that looks at the clock ends a run) */
    if (m > tl) m = tl;
    size_t i0 = (size_t)*done;
    memcpy(w->tbuf + r, t + i0, sizeof(double) * m);
    memcpy(w->xbuf + r * (hsize_t)dim, x + i0 * (size_t)dim, sizeof(double) * m * (size_t)dim);
    for (int k = 0; k < nsig; k++)
      memcpy(w->sbuf + (size_t)k * rows + r, sig + (size_t)k * (size_t)stride + i0, sizeof(double) * m);
    w->nbuf = r + m;
    w->tick_left -= (int)m;
    int st = CUP_OK;
    if (w->tick_left <= 0) st = tick(w);
    else if (w->nbuf >= room(w)) st = write_buffer(w);
    *done += (int)m - (st != CUP_OK);
    if (st != CUP_OK) return st;
  }
  return CUP_OK;
}

int cup_h5run_event(double t, int row, int on, void *ctx) {
  cup_h5run *w = ctx;
  if (!w) return CUP_ERR_ARG;
  if (w->data_status != CUP_OK) return w->data_status;
  w->ebuf[w->enbuf++] = (h5_event){t, (int32_t)row, (int8_t)(on != 0)};
  if (w->enbuf == EVENT_ROWS || tick_seconds() - w->last_flush >= FLUSH_SECONDS) return cup_h5run_flush(w);
  return CUP_OK;
}

int cup_h5run_sink(long k, double t, const double *x, void *ctx) {
  (void)k;
  return cup_h5run_append(ctx, t, x, NULL);
}

long cup_h5run_count(const cup_h5run *w) {
  return w ? (long)(w->written + w->nbuf) : 0;
}

/* The board HAL (whisker/hal.h) on a PC, for the firmware tests and the simulator's virtual
 * whisker board. Plain C99 with no OS calls, so the same code also runs on an AVR under simavr.
 *
 * Contexts: hal.h is a set of global functions, but the simulator runs several boards in one
 * process. All HAL state lives in a hal_host_t; hal_host_bind() selects the one the hal_*()
 * calls act on. Single-threaded: bind a board's context, then run its sampler_tick() /
 * board_poll(), then bind the next. A hal_*() call with no context bound returns FW_EINVAL
 * (hal_irq_save/restore assert instead). The context does not own its link buffer.
 *
 * SPI (fake master with a scriptable sensor on the other end):
 *  - hal_spi_start(): FW_EINVAL for null buffers or n == 0; FW_EBUSY if `spi_refuse` is set
 *    (counted in spi_refused) or a transfer is under way; else the transfer begins and will
 *    report FW_EBUSY to the next `spi_busy_polls` hal_spi_poll() calls (negative: it never
 *    completes, a stuck bus, until hal_spi_abort()).
 *  - hal_spi_poll(): on the completing call the responder `spi(spi_user, tx, rx, n)` is called
 *    and must fill rx[0..n-1] (on the wire the last byte arrives at completion). With no
 *    responder, or if it returns non-zero, rx is filled with 0xFF as an idle, pulled-up MISO
 *    line reads. FW_OK with nothing under way (the last transfer has completed).
 *  - hal_spi_abort(): ends a transfer, counts it in spi_aborts, FW_OK.
 *  The knobs may be changed between calls; spi_busy_polls is read when a transfer starts.
 *
 * Link (what the board sends to the bridge): bytes written go into `link_buf` (capacity
 * `link_cap`, caller's storage). hal_link_write() returns FW_EBUSY and queues nothing when
 * `link_refuse` is set or the bytes do not fit (counted in link_refused). Tests and virtual
 * boards take bytes out with hal_host_link_drain().
 *
 * Interrupts: hal_irq_save() returns the current depth and increments it; hal_irq_restore()
 * asserts the depth is non-zero and that `state` is the matching save's, then restores it.
 * irq_depth must be 0 between calls (hal_host_irq_balanced()).
 *
 * Timer: hal_timer_start() records the rate in timer_hz (FW_EINVAL for 0). Nothing ticks on
 * its own: the test or simulator calls sampler_tick() at its own pace (2 kHz simulated). */
#ifndef WHISKER_HAL_HOST_H
#define WHISKER_HAL_HOST_H

#include <stdint.h>

#include "whisker/hal.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The sensor side of an SPI transfer: fills rx[0..n-1] from tx; 0 on success. */
typedef int (*hal_host_spi_fn)(void *user, const uint8_t *tx, uint8_t *rx, uint8_t n);

typedef struct {
  /* ---- SPI: set by the user ---- */
  hal_host_spi_fn spi;    /* responder, may be NULL (reads 0xFF) */
  void *spi_user;         /* passed to spi() */
  uint8_t spi_refuse;     /* knob: non-zero makes hal_spi_start() return FW_EBUSY */
  int16_t spi_busy_polls; /* knob: polls reporting FW_EBUSY per transfer; < 0 never completes */
  /* ---- SPI: state and counters, read-only for the user ---- */
  uint8_t spi_active;       /* a transfer is under way */
  int16_t spi_polls_left;   /* FW_EBUSY polls left for it (< 0: stuck) */
  const uint8_t *spi_tx;
  uint8_t *spi_rx;
  uint8_t spi_n;
  uint16_t spi_starts;      /* transfers begun */
  uint16_t spi_completed;   /* transfers completed (responder called) */
  uint16_t spi_refused;     /* starts refused by the knob or an active transfer */
  uint16_t spi_aborts;      /* hal_spi_abort() calls */

  /* ---- Link: set by the user (hal_host_init) ---- */
  uint8_t *link_buf;      /* caller's storage, link_cap bytes */
  uint16_t link_cap;
  uint8_t link_refuse;    /* knob: non-zero makes hal_link_write() return FW_EBUSY */
  /* ---- Link: state and counters ---- */
  uint16_t link_len;      /* bytes waiting in link_buf */
  uint16_t link_writes;   /* accepted hal_link_write() calls */
  uint16_t link_refused;  /* hal_link_write() calls answered FW_EBUSY */

  /* ---- Interrupt masking ---- */
  uint16_t irq_depth;     /* hal_irq_save() calls not yet restored */
  uint16_t irq_saves;     /* hal_irq_save() calls in all */

  /* ---- Timer ---- */
  uint16_t timer_hz;      /* rate given to the last hal_timer_start(), 0 if none */
  uint16_t timer_starts;
} hal_host_t;

/* Zeroes ctx (no responder, no fault knobs) and gives it link storage (may be NULL with
 * cap 0: every write is then refused). Does not bind it. */
void hal_host_init(hal_host_t *ctx, uint8_t *link_buf, uint16_t link_cap);

/* Selects the context that the hal_*() functions act on; NULL unbinds. */
void hal_host_bind(hal_host_t *ctx);

/* The bound context, or NULL. */
hal_host_t *hal_host_bound(void);

/* Moves up to `max` of the oldest link bytes into `out` (out may be NULL to discard them) and
 * returns how many were moved. */
uint16_t hal_host_link_drain(hal_host_t *ctx, uint8_t *out, uint16_t max);

/* 1 if every hal_irq_save() has been restored, else 0. */
uint8_t hal_host_irq_balanced(const hal_host_t *ctx);

#ifdef __cplusplus
}
#endif

#endif

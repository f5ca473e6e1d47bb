/* The board's hardware abstraction: one interface, two implementations (hal/dspic33 on the
 * target, hal/host on a PC for tests and the simulator's virtual whisker board).
 * Every call returns FW_OK or a negative FW_E* code (error.h). */
#ifndef WHISKER_HAL_H
#define WHISKER_HAL_H

#include <stdint.h>

/* ---- SPI master to the MLX90333 (3-wire, mode 1, <= 320 kHz) ----
 * Starts a non-blocking full-duplex transfer of n bytes with chip select asserted for its
 * duration: tx is clocked out, rx filled. FW_EBUSY if a transfer is under way. The buffers must
 * stay valid until hal_spi_poll() reports completion. */
int hal_spi_start(const uint8_t *tx, uint8_t *rx, uint8_t n);

/* FW_OK when the last transfer has completed (chip select released), FW_EBUSY while it runs. */
int hal_spi_poll(void);

/* Aborts a transfer that never completed: releases chip select and resets the peripheral.
 * Always FW_OK. */
int hal_spi_abort(void);

/* ---- Link to the FPGA bridge (UART, docs/protocol.md) ----
 * Queues n bytes for transmission without blocking: FW_OK if all were queued, FW_EBUSY (and
 * nothing queued) if the transmit buffer lacks room. */
int hal_link_write(const uint8_t *data, uint8_t n);

/* ---- Timer: calls sampler_tick() from its interrupt at `hz` ---- */
int hal_timer_start(uint16_t hz);

/* ---- Interrupt masking around the ring's consumer side (ring.h) ---- */
typedef uint16_t hal_irq_state_t;
hal_irq_state_t hal_irq_save(void);
void hal_irq_restore(hal_irq_state_t state);

#endif

/* The 2 kHz sampler: a state machine advanced by the timer ISR, one step per 500 us tick.
 *
 * Each tick collects the transfer started at the previous tick and starts the next one, so the
 * ISR never waits on the bus (O(1), no loops over data beyond the 8-byte frame):
 *  - POWERUP: the MLX90333 needs ~16 ms after power-up (SAMPLER_POWERUP_TICKS ticks); samples
 *    pushed then carry BRIDGE_ST_POWERUP with Alpha = Beta = 0, and the bus stays quiet until
 *    the last of those ticks, which starts the first transfer (collected at the first RUN tick).
 *  - RUN: if the previous transfer is still running the sample is BRIDGE_ST_BUSY; after
 *    SAMPLER_TIMEOUT_TICKS ticks it is aborted (hal_spi_abort), the sample is
 *    BRIDGE_ST_TIMEOUT and a new transfer starts at once. If hal_spi_start() refuses, that is
 *    counted in spi_error and the next tick, having nothing to collect, is BRIDGE_ST_BUSY.
 *    A completed frame is decoded (mlx90333.h): a bad start byte or checksum gives
 *    BRIDGE_ST_BAD_START / BRIDGE_ST_CHECKSUM; a frame identical to the previous good one
 *    (the sensor has not refreshed) gives BRIDGE_ST_STALE; MLX diagnostics are copied in as
 *    MLX_ST_* bits.
 *    Samples with a NO_DATA bit (bridge_frame.h) carry Alpha = Beta = 0; STALE and diagnostic
 *    samples carry the values the sensor sent, flagged. (An emulator that answers the same
 *    deflection twice in a row therefore sees STALE: a real sensor's LSBs never hold still.)
 * Every tick pushes exactly one sample into the ring, with status 0 only for a fresh, valid
 * measurement. A sample that is not fresh and valid is never passed on as if it were.
 * Each fault has a counter in sampler_counters_t. */
#ifndef WHISKER_SAMPLER_H
#define WHISKER_SAMPLER_H

#include <stdint.h>

#include "whisker/mlx90333.h"
#include "whisker/ring.h"

#define SAMPLER_HZ 2000u
#define SAMPLER_POWERUP_TICKS 32u  /* 16 ms at 2 kHz */
#define SAMPLER_TIMEOUT_TICKS 3u   /* a transfer still running 1.5 ms after it began is stuck */

typedef enum { SAMPLER_POWERUP = 0, SAMPLER_RUN = 1 } sampler_state_t;

typedef struct {
  uint16_t ok;
  uint16_t stale;
  uint16_t bad_start;
  uint16_t checksum;
  uint16_t timeout;
  uint16_t busy;
  uint16_t diag;      /* samples with any MLX_ST_* bit */
  uint16_t spi_error; /* hal_spi_start() refused */
} sampler_counters_t; /* all saturate at 0xFFFF */

typedef struct {
  sampler_state_t state;
  uint32_t tick;
  uint8_t in_flight;       /* a transfer was started and not yet collected */
  uint8_t busy_ticks;      /* ticks the current transfer has been running */
  uint8_t have_last;       /* last_frame holds a previous good frame */
  uint8_t tx[MLX_FRAME_LEN];
  uint8_t rx[MLX_FRAME_LEN];
  uint8_t last_frame[MLX_FRAME_LEN];
  sampler_counters_t counters;
  ring_t *ring;
} sampler_t;

void sampler_init(sampler_t *s, ring_t *ring);
/* One 500 us step; called from the timer ISR (or a test). */
void sampler_tick(sampler_t *s);

#endif

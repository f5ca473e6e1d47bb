/* The 2 kHz sampler state machine (sampler.h). Runs in the timer ISR: O(1), never waits on the
 * bus, loops only over the 8-byte MLX frame. */
#include "whisker/sampler.h"

#include <stddef.h>

#include "whisker/bridge_frame.h"
#include "whisker/error.h"
#include "whisker/hal.h"

static void count(uint16_t *c) {
  if (*c != 0xFFFFu) *c = (uint16_t)(*c + 1u);
}

void sampler_init(sampler_t *s, ring_t *ring) {
  uint8_t i;
  if (s == NULL) return;
  s->state = SAMPLER_POWERUP;
  s->tick = 0u;
  s->in_flight = 0u;
  s->busy_ticks = 0u;
  s->have_last = 0u;
  for (i = 0u; i < MLX_FRAME_LEN; ++i) {
    s->tx[i] = 0xFFu; /* the master clocks out 0xFF while the sensor answers */
    s->rx[i] = 0u;
    s->last_frame[i] = 0u;
  }
  s->counters.ok = 0u;
  s->counters.stale = 0u;
  s->counters.bad_start = 0u;
  s->counters.checksum = 0u;
  s->counters.timeout = 0u;
  s->counters.busy = 0u;
  s->counters.diag = 0u;
  s->counters.spi_error = 0u;
  s->ring = ring;
}

/* Starts the next transfer. rx is cleared first so that a transfer which "completes" without
 * filling it can never be read as the sensor's data (it fails the start byte instead). A refusal
 * is counted here; the next tick then has nothing to collect and reports BRIDGE_ST_BUSY. */
static void sampler_start(sampler_t *s) {
  uint8_t i;
  int rc;
  for (i = 0u; i < MLX_FRAME_LEN; ++i) s->rx[i] = 0u;
  rc = hal_spi_start(s->tx, s->rx, (uint8_t)MLX_FRAME_LEN);
  if (rc == FW_OK) {
    s->in_flight = 1u;
    s->busy_ticks = 0u;
  } else {
    s->in_flight = 0u;
    count(&s->counters.spi_error);
  }
}

static uint8_t same_as_last(const sampler_t *s) {
  uint8_t i;
  for (i = 0u; i < MLX_FRAME_LEN; ++i) {
    if (s->rx[i] != s->last_frame[i]) return 0u;
  }
  return 1u;
}

/* Decodes the completed frame in rx into `out` and returns its status bits. */
static uint16_t sampler_decode(sampler_t *s, ring_sample_t *out) {
  mlx_sample_t m;
  uint16_t status = 0u;
  uint8_t i;
  int rc = mlx_decode(s->rx, &m);
  if (rc == FW_ESTART) {
    count(&s->counters.bad_start);
    return BRIDGE_ST_BAD_START;
  }
  if (rc != FW_OK) { /* FW_ECHECKSUM (FW_EINVAL cannot happen: both pointers are ours) */
    count(&s->counters.checksum);
    return BRIDGE_ST_CHECKSUM;
  }
  if (s->have_last != 0u && same_as_last(s) != 0u) {
    status = BRIDGE_ST_STALE;
    count(&s->counters.stale);
  } else {
    for (i = 0u; i < MLX_FRAME_LEN; ++i) s->last_frame[i] = s->rx[i];
    s->have_last = 1u;
  }
  if (m.status != 0u) {
    status = (uint16_t)(status | m.status);
    count(&s->counters.diag);
  }
  out->alpha = m.alpha;
  out->beta = m.beta;
  return status;
}

/* RUN state: collects the transfer started at an earlier tick. Returns the sample's status. */
static uint16_t sampler_collect(sampler_t *s, ring_sample_t *out) {
  int rc;
  if (s->in_flight == 0u) {
    /* The start at the previous tick was refused: there is nothing to collect. */
    count(&s->counters.busy);
    return BRIDGE_ST_BUSY;
  }
  rc = hal_spi_poll();
  if (rc == FW_OK) {
    s->in_flight = 0u;
    return sampler_decode(s, out);
  }
  if (rc == FW_EBUSY) {
    s->busy_ticks = (uint8_t)(s->busy_ticks + 1u);
    if (s->busy_ticks < SAMPLER_TIMEOUT_TICKS) {
      count(&s->counters.busy);
      return BRIDGE_ST_BUSY;
    }
    count(&s->counters.timeout);
  } else {
    /* Not in hal.h's contract for hal_spi_poll(): treat as a transfer that did not finish. */
    count(&s->counters.spi_error);
  }
  if (hal_spi_abort() != FW_OK) count(&s->counters.spi_error);
  s->in_flight = 0u;
  return BRIDGE_ST_TIMEOUT;
}

void sampler_tick(sampler_t *s) {
  ring_sample_t out;
  if (s == NULL || s->ring == NULL) return;
  out.tick = s->tick;
  out.alpha = 0u;
  out.beta = 0u;
  if (s->state == SAMPLER_POWERUP) {
    out.status = BRIDGE_ST_POWERUP;
    if (s->tick + 1u >= (uint32_t)SAMPLER_POWERUP_TICKS) {
      /* Last power-up tick: start the first transfer so the first RUN tick has a frame. The
       * sensor's ~16 ms start-up runs from supply rise, which precedes tick 0 by the MCU's own
       * power-up timer and clock start-up; a frame read too early fails its checks anyway. */
      s->state = SAMPLER_RUN;
      sampler_start(s);
    }
  } else {
    out.status = sampler_collect(s, &out);
    if (out.status == 0u) count(&s->counters.ok);
    if (s->in_flight == 0u) sampler_start(s);
  }
  s->tick = s->tick + 1u;
  ring_push(s->ring, &out);
}

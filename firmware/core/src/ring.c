/* The ISR-to-main-loop sample ring (ring.h has the concurrency rules). */
#include "whisker/ring.h"

#include <stddef.h>

#include "whisker/bridge_frame.h"
#include "whisker/error.h"
#include "whisker/hal.h"

#define RING_MASK ((uint8_t)(RING_CAPACITY - 1u))

#if (RING_CAPACITY & (RING_CAPACITY - 1u)) != 0u || RING_CAPACITY > 128u
#error "RING_CAPACITY must be a power of two no larger than 128 (uint8_t indices)"
#endif

void ring_init(ring_t *r) {
  uint8_t i;
  if (r == NULL) return;
  for (i = 0u; i < RING_CAPACITY; ++i) {
    r->items[i].tick = 0u;
    r->items[i].alpha = 0u;
    r->items[i].beta = 0u;
    r->items[i].status = 0u;
  }
  r->head = 0u;
  r->tail = 0u;
  r->count = 0u;
  r->dropped = 0u;
}

/* ISR side. O(1): at most one drop and one copy. */
void ring_push(ring_t *r, const ring_sample_t *s) {
  uint8_t head;
  if (r == NULL || s == NULL) return;
  if (r->count >= RING_CAPACITY) {
    /* Full: drop the oldest and mark the new oldest, the sample right after the gap. Safe
     * because the consumer only touches tail/count/items with this interrupt masked. */
    r->tail = (uint8_t)((r->tail + 1u) & RING_MASK);
    r->count = (uint8_t)(r->count - 1u);
    if (r->dropped != 0xFFFFu) r->dropped = (uint16_t)(r->dropped + 1u);
    r->items[r->tail].status = (uint16_t)(r->items[r->tail].status | BRIDGE_ST_DROPPED);
  }
  head = r->head;
  r->items[head] = *s;
  r->head = (uint8_t)((head + 1u) & RING_MASK);
  r->count = (uint8_t)(r->count + 1u);
}

int ring_pop(ring_t *r, ring_sample_t *out) {
  uint8_t tail;
  if (r == NULL || out == NULL) return FW_EINVAL;
  if (r->count == 0u) return FW_EEMPTY;
  tail = r->tail;
  *out = r->items[tail];
  r->tail = (uint8_t)((tail + 1u) & RING_MASK);
  r->count = (uint8_t)(r->count - 1u);
  return FW_OK;
}

int ring_pop_irqsafe(ring_t *r, ring_sample_t *out) {
  int rc;
  hal_irq_state_t st = hal_irq_save();
  rc = ring_pop(r, out);
  hal_irq_restore(st);
  return rc;
}

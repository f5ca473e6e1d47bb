/* The whisker board's main loop (board.h): ring -> bridge frame -> link. */
#include "whisker/board.h"

#include <stddef.h>

#include "whisker/error.h"
#include "whisker/hal.h"

int board_init(board_t *b, uint8_t board_id) {
  uint8_t i;
  if (b == NULL || board_id >= BRIDGE_MAX_BOARDS) return FW_EINVAL;
  b->board_id = board_id;
  b->seq = 0u;
  b->pending = 0u;
  for (i = 0u; i < BRIDGE_FRAME_LEN; ++i) b->frame[i] = 0u;
  b->frames_sent = 0u;
  b->link_busy = 0u;
  ring_init(&b->ring);
  sampler_init(&b->sampler, &b->ring);
  return FW_OK;
}

int board_poll(board_t *b) {
  int rc;
  if (b == NULL) return FW_EINVAL;
  if (b->pending == 0u) {
    ring_sample_t s;
    bridge_frame_t f;
    rc = ring_pop_irqsafe(&b->ring, &s);
    if (rc != FW_OK) return rc; /* FW_EEMPTY */
    f.board = b->board_id;
    f.seq = b->seq;
    f.tick = s.tick;
    f.alpha = s.alpha;
    f.beta = s.beta;
    f.status = s.status;
    rc = bridge_encode(&f, b->frame);
    if (rc != FW_OK) return rc; /* cannot happen: board_id was checked by board_init */
    b->seq = (uint16_t)(b->seq + 1u);
    b->pending = 1u;
  }
  rc = hal_link_write(b->frame, (uint8_t)BRIDGE_FRAME_LEN);
  if (rc != FW_OK) {
    /* The frame stays pending and is sent unchanged (same sequence number) next time. */
    if (rc == FW_EBUSY && b->link_busy != 0xFFFFu) b->link_busy = (uint16_t)(b->link_busy + 1u);
    return rc;
  }
  b->pending = 0u;
  b->frames_sent = b->frames_sent + 1u;
  return FW_OK;
}

/* The whisker board's main loop: drains the ring, frames each sample (bridge_frame.h) and writes
 * it to the bridge link. A frame the link cannot take yet is kept and retried, never dropped
 * silently; if the ring overflows meanwhile the loss shows as BRIDGE_ST_DROPPED. */
#ifndef WHISKER_BOARD_H
#define WHISKER_BOARD_H

#include <stdint.h>

#include "whisker/bridge_frame.h"
#include "whisker/ring.h"
#include "whisker/sampler.h"

typedef struct {
  uint8_t board_id;
  uint16_t seq;
  uint8_t pending;                        /* frame[] waits for the link */
  uint8_t frame[BRIDGE_FRAME_LEN];
  uint32_t frames_sent;
  uint16_t link_busy;                     /* hal_link_write() said FW_EBUSY, saturating */
  ring_t ring;
  sampler_t sampler;
} board_t;

/* Initialises the ring and sampler. FW_EINVAL if board_id >= BRIDGE_MAX_BOARDS. */
int board_init(board_t *b, uint8_t board_id);
/* Moves at most one sample from the ring to the link. FW_OK if a frame went out, FW_EEMPTY if
 * there was nothing to send, FW_EBUSY if the link is full (the frame stays pending). */
int board_poll(board_t *b);

#endif

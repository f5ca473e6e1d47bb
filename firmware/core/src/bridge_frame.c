/* Bridge frame encode/decode and CRC-16 (bridge_frame.h, docs/protocol.md). Pure functions. */
#include "whisker/bridge_frame.h"

#include <stddef.h>

#include "whisker/error.h"

#define BRIDGE_OFF_SYNC0 0u
#define BRIDGE_OFF_SYNC1 1u
#define BRIDGE_OFF_BOARD 2u
#define BRIDGE_OFF_VERSION 3u
#define BRIDGE_OFF_SEQ 4u
#define BRIDGE_OFF_TICK 6u
#define BRIDGE_OFF_ALPHA 10u
#define BRIDGE_OFF_BETA 12u
#define BRIDGE_OFF_STATUS 14u
#define BRIDGE_OFF_CRC 16u
#define BRIDGE_CRC_FIRST 2u /* the CRC covers bytes 2..15 */

static void put16(uint8_t *p, uint16_t v) {
  p[0] = (uint8_t)(v & 0xFFu);
  p[1] = (uint8_t)(v >> 8);
}

static uint16_t get16(const uint8_t *p) {
  return (uint16_t)((uint16_t)p[0] | (uint16_t)((uint16_t)p[1] << 8));
}

static void put32(uint8_t *p, uint32_t v) {
  p[0] = (uint8_t)(v & 0xFFu);
  p[1] = (uint8_t)((v >> 8) & 0xFFu);
  p[2] = (uint8_t)((v >> 16) & 0xFFu);
  p[3] = (uint8_t)(v >> 24);
}

static uint32_t get32(const uint8_t *p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
         ((uint32_t)p[3] << 24);
}

/* Bitwise, MSB first, no reflection, no final XOR. A 256-entry table would cost 512 B of flash
 * for a routine that runs in the main loop over 14 bytes; the bitwise loop is enough. */
uint16_t bridge_crc16(const uint8_t *data, uint16_t n) {
  uint16_t crc = 0xFFFFu;
  uint16_t i;
  uint8_t bit;
  if (data == NULL) return crc;
  for (i = 0u; i < n; ++i) {
    crc = (uint16_t)(crc ^ (uint16_t)((uint16_t)data[i] << 8));
    for (bit = 0u; bit < 8u; ++bit) {
      if ((crc & 0x8000u) != 0u) {
        crc = (uint16_t)((uint16_t)(crc << 1) ^ 0x1021u);
      } else {
        crc = (uint16_t)(crc << 1);
      }
    }
  }
  return crc;
}

int bridge_encode(const bridge_frame_t *f, uint8_t out[BRIDGE_FRAME_LEN]) {
  if (f == NULL || out == NULL || f->board >= BRIDGE_MAX_BOARDS) return FW_EINVAL;
  out[BRIDGE_OFF_SYNC0] = (uint8_t)BRIDGE_SYNC0;
  out[BRIDGE_OFF_SYNC1] = (uint8_t)BRIDGE_SYNC1;
  out[BRIDGE_OFF_BOARD] = f->board;
  out[BRIDGE_OFF_VERSION] = (uint8_t)BRIDGE_VERSION;
  put16(&out[BRIDGE_OFF_SEQ], f->seq);
  put32(&out[BRIDGE_OFF_TICK], f->tick);
  put16(&out[BRIDGE_OFF_ALPHA], f->alpha);
  put16(&out[BRIDGE_OFF_BETA], f->beta);
  put16(&out[BRIDGE_OFF_STATUS], f->status);
  put16(&out[BRIDGE_OFF_CRC],
        bridge_crc16(&out[BRIDGE_CRC_FIRST], (uint16_t)(BRIDGE_OFF_CRC - BRIDGE_CRC_FIRST)));
  return FW_OK;
}

int bridge_decode(const uint8_t in[BRIDGE_FRAME_LEN], bridge_frame_t *out) {
  uint16_t crc;
  if (in == NULL || out == NULL) return FW_EINVAL;
  if (in[BRIDGE_OFF_SYNC0] != BRIDGE_SYNC0 || in[BRIDGE_OFF_SYNC1] != BRIDGE_SYNC1) {
    return FW_ESYNC;
  }
  crc = bridge_crc16(&in[BRIDGE_CRC_FIRST], (uint16_t)(BRIDGE_OFF_CRC - BRIDGE_CRC_FIRST));
  if (crc != get16(&in[BRIDGE_OFF_CRC])) return FW_ECRC;
  if (in[BRIDGE_OFF_VERSION] != BRIDGE_VERSION || in[BRIDGE_OFF_BOARD] >= BRIDGE_MAX_BOARDS) {
    return FW_EINVAL;
  }
  out->board = in[BRIDGE_OFF_BOARD];
  out->seq = get16(&in[BRIDGE_OFF_SEQ]);
  out->tick = get32(&in[BRIDGE_OFF_TICK]);
  out->alpha = get16(&in[BRIDGE_OFF_ALPHA]);
  out->beta = get16(&in[BRIDGE_OFF_BETA]);
  out->status = get16(&in[BRIDGE_OFF_STATUS]);
  return FW_OK;
}

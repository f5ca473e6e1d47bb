/* Bridge frame encode/decode and CRC-16 (bridge_frame.h, docs/protocol.md). Pure functions. */
#include "whisker/bridge_frame.h"

#include <stddef.h>

#include "whisker/error.h"
#include "bridge_crc16_tables.h"

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

/* The definition: bitwise, MSB first, no reflection, no final XOR. The tables, the tests and the
 * bench are checked against it. */
uint16_t bridge_crc16_bitwise(const uint8_t *data, uint16_t n) {
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

/* By table (bridge_crc16_tables.h, 512 B of flash): one look-up per byte instead of eight
 * shift-and-XOR steps. The host builds it with BRIDGE_CRC_SLICE8 (4 KB of tables): a frame's 14
 * bytes are then two steps of independent look-ups, 8 bytes and 6, instead of 14 dependent ones
 * (docs/BENCHMARKS.md, "Issue 15"). The CRC is linear: the register folds into the block's first
 * two bytes and each byte's share is its table entry for the bytes that follow it. */
#ifdef BRIDGE_CRC_SLICE8
static uint16_t crc16_block(uint16_t crc, const uint8_t *p, uint16_t m) {
  /* 2 <= m <= 8 */
  uint16_t r = (uint16_t)(bridge_crc16_t[m - 1u][(uint8_t)((crc >> 8) ^ p[0])] ^
                          bridge_crc16_t[m - 2u][(uint8_t)((crc & 0xFFu) ^ p[1])]);
  uint16_t k;
  for (k = 2u; k < m; ++k) r = (uint16_t)(r ^ bridge_crc16_t[m - 1u - k][p[k]]);
  return r;
}
#endif

uint16_t bridge_crc16(const uint8_t *data, uint16_t n) {
  uint16_t crc = 0xFFFFu;
  uint16_t i = 0u;
  if (data == NULL) return crc;
#ifdef BRIDGE_CRC_SLICE8
  for (; (uint16_t)(n - i) >= 8u; i = (uint16_t)(i + 8u)) crc = crc16_block(crc, &data[i], 8u);
  if ((uint16_t)(n - i) >= 2u) {
    crc = crc16_block(crc, &data[i], (uint16_t)(n - i));
    i = n;
  }
#endif
  for (; i < n; ++i) {
    crc = (uint16_t)((uint16_t)(crc << 8) ^ bridge_crc16_t[0][(uint8_t)((crc >> 8) ^ data[i])]);
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

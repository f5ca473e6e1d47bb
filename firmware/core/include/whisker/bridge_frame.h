/* The whisker board's output frame to the FPGA bridge (docs/protocol.md is the definition; the
 * host decoder and the virtual bridge use this same code). Little-endian, 18 bytes:
 *   off len field
 *    0   2  sync 0xA5 0x5A
 *    2   1  board id (0..27)
 *    3   1  protocol version (BRIDGE_VERSION)
 *    4   2  sequence number, +1 per frame, wraps
 *    6   4  timestamp: sampler ticks of 500 us since power-up
 *   10   2  Alpha
 *   12   2  Beta
 *   14   2  status: 0 = a fresh, valid sample; else BRIDGE_ST_* | MLX_ST_* bits
 *   16   2  CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF) of bytes 2..15
 */
#ifndef WHISKER_BRIDGE_FRAME_H
#define WHISKER_BRIDGE_FRAME_H

#include <stdint.h>

#define BRIDGE_FRAME_LEN 18u
#define BRIDGE_SYNC0 0xA5u
#define BRIDGE_SYNC1 0x5Au
#define BRIDGE_VERSION 1u
#define BRIDGE_MAX_BOARDS 28u

/* Sampler status bits (bits 0..7); bits 8..14 are the MLX_ST_* diagnostics (mlx90333.h). */
#define BRIDGE_ST_STALE 0x0001u     /* the sensor repeated its last sample: not fresh */
#define BRIDGE_ST_BAD_START 0x0002u /* MLX frame start byte wrong */
#define BRIDGE_ST_CHECKSUM 0x0004u  /* MLX frame checksum wrong */
#define BRIDGE_ST_TIMEOUT 0x0008u   /* the SPI transfer did not finish: bus stuck */
#define BRIDGE_ST_BUSY 0x0010u      /* the bus was still busy at the tick: sample skipped */
#define BRIDGE_ST_POWERUP 0x0020u   /* within the sensor's power-up window: no data yet */
#define BRIDGE_ST_DROPPED 0x0040u   /* the ring overflowed before this sample: data was lost */
#define BRIDGE_ST_NO_DATA 0x003Eu   /* these mean Alpha and Beta carry no measurement (0) */
/* STALE, DROPPED and the MLX_ST_* bits leave Alpha and Beta as measured, but the sample is
 * still not "fresh and valid": only status 0 is. */

typedef struct {
  uint8_t board;
  uint16_t seq;
  uint32_t tick;
  uint16_t alpha;
  uint16_t beta;
  uint16_t status;
} bridge_frame_t;

/* CRC-16/CCITT-FALSE of n bytes (check value: "123456789" -> 0x29B1), by table: 512 B of flash;
 * built with BRIDGE_CRC_SLICE8 defined (the host build does), slicing-by-8 with 4 KB of tables. */
uint16_t bridge_crc16(const uint8_t *data, uint16_t n);

/* The same CRC bit by bit: the definition, for tests and benchmarks to compare with. */
uint16_t bridge_crc16_bitwise(const uint8_t *data, uint16_t n);

/* Writes the 18 bytes of `f`. FW_EINVAL for null pointers or board >= BRIDGE_MAX_BOARDS. */
int bridge_encode(const bridge_frame_t *f, uint8_t out[BRIDGE_FRAME_LEN]);

/* Decodes 18 bytes. FW_OK, FW_ESYNC, FW_ECRC, or FW_EINVAL (version or board out of range);
 * `out` is written only on FW_OK. */
int bridge_decode(const uint8_t in[BRIDGE_FRAME_LEN], bridge_frame_t *out);

#endif

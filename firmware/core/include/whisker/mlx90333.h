/* MLX90333 Triaxis SPI frame in Alpha/Beta mode (paper §2.1): pure decoding, no bus access.
 *
 * 8 bytes per chip-select, the master clocking out 0xFF:
 *   [0] start byte 0xFF, [1..2] Alpha LSB first, [3..4] Beta LSB first,
 *   [5..6] diagnostic word LSB first, [7] checksum.
 * The checksum is taken as the 8-bit sum of bytes 1..6 (mlx_checksum). Only one public driver
 * corroborates that; the datasheet's serial-protocol section is what confirms it, and this one
 * function is what to change if the bench says otherwise (test vectors in test/firmware). */
#ifndef WHISKER_MLX90333_H
#define WHISKER_MLX90333_H

#include <stdint.h>

#define MLX_FRAME_LEN 8u
#define MLX_START_BYTE 0xFFu

/* Decoded status bits of the diagnostic word; also used in the bridge frame's status field
 * (bridge_frame.h), bits 8..15. Bit positions in the diagnostic word are in mlx_diag_status(). */
#define MLX_ST_ADC_FAIL 0x0100u    /* ADC monitor failure */
#define MLX_ST_ADC_SAT 0x0200u     /* ADC saturation (electrical or magnetic) */
#define MLX_ST_FIELD_LOW 0x0400u   /* magnetic field too low: magnet lost or too far */
#define MLX_ST_FIELD_HIGH 0x0800u  /* magnetic field too high: magnet too close */
#define MLX_ST_GAIN_CLAMP 0x1000u  /* gain at its clamp (field out of the AGC range) */
#define MLX_ST_DEAD_ZONE 0x2000u   /* output in an angular dead zone */
#define MLX_ST_MEM_FAIL 0x4000u    /* ROM/EEPROM check failed */
#define MLX_ST_DIAG_MASK 0x7F00u

typedef struct {
  uint16_t alpha;
  uint16_t beta;
  uint16_t diag;    /* the raw diagnostic word */
  uint16_t status;  /* mlx_diag_status(diag) */
} mlx_sample_t;

/* The frame's checksum over bytes 1..6. */
uint8_t mlx_checksum(const uint8_t frame[MLX_FRAME_LEN]);

/* Decodes a frame. Returns FW_OK, FW_ESTART or FW_ECHECKSUM; `out` is written only on FW_OK.
 * FW_EINVAL for null pointers. */
int mlx_decode(const uint8_t frame[MLX_FRAME_LEN], mlx_sample_t *out);

/* Maps the raw diagnostic word to MLX_ST_* bits. */
uint16_t mlx_diag_status(uint16_t diag);

/* Encodes a frame (the inverse of mlx_decode): used by the emulator and the tests. */
void mlx_encode(uint16_t alpha, uint16_t beta, uint16_t diag, uint8_t frame[MLX_FRAME_LEN]);

#endif

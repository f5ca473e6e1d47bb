/* MLX90333 Alpha/Beta frame decoding (mlx90333.h). Pure functions: no bus access.
 *
 * 16-bit int safety: every byte is widened to uint16_t before a shift and every sum is kept
 * in a uint16_t or uint8_t explicitly, so the arithmetic is the same on the dsPIC (16-bit int)
 * and on a PC (32-bit int). */
#include "whisker/mlx90333.h"

#include <stddef.h>

#include "whisker/error.h"

/* Byte offsets in the 8-byte frame. */
#define MLX_OFF_START 0u
#define MLX_OFF_ALPHA 1u
#define MLX_OFF_BETA 3u
#define MLX_OFF_DIAG 5u
#define MLX_OFF_CRC 7u

static uint16_t mlx_get16(const uint8_t *p) {
  return (uint16_t)((uint16_t)p[0] | (uint16_t)((uint16_t)p[1] << 8));
}

static void mlx_put16(uint8_t *p, uint16_t v) {
  p[0] = (uint8_t)(v & 0xFFu);
  p[1] = (uint8_t)(v >> 8);
}

/* The checksum is the 8-bit sum (mod 256) of bytes 1..6. This is the only place that knows it:
 * one public driver corroborates the sum; the datasheet's serial-protocol section ("SPI frame",
 * checksum definition) is what confirms it. If the bench disagrees (e.g. an inverted sum or an
 * XOR), change this function and the vectors in test/firmware/core_test.c together. */
uint8_t mlx_checksum(const uint8_t frame[MLX_FRAME_LEN]) {
  uint8_t sum = 0u;
  uint8_t i;
  for (i = MLX_OFF_ALPHA; i < MLX_OFF_CRC; ++i) {
    sum = (uint8_t)(sum + frame[i]);
  }
  return sum;
}

/* Raw diagnostic word -> MLX_ST_* bits.
 *
 * The bit positions below follow our reading of the datasheet's diagnostic table (the
 * "Diagnostic" section listing ADC monitor, saturation, field strength, gain and dead-zone
 * flags). They live in this one function and are to be confirmed on the bench: if a position
 * is wrong, only this table changes (and its test in test/firmware). Bits 8..15 of the raw
 * word are ignored.
 *   bit 0  ADC monitor failure          -> MLX_ST_ADC_FAIL
 *   bit 1  ADC saturation               -> MLX_ST_ADC_SAT
 *   bit 2  field too low                -> MLX_ST_FIELD_LOW
 *   bit 3  field too high               -> MLX_ST_FIELD_HIGH
 *   bit 4  gain clamp                   -> MLX_ST_GAIN_CLAMP
 *   bit 5  dead zone                    -> MLX_ST_DEAD_ZONE
 *   bit 6  ROM check failure            -> MLX_ST_MEM_FAIL
 *   bit 7  EEPROM check failure         -> MLX_ST_MEM_FAIL */
#define MLX_DIAG_ADC_FAIL 0x0001u
#define MLX_DIAG_ADC_SAT 0x0002u
#define MLX_DIAG_FIELD_LOW 0x0004u
#define MLX_DIAG_FIELD_HIGH 0x0008u
#define MLX_DIAG_GAIN_CLAMP 0x0010u
#define MLX_DIAG_DEAD_ZONE 0x0020u
#define MLX_DIAG_ROM_FAIL 0x0040u
#define MLX_DIAG_EEPROM_FAIL 0x0080u

uint16_t mlx_diag_status(uint16_t diag) {
  uint16_t st = 0u;
  if ((diag & MLX_DIAG_ADC_FAIL) != 0u) st = (uint16_t)(st | MLX_ST_ADC_FAIL);
  if ((diag & MLX_DIAG_ADC_SAT) != 0u) st = (uint16_t)(st | MLX_ST_ADC_SAT);
  if ((diag & MLX_DIAG_FIELD_LOW) != 0u) st = (uint16_t)(st | MLX_ST_FIELD_LOW);
  if ((diag & MLX_DIAG_FIELD_HIGH) != 0u) st = (uint16_t)(st | MLX_ST_FIELD_HIGH);
  if ((diag & MLX_DIAG_GAIN_CLAMP) != 0u) st = (uint16_t)(st | MLX_ST_GAIN_CLAMP);
  if ((diag & MLX_DIAG_DEAD_ZONE) != 0u) st = (uint16_t)(st | MLX_ST_DEAD_ZONE);
  if ((diag & (MLX_DIAG_ROM_FAIL | MLX_DIAG_EEPROM_FAIL)) != 0u) {
    st = (uint16_t)(st | MLX_ST_MEM_FAIL);
  }
  return st;
}

int mlx_decode(const uint8_t frame[MLX_FRAME_LEN], mlx_sample_t *out) {
  uint16_t diag;
  if (frame == NULL || out == NULL) return FW_EINVAL;
  if (frame[MLX_OFF_START] != MLX_START_BYTE) return FW_ESTART;
  if (mlx_checksum(frame) != frame[MLX_OFF_CRC]) return FW_ECHECKSUM;
  diag = mlx_get16(&frame[MLX_OFF_DIAG]);
  out->alpha = mlx_get16(&frame[MLX_OFF_ALPHA]);
  out->beta = mlx_get16(&frame[MLX_OFF_BETA]);
  out->diag = diag;
  out->status = mlx_diag_status(diag);
  return FW_OK;
}

void mlx_encode(uint16_t alpha, uint16_t beta, uint16_t diag, uint8_t frame[MLX_FRAME_LEN]) {
  if (frame == NULL) return;
  frame[MLX_OFF_START] = (uint8_t)MLX_START_BYTE;
  mlx_put16(&frame[MLX_OFF_ALPHA], alpha);
  mlx_put16(&frame[MLX_OFF_BETA], beta);
  mlx_put16(&frame[MLX_OFF_DIAG], diag);
  frame[MLX_OFF_CRC] = mlx_checksum(frame);
}

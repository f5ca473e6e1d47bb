/* Firmware core tests: frame code, ring, sampler and board driven through the host HAL with a
 * fake MLX90333 that injects each fault. Plain C99 (fw_test.h): the same suite runs natively
 * (fw_core_test) and on an AVR with 16-bit int under simavr (tools/avr-core-test.sh).
 *
 * Every fault test checks three things: the fault reaches the decoded output frame's status,
 * it reaches a counter, and the frame's status is never 0 (0 means a fresh, valid sample). */
#include <stddef.h>
#include <stdint.h>

#include "fw_test.h"
#include "hal_host.h"
#include "whisker/board.h"
#include "whisker/bridge_frame.h"
#include "whisker/error.h"
#include "whisker/mlx90333.h"
#include "whisker/ring.h"
#include "whisker/sampler.h"

/* ---- A fake MLX90333 on the far side of the host HAL's SPI ---- */

typedef struct {
  uint16_t alpha;
  uint16_t beta;
  uint16_t diag;
  uint16_t alpha_step;  /* added to alpha after each answer (0: the sensor repeats itself) */
  uint8_t bad_start;    /* answer with start byte 0x7F */
  uint8_t bad_checksum; /* answer with the checksum off by one */
  uint16_t answers;
} fake_mlx_t;

static int fake_mlx_spi(void *user, const uint8_t *tx, uint8_t *rx, uint8_t n) {
  fake_mlx_t *m = (fake_mlx_t *)user;
  uint8_t frame[MLX_FRAME_LEN];
  uint8_t i;
  (void)tx;
  if (n != MLX_FRAME_LEN) return FW_EINVAL;
  mlx_encode(m->alpha, m->beta, m->diag, frame);
  if (m->bad_start != 0u) frame[0] = 0x7Fu;
  if (m->bad_checksum != 0u) frame[7] = (uint8_t)(frame[7] + 1u);
  for (i = 0u; i < n; ++i) rx[i] = frame[i];
  m->alpha = (uint16_t)(m->alpha + m->alpha_step);
  m->answers = (uint16_t)(m->answers + 1u);
  return 0;
}

/* ---- One board on the host HAL ---- */

#define LINK_CAP 64u

typedef struct {
  hal_host_t hal;
  uint8_t link[LINK_CAP];
  fake_mlx_t mlx;
  board_t board;
} fixture_t;

static fixture_t fx; /* static, not on the stack: the AVR has 16 KB of RAM */

static void setup(uint8_t board_id) {
  hal_host_init(&fx.hal, fx.link, (uint16_t)LINK_CAP);
  fx.mlx.alpha = 1000u;
  fx.mlx.beta = 2000u;
  fx.mlx.diag = 0u;
  fx.mlx.alpha_step = 1u;
  fx.mlx.bad_start = 0u;
  fx.mlx.bad_checksum = 0u;
  fx.mlx.answers = 0u;
  fx.hal.spi = fake_mlx_spi;
  fx.hal.spi_user = &fx.mlx;
  hal_host_bind(&fx.hal);
  (void)board_init(&fx.board, board_id);
}

/* Frames whatever the ring holds and sends it over the link, then reads one frame back from the
 * link and decodes it. Returns bridge_decode()'s result (or board_poll()'s if that failed). */
static int next_frame(bridge_frame_t *out) {
  uint8_t bytes[BRIDGE_FRAME_LEN];
  int rc = board_poll(&fx.board);
  if (rc != FW_OK) return rc;
  if (hal_host_link_drain(&fx.hal, bytes, (uint16_t)BRIDGE_FRAME_LEN) != BRIDGE_FRAME_LEN) {
    return FW_EEMPTY;
  }
  return bridge_decode(bytes, out);
}

/* One 500 us tick, then the frame it produced. */
static int tick_frame(bridge_frame_t *out) {
  sampler_tick(&fx.board.sampler);
  return next_frame(out);
}

/* Runs the power-up window and sends its frames away. */
static void pass_powerup(void) {
  bridge_frame_t f;
  uint8_t i;
  for (i = 0u; i < SAMPLER_POWERUP_TICKS; ++i) (void)tick_frame(&f);
}

/* ---- Frame code ---- */

static void test_crc16_check_value(void) {
  static const uint8_t digits[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  CHECK_EQ(bridge_crc16(digits, 9u), 0x29B1u);
  CHECK_EQ(bridge_crc16(digits, 0u), 0xFFFFu);
}

/* A small xorshift for test data (16-bit int safe). */
static uint32_t test_rand_state = 0x2545F491ul;
static uint8_t test_rand_byte(void) {
  test_rand_state ^= test_rand_state << 13;
  test_rand_state ^= test_rand_state >> 17;
  test_rand_state ^= test_rand_state << 5;
  return (uint8_t)(test_rand_state >> 24);
}

static void test_crc16_table_matches_bitwise(void) {
  /* Every byte value at every position of a frame's 14 bytes (every entry of every table the
   * build has), then random buffers of 0..40 bytes from random offsets (every block split). */
  static uint8_t buf[48];
  uint16_t pos;
  uint16_t v;
  uint16_t k;
  uint16_t n;
  uint16_t off;
  uint16_t mismatches = 0u;
  for (k = 0u; k < 14u; ++k) buf[k] = test_rand_byte();
  for (pos = 0u; pos < 14u; ++pos) {
    const uint8_t keep = buf[pos];
    for (v = 0u; v < 256u; ++v) {
      buf[pos] = (uint8_t)v;
      if (bridge_crc16(buf, 14u) != bridge_crc16_bitwise(buf, 14u)) ++mismatches;
    }
    buf[pos] = keep;
  }
  for (k = 0u; k < 1000u; ++k) {
    n = (uint16_t)(test_rand_byte() % 41u);
    off = (uint16_t)(test_rand_byte() % 8u);
    for (v = 0u; v < n; ++v) buf[off + v] = test_rand_byte();
    if (bridge_crc16(&buf[off], n) != bridge_crc16_bitwise(&buf[off], n)) ++mismatches;
  }
  CHECK_EQ(mismatches, 0u);
  CHECK_EQ(bridge_crc16_bitwise((const uint8_t *)"123456789", 9u), 0x29B1u);
  CHECK_EQ(bridge_crc16(NULL, 5u), 0xFFFFu);
}

static void test_mlx_checksum_vectors(void) {
  /* The 8-bit sum of bytes 1..6; switching the checksum means changing these with it. */
  static const uint8_t ones[MLX_FRAME_LEN] = {0xFF, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x15};
  static const uint8_t all_ff[MLX_FRAME_LEN] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFA};
  static const uint8_t mixed[MLX_FRAME_LEN] = {0xFF, 0x34, 0x12, 0xCD, 0xAB, 0x00, 0x00, 0xBE};
  uint8_t frame[MLX_FRAME_LEN];
  CHECK_EQ(mlx_checksum(ones), 0x15u);
  CHECK_EQ(mlx_checksum(all_ff), 0xFAu);
  CHECK_EQ(mlx_checksum(mixed), 0xBEu);
  mlx_encode(0x1234u, 0xABCDu, 0x0000u, frame);
  CHECK_EQ(frame[0], 0xFFu);
  CHECK_EQ(frame[1], 0x34u); /* LSB first */
  CHECK_EQ(frame[2], 0x12u);
  CHECK_EQ(frame[3], 0xCDu);
  CHECK_EQ(frame[4], 0xABu);
  CHECK_EQ(frame[7], 0xBEu);
}

static void test_mlx_round_trip_edge_values(void) {
  static const uint16_t edges[5] = {0x0000u, 0xFFFFu, 0x8000u, 0x7FFFu, 0x0001u};
  uint8_t frame[MLX_FRAME_LEN];
  mlx_sample_t s;
  uint8_t i;
  uint8_t j;
  for (i = 0u; i < 5u; ++i) {
    for (j = 0u; j < 5u; ++j) {
      mlx_encode(edges[i], edges[j], 0u, frame);
      CHECK_EQ(mlx_decode(frame, &s), FW_OK);
      CHECK_EQ(s.alpha, edges[i]);
      CHECK_EQ(s.beta, edges[j]);
      CHECK_EQ(s.diag, 0u);
      CHECK_EQ(s.status, 0u);
    }
  }
}

static void test_mlx_decode_rejects_bad_frames(void) {
  uint8_t frame[MLX_FRAME_LEN];
  mlx_sample_t s = {0x1111u, 0x2222u, 0u, 0u};
  mlx_encode(0x0102u, 0x0304u, 0u, frame);
  frame[0] = 0xFEu;
  CHECK_EQ(mlx_decode(frame, &s), (unsigned long)FW_ESTART);
  CHECK_EQ(s.alpha, 0x1111u); /* untouched on failure */
  mlx_encode(0x0102u, 0x0304u, 0u, frame);
  frame[3] = (uint8_t)(frame[3] ^ 0x10u);
  CHECK_EQ(mlx_decode(frame, &s), (unsigned long)FW_ECHECKSUM);
  CHECK_EQ(s.beta, 0x2222u);
  CHECK_EQ(mlx_decode(NULL, &s), (unsigned long)FW_EINVAL);
  CHECK_EQ(mlx_decode(frame, NULL), (unsigned long)FW_EINVAL);
}

static void test_mlx_diag_bits_map_to_status(void) {
  static const uint16_t expect[8] = {MLX_ST_ADC_FAIL,   MLX_ST_ADC_SAT,    MLX_ST_FIELD_LOW,
                                     MLX_ST_FIELD_HIGH, MLX_ST_GAIN_CLAMP, MLX_ST_DEAD_ZONE,
                                     MLX_ST_MEM_FAIL,   MLX_ST_MEM_FAIL};
  uint8_t i;
  for (i = 0u; i < 8u; ++i) {
    CHECK_EQ(mlx_diag_status((uint16_t)(1u << i)), expect[i]);
  }
  CHECK_EQ(mlx_diag_status(0u), 0u);
  CHECK_EQ(mlx_diag_status(0x00FFu), MLX_ST_DIAG_MASK);
  CHECK_EQ(mlx_diag_status(0xFF00u), 0u); /* the high byte carries no diagnostic */
}

static void test_bridge_layout_is_little_endian(void) {
  bridge_frame_t f = {5u, 0x1234u, 0x89ABCDEFul, 0x0102u, 0x0304u, 0x0506u};
  uint8_t b[BRIDGE_FRAME_LEN];
  uint16_t crc;
  CHECK_EQ(bridge_encode(&f, b), FW_OK);
  CHECK_EQ(b[0], 0xA5u);
  CHECK_EQ(b[1], 0x5Au);
  CHECK_EQ(b[2], 5u);
  CHECK_EQ(b[3], BRIDGE_VERSION);
  CHECK_EQ(b[4], 0x34u);
  CHECK_EQ(b[5], 0x12u);
  CHECK_EQ(b[6], 0xEFu);
  CHECK_EQ(b[7], 0xCDu);
  CHECK_EQ(b[8], 0xABu);
  CHECK_EQ(b[9], 0x89u);
  CHECK_EQ(b[10], 0x02u);
  CHECK_EQ(b[11], 0x01u);
  CHECK_EQ(b[12], 0x04u);
  CHECK_EQ(b[13], 0x03u);
  CHECK_EQ(b[14], 0x06u);
  CHECK_EQ(b[15], 0x05u);
  crc = bridge_crc16(&b[2], 14u);
  CHECK_EQ(b[16], crc & 0xFFu);
  CHECK_EQ(b[17], crc >> 8);
}

static void test_bridge_round_trip_edge_values(void) {
  static const uint16_t e16[3] = {0x0000u, 0xFFFFu, 0x8000u};
  static const uint32_t e32[4] = {0ul, 0xFFFFFFFFul, 0x80000000ul, 0x00010000ul};
  bridge_frame_t f;
  bridge_frame_t g;
  uint8_t b[BRIDGE_FRAME_LEN];
  uint8_t i;
  uint8_t j;
  for (i = 0u; i < 3u; ++i) {
    for (j = 0u; j < 4u; ++j) {
      f.board = (uint8_t)(i == 0u ? 0u : BRIDGE_MAX_BOARDS - 1u);
      f.seq = e16[i];
      f.tick = e32[j];
      f.alpha = e16[i];
      f.beta = e16[(uint8_t)((i + 1u) % 3u)];
      f.status = e16[(uint8_t)((i + 2u) % 3u)];
      CHECK_EQ(bridge_encode(&f, b), FW_OK);
      CHECK_EQ(bridge_decode(b, &g), FW_OK);
      CHECK_EQ(g.board, f.board);
      CHECK_EQ(g.seq, f.seq);
      CHECK_EQ(g.tick, f.tick);
      CHECK_EQ(g.alpha, f.alpha);
      CHECK_EQ(g.beta, f.beta);
      CHECK_EQ(g.status, f.status);
    }
  }
}

static void test_bridge_decode_rejects_bad_frames(void) {
  bridge_frame_t f = {3u, 7u, 100ul, 1u, 2u, 0u};
  bridge_frame_t g = {0u, 0u, 0ul, 0u, 0u, 0u};
  uint8_t b[BRIDGE_FRAME_LEN];
  uint16_t crc;
  uint8_t i;
  CHECK_EQ(bridge_encode(&f, b), FW_OK);
  b[1] = 0x5Bu;
  CHECK_EQ(bridge_decode(b, &g), (unsigned long)FW_ESYNC);
  /* Any single flipped bit in bytes 2..17 fails the CRC. */
  for (i = 2u; i < BRIDGE_FRAME_LEN; ++i) {
    CHECK_EQ(bridge_encode(&f, b), FW_OK);
    b[i] = (uint8_t)(b[i] ^ (uint8_t)(1u << (i & 7u)));
    CHECK_EQ(bridge_decode(b, &g), (unsigned long)FW_ECRC);
  }
  CHECK_EQ(g.seq, 0u); /* untouched on failure */
  /* A wrong version or board with a valid CRC is FW_EINVAL. */
  CHECK_EQ(bridge_encode(&f, b), FW_OK);
  b[3] = 2u;
  crc = bridge_crc16(&b[2], 14u);
  b[16] = (uint8_t)(crc & 0xFFu);
  b[17] = (uint8_t)(crc >> 8);
  CHECK_EQ(bridge_decode(b, &g), (unsigned long)FW_EINVAL);
  b[3] = BRIDGE_VERSION;
  b[2] = BRIDGE_MAX_BOARDS;
  crc = bridge_crc16(&b[2], 14u);
  b[16] = (uint8_t)(crc & 0xFFu);
  b[17] = (uint8_t)(crc >> 8);
  CHECK_EQ(bridge_decode(b, &g), (unsigned long)FW_EINVAL);
  f.board = BRIDGE_MAX_BOARDS;
  CHECK_EQ(bridge_encode(&f, b), (unsigned long)FW_EINVAL);
  CHECK_EQ(bridge_encode(NULL, b), (unsigned long)FW_EINVAL);
}

static void test_error_names(void) {
  const char *s = fw_strerror(FW_ETIMEOUT);
  CHECK(s[0] == 'F' && s[3] == 'E' && s[4] == 'T');
  s = fw_strerror(-99);
  CHECK(s[3] == 'U');
  s = fw_strerror(FW_OK);
  CHECK(s[3] == 'O');
}

/* ---- Ring ---- */

static ring_t ring;

static ring_sample_t sample(uint32_t tick) {
  ring_sample_t s;
  s.tick = tick;
  s.alpha = (uint16_t)(tick & 0xFFFFu);
  s.beta = 0u;
  s.status = 0u;
  return s;
}

static void test_ring_is_fifo(void) {
  ring_sample_t s;
  uint32_t t;
  ring_init(&ring);
  CHECK_EQ(ring_pop(&ring, &s), (unsigned long)FW_EEMPTY);
  for (t = 0u; t < 5u; ++t) {
    s = sample(t);
    ring_push(&ring, &s);
  }
  for (t = 0u; t < 5u; ++t) {
    CHECK_EQ(ring_pop(&ring, &s), FW_OK);
    CHECK_EQ(s.tick, t);
    CHECK_EQ(s.status, 0u);
  }
  CHECK_EQ(ring_pop(&ring, &s), (unsigned long)FW_EEMPTY);
  CHECK_EQ(ring.dropped, 0u);
}

static void test_ring_overflow_drops_oldest_and_counts(void) {
  ring_sample_t s;
  uint32_t t;
  ring_init(&ring);
  for (t = 0u; t < RING_CAPACITY + 3u; ++t) {
    s = sample(t);
    ring_push(&ring, &s);
  }
  CHECK_EQ(ring.dropped, 3u);
  CHECK_EQ(ring.count, RING_CAPACITY);
  for (t = 3u; t < RING_CAPACITY + 3u; ++t) {
    CHECK_EQ(ring_pop(&ring, &s), FW_OK);
    CHECK_EQ(s.tick, t); /* the three oldest went */
    /* the first sample after the gap carries the mark, and only it */
    CHECK_EQ(s.status, t == 3u ? BRIDGE_ST_DROPPED : 0u);
  }
  CHECK_EQ(ring_pop(&ring, &s), (unsigned long)FW_EEMPTY);
  ring.dropped = 0xFFFFu;
  for (t = 0u; t < RING_CAPACITY + 1u; ++t) ring_push(&ring, &s);
  CHECK_EQ(ring.dropped, 0xFFFFu); /* saturates */
}

static void test_ring_pop_irqsafe_balances_masking(void) {
  ring_sample_t s = sample(9u);
  setup(0u);
  ring_init(&ring);
  ring_push(&ring, &s);
  CHECK_EQ(ring_pop_irqsafe(&ring, &s), FW_OK);
  CHECK_EQ(ring_pop_irqsafe(&ring, &s), (unsigned long)FW_EEMPTY);
  CHECK_EQ(fx.hal.irq_saves, 2u);
  CHECK(hal_host_irq_balanced(&fx.hal));
}

/* ---- Sampler and board through the host HAL ---- */

static void test_powerup_window_has_no_data(void) {
  bridge_frame_t f;
  uint8_t i;
  setup(1u);
  for (i = 0u; i < SAMPLER_POWERUP_TICKS; ++i) {
    if (i + 1u == SAMPLER_POWERUP_TICKS) CHECK_EQ(fx.hal.spi_starts, 0u); /* quiet bus so far */
    CHECK_EQ(tick_frame(&f), FW_OK);
    CHECK_EQ(f.tick, i);
    CHECK_EQ(f.status, BRIDGE_ST_POWERUP);
    CHECK_EQ(f.alpha, 0u);
    CHECK_EQ(f.beta, 0u);
  }
  CHECK_EQ(fx.board.sampler.counters.ok, 0u);
  /* The last power-up tick started the first transfer; the next tick is a fresh sample. */
  CHECK_EQ(fx.hal.spi_starts, 1u);
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.status, 0u);
  CHECK_EQ(f.alpha, 1000u);
  CHECK_EQ(f.beta, 2000u);
  CHECK_EQ(fx.board.sampler.counters.ok, 1u);
  CHECK(hal_host_irq_balanced(&fx.hal));
}

static void test_healthy_sensor_gives_fresh_frames(void) {
  bridge_frame_t f;
  uint16_t i;
  setup(7u);
  pass_powerup();
  for (i = 0u; i < 100u; ++i) {
    CHECK_EQ(tick_frame(&f), FW_OK);
    CHECK_EQ(f.status, 0u);
    CHECK_EQ(f.board, 7u);
    CHECK_EQ(f.seq, SAMPLER_POWERUP_TICKS + i);
    CHECK_EQ(f.tick, SAMPLER_POWERUP_TICKS + i);
    CHECK_EQ(f.alpha, 1000u + i);
    CHECK_EQ(f.beta, 2000u);
  }
  CHECK_EQ(fx.board.sampler.counters.ok, 100u);
  CHECK_EQ(fx.board.frames_sent, SAMPLER_POWERUP_TICKS + 100u);
  CHECK_EQ(fx.hal.spi_aborts, 0u);
  CHECK(hal_host_irq_balanced(&fx.hal));
}

static void test_bad_start_byte_reaches_frame_and_counter(void) {
  bridge_frame_t f;
  setup(2u);
  pass_powerup();
  fx.mlx.bad_start = 1u;
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK(f.status != 0u);
  CHECK_EQ(f.status, BRIDGE_ST_BAD_START);
  CHECK_EQ(f.alpha, 0u);
  CHECK_EQ(f.beta, 0u);
  CHECK_EQ(fx.board.sampler.counters.bad_start, 1u);
  CHECK_EQ(fx.board.sampler.counters.ok, 0u);
  fx.mlx.bad_start = 0u;
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.status, 0u);
}

static void test_bad_checksum_reaches_frame_and_counter(void) {
  bridge_frame_t f;
  setup(2u);
  pass_powerup();
  fx.mlx.bad_checksum = 1u;
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK(f.status != 0u);
  CHECK_EQ(f.status, BRIDGE_ST_CHECKSUM);
  CHECK_EQ(f.alpha, 0u);
  CHECK_EQ(fx.board.sampler.counters.checksum, 1u);
  CHECK_EQ(fx.board.sampler.counters.ok, 0u);
}

static void test_no_responder_reads_idle_line_as_checksum_fault(void) {
  bridge_frame_t f;
  setup(2u);
  fx.hal.spi = NULL; /* nothing on the bus: MISO reads 0xFF */
  pass_powerup();
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.status, BRIDGE_ST_CHECKSUM);
  CHECK_EQ(fx.board.sampler.counters.checksum, 1u);
}

static void test_each_diagnostic_bit_reaches_frame_and_counter(void) {
  static const uint16_t expect[8] = {MLX_ST_ADC_FAIL,   MLX_ST_ADC_SAT,    MLX_ST_FIELD_LOW,
                                     MLX_ST_FIELD_HIGH, MLX_ST_GAIN_CLAMP, MLX_ST_DEAD_ZONE,
                                     MLX_ST_MEM_FAIL,   MLX_ST_MEM_FAIL};
  bridge_frame_t f;
  uint8_t i;
  setup(3u);
  pass_powerup();
  for (i = 0u; i < 8u; ++i) {
    fx.mlx.diag = (uint16_t)(1u << i);
    CHECK_EQ(tick_frame(&f), FW_OK);
    CHECK(f.status != 0u);
    CHECK_EQ(f.status, expect[i]);
    CHECK_EQ(fx.board.sampler.counters.diag, i + 1u);
    /* the measurement is passed on, flagged: the diagnostic bits are not BRIDGE_ST_NO_DATA */
    CHECK_EQ(f.alpha, 1000u + i);
  }
  CHECK_EQ(fx.board.sampler.counters.ok, 0u);
}

static void test_stuck_bus_times_out_and_aborts(void) {
  bridge_frame_t f;
  uint8_t i;
  setup(4u);
  pass_powerup(); /* the first transfer is started, with spi_busy_polls = 0 */
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.status, 0u);
  fx.hal.spi_busy_polls = -1; /* the transfer the next tick starts never completes */
  CHECK_EQ(tick_frame(&f), FW_OK);
  fx.hal.spi_busy_polls = 0; /* transfers started from now on are fine */
  CHECK_EQ(f.status, 0u);    /* the transfer collected here started before the fault */
  for (i = 1u; i < SAMPLER_TIMEOUT_TICKS; ++i) {
    CHECK_EQ(tick_frame(&f), FW_OK);
    CHECK_EQ(f.status, BRIDGE_ST_BUSY);
    CHECK_EQ(f.alpha, 0u);
  }
  CHECK_EQ(fx.hal.spi_aborts, 0u);
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK(f.status != 0u);
  CHECK_EQ(f.status, BRIDGE_ST_TIMEOUT);
  CHECK_EQ(f.alpha, 0u);
  CHECK_EQ(fx.hal.spi_aborts, 1u);
  CHECK_EQ(fx.board.sampler.counters.timeout, 1u);
  CHECK_EQ(fx.board.sampler.counters.busy, SAMPLER_TIMEOUT_TICKS - 1u);
  /* A new transfer began right after the abort: the next tick is fresh again. */
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.status, 0u);
}

static void test_stuck_bus_keeps_timing_out(void) {
  bridge_frame_t f;
  uint8_t i;
  uint8_t timeouts = 0u;
  setup(4u);
  fx.hal.spi_busy_polls = -1;
  pass_powerup();
  for (i = 0u; i < 4u * SAMPLER_TIMEOUT_TICKS; ++i) {
    CHECK_EQ(tick_frame(&f), FW_OK);
    CHECK(f.status == BRIDGE_ST_BUSY || f.status == BRIDGE_ST_TIMEOUT);
    if (f.status == BRIDGE_ST_TIMEOUT) timeouts = (uint8_t)(timeouts + 1u);
  }
  CHECK_EQ(timeouts, 4u);
  CHECK_EQ(fx.hal.spi_aborts, 4u);
  CHECK_EQ(fx.board.sampler.counters.timeout, 4u);
  CHECK_EQ(fx.board.sampler.counters.ok, 0u);
  CHECK_EQ(fx.mlx.answers, 0u);
}

static void test_slow_bus_reports_busy_then_data(void) {
  bridge_frame_t f;
  setup(4u);
  fx.hal.spi_busy_polls = 1; /* each transfer needs two ticks */
  pass_powerup();
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.status, BRIDGE_ST_BUSY);
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.status, 0u);
  CHECK_EQ(f.alpha, 1000u);
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.status, BRIDGE_ST_BUSY);
  CHECK_EQ(fx.board.sampler.counters.busy, 2u);
  CHECK_EQ(fx.board.sampler.counters.timeout, 0u);
}

static void test_refused_start_reaches_frame_and_counter(void) {
  bridge_frame_t f;
  setup(5u);
  pass_powerup();
  fx.hal.spi_refuse = 1u;
  CHECK_EQ(tick_frame(&f), FW_OK); /* collects the earlier transfer; the next start is refused */
  CHECK_EQ(f.status, 0u);
  CHECK_EQ(fx.board.sampler.counters.spi_error, 1u);
  CHECK_EQ(fx.hal.spi_refused, 1u);
  fx.hal.spi_refuse = 0u;
  CHECK_EQ(tick_frame(&f), FW_OK); /* nothing to collect */
  CHECK(f.status != 0u);
  CHECK_EQ(f.status, BRIDGE_ST_BUSY);
  CHECK_EQ(f.alpha, 0u);
  CHECK_EQ(fx.board.sampler.counters.busy, 1u);
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.status, 0u);
}

static void test_host_spi_refuses_a_second_start(void) {
  uint8_t tx[2] = {0xFFu, 0xFFu};
  uint8_t rx[2];
  setup(0u);
  CHECK_EQ(hal_spi_start(tx, rx, 2u), FW_OK);
  CHECK_EQ(hal_spi_start(tx, rx, 2u), (unsigned long)FW_EBUSY);
  CHECK_EQ(hal_spi_start(tx, rx, 0u), (unsigned long)FW_EINVAL);
  CHECK_EQ(hal_spi_abort(), FW_OK);
  CHECK_EQ(hal_spi_poll(), FW_OK);
  CHECK_EQ(hal_timer_start(SAMPLER_HZ), FW_OK);
  CHECK_EQ(fx.hal.timer_hz, SAMPLER_HZ);
  CHECK_EQ(hal_timer_start(0u), (unsigned long)FW_EINVAL);
  hal_host_bind(NULL);
  CHECK_EQ(hal_spi_poll(), (unsigned long)FW_EINVAL);
  CHECK_EQ(hal_link_write(tx, 2u), (unsigned long)FW_EINVAL);
}

static void test_repeated_sample_is_stale(void) {
  bridge_frame_t f;
  setup(6u);
  pass_powerup();
  fx.mlx.alpha_step = 0u; /* the sensor stops refreshing */
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.status, 0u);
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK(f.status != 0u);
  CHECK_EQ(f.status, BRIDGE_ST_STALE);
  CHECK_EQ(f.alpha, 1000u); /* the repeated value, flagged */
  CHECK_EQ(fx.board.sampler.counters.stale, 1u);
  CHECK_EQ(fx.board.sampler.counters.ok, 1u);
  fx.mlx.alpha = 1001u;
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.status, 0u);
}

static void test_ring_overflow_marks_dropped_in_frames(void) {
  bridge_frame_t f;
  uint8_t i;
  setup(8u);
  pass_powerup();
  /* The main loop stalls for RING_CAPACITY + 5 ticks. */
  for (i = 0u; i < RING_CAPACITY + 5u; ++i) sampler_tick(&fx.board.sampler);
  CHECK_EQ(fx.board.ring.dropped, 5u);
  for (i = 0u; i < RING_CAPACITY; ++i) {
    CHECK_EQ(next_frame(&f), FW_OK);
    CHECK_EQ(f.tick, SAMPLER_POWERUP_TICKS + 5u + i); /* the gap is in the timestamps */
    CHECK_EQ(f.status, i == 0u ? BRIDGE_ST_DROPPED : 0u); /* and the frame after it says so */
  }
  CHECK_EQ(next_frame(&f), (unsigned long)FW_EEMPTY);
  /* The fresh samples stored over the dropped ones keep their measurement. */
  CHECK_EQ(f.alpha, 1000u + RING_CAPACITY + 4u);
}

static void test_board_frames_round_trip_and_sequence_wraps(void) {
  bridge_frame_t f;
  setup(BRIDGE_MAX_BOARDS - 1u);
  pass_powerup();
  fx.mlx.alpha = 0xFFFFu;
  fx.mlx.beta = 0x8000u;
  fx.board.seq = 0xFFFFu;
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.board, BRIDGE_MAX_BOARDS - 1u);
  CHECK_EQ(f.seq, 0xFFFFu);
  CHECK_EQ(f.alpha, 0xFFFFu);
  CHECK_EQ(f.beta, 0x8000u);
  CHECK_EQ(f.status, 0u);
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.seq, 0u);
  CHECK_EQ(f.alpha, 0x0000u); /* 0xFFFF + 1 wrapped in the fake sensor */
  CHECK_EQ(f.status, 0u);
  CHECK_EQ(board_poll(&fx.board), (unsigned long)FW_EEMPTY);
  CHECK_EQ(board_init(&fx.board, BRIDGE_MAX_BOARDS), (unsigned long)FW_EINVAL);
}

static void test_timestamp_crosses_16_bits(void) {
  bridge_frame_t f;
  setup(0u);
  pass_powerup();
  fx.board.sampler.tick = 0xFFFFul;
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.tick, 0xFFFFul);
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.tick, 0x10000ul);
  CHECK_EQ(f.status, 0u);
}

static void test_counters_saturate(void) {
  bridge_frame_t f;
  setup(0u);
  pass_powerup();
  fx.board.sampler.counters.bad_start = 0xFFFFu;
  fx.mlx.bad_start = 1u;
  CHECK_EQ(tick_frame(&f), FW_OK);
  CHECK_EQ(f.status, BRIDGE_ST_BAD_START);
  CHECK_EQ(fx.board.sampler.counters.bad_start, 0xFFFFu);
}

static void test_link_busy_keeps_frame_pending_and_resends(void) {
  bridge_frame_t f;
  uint16_t seq;
  uint32_t tick;
  setup(9u);
  pass_powerup();
  fx.hal.link_refuse = 1u;
  sampler_tick(&fx.board.sampler);
  CHECK_EQ(board_poll(&fx.board), (unsigned long)FW_EBUSY);
  CHECK_EQ(board_poll(&fx.board), (unsigned long)FW_EBUSY);
  CHECK_EQ(fx.board.pending, 1u);
  CHECK_EQ(fx.board.link_busy, 2u);
  CHECK_EQ(fx.hal.link_len, 0u);
  seq = fx.board.seq; /* already advanced past the pending frame */
  sampler_tick(&fx.board.sampler);
  fx.hal.link_refuse = 0u;
  CHECK_EQ(next_frame(&f), FW_OK); /* the pending frame goes first, unchanged */
  CHECK_EQ(f.seq, (uint16_t)(seq - 1u));
  CHECK_EQ(f.tick, SAMPLER_POWERUP_TICKS);
  CHECK_EQ(f.status, 0u);
  tick = f.tick;
  CHECK_EQ(next_frame(&f), FW_OK);
  CHECK_EQ(f.seq, seq);
  CHECK_EQ(f.tick, tick + 1u);
  CHECK_EQ(fx.board.pending, 0u);
  CHECK(hal_host_irq_balanced(&fx.hal));
}

static void test_full_link_buffer_is_busy_until_drained(void) {
  uint8_t bytes[BRIDGE_FRAME_LEN];
  bridge_frame_t f;
  setup(9u);
  fx.hal.link_cap = BRIDGE_FRAME_LEN + 2u; /* room for one frame only */
  sampler_tick(&fx.board.sampler);
  sampler_tick(&fx.board.sampler);
  CHECK_EQ(board_poll(&fx.board), FW_OK);
  CHECK_EQ(board_poll(&fx.board), (unsigned long)FW_EBUSY);
  CHECK_EQ(fx.hal.link_refused, 1u);
  CHECK_EQ(hal_host_link_drain(&fx.hal, bytes, (uint16_t)BRIDGE_FRAME_LEN), BRIDGE_FRAME_LEN);
  CHECK_EQ(bridge_decode(bytes, &f), FW_OK);
  CHECK_EQ(f.tick, 0u);
  CHECK_EQ(board_poll(&fx.board), FW_OK);
  CHECK_EQ(hal_host_link_drain(&fx.hal, bytes, (uint16_t)BRIDGE_FRAME_LEN), BRIDGE_FRAME_LEN);
  CHECK_EQ(bridge_decode(bytes, &f), FW_OK);
  CHECK_EQ(f.tick, 1u);
  CHECK_EQ(f.seq, 1u);
}

/* Two boards in one process, each with its own HAL context (the simulator's case). */
static void test_two_boards_keep_separate_contexts(void) {
  static hal_host_t hal_b;
  static uint8_t link_b[LINK_CAP];
  static fake_mlx_t mlx_b;
  static board_t board_b;
  bridge_frame_t f;
  uint8_t bytes[BRIDGE_FRAME_LEN];
  uint8_t i;
  setup(10u);
  hal_host_init(&hal_b, link_b, (uint16_t)LINK_CAP);
  mlx_b = fx.mlx;
  mlx_b.alpha = 5000u;
  hal_b.spi = fake_mlx_spi;
  hal_b.spi_user = &mlx_b;
  hal_host_bind(&hal_b);
  CHECK_EQ(board_init(&board_b, 11u), FW_OK);
  hal_b.spi_busy_polls = -1; /* board B's bus is stuck */
  for (i = 0u; i <= SAMPLER_POWERUP_TICKS; ++i) {
    hal_host_bind(&fx.hal);
    CHECK_EQ(tick_frame(&f), FW_OK);
    CHECK_EQ(f.board, 10u);
    hal_host_bind(&hal_b);
    sampler_tick(&board_b.sampler);
    CHECK_EQ(board_poll(&board_b), FW_OK);
    CHECK_EQ(hal_host_link_drain(&hal_b, bytes, (uint16_t)BRIDGE_FRAME_LEN), BRIDGE_FRAME_LEN);
  }
  CHECK_EQ(f.status, 0u); /* A's first RUN tick: fresh */
  CHECK_EQ(f.alpha, 1000u);
  CHECK_EQ(bridge_decode(bytes, &f), FW_OK);
  CHECK_EQ(f.board, 11u);
  CHECK_EQ(f.status, BRIDGE_ST_BUSY); /* B's first RUN tick: its transfer is still running */
  CHECK_EQ(board_b.sampler.counters.busy, 1u);
  CHECK_EQ(fx.board.sampler.counters.busy, 0u);
  CHECK_EQ(fx.hal.spi_aborts, 0u);
  CHECK_EQ(mlx_b.answers, 0u);
}

#ifdef __AVR__
/* ISR budget on the AVR build: Timer1 counts CPU cycles (prescaler 1) around sampler_tick() on
 * each of its paths; the slowest is printed for docs/protocol.md. The host HAL's SPI here is a
 * plain 8-byte copy, close to what the target's hal_spi_poll() costs. */
static uint8_t canned[MLX_FRAME_LEN];
static int canned_spi(void *user, const uint8_t *tx, uint8_t *rx, uint8_t n) {
  uint8_t i;
  (void)user;
  (void)tx;
  for (i = 0u; i < n; ++i) rx[i] = canned[i];
  return 0;
}

static uint16_t cycles_of_tick(void) {
  uint16_t t0;
  uint16_t t1;
  TCCR1A = 0u;
  TCCR1B = (uint8_t)(1u << CS10);
  t0 = TCNT1;
  sampler_tick(&fx.board.sampler);
  t1 = TCNT1;
  return (uint16_t)(t1 - t0);
}

static void test_isr_cycles_avr(void) {
  uint16_t worst_data = 0u;
  uint16_t worst_bus = 0u;
  uint16_t c;
  uint8_t i;
  setup(0u);
  fx.hal.spi = canned_spi;
  for (i = 0u; i < SAMPLER_POWERUP_TICKS + RING_CAPACITY; ++i) { /* fill the ring: drops */
    mlx_encode(i, 2u, 0x00FFu, canned); /* every diagnostic bit set */
    c = cycles_of_tick();
    if (c > worst_data) worst_data = c;
  }
  c = cycles_of_tick(); /* the same frame again: STALE, all diagnostics, ring full */
  if (c > worst_data) worst_data = c;
  fx.hal.spi_busy_polls = -1;
  (void)cycles_of_tick(); /* collects the last good transfer; starts a stuck one */
  for (i = 0u; i < 2u * SAMPLER_TIMEOUT_TICKS; ++i) { /* busy, then timeout + abort + restart */
    c = cycles_of_tick();
    if (c > worst_bus) worst_bus = c;
  }
  CHECK(fx.board.sampler.counters.stale >= 1u);
  CHECK_EQ(fx.board.sampler.counters.timeout, 2u);
  CHECK(fx.board.ring.dropped > 0u);
  FW_PRINTF(FW_PSTR("isr: sampler_tick worst AVR cycles: data path %u, bus-fault path %u\n"),
            (unsigned)worst_data, (unsigned)worst_bus);
  CHECK(worst_data < 20000u); /* 500 us at 40 MIPS */
  CHECK(worst_bus < 20000u);
}

/* The main loop's cost per frame (ring pop under the mask, CRC-16, link write). */
static void test_board_poll_cycles_avr(void) {
  uint16_t t0;
  uint16_t t1;
  uint8_t bytes[BRIDGE_FRAME_LEN];
  setup(0u);
  sampler_tick(&fx.board.sampler);
  TCCR1A = 0u;
  TCCR1B = (uint8_t)(1u << CS10);
  t0 = TCNT1;
  CHECK_EQ(board_poll(&fx.board), FW_OK);
  t1 = TCNT1;
  CHECK_EQ(hal_host_link_drain(&fx.hal, bytes, (uint16_t)BRIDGE_FRAME_LEN), BRIDGE_FRAME_LEN);
  FW_PRINTF(FW_PSTR("main loop: board_poll one frame %u AVR cycles\n"), (unsigned)(t1 - t0));
}
#endif

int main(void) {
  fw_test_begin();
  FW_RUN(test_crc16_check_value);
  FW_RUN(test_crc16_table_matches_bitwise);
  FW_RUN(test_mlx_checksum_vectors);
  FW_RUN(test_mlx_round_trip_edge_values);
  FW_RUN(test_mlx_decode_rejects_bad_frames);
  FW_RUN(test_mlx_diag_bits_map_to_status);
  FW_RUN(test_bridge_layout_is_little_endian);
  FW_RUN(test_bridge_round_trip_edge_values);
  FW_RUN(test_bridge_decode_rejects_bad_frames);
  FW_RUN(test_error_names);
  FW_RUN(test_ring_is_fifo);
  FW_RUN(test_ring_overflow_drops_oldest_and_counts);
  FW_RUN(test_ring_pop_irqsafe_balances_masking);
  FW_RUN(test_powerup_window_has_no_data);
  FW_RUN(test_healthy_sensor_gives_fresh_frames);
  FW_RUN(test_bad_start_byte_reaches_frame_and_counter);
  FW_RUN(test_bad_checksum_reaches_frame_and_counter);
  FW_RUN(test_no_responder_reads_idle_line_as_checksum_fault);
  FW_RUN(test_each_diagnostic_bit_reaches_frame_and_counter);
  FW_RUN(test_stuck_bus_times_out_and_aborts);
  FW_RUN(test_stuck_bus_keeps_timing_out);
  FW_RUN(test_slow_bus_reports_busy_then_data);
  FW_RUN(test_refused_start_reaches_frame_and_counter);
  FW_RUN(test_host_spi_refuses_a_second_start);
  FW_RUN(test_repeated_sample_is_stale);
  FW_RUN(test_ring_overflow_marks_dropped_in_frames);
  FW_RUN(test_board_frames_round_trip_and_sequence_wraps);
  FW_RUN(test_timestamp_crosses_16_bits);
  FW_RUN(test_counters_saturate);
  FW_RUN(test_link_busy_keeps_frame_pending_and_resends);
  FW_RUN(test_full_link_buffer_is_busy_until_drained);
  FW_RUN(test_two_boards_keep_separate_contexts);
#ifdef __AVR__
  FW_RUN(test_isr_cycles_avr);
  FW_RUN(test_board_poll_cycles_avr);
#endif
  FW_PRINTF(FW_PSTR("sizes: board_t %u B, sampler_t %u B, ring_t %u B\n"),
            (unsigned)sizeof(board_t), (unsigned)sizeof(sampler_t), (unsigned)sizeof(ring_t));
  return fw_test_end();
}

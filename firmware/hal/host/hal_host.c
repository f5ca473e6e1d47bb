/* The board HAL on a PC (hal_host.h). Portable C99: also built for the AVR test run. */
#include "hal_host.h"

#include <assert.h>
#include <stddef.h>

#include "whisker/error.h"

static hal_host_t *g_ctx; /* the bound context (single-threaded by contract) */

static void count(uint16_t *c) {
  if (*c != 0xFFFFu) *c = (uint16_t)(*c + 1u);
}

void hal_host_init(hal_host_t *ctx, uint8_t *link_buf, uint16_t link_cap) {
  if (ctx == NULL) return;
  ctx->spi = NULL;
  ctx->spi_user = NULL;
  ctx->spi_refuse = 0u;
  ctx->spi_busy_polls = 0;
  ctx->spi_active = 0u;
  ctx->spi_polls_left = 0;
  ctx->spi_tx = NULL;
  ctx->spi_rx = NULL;
  ctx->spi_n = 0u;
  ctx->spi_starts = 0u;
  ctx->spi_completed = 0u;
  ctx->spi_refused = 0u;
  ctx->spi_aborts = 0u;
  ctx->link_buf = link_buf;
  ctx->link_cap = link_buf != NULL ? link_cap : 0u;
  ctx->link_refuse = 0u;
  ctx->link_len = 0u;
  ctx->link_writes = 0u;
  ctx->link_refused = 0u;
  ctx->irq_depth = 0u;
  ctx->irq_saves = 0u;
  ctx->timer_hz = 0u;
  ctx->timer_starts = 0u;
}

void hal_host_bind(hal_host_t *ctx) { g_ctx = ctx; }

hal_host_t *hal_host_bound(void) { return g_ctx; }

uint16_t hal_host_link_drain(hal_host_t *ctx, uint8_t *out, uint16_t max) {
  uint16_t n;
  uint16_t i;
  if (ctx == NULL) return 0u;
  n = ctx->link_len < max ? ctx->link_len : max;
  if (out != NULL) {
    for (i = 0u; i < n; ++i) out[i] = ctx->link_buf[i];
  }
  for (i = n; i < ctx->link_len; ++i) ctx->link_buf[i - n] = ctx->link_buf[i];
  ctx->link_len = (uint16_t)(ctx->link_len - n);
  return n;
}

uint8_t hal_host_irq_balanced(const hal_host_t *ctx) {
  return (uint8_t)(ctx != NULL && ctx->irq_depth == 0u);
}

/* ---- hal.h ---- */

int hal_spi_start(const uint8_t *tx, uint8_t *rx, uint8_t n) {
  hal_host_t *c = g_ctx;
  if (c == NULL || tx == NULL || rx == NULL || n == 0u) return FW_EINVAL;
  if (c->spi_refuse != 0u || c->spi_active != 0u) {
    count(&c->spi_refused);
    return FW_EBUSY;
  }
  c->spi_active = 1u;
  c->spi_polls_left = c->spi_busy_polls;
  c->spi_tx = tx;
  c->spi_rx = rx;
  c->spi_n = n;
  count(&c->spi_starts);
  return FW_OK;
}

int hal_spi_poll(void) {
  hal_host_t *c = g_ctx;
  uint8_t i;
  if (c == NULL) return FW_EINVAL;
  if (c->spi_active == 0u) return FW_OK;
  if (c->spi_polls_left < 0) return FW_EBUSY; /* stuck until aborted */
  if (c->spi_polls_left > 0) {
    c->spi_polls_left = (int16_t)(c->spi_polls_left - 1);
    return FW_EBUSY;
  }
  if (c->spi == NULL || c->spi(c->spi_user, c->spi_tx, c->spi_rx, c->spi_n) != 0) {
    for (i = 0u; i < c->spi_n; ++i) c->spi_rx[i] = 0xFFu;
  }
  c->spi_active = 0u;
  count(&c->spi_completed);
  return FW_OK;
}

int hal_spi_abort(void) {
  hal_host_t *c = g_ctx;
  if (c == NULL) return FW_EINVAL;
  c->spi_active = 0u;
  count(&c->spi_aborts);
  return FW_OK;
}

int hal_link_write(const uint8_t *data, uint8_t n) {
  hal_host_t *c = g_ctx;
  uint8_t i;
  if (c == NULL || data == NULL) return FW_EINVAL;
  if (c->link_refuse != 0u || (uint16_t)(c->link_cap - c->link_len) < (uint16_t)n) {
    count(&c->link_refused);
    return FW_EBUSY;
  }
  for (i = 0u; i < n; ++i) c->link_buf[c->link_len + i] = data[i];
  c->link_len = (uint16_t)(c->link_len + n);
  count(&c->link_writes);
  return FW_OK;
}

int hal_timer_start(uint16_t hz) {
  hal_host_t *c = g_ctx;
  if (c == NULL || hz == 0u) return FW_EINVAL;
  c->timer_hz = hz;
  count(&c->timer_starts);
  return FW_OK;
}

hal_irq_state_t hal_irq_save(void) {
  hal_host_t *c = g_ctx;
  hal_irq_state_t prev;
  assert(c != NULL);
  if (c == NULL) return 0u;
  prev = c->irq_depth;
  c->irq_depth = (uint16_t)(c->irq_depth + 1u);
  count(&c->irq_saves);
  return prev;
}

void hal_irq_restore(hal_irq_state_t state) {
  hal_host_t *c = g_ctx;
  assert(c != NULL);
  if (c == NULL) return;
  assert(c->irq_depth > 0u && state == (hal_irq_state_t)(c->irq_depth - 1u));
  c->irq_depth = state;
}

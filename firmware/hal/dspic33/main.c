/* Whisker board firmware entry point (dsPIC33FJ128MC802): clock, pins, core, peripherals, then
 * the main loop that frames samples and hands them to the UART (board.h). The 2 kHz sampling
 * itself runs in the Timer2 interrupt (hal_dspic33.c). */
#include <stdint.h>

#include "hal_dspic33.h"
#include "whisker/board.h"
#include "whisker/error.h"
#include "whisker/hal.h"
#include "whisker/sampler.h"

/* This board's position in the bridge (0..BRIDGE_MAX_BOARDS-1), one image per board:
 * cmake ... -DBOARD_ID=<n> (firmware/hal/dspic33/CMakeLists.txt) passes -DBOARD_ID=<n>. */
#ifndef BOARD_ID
#define BOARD_ID 0
#endif
typedef char board_id_in_range[(BOARD_ID >= 0 && BOARD_ID < (int)BRIDGE_MAX_BOARDS) ? 1 : -1];

board_t g_board; /* shared with the Timer2 handler (hal_dspic33.h) */

int main(void) {
  int rc;
  /* Until the PLL runs, nothing below has the right timing: stay silent rather than send at a
   * wrong baud rate. */
  if (hal_clock_init() != FW_OK) hal_halt();
  hal_pins_init();
  if (board_init(&g_board, (uint8_t)BOARD_ID) != FW_OK) hal_halt();
  hal_spi_init();
  hal_link_init();
  /* Last: the first tick may fire at once and uses everything above. */
  if (hal_timer_start(SAMPLER_HZ) != FW_OK) hal_halt();

  for (;;) {
    rc = board_poll(&g_board);
    /* Nothing to frame (FW_EEMPTY) or the link ring full (FW_EBUSY): sleep until the next
     * interrupt, which is at most one sampler tick away; the UART interrupt also wakes us once
     * it has drained room. A sample pushed just before Idle waits for the next wake-up, well
     * inside the ring's 16 ms. */
    if (rc == FW_EEMPTY || rc == FW_EBUSY) hal_idle();
  }
}

/* The board HAL (whisker/hal.h) on the dsPIC33FJ128MC802: private interface between main.c and
 * hal_dspic33.c, plus the clock, pin and timing constants both use. Not part of the core's
 * contract; the host build never sees this file.
 *
 * Clock: FRC (7.37 MHz nominal) x PLL -> FOSC = 79.2275 MHz, FCY = FOSC / 2 = 39.61375 MIPS.
 *   FRC with the PLL cannot reach 40.000 MIPS exactly: M = 44 would give FOSC = 81.07 MHz, above
 *   the part's 80 MHz limit. Everything below is derived from HAL_FCY_HZ, so moving to a crystal
 *   (an 8 MHz XT gives exactly 40 MIPS with N1 = 2, M = 40, N2 = 2) changes only this block.
 *
 * Derived rates at HAL_FCY_HZ = 39 613 750 Hz:
 *   SPI1 SCK  = FCY / (64 * 2)      = 309.48 kHz (<= 320 kHz for the MLX90333; 312.5 kHz at 40 MIPS)
 *   UART1     = FCY / (4 * (9 + 1)) = 990.34 kbaud (-0.97 % from 1 Mbaud; exact at 40 MIPS), plus
 *               the FRC's own tolerance (datasheet AC characteristics): the FPGA receiver must
 *               tolerate it, or trim OSCTUN / fit a crystal (firmware/README.md)
 *   Timer2    = PR2 = 19806 at 1:1 -> 19807 cycles = 500.003 us per sample (1999.99 Hz)
 *
 * Interrupt priorities (CPU at IPL 0 in the main loop; nesting is enabled, INTCON1.NSTDIS = 0):
 *   6  SPI1 byte done, Timer3 SPI pacing -- a few instructions each; they may preempt the sampler,
 *      so hal_spi_start()/hal_spi_abort() touch the transfer state only at IPL 7
 *   5  Timer2: sampler_tick() -- outranks the UART so a full link never delays a sample
 *   3  UART1 TX: drains the link ring into the 4-byte hardware FIFO
 *   7  is used only by hal_irq_save() (the ring's consumer) and the SPI critical sections
 *
 * Pins (28-pin SPDIP/SOIC/SSOP numbering; firmware/README.md has the full board map):
 *   pin 15 RB6       GPIO out  MLX90333 /SS (chip select, active low)
 *   pin 16 RB7 = RP7  SCK1OUT  MLX90333 SCLK (SCK1 input mapped to the same pin)
 *   pin 17 RB8 = RP8  SDO1     -> 1 kOhm -> MLX90333 MOSI/MISO (3-wire data line)
 *   pin 18 RB9 = RP9  SDI1     <- MLX90333 MOSI/MISO directly
 *   pin 21 RB10 = RP10 U1TX    -> FPGA bridge RX
 *   pins 4/5 RB0/RB1  PGED1/PGEC1 and pin 1 MCLR: the programmer (ICS = PGD1), left unused
 * All five are digital-only pins (no ANx on RB4..RB15 of this part). JTAG must be off
 * (JTAGEN = OFF) because RB10..RB13 are also TDI/TMS/TDO/TCK. */
#ifndef WHISKER_HAL_DSPIC33_H
#define WHISKER_HAL_DSPIC33_H

#include <stdint.h>

#include "whisker/board.h"

/* ---- Clock: FOSC = FIN * M / (N1 * N2), FCY = FOSC / 2 ---- */
#define HAL_FRC_HZ 7370000UL     /* FRC nominal (OSCTUN = 0) */
#define HAL_PLL_N1 2UL           /* CLKDIV.PLLPRE = N1 - 2 = 0 */
#define HAL_PLL_M 43UL           /* PLLFBD.PLLDIV = M - 2 = 41 */
#define HAL_PLL_N2 2UL           /* CLKDIV.PLLPOST = 0 selects N2 = 2 */
#define HAL_FOSC_HZ (HAL_FRC_HZ * HAL_PLL_M / (HAL_PLL_N1 * HAL_PLL_N2)) /* 79 227 500 */
#define HAL_FCY_HZ (HAL_FOSC_HZ / 2UL)                                   /* 39 613 750 */

/* ---- SPI1: SCK = FCY / (primary * secondary) ---- */
#define HAL_SPI_PRESCALE (64UL * 2UL)
#define HAL_SPI_SCK_HZ (HAL_FCY_HZ / HAL_SPI_PRESCALE) /* 309 482 */

/* MLX90333 byte pacing, in microseconds, timed by Timer3 (one-shot). Melexis's Triaxis SPI
 * slaves want idle time around and between bytes; these are conservative values, to be checked
 * against the serial-interface timing table of the MLX90333 datasheet (a public MLX90333 driver
 * that works on hardware waits ~50 us after the first byte and ~20 us between the others). The
 * whole 8-byte frame must end well inside one 500 us sampler tick: see HAL_SPI_FRAME_US. */
#define HAL_SPI_T_LEAD_US 10u  /* /SS low -> first SCLK edge */
#define HAL_SPI_T_GAP0_US 50u  /* after byte 0 (the sensor's start byte) */
#define HAL_SPI_T_GAP_US 20u   /* between the later bytes */
#define HAL_SPI_T_TAIL_US 5u   /* last SCLK edge -> /SS high */
#define HAL_SPI_FRAME_US                                                                    \
  (HAL_SPI_T_LEAD_US + HAL_SPI_T_GAP0_US + 6u * HAL_SPI_T_GAP_US + HAL_SPI_T_TAIL_US +      \
   (uint32_t)(8UL * 8UL * 1000000UL / HAL_SPI_SCK_HZ)) /* ~392 us */

/* Microseconds -> Timer3 period register at 1:1 (the period is PR3 + 1 cycles), rounded up. */
#define HAL_US_TO_PR(us) ((uint16_t)(((HAL_FCY_HZ / 1000UL) * (uint32_t)(us) + 999UL) / 1000UL - 1UL))

/* ---- UART1 to the FPGA bridge ---- */
#define HAL_LINK_BAUD 1000000UL
#define HAL_LINK_BRG 9u          /* BRGH = 1: baud = FCY / (4 * (U1BRG + 1)) */
#define HAL_LINK_RING_SIZE 128u  /* power of two: 7 frames of 18 bytes */
#define HAL_UART_FIFO_DEPTH 4u   /* U1TXREG is a 4-deep FIFO on this part */

/* ---- Interrupt priority levels (see above) ---- */
#define HAL_IPL_SPI 6u
#define HAL_IPL_SAMPLER 5u
#define HAL_IPL_LINK 3u

/* ---- Pins ---- */
#define HAL_RP_SCK1 7u   /* RP7 = RB7 */
#define HAL_RP_SDO1 8u   /* RP8 = RB8 */
#define HAL_RP_SDI1 9u   /* RP9 = RB9 */
#define HAL_RP_U1TX 10u  /* RP10 = RB10 */
#define HAL_PPS_U1TX 3u      /* RPnR output function codes (datasheet PPS output table) */
#define HAL_PPS_SDO1 7u
#define HAL_PPS_SCK1OUT 8u

/* ---- Bounded waits: loop iterations, each at least 4 instruction cycles ---- */
/* The clock switch runs on FRC (FCY = 3.685 MHz, >= 1.08 us per iteration) until it completes;
 * the PLL locks within a few ms (datasheet TLOCK), so 20 000 iterations (>= 21 ms) is ample. */
#define HAL_CLOCK_SWITCH_POLLS 20000u
#define HAL_CLOCK_SWITCH_TRIES 3u

/* The board the interrupt handlers serve: defined in main.c, initialised by board_init() before
 * hal_timer_start() enables the sampler interrupt. */
extern board_t g_board;

/* Switches from FRC to FRC + PLL (FCY = HAL_FCY_HZ). FW_OK, or FW_ETIMEOUT if the switch or the
 * PLL lock did not complete within the bounded wait after HAL_CLOCK_SWITCH_TRIES tries (the CPU
 * then still runs on plain FRC and no peripheral timing above holds). */
int hal_clock_init(void);

/* Analog pins to digital, pin directions and idle levels, Peripheral Pin Select. Call once, after
 * hal_clock_init(): it locks the PPS registers (IOL1WAY = ON, one configuration per reset). */
void hal_pins_init(void);

/* SPI1 master + Timer3 pacing, interrupts enabled, bus idle. */
void hal_spi_init(void);

/* UART1 at 1 Mbaud 8N1 with an empty transmit ring. */
void hal_link_init(void);

/* Stops every interrupt source and idles forever: the board stays silent on the link, which the
 * bridge sees as a missing board. Used when the clock or the core refuses to start. */
void hal_halt(void);

/* Waits in Idle mode (CPU stopped, peripherals running) for the next interrupt. */
void hal_idle(void);

#endif

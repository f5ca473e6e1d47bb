/* The board HAL (whisker/hal.h) on the dsPIC33FJ128MC802, built with MPLAB XC16.
 * Register and bit names are those of the datasheet (DS70291) and the XC16 device header
 * p33FJ128MC802.h; constants, pins and priorities are in hal_dspic33.h.
 *
 * Interrupt handlers only move data (STYLE.md item 10):
 *   _T2Interrupt    calls sampler_tick(), which collects the last SPI frame and starts the next
 *   _T3Interrupt    Timer3 one-shot: puts the next SPI byte into SPI1BUF, or releases /SS
 *   _SPI1Interrupt  takes one received byte from SPI1BUF and arms Timer3 for the next step
 *   _U1TXInterrupt  moves up to 4 bytes from the link ring into the UART FIFO
 * No handler and no function here waits on hardware without a bound. */
#include <xc.h>

#include <stddef.h>
#include <stdint.h>

#include "hal_dspic33.h"
#include "whisker/error.h"
#include "whisker/hal.h"
#include "whisker/sampler.h"

/* ---- Configuration bits (programmed with the image; erased bits read 1) ---- */
#pragma config FNOSC = FRC       /* FOSCSEL: start on the FRC; main switches to FRC + PLL */
#pragma config IESO = OFF        /* FOSCSEL: no two-speed start-up */
#pragma config POSCMD = NONE     /* FOSC: primary oscillator off (no crystal on the board) */
#pragma config OSCIOFNC = ON     /* FOSC: OSC2 is a digital I/O */
#pragma config IOL1WAY = ON      /* FOSC: PPS may be configured once per reset */
#pragma config FCKSM = CSECMD    /* FOSC: clock switching on, fail-safe clock monitor off */
#pragma config WDTPOST = PS32768 /* FWDT: (watchdog unused) */
#pragma config WDTPRE = PR128    /* FWDT: (watchdog unused) */
#pragma config WINDIS = OFF      /* FWDT: non-window watchdog */
#pragma config FWDTEN = OFF      /* FWDT: watchdog off unless software sets RCON.SWDTEN */
#pragma config FPWRT = PWR128    /* FPOR: 128 ms power-up timer, covers the MLX90333's start-up */
#pragma config ALTI2C = OFF      /* FPOR: I2C1 (unused) on its default pins */
#pragma config LPOL = ON         /* FPOR: motor PWM low side active-high (PWM unused) */
#pragma config HPOL = ON         /* FPOR: motor PWM high side active-high (PWM unused) */
#pragma config PWMPIN = ON       /* FPOR: PWM pins (RB10..RB15) belong to PORT at reset */
#pragma config ICS = PGD1        /* FICD: programmer/debugger on PGEC1/PGED1 (pins 5/4) */
#pragma config JTAGEN = OFF      /* FICD: JTAG off, frees RB10..RB13 */
#pragma config GWRP = OFF        /* FGS: general segment not write-protected */
#pragma config GSS = OFF         /* FGS: general segment not code-protected */

/* Compile-time checks of the derived rates (negative array size on failure; C99 has no
 * _Static_assert). */
typedef char hal_check_pll_input[(HAL_FRC_HZ / HAL_PLL_N1 >= 800000UL &&
                                  HAL_FRC_HZ / HAL_PLL_N1 <= 8000000UL) ? 1 : -1];
typedef char hal_check_vco[(HAL_FRC_HZ / HAL_PLL_N1 * HAL_PLL_M >= 100000000UL &&
                            HAL_FRC_HZ / HAL_PLL_N1 * HAL_PLL_M <= 200000000UL) ? 1 : -1];
typedef char hal_check_fcy[(HAL_FCY_HZ <= 40000000UL) ? 1 : -1];
typedef char hal_check_sck[(HAL_SPI_SCK_HZ <= 320000UL) ? 1 : -1];
typedef char hal_check_frame[(HAL_SPI_FRAME_US <= 450UL) ? 1 : -1];
/* Baud error under 1.5 %: |FCY / (4 * (BRG + 1)) - baud| * 1000 < 15 * baud. */
#define HAL_LINK_ACTUAL (HAL_FCY_HZ / (4UL * (HAL_LINK_BRG + 1UL)))
typedef char hal_check_baud[((HAL_LINK_ACTUAL > HAL_LINK_BAUD ? HAL_LINK_ACTUAL - HAL_LINK_BAUD
                                                              : HAL_LINK_BAUD - HAL_LINK_ACTUAL) *
                                 1000UL < 15UL * HAL_LINK_BAUD) ? 1 : -1];
typedef char hal_check_ring[((HAL_LINK_RING_SIZE & (HAL_LINK_RING_SIZE - 1u)) == 0u &&
                             HAL_LINK_RING_SIZE >= BRIDGE_FRAME_LEN) ? 1 : -1];

/* ======================================================================================== */
/* Clock                                                                                     */
/* ======================================================================================== */

int hal_clock_init(void) {
  uint16_t tries;
  PLLFBD = HAL_PLL_M - 2u;   /* PLLDIV = 41: M = 43 */
  CLKDIVbits.PLLPRE = 0;     /* N1 = 2: PLL input 3.685 MHz (0.8..8 MHz) */
  CLKDIVbits.PLLPOST = 0;    /* N2 = 2: VCO 158.455 MHz (100..200 MHz) / 2 = FOSC 79.2275 MHz */
  CLKDIVbits.DOZEN = 0;      /* CPU clock not divided from the peripheral clock */
  OSCTUN = 0;                /* TUN = 0: FRC at its factory-calibrated 7.37 MHz */
  for (tries = 0u; tries < HAL_CLOCK_SWITCH_TRIES; ++tries) {
    uint16_t polls;
    __builtin_write_OSCCONH(0x01);          /* NOSC = 0b001: FRC with PLL (unlock sequence) */
    __builtin_write_OSCCONL((uint8_t)((OSCCON | 0x01u) & 0xFFu)); /* OSWEN = 1: go (unlock seq.) */
    for (polls = 0u; polls < HAL_CLOCK_SWITCH_POLLS; ++polls) {
      if (OSCCONbits.COSC == 0x1 && OSCCONbits.LOCK == 1) return FW_OK;
    }
  }
  return FW_ETIMEOUT;
}

/* ======================================================================================== */
/* Pins                                                                                      */
/* ======================================================================================== */

void hal_pins_init(void) {
  AD1PCFGL = 0xFFFF;         /* PCFG5..PCFG0 = 1: AN0..AN5 (RA0, RA1, RB0..RB3) digital */

  /* Idle levels first, so nothing glitches when the directions switch to output. */
  LATBbits.LATB6 = 1;        /* /SS high: MLX90333 deselected */
  LATBbits.LATB7 = 0;        /* SCLK low, its idle level (CKP = 0), until SPI1 takes the pin */
  LATBbits.LATB8 = 1;        /* data line high until SPI1 takes the pin (sensor is open-drain) */
  LATBbits.LATB10 = 1;       /* UART idle (mark) level while UART1 is off */
  TRISBbits.TRISB6 = 0;      /* RB6 output: /SS */
  TRISBbits.TRISB7 = 0;      /* RB7 output: SCK1OUT */
  TRISBbits.TRISB8 = 0;      /* RB8 output: SDO1 */
  TRISBbits.TRISB9 = 1;      /* RB9 input: SDI1 */
  TRISBbits.TRISB10 = 0;     /* RB10 output: U1TX */
#if defined(HAL_SPI_OPEN_DRAIN) && HAL_SPI_OPEN_DRAIN
  /* 5 V sensor whose inputs do not accept 3.3 V highs: drive /SS, SCLK and the data line
   * open-drain with external pull-ups to 5 V (RB6..RB9 are 5 V tolerant digital pins). */
  ODCBbits.ODCB6 = 1;        /* RB6 open-drain */
  ODCBbits.ODCB7 = 1;        /* RB7 open-drain */
  ODCBbits.ODCB8 = 1;        /* RB8 open-drain */
#endif

  __builtin_write_OSCCONL((uint8_t)(OSCCON & 0xBFu)); /* IOLOCK = 0: unlock PPS */
  RPINR20bits.SDI1R = HAL_RP_SDI1;        /* SDI1 input <- RP9 (RB9, pin 18) */
  RPINR20bits.SCK1R = HAL_RP_SCK1;        /* SCK1 input <- RP7, the pin SCK1OUT drives */
  RPOR3bits.RP7R = HAL_PPS_SCK1OUT;       /* RP7 (RB7, pin 16) <- SCK1OUT (function 8) */
  RPOR4bits.RP8R = HAL_PPS_SDO1;          /* RP8 (RB8, pin 17) <- SDO1 (function 7) */
  RPOR5bits.RP10R = HAL_PPS_U1TX;         /* RP10 (RB10, pin 21) <- U1TX (function 3) */
  __builtin_write_OSCCONL((uint8_t)((OSCCON | 0x40u) & 0xFFu)); /* IOLOCK = 1: lock PPS */
}

/* ======================================================================================== */
/* SPI1 master to the MLX90333                                                               */
/* ======================================================================================== */
/* 3-wire bus: the sensor has one open-drain MOSI/MISO pin. SDO1 drives that line through a
 * 1 kOhm series resistor and SDI1 reads it directly, so while the master clocks out 0xFF (line
 * held high through the resistor) the sensor can pull it low for its 0 bits, and a collision can
 * never short two push-pull drivers.
 *
 * SPI mode 1 (CPOL = 0, CPHA = 1): SCLK idles low; the sensor shifts out on the rising (leading)
 * edge and the master samples on the falling (trailing) edge. On the dsPIC, CKP = 0 is "idle
 * low" and CKE = 0 is "output changes on the idle-to-active edge" (CKE is the inverse of CPHA),
 * with SMP = 0 sampling in the middle of the data time, i.e. on the falling edge.
 *
 * A transfer is a chain of one-shot steps: LEAD (Timer3) -> BYTE (SPI1) -> GAP (Timer3) ->
 * BYTE ... -> TAIL (Timer3) -> IDLE. Only `busy` is read outside the interrupts. */

enum { SPI_IDLE = 0, SPI_LEAD, SPI_BYTE, SPI_GAP, SPI_TAIL };

static struct {
  const uint8_t *tx;
  uint8_t *rx;
  uint8_t n;
  volatile uint8_t idx;    /* next byte to send / receive */
  volatile uint8_t phase;  /* SPI_* step in progress */
  volatile uint8_t busy;   /* a transfer holds /SS low; cleared last, after rx[] is complete */
} g_spi;

/* Starts Timer3 as a one-shot of pr + 1 instruction cycles (its interrupt stops it). */
static void spi_pace(uint16_t pr) {
  T3CONbits.TON = 0;         /* stop */
  TMR3 = 0;                  /* count from zero */
  PR3 = pr;                  /* period match after pr + 1 cycles */
  IFS0bits.T3IF = 0;         /* no stale match */
  T3CONbits.TON = 1;         /* run */
}

/* Returns the bus to idle: Timer3 stopped, SPI1 reset, /SS released. Call at IPL 7. */
static void spi_reset(void) {
  T3CONbits.TON = 0;         /* pacing timer stopped */
  IFS0bits.T3IF = 0;         /* and its pending match dropped */
  SPI1STATbits.SPIEN = 0;    /* SPI1 off: shift register and state machine reset */
  SPI1STATbits.SPIROV = 0;   /* clear a receive overflow */
  IFS0bits.SPI1IF = 0;       /* drop a pending byte-done event */
  LATBbits.LATB6 = 1;        /* /SS high */
  g_spi.phase = SPI_IDLE;
  g_spi.busy = 0u;
  SPI1STATbits.SPIEN = 1;    /* SPI1 on again, idle */
}

void hal_spi_init(void) {
  hal_irq_state_t s = hal_irq_save();
  IEC0bits.SPI1IE = 0;       /* interrupts off while configuring */
  IEC0bits.T3IE = 0;
  SPI1STATbits.SPIEN = 0;    /* module off while configuring */
  SPI1CON1bits.DISSCK = 0;   /* SCK1 driven by the module (master clock out) */
  SPI1CON1bits.DISSDO = 0;   /* SDO1 driven by the module */
  SPI1CON1bits.MODE16 = 0;   /* 8-bit transfers */
  SPI1CON1bits.SMP = 0;      /* master samples in the middle of the data time (falling edge) */
  SPI1CON1bits.CKE = 0;      /* output changes on idle-to-active (rising) edge: CPHA = 1 */
  SPI1CON1bits.CKP = 0;      /* SCK idles low: CPOL = 0 -> together SPI mode 1 */
  SPI1CON1bits.SSEN = 0;     /* /SS is a GPIO (RB6), not the module's SS1 pin */
  SPI1CON1bits.MSTEN = 1;    /* master mode */
  SPI1CON1bits.SPRE = 0x6;   /* secondary prescale 2:1 (0b110) */
  SPI1CON1bits.PPRE = 0x0;   /* primary prescale 64:1 (0b00): SCK = FCY / 128 = 309.48 kHz */
  SPI1CON2 = 0;              /* FRMEN = 0: framed mode off */
  SPI1STATbits.SPISIDL = 0;  /* keep running in Idle mode */

  T3CON = 0;                 /* Timer3: TCS = 0 (FCY), TCKPS = 00 (1:1), TGATE = 0, off */
  T3CONbits.TSIDL = 0;       /* keep running in Idle mode */
  T2CONbits.T32 = 0;         /* Timer2/3 as two 16-bit timers */

  IPC2bits.SPI1IP = HAL_IPL_SPI; /* SPI1 byte-done priority 6 */
  IPC2bits.T3IP = HAL_IPL_SPI;   /* Timer3 pacing priority 6 */
  spi_reset();               /* bus idle, SPI1 enabled */
  IEC0bits.SPI1IE = 1;       /* byte-done interrupt on */
  IEC0bits.T3IE = 1;         /* pacing interrupt on */
  hal_irq_restore(s);
}

int hal_spi_start(const uint8_t *tx, uint8_t *rx, uint8_t n) {
  hal_irq_state_t s;
  if (tx == NULL || rx == NULL || n == 0u) return FW_EINVAL;
  s = hal_irq_save();        /* the SPI interrupts (IPL 6) may preempt the sampler (IPL 5) */
  if (g_spi.busy != 0u) {
    hal_irq_restore(s);
    return FW_EBUSY;
  }
  g_spi.tx = tx;
  g_spi.rx = rx;
  g_spi.n = n;
  g_spi.idx = 0u;
  g_spi.busy = 1u;
  g_spi.phase = SPI_LEAD;
  LATBbits.LATB6 = 0;        /* /SS low: select the sensor */
  spi_pace(HAL_US_TO_PR(HAL_SPI_T_LEAD_US));
  hal_irq_restore(s);
  return FW_OK;
}

int hal_spi_poll(void) { return g_spi.busy != 0u ? FW_EBUSY : FW_OK; }

int hal_spi_abort(void) {
  hal_irq_state_t s = hal_irq_save();
  spi_reset();
  hal_irq_restore(s);
  return FW_OK;
}

/* Timer3 one-shot: the pause before a byte, or after the last one, is over. */
void __attribute__((interrupt, no_auto_psv)) _T3Interrupt(void) {
  T3CONbits.TON = 0;         /* one-shot: stop */
  IFS0bits.T3IF = 0;         /* acknowledge */
  if (g_spi.phase == SPI_LEAD || g_spi.phase == SPI_GAP) {
    g_spi.phase = SPI_BYTE;
    SPI1BUF = g_spi.tx[g_spi.idx]; /* clock out the next byte; SPI1IF follows 8 clocks later */
  } else if (g_spi.phase == SPI_TAIL) {
    LATBbits.LATB6 = 1;      /* /SS high: frame done */
    g_spi.phase = SPI_IDLE;
    g_spi.busy = 0u;         /* last: rx[] is complete */
  }
}

/* SPI1: one byte has been shifted in. */
void __attribute__((interrupt, no_auto_psv)) _SPI1Interrupt(void) {
  uint8_t b;
  IFS0bits.SPI1IF = 0;       /* acknowledge */
  b = (uint8_t)SPI1BUF;      /* reading clears SPIRBF */
  SPI1STATbits.SPIROV = 0;   /* cannot overflow with one byte in flight; clear defensively */
  if (g_spi.phase != SPI_BYTE) return; /* stale event after an abort */
  g_spi.rx[g_spi.idx] = b;
  g_spi.idx = (uint8_t)(g_spi.idx + 1u);
  if (g_spi.idx < g_spi.n) {
    g_spi.phase = SPI_GAP;
    spi_pace(g_spi.idx == 1u ? HAL_US_TO_PR(HAL_SPI_T_GAP0_US) : HAL_US_TO_PR(HAL_SPI_T_GAP_US));
  } else {
    g_spi.phase = SPI_TAIL;
    spi_pace(HAL_US_TO_PR(HAL_SPI_T_TAIL_US));
  }
}

/* ======================================================================================== */
/* UART1 link to the FPGA bridge                                                            */
/* ======================================================================================== */
/* Single-producer (main loop: hal_link_write) single-consumer (_U1TXInterrupt) ring. head is
 * written only by the producer, tail only by the consumer; both are free-running 16-bit
 * counters, each read and written in one instruction, so no lock is needed. */

static struct {
  uint8_t buf[HAL_LINK_RING_SIZE];
  volatile uint16_t head;  /* next byte to write (producer) */
  volatile uint16_t tail;  /* next byte to send (consumer) */
} g_link;

void hal_link_init(void) {
  IEC0bits.U1TXIE = 0;       /* TX interrupt off while configuring */
  IEC0bits.U1RXIE = 0;       /* the board only sends */
  U1MODE = 0;                /* UARTEN = 0, STSEL = 0 (1 stop), PDSEL = 00 (8 data, no parity),
                                UEN = 00 (TX/RX only, no flow control), URXINV = 0 */
  U1MODEbits.USIDL = 0;      /* keep running in Idle mode */
  U1MODEbits.BRGH = 1;       /* high-speed: 4 clocks per bit */
  U1BRG = HAL_LINK_BRG;      /* 9: FCY / (4 * 10) = 990.34 kbaud */
  U1STA = 0;                 /* UTXEN = 0, UTXINV = 0 (idle high), UTXBRK = 0 */
  U1STAbits.UTXISEL1 = 1;    /* UTXISEL = 10: interrupt when the TX buffer becomes empty */
  U1STAbits.UTXISEL0 = 0;
  g_link.head = 0u;
  g_link.tail = 0u;
  IPC3bits.U1TXIP = HAL_IPL_LINK; /* TX priority 3, below the sampler */
  U1MODEbits.UARTEN = 1;     /* UART on (takes the U1TX pin from LATB) */
  U1STAbits.UTXEN = 1;       /* transmitter on (must follow UARTEN) */
  IFS0bits.U1TXIF = 0;       /* enabling UTXEN flags an empty buffer: nothing to send yet */
}

int hal_link_write(const uint8_t *data, uint8_t n) {
  uint16_t head;
  uint16_t used;
  uint8_t i;
  if (data == NULL) return FW_EINVAL;
  head = g_link.head;
  used = (uint16_t)(head - g_link.tail);
  if ((uint16_t)(HAL_LINK_RING_SIZE - used) < (uint16_t)n) return FW_EBUSY;
  for (i = 0u; i < n; ++i) {
    g_link.buf[(uint16_t)(head + i) & (HAL_LINK_RING_SIZE - 1u)] = data[i];
  }
  g_link.head = (uint16_t)(head + n); /* publish: one 16-bit store */
  IFS0bits.U1TXIF = 1;       /* kick: the handler runs now and fills the FIFO if it has room */
  IEC0bits.U1TXIE = 1;       /* TX interrupt on while the ring holds data */
  return FW_OK;
}

/* UART1 TX buffer empty (or kicked by hal_link_write): refill the 4-byte FIFO. */
void __attribute__((interrupt, no_auto_psv)) _U1TXInterrupt(void) {
  uint8_t k;
  uint16_t tail = g_link.tail;
  IFS0bits.U1TXIF = 0;       /* acknowledge first: an "empty" after this re-raises it */
  for (k = 0u; k < HAL_UART_FIFO_DEPTH && tail != g_link.head && U1STAbits.UTXBF == 0; ++k) {
    U1TXREG = g_link.buf[tail & (HAL_LINK_RING_SIZE - 1u)];
    tail = (uint16_t)(tail + 1u);
  }
  g_link.tail = tail;
  if (tail == g_link.head) IEC0bits.U1TXIE = 0; /* ring empty: quiet until the next write */
}

/* ======================================================================================== */
/* Timer2: the sampler tick                                                                  */
/* ======================================================================================== */

/* Timer2 prescaler choices, smallest first (finest period resolution). */
static const struct {
  uint16_t div;
  uint8_t tckps; /* T2CON.TCKPS code */
} k_t2_prescale[4] = {{1u, 0x0u}, {8u, 0x1u}, {64u, 0x2u}, {256u, 0x3u}};

int hal_timer_start(uint16_t hz) {
  uint32_t period;
  uint32_t ticks = 0UL;
  uint8_t i;
  if (hz == 0u) return FW_EINVAL;
  period = (uint32_t)((HAL_FCY_HZ + hz / 2u) / hz); /* instruction cycles per tick, rounded */
  for (i = 0u; i < 4u; ++i) {
    ticks = (period + k_t2_prescale[i].div / 2u) / k_t2_prescale[i].div;
    if (ticks >= 2UL && ticks <= 65536UL) break;
  }
  if (i == 4u) return FW_EINVAL; /* faster than FCY / 2 or slower than FCY / 2^24 */
  T2CONbits.TON = 0;         /* stop while reconfiguring */
  IEC0bits.T2IE = 0;         /* and no interrupt meanwhile */
  T2CONbits.TCS = 0;         /* clock from FCY */
  T2CONbits.TGATE = 0;       /* no gating */
  T2CONbits.T32 = 0;         /* 16-bit timer (Timer3 is the SPI pacer) */
  T2CONbits.TSIDL = 0;       /* keep counting in Idle mode */
  T2CONbits.TCKPS = k_t2_prescale[i].tckps & 0x3u; /* 00 1:1, 01 1:8, 10 1:64, 11 1:256 */
  TMR2 = 0;                  /* count from zero */
  PR2 = (uint16_t)(ticks - 1UL); /* period match after PR2 + 1 counts: 19806 at 2 kHz, 1:1 */
  IPC1bits.T2IP = HAL_IPL_SAMPLER; /* sampler priority 5 */
  IFS0bits.T2IF = 0;         /* no stale match */
  IEC0bits.T2IE = 1;         /* period-match interrupt on */
  T2CONbits.TON = 1;         /* run */
  return FW_OK;
}

/* Every 500 us: one sampler step. auto_psv: the core may read const data placed in program
 * memory, so PSVPAG is set on entry (2 cycles). */
void __attribute__((interrupt, auto_psv)) _T2Interrupt(void) {
  IFS0bits.T2IF = 0;         /* acknowledge */
  sampler_tick(&g_board.sampler);
}

/* ======================================================================================== */
/* Interrupt masking (ring.h's consumer side) and power                                      */
/* ======================================================================================== */

hal_irq_state_t hal_irq_save(void) {
  hal_irq_state_t prev;
  SET_AND_SAVE_CPU_IPL(prev, 7); /* SR.IPL = 7 masks every maskable source; returns old IPL */
  return prev;
}

void hal_irq_restore(hal_irq_state_t state) {
  RESTORE_CPU_IPL(state & 0x7u); /* SR.IPL back to the saved level */
}

void hal_idle(void) { __builtin_pwrsav(1); /* PWRSAV #IDLE_MODE: wake on any interrupt */ }

void hal_halt(void) {
  SET_CPU_IPL(7);            /* no interrupt from here on */
  IEC0 = 0;                  /* and none enabled */
  U1MODEbits.UARTEN = 0;     /* link silent (U1TX back to LATB: idle high) */
  for (;;) __builtin_pwrsav(1);
}

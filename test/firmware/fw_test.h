/* A tiny test framework in plain C99 for the firmware core: the same suite runs natively and on
 * an AVR under simavr (16-bit int). Header-only; include it in exactly one translation unit.
 *
 *   static void test_ring_overflow_drops_oldest(void) { CHECK(x == 1); CHECK_EQ(a, b); }
 *   int main(void) { fw_test_begin(); FW_RUN(test_ring_overflow_drops_oldest);
 *                    return fw_test_end(); }
 *
 * Every CHECK counts one pass or one failure; a failure prints the test, line and expression.
 * fw_test_end() prints the closing line exactly as "N passed, N failed" and returns 0 only if
 * nothing failed and something passed. On the AVR, stdout is UART0 (simavr prints it), strings
 * stay in flash (PSTR) so the suite fits in RAM, and fw_test_end() stops the simulator by
 * sleeping with interrupts off. */
#ifndef FW_TEST_H
#define FW_TEST_H

#include <stdint.h>
#include <stdio.h>

#ifdef __AVR__
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/pgmspace.h>
#include <avr/sleep.h>
#define FW_PSTR(s) PSTR(s)
#define FW_PRINTF printf_P
#define FW_PS "%S" /* a string in program memory */
#else
#define FW_PSTR(s) (s)
#define FW_PRINTF printf
#define FW_PS "%s"
#endif

static uint16_t fw_passed_;
static uint16_t fw_failed_;
static const char *fw_current_; /* the running test's name (in flash on the AVR) */
static uint8_t fw_current_failed_;

static void fw_fail_(uint16_t line, const char *expr, unsigned long a, unsigned long b,
                     uint8_t has_values) {
  if (fw_current_failed_ == 0u) {
    FW_PRINTF(FW_PSTR("FAIL " FW_PS "\n"), fw_current_);
    fw_current_failed_ = 1u;
  }
  FW_PRINTF(FW_PSTR("  line %u: " FW_PS), (unsigned)line, expr);
  if (has_values != 0u) FW_PRINTF(FW_PSTR(" (0x%lX vs 0x%lX)"), a, b);
  FW_PRINTF(FW_PSTR("\n"));
}

static void fw_check_(uint8_t ok, uint16_t line, const char *expr) {
  if (ok != 0u) {
    fw_passed_ = (uint16_t)(fw_passed_ + 1u);
  } else {
    fw_failed_ = (uint16_t)(fw_failed_ + 1u);
    fw_fail_(line, expr, 0ul, 0ul, 0u);
  }
}

static void fw_check_eq_(unsigned long a, unsigned long b, uint16_t line, const char *expr) {
  if (a == b) {
    fw_passed_ = (uint16_t)(fw_passed_ + 1u);
  } else {
    fw_failed_ = (uint16_t)(fw_failed_ + 1u);
    fw_fail_(line, expr, a, b, 1u);
  }
}

/* CHECK(cond): counts cond as a pass or a failure. */
#define CHECK(cond) fw_check_((uint8_t)((cond) ? 1u : 0u), (uint16_t)__LINE__, FW_PSTR(#cond))
/* CHECK_EQ(a, b): integer equality (compared as unsigned long); prints both on failure. */
#define CHECK_EQ(a, b) \
  fw_check_eq_((unsigned long)(a), (unsigned long)(b), (uint16_t)__LINE__, FW_PSTR(#a " == " #b))

/* Runs one test function. */
#define FW_RUN(fn)                      \
  do {                                  \
    fw_current_ = FW_PSTR(#fn);         \
    fw_current_failed_ = 0u;            \
    fn();                               \
  } while (0)

#ifdef __AVR__
static int fw_uart_putc_(char c, FILE *f) {
  (void)f;
  while ((UCSR0A & (1u << UDRE0)) == 0u) {
  }
  UDR0 = (uint8_t)c;
  return 0;
}
static FILE fw_uart_ = FDEV_SETUP_STREAM(fw_uart_putc_, NULL, _FDEV_SETUP_WRITE);
#endif

static void fw_test_begin(void) {
#ifdef __AVR__
  UCSR0B = (uint8_t)(1u << TXEN0);
  stdout = &fw_uart_;
#endif
  fw_passed_ = 0u;
  fw_failed_ = 0u;
}

/* Prints "N passed, N failed"; returns the process exit code (on the AVR it never returns). */
static int fw_test_end(void) {
  FW_PRINTF(FW_PSTR("%u passed, %u failed\n"), (unsigned)fw_passed_, (unsigned)fw_failed_);
#ifdef __AVR__
  while ((UCSR0A & (1u << TXC0)) == 0u && (UCSR0A & (1u << UDRE0)) == 0u) {
  }
  cli();
  sleep_enable();
  sleep_cpu(); /* simavr ends the run: "sleeping with interrupts off" */
  for (;;) {
  }
#endif
  return (fw_failed_ == 0u && fw_passed_ > 0u) ? 0 : 1;
}

#endif

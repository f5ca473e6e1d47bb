/* A fixed ring of samples between the timer ISR (producer) and the main loop (consumer).
 *
 * Concurrency rules (STYLE.md item 10):
 *  - ring_push() is called only from the timer ISR; it never blocks and never fails. When the
 *    ring is full it drops the OLDEST sample, counts it in `dropped`, and marks the sample that
 *    is now the oldest with BRIDGE_ST_DROPPED, so the loss is visible downstream.
 *  - ring_pop() is called only from the main loop, and only between hal_irq_save() and
 *    hal_irq_restore() (ring_pop_irqsafe() does that), because the producer may move the tail
 *    when it drops the oldest sample. The critical section copies one record (10 bytes on
 *    the dsPIC and the AVR, 12 with a PC's padding).
 *  - No allocation: storage is the struct itself; RING_CAPACITY is a power of two (16 ms of
 *    samples at 2 kHz), so the main loop may stall that long before anything is lost.
 *  - The DROPPED mark sits on the first sample after the gap: a reader that sees it knows the
 *    timestamps' gap just before it is lost data (not a link fault), and how much was lost.
 *    Further drops move the mark along with the gap's edge.
 */
#ifndef WHISKER_RING_H
#define WHISKER_RING_H

#include <stdint.h>

#define RING_CAPACITY 32u

typedef struct {
  uint32_t tick;
  uint16_t alpha;
  uint16_t beta;
  uint16_t status; /* BRIDGE_ST_* | MLX_ST_* */
} ring_sample_t;

typedef struct {
  ring_sample_t items[RING_CAPACITY];
  volatile uint8_t head;  /* next slot to write (producer) */
  volatile uint8_t tail;  /* next slot to read (consumer; moved by the producer on overflow) */
  volatile uint8_t count;
  uint16_t dropped;       /* samples lost to overflow, saturating */
} ring_t;

void ring_init(ring_t *r);
void ring_push(ring_t *r, const ring_sample_t *s);
/* FW_OK and *out filled, or FW_EEMPTY. Call with interrupts masked (see above). */
int ring_pop(ring_t *r, ring_sample_t *out);
/* ring_pop() inside hal_irq_save()/hal_irq_restore(). */
int ring_pop_irqsafe(ring_t *r, ring_sample_t *out);

#endif

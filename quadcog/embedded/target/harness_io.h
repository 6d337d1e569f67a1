/* What the harness needs from its platform: the Cortex-M4 under QEMU (startup.c) or the host
   (host_io.c). */
#ifndef HARNESS_IO_H
#define HARNESS_IO_H
#include <stdint.h>
void io_write(const char *text);
void io_exit(int status);
uint32_t io_ticks(void);
void io_calibration_loop(uint32_t loops);  /* exactly 2 instructions per loop */
uint32_t io_ticks_mask(void);
uint32_t io_instructions_per_tick(void);
uint32_t io_stack_pointer(void);
uint32_t io_lowest_stack_use(void);
#endif

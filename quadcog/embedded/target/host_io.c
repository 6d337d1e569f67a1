/* The harness platform on the host: stdout, exit; no timer and no stack measurement. */
#include <stdio.h>
#include <stdlib.h>

#include "harness_io.h"

void io_write(const char *text) { fputs(text, stdout); }
void io_exit(int status) { exit(status); }
uint32_t io_ticks(void) { return 0u; }
void io_calibration_loop(uint32_t loops) { (void)loops; }
uint32_t io_ticks_mask(void) { return 0u; }
uint32_t io_instructions_per_tick(void) { return 0u; }
uint32_t io_stack_pointer(void) { return 0u; }
uint32_t io_lowest_stack_use(void) { return 0u; }

/* Minimal start-up for the Cortex-M4 harness under QEMU (mps2-an386): vector table, a reset
   handler that switches the FPU on (CPACR) before any floating-point instruction, copies
   .data, clears .bss and paints the stack (for the stack-depth measurement), then main();
   output and exit through Arm semihosting (bkpt 0xAB), and the SysTick timer as the clock
   (under `-icount shift=0` one tick is 40 instructions: 1 ns per instruction, 25 MHz). */
#include <stdint.h>

#include "harness_io.h"

extern uint32_t _data_load, _data_start, _data_end, _bss_start, _bss_end;
extern uint32_t _stack_bottom, _stack_top;
int main(void);
void reset_handler(void);
static void fault_handler(void);

#define PAINT 0xC0FFEE11u
#define CPACR (*(volatile uint32_t *)0xE000ED88u)
#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)

__attribute__((section(".vectors"), used))
static void (*const vectors[16])(void) = {
    (void (*)(void))(&_stack_top), reset_handler, fault_handler, fault_handler,
    fault_handler, fault_handler, fault_handler, 0, 0, 0, 0, fault_handler, fault_handler,
    0, fault_handler, fault_handler,
};

static int semihost(int op, const void *arg)
{
    register int r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xAB" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

void io_write(const char *text) { semihost(0x04, text); }            /* SYS_WRITE0 */

void io_exit(int status)                                             /* SYS_EXIT */
{
    /* ADP_Stopped_ApplicationExit: QEMU exits 0; RunTimeErrorUnknown: QEMU exits 1 */
    semihost(0x18, (const void *)(status == 0 ? 0x20026u : 0x20023u));
    for (;;) {
    }
}

uint32_t io_ticks(void) { return (0x1000000u - SYST_CVR) & 0xFFFFFFu; }  /* counts up */
void io_calibration_loop(uint32_t loops)
{
    __asm__ volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(loops));
}

uint32_t io_ticks_mask(void) { return 0xFFFFFFu; }
uint32_t io_instructions_per_tick(void) { return 40u; }

uint32_t io_stack_pointer(void)
{
    uint32_t sp;
    __asm__ volatile("mov %0, sp" : "=r"(sp));
    return sp;
}

uint32_t io_lowest_stack_use(void)
{
    const uint32_t *p = &_stack_bottom;
    while (p < &_stack_top && *p == PAINT)
        ++p;
    return (uint32_t)p;
}

static void fault_handler(void)
{
    io_write("fault\n");
    io_exit(1);
}

void reset_handler(void)
{
    uint32_t *src = &_data_load, *dst = &_data_start;
    CPACR |= 0xFu << 20;                      /* CP10, CP11: full access */
    __asm__ volatile("dsb\n\tisb" ::: "memory");
    while (dst < &_data_end)
        *dst++ = *src++;
    for (dst = &_bss_start; dst < &_bss_end; ++dst)
        *dst = 0;
    for (dst = &_stack_bottom; dst < (uint32_t *)(io_stack_pointer() - 64u); ++dst)
        *dst = PAINT;
    SYST_RVR = 0xFFFFFFu;
    SYST_CVR = 0u;
    SYST_CSR = 0x5u;                          /* enable, processor clock, no interrupt */
    io_exit(main());
}

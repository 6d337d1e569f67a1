/* Drive one exported controller over a recorded sequence of states and references
   (harness_data.h) and print, per step, U and the controller state c as the hex of their bits;
   then the timer ticks spent in the step (sum, max), a calibration loop and the stack depth.
   Compiled with -DQC_HEADER='"quadcog_<name>.h"' -DQC_STEP=... -DQC_INIT=... -DQC_NC=... */
#include <stdint.h>
#include <string.h>

#include QC_HEADER
#include "harness_data.h"
#include "harness_io.h"

#define CALIBRATION_LOOPS 100000u          /* 2 instructions each */

/* one step's line: 4 + QC_NC hex numbers with a space each, newline, NUL */
#define LINE_NEEDED ((4u + QC_NC) * (2u * sizeof(qc_real) + 1u) + 2u)
static char line[LINE_NEEDED > 512u ? LINE_NEEDED : 512u];

static char *put_hex(char *p, const qc_real *v)
{
    static const char digits[] = "0123456789abcdef";
    unsigned char bytes[sizeof(qc_real)];
    size_t i;
    memcpy(bytes, v, sizeof bytes);
    for (i = sizeof bytes; i-- > 0;) {      /* little-endian on both: most significant first */
        *p++ = digits[bytes[i] >> 4];
        *p++ = digits[bytes[i] & 15u];
    }
    *p++ = ' ';
    return p;
}

static char *put_uint(char *p, uint32_t v)
{
    char tmp[12];
    int n = 0;
    do {
        tmp[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v);
    while (n)
        *p++ = tmp[--n];
    *p++ = ' ';
    return p;
}

static void put_line(const char *tag, const uint32_t *values, int n)
{
    char *p = line;
    int i;
    while (*tag)
        *p++ = *tag++;
    *p++ = ' ';
    for (i = 0; i < n; ++i)
        p = put_uint(p, values[i]);
    *p++ = '\n';
    *p = 0;
    io_write(line);
}

int main(void)
{
    qc_real c[QC_NC > 0 ? QC_NC : 1], U[4];
    uint32_t k, t0, t1, d, sum = 0u, max = 0u, empty = 0u, sp, result[4];
    const uint32_t mask = io_ticks_mask();
    int i;
    /* calibration: a loop of known length, and the cost of two timer reads */
    t0 = io_ticks();
    io_calibration_loop(CALIBRATION_LOOPS);
    t1 = io_ticks();
    result[0] = ((t1 - t0) & mask) * io_instructions_per_tick();
    result[1] = 2u * CALIBRATION_LOOPS;
    for (k = 0; k < 64u; ++k) {
        t0 = io_ticks();
        t1 = io_ticks();
        empty += (t1 - t0) & mask;
    }
    result[2] = empty * io_instructions_per_tick();
    result[3] = 64u;
    put_line("calibration", result, 4);

    QC_INIT(c);
    sp = io_stack_pointer();
    for (k = 0; k < HARNESS_N; ++k) {
        char *p = line;
        t0 = io_ticks();
        QC_STEP(harness_x[k], harness_ref[k], c, harness_dt, U);
        t1 = io_ticks();
        d = (t1 - t0) & mask;
        sum += d;
        max = d > max ? d : max;
        for (i = 0; i < 4; ++i)
            p = put_hex(p, &U[i]);
        for (i = 0; i < QC_NC; ++i)
            p = put_hex(p, &c[i]);
        *p++ = '\n';
        *p = 0;
        io_write(line);
    }
    result[0] = sum * io_instructions_per_tick();
    result[1] = max * io_instructions_per_tick();
    result[2] = HARNESS_N;
    result[3] = sp ? sp - io_lowest_stack_use() : 0u;
    put_line("cost", result, 4);
    return 0;
}

/* quadcog: the firmware's debug.h, its prints kept by the loop (the flight's console) instead
 * of written to stdout. */
#ifndef QC_DEBUG_SHIM
#define QC_DEBUG_SHIM
#include_next "debug.h"
void qc_console_printf(const char *fmt, ...);
#undef DEBUG_PRINT
#undef DEBUG_PRINT_OS
#define DEBUG_PRINT(fmt, ...) qc_console_printf(DEBUG_FMT(fmt), ##__VA_ARGS__)
#define DEBUG_PRINT_OS(fmt, ...) qc_console_printf(DEBUG_FMT(fmt), ##__VA_ARGS__)
#endif

/* quadcog: what an out-of-tree controller app may take from task.h on the host (its appMain
 * is never run in the loop). */
#ifndef QC_TASK_SHIM
#define QC_TASK_SHIM
#include "FreeRTOS.h"
static inline void vTaskDelay(TickType_t ticks) { (void)ticks; }
static inline TickType_t xTaskGetTickCount(void) { return 0; }
#endif

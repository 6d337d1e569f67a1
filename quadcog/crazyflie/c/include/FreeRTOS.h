/* quadcog: what an out-of-tree controller app may take from FreeRTOS.h on the host. */
#ifndef QC_FREERTOS_SHIM
#define QC_FREERTOS_SHIM
#include <stdint.h>
typedef uint32_t TickType_t;
#define M2T(X) ((TickType_t)(X))
#define F2T(X) ((TickType_t)(1000 / (X)))
#endif

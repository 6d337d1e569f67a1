/* quadcog: the firmware's param.h, with its tables registered with quadcog's loop (as log.h),
 * so a flight can set any parameter by its firmware name (group.name) before it starts. */
#ifndef QC_PARAM_SHIM
#define QC_PARAM_SHIM
#include_next "param.h"
void qc_register_param(const struct param_s *table, int n);
#undef PARAM_GROUP_STOP
#define PARAM_GROUP_STOP(NAME) \
  PARAM_ADD_GROUP(PARAM_GROUP | PARAM_STOP, stop_##NAME, 0x0) }; \
  __attribute__((constructor)) static void __qc_register_params_##NAME(void) { \
    qc_register_param(__params_##NAME, (int)(sizeof(__params_##NAME) / sizeof(__params_##NAME[0]))); }
#endif

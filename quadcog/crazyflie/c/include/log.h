/* quadcog: the firmware's log.h, with its tables registered with quadcog's loop.
 * The firmware is built with UNIT_TEST_MODE, where log.h defines its table macros empty; here
 * they build the same table (group start, variables, group stop) as a static array and a
 * constructor hands it to qc_register_log, so the loop can record any log variable by its
 * firmware name (group.name). */
#ifndef QC_LOG_SHIM
#define QC_LOG_SHIM
#include_next "log.h"
struct qc_log_s { int type; const char *name; void *address; };
void qc_register_log(const struct qc_log_s *table, int n);
#undef LOG_ADD
#undef LOG_ADD_CORE
#undef LOG_ADD_BY_FUNCTION
#undef LOG_ADD_GROUP
#undef LOG_GROUP_START
#undef LOG_GROUP_STOP
#undef LOG_ADD_DEBUG
#define LOG_ADD(TYPE, NAME, ADDRESS) { .type = TYPE, .name = #NAME, .address = (void*)(ADDRESS), },
#define LOG_ADD_CORE(TYPE, NAME, ADDRESS) LOG_ADD(TYPE | LOG_CORE, NAME, ADDRESS)
#define LOG_ADD_BY_FUNCTION(TYPE, NAME, ADDRESS) { .type = TYPE | LOG_BY_FUNCTION, .name = #NAME, .address = (void*)(ADDRESS), },
#define LOG_ADD_DEBUG(TYPE, NAME, ADDRESS) LOG_ADD(TYPE, NAME, ADDRESS)
#define LOG_ADD_GROUP(TYPE, NAME, ADDRESS) { .type = TYPE, .name = #NAME, .address = (void*)(ADDRESS), },
#define LOG_GROUP_START(NAME) \
  static const struct qc_log_s __qc_logs_##NAME[] = { LOG_ADD_GROUP(LOG_GROUP | LOG_START, NAME, 0x0)
#define LOG_GROUP_STOP(NAME) \
  LOG_ADD_GROUP(LOG_GROUP | LOG_STOP, stop_##NAME, 0x0) }; \
  __attribute__((constructor)) static void __qc_register_logs_##NAME(void) { \
    qc_register_log(__qc_logs_##NAME, (int)(sizeof(__qc_logs_##NAME) / sizeof(__qc_logs_##NAME[0]))); }
#endif

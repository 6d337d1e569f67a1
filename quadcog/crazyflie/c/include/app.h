/* quadcog: the app layer's app.h on the host. */
#ifndef QC_APP_SHIM
#define QC_APP_SHIM
void appMain(void);
#endif

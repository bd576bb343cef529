/* Compiles every kernel header as strict C99: see docs/kernel-subset.md. */
#include "host_c.h"
#include "knit_kernel.h"

int knit_kernel_strict_c_anchor(void);
int knit_kernel_strict_c_anchor(void) { return 0; }

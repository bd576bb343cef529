// C++ access to the shared kernel (native/kernel/*.h), wrapped in namespace
// knit::k together with its C host adaptation (kvec3, kv3, ...). Host code
// includes this, never the kernel headers directly.
#pragma once

#include <math.h>  // before the namespace: host_c.h's own includes are then no-ops
#include <string.h>

namespace knit::k {
#include "host_c.h"
#include "knit_kernel.h"
}  // namespace knit::k

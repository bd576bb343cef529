// C++ access to the shared kernel (native/kernel/*.h), wrapped in namespace
// knit::k. Host code includes this, never the kernel headers directly.
#pragma once

#include <cmath>

#include "host_c.h"

namespace knit::k {
#include "knit_kernel.h"
}  // namespace knit::k

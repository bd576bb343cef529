// C++ access to the shared kernel (native/kernel/*.h), wrapped in namespace
// knit::k. Host code includes this, never the kernel headers directly.
#pragma once

#include <cmath>

#include "host_c.h"

namespace knit::k {
// host_c.h declares the vector type at global scope (it is C); name it here
// too so that C++ code can write knit::k::kvec3.
using ::kv3;
using ::kvec3;
#include "knit_kernel.h"
}  // namespace knit::k

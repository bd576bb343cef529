#include "knit/version.h"
namespace knit {
const char* version() { return "0.1.0"; }
}  // namespace knit

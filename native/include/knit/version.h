#pragma once
namespace knit {
// Library version, "major.minor.patch".
const char* version();
}  // namespace knit

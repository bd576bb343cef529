// What `knitshade --version` reports beyond the version number: the
// compiler, the vector path of the batched vertical query on this CPU, and
// the versions of the libraries the renderer runs with.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace knit::render {

// (name, value) pairs, in the order they are printed.
std::vector<std::pair<std::string, std::string>> build_info();

}  // namespace knit::render

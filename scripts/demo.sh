#!/usr/bin/env bash
# Installs what is missing, builds the renderer and renders the demo scene.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup-debian.sh --minimal
if [ -f build/CMakeCache.txt ]; then
  # A build folder configured before (by scripts/test.sh, say) keeps its
  # options: turning its tests off here would leave `ctest --test-dir build`
  # with no tests to run.
  cmake -S . -B build
else
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DKNIT_BUILD_TESTS=OFF -DKNIT_BUILD_BENCH=OFF -DKNIT_BUILD_PYTHON=OFF
fi
cmake --build build -j"$(nproc)" --target knitshade_cli
./build/knitshade render examples/scenes/demo.json -o demo.png "$@"
echo "demo: wrote $(pwd)/demo.png"

#!/usr/bin/env bash
# Installs what is missing, builds the renderer and the Blender add-on,
# renders the demo scene with the native renderer, then renders the same
# scene in Blender: the add-on installed from its zip into an empty user
# folder, the knit objects as yarn geometry (Debian's Blender has no OSL),
# Cycles on the CPU (examples/blender/demo.py).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup-debian.sh --minimal
if [ -f build/CMakeCache.txt ]; then
  # A build folder configured before (by scripts/test.sh, say) keeps its
  # options: turning its tests off here would leave `ctest --test-dir build`
  # with no tests to run. The Blender demo needs the Python module.
  cmake -S . -B build -DKNIT_BUILD_PYTHON=ON
else
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DKNIT_BUILD_TESTS=OFF -DKNIT_BUILD_BENCH=OFF -DKNIT_BUILD_PYTHON=ON
fi
cmake --build build -j"$(nproc)" --target knitshade_cli addon_zip
./build/knitshade render examples/scenes/demo.json -o demo.png "$@"
echo "demo: wrote $(pwd)/demo.png"

# The Blender demo. Blender finds its Python home from the first python3.11
# on PATH: keep pyenv and virtual environments out of its way (numpy would
# vanish), and give it an empty user folder to install the add-on into.
zip=$(ls -t build/knitshade_blender-*.zip | head -n 1)
user=$(mktemp -d)
trap 'rm -rf "$user"' EXIT
mkdir -p "$user/scripts" "$user/config"
clean_path=$(printf '%s' "$PATH" | tr ':' '\n' | grep -v -e '\.pyenv' -e '/venv' | paste -sd: -)
if ! env -u PYTHONHOME -u PYTHONPATH -u VIRTUAL_ENV PATH="${clean_path:-/usr/bin:/bin}" \
    BLENDER_USER_SCRIPTS="$user/scripts" BLENDER_USER_CONFIG="$user/config" \
    blender -b --factory-startup --python-exit-code 1 --python examples/blender/demo.py -- \
    --zip "$zip" --out demo_blender.png >"$user/blender.log" 2>&1; then
  tail -n 40 "$user/blender.log"
  echo "demo: the Blender demo failed (the log above)" >&2
  exit 1
fi
grep '^demo:' "$user/blender.log"
echo "demo: wrote $(pwd)/demo_blender.png"

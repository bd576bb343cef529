#!/usr/bin/env bash
# Renders every example scene at its default settings with the CLI, prints
# the wall time of each (the README table), and writes small PNGs for the
# docs to docs/images/ (downscaled with oiiotool to at most 400 pixels wide).
#
#   scripts/render_examples.sh BUILD_DIR [SCENE...]     (names without .json)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:?usage: scripts/render_examples.sh BUILD_DIR [SCENE...]}
shift
scenes=("$@")
if ((${#scenes[@]} == 0)); then
  scenes=(demo half_cylinder_front half_cylinder_back half_cylinder_closeup swatch_closeup swatch_far
          swatch_distant scarf cushions tablecloth tablecloth_no_capm)
fi
out=$(mktemp -d)
mkdir -p docs/images
printf '| scene | size | spp | wall time (2 threads) |\n| --- | --- | --- | --- |\n'
for s in "${scenes[@]}"; do
  "$build/knitshade" render "examples/scenes/$s.json" -o "$out/$s.png" --quiet --report "$out/$s.report.json"
  /usr/bin/python3 - "$out/$s.report.json" "$s" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
print(f"| {sys.argv[2]} | {r['width']}x{r['height']} | {r['spp']} | {r['seconds']['total']:.1f} s |")
EOF
  oiiotool "$out/$s.png" --resize "400x0" -o "docs/images/$s.png" 2>/dev/null ||
    oiiotool "$out/$s.png" -o "docs/images/$s.png"
done
rm -rf "$out"

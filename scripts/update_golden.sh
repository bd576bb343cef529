#!/usr/bin/env bash
# Re-renders the golden references tests/render/golden/<case>/reference.exr
# with the knitshade CLI at the sample count named in each case's
# threshold.txt ("reference_spp"). Run after an intended change of the
# renderer's output, look at the images, and commit them with the change.
#
#   scripts/update_golden.sh BUILD_DIR [CASE...]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:?usage: scripts/update_golden.sh BUILD_DIR [CASE...]}
shift
cases=("$@")
if ((${#cases[@]} == 0)); then
  for d in tests/render/golden/*/; do cases+=("$(basename "$d")"); done
fi
for c in "${cases[@]}"; do
  dir=tests/render/golden/$c
  spp=$(awk '$1 == "reference_spp" {print $2}' "$dir/threshold.txt")
  echo "golden $c: rendering the reference at $spp spp"
  "$build/knitshade" render "$dir/scene.json" -o "$dir/reference.exr" --spp "$spp" --quiet
done

#!/usr/bin/env bash
# Fuzzes the pattern parser, the scene parser, the mesh loader or the
# geometric queries with libFuzzer (docs/patterns.md, docs/scene-format.md
# and docs/geometry.md, "Fuzzing").
#
#   scripts/fuzz.sh [SECONDS] [BUILD_DIR] [TARGET]   default 600 s, build-fuzz, pattern
#
# TARGET is `pattern`, `scene`, `mesh` or `query`. Configures a separate clang build with
# -DKNIT_FUZZ=ON, runs `fuzz_TARGET` for SECONDS on a scratch copy of
# tests/fuzz/corpus/TARGET, then merges the inputs that add coverage back
# into that corpus (-merge=1). Crashes land in
# tests/fuzz/crash-* (git-ignored). FUZZ_JOBS=N runs N fuzzer processes.
# FUZZ_MAX_LEN (default 9000 bytes: enough for 4097 cells or 4097 rows, so
# the limits are reachable) caps the input size.
# FUZZ_MINIMISE=1 afterwards rewrites the corpus as its minimal subset plus
# the hand-written seed-* files.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-600}"
build="${2:-build-fuzz}"
target="${3:-pattern}"
case "$target" in
  pattern | query) renderer=OFF ;;
  scene | mesh) renderer=ON ;;
  *) echo "scripts/fuzz.sh: unknown target '$target' (pattern, scene, mesh or query)" >&2; exit 2 ;;
esac
jobs="${FUZZ_JOBS:-1}"
max_len="${FUZZ_MAX_LEN:-9000}"
corpus=tests/fuzz/corpus/$target

cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DKNIT_FUZZ=ON \
  -DKNIT_BUILD_PYTHON=OFF -DKNIT_BUILD_BENCH=OFF -DKNIT_BUILD_RENDERER=$renderer >/dev/null
cmake --build "$build" --target "fuzz_$target"
fuzzer="$build/tests/fuzz/fuzz_$target"

scratch="$build/fuzz-scratch"
rm -rf "$scratch"
mkdir -p "$scratch"
echo "fuzzing for ${seconds}s with ${jobs} job(s); corpus $corpus ($(ls "$corpus" | wc -l) files)"
run_args=(-max_total_time="$seconds" -dict="tests/fuzz/$target.dict" -max_len="$max_len" -timeout=10
          -rss_limit_mb=4096 -artifact_prefix=tests/fuzz/ -print_final_stats=1)
if [ "$target" = mesh ]; then
  # assimp leaks a little on some malformed files, inside the library: no
  # leak checks, neither per input nor at exit
  run_args+=(-detect_leaks=0)
  export ASAN_OPTIONS="detect_leaks=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
fi
if [ "$jobs" -gt 1 ]; then
  run_args+=(-fork="$jobs")
fi
"$fuzzer" "${run_args[@]}" "$scratch" "$corpus"

echo "merging new coverage into $corpus"
"$fuzzer" -merge=1 "$corpus" "$scratch"
if [ "${FUZZ_MINIMISE:-0}" = 1 ]; then
  minimal="$build/fuzz-minimal"
  rm -rf "$minimal"
  mkdir -p "$minimal"
  "$fuzzer" -merge=1 "$minimal" "$corpus"
  find "$corpus" -type f ! -name 'seed-*' -delete   # hand-written seeds stay
  cp -n "$minimal"/* "$corpus"/
fi
echo "corpus: $(ls "$corpus" | wc -l) files, $(du -sh "$corpus" | cut -f1)"

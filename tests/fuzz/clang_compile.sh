#!/usr/bin/env bash
# Compiles every source of the knit library with clang++, the compiler of the
# fuzzing build (scripts/fuzz.sh links the scene fuzzer against the library),
# so that a GCC-only construct fails here rather than the next time somebody
# fuzzes. The vector paths of query_batch.cpp are what this guards: their
# target pragmas must work under both compilers.
#
#   tests/fuzz/clang_compile.sh SOURCE_DIR [CLANGXX]     exit 77: no clang++
set -euo pipefail
src=${1:?usage: clang_compile.sh SOURCE_DIR [CLANGXX]}
cxx=${2:-$(command -v clang++ || true)}
if [[ -z "$cxx" || ! -x "$cxx" ]]; then
  echo "clang++ not found (apt-get install clang): the knit library was NOT compiled with clang."
  exit 77
fi
echo "compiling native/src/*.cpp with $("$cxx" --version | head -n 1)"
failed=0
for f in "$src"/native/src/*.cpp; do
  if ! "$cxx" -std=c++17 -O1 -Werror=unknown-pragmas -c "$f" -o /dev/null \
       -I"$src/native/include" -I"$src/native" -I"$src/native/kernel"; then
    echo "FAILED: $f"
    failed=1
  fi
done
exit $failed

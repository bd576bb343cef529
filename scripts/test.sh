#!/usr/bin/env bash
# Installs what is missing, builds everything and runs every test.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup-debian.sh
# PyPI's bpy 5.0.1 for the add-on and shader tests (a venv, installed once);
# without it those tests say they did not run.
bpy_python=$(scripts/setup-bpy.sh) || bpy_python=""
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DKNIT_BUILD_TESTS=ON -DKNIT_BUILD_BENCH=ON -DKNIT_BUILD_PYTHON=ON \
  ${bpy_python:+-DKNIT_BPY_PYTHON="$bpy_python"}
cmake --build build -j"$(nproc)"
set +e
ctest --test-dir build --output-on-failure -j"$(nproc)" "$@" | tee build/ctest-last.log
rc=${PIPESTATUS[0]}
set -e
# CTest prints no output for a skipped test: show why each one skipped (an
# optional tool such as oslc missing), so the log says it plainly.
for t in $(sed -n 's/.*Test *#[0-9]*: \([^ ]*\) .*\*\*\*Skipped.*/\1/p' build/ctest-last.log); do
  echo "---- skipped: $t"
  ctest --test-dir build -R "^${t}\$" -V 2>&1 | sed -n "s/^[0-9]*: //p" | grep -v -E '^(Test timeout|Working Directory|Environment variables| *[A-Z_]+=)' || true
done
exit "$rc"

#!/usr/bin/env bash
# Makes the Python the add-on tests use for Blender 5.0: a venv of Debian's
# python3 (3.11, the Python bpy 5.0 is built for) with PyPI's bpy 5.0.1,
# installed only when missing. Prints the venv's python on stdout (progress
# goes to stderr), so scripts/test.sh passes it to CMake as KNIT_BPY_PYTHON.
#
#   scripts/setup-bpy.sh                 venv at ${KNIT_BPY_VENV:-~/.cache/knitshade/bpy-5.0.1}
#   KNIT_BPY_VENV=/path scripts/setup-bpy.sh
#
# Needs the Debian packages python3-venv and libvulkan1 (scripts/setup-debian.sh
# installs both). Without network access to PyPI it says so and exits 1; the
# bpy tests then report that they did not run.
set -euo pipefail

BPY_VERSION=5.0.1
venv="${KNIT_BPY_VENV:-$HOME/.cache/knitshade/bpy-$BPY_VERSION}"
py="$venv/bin/python"

have_bpy() {
  [[ -x "$py" ]] && "$py" - "$BPY_VERSION" >/dev/null 2>&1 <<'EOF'
import sys
from importlib.metadata import version
sys.exit(0 if version("bpy") == sys.argv[1] else 1)
EOF
}

if have_bpy; then
  echo "setup-bpy: bpy $BPY_VERSION present in $venv" >&2
  echo "$py"
  exit 0
fi

if [[ ! -x "$py" ]]; then
  echo "setup-bpy: creating $venv" >&2
  mkdir -p "$(dirname "$venv")"
  /usr/bin/python3 -m venv "$venv" >&2
fi
echo "setup-bpy: pip install bpy==$BPY_VERSION (about 400 MB)" >&2
if ! "$py" -m pip install --disable-pip-version-check --quiet "bpy==$BPY_VERSION" >&2; then
  echo "setup-bpy: installing bpy $BPY_VERSION failed (no network to PyPI?)" >&2
  exit 1
fi
if ! "$py" -c "import bpy" >/dev/null 2>&1; then
  echo "setup-bpy: bpy installed but does not import (missing libvulkan1? run scripts/setup-debian.sh)" >&2
  exit 1
fi
echo "setup-bpy: bpy $BPY_VERSION ready in $venv" >&2
echo "$py"

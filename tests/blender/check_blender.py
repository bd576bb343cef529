#!/usr/bin/env python3
"""The pybind11 module inside Debian's Blender, which embeds the system's
Python 3.11: what the add-on will stand on (docs/testing.md).

Run by CTest with Debian's python3: computes vertical queries and CAPM
marches with the module here, then runs Blender headless
(`blender -b --factory-startup --python-exit-code 1 --python in_blender.py`),
which imports the same module from the build tree and must give the same
arrays to the bit, raise the module's errors as Python exceptions with their
messages, and keep a pattern and stitch stored on a material through a save
and reload of the .blend.

Blender is looked up in $BLENDER, then on PATH. Without it the test says so
and exits 77 (CTest reports it as skipped).
"""
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.environ.get("KNIT_PYTHON_DIR", os.path.join(ROOT, "build", "python")))

import numpy as np  # noqa: E402

from blender_env import blender_env  # noqa: E402

import knitshade  # noqa: E402  (the module built by this project)

PATTERN = "# seed stitch with a purl column\nK P K P\nP K P P\n"
STITCH = dict(a=1.25, h=3.0, d=-0.6, r=0.4)


def reference(surface):
    """Vertical queries on a grid over two repeats and CAPM marches from a
    slanted view: computed here, and again by in_blender.py inside Blender."""
    n = 48
    xs, ys = np.meshgrid(np.linspace(-3.0, 30.0, n), np.linspace(-2.0, 16.0, n))
    u, v = xs.ravel(), ys.ravel()
    q = surface.query(u, v)
    wi = np.tile(np.array([[0.35, -0.2, 0.915]]), (u.size, 1))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    c = surface.capm(u, v, wi)
    return {"u": u, "v": v, "q_hit": q["hit"], "q_z": q["z"], "q_normal": q["normal"], "q_layers": q["layers"],
            "c_hit": c["hit"], "c_position": c["position"], "c_steps": c["steps"]}


def main():
    blender = os.environ.get("BLENDER") or shutil.which("blender")
    if not blender or not os.path.exists(blender):
        print("blender not found: set BLENDER=/path/to/blender or put blender on PATH "
              "(Debian: apt-get install blender). The module-in-Blender check did NOT run.")
        return 77
    surface = knitshade.KnitSurface(knitshade.Pattern.from_text(PATTERN), knitshade.StitchParams(**STITCH))
    ref = reference(surface)
    if not ref["q_hit"].any() or ref["q_hit"].all() or not ref["c_hit"].any():
        print("FAIL: the reference grid saw only hits or only misses; it would not compare anything")
        return 1
    with tempfile.TemporaryDirectory(prefix="knit-blender-") as out:
        np.savez(os.path.join(out, "reference.npz"), **ref)
        env = blender_env({"KNIT_PYTHON_DIR": os.path.dirname(knitshade.__file__), "KNIT_BLENDER_OUT": out})
        # --python-exit-code must come before --python: a failing script
        # then ends Blender with status 1 instead of 0.
        cmd = [blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python",
               os.path.join(HERE, "in_blender.py")]
        print(" ".join(cmd))
        r = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    lines = [ln for ln in (r.stdout + r.stderr).splitlines()
             if ln.startswith(("knit:", "Traceback", "  ")) or "Error" in ln]
    print("\n".join(lines))
    if r.returncode != 0 or "knit: all checks passed" not in r.stdout:
        print(f"FAIL: Blender exited with {r.returncode}")
        if r.returncode != 0 and not lines:
            print(r.stdout[-3000:] + r.stderr[-3000:])
        return 1
    print("OK: the module gives the same results inside Blender")
    return 0


if __name__ == "__main__":
    sys.exit(main())

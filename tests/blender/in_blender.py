"""Run inside Blender by check_blender.py (see there): the module from the
build tree, its results against the reference computed outside Blender (by
the same function, check_blender.reference), its errors, and a pattern
stored on a material through a save and reload. Any failure raises, which
--python-exit-code turns into Blender's exit status."""
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_blender import PATTERN, STITCH, knitshade, reference  # noqa: E402  (knitshade: KNIT_PYTHON_DIR's)

OUT = os.environ["KNIT_BLENDER_OUT"]


def say(msg):
    print("knit: " + msg, flush=True)


def same(name, a, b):
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape or a.dtype != b.dtype:
        raise AssertionError(f"{name}: shape/type {a.shape} {a.dtype} inside Blender, {b.shape} {b.dtype} outside")
    equal = a == b
    if a.dtype.kind == "f":
        equal |= np.isnan(a) & np.isnan(b)  # (misses: NaN on both sides)
    if not equal.all():
        raise AssertionError(f"{name}: {int(np.count_nonzero(~equal))} of {a.size} values differ from the module "
                             "outside Blender")


def compare(surface, ref, label):
    got = reference(surface)
    for key in ref:
        same(f"{label} {key}", got[key], ref[key])
    say(f"{label}: {got['u'].size} vertical queries ({int(got['q_hit'].sum())} hits) and CAPM marches "
        f"({int(got['c_hit'].sum())} hits) the same to the bit")


def main():
    say(f"Blender {bpy.app.version_string}, Python {sys.version.split()[0]}, module {knitshade.__file__}")
    ref = dict(np.load(os.path.join(OUT, "reference.npz")))
    surface = knitshade.KnitSurface(knitshade.Pattern.from_text(PATTERN), knitshade.StitchParams(**STITCH))
    compare(surface, ref, "in Blender")

    # Errors come through as Python exceptions with their messages, and
    # Blender goes on.
    try:
        knitshade.Pattern.from_text("K P\nK\n")
    except ValueError as e:  # (knitshade.PatternError derives from ValueError)
        if ":2:" not in str(e):
            raise AssertionError(f"the pattern error does not name line 2: {e}")
        say(f"a ragged pattern raises {type(e).__name__}: {e}")
    else:
        raise AssertionError("a ragged pattern was accepted")
    try:
        knitshade.StitchParams(**dict(STITCH, r=-1.0))
    except ValueError as e:
        if "parameter r " not in str(e) or "-1" not in str(e):
            raise AssertionError(f"the parameter error does not name the parameter and value: {e}")
        say(f"a negative radius raises {type(e).__name__}: {e}")
    else:
        raise AssertionError("a negative radius was accepted")

    # A pattern and stitch kept on a material (as ID properties) survive a
    # save and reload of the .blend, and give the same surface again.
    mat = bpy.data.materials.new("KnitCheck")
    mat["knit_pattern"] = PATTERN
    for k, val in STITCH.items():
        mat["knit_" + k] = val
    mat.use_fake_user = True
    path = os.path.join(OUT, "knit_check.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if "KnitCheck" in bpy.data.materials:
        raise AssertionError("the material outlived read_factory_settings: the reload below would prove nothing")
    bpy.ops.wm.open_mainfile(filepath=path)
    m = bpy.data.materials["KnitCheck"]
    again = knitshade.KnitSurface(knitshade.Pattern.from_text(m["knit_pattern"]),
                                  knitshade.StitchParams(**{k: m["knit_" + k] for k in STITCH}))
    compare(again, ref, "after a save and reload")
    say("all checks passed")


main()

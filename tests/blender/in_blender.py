"""Run inside Blender by check_blender.py (see there): the module from the
build tree, its results against the reference computed outside Blender,
its errors, and a pattern stored on a material through a save and reload.
Any failure raises, which --python-exit-code turns into Blender's exit
status."""
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.environ["KNIT_PYTHON_DIR"])
import knitshade  # noqa: E402

OUT = os.environ["KNIT_BLENDER_OUT"]
PATTERN = os.environ["KNIT_BLENDER_PATTERN"]
STITCH = {k: float(v) for k, v in (kv.split("=") for kv in os.environ["KNIT_BLENDER_STITCH"].split(","))}


def say(msg):
    print("knit: " + msg, flush=True)


def same(name, a, b):
    a, b = np.asarray(a), np.asarray(b)
    if a.shape != b.shape or a.dtype != b.dtype:
        raise AssertionError(f"{name}: shape/type {a.shape} {a.dtype} inside Blender, {b.shape} {b.dtype} outside")
    if not np.array_equal(a, b, equal_nan=a.dtype.kind == "f"):
        bad = int(np.count_nonzero(~np.isclose(a, b, rtol=0, atol=0, equal_nan=True)))
        raise AssertionError(f"{name}: {bad} of {a.size} values differ from the module outside Blender")


def compare(surface, ref, label):
    u, v = ref["u"], ref["v"]
    q = surface.query(u, v)
    wi = np.tile(np.array([[0.35, -0.2, 0.915]]), (u.size, 1))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    c = surface.capm(u, v, wi)
    for key, val in (("q_hit", q["hit"]), ("q_z", q["z"]), ("q_normal", q["normal"]), ("q_layers", q["layers"]),
                     ("c_hit", c["hit"]), ("c_position", c["position"]), ("c_steps", c["steps"])):
        same(f"{label} {key}", val, ref[key])
    say(f"{label}: {u.size} vertical queries ({int(q['hit'].sum())} hits) and CAPM marches "
        f"({int(c['hit'].sum())} hits) the same to the bit")


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
        if "line" not in str(e) and ":2:" not in str(e):
            raise AssertionError(f"the pattern error does not say where: {e}")
        say(f"a ragged pattern raises {type(e).__name__}: {e}")
    else:
        raise AssertionError("a ragged pattern was accepted")
    try:
        knitshade.StitchParams(**dict(STITCH, r=-1.0))
    except ValueError as e:
        if "r" not in str(e) or "-1" not in str(e):
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

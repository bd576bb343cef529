"""Yarn geometry against the knit shader on the scarf example, inside Blender
(docs/blender-yarns.md, "Figures"):

    BLENDER_USER_SCRIPTS=$(mktemp -d) blender -b --factory-startup --python bench/blender_yarns.py -- \\
        --zip build/knitshade_blender-0.1.0.zip [--out FILE.json] [--samples 4]
    KNIT_BPY=... ~/.cache/knitshade/bpy-5.0.1/bin/python bench/blender_yarns.py -- --zip ...

The scarf of examples/scenes/scarf.json built with the add-on's API
(examples/blender/scene_json.py). Measured: Generate Yarn Geometry's time
(best of 3) at 8, 16, 32 and 64 points per stitch, its curves and points,
the bytes of the curves' data in Blender (the arrays of its attributes)
against the Knit Fabric material's (its shader text and, where Blender has
OSL, the compiled bytecode); and a Cycles CPU render of the scene at its
400 x 480 pixels with the yarns (the default points per stitch) and, where Blender
has OSL, with the knit shader, and without the scarf: time and Cycles'
peak memory (from the render's status lines).
"""
import argparse
import json
import os
import re
import sys
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "examples", "blender"))
import scene_json  # noqa: E402

TYPE_BYTES = {"FLOAT": 4, "INT": 4, "FLOAT_VECTOR": 12, "FLOAT_COLOR": 16, "BYTE_COLOR": 4, "BOOLEAN": 1,
              "INT8": 1, "FLOAT2": 8, "INT32_2D": 8, "QUATERNION": 16}

def peaks(text):
    """(Blender's peak, Cycles' device peak) in MB from render status lines:
    'Fra:1 Mem:9.77M (Peak 9.77M) | ... | Mem:0.75M, Peak:0.75M | ...'."""
    def mb(m):
        return float(m.group(1)) * (1024.0 if m.group(2) == "G" else 1.0)
    blender = [mb(m) for m in re.finditer(r"\(Peak ([0-9.]+)([MG])\)", text)]
    cycles = [mb(m) for m in re.finditer(r"Peak:([0-9.]+)([MG])", text)]
    # Blender 4.x/5.x hand the render_stats handler 'Mem: 2M | Sample 1/2' (Cycles' memory)
    cycles += [mb(m) for m in re.finditer(r"(?:^|\| )Mem: ?([0-9.]+)([MG])(?! \()", text, re.M)]
    return max(blender or [0.0]), max(cycles or [0.0])


_stats = []


def _on_stats(*args):
    if args and isinstance(args[0], str):
        _stats.append(args[0])


def curves_bytes(cv):
    """Bytes of a Curves datablock's arrays: every attribute, and the offsets."""
    n = 0
    for a in cv.attributes:
        if a.name.startswith("."):
            continue
        n += len(a.data) * TYPE_BYTES.get(a.data_type, 4)
    return n + 4 * (len(cv.curves) + 1)


def render(scene, what):
    """Render once, reading Blender's own status lines (its render_stats
    handler gets no text) from its standard output."""
    import tempfile
    scene.render.filepath = os.path.join(tempfile.gettempdir(), "bench_%s.png" % what)
    del _stats[:]
    sys.stdout.flush()
    log = tempfile.TemporaryFile()
    saved = os.dup(1)
    os.dup2(log.fileno(), 1)
    t0 = time.time()
    try:
        bpy.ops.render.render(write_still=True)
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)
    dt = time.time() - t0
    log.seek(0)
    b, c = peaks(log.read().decode("utf-8", "replace") + "\n" + "\n".join(_stats))
    return {"seconds": round(dt, 2), "blender_peak_mb": round(b, 1), "cycles_peak_mb": round(c, 1)}


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="blender_yarns.py")
    ap.add_argument("--zip", default="")
    ap.add_argument("--out", default="")
    ap.add_argument("--samples", type=int, default=4, help="render samples")
    a = ap.parse_args(argv)
    ks = scene_json.ensure_addon(a.zip)
    bpy.ops.wm.read_homefile(use_empty=True)
    made = scene_json.build(os.path.join(ROOT, "examples", "scenes", "scarf.json"), yarns=False, samples=a.samples)
    scene = bpy.context.scene
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    obj = made["objects"]["scarf"]
    mat = made["knit_materials"]["wool"]
    tree = ks.nodes.knit_node(mat).node_tree
    script = ks.nodes.script_node(tree)
    text = script.script.as_string() if script.script is not None else ""
    out = {"blender": bpy.app.version_string, "osl": ks.api.has_osl(),
           "shader_material": {"text_bytes": len(text.encode("utf-8")), "bytecode_bytes": len(script.bytecode or "")},
           "yarns": {}}
    for samples in (8, 16, 32, 64):
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            yo = ks.yarns.generate(obj, samples=samples)
            times.append(time.perf_counter() - t0)
        info = yo[ks.yarns.YARN_KEY]
        out["yarns"][samples] = {"seconds": round(min(times), 3), "curves": int(info["curves"]),
                                 "points": int(info["points"]), "bytes": curves_bytes(yo.data)}
        print("bench: %d points per stitch: %.2f s, %d curves, %d points, %.2f MB"
              % (samples, min(times), info["curves"], info["points"], curves_bytes(yo.data) / 2 ** 20), flush=True)
    yo = ks.yarns.generate(obj)  # the default points per stitch
    bpy.app.handlers.render_stats.append(_on_stats)
    obj.hide_render, yo.hide_render = True, True
    out["render_without_scarf"] = render(scene, "without")
    print("bench: render without the scarf: %s" % out["render_without_scarf"], flush=True)
    obj.hide_render, yo.hide_render = True, False
    out["render_yarns"] = render(scene, "yarns")
    print("bench: render with yarns: %s" % out["render_yarns"], flush=True)
    if ks.api.has_osl():
        obj.hide_render, yo.hide_render = False, True
        ks.nodes.ensure_scene_renders_osl(scene)
        out["render_shader"] = render(scene, "shader")
        print("bench: render with the shader: %s" % out["render_shader"], flush=True)
    print("bench: " + json.dumps(out), flush=True)
    if a.out:
        with open(a.out, "w") as f:
            json.dump(out, f, indent=1)


main()

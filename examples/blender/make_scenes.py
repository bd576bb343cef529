"""Make the example .blend files: a scarf, cushions and the demo scene,
built from the native scene files (examples/scenes/*.json) with the
Knitshade add-on's API (scene_json.py says how each part converts).

    blender -b --factory-startup -P examples/blender/make_scenes.py -- --out DIR
            [--scenes scarf,cushion,demo,...] [--yarns auto|on|off] [--render SAMPLES]
            [--addon-zip build/knitshade_blender-*.zip]

(or the same arguments after `python make_scenes.py --` in a Python with
PyPI's bpy). Writes DIR/<scene>.blend, and with --render also renders it
in Cycles (CPU) at that many samples to DIR/<scene>.png. The Knit Fabric
materials are plain Blender data: where this Blender has OSL their shader
is compiled into the file, which then renders in any Blender with OSL,
add-on or not. --yarns on (or auto in a Blender without OSL) also lays the
yarns on the knit objects as curves (Generate Yarn Geometry), which render
in any Blender from 3.4 on. Images are packed into the files.
"""
import argparse
import os
import sys
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import scene_json  # noqa: E402

SCENES = {
    "scarf": os.path.join(ROOT, "examples", "scenes", "scarf.json"),
    "cushion": os.path.join(ROOT, "examples", "scenes", "cushions.json"),
    "demo": os.path.join(ROOT, "examples", "scenes", "demo.json"),
    "swatch_closeup": os.path.join(ROOT, "examples", "scenes", "swatch_closeup.json"),
    "half_cylinder_closeup": os.path.join(ROOT, "examples", "scenes", "half_cylinder_closeup.json"),
}


def args_after_dashes(argv):
    return argv[argv.index("--") + 1:] if "--" in argv else []


def render(path, samples):
    """Render the saved scene at `path` with Cycles on the CPU to a PNG
    beside it; returns the PNG's path."""
    scene = bpy.context.scene
    scene.cycles.samples = samples
    scene.render.image_settings.file_format = "PNG"
    png = os.path.splitext(path)[0] + ".png"
    scene.render.filepath = png
    t0 = time.time()
    bpy.ops.render.render(write_still=True)
    print("make_scenes: rendered %s (%d x %d, %d samples, shading system %s) in %.1f s"
          % (png, scene.render.resolution_x, scene.render.resolution_y, samples,
             "OSL" if scene.cycles.shading_system else "SVM", time.time() - t0), flush=True)
    return png


def make(name, out_dir, yarns="auto", samples=0):
    """Build scene `name` into an empty file and save it (and render it at
    `samples` samples, if any); returns the path."""
    bpy.ops.wm.read_homefile(use_empty=True)
    t0 = time.time()
    made = scene_json.build(SCENES[name], yarns=yarns)
    path = os.path.join(out_dir, name + ".blend")
    bpy.ops.wm.save_as_mainfile(filepath=path, compress=True)
    print("make_scenes: %s: %d objects, knit materials %s, %d yarn objects, %.1f s -> %s"
          % (name, len(made["objects"]), ", ".join(made["knit_materials"]) or "none", len(made["yarns"]),
             time.time() - t0, path), flush=True)
    if samples > 0:
        render(path, samples)
    return path


def main(argv=None):
    ap = argparse.ArgumentParser(prog="make_scenes.py")
    ap.add_argument("--out", required=True, help="folder for the .blend files")
    ap.add_argument("--scenes", default="scarf,cushion,demo", help="comma-separated: " + ", ".join(SCENES))
    ap.add_argument("--yarns", choices=("auto", "on", "off"), default="auto",
                    help="lay yarn geometry on the knit objects (auto: where Blender has no OSL)")
    ap.add_argument("--render", type=int, default=0, metavar="SAMPLES",
                    help="also render each scene in Cycles (CPU) at this many samples to DIR/<scene>.png")
    ap.add_argument("--addon-zip", default="", help="install the add-on from this zip if it is not installed")
    a = ap.parse_args(args_after_dashes(sys.argv) if argv is None else argv)
    scene_json.ensure_addon(a.addon_zip)
    os.makedirs(a.out, exist_ok=True)
    yarns = {"auto": "auto", "on": True, "off": False}[a.yarns]
    names = [s.strip() for s in a.scenes.split(",") if s.strip()]
    for n in names:
        if n not in SCENES:
            raise SystemExit("make_scenes: unknown scene '%s' (known: %s)" % (n, ", ".join(SCENES)))
    return [make(n, a.out, yarns, a.render) for n in names]


if __name__ == "__main__":
    main()

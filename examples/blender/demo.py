"""The Blender demo: the add-on installed from its zip into an empty user
folder, the demo scene (examples/scenes/demo.json, the native demo's scene)
built with the add-on's API, its knit objects given yarn geometry, rendered
by Cycles on the CPU to a PNG.

    BLENDER_USER_SCRIPTS=$(mktemp -d) blender -b --factory-startup --python-exit-code 1 \\
        --python examples/blender/demo.py -- --zip build/knitshade_blender-0.1.0.zip --out demo_blender.png

Options after --: --zip (required unless the add-on is already installed
there), --out (PNG, default demo_blender.png), --samples (default: the
scene's 24), --scale (resolution factor, default 1: 480 x 270), --save
FILE.blend (the scene too). scripts/demo.sh runs it after the native demo.
It refuses to install into a user folder that already holds the add-on
unless that is the same zip's (it never touches your own Blender set-up:
set BLENDER_USER_SCRIPTS to an empty folder).
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


def main(argv=None):
    t0 = time.time()
    argv = sys.argv[sys.argv.index("--") + 1:] if argv is None and "--" in sys.argv else (argv or [])
    ap = argparse.ArgumentParser(prog="demo.py")
    ap.add_argument("--zip", default="", help="the add-on zip (build/knitshade_blender-*.zip)")
    ap.add_argument("--out", default="demo_blender.png")
    ap.add_argument("--samples", type=int, default=0)
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--save", default="")
    a = ap.parse_args(argv)
    if a.zip and not os.environ.get("BLENDER_USER_SCRIPTS"):
        raise SystemExit("demo.py: set BLENDER_USER_SCRIPTS to an empty folder: the add-on is installed there")
    ks = scene_json.ensure_addon(a.zip)
    print("demo: Blender %s, add-on from %s; %s" % (bpy.app.version_string, os.path.dirname(ks.__file__),
                                                    ks.native.status()), flush=True)
    bpy.ops.wm.read_homefile(use_empty=True)
    t1 = time.time()
    made = scene_json.build(os.path.join(ROOT, "examples", "scenes", "demo.json"), yarns=True,
                            samples=a.samples or None, scale_resolution=a.scale)
    pts = sum(int(y.get(ks.yarns.YARN_KEY, {}).get("points", 0)) for y in made["yarns"])
    print("demo: scene built in %.1f s: %d yarn objects, %s curve points" % (time.time() - t1, len(made["yarns"]),
                                                                           format(pts, ",")), flush=True)
    scene = bpy.context.scene
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = os.path.abspath(a.out)
    if a.save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(a.save), copy=True)
    t2 = time.time()
    bpy.ops.render.render(write_still=True)
    print("demo: rendered %d x %d, %d samples, in %.1f s (total %.1f s): wrote %s"
          % (scene.render.resolution_x, scene.render.resolution_y, scene.cycles.samples, time.time() - t2,
             time.time() - t0, scene.render.filepath), flush=True)


if __name__ == "__main__":
    main()

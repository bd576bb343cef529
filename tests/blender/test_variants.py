"""Batch renders (examples/blender/render_variants.py, issue 54), in Debian's
Blender 3.4 (run as the command line it documents, `blender -b SCENE.blend
-P render_variants.py -- ...`, in a Blender of its own: yarn geometry, no
OSL) and in bpy 5.0 (called in this process: the knit shader in Cycles'
OSL). A small scene (a plane with a Knit Fabric in front of a green
backdrop) and a list of two pattern x palette variants: both rendered, their
images differ from each other and from the scene rendered without the
plane; the contact sheet and a .blend per variant are written; a saved
variant opened again with the add-on disabled renders the same image (the
knit shader compiled into the file, or the yarn curves). A list with a
mistake is refused with its place named.
"""
import json
import math
import os
import subprocess
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside as T  # noqa: E402

RES = 64


def read(path):
    img = bpy.data.images.load(path, check_existing=False)
    w, h = img.size
    a = np.array(img.pixels[:], dtype=np.float32).reshape(h, w, 4)[..., :3]
    bpy.data.images.remove(img)
    return a


def make_scene(mod, path):
    T.fresh_scene()
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 8
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.seed = 3
    scene.render.resolution_x = scene.render.resolution_y = RES
    scene.render.resolution_percentage = 100
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    scene.view_settings.view_transform = "Standard"
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    cam.location = (0.0, -0.45, 0.9)
    cam.rotation_euler = (math.radians(25.0), 0.0, 0.0)
    scene.camera = cam
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 4.0
    scene.collection.objects.link(sun)
    back = T.plane("Backdrop", size=30.0, location=(0.0, 0.0, -0.5))
    bm = bpy.data.materials.new("Backdrop")
    if bm.node_tree is None:
        bm.use_nodes = True
    nt = bm.node_tree
    nt.nodes.clear()
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (0.0, 0.6, 0.0, 1.0)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    back.data.materials.append(bm)
    plane = T.plane("Swatch", size=2.0)
    mod.api.add_knit_material(plane, name="wool", pattern="K", uv_scale=40.0, colours=[(0.5, 0.5, 0.5)])
    bpy.ops.wm.save_as_mainfile(filepath=path)
    return scene, plane


def main():
    T.say(T.blender())
    mod = T.install()
    sys.path.insert(0, os.path.join(T.SOURCE, "examples", "blender"))
    import render_variants as RV

    scene_path = T.out_path("scene.blend")
    scene, plane = make_scene(mod, scene_path)
    # the scene without the knit: what an empty render looks like
    plane.hide_render = True
    scene.render.filepath = T.out_path("empty.png")
    bpy.ops.render.render(write_still=True)
    empty = read(T.out_path("empty.png"))
    bpy.ops.wm.open_mainfile(filepath=scene_path)

    lst = {
        "material": "wool",
        "patterns": {"rib": "(set below: the file, relative to the list)", "seed": "preset:seed"},
        "palettes": {"red": [[0.7, 0.08, 0.05]], "blue": [[0.08, 0.15, 0.7]]},
        "settings": {"uv_scale": 45.0},
        "variants": [{"name": "rib red", "pattern": "rib", "palette": "red"},
                     {"name": "seed-blue", "pattern": "seed", "palette": "blue", "settings": {"r": 0.6}}],
    }
    list_path = T.out_path("lists/variants.json")
    os.makedirs(os.path.dirname(list_path), exist_ok=True)
    lst["patterns"]["rib"] = os.path.relpath(os.path.join(T.SOURCE, "examples", "patterns", "rib_1x1.knit"),
                                             os.path.dirname(list_path))
    with open(list_path, "w") as f:
        json.dump(lst, f, indent=1)
    out = T.out_path("variants")
    t0 = time.time()
    if bpy.app.background and bpy.app.binary_path and os.path.basename(bpy.app.binary_path).startswith("blender"):
        # Debian's Blender: the documented command line, in a Blender of its own
        cmd = [bpy.app.binary_path, "-b", scene_path, "--python-exit-code", "1", "--python",
               os.path.join(T.SOURCE, "examples", "blender", "render_variants.py"), "--",
               "--variants", list_path, "--out", out]
        T.say("running: " + " ".join(cmd))
        r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, errors="replace",
                           timeout=240)
        lines = [ln for ln in r.stdout.splitlines() if ln.startswith(("[", "render_variants"))]
        for ln in lines:
            T.say("  " + ln)
        T.check(r.returncode == 0, "render_variants.py ended with status %d:\n%s" % (r.returncode, r.stdout[-3000:]))
        T.check(not any(ln.startswith("Traceback") for ln in r.stdout.splitlines()),
                "render_variants.py printed a traceback:\n" + r.stdout[-3000:])
        T.equal(sum(1 for ln in lines if ln.startswith("[")), 2, "progress lines")
    else:
        # bpy: the script's main() in this process, the scene opened as the command line would
        T.equal(RV.main(["--variants", list_path, "--out", out]), 0, "render_variants.main")
    T.say("two variants in %.1f s" % (time.time() - t0))
    a, b = read(os.path.join(out, "rib_red.png")), read(os.path.join(out, "seed-blue.png"))
    d_ab, d_ae, d_be = (float(np.abs(x - y).mean()) for x, y in ((a, b), (a, empty), (b, empty)))
    T.say("mean differences: the two variants %.3f, each from the empty render %.3f and %.3f" % (d_ab, d_ae, d_be))
    T.check(min(d_ab, d_ae, d_be) > 0.02, "variants too alike or empty: %.3f %.3f %.3f" % (d_ab, d_ae, d_be))
    T.check(a[..., 0].mean() > a[..., 2].mean() and b[..., 2].mean() > b[..., 0].mean(),
            "the variants do not show their palettes")
    sheet = read(os.path.join(out, "contact_sheet.png"))
    T.check(sheet.shape[1] >= 2 * RES and sheet.shape[0] >= RES + 10, "contact sheet of %s" % (sheet.shape,))
    for name in ("rib_red", "seed-blue"):
        T.check(os.path.isfile(os.path.join(out, name + ".blend")), "%s.blend was not written" % name)

    # a mistake in the list: refused, naming it
    bad = T.out_path("lists/bad.json")
    with open(bad, "w") as f:
        json.dump({"patterns": {"x": "K"}, "palettes": {}, "variant": []}, f)
    msg = T.raises(RV.VariantError, RV.load_list, bad, contains="unknown key variant")
    T.say("bad list: " + msg)

    # the farm: a variant's file opened with the add-on disabled renders the same
    T.disable(mod.__name__)
    bpy.ops.wm.open_mainfile(filepath=os.path.join(out, "seed-blue.blend"))
    T.check(not hasattr(bpy.types.Material, "knitshade"), "the add-on is still enabled")
    sc = bpy.context.scene
    sc.render.filepath = T.out_path("farm.png")
    t0 = time.time()
    bpy.ops.render.render(write_still=True)
    farm = read(T.out_path("farm.png"))
    d = float(np.abs(farm - b).mean())
    T.say("seed-blue.blend without the add-on: rendered in %.1f s, %.4f from the batch's image (%s)"
          % (time.time() - t0, d, "the knit shader" if T.blender().startswith("Blender 5") else "yarn curves"))
    T.check(d < 0.01, "the variant's file renders differently without the add-on (%.4f)" % d)


T.run(main)

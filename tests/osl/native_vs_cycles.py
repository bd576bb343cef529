"""The knit shader in Blender's Cycles against the native renderer rendering
the model as Cycles does (a knit material's "bsdf_model": "cycles",
docs/cycles.md): the flat swatch, the swatch over a floor lit through it
and the half cylinder of tests/cycles/comparison_scenes.py, built once as
native scene JSON and once in Blender through the add-on's API (the
material a user gets), rendered with two seeds each; the Cycles image must
match the native one within the noise of the two.

Run with the Python that has PyPI's bpy (KNIT_BPY_PYTHON); the native CLI
from KNIT_CLI. `--figures OUT.json` renders larger and writes the figures
(docs/cycles.md) instead of asserting. Exits 77, saying so, where bpy or its
OSL is missing.
"""
import json
import math
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

try:
    import bpy
    import _cycles
except ImportError as e:
    print(f"bpy is not importable here ({e}): the Cycles-against-native comparison did NOT run")
    sys.exit(77)
if not getattr(_cycles, "with_osl", False):
    print(f"bpy {bpy.app.version_string} has no OSL: the Cycles-against-native comparison did NOT run")
    sys.exit(77)

import mathutils  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(ROOT, "addon"))
import knitshade_blender  # noqa: E402
from knitshade_blender import api, preview  # noqa: E402
from knitshade_blender.core import pattern as kpattern  # noqa: E402

CLI = os.environ.get("KNIT_CLI", os.path.join(ROOT, "build", "knitshade"))
OUT = os.environ.get("KNIT_TEST_OUT") or tempfile.mkdtemp(prefix="knit-native-cycles-")
os.makedirs(OUT, exist_ok=True)

sys.path.insert(0, os.path.join(ROOT, "tests", "cycles"))
from comparison_scenes import scenes as comparison_scenes  # noqa: E402


def scenes(size, spp):
    """The flat swatch, the swatch over a floor and the half cylinder of
    tests/cycles/comparison_scenes.py, rendered natively with the closure
    rules of this Blender's Cycles (the swatch preview's choice)."""
    all_scenes = comparison_scenes(size, spp, preview.cycles_version())
    return {name: all_scenes[name] for name in ("swatch", "swatch_floor", "half_cylinder")}


# ---- native ----------------------------------------------------------------

def render_native(name, scene, seed):
    s = json.loads(json.dumps(scene))
    s["film"]["seed"] = seed
    path = os.path.join(OUT, f"{name}_native_{seed}.json")
    with open(path, "w") as f:
        json.dump(s, f, indent=1)
    exr = path[:-5] + ".exr"
    r = subprocess.run([CLI, "render", path, "-o", exr, "--no-cache"], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"knitshade render {path}: {r.stderr.strip()}")
    return read_exr(exr)


# ---- Blender ---------------------------------------------------------------

def look_at_matrix(position, look_at, up):
    p, t, u = (mathutils.Vector(v) for v in (position, look_at, up))
    f = (t - p).normalized()
    x = f.cross(u).normalized()
    y = x.cross(f)
    m = mathutils.Matrix((x, y, -f)).transposed().to_4x4()
    m.translation = p
    return m


_registered = []


def build_blender(scene):
    if _registered:
        knitshade_blender.unregister()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    knitshade_blender.register()
    _registered.append(True)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.shading_system = True
    film = scene["film"]
    sc.render.resolution_x, sc.render.resolution_y = film["width"], film["height"]
    sc.render.resolution_percentage = 100
    sc.cycles.samples = film["spp"]
    sc.cycles.use_adaptive_sampling = False
    sc.cycles.use_denoising = False
    sc.cycles.pixel_filter_type = "BOX"
    sc.cycles.filter_width = 1.0
    sc.cycles.sample_clamp_direct = 0.0
    sc.cycles.sample_clamp_indirect = 0.0
    sc.cycles.blur_glossy = 0.0
    sc.cycles.light_sampling_threshold = 0.0
    depth = scene["integrator"]["max_depth"]
    sc.cycles.max_bounces = depth
    sc.cycles.diffuse_bounces = sc.cycles.glossy_bounces = sc.cycles.transmission_bounces = depth
    sc.cycles.transparent_max_bounces = 64
    sc.cycles.caustics_reflective = sc.cycles.caustics_refractive = True
    sc.view_settings.view_transform = "Standard"
    sc.render.image_settings.file_format = "OPEN_EXR"
    sc.render.image_settings.color_depth = "32"
    sc.render.threads_mode = "FIXED"
    sc.render.threads = 2
    cam_d = scene["camera"]
    cam = bpy.data.cameras.new("camera")
    cam.sensor_fit = "VERTICAL"
    cam.angle_y = math.radians(cam_d["fov"])
    cam.clip_start = 1e-3
    co = bpy.data.objects.new("camera", cam)
    sc.collection.objects.link(co)
    co.matrix_world = look_at_matrix(cam_d["position"], cam_d["look_at"], cam_d.get("up", [0, 1, 0]))
    sc.camera = co
    world = bpy.data.worlds.new("world")
    sc.world = world
    world.color = (0, 0, 0)
    for light in scene["lights"]:
        if light["type"] == "environment":
            world.use_nodes = True
            bg = world.node_tree.nodes["Background"]
            bg.inputs["Color"].default_value = tuple(light["color"]) + (1.0,)
            bg.inputs["Strength"].default_value = light.get("strength", 1.0)
        elif light["type"] == "directional":
            e = light["irradiance"]
            sun = bpy.data.lights.new("sun", "SUN")
            sun.energy = max(e)
            sun.color = tuple(c / max(e) for c in e)
            sun.angle = 0.0
            so = bpy.data.objects.new("sun", sun)
            so.rotation_euler = mathutils.Vector((0, 0, 1)).rotation_difference(
                mathutils.Vector(light["to_light"]).normalized()).to_euler()
            sc.collection.objects.link(so)
        else:
            raise ValueError(f"light type {light['type']} is not translated")
    for ob_d in scene["objects"]:
        bpy.ops.wm.obj_import(filepath=ob_d["mesh"], forward_axis="Y", up_axis="Z")
        ob = bpy.context.selected_objects[0]
        tf = ob_d.get("transform", {})
        if set(tf) - {"translate", "scale"}:
            raise ValueError(f"transform keys {sorted(tf)} are not translated")
        ob.scale = (tf.get("scale", 1.0),) * 3
        ob.location = tf.get("translate", (0.0, 0.0, 0.0))
        m = scene["materials"][ob_d["material"]]
        if m["type"] == "diffuse":
            mat = bpy.data.materials.new(ob_d["material"])
            mat.use_nodes = True
            bsdf = mat.node_tree.nodes.new("ShaderNodeBsdfDiffuse")
            bsdf.inputs["Color"].default_value = tuple(m["albedo"]) + (1.0,)
            bsdf.inputs["Roughness"].default_value = 0.0
            out = next(n for n in mat.node_tree.nodes if n.type == "OUTPUT_MATERIAL")
            mat.node_tree.links.new(bsdf.outputs["BSDF"], out.inputs["Surface"])
            ob.data.materials.clear()
            ob.data.materials.append(mat)
            continue
        pattern = kpattern.load(m["pattern"])
        params = {"uv_scale": m["uv_scale"], "a": m.get("a", 1.5), "h": m.get("h", 4.0), "d": m.get("d", 1.0),
                  "r": m.get("r", 0.65), "body_energy": m["bsdf"]["body_energy"],
                  "body_reflect": m["bsdf"]["body_reflect"], "optical_depth": m["bsdf"]["optical_depth"],
                  "ply_count": 3, "mode": m["mode"].upper()}
        mat = api.add_knit_material(ob, pattern=pattern, colours=[tuple(c) for c in m["yarn_colors"]], **params)
        api.compile_shader(mat)
    return sc


def render_blender(sc, name, seed):
    sc.cycles.seed = seed
    sc.render.filepath = os.path.join(OUT, f"{name}_cycles_{seed}.exr")
    bpy.ops.render.render(write_still=True)
    return read_exr(sc.render.filepath)


def read_exr(path):
    img = bpy.data.images.load(path)
    w, h = img.size
    a = np.array(img.pixels[:], dtype=np.float64).reshape(h, w, 4)[..., :3]
    bpy.data.images.remove(img)
    return a


# ---- comparison -------------------------------------------------------------

def blocks(a, n=4):
    h, w = a.shape[0] // n * n, a.shape[1] // n * n
    return a[:h, :w].reshape(h // n, n, w // n, n, 3).mean(axis=(1, 3))


def compare(c1, c2, n1, n2):
    rmse = lambda a, b: float(np.sqrt(np.mean((a - b) ** 2)))  # noqa: E731
    noise = math.sqrt(0.5 * rmse(c1, c2) ** 2 + 0.5 * rmse(n1, n2) ** 2)
    c, n = 0.5 * (c1 + c2), 0.5 * (n1 + n2)
    noise_mean = noise / math.sqrt(2.0)  # the noise of a difference of two-seed means
    bnoise = math.sqrt(0.5 * rmse(blocks(c1), blocks(c2)) ** 2 + 0.5 * rmse(blocks(n1), blocks(n2)) ** 2)
    return {"mean_cycles": float(c.mean()), "mean_native": float(n.mean()),
            "bias": float(c.mean() / n.mean() - 1.0),
            "rmse": rmse(c, n), "rmse_noise": noise_mean, "rmse_over_noise": rmse(c, n) / noise_mean,
            "rel_rmse": rmse(c, n) / float(n.mean()),
            "block_rmse": rmse(blocks(c), blocks(n)), "block_noise": bnoise / math.sqrt(2.0),
            "block_over_noise": rmse(blocks(c), blocks(n)) / (bnoise / math.sqrt(2.0))}


def main():
    figures = "--figures" in sys.argv
    size, spp = (192, 64) if figures else (96, 16)
    results, failures = {}, []
    for name, scene in scenes(size, spp).items():
        n1, n2 = render_native(name, scene, 1), render_native(name, scene, 2)
        sc = build_blender(scene)
        c1, c2 = render_blender(sc, name, 1), render_blender(sc, name, 2)
        if not (np.isfinite(c1).all() and np.isfinite(c2).all()):
            failures.append(f"{name}: the Cycles render has NaN or infinite pixels")
        r = compare(c1, c2, n1, n2)
        results[name] = r
        ok = r["rmse_over_noise"] < 1.3 and abs(r["bias"]) < 0.03
        print(("ok:   " if ok else "FAIL: ") + f"{name}: Cycles against native 'cycles' at {size} px, {spp} spp: "
              f"RMSE {r['rmse']:.4f} = {r['rmse_over_noise']:.2f} x the noise, 4x4 blocks "
              f"{r['block_over_noise']:.2f} x, bias {r['bias'] * 100:+.2f}% (means {r['mean_cycles']:.4f}, "
              f"{r['mean_native']:.4f})", flush=True)
        if not ok:
            failures.append(name)
    if figures:
        with open(sys.argv[sys.argv.index("--figures") + 1], "w") as f:
            json.dump({"size": size, "spp": spp, "bpy": bpy.app.version_string, "scenes": results}, f, indent=2)
        return 0
    if failures:
        print(f"{len(failures)} comparison(s) failed; images in {OUT}")
        return 1
    print("Cycles renders the knit model as the native renderer's 'cycles' option does, within the noise")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The knit shader in a real Cycles: PyPI's bpy (Blender as a Python module),
whose Cycles has OSL. Run with that Python (KNIT_BPY_PYTHON; docs/testing.md).

  compile   every example pattern's generated shader, a 128 x 128 and a
            256 x 256 one compile in Cycles (`_cycles.osl_compile`), and the
            Script node gets a socket for every parameter and output.
  values    a plane under an orthographic camera, seen slanted, one sample a
            pixel: the shader's outputs (the UV it was given, coverage,
            height, layers, colour index, steps, yarn normal) are rendered
            as emission, pass by pass (the same seed, so the same sample
            positions), and compared with the C++ library's CAPM at the same
            UV and view direction (KnitSurface.capm through the module).
  render    the knit plane lit by a sun in front of an emissive backdrop:
            the stitches show (variance) and so do the holes (backdrop
            pixels).

Exits 77 with a plain message when bpy is not importable or its Cycles has
no OSL; 1 on any failure.
"""
import math
import os
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

try:
    import bpy
    import _cycles
except ImportError as e:
    print(f"bpy is not importable here ({e}): the Cycles (OSL) checks did NOT run. "
          "Run this with the Python that has PyPI's bpy (scripts/setup-bpy.sh, KNIT_BPY_PYTHON).")
    sys.exit(77)
if not getattr(_cycles, "with_osl", False):
    print(f"this bpy {bpy.app.version_string} has no OSL in its Cycles: the Cycles (OSL) checks did NOT run")
    sys.exit(77)

import numpy as np  # noqa: E402  (bpy depends on it)

sys.path.insert(0, os.environ.get("KNIT_PYTHON_DIR", os.path.join(ROOT, "build", "python")))
sys.path.insert(0, os.path.join(ROOT, "addon", "knitshade_blender"))
import knitshade  # noqa: E402  (the module built by this project)
from core import shader  # noqa: E402

# The Cycles add-on's osl.update_script_node imports oslquery, which bpy
# keeps in its own site-packages folder.
sys.path.append(os.path.join(bpy.utils.resource_path("LOCAL"), "python", "lib",
                             f"python{sys.version_info.major}.{sys.version_info.minor}", "site-packages"))
import cycles.osl  # noqa: E402

OUT = os.environ.get("KNIT_TEST_OUT") or tempfile.mkdtemp(prefix="knit-cycles-")
os.makedirs(OUT, exist_ok=True)
failures = []


def check(ok, msg):
    print(("ok:   " if ok else "FAIL: ") + msg, flush=True)
    if not ok:
        failures.append(msg)


def script_node(tree, text_name, source):
    node = tree.nodes.new("ShaderNodeScript")
    text = bpy.data.texts.new(text_name)
    text.write(source)
    node.mode = "INTERNAL"
    node.script = text
    reports = []
    cycles.osl.update_script_node(node, lambda kind, msg: reports.append((kind, msg)))
    return node, reports


def compile_checks():
    patterns = sorted(f for f in os.listdir(os.path.join(ROOT, "examples", "patterns")) if f.endswith(".knit"))
    for name in patterns:
        p = knitshade.Pattern.from_file(os.path.join(ROOT, "examples", "patterns", name))
        src = knitshade.osl_source(p)
        path = os.path.join(OUT, name.replace(".knit", ".osl"))
        with open(path, "w") as f:
            f.write(src)
        ok = _cycles.osl_compile(path, path + ".oso")
        check(ok and "#include" not in src, f"{name}: the generated shader is self-contained and compiles in Cycles")
    rng = np.random.default_rng(7)
    for side in (128, 256):
        codes = rng.integers(0, 2, size=(side, side))
        cols = rng.integers(0, 8, size=(side, side))
        p = knitshade.Pattern.from_rows(codes.tolist(), colors=cols.tolist())
        src = knitshade.osl_source(p)
        path = os.path.join(OUT, f"random_{side}.osl")
        with open(path, "w") as f:
            f.write(src)
        t0 = time.perf_counter()
        ok = _cycles.osl_compile(path, path + ".oso")
        check(ok, f"a {side} x {side} pattern's shader ({len(src) // 1024} KiB) compiles "
                  f"({time.perf_counter() - t0:.2f} s)")
    # Sockets: one per parameter and output, of the kinds Blender makes.
    mat = bpy.data.materials.new("sockets")
    mat.use_nodes = True
    node, reports = script_node(mat.node_tree, "sockets.osl", knitshade.osl_source(knitshade.Pattern.from_rows([[0]])))
    ids_in = [s.identifier for s in node.inputs]
    labels_ok = all(s.name in (p.name, p.label) for s, p in zip(node.inputs, shader.PARAMS))
    names_out = [s.identifier for s in node.outputs]
    check(ids_in == [p.name for p in shader.PARAMS] and labels_ok,
          f"the Script node's inputs are the shader's parameters, in order, named by their labels "
          f"({len(ids_in)}; reports {reports})")
    check(names_out == [o.name for o in shader.OUTPUTS], f"its outputs are the shader's outputs ({names_out})")


def new_scene(res, samples=1):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.shading_system = True
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.seed = 3
    scene.render.resolution_x = scene.render.resolution_y = res
    scene.render.resolution_percentage = 100
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    return scene


def plane_with_uvs(size=2.0):
    bpy.ops.mesh.primitive_plane_add(size=size)
    return bpy.context.object


def render_to_array(scene, path):
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path)
    w, h = img.size
    a = np.array(img.pixels[:], dtype=np.float32).reshape(h, w, 4)
    bpy.data.images.remove(img)
    return a


# The quantities rendered, three per pass; the yarn normal mapped to [0, 1].
PASSES = (("UV.x", "UV.y", "Coverage"), ("Height", "Layers", "ColourIndex"), ("YarnNormal.x", "YarnNormal.y",
                                                                             "YarnNormal.z"), ("Steps", "Error", None))
VALUE_PATTERN = "# two colours, knit and purl\nK K P P\nP K K P\ncolors:\n0 1 1 0\n2 2 0 1\n"
UV_SCALE = 14.0


def values_check():
    res = 96
    scene = new_scene(res)
    ob = plane_with_uvs()
    cam = bpy.data.cameras.new("cam")
    cam.type = "ORTHO"
    cam.ortho_scale = 1.2
    co = bpy.data.objects.new("cam", cam)
    scene.collection.objects.link(co)
    tilt = math.radians(35.0)
    co.location = (0.1, -3.0 * math.sin(tilt), 3.0 * math.cos(tilt))
    co.rotation_euler = (tilt, 0.0, 0.0)
    scene.camera = co
    pattern = knitshade.Pattern.from_text(VALUE_PATTERN)
    mat = bpy.data.materials.new("knit")
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    sn, reports = script_node(nt, "knit.osl", knitshade.osl_source(pattern))
    check(len(sn.inputs) > 0, f"the knit shader compiled in a Script node ({reports})")
    uvn = nt.nodes.new("ShaderNodeUVMap")
    nt.links.new(uvn.outputs["UV"], sn.inputs["UV"])
    sn.inputs["UVScale"].default_value = UV_SCALE
    sep_uv = nt.nodes.new("ShaderNodeSeparateXYZ")
    nt.links.new(uvn.outputs["UV"], sep_uv.inputs[0])
    sep_n = nt.nodes.new("ShaderNodeSeparateXYZ")
    nt.links.new(sn.outputs["YarnNormal"], sep_n.inputs[0])
    sources = {"UV.x": sep_uv.outputs["X"], "UV.y": sep_uv.outputs["Y"]}
    for axis in "xyz":
        m = nt.nodes.new("ShaderNodeMath")
        m.operation = "MULTIPLY_ADD"
        nt.links.new(sep_n.outputs[axis.upper()], m.inputs[0])
        m.inputs[1].default_value = 0.5
        m.inputs[2].default_value = 0.5
        sources["YarnNormal." + axis] = m.outputs[0]
    for name in ("Coverage", "Height", "Layers", "ColourIndex", "Steps", "Error"):
        sources[name] = sn.outputs[name]
    comb = nt.nodes.new("ShaderNodeCombineXYZ")
    emit = nt.nodes.new("ShaderNodeEmission")
    emit.inputs["Strength"].default_value = 1.0
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(comb.outputs[0], emit.inputs["Color"])
    nt.links.new(emit.outputs[0], out.inputs["Surface"])
    ob.data.materials.append(mat)
    got = {}
    for i, names in enumerate(PASSES):
        for slot, name in zip("XYZ", names):
            for link in list(comb.inputs[slot].links):
                nt.links.remove(link)
            comb.inputs[slot].default_value = 0.0
            if name:
                nt.links.new(sources[name], comb.inputs[slot])
        img = render_to_array(scene, os.path.join(OUT, f"values_{i}.exr"))
        for c, name in enumerate(names):
            if name:
                got[name] = img[..., c].ravel()
    on_plane = (got["UV.x"] > 0.02) & (got["UV.x"] < 0.98) & (got["UV.y"] > 0.02) & (got["UV.y"] < 0.98)
    check(on_plane.sum() > 0.5 * res * res, f"{on_plane.sum()} of {res * res} pixels see the plane")
    check(not np.any(got["Error"][on_plane]), "no pixel reports an invalid parameter or missing differentials")
    # The view direction in the plane's frame (t = +x, b = +y, n = +z):
    # towards the orthographic camera.
    view = np.array(co.matrix_world.to_3x3() @ __import__("mathutils").Vector((0.0, 0.0, 1.0)))
    surf = knitshade.KnitSurface(pattern, knitshade.StitchParams(1.5, 4.0, 1.0, 0.65), UV_SCALE)
    u = got["UV.x"][on_plane].astype(np.float64)
    v = got["UV.y"][on_plane].astype(np.float64)
    ref = surf.capm(u, v, view / np.linalg.norm(view))
    cov = got["Coverage"][on_plane] > 0.5
    hit = np.asarray(ref["hit"])
    agree = cov == hit
    check(agree.mean() >= 0.995, f"hit or miss as the C++ CAPM at {agree.mean() * 100:.2f}% of "
                                 f"{on_plane.sum()} pixels ({hit.mean() * 100:.0f}% hits)")
    both = cov & hit
    dz = np.abs(got["Height"][on_plane][both] - np.asarray(ref["position"])[both, 2])
    check(np.percentile(dz, 99) < 1e-4 and dz.max() < 1e-2,
          f"height within 1e-4 of the C++ at 99% of {both.sum()} hits (99th percentile {np.percentile(dz, 99):.2e}, "
          f"max {dz.max():.2e})")
    same_layers = got["Layers"][on_plane][both] == np.asarray(ref["layers"])[both]
    same_colour = got["ColourIndex"][on_plane][both] == np.asarray(ref["color"])[both]
    same_steps = got["Steps"][on_plane] == np.asarray(ref["steps"])
    check(same_layers.mean() >= 0.995, f"layer count equal at {same_layers.mean() * 100:.2f}% of the hits")
    check(same_colour.mean() >= 0.995 and len(set(got["ColourIndex"][on_plane][both])) == 3,
          f"colour index equal at {same_colour.mean() * 100:.2f}% of the hits (indices 0, 1, 2 all seen)")
    check(same_steps.mean() >= 0.995, f"CAPM steps equal at {same_steps.mean() * 100:.2f}% of the pixels")
    n_got = np.stack([got["YarnNormal." + a][on_plane][both] for a in "xyz"], axis=1) * 2.0 - 1.0
    dn = np.linalg.norm(n_got - np.asarray(ref["normal"])[both], axis=1)
    check(np.percentile(dn, 99) < 1e-3, f"yarn normal within 1e-3 at 99% of the hits "
                                         f"(99th percentile {np.percentile(dn, 99):.2e})")

    # Multi-scale, stitches far smaller than a pixel: each pixel's coverage
    # (1 - p_delta of its footprint) averages to the share of view rays
    # that meet yarn, which the C++ CAPM gives over many random points.
    sn.inputs["Mode"].default_value = 1
    sn.inputs["UVScale"].default_value = 40.0 * UV_SCALE
    for slot, name in zip("XYZ", PASSES[0]):
        for link in list(comb.inputs[slot].links):
            nt.links.remove(link)
        nt.links.new(sources[name], comb.inputs[slot])
    img = render_to_array(scene, os.path.join(OUT, "values_multiscale.exr"))
    cov_ms = img[..., 2].ravel()[on_plane]
    fine = knitshade.KnitSurface(pattern, knitshade.StitchParams(1.5, 4.0, 1.0, 0.65), 1.0)
    rng = np.random.default_rng(5)
    pts = rng.uniform(0.0, 200.0, size=(200000, 2))
    share = np.asarray(fine.capm(pts[:, 0], pts[:, 1], view / np.linalg.norm(view))["hit"]).mean()
    partial = ((cov_ms > 0.01) & (cov_ms < 0.99)).mean()
    check(abs(cov_ms.mean() - share) < 0.01 and partial > 0.5,
          f"multi-scale coverage {cov_ms.mean():.4f} over the plane against the C++ CAPM's hit share {share:.4f} "
          f"(partial coverage at {partial * 100:.0f}% of the pixels)")


def render_check():
    res = 96
    scene = new_scene(res, samples=8)
    ob = plane_with_uvs()
    cam = bpy.data.cameras.new("cam")
    co = bpy.data.objects.new("cam", cam)
    scene.collection.objects.link(co)
    co.location = (0.0, -0.9, 1.6)
    co.rotation_euler = (math.radians(30.0), 0.0, 0.0)
    scene.camera = co
    bpy.ops.mesh.primitive_plane_add(size=30.0, location=(0.0, 0.0, -1.0))
    back = bpy.context.object
    bm = bpy.data.materials.new("backdrop")
    bm.use_nodes = True
    bn = bm.node_tree.nodes
    for n in list(bn):
        bn.remove(n)
    em = bn.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (0.0, 1.0, 0.0, 1.0)
    bo = bn.new("ShaderNodeOutputMaterial")
    bm.node_tree.links.new(em.outputs[0], bo.inputs["Surface"])
    back.data.materials.append(bm)
    sun = bpy.data.lights.new("sun", "SUN")
    sun.energy = 3.0
    so = bpy.data.objects.new("sun", sun)
    so.rotation_euler = (math.radians(20.0), math.radians(10.0), 0.0)
    scene.collection.objects.link(so)
    mat = bpy.data.materials.new("knit")
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    sn, _ = script_node(nt, "knit.osl", knitshade.osl_source(knitshade.Pattern.from_file(
        os.path.join(ROOT, "examples", "patterns", "stockinette.knit"))))
    uvn = nt.nodes.new("ShaderNodeUVMap")
    nt.links.new(uvn.outputs["UV"], sn.inputs["UV"])
    sn.inputs["UVScale"].default_value = 40.0
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(sn.outputs["BSDF"], out.inputs["Surface"])
    ob.data.materials.append(mat)
    t0 = time.perf_counter()
    img = render_to_array(scene, os.path.join(OUT, "knit_plane.exr"))
    secs = time.perf_counter() - t0
    rgb = img[..., :3]
    finite = np.isfinite(rgb).all()
    check(finite, "the knit render has no NaN or infinite pixel")
    backdrop = (rgb[..., 1] > 0.6) & (rgb[..., 0] < 0.2) & (rgb[..., 2] < 0.2)
    yarn = ~backdrop
    check(0.02 < backdrop.mean() < 0.6, f"the holes show the backdrop at {backdrop.mean() * 100:.1f}% of the pixels")
    lum = rgb[yarn].mean(axis=1)
    check(lum.std() > 0.02 and lum.mean() > 0.02, f"the yarn is lit and varies (mean {lum.mean():.3f}, "
                                                   f"std {lum.std():.3f}); render {secs:.1f} s")
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_depth = "8"
    scene.render.filepath = os.path.join(OUT, "knit_plane.png")
    bpy.ops.render.render(write_still=True)


def main():
    print(f"bpy {bpy.app.version_string}, OSL {_cycles.osl_version_string}; output in {OUT}")
    compile_checks()
    values_check()
    render_check()
    if failures:
        print(f"{len(failures)} check(s) failed")
        return 1
    print("all Cycles (OSL) checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())

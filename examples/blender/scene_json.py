"""Build a Blender scene from a native scene file (docs/scene-format.md),
with the Knitshade add-on's API for the knit materials.

    import scene_json
    scene_json.build("examples/scenes/scarf.json", yarns="auto")

Used by make_scenes.py, demo.py and the tests. Scene files are +y up;
Blender is +z up: a point (x, y, z) of the file is (x, -z, y) here, as the
OBJ importer maps it. What it converts:

| scene file                  | Blender                                                  |
| --------------------------- | -------------------------------------------------------- |
| film width, height, spp, seed | render resolution, Cycles samples and seed             |
| integrator max_depth        | Cycles max bounces                                       |
| camera (pinhole, fov)       | camera, vertical field of view                           |
| environment file / color    | world: Environment Texture (image packed) / Background   |
| quad light                  | area light (rectangle), power = radiance x pi x area     |
| point / directional light   | point light (power 4 pi I) / sun (strength = irradiance) |
| diffuse / dielectric / thin | Diffuse BSDF / Glass BSDF / Translucent + Transparent    |
| knit                        | a Knit Fabric material (api.add_knit_material)           |
| objects (OBJ, transform)    | imported meshes, the transform M = T Rz Ry Rx S          |

Knit objects get yarn geometry (the add-on's generate_yarns) when `yarns`
is True, or "auto" and this Blender has no OSL. Keys it does not convert
(multi-scale tuning, frames, ...) are left out, said once on the console.
"""
import json
import math
import os

import bpy
from mathutils import Euler, Matrix, Vector

# The file's axes in Blender's: (x, y, z) -> (x, -z, y)
AXES = Matrix(((1, 0, 0, 0), (0, 0, -1, 0), (0, 1, 0, 0), (0, 0, 0, 1)))


def addon():
    """The enabled Knitshade add-on's package (knitshade_blender)."""
    import importlib
    for name in ("knitshade_blender", "bl_ext.user_default.knitshade_blender"):
        try:
            mod = importlib.import_module(name)
        except ImportError:
            continue
        if hasattr(mod, "api"):
            return mod
    raise RuntimeError("the Knitshade add-on is not enabled (install build/knitshade_blender-*.zip)")


def ensure_addon(zip_path=""):
    """Enable the add-on (installing it from `zip_path` first if it is not
    installed); returns its package. addon_utils.enable swallows errors,
    so its result is checked."""
    import addon_utils
    for name in ("knitshade_blender", "bl_ext.user_default.knitshade_blender"):
        if name in bpy.context.preferences.addons:
            return addon()
    installed = any(m.__name__ == "knitshade_blender" for m in addon_utils.modules(refresh=True))
    mod = addon_utils.enable("knitshade_blender", default_set=True, handle_error=None) if installed else None
    if mod is None and zip_path:
        r = bpy.ops.preferences.addon_install(filepath=os.path.abspath(zip_path))
        if r != {"FINISHED"}:
            raise RuntimeError("installing %s failed: %s" % (zip_path, r))
        mod = addon_utils.enable("knitshade_blender", default_set=True, handle_error=None)
    if mod is None:
        raise RuntimeError("the Knitshade add-on could not be enabled%s (see the messages above)"
                           % ("" if zip_path else "; give its zip with --addon-zip"))
    return addon()


def v3(p):
    """A point or direction of the file in Blender's axes."""
    return Vector((p[0], -p[2], p[1]))


def json_transform(t):
    """The object transform of the file (M = T Rz Ry Rx S, or a matrix)."""
    if not t:
        return Matrix.Identity(4)
    if "matrix" in t:
        m = t["matrix"]
        rows = m if isinstance(m[0], list) else [m[i * 4:i * 4 + 4] for i in range(4)]
        return Matrix(rows)
    tr = Matrix.Translation(Vector(t.get("translate", (0, 0, 0))))
    rx, ry, rz = (math.radians(a) for a in t.get("rotate", (0, 0, 0)))
    rot = (Matrix.Rotation(rz, 4, "Z") @ Matrix.Rotation(ry, 4, "Y") @ Matrix.Rotation(rx, 4, "X"))
    s = t.get("scale", 1.0)
    s = (s, s, s) if isinstance(s, (int, float)) else s
    sc = Matrix.Diagonal((s[0], s[1], s[2], 1.0))
    return tr @ rot @ sc


def import_obj(path):
    before = set(bpy.data.objects)
    if hasattr(bpy.ops.wm, "obj_import"):
        bpy.ops.wm.obj_import(filepath=path, forward_axis="NEGATIVE_Z", up_axis="Y")
    else:
        bpy.ops.import_scene.obj(filepath=path, axis_forward="-Z", axis_up="Y")
    new = [o for o in bpy.data.objects if o not in before]
    if len(new) != 1:
        raise RuntimeError("%s: expected one object, the importer made %d" % (path, len(new)))
    return new[0]


def _node_material(name, make):
    mat = bpy.data.materials.new(name)
    if not getattr(mat, "use_nodes", True) or mat.node_tree is None:
        mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.location = (300, 0)
    shader = make(nt)
    nt.links.new(shader.outputs[0], out.inputs["Surface"])
    return mat


def _rgba(c):
    return (float(c[0]), float(c[1]), float(c[2]), 1.0)


def plain_material(name, desc):
    kind = desc["type"]
    if kind == "diffuse":
        def make(nt):
            n = nt.nodes.new("ShaderNodeBsdfDiffuse")
            n.inputs["Color"].default_value = _rgba(desc["albedo"])
            return n
    elif kind == "dielectric":
        def make(nt):
            n = nt.nodes.new("ShaderNodeBsdfGlass")
            n.inputs["IOR"].default_value = float(desc.get("eta", 1.5))
            n.inputs["Roughness"].default_value = math.sqrt(float(desc.get("roughness", 0.0)))
            n.inputs["Color"].default_value = _rgba(desc.get("tint", (1, 1, 1)))
            return n
    elif kind == "thin":
        def make(nt):
            tr = desc["transmittance"]
            al = desc.get("albedo", (0, 0, 0))
            d = nt.nodes.new("ShaderNodeBsdfDiffuse")
            t = nt.nodes.new("ShaderNodeBsdfTransparent")
            add = nt.nodes.new("ShaderNodeAddShader")
            d.inputs["Color"].default_value = _rgba(al)
            t.inputs["Color"].default_value = _rgba(tr)
            nt.links.new(d.outputs[0], add.inputs[0])
            nt.links.new(t.outputs[0], add.inputs[1])
            return add
    else:
        raise ValueError("material '%s': type '%s' is not converted" % (name, kind))
    mat = _node_material(name, make)
    col = desc.get("albedo") or desc.get("tint") or (0.8, 0.8, 0.8)
    mat.diffuse_color = _rgba(col)
    return mat


def knit_settings(desc, base_dir):
    """(pattern, {api keyword: value}) of a knit material of the file."""
    ks = addon()
    from importlib import import_module
    kpattern = import_module(ks.__name__ + ".core.pattern")
    pat = desc["pattern"]
    if isinstance(pat, str):
        pattern = kpattern.load(os.path.join(base_dir, pat))
    else:
        rows = [r if isinstance(r, list) else [c for c in r if c not in " ,"] for r in pat]
        rows = [[kpattern.LETTERS.index(c.upper()) if isinstance(c, str) and not c.isdigit() else int(c)
                 for c in r] for r in rows]
        pattern = kpattern.Pattern.from_rows(rows, desc.get("colors"))
    kw = {"a": desc.get("a", 1.5), "h": desc.get("h", 4.0), "d": desc.get("d", 1.0), "r": desc.get("r", 0.65),
          "uv_scale": desc["uv_scale"], "colours": [tuple(c) for c in desc["yarn_colors"][:8]]}
    bsdf = desc.get("bsdf", {})
    for src, dst in (("roughness_x", "roughness"), ("roughness_y", "roughness_across"), ("eta", "ior"),
                     ("body_energy", "body_energy"), ("body_reflect", "body_reflect"),
                     ("optical_depth", "optical_depth")):
        if src in bsdf:
            kw[dst] = bsdf[src]
    ply = desc.get("ply", {})
    for src, dst in (("ply_count", "ply_count"), ("ply_twist", "ply_twist"), ("fiber_count", "fiber_count"),
                     ("fiber_twist", "fiber_twist")):
        if src in ply:
            kw[dst] = ply[src]
    if "enabled" in ply:
        kw["ply_detail"] = 1 if ply["enabled"] else 0
    if "mode" in desc:
        kw["mode"] = {"near_field": "NEAR_FIELD", "multi_scale": "MULTI_SCALE"}[desc["mode"]]
    if "capm" in desc:
        kw["capm"] = 1 if desc["capm"] else 0
    if "footprint_points" in desc:
        kw["footprint_points"] = desc["footprint_points"]
    return pattern, kw


def _world(scene, lights, base_dir):
    world = bpy.data.worlds.new("World")
    scene.world = world
    if not getattr(world, "use_nodes", True) or world.node_tree is None:
        world.use_nodes = True
    nt = world.node_tree
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputWorld")
    bg = nt.nodes.new("ShaderNodeBackground")
    nt.links.new(bg.outputs[0], out.inputs["Surface"])
    env = next((light for light in lights if light["type"] == "environment"), None)
    if env is None:
        bg.inputs["Color"].default_value = (0, 0, 0, 1)
        return
    bg.inputs["Strength"].default_value = float(env.get("strength", 1.0))
    if "color" in env:
        bg.inputs["Color"].default_value = _rgba(env["color"])
        return
    img = bpy.data.images.load(os.path.join(base_dir, env["file"]), check_existing=True)
    img.pack()  # self-contained .blend
    tex = nt.nodes.new("ShaderNodeTexEnvironment")
    tex.image = img
    coord = nt.nodes.new("ShaderNodeTexCoord")
    mapping = nt.nodes.new("ShaderNodeMapping")
    mapping.vector_type = "VECTOR"
    # The file's u = 0.5 looks toward -z (Blender's +y) and u = 0.75 toward
    # +x; Blender's looks toward +x at u = 0.5: a quarter turn about z, and
    # the file's rotation (about its +y, Blender's +z).
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(-90.0 - float(env.get("rotation", 0.0))))
    nt.links.new(coord.outputs["Generated"], mapping.inputs["Vector"])
    nt.links.new(mapping.outputs[0], tex.inputs["Vector"])
    nt.links.new(tex.outputs["Color"], bg.inputs["Color"])


def _lights(scene, lights):
    for i, light in enumerate(lights):
        kind = light["type"]
        if kind == "quad":
            c, eu, ev = v3(light["corner"]), v3(light["edge_u"]), v3(light["edge_v"])
            n = eu.cross(ev).normalized()
            data = bpy.data.lights.new("Quad %d" % i, "AREA")
            data.shape = "RECTANGLE"
            data.size, data.size_y = eu.length, ev.length
            e = light["emission"]
            m = max(e) or 1.0
            data.color = (e[0] / m, e[1] / m, e[2] / m)
            data.energy = m * math.pi * eu.length * ev.length
            obj = bpy.data.objects.new("Quad %d" % i, data)
            # the light's -z emits: -z along n, x along edge_u
            x = eu.normalized()
            z = -n
            y = z.cross(x)
            rot = Matrix((x, y, z)).transposed().to_4x4()
            obj.matrix_world = Matrix.Translation(c + 0.5 * eu + 0.5 * ev) @ rot
            scene.collection.objects.link(obj)
        elif kind == "point":
            data = bpy.data.lights.new("Point %d" % i, "POINT")
            e = light["intensity"]
            m = max(e) or 1.0
            data.color = (e[0] / m, e[1] / m, e[2] / m)
            data.energy = 4.0 * math.pi * m
            data.shadow_soft_size = 0.0
            obj = bpy.data.objects.new("Point %d" % i, data)
            obj.location = v3(light["position"])
            scene.collection.objects.link(obj)
        elif kind == "directional":
            data = bpy.data.lights.new("Sun %d" % i, "SUN")
            e = light["irradiance"]
            m = max(e) or 1.0
            data.color = (e[0] / m, e[1] / m, e[2] / m)
            data.energy = m
            data.angle = 0.0
            obj = bpy.data.objects.new("Sun %d" % i, data)
            obj.rotation_euler = (-v3(light["to_light"])).to_track_quat("-Z", "Y").to_euler()
            scene.collection.objects.link(obj)


def _camera(scene, cam_desc, film):
    data = bpy.data.cameras.new("Camera")
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.radians(float(cam_desc.get("fov", 40.0)))
    cam = bpy.data.objects.new("Camera", data)
    pos, at = v3(cam_desc["position"]), v3(cam_desc["look_at"])
    up = v3(cam_desc.get("up", (0, 1, 0)))
    z = (pos - at).normalized()
    x = up.cross(z).normalized()
    y = z.cross(x)
    cam.matrix_world = Matrix.Translation(pos) @ Matrix((x, y, z)).transposed().to_4x4()
    scene.collection.objects.link(cam)
    scene.camera = cam


def build(path, yarns="auto", samples=None, scale_resolution=1.0, yarn_samples=None):
    """Build the scene of a scene file into the current scene (emptied
    first). Returns {objects by name, knit materials by name, yarn objects}."""
    ks = addon()
    path = os.path.abspath(path)
    base = os.path.dirname(path)
    with open(path, "r", encoding="utf-8") as f:
        desc = json.load(f)
    scene = bpy.context.scene
    for o in list(scene.objects):
        bpy.data.objects.remove(o)
    film = desc["film"]
    scene.render.engine = "CYCLES"
    scene.render.resolution_x = max(1, int(round(film["width"] * scale_resolution)))
    scene.render.resolution_y = max(1, int(round(film["height"] * scale_resolution)))
    scene.render.resolution_percentage = 100
    scene.cycles.samples = int(samples or film.get("spp", 16))
    scene.cycles.seed = int(film.get("seed", 0))
    scene.cycles.device = "CPU"
    scene.cycles.use_denoising = False
    scene.cycles.max_bounces = int(desc.get("integrator", {}).get("max_depth", 8))
    scene.cycles.transparent_max_bounces = max(scene.cycles.transparent_max_bounces, 32)
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.exposure = float(film.get("exposure", 0.0))
    _camera(scene, desc["camera"], film)
    lights = desc.get("lights", [])
    _world(scene, lights, base)
    _lights(scene, lights)
    materials = desc.get("materials", {})
    plain, knit_desc = {}, {}
    for name, m in materials.items():
        if m["type"] == "knit":
            knit_desc[name] = m
        else:
            plain[name] = plain_material(name, m)
    want_yarns = (not ks.api.has_osl()) if yarns == "auto" else bool(yarns)
    made = {"objects": {}, "knit_materials": {}, "yarns": []}
    knit_mats = {}
    for i, o in enumerate(desc.get("objects", [])):
        obj = import_obj(os.path.join(base, o["mesh"]))
        obj.name = o.get("name", "object %d" % i)
        imported = obj.matrix_world.copy()
        obj.matrix_world = (AXES @ json_transform(o.get("transform")) @ AXES.inverted()) @ imported
        mname = o["material"]
        if mname in plain:
            obj.data.materials.clear()
            obj.data.materials.append(plain[mname])
        elif mname in knit_desc:
            obj.data.materials.clear()
            if mname in knit_mats:
                obj.data.materials.append(knit_mats[mname])
                ks.api.refresh_curvature(obj)
            else:
                pattern, kw = knit_settings(knit_desc[mname], base)
                mat = ks.api.add_knit_material(obj, pattern=pattern, name=mname, **kw)
                knit_mats[mname] = mat
        made["objects"][obj.name] = obj
    made["knit_materials"] = knit_mats
    if want_yarns:
        for obj in list(made["objects"].values()):
            if obj.active_material in knit_mats.values():
                kw = {} if yarn_samples is None else {"samples": yarn_samples}
                made["yarns"].append(ks.yarns.generate(obj, **kw))
    return made

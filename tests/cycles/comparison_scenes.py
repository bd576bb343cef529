"""The scenes on which a Cycles render of the knit shader is compared with
the native renderer's model of it (a knit material's "bsdf_model":
"cycles"): a flat two-colour swatch with see-through holes, the same
swatch over a white floor (seen through the holes, lit by the sun through
the fabric: shadow rays that cross the knit from behind), a half cylinder
and a sphere (whose inside shows through the holes), each lit by a sun and
a sky. Shared by
tests/osl/native_vs_cycles.py (Cycles inside Blender, through the add-on)
and tests/cycles/render_standalone.py (the standalone Cycles app, through
`knitshade export-cycles`), so both compare the same thing.

scenes(size, spp) returns native scene dictionaries (docs/scene-format.md)
with absolute paths; diffuse_twin(scene) the same scene with every knit
material replaced by a plain diffuse one of the mean yarn colour, for
timing the shader against.
"""
import copy
import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MESHES = os.path.join(ROOT, "examples", "scenes", "meshes")
PATTERNS = os.path.join(ROOT, "examples", "patterns")

SUN = {"type": "directional", "to_light": [0.3, -0.5, 1.0], "irradiance": [3.0, 2.9, 2.8]}
SKY = {"type": "environment", "color": [0.06, 0.065, 0.075]}


def _wool(pattern, uv_scale, yarn_colors, **extra):
    m = {"type": "knit", "pattern": os.path.join(PATTERNS, pattern), "uv_scale": uv_scale,
         "yarn_colors": yarn_colors,
         "bsdf": {"body_energy": 0.85, "body_reflect": 0.7, "optical_depth": 1.0},
         "bsdf_model": "cycles", "mode": "near_field"}
    m.update(extra)
    return m


def _scene(size, spp, camera, mesh, material, name):
    return {"version": 1, "film": {"width": size, "height": size, "spp": spp, "seed": 1},
            "integrator": {"max_depth": 8}, "camera": camera, "lights": [SKY, SUN],
            "materials": {"wool": material},
            "objects": [{"name": name, "mesh": os.path.join(MESHES, mesh), "material": "wool"}]}


def _with_floor(scene):
    """scene with a white diffuse floor 0.1 under its first object (z = 0)."""
    scene["materials"]["floor"] = {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}
    scene["objects"].append({"name": "floor", "mesh": os.path.join(MESHES, "quad.obj"), "material": "floor",
                             "transform": {"translate": [0.0, 0.0, -0.1], "scale": 2.0}})
    return scene


def scenes(size, spp, cycles_version=5):
    """The scenes, their knit materials following the closure rules of
    Cycles `cycles_version` (4: before 5.0, 5: 5.0 and later)."""
    two_colours = [[0.72, 0.30, 0.16], [0.85, 0.80, 0.70]]
    out = {
        "swatch": _scene(size, spp,
                         {"position": [0.0, -0.28, 0.36], "look_at": [0.0, 0.0, 0.0], "up": [0, 1, 0], "fov": 40},
                         "quad.obj", _wool("diamond_blocks_2colour.knit", 60, two_colours), "swatch"),
        "half_cylinder": _scene(size, spp,
                                {"position": [0.0, -1.3, 3.3], "look_at": [0.0, 0.0, 0.45], "up": [0, 1, 0],
                                 "fov": 42},
                                "half_cylinder.obj", _wool("rib_2x2.knit", 160, [[0.82, 0.72, 0.58]]),
                                "half cylinder"),
        "sphere": _scene(size, spp,
                         {"position": [0.0, 0.4, 3.4], "look_at": [0.0, 0.0, 0.0], "up": [0, 1, 0], "fov": 40},
                         "sphere.obj", _wool("stripes_two_colour.knit", 240, two_colours, r=0.55), "sphere"),
    }
    out["swatch_floor"] = _with_floor(copy.deepcopy(out["swatch"]))
    for scene in out.values():
        scene["materials"]["wool"]["cycles_version"] = int(cycles_version)
    order = ("swatch", "swatch_floor", "half_cylinder", "sphere")
    return {name: out[name] for name in order}


def diffuse_twin(scene):
    twin = copy.deepcopy(scene)
    for name, m in twin["materials"].items():
        if m.get("type") == "knit":
            colours = m["yarn_colors"]
            mean = [sum(c[i] for c in colours) / len(colours) for i in range(3)]
            twin["materials"][name] = {"type": "diffuse", "albedo": mean}
    return twin

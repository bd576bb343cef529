"""The swatch preview's scene: a Knit Fabric material's settings as a native
scene file (docs/scene-format.md) the `knitshade` CLI renders (no bpy).

The swatch is a curved patch (a 70 degree arc of a cylinder about the
vertical axis, 1 x 1 world units, UVs 0..1 both ways) seen from the front
and a little above, under a fixed light rig: a uniform grey sky, a warm
key light above left in front, and a dim light behind the patch that shows
the holes between the stitches. The material's UV scale is not used: the
swatch shows a fixed number of stitches across (stitches_across()), so
the preview shows the stitch and its colours whatever the mesh's size.
The knit material is rendered with "bsdf_model": "cycles", what the OSL
shader renders in Cycles (with the closure rules of the caller's Cycles,
"cycles_version").
"""
import hashlib
import json
import math

PATCH_WIDTH = 1.0
PATCH_BEND_DEGREES = 70.0
SIZE = 192  # pixels, square
SPP = 16
MAX_STITCHES = 24
LETTERS = "KPFB"


def stitches_across(cols):
    """Stitches the swatch shows across: whole pattern repeats, at least 8
    stitches, at most MAX_STITCHES (a wider pattern is shown in part)."""
    cols = max(1, int(cols))
    if cols >= MAX_STITCHES:
        return MAX_STITCHES
    return min(MAX_STITCHES, cols * max(1, int(math.ceil(8.0 / cols))))


def patch_obj(segments_u=48, segments_v=16, width=PATCH_WIDTH, bend_degrees=PATCH_BEND_DEGREES):
    """OBJ text of the swatch patch: an arc of a cylinder about +y (the
    scene's up), convex towards +z (the camera), `width` long along the arc
    and as tall, with u along the arc and v up (0..1), normals outward."""
    bend = math.radians(bend_degrees)
    radius = width / bend
    lines = ["# Knitshade swatch patch: %d degree arc, %g wide" % (bend_degrees, width)]
    for j in range(segments_v + 1):
        v = j / segments_v
        y = (v - 0.5) * width
        for i in range(segments_u + 1):
            u = i / segments_u
            phi = (u - 0.5) * bend
            lines.append("v %.7f %.7f %.7f" % (radius * math.sin(phi), y, radius * (math.cos(phi) - 1.0)))
    for j in range(segments_v + 1):
        for i in range(segments_u + 1):
            lines.append("vt %.7f %.7f" % (i / segments_u, j / segments_v))
    for j in range(segments_v + 1):
        for i in range(segments_u + 1):
            phi = (i / segments_u - 0.5) * bend
            lines.append("vn %.7f 0 %.7f" % (math.sin(phi), math.cos(phi)))
    w = segments_u + 1
    for j in range(segments_v):
        for i in range(segments_u):
            a = j * w + i + 1
            b, c, d = a + 1, a + 1 + w, a + w
            lines.append("f %d/%d/%d %d/%d/%d %d/%d/%d" % (a, a, a, b, b, b, c, c, c))
            lines.append("f %d/%d/%d %d/%d/%d %d/%d/%d" % (a, a, a, c, c, c, d, d, d))
    return "\n".join(lines) + "\n"


def _rgb(c):
    return [round(float(x), 6) for x in tuple(c)[:3]]


def knit_material(values, pattern, cycles_version=5):
    """The scene file's knit material for a Knit Fabric's settings
    (`values`: {shader parameter name: value}, as nodes.get_value gives
    them) and pattern (a core.pattern.Pattern), rendered as the Cycles of
    `cycles_version` (4: before Blender 5.0, 5: 5.0 and later) renders it."""
    g = values.get
    n = stitches_across(pattern.cols)
    palette = [_rgb(g("Yarn%d" % i, (0.5, 0.5, 0.5))) for i in range(8)]
    tint = _rgb(g("TransmitTint", (1, 1, 1)))
    used = max(1, min(8, pattern.num_colors))
    mat = {
        "type": "knit",
        "pattern": ["".join(LETTERS[c] for c in row) for row in pattern.code_rows()],
        "a": float(g("A", 1.5)), "h": float(g("H", 4.0)), "d": float(g("D", 1.0)), "r": float(g("R", 0.65)),
        "uv_scale": round(2.0 * math.pi * n, 6),  # u runs 0..1 across the patch
        "yarn_colors": palette[:used],
        "transmit_colors": [[c * t for c, t in zip(col, tint)] for col in palette[:used]],
        "bsdf": {
            "roughness_x": float(g("Roughness", 0.15)), "roughness_y": float(g("RoughnessAcross", 0.45)),
            "eta": float(g("IOR", 1.55)), "body_energy": float(g("BodyEnergy", 0.7)),
            "body_reflect": float(g("BodyReflect", 0.6)), "optical_depth": float(g("OpticalDepth", 1.0)),
        },
        "ply": {
            "enabled": bool(g("PlyDetail", True)), "ply_count": int(g("PlyCount", 3)),
            "ply_twist": float(g("PlyTwist", 28.65)), "fiber_count": int(g("FiberCount", 40)),
            "fiber_twist": float(g("FiberTwist", -20.05)),
        },
        "mode": "multi_scale" if int(g("Mode", 0)) == 1 else "near_field",
        "capm": bool(g("CAPM", True)),
        "footprint_points": int(g("FootprintPoints", 4)),
        "capm_options": {"max_steps": int(g("CapmSteps", 32))},
        "bsdf_model": "cycles",
        "cycles_version": int(cycles_version),
    }
    if pattern.has_colors:
        rows = pattern.color_rows()
        # indices beyond the palette take its last colour, as the shader does
        mat["colors"] = [[min(c, used - 1) for c in row] for row in rows]
    return mat


def scene(values, pattern, mesh_file, size=SIZE, spp=SPP, cycles_version=5):
    """The whole scene file (a dict) of the swatch."""
    return {
        "version": 1,
        "film": {"width": int(size), "height": int(size), "spp": int(spp), "seed": 1},
        "camera": {"position": [0.0, 0.35, 1.55], "look_at": [0.0, 0.0, -0.08], "fov": 38.0},
        "integrator": {"max_depth": 8},
        "lights": [
            {"type": "environment", "color": [0.25, 0.26, 0.28]},
            {"type": "quad", "corner": [-1.6, 1.2, 0.6], "edge_u": [0.5, 0.5, 0.0], "edge_v": [0.0, 0.0, 0.8],
             "emission": [7.0, 6.5, 5.8]},
            {"type": "quad", "corner": [-0.6, -0.6, -1.4], "edge_u": [1.2, 0.0, 0.0], "edge_v": [0.0, 1.2, 0.0],
             "emission": [1.2, 1.25, 1.35]},
        ],
        "materials": {"knit": knit_material(values, pattern, cycles_version)},
        "objects": [{"name": "swatch", "mesh": mesh_file, "material": "knit"}],
    }


def scene_text(values, pattern, mesh_file, size=SIZE, spp=SPP, cycles_version=5):
    return json.dumps(scene(values, pattern, mesh_file, size, spp, cycles_version), indent=1, sort_keys=True)


def settings_key(values, pattern, size=SIZE, spp=SPP):
    """A short hash of what the swatch shows: equal keys, equal images."""
    text = json.dumps({"v": {k: (list(v) if isinstance(v, tuple) else v) for k, v in sorted(values.items())},
                       "p": pattern.to_storage(), "s": [size, spp]}, sort_keys=True)
    return hashlib.sha1(text.encode("utf-8")).hexdigest()[:16]

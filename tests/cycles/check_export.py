"""`knitshade export-cycles` checked against the scene it exports (no Cycles
needed): the XML parses, and holds what the scene says in the form the
standalone Cycles 4.2 app reads (docs/renderer.md, "Export to Cycles").

    check_export.py --cli KNITSHADE --out DIR SCENE.json ...
    check_export.py --cli KNITSHADE --out DIR --synthetic

--synthetic writes and checks a scene with what the examples lack: point
lights, a two-sided quad, a rotated environment image, a dielectric with a
tint and roughness, a smooth one of eta 1, a thin sheet, object
transforms, a multi-scale knit material with two colours and a
transmission tint, ply and CAPM settings, a portrait image.

Checked per scene: one camera, in a transform whose matrix is the scene
camera's frame (right, up, forward, position) and whose fov is the
vertical field of view over the shorter image side; the integrator's
depth and the film's exposure; one mesh per object under its material's
shader, of triangles, with smooth normals, and UVs of 3 corners x 2
numbers per triangle; each knit material's script node, its shader file
beside the XML, self-contained (no #include), of the pattern's size (the
same bytes as `knitshade osl` for pattern files), its UV input linked from
a texture coordinate's UV, its BSDF into the surface, every value set a
parameter of the shader and equal to the scene's; on curved knit meshes
the per-corner tangent attribute equal to the add-on's per-face curvature
of the exported mesh, linked into Curvature; the lights (quads as
emissive meshes of their radiance, points as Cycles point lights of
strength 4 pi I, directional as suns, the environment as the background
with a background light, its image's lookup equal to the native one in 200
directions).
"""
import argparse
import json
import math
import os
import random
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

FAILURES = []


def check(ok, what):
    if not ok:
        FAILURES.append(what)
        print("FAIL:", what)
    return ok


def close(a, b, tol=1e-5):
    return abs(a - b) <= tol * max(1.0, abs(a), abs(b))


def floats(text):
    return [float(t) for t in text.replace(",", " ").split()]


def close_list(a, b, tol=1e-5):
    return len(a) == len(b) and all(close(x, y, tol) for x, y in zip(a, b))


# ---- running the exporter ----------------------------------------------------

def export(cli, scene, xml, *extra):
    r = subprocess.run([cli, "export-cycles", scene, "-o", xml, *extra], capture_output=True, text=True)
    return r


# ---- the scene as the exporter should see it ---------------------------------

KNIT_DEFAULTS = {"a": 1.5, "h": 4.0, "d": 1.0, "r": 0.65}
BSDF_DEFAULTS = {"roughness_x": 0.15, "roughness_y": 0.45, "eta": 1.55, "body_energy": 0.7, "body_reflect": 0.6,
                 "optical_depth": 1.0}
PLY_TWIST_RAD, FIBER_TWIST_RAD = 0.5, -0.35  # the library's defaults (the scene's in degrees)


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def norm(a):
    n = math.sqrt(sum(x * x for x in a))
    return [x / n for x in a]


def pattern_size(material, scene_dir):
    """(rows, cols) of a knit material's pattern."""
    pat = material["pattern"]
    if isinstance(pat, str):
        path = pat if os.path.isabs(pat) else os.path.join(scene_dir, pat)
        rows = []
        with open(path) as f:
            for line in f:
                line = line.split("#", 1)[0].strip()
                if not line:
                    continue
                if line.lower().rstrip(":") in ("colors", "colours"):
                    break
                rows.append(line)
    else:
        rows = pat
    def cells(row):
        if isinstance(row, list):
            return len(row)
        return len(row.replace(",", " ").split()) if (" " in row or "," in row) else len(row)
    return len(rows), cells(rows[0])


def expected_knit_params(m):
    b = dict(BSDF_DEFAULTS, **m.get("bsdf", {}))
    ply = m.get("ply", {})
    cols = m["yarn_colors"]
    tint = [1.0, 1.0, 1.0]
    if "transmit_colors" in m:
        for c in range(3):
            for y, t in zip(cols, m["transmit_colors"]):
                if y[c] > 0:
                    tint[c] = t[c] / y[c]
                    break
    p = {"UVScale": m["uv_scale"], "A": m.get("a", 1.5), "H": m.get("h", 4.0), "D": m.get("d", 1.0),
         "R": m.get("r", 0.65), "TransmitTint": tint,
         "Roughness": b["roughness_x"], "RoughnessAcross": b["roughness_y"], "IOR": b["eta"],
         "BodyEnergy": b["body_energy"], "BodyReflect": b["body_reflect"], "OpticalDepth": b["optical_depth"],
         "PlyDetail": 1 if ply.get("enabled", True) else 0, "PlyCount": ply.get("ply_count", 3),
         "PlyTwist": ply.get("ply_twist", math.degrees(PLY_TWIST_RAD)),
         "FiberCount": ply.get("fiber_count", 40),
         "FiberTwist": ply.get("fiber_twist", math.degrees(FIBER_TWIST_RAD)),
         "Mode": 1 if m.get("mode", "near_field") == "multi_scale" else 0,
         "FootprintPoints": m.get("footprint_points", 4), "CAPM": 1 if m.get("capm", True) else 0,
         "CapmSteps": m.get("capm_options", {}).get("max_steps", 32)}
    for i, c in enumerate(cols):
        p["Yarn%d" % i] = c
    return p


# ---- the shader's parameters --------------------------------------------------

DECL = re.compile(r"^\s*(output\s+)?(point|vector|normal|color|float|int|string|closure\s+color)\s+(\w+)\s*=",
                  re.M)


def shader_params(text):
    """{name: type} of the knit_fabric shader's inputs, read from its declaration."""
    start = text.index("shader knit_fabric(")
    body = text[start:text.index(")\n{", start)]
    return {m.group(3): m.group(2) for m in DECL.finditer(body) if not m.group(1)}


# ---- lat-long lookups ----------------------------------------------------------

def native_uv(d, rotation_deg):
    c, s = math.cos(math.radians(rotation_deg)), math.sin(math.radians(rotation_deg))
    x, y, z = c * d[0] - s * d[2], d[1], s * d[0] + c * d[2]
    theta = math.acos(max(-1.0, min(1.0, y)))
    phi = math.atan2(x, -z)
    return (phi / (2 * math.pi) + 0.5) % 1.0, theta / math.pi


def rot(axis, a):
    c, s = math.cos(a), math.sin(a)
    if axis == 0:
        return [[1, 0, 0], [0, c, -s], [0, s, c]]
    if axis == 1:
        return [[c, 0, s], [0, 1, 0], [-s, 0, c]]
    return [[c, -s, 0], [s, c, 0], [0, 0, 1]]


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def cycles_uv(d, euler):
    """Cycles 4.2's environment texture (OSL node_environment_texture,
    equirectangular) with a 'vector' texture mapping of Euler angles
    `euler`: R = Rz Ry Rx applied to the direction; the image's t (0 at the
    top row)."""
    r = matmul(rot(2, euler[2]), matmul(rot(1, euler[1]), rot(0, euler[0])))
    p = norm([sum(r[i][k] * d[k] for k in range(3)) for i in range(3)])
    u = -math.atan2(p[1], p[0]) / (2 * math.pi) + 0.5
    v = math.atan2(p[2], math.hypot(p[0], p[1])) / math.pi + 0.5
    return u % 1.0, 1.0 - v


# ---- the checks ----------------------------------------------------------------

def graph(shader):
    """{node name: element} and [(from node, socket, to node, socket)] of a shader graph."""
    nodes = {n.get("name"): n for n in shader if n.tag != "connect" and n.get("name")}
    links = []
    for c in shader.findall("connect"):
        f, t = c.get("from").split(), c.get("to").split()
        links.append((f[0], f[1].lower(), t[0], t[1].lower()))
    return nodes, links


def linked(links, to_node, to_socket):
    for f, fs, t, ts in links:
        if t == to_node and ts == to_socket.lower():
            return f, fs
    return None


def check_scene(cli, scene_path, out_dir, *extra):
    name = os.path.splitext(os.path.basename(scene_path))[0]
    xml_path = os.path.join(out_dir, name + ".xml")
    r = export(cli, scene_path, xml_path, *extra)
    if not check(r.returncode == 0, f"{name}: export failed: {r.stderr.strip()}"):
        return
    with open(scene_path) as f:
        scene = json.load(f)
    scene_dir = os.path.dirname(os.path.abspath(scene_path))
    root = ET.parse(xml_path).getroot()
    check(root.tag == "cycles", f"{name}: root element {root.tag}")
    film = scene["film"]
    W, H = film["width"], film["height"]

    # Camera.
    cams = root.iter("camera")
    cams = list(cams)
    if check(len(cams) == 1, f"{name}: {len(cams)} cameras"):
        parent = {c: p for p in root.iter() for c in p}
        t = parent[cams[0]]
        check(t.tag == "transform", f"{name}: camera not in a transform")
        m = floats(t.get("matrix"))
        cam = scene["camera"]
        pos, look, up = cam["position"], cam["look_at"], cam.get("up", [0, 1, 0])
        fwd = norm(sub(look, pos))
        right = norm(cross(fwd, up))
        upv = cross(right, fwd)
        want = right + [0] + upv + [0] + fwd + [0] + pos + [1]
        check(close_list(m, want, 1e-5), f"{name}: camera matrix {m} != {want}")
        fov = math.radians(cam.get("fov", 40))
        if W < H:
            fov = 2 * math.atan(math.tan(fov / 2) * W / H)
        check(close(float(cams[0].get("fov")), fov, 1e-6), f"{name}: fov {cams[0].get('fov')} != {fov}")
        check(int(cams[0].get("width")) == W and int(cams[0].get("height")) == H, f"{name}: camera size")

    integ = root.find("integrator")
    depth = scene.get("integrator", {}).get("max_depth", 8)
    check(integ is not None and int(integ.get("max_bounce")) == depth, f"{name}: max_bounce != {depth}")
    check(integ.get("use_adaptive_sampling") == "false", f"{name}: adaptive sampling on")
    check(close(float(root.find("film").get("exposure")), 2.0 ** film.get("exposure", 0)), f"{name}: exposure")

    shaders = {s.get("name"): s for s in root.findall("shader")}
    states = root.findall("state")
    materials = scene.get("materials", {})

    # Objects: one mesh each, in order, under its material.
    obj_states = [s for s in states if (s.get("shader") or "").startswith("materials.")]
    objects = scene.get("objects", [])
    check(len(obj_states) == len(objects), f"{name}: {len(obj_states)} object meshes for {len(objects)} objects")
    curved_materials = set()
    for i, (o, st) in enumerate(zip(objects, obj_states)):
        what = f"{name}: objects[{i}]"
        check(st.get("shader") == "materials." + o["material"], f"{what}: shader {st.get('shader')}")
        check(st.get("interpolation") == "smooth", f"{what}: not smooth")
        meshes = st.findall("mesh")
        if not check(len(meshes) == 1, f"{what}: {len(meshes)} meshes"):
            continue
        me = meshes[0]
        P, N = floats(me.get("P")), floats(me.get("N"))
        verts, nverts = [int(v) for v in me.get("verts").split()], [int(v) for v in me.get("nverts").split()]
        ntri = len(nverts)
        check(set(nverts) == {3} and len(verts) == 3 * ntri, f"{what}: not triangles")
        check(len(P) % 3 == 0 and len(N) == len(P), f"{what}: P/N sizes {len(P)} {len(N)}")
        check(max(verts) < len(P) // 3 and min(verts) >= 0, f"{what}: index out of range")
        check(all(close(math.sqrt(sum(x * x for x in N[3 * k:3 * k + 3])), 1.0, 1e-5) for k in range(len(N) // 3)),
              f"{what}: normals not unit")
        m = materials[o["material"]]
        uv = me.get("UV")
        if m["type"] == "knit":
            check(uv is not None, f"{what}: knit mesh without UV")
        if uv is not None:
            check(len(floats(uv)) == 6 * ntri, f"{what}: {len(floats(uv))} UV numbers for {ntri} triangles")
        if m["type"] == "knit":
            curved = any(not close_list(N[3 * k:3 * k + 3], N[0:3], 1e-4) for k in range(len(N) // 3))
            tangent = me.get("tangent")
            if curved and "--no-curvature" not in extra:
                curved_materials.add(o["material"])
                if check(tangent is not None, f"{what}: curved knit mesh without the curvature attribute"):
                    check_curvature(what, P, N, verts, floats(uv), floats(tangent))
            else:
                check(tangent is None, f"{what}: curvature attribute on a flat mesh or with --no-curvature")

    # Materials.
    used = {o["material"] for o in objects}
    for mname, m in materials.items():
        sh = shaders.get("materials." + mname)
        if mname not in used:
            check(sh is None, f"{name}: unused material {mname} exported")
            continue
        if not check(sh is not None, f"{name}: no shader for material {mname}"):
            continue
        nodes, links = graph(sh)
        out = linked(links, "output", "surface")
        check(out is not None, f"{name}: {mname}: nothing into the surface")
        t = m["type"]
        if t == "diffuse":
            check(close_list(floats(nodes["bsdf"].get("color")), m["albedo"]), f"{name}: {mname}: albedo")
        elif t == "dielectric":
            eta, tint = m.get("eta", 1.5), m.get("tint", [1, 1, 1])
            node = nodes["bsdf"]
            if eta == 1:
                check(node.tag == "transparent_bsdf" and close_list(floats(node.get("color")), tint),
                      f"{name}: {mname}: eta 1")
            else:
                check(node.tag == "principled_bsdf", f"{name}: {mname}: {node.tag}")
                check(close(float(node.get("ior")), eta) and close(float(node.get("roughness")), m.get("roughness", 0))
                      and float(node.get("transmission_weight")) == 1 and node.get("distribution") == "ggx",
                      f"{name}: {mname}: principled settings")
                check(close_list(floats(node.get("base_color")), [c * c for c in tint]), f"{name}: {mname}: tint")
        elif t == "thin":
            check(close_list(floats(nodes["through"].get("color")), m["transmittance"]), f"{name}: {mname}: thin")
            check(close_list(floats(nodes["bsdf"].get("color")), m.get("albedo", [0, 0, 0])), f"{name}: {mname}")
        elif t == "knit":
            check_knit(name, mname, m, sh, nodes, links, scene_dir, out_dir, cli, mname in curved_materials)

    # Lights.
    check_lights(name, scene, root, shaders, states, scene_dir, out_dir)


def check_curvature(what, P, N, verts, uv, tangent):
    """The exported curvature equals the add-on's per-face curvature of the
    exported mesh (knitshade_blender.core.curvature), constant per triangle."""
    try:
        import importlib.util
        import numpy as np
        # (the module alone: the add-on package imports bpy)
        spec = importlib.util.spec_from_file_location(
            "knit_curvature", os.path.join(ROOT, "addon", "knitshade_blender", "core", "curvature.py"))
        curvature = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(curvature)
    except ImportError as e:
        print(f"{what}: curvature values not compared ({e})")
        return
    ntri = len(verts) // 3
    k = np.array(tangent, dtype=np.float64).reshape(ntri, 3, 3)
    check(np.all(k[:, 0] == k[:, 1]) and np.all(k[:, 0] == k[:, 2]) and np.all(k[:, :, 2] == 0),
          f"{what}: curvature not constant per triangle")
    ref = curvature.face_curvature(np.array(P).reshape(-1, 3), np.array(N).reshape(-1, 3), np.array(verts),
                                   np.array(uv).reshape(-1, 2), np.arange(ntri) * 3, np.full(ntri, 3))
    scale = max(1e-9, float(np.abs(ref[:, :2]).max()))
    err = float(np.abs(k[:, 0, :2] - ref[:, :2]).max()) / scale
    check(err < 1e-3, f"{what}: curvature differs from the add-on's by {err:.2e} of its largest")
    print(f"{what}: curvature of {ntri} triangles within {err:.1e} of the add-on's (largest {scale:.4g})")


def check_knit(name, mname, m, sh, nodes, links, scene_dir, out_dir, cli, curved):
    what = f"{name}: {mname}"
    check(sh.get("emission_sampling_method") == "none", f"{what}: the fabric is sampled as a light")
    check(sh.get("use_bump_map_correction") == "false", f"{what}: bump map correction is left on")
    knits = [n for n in nodes.values() if n.tag == "osl_shader"]
    if not check(len(knits) == 1, f"{what}: {len(knits)} script nodes"):
        return
    node = knits[0]
    kn = node.get("name")
    src = node.get("src")
    check(os.path.dirname(src) == "" and src == f"{name}_{mname}.osl", f"{what}: shader file {src}")
    path = os.path.join(out_dir, src)
    if not check(os.path.isfile(path), f"{what}: {path} not written"):
        return
    with open(path) as f:
        text = f.read()
    check("#include" not in text, f"{what}: {src} has an #include")
    rows, cols = pattern_size(m, scene_dir)
    check(f"#define KNIT_PATTERN_ROWS {rows}\n" in text and f"#define KNIT_PATTERN_COLS {cols}\n" in text,
          f"{what}: {src} not of the pattern's {rows} x {cols}")
    if isinstance(m["pattern"], str):
        pat = m["pattern"] if os.path.isabs(m["pattern"]) else os.path.join(scene_dir, m["pattern"])
        r = subprocess.run([cli, "osl", pat], capture_output=True)
        check(r.returncode == 0 and r.stdout.decode() == text, f"{what}: {src} differs from `knitshade osl {pat}`")
    # UV, Curvature and BSDF links.
    uv_from = linked(links, kn, "UV")
    check(uv_from is not None and nodes.get(uv_from[0]) is not None
          and nodes[uv_from[0]].tag in ("texture_coordinate", "uvmap") and uv_from[1] == "uv",
          f"{what}: UV input not linked from a UV output ({uv_from})")
    k_from = linked(links, kn, "Curvature")
    if curved:
        check(k_from is not None and nodes[k_from[0]].tag == "attribute"
              and nodes[k_from[0]].get("attribute") == "tangent" and k_from[1] == "vector",
              f"{what}: Curvature not linked from the tangent attribute")
    else:
        check(k_from is None, f"{what}: Curvature linked on flat meshes")
    check(linked(links, "output", "surface") == (kn, "bsdf"), f"{what}: BSDF not into the surface")
    # Values: every one a parameter of the shader, equal to the scene's.
    params = shader_params(text)
    for key, value in node.attrib.items():
        if key in ("name", "src"):
            continue
        if not check(key in params, f"{what}: {key} is not a parameter of the shader"):
            continue
        kind = params[key]
        if kind == "int":
            check(re.fullmatch(r"-?\d+", value) is not None, f"{what}: {key}={value} not an integer")
        elif kind in ("color", "point", "vector", "normal"):
            check(len(floats(value)) == 3, f"{what}: {key}={value} not 3 numbers")
    want = expected_knit_params(m)
    for key, value in want.items():
        got = node.get(key)
        if not check(got is not None, f"{what}: {key} not set"):
            continue
        if isinstance(value, list):
            check(close_list(floats(got), value, 1e-5), f"{what}: {key}={got}, the scene's {value}")
        else:
            check(close(float(got), float(value), 1e-5), f"{what}: {key}={got}, the scene's {value}")
    for i in range(len(m["yarn_colors"]), 8):
        check(node.get("Yarn%d" % i) is None, f"{what}: Yarn{i} set beyond the palette")


def check_lights(name, scene, root, shaders, states, scene_dir, out_dir):
    lights = scene.get("lights", [])
    by_shader = {s.get("shader"): s for s in states}
    envs = 0
    for i, l in enumerate(lights):
        path = f"lights[{i}]"
        what = f"{name}: {path}"
        t = l["type"]
        if t == "quad":
            sh, st = shaders.get(path), by_shader.get(path)
            if not check(sh is not None and st is not None, f"{what}: no emissive mesh"):
                continue
            nodes, links = graph(sh)
            em = nodes["emission"]
            check(close_list(floats(em.get("color")), l["emission"]) and float(em.get("strength")) == 1,
                  f"{what}: radiance")
            two = l.get("two_sided", False)
            check(sh.get("emission_sampling_method") == ("front_back" if two else "front"), f"{what}: sampling")
            strength = linked(links, "emission", "strength")
            if two:
                check(strength is None, f"{what}: two-sided light with a strength link")
            else:
                check(strength is not None and nodes[strength[0]].get("math_type") == "subtract"
                      and linked(links, strength[0], "value2")[1] == "backfacing", f"{what}: one-sided")
            P = floats(st.find("mesh").get("P"))
            c, eu, ev = l["corner"], l["edge_u"], l["edge_v"]
            want = c + [c[k] + eu[k] for k in range(3)] + [c[k] + eu[k] + ev[k] for k in range(3)] + \
                [c[k] + ev[k] for k in range(3)]
            check(close_list(P, want), f"{what}: corners")
            verts = [int(v) for v in st.find("mesh").get("verts").split()]
            tri = [P[3 * v:3 * v + 3] for v in verts[:3]]
            n = cross(sub(tri[1], tri[0]), sub(tri[2], tri[0]))
            check(sum(a * b for a, b in zip(n, cross(eu, ev))) > 0, f"{what}: winding against edge_u x edge_v")
        elif t in ("point", "directional"):
            st = by_shader.get(path)
            li = st.find("light") if st is not None else None
            if not check(li is not None, f"{what}: no light"):
                continue
            em = graph(shaders[path])[0]["emission"]
            check(floats(em.get("color")) == [1, 1, 1] and float(em.get("strength")) == 1, f"{what}: unit shader")
            tfm = floats(li.get("tfm"))
            if t == "point":
                check(li.get("light_type") == "point" and float(li.get("size")) == 0, f"{what}: type")
                check(close_list(floats(li.get("strength")), [4 * math.pi * x for x in l["intensity"]]),
                      f"{what}: strength")
                check(close_list([tfm[3], tfm[7], tfm[11]], l["position"]), f"{what}: position")
            else:
                check(li.get("light_type") == "distant" and float(li.get("angle")) == 0, f"{what}: type")
                check(close_list(floats(li.get("strength")), l["irradiance"]), f"{what}: strength")
                check(close_list([tfm[2], tfm[6], tfm[10]], norm(l["to_light"])), f"{what}: direction")
        elif t == "environment":
            envs += 1
            bg = root.find("background")
            if not check(bg is not None, f"{what}: no background"):
                continue
            nodes, links = graph(bg)
            b = nodes["bg"]
            check(linked(links, "output", "surface") == ("bg", "background"), f"{what}: background not linked")
            check(close(float(b.get("strength")), l.get("strength", 1.0)), f"{what}: strength")
            if "color" in l:
                check(close_list(floats(b.get("color")), l["color"]), f"{what}: colour")
            else:
                env = nodes["env"]
                check(linked(links, "bg", "color") == ("env", "color"), f"{what}: texture not linked")
                f = os.path.join(out_dir, env.get("filename"))
                want = l["file"] if os.path.isabs(l["file"]) else os.path.join(scene_dir, l["file"])
                check(not os.path.isabs(env.get("filename")) and os.path.samefile(f, want),
                      f"{what}: {env.get('filename')} is not {want} relative to the XML")
                check(env.get("tex_mapping.type") == "vector" and env.get("colorspace") == "__builtin_raw",
                      f"{what}: mapping type or colour space")
                euler = floats(env.get("tex_mapping.rotation"))
                rng = random.Random(7)
                worst = 0.0
                for _ in range(200):
                    d = norm([rng.gauss(0, 1) for _ in range(3)])
                    if abs(d[1]) > 0.999:
                        continue
                    (un, vn), (uc, vc) = native_uv(d, l.get("rotation", 0)), cycles_uv(d, euler)
                    du = abs(un - uc)
                    worst = max(worst, min(du, 1 - du), abs(vn - vc))
                check(worst < 1e-5, f"{what}: Cycles' lookup differs from the native one by {worst:.2e}")
            bl = by_shader.get("default_background")
            check(bl is not None and bl.find("light").get("light_type") == "background", f"{what}: no background light")
    if envs == 0:
        check(root.find("background") is None, f"{name}: background without an environment")


# ---- the synthetic scene -------------------------------------------------------

def synthetic_scene(out_dir):
    meshes = os.path.join(ROOT, "examples", "scenes", "meshes")
    scene = {
        "version": 1,
        "film": {"width": 90, "height": 160, "spp": 4, "seed": 3, "exposure": -1.5},
        "camera": {"position": [0.3, 1.1, 2.4], "look_at": [0.1, 0.3, 0], "up": [0.1, 1, 0], "fov": 33},
        "integrator": {"max_depth": 5, "rr_depth": 2},
        "lights": [
            {"type": "environment", "file": os.path.join(ROOT, "examples", "scenes", "sky.hdr"), "strength": 0.7,
             "rotation": 63},
            {"type": "point", "position": [0.5, 2, 1], "intensity": [3, 2.5, 2]},
            {"type": "quad", "corner": [-1, 2, -1], "edge_u": [2, 0, 0.3], "edge_v": [0, 0.2, 2],
             "emission": [4, 4, 3.5], "two_sided": True},
            {"type": "quad", "corner": [1, 0.5, -1], "edge_u": [0, 0, 1], "edge_v": [0, 1, 0],
             "emission": [2, 1, 1]},
            {"type": "directional", "to_light": [0.3, 1, 0.2], "irradiance": [1.5, 1.4, 1.3]},
        ],
        "materials": {
            "wool": {"type": "knit", "pattern": ["KKPPF", "PPKKB", "KPKPK"], "colors": [[0, 1, 1, 0, 1],
                                                                                      [1, 0, 0, 1, 0],
                                                                                      [0, 0, 1, 1, 0]],
                     "uv_scale": 30, "a": 1.4, "h": 3.6, "d": -0.9, "r": 0.55,
                     "yarn_colors": [[0.7, 0.2, 0.1], [0.2, 0.3, 0.6]],
                     "transmit_colors": [[0.35, 0.16, 0.03], [0.1, 0.24, 0.18]],
                     "bsdf": {"roughness_x": 0.2, "roughness_y": 0.5, "eta": 1.6, "body_energy": 0.8,
                              "body_reflect": 0.65, "optical_depth": 2.5},
                     "ply": {"enabled": True, "ply_count": 4, "ply_twist": 30, "fiber_twist": -15, "fiber_count": 25},
                     "mode": "multi_scale", "footprint_points": 6, "capm": False, "capm_options": {"max_steps": 48}},
            "glass": {"type": "dielectric", "eta": 1.45, "roughness": 0.3, "tint": [0.9, 0.8, 0.7]},
            "air": {"type": "dielectric", "eta": 1.0, "tint": [0.95, 0.95, 0.9]},
            "veil": {"type": "thin", "transmittance": [0.5, 0.5, 0.4], "albedo": [0.2, 0.2, 0.3]},
            "floor": {"type": "diffuse", "albedo": [0.4, 0.4, 0.35]},
            "unused": {"type": "diffuse", "albedo": [1, 0, 0]},
        },
        "objects": [
            {"name": "cylinder", "mesh": os.path.join(meshes, "half_cylinder.obj"), "material": "wool",
             "transform": {"translate": [0, 0.3, 0], "rotate": [10, 20, 30], "scale": [0.3, 0.4, 0.3]}},
            {"name": "ball", "mesh": os.path.join(meshes, "sphere.obj"), "material": "glass",
             "transform": {"matrix": [0.2, 0, 0, 0.5, 0, 0.2, 0, 0.2, 0, 0, 0.2, 0, 0, 0, 0, 1]}},
            {"name": "pane", "mesh": os.path.join(meshes, "quad.obj"), "material": "air"},
            {"name": "curtain", "mesh": os.path.join(meshes, "quad.obj"), "material": "veil",
             "transform": {"translate": [0, 0, -1]}},
            {"name": "floor", "mesh": os.path.join(meshes, "ground.obj"), "material": "floor"},
        ],
    }
    path = os.path.join(out_dir, "synthetic.json")
    with open(path, "w") as f:
        json.dump(scene, f, indent=1)
    return path


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--synthetic", action="store_true")
    ap.add_argument("--no-curvature", action="store_true")
    ap.add_argument("scenes", nargs="*")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    scenes = list(a.scenes)
    if a.synthetic:
        scenes.append(synthetic_scene(a.out))
    extra = ("--no-curvature",) if a.no_curvature else ()
    for s in scenes:
        check_scene(a.cli, s, a.out, *extra)
        print(f"{os.path.basename(s)}: checked")
    if FAILURES:
        print(f"{len(FAILURES)} failures")
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())

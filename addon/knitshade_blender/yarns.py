"""Generate Yarn Geometry: a Knit Fabric material's yarns as a Blender
curves object laid on the mesh (docs/blender-yarns.md).

For Blenders where the knit shader cannot render (no OSL: Debian's 3.4,
EEVEE, GPUs other than OptiX) and as the look-development reference beside
it: the native library's explicit yarns (the ground truth every shortcut of
the model is tested against) laid on the mesh through its UVs, in the units
and conventions the shader uses (core/yarn_layout.py).

What it makes, for a mesh object and one of its Knit Fabric materials:

- a Curves object "<object> Yarns" (the hair-curves type of Blender 3.3 and
  later: Cycles renders it as round tubes on every device, EEVEE as
  strands), a child of the mesh object with its points in the mesh's local
  space, so it follows the object's transform; per point the builtin
  `radius` (r / S) and a colour attribute `knit_yarn_colour` (the palette
  colour of the point's colour index);
- a material "<material> Yarn" reading that attribute: Diffuse, Translucent,
  Glossy and Transparent closures weighted by the albedos of the yarn BSDF's
  four lobes (yarn_material());
- Cycles' curve shape set to 3D curves (round tubes; ribbons would look
  flat) and EEVEE's hair shape to cylinders (strips before 4.2).

Yarns are generated for the faces that use the material, from the mesh as
it is evaluated now (modifiers applied). They are static: a mesh that
deforms afterwards (armature, cloth, shape keys) keeps yarns made for the
frame they were generated on; the operator warns. Generating again replaces
the object's data in place.

Blender 3.4 has no Python call that sizes a Curves datablock: there the
curves are made as a mesh of edge chains turned into curves by a Mesh to
Curve node and converted (object.convert); where Curves.add_curves exists
(4.x and later) it is used directly. Both give the same data.
"""
import math
import time

import bpy
import numpy as np
from bpy.props import BoolProperty, IntProperty, StringProperty

from . import nodes
from .core import yarn_layout as L
from .native import yarns as nyarns

YARN_KEY = "knitshade_yarns"  # on the yarn object: {"source", "material", "samples", ...}
MATERIAL_KEY = "knitshade_yarn_material"  # on the yarn material: the Knit Fabric material's name
COLOUR_ATTR = "knit_yarn_colour"
COLOUR_TYPE = "FLOAT_COLOR"
DEFAULT_SAMPLES = 32  # points per stitch: Cycles draws Catmull-Rom splines through them, within 1% of r of the curve
CONFIRM_POINTS = 4_000_000  # above this many curve points the operator asks first
# Modifiers that move a mesh's vertices over time.
DEFORMING = {"ARMATURE", "CLOTH", "SOFT_BODY", "MESH_DEFORM", "SURFACE_DEFORM", "LATTICE", "HOOK", "WAVE",
             "CAST", "CURVE", "DISPLACE", "SIMPLE_DEFORM", "SMOOTH", "CORRECTIVE_SMOOTH", "LAPLACIANSMOOTH",
             "LAPLACIANDEFORM", "MESH_CACHE", "MESH_SEQUENCE_CACHE", "OCEAN", "DYNAMIC_PAINT", "NODES",
             "SHRINKWRAP", "WARP", "EXPLODE", "PARTICLE_INSTANCE", "FLUID"}


class YarnError(ValueError):
    """What the artist must be told (names the object and the value)."""


# ---- finding the material ------------------------------------------------

def knit_materials(obj):
    """[(slot index, material)] of the object's slots holding a Knit Fabric."""
    out = []
    for i, slot in enumerate(getattr(obj, "material_slots", ())):
        mat = slot.material
        if mat is not None and nodes.knit_node(mat) is not None:
            out.append((i, mat))
    return out


def pick_material(obj, name=""):
    """The Knit Fabric material to generate for: the one named, else the
    active one if it is a Knit Fabric, else the first. YarnError naming the
    object otherwise."""
    found = knit_materials(obj)
    if name:
        for _i, m in found:
            if m.name == name:
                return m
        raise YarnError("%s has no Knit Fabric material '%s' (it has: %s)"
                        % (obj.name, name, ", ".join(m.name for _i, m in found) or "none"))
    if not found:
        raise YarnError("%s has no Knit Fabric material: add one first (Add Knit Fabric)" % obj.name)
    active = obj.active_material
    for _i, m in found:
        if m == active:
            return m
    return found[0][1]


def material_settings(mat):
    """{pattern, a, h, d, r, uv_scale, palette [(r, g, b)] * 8, and the
    yarn's appearance} of a Knit Fabric material."""
    node = nodes.knit_node(mat)
    if node is None:
        raise YarnError("material '%s' has no Knit Fabric node" % mat.name)
    get = lambda n: nodes.get_value(node, n)  # noqa: E731
    out = {"pattern": nodes.get_pattern(node.node_tree)}
    for key, name in (("a", "A"), ("h", "H"), ("d", "D"), ("r", "R"), ("uv_scale", "UVScale"),
                      ("roughness", "Roughness"), ("roughness_across", "RoughnessAcross"), ("ior", "IOR"),
                      ("body_energy", "BodyEnergy"), ("body_reflect", "BodyReflect"),
                      ("optical_depth", "OpticalDepth"), ("transmit_tint", "TransmitTint"),
                      ("ply_detail", "PlyDetail"), ("ply_count", "PlyCount"), ("ply_twist", "PlyTwist"),
                      ("fiber_count", "FiberCount"), ("fiber_twist", "FiberTwist")):
        try:
            out[key] = get(name)
        except KeyError:
            pass
    out["palette"] = [tuple(get("Yarn%d" % i)) for i in range(8)]
    return out


# ---- the mesh ------------------------------------------------------------

def _corner_normals(mesh):
    """Shading normals per corner (loop), as Cycles shades: smooth faces
    interpolate, flat faces take the face's, custom normals kept."""
    n = np.empty(3 * len(mesh.loops), dtype=np.float32)
    if hasattr(mesh, "corner_normals"):  # 4.1 and later
        mesh.corner_normals.foreach_get("vector", n)
    else:  # 3.x .. 4.0
        mesh.calc_normals_split()
        mesh.loops.foreach_get("normal", n)
    return n.reshape(-1, 3)


def _active_uv(mesh):
    for layer in mesh.uv_layers:
        if layer.active_render:
            return layer
    return mesh.uv_layers.active


def deforming(obj):
    """Names of what deforms the object's mesh over time (modifiers, shape
    keys, a parent armature)."""
    why = [m.name for m in obj.modifiers if m.type in DEFORMING and m.show_render]
    keys = getattr(obj.data, "shape_keys", None)
    if keys is not None and len(keys.key_blocks) > 1:
        why.append("shape keys")
    if obj.parent is not None and obj.parent_type in {"ARMATURE", "LATTICE", "VERTEX", "VERTEX_3"}:
        why.append("parent " + obj.parent.name)
    return why


def gather_surface(obj, mat, depsgraph, uv_scale):
    """The faces of `obj` that use `mat`, evaluated, in world space, as a
    core Surface; and the object's matrix (4x4 numpy). YarnError for a
    mesh without UVs or faces."""
    if obj.type != "MESH":
        raise YarnError("%s is a %s, not a mesh: yarns are laid on a mesh's UVs" % (obj.name, obj.type.lower()))
    if not obj.data.uv_layers:
        raise YarnError("%s has no UV map: unwrap it first (the yarns follow the UVs)" % obj.name)
    slots = [i for i, s in enumerate(obj.material_slots) if s.material == mat]
    ev = obj.evaluated_get(depsgraph)
    mesh = ev.to_mesh()
    try:
        layer = _active_uv(mesh)
        if layer is None:
            raise YarnError("%s has no UV map after its modifiers: unwrap it first" % obj.name)
        mesh.calc_loop_triangles()
        lt = mesh.loop_triangles
        t = len(lt)
        loops = np.empty(3 * t, dtype=np.int32)
        verts = np.empty(3 * t, dtype=np.int32)
        midx = np.empty(t, dtype=np.int32)
        lt.foreach_get("loops", loops)
        lt.foreach_get("vertices", verts)
        lt.foreach_get("material_index", midx)
        co = np.empty(3 * len(mesh.vertices), dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
        uv = np.empty(2 * len(mesh.loops), dtype=np.float32)
        layer.data.foreach_get("uv", uv)
        nor = _corner_normals(mesh)
    finally:
        ev.to_mesh_clear()
    keep = np.isin(midx, slots)
    loops = loops.reshape(-1, 3)[keep]
    verts = verts.reshape(-1, 3)[keep]
    if len(loops) == 0:
        raise YarnError("%s has no faces with the material '%s'" % (obj.name, mat.name))
    M = np.array([list(r) for r in obj.matrix_world], dtype=np.float64)
    M3, tr = M[:3, :3], M[:3, 3]
    co = co.reshape(-1, 3).astype(np.float64) @ M3.T + tr
    try:
        nM = np.linalg.inv(M3)  # normals: the inverse transpose (rows: n @ inv(M3))
    except np.linalg.LinAlgError:
        raise YarnError("%s has a flat (singular) transform: scale it in all three axes" % obj.name) from None
    nw = nor.astype(np.float64) @ nM
    nw /= np.maximum(np.linalg.norm(nw, axis=1), 1e-300)[:, None]
    uv = uv.reshape(-1, 2).astype(np.float64)
    surf = L.Surface(co[verts], nw[loops], uv[loops], verts, uv_scale)
    return surf, M


# ---- the curves ----------------------------------------------------------

def _new_group_socket(tree, in_out, socket_type, name):
    if hasattr(tree, "interface"):  # 4.0 and later
        return tree.interface.new_socket(name=name, in_out=in_out, socket_type=socket_type)
    return (tree.inputs if in_out == "INPUT" else tree.outputs).new(socket_type, name)


def _curves_by_conversion(name, sizes, pos, radius, colour, scene):
    """Blender 3.x: the curves as edge chains of a mesh, made curves by a
    Mesh to Curve node and converted; returns the Curves datablock."""
    n = len(pos)
    me = bpy.data.meshes.new(name + " (building)")
    me.vertices.add(n)
    me.vertices.foreach_set("co", pos.ravel())
    starts = np.cumsum(sizes) - sizes
    idx = np.arange(n, dtype=np.int64)
    last = np.zeros(n, dtype=bool)
    last[np.cumsum(sizes) - 1] = True
    a = idx[~last]
    edges = np.stack([a, a + 1], axis=1).astype(np.int32)
    me.edges.add(len(edges))
    me.edges.foreach_set("vertices", edges.ravel())
    rad = me.attributes.new("knit_radius", "FLOAT", "POINT")
    rad.data.foreach_set("value", radius)
    col = me.attributes.new(COLOUR_ATTR, COLOUR_TYPE, "POINT")
    col.data.foreach_set("color", colour.ravel())
    me.update()
    del starts
    tmp = bpy.data.objects.new(name + " (building)", me)
    scene.collection.objects.link(tmp)
    group = bpy.data.node_groups.new(name + " (building)", "GeometryNodeTree")
    _new_group_socket(group, "INPUT", "NodeSocketGeometry", "Geometry")
    _new_group_socket(group, "OUTPUT", "NodeSocketGeometry", "Geometry")
    gin, gout = group.nodes.new("NodeGroupInput"), group.nodes.new("NodeGroupOutput")
    m2c = group.nodes.new("GeometryNodeMeshToCurve")
    named = group.nodes.new("GeometryNodeInputNamedAttribute")
    named.data_type = "FLOAT"
    named.inputs["Name"].default_value = "knit_radius"
    setr = group.nodes.new("GeometryNodeSetCurveRadius")
    group.links.new(gin.outputs[0], m2c.inputs["Mesh"])
    group.links.new(m2c.outputs[0], setr.inputs["Curve"])
    # (the node has an output per data type; the float one is the one enabled)
    out_float = [o for o in named.outputs if o.name == "Attribute" and o.enabled and o.type == "VALUE"][0]
    group.links.new(out_float, setr.inputs["Radius"])
    group.links.new(setr.outputs[0], gout.inputs[0])
    mod = tmp.modifiers.new("to curves", "NODES")
    mod.node_group = group
    view_layer = bpy.context.view_layer
    if view_layer is None or view_layer not in scene.view_layers.values():
        view_layer = scene.view_layers[0]
    active = view_layer.objects.active
    selected = [o for o in view_layer.objects if o.select_get(view_layer=view_layer)]
    try:
        for o in selected:
            o.select_set(False, view_layer=view_layer)
        view_layer.objects.active = tmp
        tmp.select_set(True, view_layer=view_layer)
        override = dict(scene=scene, view_layer=view_layer)
        window = bpy.context.window or (bpy.context.window_manager.windows[0]
                                        if bpy.context.window_manager.windows else None)
        if window is not None:
            override["window"] = window
        with bpy.context.temp_override(**override):
            result = bpy.ops.object.convert(target="CURVES", keep_original=False)
        if result != {"FINISHED"} or tmp.type != "CURVES":
            raise YarnError("%s: converting the yarns to curves failed (%s)" % (name, result))
        cv = tmp.data
        for attr_name in ("knit_radius", ".select_vert", ".select_edge"):
            attr = cv.attributes.get(attr_name)
            if attr is not None:
                cv.attributes.remove(attr)
        cv.name = name
        return cv
    finally:
        bpy.data.objects.remove(tmp)
        bpy.data.node_groups.remove(group)
        for o in selected:
            try:
                o.select_set(True, view_layer=view_layer)
            except (ReferenceError, RuntimeError):
                pass
        try:
            view_layer.objects.active = active
        except (ReferenceError, RuntimeError):
            pass
        if me.users == 0:
            bpy.data.meshes.remove(me)


def _curves_direct(name, sizes, pos, radius, colour):
    cv = bpy.data.hair_curves.new(name)
    cv.add_curves([int(s) for s in sizes])
    cv.position_data.foreach_set("vector", pos.ravel())
    rad = cv.attributes.get("radius") or cv.attributes.new("radius", "FLOAT", "POINT")
    rad.data.foreach_set("value", radius)
    col = cv.attributes.new(COLOUR_ATTR, COLOUR_TYPE, "POINT")
    col.data.foreach_set("color", colour.ravel())
    return cv


def make_curves(name, sizes, pos, radius, colour, scene):
    """A Curves datablock of poly curves: `sizes` points each, positions
    (P, 3), radius (P,), linear RGBA colour (P, 4)."""
    pos = np.ascontiguousarray(pos, dtype=np.float32)
    radius = np.ascontiguousarray(radius, dtype=np.float32)
    colour = np.ascontiguousarray(colour, dtype=np.float32)
    probe = bpy.data.hair_curves.new(name)
    direct = hasattr(probe, "add_curves")
    bpy.data.hair_curves.remove(probe)
    if direct:
        cv = _curves_direct(name, sizes, pos, radius, colour)
    else:
        cv = _curves_by_conversion(name, sizes, pos, radius, colour, scene)
    # Poly curves: the viewport and EEVEE draw the points as they are (a
    # Catmull-Rom type would be drawn subdivided, 12 times the points);
    # Cycles smooths 3D curves through the points either way.
    # (Mesh to Curve makes poly curves already; CURVE_TYPE_POLY is 1, and a
    # 2 there is Bezier without handles, which crashes Blender 3.4 on load.)
    if hasattr(cv, "set_types"):
        cv.set_types(type="POLY")
    return cv


# ---- the yarn material ---------------------------------------------------

def _multiply(nt, colour_socket, factor_rgb, location):
    """A Mix (multiply) node: colour_socket x factor_rgb; returns its output."""
    mix = nt.nodes.new("ShaderNodeMix")
    mix.data_type = "RGBA"
    mix.blend_type = "MULTIPLY"
    mix.location = location
    mix.inputs[0].default_value = 1.0
    a_in = [s for s in mix.inputs if s.name == "A" and s.type == "RGBA"][0]
    b_in = [s for s in mix.inputs if s.name == "B" and s.type == "RGBA"][0]
    nt.links.new(colour_socket, a_in)
    b_in.default_value = tuple(factor_rgb)[:3] + (1.0,)
    return [s for s in mix.outputs if s.name == "Result" and s.type == "RGBA"][0]


def yarn_weights(settings):
    """The yarn material's closure weights for a Knit Fabric's settings
    (native.yarns.yarn_weights: the exact lobes' albedos)."""
    g = settings.get
    return nyarns.yarn_weights(
        roughness=g("roughness", 0.15), roughness_across=g("roughness_across", 0.45), ior=g("ior", 1.55),
        body_energy=g("body_energy", 0.7), body_reflect=g("body_reflect", 0.6),
        optical_depth=g("optical_depth", 1.0), ply_detail=bool(g("ply_detail", True)),
        ply_count=g("ply_count", 3), ply_twist=g("ply_twist", 28.65), fiber_count=g("fiber_count", 40),
        fiber_twist=g("fiber_twist", -20.05), r=g("r", 0.65))


def yarn_material(knit_mat, settings, weights=None):
    """The curves' material for a Knit Fabric material: made once, its
    nodes made again at every generation. The yarn colour comes from the
    curves' colour attribute. Each lobe of the yarn BSDF becomes the Blender
    closure that stands for it, weighted by the lobe's albedo for a white
    yarn (averaged over view directions, with the ply detail's mean
    shadowing): Diffuse (body reflection, x colour), Translucent (body
    transmission, x colour x transmission tint), Glossy GGX (specular
    reflection) and Transparent (light straight through the yarn), added.
    The same split the OSL shader makes per view direction
    (native/kernel/bsdf_cycles.h), fixed per material, with Blender's own
    nodes, so it renders in Cycles and EEVEE alike."""
    weights = weights or yarn_weights(settings)
    mat = None
    for m in bpy.data.materials:
        if m.get(MATERIAL_KEY) == knit_mat.name:
            mat = m
            break
    if mat is None:
        mat = bpy.data.materials.new(knit_mat.name + " Yarn")
        mat[MATERIAL_KEY] = knit_mat.name
    if mat.node_tree is None or not getattr(mat, "use_nodes", True):
        mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    N = nt.nodes.new
    attr = N("ShaderNodeAttribute")
    attr.attribute_type = "GEOMETRY"
    attr.attribute_name = COLOUR_ATTR
    attr.location = (-900, 0)
    col = attr.outputs["Color"]
    wr, wt = weights["body_r"], weights["body_t"]
    tint = tuple(settings.get("transmit_tint", (1.0, 1.0, 1.0)))[:3]
    diffuse = N("ShaderNodeBsdfDiffuse")
    diffuse.location = (-300, 300)
    nt.links.new(_multiply(nt, col, (wr, wr, wr), (-600, 300)), diffuse.inputs["Color"])
    translucent = N("ShaderNodeBsdfTranslucent")
    translucent.location = (-300, 100)
    nt.links.new(_multiply(nt, col, tuple(wt * c for c in tint), (-600, 100)), translucent.inputs["Color"])
    glossy = N("ShaderNodeBsdfGlossy")
    glossy.location = (-300, -100)
    if hasattr(glossy, "distribution"):
        glossy.distribution = "GGX"
    ws = weights["spec"]
    glossy.inputs["Color"].default_value = (ws, ws, ws, 1.0)
    # isotropic, at the lobe's geometric-mean alpha (Blender's roughness is sqrt(alpha))
    alpha = math.sqrt(max(1e-6, float(settings.get("roughness", 0.15))
                          * float(settings.get("roughness_across", 0.45))))
    glossy.inputs["Roughness"].default_value = math.sqrt(alpha)
    transparent = N("ShaderNodeBsdfTransparent")
    transparent.location = (-300, -300)
    wd = weights["through"]
    transparent.inputs["Color"].default_value = (wd, wd, wd, 1.0)
    add1 = N("ShaderNodeAddShader")
    add1.location = (-50, 200)
    add2 = N("ShaderNodeAddShader")
    add2.location = (-50, -200)
    add3 = N("ShaderNodeAddShader")
    add3.location = (150, 0)
    out = N("ShaderNodeOutputMaterial")
    out.location = (350, 0)
    L_ = nt.links
    L_.new(diffuse.outputs[0], add1.inputs[0])
    L_.new(translucent.outputs[0], add1.inputs[1])
    L_.new(glossy.outputs[0], add2.inputs[0])
    L_.new(transparent.outputs[0], add2.inputs[1])
    L_.new(add1.outputs[0], add3.inputs[0])
    L_.new(add2.outputs[0], add3.inputs[1])
    L_.new(add3.outputs[0], out.inputs["Surface"])
    mat["knitshade_yarn_weights"] = {k: float(v) for k, v in weights.items()}
    pal = settings.get("palette") or [(0.5, 0.36, 0.25)]
    mat.diffuse_color = tuple(pal[0])[:3] + (1.0,)
    if hasattr(mat, "surface_render_method"):  # EEVEE 4.2 and later
        mat.surface_render_method = "DITHERED"
    elif hasattr(mat, "blend_method"):  # EEVEE before 4.2: the transparent part needs it
        mat.blend_method = "HASHED"
        if hasattr(mat, "shadow_method"):
            mat.shadow_method = "HASHED"
    return mat


def setup_scene_for_curves(scene):
    """Round tubes in Cycles (3D curves) and in EEVEE (cylinders where it
    has them, strips before); returns what was changed."""
    changed = []
    cc = getattr(scene, "cycles_curves", None)
    if cc is not None and cc.shape != "THICK":
        cc.shape = "THICK"
        changed.append("Cycles curve shape set to 3D Curves")
    r = scene.render
    if hasattr(r, "hair_type"):
        items = r.bl_rna.properties["hair_type"].enum_items.keys()
        want = "CYLINDER" if "CYLINDER" in items else "STRIP"
        if r.hair_type != want:
            r.hair_type = want
            changed.append("EEVEE hair shape set to %s" % want.title())
    return changed


# ---- the job -------------------------------------------------------------

def _find_yarn_object(obj_name, mat_name):
    for o in bpy.data.objects:
        info = o.get(YARN_KEY)
        if info is not None and info.get("source") == obj_name and info.get("material") == mat_name:
            return o
    return None


class YarnJob:
    """One generation: prepare() gathers and checks (fast), step() lays a
    part of the yarns (progress and cancelling between steps), finish()
    makes the Blender data. The data stays untouched until finish()."""

    def __init__(self, context, obj, material="", samples=DEFAULT_SAMPLES, hide_source=True):
        self.scene = context.scene
        self.obj_name = obj.name
        self.samples = int(samples)
        self.hide_source = hide_source
        self.warnings = []
        self.t0 = time.perf_counter()
        if not nyarns.available():
            raise YarnError("%s: %s" % (obj.name, nyarns.why_not()))
        mat = pick_material(obj, material)
        self.mat_name = mat.name
        self.settings = s = material_settings(mat)
        depsgraph = context.evaluated_depsgraph_get()
        self.surface, self.matrix = gather_surface(obj, mat, depsgraph, s["uv_scale"])
        surf = self.surface
        if surf.grid.count == 0:
            raise YarnError("%s: all %d triangles with '%s' are degenerate in UV or in space (no UV area)"
                            % (obj.name, surf.triangles, mat.name))
        if surf.degenerate:
            self.warnings.append("%s: %d of %d triangles are degenerate (no UV or no surface area; the first "
                                 "is triangle %d) and get no yarns" % (obj.name, surf.degenerate, surf.triangles,
                                                                      surf.first_degenerate))
        w = surf.scale_warning(obj.name)
        if w:
            self.warnings.append(w)
        moving = deforming(obj)
        if moving:
            self.warnings.append("%s deforms (%s): the yarns are made for frame %d and stay static; generate "
                                 "again after a change, or render with the knit shader"
                                 % (obj.name, ", ".join(moving), self.scene.frame_current))
        pat = s["pattern"]
        try:
            px, py, top = nyarns.period(pat, s["a"], s["h"], s["d"], s["r"], mat.name)
        except ValueError as e:
            raise YarnError("%s: the stitch a = %g, h = %g, d = %g, r = %g is refused: %s"
                            % (mat.name, s["a"], s["h"], s["d"], s["r"], e)) from None
        self.period, self.shell_top = (px, py), top
        self.estimate = L.estimate(surf, (px, py), pat.rows, pat.cols, self.samples)
        e = self.estimate
        if e["tiles_u"] > 4096 or e["tiles_v"] > 4096 or e["points_total"] > 400_000_000:
            raise YarnError("%s: the yarns would need %d x %d pattern repeats (%d curve points): lower the UV "
                            "scale of '%s' (%g) or the points per stitch (%d)"
                            % (obj.name, e["tiles_u"], e["tiles_v"], e["points_total"], mat.name,
                               s["uv_scale"], self.samples))
        self.layout = None

    def describe_estimate(self):
        e = self.estimate
        return ("about %s yarn curve points on %d knitted rows: %s of curves, about %s to render"
                % (format(e["points"], ","), e["rows"], L.human_bytes(e["blender_bytes"]),
                   L.human_bytes(e["cycles_bytes"])))

    def start(self):
        s, e = self.settings, self.estimate
        b = nyarns.band(s["pattern"], s["a"], s["h"], s["d"], s["r"], e["tiles_u"], self.samples, self.mat_name)
        self.layout = L.Layout(self.surface, b["curves"], b["colors"], b["period"], b["shell_top"], b["radius"],
                               e["tx0"], e["ty0"], e["tiles_v"])

    def step(self):
        if self.layout is None:
            self.start()
        return self.layout.step()

    @property
    def done(self):
        return self.layout is not None and self.layout.done

    def run(self):
        while not self.done:
            self.step()

    def finish(self):
        """Make (or replace) the yarn object. Returns it."""
        obj = bpy.data.objects.get(self.obj_name)
        if obj is None:
            raise YarnError("%s was removed while its yarns were being generated" % self.obj_name)
        knit_mat = bpy.data.materials.get(self.mat_name)
        res = self.layout.result()
        sizes = res["sizes"]
        if len(sizes) == 0:
            raise YarnError("%s: no yarn lands on the mesh (the UVs with '%s' cover %.3g UV units; check the UV "
                            "scale %g)" % (obj.name, self.mat_name, self.surface.uv_area, self.settings["uv_scale"]))
        M = self.matrix
        M3, tr = M[:3, :3], M[:3, 3]
        inv = np.linalg.inv(M3)
        local = (res["positions"] - tr) @ inv.T
        scale = abs(np.linalg.det(M3)) ** (1.0 / 3.0)
        radius = res["radius"] / scale
        pal = np.asarray(self.settings["palette"], dtype=np.float32)
        ci = np.clip(res["colour"], 0, len(pal) - 1)
        colour = np.ones((len(ci), 4), dtype=np.float32)
        colour[:, :3] = pal[ci]
        name = "%s Yarns" % obj.name
        cv = make_curves(name, sizes, local, radius, colour, self.scene)
        ymat = yarn_material(knit_mat, self.settings)
        cv.materials.append(ymat)
        yo = _find_yarn_object(obj.name, self.mat_name)
        if yo is not None and yo.type == "CURVES":
            old = yo.data
            yo.data = cv
            if old.users == 0:
                bpy.data.hair_curves.remove(old)
        else:
            yo = bpy.data.objects.new(name, cv)
            cols = list(obj.users_collection) or [self.scene.collection]
            cols[0].objects.link(yo)
        yo.parent = obj
        yo.matrix_parent_inverse.identity()
        yo.matrix_basis.identity()
        total = int(sizes.sum())
        self.result_stats = {
            "curves": int(len(sizes)), "points": total,
            "length": L.polyline_length(res["positions"], sizes),
            "bytes": total * L.BLENDER_BYTES_PER_POINT + len(sizes) * L.BLENDER_BYTES_PER_CURVE,
            "seconds": time.perf_counter() - self.t0,
        }
        yo[YARN_KEY] = {"source": obj.name, "material": self.mat_name, "samples": self.samples,
                        "curves": int(len(sizes)), "points": total, "uv_scale": float(self.settings["uv_scale"]),
                        "frame": int(self.scene.frame_current)}
        if self.hide_source:
            obj.hide_render = True
        self.changed = setup_scene_for_curves(self.scene)
        return yo

    def summary(self):
        r = self.result_stats
        return ("%s: %s yarn curves, %s points (%s) in %.1f s" %
                (self.obj_name, format(r["curves"], ","), format(r["points"], ","), L.human_bytes(r["bytes"]),
                 r["seconds"]))


def generate(obj, material="", samples=DEFAULT_SAMPLES, hide_source=True, context=None, report=None):
    """Generate the yarns of `obj` (a mesh object with a Knit Fabric
    material; `material`: which one, by name) at once and return the yarn
    object. `report(type_set, text)` gets the warnings. YarnError (a
    ValueError) names the object and the value when it cannot be done."""
    context = context or bpy.context
    job = YarnJob(context, obj, material, samples, hide_source)
    job.run()
    yo = job.finish()
    if report is not None:
        for w in job.warnings:
            report({"WARNING"}, w)
    return yo


# ---- the operator --------------------------------------------------------

def needs_confirmation(job):
    """Whether the operator asks before it starts (many curve points)."""
    return job.estimate["points"] > CONFIRM_POINTS


class KNITSHADE_OT_generate_yarns(bpy.types.Operator):
    """Lay the Knit Fabric's yarns on the mesh as curves: they render in Cycles on every device and in EEVEE"""

    bl_idname = "knitshade.generate_yarns"
    bl_label = "Generate Yarn Geometry"
    bl_options = {"REGISTER", "UNDO"}

    object: StringProperty(name="Object", description="The mesh object (default: the active object)",
                           options={"SKIP_SAVE"})
    material: StringProperty(name="Material", description="Its Knit Fabric material (default: the active one, "
                             "else the first)", options={"SKIP_SAVE"})
    samples: IntProperty(name="Points per Stitch", description="Curve points per stitch along each yarn "
                         "(Cycles draws smooth splines through them)", default=DEFAULT_SAMPLES, min=4, max=256)
    hide_source: BoolProperty(name="Hide Mesh in Renders", description="Render the yarns instead of the mesh",
                              default=True)
    interactive: BoolProperty(options={"HIDDEN", "SKIP_SAVE"}, default=False)

    @classmethod
    def poll(cls, context):
        if not nyarns.available():
            cls.poll_message_set(nyarns.why_not())
            return False
        return True

    def _target(self, context):
        if self.object:
            obj = bpy.data.objects.get(self.object)
            if obj is None:
                raise YarnError("there is no object '%s'" % self.object)
            return obj
        obj = context.active_object if hasattr(context, "active_object") else None
        obj = obj or getattr(context, "object", None)
        if obj is None:
            raise YarnError("no active object: select a mesh with a Knit Fabric material, or name it with object=")
        return obj

    def _job(self, context):
        obj = self._target(context)
        return YarnJob(context, obj, self.material, self.samples, self.hide_source)

    def invoke(self, context, _event):
        try:
            job = self._job(context)
        except (YarnError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.interactive = True
        self._estimate_text = job.describe_estimate()
        if needs_confirmation(job):
            return context.window_manager.invoke_props_dialog(self, width=460)
        return self.execute(context)

    def draw(self, context):
        layout = self.layout
        text = getattr(self, "_estimate_text", "")
        if not text:
            try:
                text = self._job(context).describe_estimate()
            except (YarnError, ValueError) as e:
                text = str(e)
        layout.label(text="This makes " + text[:80])
        if len(text) > 80:
            layout.label(text=text[80:])
        layout.label(text="Continue? (Esc stops it while it runs)")
        layout.prop(self, "samples")
        layout.prop(self, "hide_source")

    def execute(self, context):
        try:
            self._job_ = job = self._job(context)
        except (YarnError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        for w in job.warnings:
            self.report({"WARNING"}, w)
        wm = context.window_manager
        if self.interactive and not bpy.app.background and context.window is not None \
                and not self.options.is_repeat:
            self._timer = wm.event_timer_add(0.01, window=context.window)
            wm.progress_begin(0, 1000)
            wm.modal_handler_add(self)
            self._area = context.area
            return {"RUNNING_MODAL"}
        try:
            job.run()
            job.finish()
        except (YarnError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self._done(job)
        return {"FINISHED"}

    def _done(self, job):
        self.report({"INFO"}, job.summary())
        for c in getattr(job, "changed", ()):
            self.report({"INFO"}, "%s: %s" % (job.scene.name, c))

    def _end(self, context):
        wm = context.window_manager
        if getattr(self, "_timer", None) is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        if self._area is not None:
            try:
                self._area.header_text_set(None)
            except (ReferenceError, AttributeError):
                pass

    def modal(self, context, event):
        job = self._job_
        if event.type == "ESC":
            self._end(context)
            self.report({"WARNING"}, "%s: yarn generation cancelled; nothing was changed" % job.obj_name)
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"RUNNING_MODAL"}
        try:
            t_end = time.perf_counter() + 0.1
            frac = 0.0
            while not job.done and time.perf_counter() < t_end:
                frac = job.step()
            context.window_manager.progress_update(int(900 * frac))
            if self._area is not None:
                self._area.header_text_set("Generating yarns of %s: %d%% (Esc to cancel)"
                                           % (job.obj_name, int(100 * frac)))
            if not job.done:
                return {"RUNNING_MODAL"}
            job.finish()
        except (YarnError, ValueError) as e:
            self._end(context)
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self._end(context)
        self._done(job)
        return {"FINISHED"}


# ---- the panel -----------------------------------------------------------

PARENT_PANEL = "KNITSHADE_PT_material"


def yarn_objects_of(obj):
    return [o for o in bpy.data.objects if (o.get(YARN_KEY) or {}).get("source") == obj.name]


class KNITSHADE_PT_material_yarns(bpy.types.Panel):
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "material"
    bl_label = "Yarn Geometry"
    bl_parent_id = PARENT_PANEL
    bl_order = 7

    @classmethod
    def poll(cls, context):
        mat = getattr(context, "material", None)
        return mat is not None and nodes.knit_node(mat) is not None

    def draw(self, context):
        layout = self.layout
        obj = context.object
        if not nyarns.available():
            col = layout.column(align=True)
            col.label(text="Yarn geometry needs the native module,", icon="INFO")
            col.label(text="which this Blender did not load:")
            for line in _wrap(nyarns.why_not(), 60):
                col.label(text=line)
            return
        row = layout.row()
        op = row.operator(KNITSHADE_OT_generate_yarns.bl_idname, icon="OUTLINER_OB_CURVES")
        if obj is not None:
            op.object = obj.name
        if context.material is not None:
            op.material = context.material.name
        if obj is None:
            return
        for yo in yarn_objects_of(obj):
            info = yo.get(YARN_KEY) or {}
            layout.label(text="%s: %s curves, %s points (frame %s)" % (
                yo.name, format(int(info.get("curves", 0)), ","), format(int(info.get("points", 0)), ","),
                info.get("frame", "?")), icon="CURVES_DATA" if hasattr(bpy.types, "Curves") else "NONE")
        if obj.type == "MESH" and deforming(obj):
            layout.label(text="The mesh deforms: yarns are static, made for one frame", icon="ERROR")


def _wrap(text, width):
    out, line = [], ""
    for w in text.split():
        if line and len(line) + 1 + len(w) > width:
            out.append(line)
            line = w
        else:
            line = (line + " " + w) if line else w
    if line:
        out.append(line)
    return out


_classes = (KNITSHADE_OT_generate_yarns, KNITSHADE_PT_material_yarns)


def register():
    for cls in _classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(_classes):
        try:
            bpy.utils.unregister_class(cls)
        except RuntimeError:
            pass

"""Knit Fabric from Python: the calls a bpy script uses (docs/blender.md).

    from knitshade_blender import api   # bl_ext.<repo>.knitshade_blender as an extension

    mat = api.add_knit_material(bpy.data.objects["Plane"], pattern="K P\\nP K",
                                colours=[(0.6, 0.1, 0.1)], a=1.5, h=4.0, d=1.0, r=0.6)
    api.set_pattern(mat, "K K P P\\nP P K K")
    api.set_parameters(mat, r=0.55, uv_scale=1500.0, yarn1=(0.9, 0.9, 0.85))

Settings are named as in the panel's Python tooltips: a, h, d, r, uv_scale,
yarn0 .. yarn7 (or colours=[...]), transmit_tint, roughness,
roughness_across, ior, body_energy, body_reflect, optical_depth,
ply_detail, ply_count, ply_twist, fiber_count, fiber_twist, mode
('NEAR_FIELD' or 'MULTI_SCALE'), footprint_points, capm, capm_steps (the
shader's own names, UVScale, Yarn0, ..., are accepted too).

Every function checks all it is given before changing anything: a refused
value raises ValueError (the library's message for a, h, d, r; a pattern's
PatternError names the source, line and column) and the material stays as it
was. Changing the pattern compiles the shader at once where Blender has OSL.
"""
import bpy

from . import compat, geometry, nodes, settings
from .core import pattern as kpattern
from .core import presets as kpresets
from .core import shader as kshader

PatternError = kpattern.PatternError
ShaderError = kshader.ShaderError
Pattern = kpattern.Pattern

__all__ = ["Pattern", "PatternError", "ShaderError", "add_knit_material", "compile_shader", "get_parameters",
           "get_pattern", "has_osl", "knit_node", "load_pattern", "refresh_curvature", "set_parameters",
           "set_pattern", "yarn_weights", "pattern_presets"]


def has_osl():
    """Whether this Blender's Cycles can run the knit shader (OSL)."""
    return compat.with_osl()


def pattern_presets():
    """[(identifier, name, description)] of the pattern presets."""
    return kpresets.pattern_presets()


def yarn_weights():
    """[(identifier, name, description)] of the yarn weights."""
    return kpresets.yarn_weight_presets()


def _as_pattern(pattern, source="<pattern>"):
    if isinstance(pattern, kpattern.Pattern):
        return pattern
    if isinstance(pattern, str):
        return kpattern.parse_text(pattern, source)
    raise TypeError("pattern must be a knitshade_blender Pattern or pattern text, got %s" % type(pattern).__name__)


def knit_node(material):
    """The material's Knit Fabric group node; ValueError when it has none."""
    node = nodes.knit_node(material)
    if node is None:
        raise ValueError("material '%s' has no Knit Fabric node" % material.name)
    return node


def add_knit_material(obj=None, pattern=None, colours=None, name=nodes.MATERIAL_NAME, preset=None,
                      yarn_weight=nodes.DEFAULT_YARN_WEIGHT, stitches_per_10cm=None, uv_scale=None,
                      setup_scene=True, **params):
    """A new Knit Fabric material, given to `obj` (an object, a list of
    objects, or None) in its active material slot (a new slot if it has
    none), and returned.

    pattern: a Pattern or pattern text (default: `preset`, else stockinette);
    colours: up to 8 yarn colours (linear RGB), colour index 0 first;
    yarn_weight: 'fingering', 'sport', 'dk', 'worsted' or 'chunky': a, h, d,
    r, ply count and gauge (what a, h, d, r, ply_count given here replace);
    uv_scale: pattern units per UV unit; default: the weight's gauge (or
    stitches_per_10cm) on the first object's size and UVs;
    setup_scene: render the current scene with Cycles and its OSL.
    Other keyword arguments: any setting (see the module's docstring).
    Mesh objects get the curvature attribute."""
    objs = [] if obj is None else (list(obj) if isinstance(obj, (list, tuple)) else [obj])
    if pattern is not None:
        pat = _as_pattern(pattern)
    elif preset is not None:
        pat = kpresets.load_preset(preset)
    else:
        pat = nodes.default_pattern()
    w = kpresets.yarn_weight(yarn_weight)
    values = {"A": w["a"], "H": w["h"], "D": w["d"], "R": w["r"], "PlyCount": w["ply_count"]}
    if colours is not None:
        params = dict(params, colours=colours)
    values.update(settings.resolve(params))
    if uv_scale is not None:
        values["UVScale"] = uv_scale
    elif "UVScale" not in values:
        gauge = stitches_per_10cm if stitches_per_10cm is not None else w["stitches_per_10cm"]
        meshes = [o for o in objs if geometry.has_uvs(o)]
        scene = bpy.context.scene
        m = geometry.metres_per_uv_unit(meshes[0], scene) if meshes else None
        values["UVScale"] = kpresets.uv_scale_for_gauge(gauge, m or nodes.DEFAULT_METRES_PER_UV)
    values = {k: v for k, v in values.items() if any(p.name == k for p in nodes.params())}
    defaults = nodes.defaults()
    values = settings.check(values, lambda n: defaults[n])
    for o in objs:
        if not hasattr(o.data, "materials"):
            raise ValueError("%s (%s) cannot hold materials" % (o.name, o.type))
    mat = nodes.new_material(pat, values, name)
    for o in objs:
        if o.material_slots:
            o.active_material = mat
        else:
            o.data.materials.append(mat)
        if geometry.has_uvs(o):
            geometry.write_curvature(o)
    if setup_scene and bpy.context.scene is not None:
        nodes.ensure_scene_renders_osl(bpy.context.scene)
    return mat


def get_pattern(material):
    """The material's pattern (a Pattern)."""
    return nodes.get_pattern(knit_node(material).node_tree)


def set_pattern(material, pattern):
    """Replace the material's pattern (a Pattern or pattern text); compiles
    the shader where Blender has OSL. Returns the Pattern."""
    pat = _as_pattern(pattern, "<%s>" % material.name)
    nodes.set_pattern(knit_node(material).node_tree, pat, compile="now")
    return pat


def load_pattern(material, path):
    """Replace the material's pattern with a .knit file's."""
    return set_pattern(material, kpattern.load(path))


def set_parameters(material, **kw):
    """Change settings (all checked first; nothing changes on a refusal).
    Returns {shader parameter name: value written}."""
    node = knit_node(material)
    changes = settings.resolve(kw)
    try:
        return settings.apply(material, changes, node)
    except ValueError as e:
        raise ValueError("%s: %s refused: %s" % (material.name, settings.describe(changes), e)) from None


def get_parameters(material):
    """{python name: value} of every setting."""
    node = knit_node(material)
    out = {}
    for p in nodes.params():
        v = nodes.get_value(node, p.name)
        if p.kind == "enum":
            v = next((i[0] for i in p.items if i[2] == v), v)
        out[settings.snake(p.name)] = v
    return out


def refresh_curvature(obj):
    """Write the curvature attribute of a mesh object (after it changed
    shape or scale); returns (faces, largest |curvature| in 1/world units)."""
    return geometry.write_curvature(obj)


def compile_shader(material):
    """Compile the material's shader now (True), or False where Blender has
    no OSL or compiling failed (the console has Cycles' message)."""
    return nodes.ensure_compiled(knit_node(material).node_tree)

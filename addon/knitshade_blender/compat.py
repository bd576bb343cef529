"""Every difference between the Blender versions the add-on supports, in one
place (Blender 3.4 to 5.x; Python 3.10 to 3.13).

The rest of the add-on imports the names below and never looks at
bpy.app.version itself.

| what                          | 3.4 .. 3.6                 | 4.0 and later                      |
| ----------------------------- | -------------------------- | ---------------------------------- |
| a node group's sockets        | tree.inputs / tree.outputs | tree.interface.new_socket()        |
| Add > Shader menu             | NODE_MT_category_SH_NEW_SHADER | NODE_MT_category_shader_shader |
| Material.use_nodes            | must be set                | deprecated in 5.0 (always nodes)   |
| group socket tooltip          | 63 bytes                   | any length                         |
| OSL in Cycles                 | _cycles.with_osl (Debian's 3.4: False) | same; PyPI's bpy: True |
| oslquery (Cycles' osl.py)     | on sys.path                | PyPI's bpy: under resource_path("LOCAL")/python/lib/python3.11/site-packages |
"""
import os
import sys

import bpy

VERSION = tuple(bpy.app.version)
IS_4_0 = VERSION >= (4, 0, 0)
IS_4_2 = VERSION >= (4, 2, 0)
IS_5_0 = VERSION >= (5, 0, 0)

# Sockets by the kind of a shader parameter or output (core.shader), as
# Cycles makes them on a compiled Script node.
SOCKET_TYPES = {
    "float": "NodeSocketFloat",
    "int": "NodeSocketInt",
    "bool": "NodeSocketBool",
    "enum": "NodeSocketInt",
    "color": "NodeSocketColor",
    "point": "NodeSocketVector",
    "vector": "NodeSocketVector",
    "normal": "NodeSocketVector",
    "closure": "NodeSocketShader",
}

# The node group's inputs: the same, but an on/off setting is an integer
# (0 or 1). In Cycles 5.0.1 a Boolean group input linked into a Script node's
# Boolean input aborts the render (std::bad_variant_access in the shader
# sync); an integer input linked there renders, and its 0/1 reaches the
# shader (tests/blender/test_render.py renders through such a group).
GROUP_SOCKET_TYPES = dict(SOCKET_TYPES, bool="NodeSocketInt")


# ---- node groups ---------------------------------------------------------

# 3.x keeps a group socket's tooltip in 64 bytes; 4.0 and later in a string.
DESCRIPTION_MAX = None if IS_4_0 else 63


def short_description(text):
    """The tooltip as this Blender stores it: whole, or cut at a word to fit."""
    if DESCRIPTION_MAX is None or len(text.encode("utf-8")) <= DESCRIPTION_MAX:
        return text
    cut = text[:DESCRIPTION_MAX - 3]
    if " " in cut:
        cut = cut[:cut.rindex(" ")]
    return cut.rstrip(" ,;:") + "..."


def new_group_socket(tree, in_out, socket_type, name, description=""):
    """A new input ('INPUT') or output ('OUTPUT') socket of node group `tree`;
    returns the interface socket (identifier, default_value, min_value, ...)."""
    if IS_4_0:
        return tree.interface.new_socket(name=name, description=description, in_out=in_out,
                                         socket_type=socket_type)
    sockets = tree.inputs if in_out == "INPUT" else tree.outputs
    sock = sockets.new(socket_type, name)
    sock.description = short_description(description)
    return sock


def group_sockets(tree, in_out):
    """The interface sockets of `tree` on one side, in order."""
    if IS_4_0:
        return [item for item in tree.interface.items_tree
                if item.item_type == "SOCKET" and item.in_out == in_out]
    return list(tree.inputs if in_out == "INPUT" else tree.outputs)


def socket_by_identifier(sockets, identifier):
    """The socket of a node's inputs or outputs with this identifier, or None
    (a socket's name is its label and may change; its identifier does not)."""
    for s in sockets:
        if s.identifier == identifier:
            return s
    return None


# ---- materials -----------------------------------------------------------

def ensure_node_tree(material):
    """Give `material` its node tree (Blender 5.0 materials always use nodes,
    and Material.use_nodes is deprecated there)."""
    if not IS_5_0 and not material.use_nodes:
        material.use_nodes = True
    return material.node_tree


def shader_add_menus():
    """The Add > Shader menus of the shader editor that exist here."""
    names = ("NODE_MT_category_shader_shader",  # 4.0 and later
             "NODE_MT_category_SH_NEW_SHADER")  # 3.x (nodeitems)
    return [getattr(bpy.types, n) for n in names if hasattr(bpy.types, n)]


# ---- OSL -----------------------------------------------------------------

def with_osl():
    """Whether this Blender's Cycles can compile and run OSL shaders."""
    try:
        import _cycles
    except ImportError:
        return False
    return bool(getattr(_cycles, "with_osl", False)) and hasattr(_cycles, "osl_compile")


def ensure_oslquery_importable():
    """Cycles' osl.py does `import oslquery`. Blender puts it on sys.path; the
    `bpy` module from PyPI keeps it under its LOCAL resource folder, which
    is not on sys.path there."""
    try:
        import oslquery  # noqa: F401
        return
    except ImportError:
        pass
    local = bpy.utils.resource_path("LOCAL")
    ver = "python%d.%d" % sys.version_info[:2]
    for path in (os.path.join(local, "python", "lib", ver, "site-packages"),
                 os.path.join(local, "python", "lib", "site-packages")):
        if os.path.isdir(os.path.join(path, "oslquery")) and path not in sys.path:
            sys.path.append(path)


def compile_script_node(node, report):
    """Compile an INTERNAL Script node with Cycles' own function: its bytecode
    goes into the node (a saved .blend renders without the add-on) and its
    sockets are made from the shader's parameters. `report(type_set, text)`
    receives Cycles' messages. Returns True on success; False without OSL."""
    if not with_osl():
        return False
    ensure_oslquery_importable()
    from cycles import osl  # the Cycles add-on, enabled wherever Cycles is
    return bool(osl.update_script_node(node, report))


def knit_cycles_material_settings(material):
    """What a Knit Fabric material sets in Cycles' material settings, where
    this Blender has them: no emission sampling (the shader never emits;
    Cycles cannot tell from an OSL script and would sample the fabric's faces
    as lights), and no bump map correction (4.2 and later: it bends the
    microfacet normal and softens diffuse light at the yarn's normals, which
    the knit model, rendered natively "as Cycles renders it", does not do;
    docs/shader.md)."""
    cm = getattr(material, "cycles", None)
    if cm is None:
        return
    if hasattr(cm, "emission_sampling"):
        cm.emission_sampling = "NONE"
    if hasattr(cm, "use_bump_map_correction"):
        cm.use_bump_map_correction = False


def cycles_device_runs_osl(scene):
    """(ok, why): whether the scene's Cycles device can run OSL shaders (CPU,
    or OptiX GPUs), and what to say when it cannot."""
    cscene = getattr(scene, "cycles", None)
    if cscene is None or cscene.device != "GPU":
        return True, ""
    try:
        prefs = bpy.context.preferences.addons["cycles"].preferences
        kind = prefs.compute_device_type
    except (KeyError, AttributeError):
        kind = "NONE"
    if kind == "OPTIX":
        return True, ""
    return False, "GPU compute (%s) does not run OSL; only CPU and OptiX do" % kind


# ---- meshes --------------------------------------------------------------

def active_uv_layer(mesh):
    """The UV map that renders (the active render one), else the active one."""
    layers = mesh.uv_layers
    for layer in layers:
        if layer.active_render:
            return layer
    return layers.active


def loop_uvs(mesh, layer, out):
    """Fill `out` (float32 numpy array of 2 * loops) with the UVs of `layer`."""
    layer.data.foreach_get("uv", out)


def vertex_normals(mesh, out):
    """Fill `out` (float32, 3 * vertices) with the mesh's vertex normals."""
    if hasattr(mesh, "vertex_normals"):  # 3.4 and later
        mesh.vertex_normals.foreach_get("vector", out)
    else:
        mesh.vertices.foreach_get("normal", out)


# ---- context -------------------------------------------------------------

def temp_override(context, **kw):
    """context.temp_override (3.2 and later), the only kind used here."""
    return context.temp_override(**kw)

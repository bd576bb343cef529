"""Knitshade for Blender: knitted fabric as a Cycles OSL material, without
yarn geometry or texture maps.

The add-on makes a "Knit Fabric" material (Add > Shader > Knit Fabric in the
shader editor, or Add Knit Fabric in the material tab): a node group holding
the generated knit shader in a Script node, with inputs for the yarn
colours, the stitch shape (a, h, d, r), the UV scale and the yarn's optics,
and a pattern editor. Scripts use knitshade_blender.api (docs/blender.md).

Layout (by role, registered in this order): props (settings on Blender
data), ops (operators), nodes (the node group, the shader text, compiling,
handlers, the Add menu entry), ui (panels). core/ is pure Python without
bpy; native/ imports the optional compiled module.
"""

bl_info = {
    "name": "Knitshade",
    "author": "Knitshade developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Material > Knit Fabric; Shader Editor > Add > Shader > Knit Fabric",
    "description": "Knitted fabric without textures: a Cycles OSL material with a pattern editor",
    "doc_url": "https://github.com/knitshade/knitshade/blob/main/docs/blender.md",
    "category": "Material",
}

if "bpy" in locals():  # F8 / script reload: reload the modules in dependency order
    import importlib

    for _name in ("compat", "native", "settings", "geometry", "nodes", "props", "ops", "ui", "api", "yarns",
                  "preview"):
        if _name in locals():
            locals()[_name] = importlib.reload(locals()[_name])

import bpy  # noqa: E402,F401

from . import compat, geometry, native, nodes, ops, props, settings, ui  # noqa: E402,F401
from . import api  # noqa: E402,F401
from . import preview, yarns  # noqa: E402  (issue 54: yarn geometry, swatch preview)

_MODULES = (props, ops, nodes, ui, yarns, preview)


def register():
    for module in _MODULES:
        module.register()


def unregister():
    for module in reversed(_MODULES):
        try:
            module.unregister()
        except Exception as e:  # noqa: BLE001  (unregister the rest even if one part fails)
            print("Knitshade: unregistering %s: %s" % (module.__name__, e))

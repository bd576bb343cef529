"""Properties: the material's Knit Fabric settings and the pattern editor's state.

Material.knitshade (KNITSHADE_PG_material) shows every shader setting as a
property made from core.shader.PARAMS (label, tooltip, range, default). It
stores nothing of its own: each property reads and writes the input socket
of the material's Knit Fabric group node, the one place the value lives
(so a value set on the node in the node editor is the value the panel
shows, and both survive save, reload, undo and append with the material).
Writing one checks it first (settings.apply): a refused value keeps the
previous one, and the refusal is kept in `message` for the panel.

WindowManager.knitshade_editor (KNITSHADE_PG_editor) is the pattern
editor's state: the tool and brush, the page shown, the cursor. It is
interface state, not part of the material and not an undo step.
"""
import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, IntProperty,
                       PointerProperty, StringProperty)

from . import nodes, settings

LOAD_ERROR = ""  # why the settings could not be made (a missing shader template)


def _getter(name, kind):
    def get(self):
        node = nodes.knit_node(self.id_data)
        v = nodes.get_value(node, name)
        return int(v) if kind == "enum" else v
    return get


def _setter(name, kind):
    def set_(self, value):
        mat = self.id_data
        try:
            settings.apply(mat, {name: value})
        except ValueError as e:  # refused: the socket keeps its value
            self["message"] = "%s: %s refused: %s" % (mat.name, settings.describe({name: value}), e)
            print("Knit Fabric: " + self["message"])
        else:
            if self.get("message"):
                self["message"] = ""
    return set_


def _property(p, default):
    common = dict(name=p.label, description=p.description, get=_getter(p.name, p.kind),
                  set=_setter(p.name, p.kind))
    limits = {}
    for key, attr in (("min", "min"), ("max", "max"), ("soft_min", "soft_min"), ("soft_max", "soft_max")):
        v = getattr(p, attr)
        if v is not None:
            limits[key] = v
    if p.kind == "float":
        return FloatProperty(default=float(default), precision=3, **limits, **common)
    if p.kind == "int":
        return IntProperty(default=int(default), **{k: int(v) for k, v in limits.items()}, **common)
    if p.kind == "bool":
        return BoolProperty(default=bool(default), **common)
    if p.kind == "enum":
        items = [(ident, label, "", number) for ident, label, number in (p.items or ())]
        ident = next((i[0] for i in items if i[3] == int(default)), items[0][0] if items else "")
        return EnumProperty(items=items, default=ident, **common)
    if p.kind == "color":
        return FloatVectorProperty(subtype="COLOR", size=3, min=0.0, soft_max=1.0,
                                   default=tuple(default)[:3], **common)
    return FloatVectorProperty(size=3, default=tuple(default), **common)


def _material_class():
    global LOAD_ERROR
    ann = {
        "message": StringProperty(
            name="Message", description="The last refused change or failed import, for the panel"),
    }
    try:
        vals = nodes.defaults()
        for p in nodes.params():
            ann[settings.snake(p.name)] = _property(p, vals.get(p.name, p.default))
        LOAD_ERROR = ""
    except Exception as e:  # noqa: BLE001  (a broken install must still register and say so)
        LOAD_ERROR = "the shader's parameters could not be read: %s" % e
    return type("KNITSHADE_PG_material", (bpy.types.PropertyGroup,), {
        "__annotations__": ann,
        "__doc__": "Knit Fabric settings of a material (stored on its Knit Fabric node's inputs)",
    })


class KNITSHADE_PG_editor(bpy.types.PropertyGroup):
    """The pattern editor's state (interface only)."""

    tool: EnumProperty(
        name="Tool", description="What a click on a cell does",
        items=[("CYCLE", "Cycle", "A click turns the stitch to the next one: K, P, F, B", "FILE_REFRESH", 0),
               ("STITCH", "Stitch", "A click paints the chosen stitch", "BRUSH_DATA", 1),
               ("COLOUR", "Colour", "A click paints the chosen yarn colour", "COLOR", 2)],
        default="CYCLE")
    stitch: EnumProperty(
        name="Stitch", description="The stitch the Stitch tool paints",
        items=[("K", "K", "Knit: the V side faces you", 0),
               ("P", "P", "Purl: the bump side faces you", 1),
               ("F", "F", "Slip stitch, yarn float in front", 2),
               ("B", "B", "Slip stitch, yarn float behind", 3)],
        default="P")
    colour: IntProperty(name="Colour", description="The yarn colour (palette index) the Colour tool paints",
                        min=0, max=7, default=1)
    page_row: IntProperty(name="First Row", description="Top row of the page the grid shows", min=0, default=0)
    page_col: IntProperty(name="First Column", description="Left column of the page the grid shows",
                          min=0, default=0)
    page_size: IntProperty(name="Cells per Page",
                           description="Rows and columns the grid shows at once; larger patterns are "
                                       "edited a page at a time beside an overview image",
                           min=4, max=48, default=24)
    cursor_row: IntProperty(name="Cursor Row", description="Row of the last cell clicked", min=0, default=0)
    cursor_col: IntProperty(name="Cursor Column", description="Column of the last cell clicked", min=0,
                            default=0)
    show_colours: BoolProperty(name="Show Colours",
                               description="Show each cell's yarn colour in the grid", default=True)


_classes = []


def register():
    global _classes
    mat_cls = _material_class()
    _classes = [mat_cls, KNITSHADE_PG_editor]
    for cls in _classes:
        bpy.utils.register_class(cls)
    bpy.types.Material.knitshade = PointerProperty(type=mat_cls, name="Knit Fabric")
    bpy.types.WindowManager.knitshade_editor = PointerProperty(type=KNITSHADE_PG_editor,
                                                                name="Knit Pattern Editor")


def unregister():
    for owner, attr in ((bpy.types.WindowManager, "knitshade_editor"), (bpy.types.Material, "knitshade")):
        if hasattr(owner, attr):
            delattr(owner, attr)
    for cls in reversed(_classes):
        try:
            bpy.utils.unregister_class(cls)
        except RuntimeError:
            pass
    _classes.clear()

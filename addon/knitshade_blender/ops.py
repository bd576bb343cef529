"""Operators (bpy.ops.knitshade.*): thin; they find the material, call the
core, and report.

Every operator works from the panel and from a script with arguments. An
operator that edits a Knit Fabric takes `material` (a material's name;
default: the material in context: the material tab's, the node editor's,
else the active object's) and `node` (the Knit Fabric group node's name in
it; default: the active node if it is one, else the first). Edits of the
pattern and of settings are one undo step each. What cannot be done is one
report line naming the material and the value, and the data stays as it was.
"""
import os

import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, IntProperty,
                       IntVectorProperty, StringProperty)
from bpy_extras.io_utils import ExportHelper, ImportHelper

from . import compat, geometry, nodes, settings
from .core import pattern as kpattern
from .core import presets as kpresets
from .core import shader as kshader

LETTERS = kpattern.LETTERS
STITCH_ITEMS = [("K", "Knit", "Knit: the V side faces you"),
                ("P", "Purl", "Purl: the bump side faces you"),
                ("F", "Front Slip", "Slip stitch with the yarn float in front"),
                ("B", "Back Slip", "Slip stitch with the yarn float behind")]

# The presets are files read once, when the add-on loads (static enum items,
# so a script that gives none gets the default, not the first in the list).
_PRESET_ITEMS = [(i, n, d) for i, n, d in kpresets.pattern_presets()] or [("", "None", "No presets found")]
_WEIGHT_ITEMS = [(i, n, d) for i, n, d in kpresets.yarn_weight_presets()]


def _default(items, wanted):
    return wanted if any(i[0] == wanted for i in items) else items[0][0]


PRESET_DEFAULT = _default(_PRESET_ITEMS, nodes.DEFAULT_PRESET)
WEIGHT_DEFAULT = _default(_WEIGHT_ITEMS, nodes.DEFAULT_YARN_WEIGHT)


class KnitTargetError(Exception):
    pass


def _context_material(context):
    mat = getattr(context, "knitshade_material", None)
    if mat is None:
        mat = getattr(context, "material", None)
    if mat is None:
        space = getattr(context, "space_data", None)
        if space is not None and getattr(space, "type", "") == "NODE_EDITOR":
            ident = getattr(space, "id", None)
            if isinstance(ident, bpy.types.Material):
                mat = ident
    if mat is None:
        obj = getattr(context, "object", None) or getattr(context, "active_object", None)
        if obj is not None:
            mat = obj.active_material
    return mat


class _Target:
    material: StringProperty(name="Material", description="Name of the material (default: the one in context)",
                             options={"SKIP_SAVE"})
    node: StringProperty(name="Node", description="Name of its Knit Fabric node (default: the active or "
                         "first one)", options={"SKIP_SAVE"})

    def target(self, context):
        """(material, group node, node group) or KnitTargetError."""
        if self.material:
            mat = bpy.data.materials.get(self.material)
            if mat is None:
                raise KnitTargetError("there is no material '%s'" % self.material)
        else:
            mat = _context_material(context)
            if mat is None:
                raise KnitTargetError("no material here: select an object with a Knit Fabric material, "
                                      "or name one with material=")
        node = None
        if not self.node:
            cn = getattr(context, "knitshade_node", None)
            if cn is not None and nodes.is_knit_node(cn) and cn.id_data == mat.node_tree:
                node = cn
        if node is None:
            node = nodes.knit_node(mat, self.node)
        if node is None:
            if self.node:
                raise KnitTargetError("material '%s' has no Knit Fabric node '%s'" % (mat.name, self.node))
            raise KnitTargetError("material '%s' has no Knit Fabric node (use Add Knit Fabric)" % mat.name)
        return mat, node, node.node_tree

    def fail(self, text, mat=None):
        if mat is not None:
            try:
                mat.knitshade.message = text
            except AttributeError:
                pass
        self.report({"ERROR"}, text)
        return {"CANCELLED"}


def _clear_message(mat):
    try:
        if mat.knitshade.message:
            mat.knitshade.message = ""
    except AttributeError:
        pass


# ---- pattern edits -------------------------------------------------------

class _PatternEdit(_Target):
    """An edit of the pattern: one undo step. The shader text is written at
    once; in the interface it compiles after a short pause (a run of clicks
    compiles once), in background Blender at once (nodes.set_pattern)."""

    bl_options = {"REGISTER", "UNDO"}
    what = "edit"
    say_unchanged = False

    def edit(self, pat, context):
        raise NotImplementedError

    def done(self, context, mat, pat):
        pass

    def invoke(self, context, _event):
        self._from_ui = True
        return self.execute(context)

    def execute(self, context):
        try:
            mat, node, tree = self.target(context)
        except KnitTargetError as e:
            return self.fail(str(e))
        try:
            old = nodes.get_pattern(tree)
            new = self.edit(old, context)
        except (kpattern.PatternError, ValueError) as e:
            return self.fail("%s: %s refused: %s" % (mat.name, self.what, e), mat)
        if new is None or new == old:  # nothing to change (and no undo step)
            _clear_message(mat)
            if self.say_unchanged:
                self.report({"INFO"}, "%s: %s: the pattern is the same" % (mat.name, self.what))
            return {"CANCELLED"}
        try:
            nodes.set_pattern(tree, new, compile="later", report=self.report)
        except (kshader.ShaderError, nodes.KnitError) as e:
            return self.fail("%s: %s refused: %s" % (mat.name, self.what, e), mat)
        _clear_message(mat)
        self.done(context, mat, new)
        return {"FINISHED"}


def _editor(context):
    return getattr(context.window_manager, "knitshade_editor", None)


class KNITSHADE_OT_paint_cell(_PatternEdit, bpy.types.Operator):
    """Change one cell of the pattern: cycle its stitch, paint a stitch, or paint a yarn colour"""

    bl_idname = "knitshade.paint_cell"
    bl_label = "Paint Cell"
    what = "painting a cell"

    row: IntProperty(name="Row", description="Row of the cell, 0 at the top", min=0)
    col: IntProperty(name="Column", description="Column of the cell, 0 at the left", min=0)
    tool: EnumProperty(name="Tool", items=[("CYCLE", "Cycle", "Next stitch: K, P, F, B"),
                                           ("STITCH", "Stitch", "Paint the stitch"),
                                           ("COLOUR", "Colour", "Paint the colour")], default="CYCLE")
    stitch: EnumProperty(name="Stitch", items=STITCH_ITEMS, default="K")
    colour: IntProperty(name="Colour", description="Palette index (0-7)", min=0, max=255, default=0)

    def edit(self, pat, context):
        if self.tool == "CYCLE":
            return pat.cycled(self.row, self.col)
        if self.tool == "STITCH":
            return pat.with_stitch(self.row, self.col, self.stitch)
        if self.colour >= kshader.PALETTE_SIZE:
            raise ValueError("colour %d: the palette has colours 0 to %d" % (self.colour, kshader.PALETTE_SIZE - 1))
        return pat.with_color(self.row, self.col, self.colour)

    def done(self, context, mat, pat):
        ed = _editor(context)
        if ed is not None:
            ed.cursor_row, ed.cursor_col = self.row, self.col


class KNITSHADE_OT_fill(_PatternEdit, bpy.types.Operator):
    """Fill the pattern (or a rectangle of it) with a stitch and/or a yarn colour"""

    bl_idname = "knitshade.fill"
    bl_label = "Fill"
    what = "fill"

    stitch: EnumProperty(name="Stitch", items=[("NONE", "Keep", "Keep the stitches")] + STITCH_ITEMS,
                         default="NONE")
    colour: IntProperty(name="Colour", description="Palette index to fill with; -1 keeps the colours",
                        min=-1, max=255, default=-1)
    rect: IntVectorProperty(name="Rectangle", size=4, min=0, default=(0, 0, 0, 0),
                            description="Top row, left column, rows, columns; 0 rows: the whole pattern")

    def invoke(self, context, event):
        ed = _editor(context)
        if ed is not None and not self.properties.is_property_set("stitch") \
                and not self.properties.is_property_set("colour"):
            if ed.tool == "COLOUR":
                self.colour = ed.colour
            else:
                self.stitch = ed.stitch
        return super().invoke(context, event)

    def edit(self, pat, context):
        if self.colour >= kshader.PALETTE_SIZE:
            raise ValueError("colour %d: the palette has colours 0 to %d" % (self.colour, kshader.PALETTE_SIZE - 1))
        stitch = None if self.stitch == "NONE" else self.stitch
        colour = None if self.colour < 0 else self.colour
        rect = tuple(self.rect) if self.rect[2] > 0 and self.rect[3] > 0 else None
        return pat.filled(stitch=stitch, color=colour, rect=rect)


class KNITSHADE_OT_shift(_PatternEdit, bpy.types.Operator):
    """Move the pattern by whole stitches, wrapping around its edges"""

    bl_idname = "knitshade.shift"
    bl_label = "Shift Pattern"
    what = "shift"

    dx: IntProperty(name="Columns", description="Columns to move right (negative: left)", default=1)
    dy: IntProperty(name="Rows", description="Rows to move down (negative: up)", default=0)

    def edit(self, pat, context):
        return pat.shifted(self.dx, self.dy)


class KNITSHADE_OT_mirror(_PatternEdit, bpy.types.Operator):
    """Mirror the pattern left to right"""

    bl_idname = "knitshade.mirror"
    bl_label = "Mirror Pattern"
    what = "mirror"

    def edit(self, pat, context):
        return pat.mirrored()


class KNITSHADE_OT_flip(_PatternEdit, bpy.types.Operator):
    """Flip the pattern top to bottom"""

    bl_idname = "knitshade.flip"
    bl_label = "Flip Pattern"
    what = "flip"

    def edit(self, pat, context):
        return pat.flipped()


class KNITSHADE_OT_resize(_PatternEdit, bpy.types.Operator):
    """Change the pattern's size: the top-left part is kept, new cells are knit in colour 0"""

    bl_idname = "knitshade.resize"
    bl_label = "Resize Pattern"
    what = "resize"

    rows: IntProperty(name="Rows", min=1, max=kpattern.MAX_ROWS, soft_max=kshader.MAX_SIDE, default=4)
    cols: IntProperty(name="Columns", min=1, max=kpattern.MAX_COLS, soft_max=kshader.MAX_SIDE, default=4)

    def invoke(self, context, _event):
        try:
            _mat, _node, tree = self.target(context)
            pat = nodes.get_pattern(tree)
        except (KnitTargetError, kpattern.PatternError) as e:
            return self.fail(str(e))
        if not self.properties.is_property_set("rows"):
            self.rows = pat.rows
        if not self.properties.is_property_set("cols"):
            self.cols = pat.cols
        self._from_ui = True
        return context.window_manager.invoke_props_dialog(self)

    def edit(self, pat, context):
        return pat.resized(self.rows, self.cols)


class _RowColEdit(_PatternEdit):
    index: IntProperty(name="Index", description="Row or column (0 first); -1: the editor's cursor, "
                       "or the end when there is no editor", default=-1, min=-1)

    def _index(self, context, count, axis, at_end):
        if self.index >= 0:
            return self.index
        ed = _editor(context)
        if ed is not None and getattr(self, "_from_ui", False):
            cur = ed.cursor_row if axis == "row" else ed.cursor_col
            return min(cur, count - 1 if not at_end else count)
        return count if at_end else count - 1


class KNITSHADE_OT_insert_row(_RowColEdit, bpy.types.Operator):
    """Insert a row of knit stitches above the cursor's row (from a script: before row `index`, -1 at the bottom)"""

    bl_idname = "knitshade.insert_row"
    bl_label = "Insert Row"
    what = "inserting a row"

    def edit(self, pat, context):
        return pat.with_row_inserted(self._index(context, pat.rows, "row", True))


class KNITSHADE_OT_remove_row(_RowColEdit, bpy.types.Operator):
    """Remove the cursor's row (from a script: row `index`, -1 the last)"""

    bl_idname = "knitshade.remove_row"
    bl_label = "Remove Row"
    what = "removing a row"

    def edit(self, pat, context):
        return pat.with_row_removed(self._index(context, pat.rows, "row", False))


class KNITSHADE_OT_insert_column(_RowColEdit, bpy.types.Operator):
    """Insert a column of knit stitches left of the cursor's column (from a script: before column `index`, -1 at the right)"""

    bl_idname = "knitshade.insert_column"
    bl_label = "Insert Column"
    what = "inserting a column"

    def edit(self, pat, context):
        return pat.with_col_inserted(self._index(context, pat.cols, "col", True))


class KNITSHADE_OT_remove_column(_RowColEdit, bpy.types.Operator):
    """Remove the cursor's column (from a script: column `index`, -1 the last)"""

    bl_idname = "knitshade.remove_column"
    bl_label = "Remove Column"
    what = "removing a column"

    def edit(self, pat, context):
        return pat.with_col_removed(self._index(context, pat.cols, "col", False))


class KNITSHADE_OT_clear_colours(_PatternEdit, bpy.types.Operator):
    """Remove the pattern's colours: every stitch in yarn colour 0"""

    bl_idname = "knitshade.clear_colours"
    bl_label = "Clear Colours"
    what = "clearing the colours"

    def edit(self, pat, context):
        return pat.without_colors()


class KNITSHADE_OT_load_preset(_PatternEdit, bpy.types.Operator):
    """Replace the pattern with a preset"""

    bl_idname = "knitshade.load_preset"
    bl_label = "Load Pattern Preset"
    what = "loading the preset"

    preset: EnumProperty(name="Preset", items=_PRESET_ITEMS, default=PRESET_DEFAULT)

    def edit(self, pat, context):
        self.what = "loading the preset '%s'" % self.preset
        return kpresets.load_preset(self.preset)


class KNITSHADE_OT_set_pattern(_PatternEdit, bpy.types.Operator):
    """Replace the pattern with one given as text (the .knit format)"""

    bl_idname = "knitshade.set_pattern"
    bl_label = "Set Pattern"
    what = "setting the pattern"
    bl_options = {"REGISTER", "UNDO", "INTERNAL"}

    text: StringProperty(name="Pattern", description="Pattern text: rows of K P F B, optional 'colors:' "
                         "section (docs/patterns.md)")

    def edit(self, pat, context):
        return kpattern.parse_text(self.text, "<text>")


class KNITSHADE_OT_import_pattern(_PatternEdit, bpy.types.Operator, ImportHelper):
    """Load a pattern from a .knit file"""

    bl_idname = "knitshade.import_pattern"
    bl_label = "Import Pattern"
    what = "import"
    say_unchanged = True

    filename_ext = ".knit"
    filter_glob: StringProperty(default="*.knit;*.txt", options={"HIDDEN"})

    def invoke(self, context, event):
        self._from_ui = True
        return ImportHelper.invoke(self, context, event)

    def edit(self, pat, context):
        return kpattern.load(self.filepath)

    def done(self, context, mat, pat):
        self.report({"INFO"}, "%s: pattern %d x %d from %s" % (mat.name, pat.rows, pat.cols,
                                                               os.path.basename(self.filepath)))


class KNITSHADE_OT_export_pattern(_Target, bpy.types.Operator, ExportHelper):
    """Save the pattern as a .knit file"""

    bl_idname = "knitshade.export_pattern"
    bl_label = "Export Pattern"
    bl_options = {"REGISTER"}

    filename_ext = ".knit"
    filter_glob: StringProperty(default="*.knit", options={"HIDDEN"})

    def execute(self, context):
        try:
            mat, _node, tree = self.target(context)
            pat = nodes.get_pattern(tree)
        except (KnitTargetError, kpattern.PatternError) as e:
            return self.fail(str(e))
        text = "# %s, exported by Knitshade (%d x %d)\n" % (mat.name, pat.rows, pat.cols) + pat.to_text()
        try:
            with open(self.filepath, "w", encoding="utf-8", newline="\n") as f:
                f.write(text)
        except OSError as e:
            return self.fail("%s: cannot write %s: %s" % (mat.name, self.filepath, e.strerror or e), mat)
        self.report({"INFO"}, "%s: pattern written to %s" % (mat.name, self.filepath))
        return {"FINISHED"}


class KNITSHADE_OT_make_single_user(_Target, bpy.types.Operator):
    """Give this material a pattern of its own (its Knit Fabric group is shared with other materials)"""

    bl_idname = "knitshade.make_single_user"
    bl_label = "Make Pattern Single User"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        try:
            mat, node, tree = self.target(context)
        except KnitTargetError as e:
            return self.fail(str(e))
        copy = tree.copy()
        script = nodes.script_node(copy)
        if script is not None and script.script is not None:
            script.script = script.script.copy()
        node.node_tree = copy
        self.report({"INFO"}, "%s: pattern group %s of its own" % (mat.name, copy.name))
        return {"FINISHED"}


# ---- settings ------------------------------------------------------------

class KNITSHADE_OT_set_stitch(_Target, bpy.types.Operator):
    """Set the stitch shape (a, h, d, r) together, checked by the library"""

    bl_idname = "knitshade.set_stitch"
    bl_label = "Set Stitch Shape"
    bl_options = {"REGISTER", "UNDO"}

    a: FloatProperty(name="Loop Roundness (a)", default=1.5)
    h: FloatProperty(name="Loop Height (h)", default=4.0)
    d: FloatProperty(name="Loop Depth (d)", default=1.0)
    r: FloatProperty(name="Yarn Radius (r)", default=0.65)

    def execute(self, context):
        try:
            mat, node, _tree = self.target(context)
        except KnitTargetError as e:
            return self.fail(str(e))
        changes = {n: getattr(self, n.lower()) for n in settings.STITCH
                   if self.properties.is_property_set(n.lower())}
        if not changes:
            return {"CANCELLED"}
        try:
            settings.apply(mat, changes, node)
        except ValueError as e:
            return self.fail("%s: %s refused: %s" % (mat.name, settings.describe(changes), e), mat)
        _clear_message(mat)
        return {"FINISHED"}


class KNITSHADE_OT_yarn_weight(_Target, bpy.types.Operator):
    """Set a, h, d, r and the ply count of a yarn weight; with an object, also the UV scale for the weight's gauge"""

    bl_idname = "knitshade.yarn_weight"
    bl_label = "Yarn Weight"
    bl_options = {"REGISTER", "UNDO"}

    weight: EnumProperty(name="Yarn Weight", items=_WEIGHT_ITEMS, default=WEIGHT_DEFAULT)
    use_gauge: BoolProperty(name="Gauge", description="Also set the UV scale so the active object shows the "
                            "weight's stitches per 10 cm", default=True)

    def execute(self, context):
        try:
            mat, node, _tree = self.target(context)
        except KnitTargetError as e:
            return self.fail(str(e))
        w = kpresets.yarn_weight(self.weight)
        changes = {"A": w["a"], "H": w["h"], "D": w["d"], "R": w["r"]}
        if any(p.name == "PlyCount" for p in nodes.params()):
            changes["PlyCount"] = w["ply_count"]
        note = ""
        if self.use_gauge:
            obj = getattr(context, "object", None)
            m = geometry.metres_per_uv_unit(obj, context.scene) if obj is not None else None
            if m is not None:
                changes["UVScale"] = kpresets.uv_scale_for_gauge(w["stitches_per_10cm"], m)
                note = ", %g stitches per 10 cm on %s" % (w["stitches_per_10cm"], obj.name)
        try:
            settings.apply(mat, changes, node)
        except ValueError as e:
            return self.fail("%s: yarn weight %s refused: %s" % (mat.name, w["name"], e), mat)
        _clear_message(mat)
        self.report({"INFO"}, "%s: %s yarn%s" % (mat.name, w["name"], note))
        return {"FINISHED"}


class KNITSHADE_OT_gauge(_Target, bpy.types.Operator):
    """Set the UV scale so an object shows a number of stitches per 10 cm (from its size and UVs)"""

    bl_idname = "knitshade.gauge"
    bl_label = "Set Gauge"
    bl_options = {"REGISTER", "UNDO"}

    stitches_per_10cm: FloatProperty(name="Stitches per 10 cm", min=0.5, max=200.0, soft_min=8, soft_max=40,
                                     default=18.0, description="Stitches across 10 cm of the object's surface "
                                     "(worsted yarn about 18, fingering about 28)")
    object: StringProperty(name="Object", description="Object whose size and UVs set the scale (default: "
                           "the active object)", options={"SKIP_SAVE"})

    def execute(self, context):
        try:
            mat, node, _tree = self.target(context)
        except KnitTargetError as e:
            return self.fail(str(e))
        obj = bpy.data.objects.get(self.object) if self.object else getattr(context, "object", None)
        if obj is None:
            return self.fail("%s: no object to measure (select one, or give object=)" % mat.name, mat)
        m = geometry.metres_per_uv_unit(obj, context.scene)
        if m is None:
            return self.fail("%s: %s has no UV map with area to measure" % (mat.name, obj.name), mat)
        try:
            settings.apply(mat, {"UVScale": kpresets.uv_scale_for_gauge(self.stitches_per_10cm, m)}, node)
        except ValueError as e:
            return self.fail("%s: gauge %g refused: %s" % (mat.name, self.stitches_per_10cm, e), mat)
        _clear_message(mat)
        return {"FINISHED"}


# ---- the material --------------------------------------------------------

def _objects(context, names):
    if names:
        out, missing = [], []
        for n in (x.strip() for x in names.split(",")):
            if not n:
                continue
            obj = bpy.data.objects.get(n)
            (out if obj is not None else missing).append(obj if obj is not None else n)
        return out, missing
    objs = list(getattr(context, "selected_objects", None) or [])
    active = getattr(context, "active_object", None)
    if active is not None and active not in objs:
        objs.append(active)
    return objs, []


def _assign(obj, mat):
    if obj.material_slots:
        obj.active_material = mat
    else:
        obj.data.materials.append(mat)


def refresh_curvature(objs):
    """Write the curvature attribute of each mesh; returns (done, problems)."""
    done, problems = [], []
    for obj in objs:
        if obj.type != "MESH":
            continue
        try:
            geometry.write_curvature(obj)
            done.append(obj.name)
        except geometry.MeshError as e:
            problems.append(str(e))
    return done, problems


class KNITSHADE_OT_add_material(bpy.types.Operator):
    """Give the selected objects a new Knit Fabric material (Cycles with OSL renders it)"""

    bl_idname = "knitshade.add_material"
    bl_label = "Add Knit Fabric"
    bl_options = {"REGISTER", "UNDO"}

    name: StringProperty(name="Name", default=nodes.MATERIAL_NAME)
    objects: StringProperty(name="Objects", description="Object names, comma separated (default: the "
                            "selected objects)", options={"SKIP_SAVE"})
    preset: EnumProperty(name="Pattern", items=_PRESET_ITEMS, default=PRESET_DEFAULT,
                         description="Pattern preset")
    pattern: StringProperty(name="Pattern Text", description="Pattern as text (.knit format); used instead of "
                            "the preset when given", options={"SKIP_SAVE"})
    yarn_weight: EnumProperty(name="Yarn Weight", items=_WEIGHT_ITEMS, default=WEIGHT_DEFAULT,
                              description="Sets a, h, d, r, the ply count and the gauge")
    a: FloatProperty(name="Loop Roundness (a)", default=1.5, options={"SKIP_SAVE"})
    h: FloatProperty(name="Loop Height (h)", default=4.0, options={"SKIP_SAVE"})
    d: FloatProperty(name="Loop Depth (d)", default=1.0, options={"SKIP_SAVE"})
    r: FloatProperty(name="Yarn Radius (r)", default=0.65, options={"SKIP_SAVE"})
    uv_scale: FloatProperty(name="UV Scale", description="Pattern units per UV unit (default: from the "
                            "gauge and the object's size)", default=0.0, min=0.0, options={"SKIP_SAVE"})
    stitches_per_10cm: FloatProperty(name="Stitches per 10 cm", description="Gauge (default: the yarn "
                                     "weight's)", default=18.0, min=0.5, max=200.0, options={"SKIP_SAVE"})
    colour: FloatVectorProperty(name="Yarn Colour", subtype="COLOR", size=3, min=0.0, soft_max=1.0,
                                default=(0.5, 0.36, 0.25), options={"SKIP_SAVE"})
    contrast_colour: FloatVectorProperty(name="Contrast Colour", subtype="COLOR", size=3, min=0.0,
                                         soft_max=1.0, default=(0.8, 0.78, 0.72), options={"SKIP_SAVE"})

    def execute(self, context):
        objs, missing = _objects(context, self.objects)
        if missing:
            self.report({"ERROR"}, "Add Knit Fabric: no object named %s" % ", ".join("'%s'" % m for m in missing))
            return {"CANCELLED"}
        unfit = [o.name for o in objs if not hasattr(o.data, "materials")]
        objs = [o for o in objs if hasattr(o.data, "materials")]
        try:
            if self.pattern:
                pat = kpattern.parse_text(self.pattern, "<pattern>")
            else:
                pat = kpresets.load_preset(self.preset) if self.preset else nodes.default_pattern()
        except kpattern.PatternError as e:
            self.report({"ERROR"}, "Add Knit Fabric: pattern refused: %s" % e)
            return {"CANCELLED"}
        props = self.properties
        w = kpresets.yarn_weight(self.yarn_weight or nodes.DEFAULT_YARN_WEIGHT)
        values = {"A": w["a"], "H": w["h"], "D": w["d"], "R": w["r"], "PlyCount": w["ply_count"]}
        for n in ("a", "h", "d", "r"):
            if props.is_property_set(n):
                values[n.upper()] = getattr(self, n)
        if props.is_property_set("colour"):
            values["Yarn0"] = tuple(self.colour)
        if props.is_property_set("contrast_colour"):
            values["Yarn1"] = tuple(self.contrast_colour)
        gauge = self.stitches_per_10cm if props.is_property_set("stitches_per_10cm") else w["stitches_per_10cm"]
        if props.is_property_set("uv_scale") and self.uv_scale > 0:
            values["UVScale"] = self.uv_scale
        else:
            meshes = [o for o in objs if geometry.has_uvs(o)]
            active = getattr(context, "active_object", None)
            probe = active if active in meshes else (meshes[0] if meshes else None)
            m = geometry.metres_per_uv_unit(probe, context.scene) if probe is not None else None
            values["UVScale"] = kpresets.uv_scale_for_gauge(gauge, m or nodes.DEFAULT_METRES_PER_UV)
        values = {k: v for k, v in values.items() if any(p.name == k for p in nodes.params())}
        defaults = nodes.defaults()
        try:
            values = settings.check(values, lambda n: defaults[n])
        except ValueError as e:
            self.report({"ERROR"}, "Add Knit Fabric: refused: %s" % e)
            return {"CANCELLED"}
        msgs = []

        def collect(kind, text):
            msgs.append((kind, text))

        try:
            mat = nodes.new_material(pat, values, self.name or nodes.MATERIAL_NAME, report=collect)
        except (kshader.ShaderError, nodes.KnitError) as e:
            self.report({"ERROR"}, "Add Knit Fabric: %s" % e)
            return {"CANCELLED"}
        for obj in objs:
            _assign(obj, mat)
        done, problems = refresh_curvature(objs)
        changed, warnings = nodes.ensure_scene_renders_osl(context.scene)
        where = ", ".join(o.name for o in objs) if objs else "no object (none selected)"
        line = "Knit Fabric '%s' on %s" % (mat.name, where)
        if changed:
            line += "; " + ", ".join(changed)
        self.report({"INFO"}, line)
        for kind, text in msgs:
            if "ERROR" in kind:
                self.report({"WARNING"}, text)
        if unfit:
            self.report({"WARNING"}, "%s cannot hold materials" % ", ".join(unfit))
        for p in problems:
            self.report({"WARNING"}, p)
        for wtext in warnings:
            self.report({"WARNING"}, wtext)
        return {"FINISHED"}


class KNITSHADE_OT_add_node(bpy.types.Operator):
    """Add a Knit Fabric node (a new node group with its own pattern)"""

    bl_idname = "knitshade.add_node"
    bl_label = "Knit Fabric"
    bl_options = {"REGISTER", "UNDO"}

    location: FloatVectorProperty(name="Location", size=2, default=(0.0, 0.0), options={"SKIP_SAVE"})

    @classmethod
    def poll(cls, context):
        space = getattr(context, "space_data", None)
        return space is not None and getattr(space, "tree_type", "") == "ShaderNodeTree" \
            and space.edit_tree is not None

    def _make(self, context):
        msgs = []
        tree = nodes.new_group(report=lambda k, t: msgs.append((k, t)))
        changed, warnings = nodes.ensure_scene_renders_osl(context.scene)
        return tree, changed, warnings

    def invoke(self, context, _event):
        tree, changed, warnings = self._make(context)
        for n in context.space_data.edit_tree.nodes:
            n.select = False
        bpy.ops.node.add_node("INVOKE_DEFAULT", type="ShaderNodeGroup", use_transform=True,
                              settings=[{"name": "node_tree", "value": "bpy.data.node_groups[%r]" % tree.name}])
        self._finish(context, tree, changed, warnings)
        return {"FINISHED"}

    def execute(self, context):
        tree, changed, warnings = self._make(context)
        edit = context.space_data.edit_tree
        node = edit.nodes.new("ShaderNodeGroup")
        node.node_tree = tree
        node.location = self.location
        edit.nodes.active = node
        self._finish(context, tree, changed, warnings)
        return {"FINISHED"}

    def _finish(self, context, tree, changed, warnings):
        edit = context.space_data.edit_tree
        node = edit.nodes.active
        if node is not None and node.bl_idname == "ShaderNodeGroup" and node.node_tree == tree:
            node.name = node.label = nodes.GROUP_NAME
            node.width = 240
            vals = nodes.defaults()
            for p in nodes.params():
                if p.name in vals:
                    nodes.set_value(node, p.name, vals[p.name])
        material = getattr(context, "material", None) or getattr(context.space_data, "id", None)
        if isinstance(material, bpy.types.Material):
            compat.knit_cycles_material_settings(material)
        self.report({"INFO"}, "Knit Fabric node added" + ("; " + ", ".join(changed) if changed else ""))
        for wtext in warnings:
            self.report({"WARNING"}, wtext)


class KNITSHADE_OT_refresh_curvature(bpy.types.Operator):
    """Compute the mesh curvature the knit shader bends its stitches with (needed after the mesh changes shape)"""

    bl_idname = "knitshade.refresh_curvature"
    bl_label = "Refresh Curvature"
    bl_options = {"REGISTER", "UNDO"}

    objects: StringProperty(name="Objects", description="Object names, comma separated (default: the "
                            "selected objects)", options={"SKIP_SAVE"})

    def execute(self, context):
        objs, missing = _objects(context, self.objects)
        if missing:
            self.report({"ERROR"}, "Refresh Curvature: no object named %s" % ", ".join("'%s'" % m for m in missing))
            return {"CANCELLED"}
        if not objs:
            self.report({"ERROR"}, "Refresh Curvature: no object selected")
            return {"CANCELLED"}
        done, problems = refresh_curvature(objs)
        if not done:
            why = "; ".join(problems) or "%s: not a mesh" % ", ".join(o.name for o in objs)
            self.report({"ERROR"}, "Refresh Curvature: " + why)
            return {"CANCELLED"}
        for p in problems:
            self.report({"WARNING"}, p)
        self.report({"INFO"}, "Curvature refreshed on %s" % ", ".join(done))
        return {"FINISHED"}


class KNITSHADE_OT_compile(_Target, bpy.types.Operator):
    """Write the shader text again from the pattern, repair the group's sockets and links, and compile it where this Blender has OSL"""

    bl_idname = "knitshade.compile"
    bl_label = "Recompile Shader"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        try:
            mat, _node, tree = self.target(context)
            added = nodes.repair_group(tree)
        except (KnitTargetError, kpattern.PatternError, kshader.ShaderError, nodes.KnitError) as e:
            return self.fail(str(e))
        msgs = []
        ok = nodes.ensure_compiled(tree, lambda k, t: msgs.append((k, t)))
        extra = " (added %s)" % ", ".join(added) if added else ""
        if ok:
            self.report({"INFO"}, "%s: shader compiled%s" % (mat.name, extra))
            return {"FINISHED"}
        if not compat.with_osl():
            self.report({"WARNING"}, "%s: shader text rewritten%s, not compiled: %s"
                        % (mat.name, extra, nodes.NO_OSL_MESSAGE))
            return {"FINISHED"}
        errors = "; ".join(t for k, t in msgs if "ERROR" in k) or "see the console"
        return self.fail("%s: the shader did not compile: %s" % (mat.name, errors), mat)


# ---- editor state (interface only, no undo) -------------------------------

class KNITSHADE_OT_page(bpy.types.Operator):
    """Show another page of a large pattern"""

    bl_idname = "knitshade.page"
    bl_label = "Pattern Page"
    bl_options = {"INTERNAL"}

    rows: IntProperty(name="Rows", default=0)
    cols: IntProperty(name="Columns", default=0)
    max_row: IntProperty(default=0, options={"HIDDEN", "SKIP_SAVE"})
    max_col: IntProperty(default=0, options={"HIDDEN", "SKIP_SAVE"})

    def execute(self, context):
        ed = _editor(context)
        if ed is None:
            return {"CANCELLED"}
        ed.page_row = max(0, min(ed.page_row + self.rows, self.max_row))
        ed.page_col = max(0, min(ed.page_col + self.cols, self.max_col))
        return {"FINISHED"}


class KNITSHADE_OT_brush(bpy.types.Operator):
    """Choose the yarn colour the Colour tool paints"""

    bl_idname = "knitshade.brush"
    bl_label = "Brush Colour"
    bl_options = {"INTERNAL"}

    colour: IntProperty(name="Colour", min=0, max=7)

    def execute(self, context):
        ed = _editor(context)
        if ed is None:
            return {"CANCELLED"}
        ed.colour = self.colour
        ed.tool = "COLOUR"
        return {"FINISHED"}


class KNITSHADE_MT_pattern_presets(bpy.types.Menu):
    bl_idname = "KNITSHADE_MT_pattern_presets"
    bl_label = "Pattern Presets"

    def draw(self, context):
        layout = self.layout
        for ident, name, desc in _PRESET_ITEMS:
            layout.operator(KNITSHADE_OT_load_preset.bl_idname, text=name).preset = ident


class KNITSHADE_MT_yarn_weights(bpy.types.Menu):
    bl_idname = "KNITSHADE_MT_yarn_weights"
    bl_label = "Yarn Weights"

    def draw(self, context):
        layout = self.layout
        for ident, name, desc in _WEIGHT_ITEMS:
            layout.operator(KNITSHADE_OT_yarn_weight.bl_idname, text=name).weight = ident


classes = (
    KNITSHADE_OT_add_material,
    KNITSHADE_OT_add_node,
    KNITSHADE_OT_paint_cell,
    KNITSHADE_OT_fill,
    KNITSHADE_OT_shift,
    KNITSHADE_OT_mirror,
    KNITSHADE_OT_flip,
    KNITSHADE_OT_resize,
    KNITSHADE_OT_insert_row,
    KNITSHADE_OT_remove_row,
    KNITSHADE_OT_insert_column,
    KNITSHADE_OT_remove_column,
    KNITSHADE_OT_clear_colours,
    KNITSHADE_OT_load_preset,
    KNITSHADE_OT_set_pattern,
    KNITSHADE_OT_import_pattern,
    KNITSHADE_OT_export_pattern,
    KNITSHADE_OT_make_single_user,
    KNITSHADE_OT_set_stitch,
    KNITSHADE_OT_yarn_weight,
    KNITSHADE_OT_gauge,
    KNITSHADE_OT_refresh_curvature,
    KNITSHADE_OT_compile,
    KNITSHADE_OT_page,
    KNITSHADE_OT_brush,
    KNITSHADE_MT_pattern_presets,
    KNITSHADE_MT_yarn_weights,
)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(classes):
        try:
            bpy.utils.unregister_class(cls)
        except RuntimeError:
            pass

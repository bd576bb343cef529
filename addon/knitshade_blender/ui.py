"""Panels: Knit Fabric in the material tab and in the shader editor's sidebar.

Both show the same sub-panels (the pattern editor, the stitch, the yarn
colours, appearance, plies and fibres, quality), drawn by the functions
below from the material and its Knit Fabric node. The pattern editor shows
the pattern as a grid of buttons, a page of at most `page_size` x
`page_size` cells at a time; a pattern larger than a page is shown whole as
an overview image (a custom preview icon, cached per pattern) with the page
marked, so drawing never walks more than one page of cells.
"""
import math

import bpy

from . import compat, native, nodes, props, settings
from .core import pattern as kpattern
from .core import shader as kshader

# Which settings each sub-panel shows; settings of a newer shader that are
# in none of these are shown under Quality.
GROUPS = (
    ("stitch", ("A", "H", "D", "R", "UVScale")),
    ("colours", tuple("Yarn%d" % i for i in range(8)) + ("TransmitTint",)),
    ("appearance", ("Roughness", "RoughnessAcross", "IOR", "BodyEnergy", "BodyReflect", "OpticalDepth")),
    ("detail", ("PlyDetail", "PlyCount", "PlyTwist", "FiberCount", "FiberTwist")),
    ("quality", ("Mode", "FootprintPoints", "CAPM", "CapmSteps")),
)

STITCH_SHADE = (1.0, 0.55, 1.25, 0.75)  # K, P, F, B in the overview image

_previews = None
_pattern_cache = {}  # tree name -> (storage text, Pattern)
_overview_key = {}  # tree name -> what the overview image shows


def _grouped():
    listed = {n for _g, names in GROUPS for n in names}
    return [p.name for p in nodes.params() if p.name not in listed]


def cached_pattern(tree):
    """The group's pattern, parsed once per change (not per redraw)."""
    text = tree.get(nodes.PATTERN_KEY)
    hit = _pattern_cache.get(tree.name_full)
    if hit is not None and hit[0] == text:
        return hit[1]
    pat = nodes.get_pattern(tree)
    if len(_pattern_cache) > 32:
        _pattern_cache.clear()
    _pattern_cache[tree.name_full] = (text, pat)
    return pat


def _srgb(c):
    c = max(0.0, min(1.0, c))
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


def _palette(node):
    out = []
    for i in range(kshader.PALETTE_SIZE):
        try:
            out.append(tuple(_srgb(x) for x in nodes.get_value(node, "Yarn%d" % i)))
        except KeyError:
            out.append((0.5, 0.5, 0.5))
    return out


def swatch_icon(rgb):
    """A preview icon filled with an sRGB colour (for the palette and the grid)."""
    if _previews is None:
        return 0
    key = "swatch_%02x%02x%02x" % tuple(int(round(255 * c)) for c in rgb)
    pv = _previews.get(key)
    if pv is None:
        pv = _previews.new(key)
        n = 16
        px = list(rgb) + [1.0]
        pv.icon_size = (n, n)
        pv.icon_pixels_float = px * (n * n)
        pv.image_size = (n, n)
        pv.image_pixels_float = px * (n * n)
    return pv.icon_id


def overview_icon(tree, pat, node, page):
    """A preview icon showing the whole pattern (each stitch's yarn colour,
    darker for purl), the current page outlined; made again only when the
    pattern, the colours or the page change."""
    if _previews is None:
        return 0
    import numpy as np

    palette = _palette(node)
    key = (tree.get(nodes.PATTERN_KEY), tuple(palette), page)
    name = "overview_" + tree.name_full
    pv = _previews.get(name)
    if pv is not None and _overview_key.get(name) == key:
        return pv.icon_id
    if pv is None:
        pv = _previews.new(name)
    rows, cols = pat.rows, pat.cols
    codes = np.asarray(pat.codes, dtype=np.int32).reshape(rows, cols)
    colours = np.asarray(pat.colors_or_zero(), dtype=np.int32).reshape(rows, cols)
    colours = np.minimum(colours, len(palette) - 1)
    rgb = np.asarray(palette, dtype=np.float32)[colours] * np.asarray(STITCH_SHADE, dtype=np.float32)[codes][..., None]
    side = max(rows, cols)
    scale = max(1, 128 // side)
    img = np.full((side * scale, side * scale, 4), 0.18, dtype=np.float32)
    img[..., 3] = 1.0
    cells = np.repeat(np.repeat(np.clip(rgb, 0, 1), scale, 0), scale, 1)
    img[:rows * scale, :cols * scale, :3] = cells
    r0, c0, r1, c1 = page
    if (r1 - r0, c1 - c0) != (rows, cols):
        y0, y1, x0, x1 = r0 * scale, max(r0 * scale, r1 * scale - 1), c0 * scale, max(c0 * scale, c1 * scale - 1)
        line = max(1, (side * scale) // 64)
        for sl in (np.s_[y0:y0 + line, x0:x1 + 1], np.s_[max(y1 - line + 1, 0):y1 + 1, x0:x1 + 1],
                   np.s_[y0:y1 + 1, x0:x0 + line], np.s_[y0:y1 + 1, max(x1 - line + 1, 0):x1 + 1]):
            img[sl + (slice(0, 3),)] = (1.0, 0.85, 0.1)
    img = img[::-1]  # Blender's pixels start at the bottom row
    n = img.shape[0]
    flat = img.ravel().tolist()
    pv.image_size = (n, n)
    pv.image_pixels_float = flat
    pv.icon_size = (n, n)
    pv.icon_pixels_float = flat
    _overview_key[name] = key
    return pv.icon_id


# ---- drawing -------------------------------------------------------------

def _target(context, space):
    """(material, Knit Fabric node) for a panel, or (material, None)."""
    if space == "PROPERTIES":
        mat = getattr(context, "material", None)
        return mat, nodes.knit_node(mat) if mat is not None else None
    sp = context.space_data
    mat = sp.id if isinstance(getattr(sp, "id", None), bpy.types.Material) else None
    node = getattr(context, "active_node", None)
    if mat is None or not nodes.is_knit_node(node) or node.id_data != mat.node_tree:
        return mat, None
    return mat, node


def _set_pointers(layout, mat, node):
    layout.context_pointer_set("knitshade_material", mat)
    layout.context_pointer_set("knitshade_node", node)


def _op(layout, idname, mat, node, **kw):
    op = layout.operator(idname, **kw)
    op.material = mat.name
    op.node = node.name
    return op


def draw_status(layout, context, mat, node):
    """What stands between this material and a render, and the last refusal."""
    msg = mat.knitshade.message if hasattr(mat, "knitshade") else ""
    if msg:
        box = layout.box()
        box.alert = True
        _wrapped(box, msg, icon="ERROR")
    if props.LOAD_ERROR:
        box = layout.box()
        box.alert = True
        _wrapped(box, "Knit Fabric is not installed completely: " + props.LOAD_ERROR, icon="ERROR")
    if not compat.with_osl():
        box = layout.box()
        _wrapped(box, "No OSL in this Blender: the knit shader does not render here.", icon="ERROR")
        _wrapped(box, "Open the file once in Blender 4.2+ with this add-on to compile it, or use yarn "
                      "geometry (docs/blender.md).", icon="BLANK1")
    else:
        scene = context.scene
        cs = getattr(scene, "cycles", None)
        if scene.render.engine != "CYCLES" or cs is None or not cs.shading_system:
            box = layout.box()
            _wrapped(box, "Renders only in Cycles with Open Shading Language on", icon="INFO")
            box.operator("knitshade.setup_scene", text="Use Cycles OSL")
        else:
            ok, why = compat.cycles_device_runs_osl(scene)
            if not ok:
                box = layout.box()
                _wrapped(box, why, icon="ERROR")
                box.operator("knitshade.setup_scene", text="Use CPU")
        if node is not None and nodes.needs_compile(node.node_tree):
            row = layout.row()
            row.label(text="Shader not compiled yet", icon="TIME")
            _op(row, "knitshade.compile", mat, node, text="Compile")
    if node is not None:
        users = nodes.materials_using(node.node_tree)
        if len(users) > 1:
            row = layout.row()
            row.label(text="Shared by %d materials" % len(users), icon="LINKED")
            _op(row, "knitshade.make_single_user", mat, node, text="Single User")


def _wrapped(layout, text, icon="NONE"):
    """`text` as labels that fit the region's width (Blender cuts a long
    label in the middle)."""
    region = getattr(bpy.context, "region", None)
    scale = bpy.context.preferences.system.ui_scale or 1.0
    width = max(16, int(((region.width if region else 400) - 70) / (7.0 * scale)))
    col = layout.column(align=True)
    words, line, first = text.split(), "", True
    indent = "BLANK1" if icon != "NONE" else "NONE"
    for w in words:
        if line and len(line) + 1 + len(w) > width:
            col.label(text=line, icon=icon if first else indent)
            first, line = False, w
        else:
            line = (line + " " + w) if line else w
    if line:
        col.label(text=line, icon=icon if first else indent)


def draw_settings(layout, mat, names):
    layout.use_property_split = True
    layout.use_property_decorate = False
    settings_pg = mat.knitshade
    col = layout.column()
    for name in names:
        attr = settings.snake(name)
        if hasattr(settings_pg, attr):
            col.prop(settings_pg, attr)


def draw_stitch(layout, context, mat, node):
    row = layout.row(align=True)
    row.menu("KNITSHADE_MT_yarn_weights", text="Weight", icon="PRESET")
    _op(row, "knitshade.gauge", mat, node, text="Gauge", icon="DRIVER_DISTANCE")
    draw_settings(layout, mat, GROUPS[0][1])
    per_uv = nodes.get_value(node, "UVScale") / (2.0 * math.pi)  # a stitch is 2 pi pattern units wide
    layout.label(text="%.1f stitches per UV unit" % per_uv, icon="UV")


def draw_colours(layout, context, mat, node):
    pat = None
    try:
        pat = cached_pattern(node.node_tree)
    except kpattern.PatternError:
        pass
    used = max(1, min(kshader.PALETTE_SIZE, pat.num_colors if pat is not None else 1))
    layout.use_property_split = True
    layout.use_property_decorate = False
    col = layout.column()
    for i in range(kshader.PALETTE_SIZE):
        attr = "yarn%d" % i
        if hasattr(mat.knitshade, attr):
            r = col.row()
            r.active = i < used
            r.prop(mat.knitshade, attr, text="Colour %d" % i + ("" if i < used else " (unused)"))
    if hasattr(mat.knitshade, "transmit_tint"):
        col.prop(mat.knitshade, "transmit_tint")


def draw_editor(layout, context, mat, node):
    tree = node.node_tree
    ed = context.window_manager.knitshade_editor
    try:
        pat = cached_pattern(tree)
    except kpattern.PatternError as e:
        box = layout.box()
        box.alert = True
        _wrapped(box, "The stored pattern is damaged: %s" % e, icon="ERROR")
        return
    _set_pointers(layout, mat, node)

    row = layout.row(align=True)
    row.menu("KNITSHADE_MT_pattern_presets", text="Presets", icon="PRESET")
    _op(row, "knitshade.import_pattern", mat, node, text="", icon="IMPORT")
    _op(row, "knitshade.export_pattern", mat, node, text="", icon="EXPORT")

    row = layout.row(align=True)
    row.prop(ed, "tool", expand=True)
    palette = _palette(node)
    if ed.tool == "STITCH":
        layout.row(align=True).prop(ed, "stitch", expand=True)
    elif ed.tool == "COLOUR":
        prow = layout.row(align=True)
        for i in range(kshader.PALETTE_SIZE):
            op = prow.operator("knitshade.brush", text="", icon_value=swatch_icon(palette[i]),
                               depress=(i == ed.colour))
            op.colour = i

    rows, cols = pat.rows, pat.cols
    size = max(1, ed.page_size)
    paged = rows > size or cols > size
    r0 = min(ed.page_row, max(0, rows - size)) if paged else 0
    c0 = min(ed.page_col, max(0, cols - size)) if paged else 0
    r1, c1 = min(rows, r0 + size), min(cols, c0 + size)

    info = layout.row()
    info.label(text="%d x %d" % (rows, cols), icon="MESH_GRID")
    info.prop(ed, "page_size", text="Page")
    if paged:
        box = layout.box()
        split = box.split(factor=0.5)
        split.template_icon(icon_value=overview_icon(tree, pat, node, (r0, c0, r1, c1)), scale=8.0)
        nav = split.column(align=True)
        nav.label(text="Rows %d-%d" % (r0 + 1, r1))
        nav.label(text="Columns %d-%d" % (c0 + 1, c1))
        arrows = nav.row(align=True)
        for icon, dr, dc in (("TRIA_LEFT", 0, -size), ("TRIA_UP", -size, 0),
                             ("TRIA_DOWN", size, 0), ("TRIA_RIGHT", 0, size)):
            op = arrows.operator("knitshade.page", text="", icon=icon)
            op.rows, op.cols = dr, dc
            op.max_row, op.max_col = max(0, rows - size), max(0, cols - size)
        nav.prop(ed, "page_row", text="Row")
        nav.prop(ed, "page_col", text="Column")

    grid = layout.column(align=True)
    codes, colours = pat.codes, pat.colors_or_zero()
    colour_mode = ed.tool == "COLOUR"
    # cells show their yarn colour (a swatch) where the pattern has colours,
    # and only the swatch when painting colours
    region = getattr(context, "region", None)
    scale = context.preferences.system.ui_scale or 1.0
    room = ((region.width if region else 400) - 40) / max(1, c1 - c0) / scale  # pixels a cell
    tinted = colour_mode or (ed.show_colours and pat.has_colors and room >= 34)
    swatches = [swatch_icon(c) for c in palette] if tinted else None
    letters = kpattern.LETTERS
    tool, stitch, brush = ed.tool, ed.stitch, ed.colour
    last = kshader.PALETTE_SIZE - 1
    for r in range(r0, r1):
        line = grid.row(align=True)
        base = r * cols
        for c in range(c0, c1):
            code = codes[base + c]
            if tinted:
                icon = swatches[min(colours[base + c], last)]
                op = line.operator("knitshade.paint_cell", text="" if colour_mode else letters[code],
                                   icon_value=icon, depress=code == 1 and not colour_mode)
            else:
                op = line.operator("knitshade.paint_cell", text=letters[code], depress=code == 1)
            op.row = r
            op.col = c
            op.tool = tool
            op.stitch = stitch
            op.colour = brush
    opts = layout.row()
    opts.prop(ed, "show_colours")

    col = layout.column(align=True)
    row = col.row(align=True)
    row.label(text="Row %d" % (ed.cursor_row + 1))
    row.operator("knitshade.insert_row", text="", icon="ADD")
    row.operator("knitshade.remove_row", text="", icon="REMOVE")
    row.separator()
    row.label(text="Col %d" % (ed.cursor_col + 1))
    row.operator("knitshade.insert_column", text="", icon="ADD")
    row.operator("knitshade.remove_column", text="", icon="REMOVE")
    row = col.row(align=True)
    for icon, dx, dy in (("TRIA_LEFT", -1, 0), ("TRIA_RIGHT", 1, 0), ("TRIA_UP", 0, -1), ("TRIA_DOWN", 0, 1)):
        op = row.operator("knitshade.shift", text="", icon=icon)
        op.dx, op.dy = dx, dy
    row.separator()
    row.operator("knitshade.mirror", text="", icon="MOD_MIRROR")
    row.operator("knitshade.flip", text="", icon="UV_SYNC_SELECT")
    row.separator()
    row.operator("knitshade.fill", text="", icon="SNAP_FACE")
    row.operator("knitshade.clear_colours", text="", icon="X")
    row.operator("knitshade.resize", text="", icon="FULLSCREEN_ENTER")


def draw_native(layout):
    col = layout.column(align=True)
    if native.AVAILABLE:
        col.label(text=native.status(), icon="CHECKMARK")
        return
    _wrapped(col, native.status(), icon="INFO")
    col.label(text="It would add:")
    for line in native.ADDS:
        _wrapped(col, "- " + line)
    _wrapped(col, "To get it: " + native.HOW_TO_GET + ".")


# ---- panels --------------------------------------------------------------

class _Base:
    space = "PROPERTIES"

    @classmethod
    def poll(cls, context):
        mat, node = _target(context, cls.space)
        return mat is not None and node is not None


def _panel_classes(space):
    if space == "PROPERTIES":
        where = dict(bl_space_type="PROPERTIES", bl_region_type="WINDOW", bl_context="material")
        prefix = "KNITSHADE_PT_material"
    else:
        # in the sidebar's Node tab, under the active node's own panels
        where = dict(bl_space_type="NODE_EDITOR", bl_region_type="UI", bl_category="Node")
        prefix = "KNITSHADE_PT_node"

    def main_poll(cls, context):
        if space == "PROPERTIES":
            return getattr(context, "material", None) is not None or getattr(context, "object", None) is not None
        if getattr(context.space_data, "tree_type", "") != "ShaderNodeTree":
            return False
        mat, node = _target(context, space)
        return node is not None

    def main_draw(self, context):
        layout = self.layout
        mat, node = _target(context, space)
        if node is None:
            if mat is not None and not props.LOAD_ERROR:
                layout.label(text="This material has no Knit Fabric node", icon="INFO")
            layout.operator("knitshade.add_material", icon="MOD_CLOTH")
            if not compat.with_osl():
                _wrapped(layout.box(), nodes.NO_OSL_MESSAGE, icon="ERROR")
            return
        draw_status(layout, context, mat, node)
        row = layout.row(align=True)
        row.operator("knitshade.refresh_curvature", text="Curvature", icon="MOD_SMOOTH")
        _op(row, "knitshade.compile", mat, node, text="Recompile", icon="FILE_REFRESH")

    main = type(prefix, (bpy.types.Panel,), dict(
        where, bl_idname=prefix, bl_label="Knit Fabric", poll=classmethod(main_poll), draw=main_draw,
        bl_order=0 if space != "PROPERTIES" else 1))

    def sub(suffix, label, fn, closed=False, order=0):
        def draw(self, context):
            mat, node = _target(context, space)
            if node is None:
                return
            fn(self.layout, context, mat, node)
        opts = {"DEFAULT_CLOSED"} if closed else set()
        return type(prefix + "_" + suffix, (_Base, bpy.types.Panel), dict(
            where, bl_idname=prefix + "_" + suffix, bl_label=label, bl_parent_id=prefix, bl_options=opts,
            draw=draw, space=space, bl_order=order))

    def settings_fn(group):
        def fn(layout, context, mat, node):
            names = dict(GROUPS)[group]
            if group == "quality":
                names = names + tuple(_grouped())
            draw_settings(layout, mat, names)
        return fn

    def native_draw(self, context):
        draw_native(self.layout)

    native_panel = type(prefix + "_native", (bpy.types.Panel,), dict(
        where, bl_idname=prefix + "_native", bl_label="Native Module", bl_parent_id=prefix,
        bl_options={"DEFAULT_CLOSED"}, draw=native_draw, bl_order=9))

    return [
        main,
        sub("pattern", "Pattern", draw_editor, order=1),
        sub("stitch", "Stitch", draw_stitch, order=2),
        sub("colours", "Yarn Colours", draw_colours, order=3),
        sub("appearance", "Yarn Appearance", settings_fn("appearance"), closed=True, order=4),
        sub("detail", "Plies and Fibres", settings_fn("detail"), closed=True, order=5),
        sub("quality", "Quality", settings_fn("quality"), closed=True, order=6),
        native_panel,
    ]


class KNITSHADE_OT_setup_scene(bpy.types.Operator):
    """Render this scene with Cycles, its Open Shading Language on, on a device that runs OSL"""

    bl_idname = "knitshade.setup_scene"
    bl_label = "Set Up Cycles OSL"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        changed, warnings = nodes.ensure_scene_renders_osl(context.scene)
        self.report({"INFO"}, "%s: %s" % (context.scene.name, ", ".join(changed) if changed else "already set"))
        for w in warnings:
            self.report({"WARNING"}, w)
        return {"FINISHED"}


_classes = []


def register():
    global _previews
    from bpy.utils import previews
    _previews = previews.new()
    _pattern_cache.clear()
    _overview_key.clear()
    _classes[:] = [KNITSHADE_OT_setup_scene] + _panel_classes("PROPERTIES") + _panel_classes("NODE_EDITOR")
    for cls in _classes:
        bpy.utils.register_class(cls)


def unregister():
    global _previews
    for cls in reversed(_classes):
        try:
            bpy.utils.unregister_class(cls)
        except RuntimeError:
            pass
    _classes.clear()
    if _previews is not None:
        from bpy.utils import previews
        previews.remove(_previews)
        _previews = None
    _pattern_cache.clear()
    _overview_key.clear()

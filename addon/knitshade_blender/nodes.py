"""The Knit Fabric node group: plain Blender data that renders without the add-on.

A Knit Fabric material's node tree holds a group node whose node group
("Knit Fabric", one per pattern) contains

    Group Input ──(every setting)──► Script node "Knit Shader" ──► Group Output
    UV Map ──UV──────────────────────►  (INTERNAL text: the generated,
    Attribute "knit_curvature" ──────►   self-contained shader for the
                                          group's pattern)

The group carries, as ID properties,
  knitshade          {"format": 1}: marks a Knit Fabric group;
  knitshade_pattern  the pattern in core.pattern's storage form;
  knitshade_sockets  {parameter name: group input identifier} and
                     {output name: group output identifier}: sockets are
                     found by identifier, so an artist may rename them;
  knitshade_compiled the MD5 of the shader text whose bytecode the Script
                     node holds ("" when it holds none).

Where Cycles has OSL the Script node is compiled with Cycles' own
update_script_node: the bytecode is stored in the node, so the saved .blend
renders on a machine without the add-on, and Cycles makes the node's
sockets. Without OSL (Debian's Blender 3.4) the add-on makes the same
sockets itself from core.shader.PARAMS and OUTPUTS, so the group is whole;
opening the file once in a Blender with OSL and the add-on compiles it
(the load_post handler below).

Settings that are sockets (colours, a, h, d, r, UV scale, ...) live on the
group node's inputs in the material: changing one never touches the
shader. Changing the pattern writes the shader text once per edit. In the
interface the operators compile it after a short pause (a run of clicks
compiles once; a save in the pause compiles first); in background
Blender (scripts, farms: no timers run there) and from the Python API it
compiles at once.
"""
import hashlib

import bpy
from bpy.app.handlers import persistent

from . import compat
from .core import pattern as kpattern
from .core import presets as kpresets
from .core import shader as kshader

GROUP_NAME = "Knit Fabric"
MATERIAL_NAME = "Knit Fabric"
FORMAT = 1

MARK = "knitshade"
PATTERN_KEY = "knitshade_pattern"
SOCKETS_KEY = "knitshade_sockets"
COMPILED_KEY = "knitshade_compiled"

SCRIPT_NODE = "Knit Shader"
UV_NODE = "Knit UV"
CURVATURE_NODE = "Knit Curvature"
INPUT_NODE = "Group Input"
OUTPUT_NODE = "Group Output"

DEFAULT_PRESET = "stockinette"
DEFAULT_YARN_WEIGHT = "worsted"  # the library's a, h, d, r
# A default 2 m plane unwrapped to one UV square, at the default yarn's
# gauge (worsted: 18 stitches to 10 cm): 2 pi * 18 * 10 * 2 = 2262.
DEFAULT_METRES_PER_UV = 2.0

COMPILE_DELAY = 0.4  # seconds of quiet after an edit from the editor before compiling
# Background Blender runs no timers, so an operator's edit compiles at once
# there. A script making many edits may turn this off and compile once at
# the end (api.compile_shader; a save compiles what waits).
compile_edits_in_background = True


class KnitError(ValueError):
    """Something about a Knit Fabric material the artist must be told."""


# ---- parameters ----------------------------------------------------------

def params():
    """The shader's settings that are group inputs (all but the linked UV and
    Curvature), in the shader's order."""
    return [p for p in kshader.PARAMS if not p.linked]


def param(name):
    for p in kshader.PARAMS:
        if p.name == name:
            return p
    raise KeyError(name)


def default_uv_scale():
    w = kpresets.yarn_weight(DEFAULT_YARN_WEIGHT)
    return kpresets.uv_scale_for_gauge(w["stitches_per_10cm"], DEFAULT_METRES_PER_UV)


def defaults():
    """{parameter name: value} a new Knit Fabric starts with: the shader's
    defaults, the default yarn weight's stitch, and a UV scale that shows
    stitches of a real knit's size on a default 2 m plane."""
    out = {p.name: p.default for p in params()}
    w = kpresets.yarn_weight(DEFAULT_YARN_WEIGHT)
    for key, name in (("a", "A"), ("h", "H"), ("d", "D"), ("r", "R"), ("ply_count", "PlyCount")):
        if name in out:
            out[name] = w[key]
    if "UVScale" in out:
        out["UVScale"] = default_uv_scale()
    return out


def default_pattern():
    try:
        return kpresets.load_preset(DEFAULT_PRESET)
    except (kpattern.PatternError, OSError):
        return kpattern.Pattern(4, 4)


# ---- finding Knit Fabric data --------------------------------------------

def is_knit_group(tree):
    return tree is not None and getattr(tree, "bl_idname", "") == "ShaderNodeTree" and tree.get(MARK) is not None


def is_knit_node(node):
    return node is not None and node.bl_idname == "ShaderNodeGroup" and is_knit_group(node.node_tree)


def knit_nodes(material):
    tree = getattr(material, "node_tree", None) if material is not None else None
    if tree is None:
        return []
    return [n for n in tree.nodes if is_knit_node(n)]


def knit_node(material, name=""):
    """The material's Knit Fabric group node: the one named `name`, else the
    active node if it is one, else the first; None when there is none."""
    nodes = knit_nodes(material)
    if not nodes:
        return None
    if name:
        for n in nodes:
            if n.name == name:
                return n
        return None
    active = material.node_tree.nodes.active
    if active is not None and active in nodes:
        return active
    return nodes[0]


def knit_groups():
    return [t for t in bpy.data.node_groups if is_knit_group(t)]


def materials_using(tree):
    return [m for m in bpy.data.materials if any(n.node_tree == tree for n in knit_nodes(m))]


def script_node(tree):
    n = tree.nodes.get(SCRIPT_NODE)
    if n is None:  # renamed by the artist: the one Script node
        n = next((x for x in tree.nodes if x.bl_idname == "ShaderNodeScript"), None)
    return n


# ---- the pattern ---------------------------------------------------------

def get_pattern(tree):
    """The group's pattern (PatternError if its storage was damaged)."""
    text = tree.get(PATTERN_KEY)
    if not isinstance(text, str):
        raise kpattern.PatternError(tree.name, 0, 0, "no pattern stored on this Knit Fabric group")
    return kpattern.Pattern.from_storage(text, tree.name)


def shader_text(pat):
    """The shader for `pat` (ShaderError for a pattern the shader cannot take)."""
    return kshader.osl_source(pat)


def text_hash(text):
    return hashlib.md5(text.encode("utf-8")).hexdigest()


def set_pattern(tree, pat, compile="now", report=None):
    """Store `pat` on the group and write its shader text; compile it now
    (compile="now"), after a pause ("later") or not at all (None). The
    shader text is made first, so a pattern it refuses (ShaderError) leaves
    the group as it was."""
    text = shader_text(pat)
    tree[PATTERN_KEY] = pat.to_storage()
    script = script_node(tree)
    if script is None:
        raise KnitError("%s: the group has no Script node (rebuild it with Recompile Shader)" % tree.name)
    if script.script is None:
        script.script = bpy.data.texts.new(tree.name + ".osl")
    if script.script.as_string() != text:
        script.script.from_string(text)
    if compile == "now":
        return ensure_compiled(tree, report)
    if compile == "later":
        if bpy.app.background and compile_edits_in_background:  # no timers: now, or not before a render
            return ensure_compiled(tree, report)
        if bpy.app.background:
            if compat.with_osl():
                _pending.add(tree.name)
            return None
        schedule_compile(tree)
    return None


# ---- building the group --------------------------------------------------

def _interface_defaults(sock, p, value):
    if p.kind in ("float", "int", "enum", "bool"):
        if p.kind == "enum":
            values = [it[2] for it in (p.items or ())] or [0]
            lo, hi = min(values), max(values)
        elif p.kind == "bool":
            lo, hi = 0, 1
        else:
            lo, hi = p.min, p.max
        if lo is not None:
            sock.min_value = lo
        if hi is not None:
            sock.max_value = hi
    if p.kind == "color":
        sock.default_value = tuple(value)[:3] + (1.0,)
    elif p.kind in ("point", "vector"):
        sock.default_value = tuple(value)
    elif p.kind in ("int", "enum", "bool"):  # (a bool is a 0/1 integer input: compat.GROUP_SOCKET_TYPES)
        sock.default_value = int(value)
    else:
        sock.default_value = float(value)


def _make_interface(tree, values):
    ids = {}
    for name, kind, description in kshader.OUTPUTS:
        s = compat.new_group_socket(tree, "OUTPUT", compat.SOCKET_TYPES[kind], name, description)
        ids["out:" + name] = s.identifier
    for p in params():
        s = compat.new_group_socket(tree, "INPUT", compat.GROUP_SOCKET_TYPES[p.kind], p.label, p.description)
        _interface_defaults(s, p, values.get(p.name, p.default))
        ids[p.name] = s.identifier
    tree[SOCKETS_KEY] = ids


def _script_sockets_by_hand(script):
    """The sockets Cycles would make for the shader, for a Blender without
    OSL: identifier = parameter name, name = its label."""
    script.inputs.clear()
    script.outputs.clear()
    for p in kshader.PARAMS:
        s = script.inputs.new(compat.SOCKET_TYPES[p.kind], p.label, identifier=p.name)
        if p.kind == "color":
            s.default_value = tuple(p.default)[:3] + (1.0,)
        elif p.kind in ("point", "vector"):
            s.default_value = tuple(p.default)
        elif p.kind == "bool":
            s.default_value = bool(p.default)
        elif p.kind in ("int", "enum"):
            s.default_value = int(p.default)
        else:
            s.default_value = float(p.default)
    for name, kind, _description in kshader.OUTPUTS:
        script.outputs.new(compat.SOCKET_TYPES[kind], name, identifier=name)


def link_group(tree):
    """(Re)make every link inside the group, by socket identifier: settings
    from the Group Input, the UV and the curvature into the Script node, its
    outputs to the Group Output. Idempotent."""
    nodes = tree.nodes
    gin, gout = nodes.get(INPUT_NODE), nodes.get(OUTPUT_NODE)
    uv, curv, script = nodes.get(UV_NODE), nodes.get(CURVATURE_NODE), script_node(tree)
    ids = tree.get(SOCKETS_KEY) or {}
    missing = []

    def link(a, b, what):
        if a is None or b is None:
            missing.append(what)
            return
        if not any(lk.from_socket == a and lk.to_socket == b for lk in b.links):
            tree.links.new(a, b)

    if script is None:
        return ["Script node"]
    for p in kshader.PARAMS:
        dst = compat.socket_by_identifier(script.inputs, p.name)
        if p.name == "UV":
            link(uv.outputs.get("UV") if uv else None, dst, "UV")
        elif p.name == "Curvature":
            link(curv.outputs.get("Vector") if curv else None, dst, "Curvature")
        else:
            src = compat.socket_by_identifier(gin.outputs, ids.get(p.name, "")) if gin else None
            link(src, dst, p.name)
    for name, _kind, _d in kshader.OUTPUTS:
        src = compat.socket_by_identifier(script.outputs, name)
        dst = compat.socket_by_identifier(gout.inputs, ids.get("out:" + name, "")) if gout else None
        link(src, dst, name)
    return missing


def new_group(pat=None, values=None, name=GROUP_NAME, report=None):
    """A new Knit Fabric node group for `pat` (default: stockinette), its
    inputs defaulting to `values` ({parameter name: value}, over defaults()).
    Compiled where this Blender has OSL."""
    pat = pat if pat is not None else default_pattern()
    text = shader_text(pat)  # first: a pattern the shader refuses makes nothing
    vals = defaults()
    vals.update(values or {})
    tree = bpy.data.node_groups.new(name, "ShaderNodeTree")
    tree[MARK] = {"format": FORMAT}
    _make_interface(tree, vals)
    nodes = tree.nodes
    gin = nodes.new("NodeGroupInput")
    gin.name = INPUT_NODE
    gin.location = (-700, 0)
    gout = nodes.new("NodeGroupOutput")
    gout.name = OUTPUT_NODE
    gout.location = (400, 0)
    uv = nodes.new("ShaderNodeUVMap")
    uv.name = uv.label = UV_NODE
    uv.location = (-400, 350)  # uv_map "": the mesh's active render UV map
    curv = nodes.new("ShaderNodeAttribute")
    curv.name = curv.label = CURVATURE_NODE
    curv.attribute_type = "GEOMETRY"
    curv.attribute_name = kshader.CURVATURE_ATTRIBUTE
    curv.location = (-400, 200)
    script = nodes.new("ShaderNodeScript")
    script.name = script.label = SCRIPT_NODE
    script.location = (0, 0)
    script.width = 260
    script.mode = "INTERNAL"
    text_block = bpy.data.texts.new(tree.name + ".osl")
    text_block.from_string(text)
    script.script = text_block
    tree[PATTERN_KEY] = pat.to_storage()
    tree[COMPILED_KEY] = ""
    _script_sockets_by_hand(script)
    link_group(tree)
    ensure_compiled(tree, report)
    return tree


def repair_group(tree):
    """Bring a Knit Fabric group made by an older add-on (or edited by hand)
    up to date: missing inputs and outputs added, the Script node's text
    made from the stored pattern with this add-on's shader, every link
    made. Returns the names of what was added."""
    ids = dict(tree.get(SOCKETS_KEY) or {})
    have_in = {s.identifier for s in compat.group_sockets(tree, "INPUT")}
    have_out = {s.identifier for s in compat.group_sockets(tree, "OUTPUT")}
    added = []
    vals = defaults()
    for name, kind, description in kshader.OUTPUTS:
        if ids.get("out:" + name) not in have_out:
            s = compat.new_group_socket(tree, "OUTPUT", compat.SOCKET_TYPES[kind], name, description)
            ids["out:" + name] = s.identifier
            added.append(name)
    for p in params():
        if ids.get(p.name) not in have_in:
            s = compat.new_group_socket(tree, "INPUT", compat.GROUP_SOCKET_TYPES[p.kind], p.label,
                                        p.description)
            _interface_defaults(s, p, vals.get(p.name, p.default))
            ids[p.name] = s.identifier
            added.append(p.name)
    tree[SOCKETS_KEY] = ids
    script = script_node(tree)
    if script is None:
        raise KnitError("%s: the Script node is gone; add a new Knit Fabric instead" % tree.name)
    set_pattern(tree, get_pattern(tree), compile=None)
    if not compat.with_osl() or not script.bytecode:
        _script_sockets_by_hand(script)
    tree[COMPILED_KEY] = ""
    link_group(tree)
    return added


# ---- compiling -----------------------------------------------------------

def _quiet_report(kind, text):
    print("Knit Fabric: %s: %s" % ("/".join(sorted(kind)), text))


def needs_compile(tree):
    """Whether the Script node's bytecode is missing or stale (its text has
    changed since it was compiled)."""
    script = script_node(tree)
    if script is None or script.script is None:
        return False
    return not script.bytecode or tree.get(COMPILED_KEY) != text_hash(script.script.as_string())


def ensure_compiled(tree, report=None):
    """Compile the group's shader if this Blender has OSL and the bytecode is
    missing or stale. Returns True (compiled now or already), False (this
    Blender has no OSL, or compiling failed: the sockets made by hand stay,
    and `report` got Cycles' message)."""
    report = report or _quiet_report
    script = script_node(tree)
    if script is None or script.script is None:
        return False
    if not compat.with_osl():
        return False
    if not needs_compile(tree):
        return True
    text = script.script.as_string()
    # Cycles finds existing sockets by name in some versions and by
    # identifier in others: start from none, so it makes every one itself
    # (the links go with them and are made again below).
    script.inputs.clear()
    script.outputs.clear()
    try:
        ok = compat.compile_script_node(script, report)
    except Exception as e:  # noqa: BLE001  (Cycles' own code: keep the group whole)
        report({"ERROR"}, "%s: compiling the shader failed: %s" % (tree.name, e))
        ok = False
    if not ok or not script.bytecode:
        _script_sockets_by_hand(script)
        tree[COMPILED_KEY] = ""
        link_group(tree)
        return False
    tree[COMPILED_KEY] = text_hash(text)
    missing = link_group(tree)
    if missing:
        report({"WARNING"}, "%s: the compiled shader has no socket for %s" % (tree.name, ", ".join(missing)))
    return True


_pending = set()


def _run_pending():
    names = list(_pending)
    _pending.clear()
    for name in names:
        tree = bpy.data.node_groups.get(name)
        if tree is not None and is_knit_group(tree):
            try:
                ensure_compiled(tree)
            except ReferenceError:
                pass
    return None  # once


def schedule_compile(tree):
    """Compile the group after COMPILE_DELAY seconds without further edits
    (or at the next render or save)."""
    if not compat.with_osl():
        return
    _pending.add(tree.name)
    if bpy.app.timers.is_registered(_run_pending):
        bpy.app.timers.unregister(_run_pending)
    bpy.app.timers.register(_run_pending, first_interval=COMPILE_DELAY)


def pending():
    """Names of the groups waiting to be compiled."""
    return sorted(_pending)


def flush_pending():
    """Compile now what is waiting (before a render, a save, a test)."""
    if bpy.app.timers.is_registered(_run_pending):
        bpy.app.timers.unregister(_run_pending)
    _run_pending()


# ---- the material --------------------------------------------------------

def socket_ids(tree):
    return tree.get(SOCKETS_KEY) or {}


def input_socket(node, name):
    """The group node's input socket of shader parameter `name`, or None."""
    ident = socket_ids(node.node_tree).get(name)
    return compat.socket_by_identifier(node.inputs, ident) if ident else None


def get_value(node, name):
    p = param(name)
    sock = input_socket(node, name) if node is not None else None
    if sock is None:
        return defaults().get(name, p.default)
    v = sock.default_value
    if p.kind == "color":
        return tuple(v)[:3]
    if p.kind in ("point", "vector"):
        return tuple(v)
    if p.kind == "bool":
        return bool(v)
    if p.kind in ("int", "enum"):
        return int(v)
    return float(v)


def set_value(node, name, value):
    """Write a checked value into the group node's input (no checks here)."""
    p = param(name)
    sock = input_socket(node, name)
    if sock is None:
        raise KnitError("%s: the Knit Fabric group has no input for %s (Recompile Shader repairs it)"
                        % (node.name, p.label))
    if p.kind == "color":
        sock.default_value = tuple(value)[:3] + (1.0,)
    elif p.kind in ("point", "vector"):
        sock.default_value = tuple(value)
    elif p.kind == "bool" and sock.bl_idname == "NodeSocketBool":
        sock.default_value = bool(value)
    elif p.kind in ("int", "enum", "bool"):
        sock.default_value = int(value)
    else:
        sock.default_value = float(value)
    if name == "Yarn0":  # the solid viewport shows the main yarn colour
        mat = node.id_data
        for m in bpy.data.materials:
            if m.node_tree == mat:
                m.diffuse_color = tuple(value)[:3] + (1.0,)
                break


def new_material(pat=None, values=None, name=MATERIAL_NAME, report=None):
    """A new material whose surface is a new Knit Fabric group node."""
    tree = new_group(pat, values, report=report)
    mat = bpy.data.materials.new(name)
    nt = compat.ensure_node_tree(mat)
    nt.nodes.clear()
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.location = (300, 0)
    node = nt.nodes.new("ShaderNodeGroup")
    node.node_tree = tree
    node.name = node.label = GROUP_NAME
    node.location = (0, 0)
    node.width = 240
    nt.links.new(node.outputs[0], out.inputs["Surface"])
    nt.nodes.active = node
    vals = defaults()
    vals.update(values or {})
    for p in params():
        if p.name in vals:
            set_value(node, p.name, vals[p.name])
    mat.diffuse_color = tuple(vals.get("Yarn0", (0.5, 0.36, 0.25)))[:3] + (1.0,)
    compat.knit_cycles_material_settings(mat)
    return mat


def ensure_scene_renders_osl(scene):
    """Cycles with its OSL shading system, on a device that runs OSL.
    Returns the list of things changed and the list of warnings."""
    changed, warnings = [], []
    if scene.render.engine != "CYCLES":
        scene.render.engine = "CYCLES"
        changed.append("render engine set to Cycles")
    cscene = getattr(scene, "cycles", None)
    if cscene is not None:
        if not cscene.shading_system:
            cscene.shading_system = True
            changed.append("Open Shading Language turned on")
        ok, why = compat.cycles_device_runs_osl(scene)
        if not ok:
            cscene.device = "CPU"
            changed.append("device set to CPU (%s)" % why)
    if not compat.with_osl():
        warnings.append(NO_OSL_MESSAGE)
    return changed, warnings


NO_OSL_MESSAGE = ("This Blender's Cycles has no OSL, so the knit shader cannot render here: "
                  "open the file once in a Blender with OSL (official 4.2 and later) with the "
                  "add-on, which compiles it, or use explicit yarn geometry (docs/blender.md)")


# ---- handlers ------------------------------------------------------------

@persistent
def _on_load_post(*_args):
    """A file saved where OSL was missing (or whose shader text was edited)
    gets its bytecode here, when this Blender has OSL."""
    if not compat.with_osl():
        return
    for tree in knit_groups():
        try:
            if needs_compile(tree):
                ensure_compiled(tree)
        except Exception as e:  # noqa: BLE001  (never break loading a file)
            print("Knit Fabric: %s: %s" % (tree.name, e))


@persistent
def _on_save(*_args):
    """Compile what waits for a pause before a save writes the bytecode."""
    if _pending:
        flush_pending()


@persistent
def _on_render(*_args):
    """A render that starts within the pause after an edit (F12 at once)
    renders the previous compile: compiling here, with the render's
    depsgraph being made, crashes Cycles."""
    for name in _pending:
        print("Knit Fabric: %s was edited just before the render, which uses its previous shader" % name)


@persistent
def _on_undo_redo(*_args):
    """After an undo the text may be older than the bytecode: compile it
    again after a pause (cheap when nothing changed)."""
    if not compat.with_osl():
        return
    for tree in knit_groups():
        try:
            if needs_compile(tree):
                schedule_compile(tree)
        except ReferenceError:
            pass


_HANDLERS = (
    ("load_post", _on_load_post),
    ("undo_post", _on_undo_redo),
    ("redo_post", _on_undo_redo),
    ("render_init", _on_render),
    ("save_pre", _on_save),
)


def add_node_menu(self, context):
    space = context.space_data
    if getattr(space, "tree_type", "") != "ShaderNodeTree":
        return
    self.layout.operator("knitshade.add_node", text="Knit Fabric", icon="MOD_CLOTH")


def register():
    if compat.with_osl():
        # (Cycles itself compiles a Script node whose text or mode changes,
        # and needs oslquery for it: PyPI's bpy keeps it off sys.path)
        compat.ensure_oslquery_importable()
    for name, fn in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        if fn not in handlers:
            handlers.append(fn)
    for menu in compat.shader_add_menus():
        menu.append(add_node_menu)


def unregister():
    for menu in compat.shader_add_menus():
        try:
            menu.remove(add_node_menu)
        except (ValueError, RuntimeError):
            pass
    for name, fn in _HANDLERS:
        handlers = getattr(bpy.app.handlers, name)
        while fn in handlers:
            handlers.remove(fn)
    if bpy.app.timers.is_registered(_run_pending):
        bpy.app.timers.unregister(_run_pending)
    _pending.clear()

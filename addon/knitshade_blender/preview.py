"""Swatch preview in the material tab (docs/blender-yarns.md, "Swatch preview").

The `knitshade` CLI renders a small swatch of the material (core/swatch.py:
a curved patch under a fixed light rig, the material's settings in the
native scene format) to an EXR, in its own process: Blender starts it with
subprocess.Popen and polls it from a timer, so it never waits on it. The
EXR is loaded as an image datablock ("Knit Swatch: <material>", open it in
the Image Editor) and written through the scene's colour management (its
view transform, look, exposure and display, by Blender's OpenColorIO:
Image.save_render) to the PNG the panel shows.

The CLI: the path in the add-on's preferences, else a `knitshade` next to
the add-on (its folder, or bin/ in it), else the one on PATH. The add-on's
zip does not carry it (it needs the renderer's libraries: Embree, OpenImage
IO, ...): point the preference at a built one (build/knitshade).

Refreshing: the Render Preview button, and, once a material has a preview,
by itself a second after its settings stop changing (the panel notices the
change when it redraws; the preference "Refresh Previews" turns it off). In
background Blender (scripts, tests) render() waits for the CLI instead.
A missing or failing CLI is a plain message in the panel, never a
traceback.
"""
import functools
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

import bpy
from bpy.props import BoolProperty, StringProperty

from . import nodes
from .core import swatch as kswatch

POLL_SECONDS = 0.25
DEBOUNCE_SECONDS = 1.0
IMAGE_PREFIX = "Knit Swatch: "
CLI_NAME = "knitshade.exe" if sys.platform == "win32" else "knitshade"
PACKAGE = __package__  # the add-on's module name (an extension's is bl_ext.<repo>.knitshade_blender)

NO_CLI = ("No knitshade CLI found: set its path in Preferences > Add-ons > Knitshade (a built "
          "build/knitshade; the add-on's zip does not carry it), or put knitshade on PATH")


class PreviewError(RuntimeError):
    pass


# ---- preferences ---------------------------------------------------------

class KNITSHADE_AP_preferences(bpy.types.AddonPreferences):
    bl_idname = PACKAGE

    cli_path: StringProperty(
        name="knitshade CLI", subtype="FILE_PATH",
        description="The knitshade command-line renderer that renders the swatch previews (empty: one next "
                    "to the add-on, else the one on PATH)")
    auto_refresh: BoolProperty(
        name="Refresh Previews", default=True,
        description="Render a material's swatch preview again a second after its settings stop changing "
                    "(once it has one)")

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "cli_path")
        layout.prop(self, "auto_refresh")
        path, why = find_cli()
        if path:
            layout.label(text="Previews use " + path, icon="CHECKMARK")
        else:
            layout.label(text=why, icon="INFO")


def prefs():
    addon = bpy.context.preferences.addons.get(PACKAGE)
    return addon.preferences if addon is not None else None


def find_cli():
    """(path, "") of the CLI to run, or ("", why none)."""
    p = prefs()
    wanted = bpy.path.abspath(p.cli_path) if p is not None and p.cli_path else ""
    if wanted:
        if os.path.isdir(wanted):
            wanted = os.path.join(wanted, CLI_NAME)
        if not os.path.isfile(wanted):
            return "", "The knitshade CLI set in the add-on's preferences, %s, does not exist" % wanted
        if not os.access(wanted, os.X_OK):
            return "", "The knitshade CLI set in the add-on's preferences, %s, is not executable" % wanted
        return wanted, ""
    here = os.path.dirname(os.path.abspath(__file__))
    for cand in (os.path.join(here, CLI_NAME), os.path.join(here, "bin", CLI_NAME)):
        if os.path.isfile(cand) and os.access(cand, os.X_OK):
            return cand, ""
    found = shutil.which("knitshade")
    if found:
        return found, ""
    return "", NO_CLI


# ---- state ---------------------------------------------------------------

class _State:
    """One material's preview: what it shows and what is running."""

    def __init__(self):
        self.key = ""  # settings key of the image shown (or being made)
        self.status = "none"  # none | running | done | error
        self.message = ""
        self.icon = 0
        self.icon_name = ""
        self.image = ""
        self.proc = None
        self.dir = ""
        self.t0 = 0.0
        self.seconds = 0.0
        self.timer = None  # the pending debounce timer
        self.poller = None
        self.stamp = ""  # what the PNG was made with (view transform)


_states = {}
_previews = None
_mesh_dir = ""
_counter = [0]


def state(mat_name):
    st = _states.get(mat_name)
    if st is None:
        st = _states[mat_name] = _State()
    return st


def material_values(mat):
    """({shader parameter name: value}, Pattern) of a Knit Fabric material."""
    node = nodes.knit_node(mat)
    if node is None:
        raise PreviewError("material '%s' has no Knit Fabric node" % mat.name)
    values = {p.name: nodes.get_value(node, p.name) for p in nodes.params()}
    return values, nodes.get_pattern(node.node_tree)


def material_key(mat):
    try:
        values, pat = material_values(mat)
    except Exception:  # noqa: BLE001  (a damaged material: no key, no auto refresh)
        return ""
    return kswatch.settings_key(values, pat)


def _mesh_file():
    global _mesh_dir
    if not _mesh_dir or not os.path.isdir(_mesh_dir):
        _mesh_dir = tempfile.mkdtemp(prefix="knitshade-swatch-")
    path = os.path.join(_mesh_dir, "patch.obj")
    if not os.path.isfile(path):
        with open(path, "w", encoding="utf-8") as f:
            f.write(kswatch.patch_obj())
    return path


def _tag_redraw():
    wm = bpy.context.window_manager
    if wm is None:
        return
    for win in wm.windows:
        for area in win.screen.areas:
            if area.type in ("PROPERTIES", "NODE_EDITOR", "IMAGE_EDITOR"):
                area.tag_redraw()


# ---- rendering -----------------------------------------------------------

def start(mat, size=kswatch.SIZE, spp=kswatch.SPP):
    """Start the CLI on the material's swatch; returns the state (status
    'running', or 'error' with the message when it could not start)."""
    st = state(mat.name)
    if st.proc is not None and st.proc.poll() is None:
        st.proc.kill()
        st.proc.wait()
    st.proc = None
    cli, why = find_cli()
    if not cli:
        st.status, st.message = "error", why
        return st
    try:
        values, pat = material_values(mat)
    except Exception as e:  # noqa: BLE001
        st.status, st.message = "error", "%s: the preview cannot read the material: %s" % (mat.name, e)
        return st
    if st.dir and os.path.isdir(st.dir):
        shutil.rmtree(st.dir, ignore_errors=True)
    st.dir = tempfile.mkdtemp(prefix="knitshade-preview-")
    scene_path = os.path.join(st.dir, "swatch.json")
    with open(scene_path, "w", encoding="utf-8") as f:
        f.write(kswatch.scene_text(values, pat, _mesh_file(), size, spp, cycles_version()))
    st.key = kswatch.settings_key(values, pat, size, spp)
    exr = os.path.join(st.dir, "swatch.exr")
    cmd = [cli, "render", scene_path, "-o", exr, "--quiet", "--no-cache"]
    kw = {}
    if hasattr(os, "nice"):
        kw["preexec_fn"] = lambda: os.nice(10)  # Blender stays responsive
    try:
        with open(os.path.join(st.dir, "cli.log"), "wb") as log:
            st.proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                       cwd=st.dir, **kw)
    except OSError as e:
        st.status, st.message = "error", "The knitshade CLI %s could not start: %s" % (cli, e.strerror or e)
        return st
    st.status, st.message, st.t0 = "running", "", time.time()
    return st


def _log_tail(st, lines=3):
    try:
        with open(os.path.join(st.dir, "cli.log"), "r", encoding="utf-8", errors="replace") as f:
            text = [ln.strip() for ln in f.read().splitlines() if ln.strip()]
    except OSError:
        return ""
    return " | ".join(text[-lines:])


def _finish(mat_name, scene=None):
    """The CLI has ended: load its EXR, make the panel's PNG through the
    scene's view transform. Sets the state's status."""
    st = state(mat_name)
    proc, st.proc = st.proc, None
    st.seconds = time.time() - st.t0
    exr = os.path.join(st.dir, "swatch.exr")
    if proc is None or proc.returncode != 0 or not os.path.isfile(exr):
        code = proc.returncode if proc is not None else "?"
        st.status = "error"
        st.message = "%s: the knitshade CLI failed (exit status %s): %s" % (mat_name, code, _log_tail(st) or
                                                                           "no output")
        return st
    try:
        scene = scene or bpy.context.scene
        name = IMAGE_PREFIX + mat_name
        img = bpy.data.images.get(name)
        if img is not None:
            img.filepath = exr
            img.reload()
        else:
            img = bpy.data.images.load(exr, check_existing=False)
            img.name = name
        st.image = img.name
        png = os.path.join(st.dir, "swatch_display.png")
        img.save_render(png, scene=scene)  # the scene's view transform, through OpenColorIO
        vs = scene.view_settings
        st.stamp = "%s, %s" % (vs.view_transform, scene.display_settings.display_device)
        _load_icon(st, png)
    except (RuntimeError, OSError, ReferenceError) as e:
        st.status, st.message = "error", "%s: the preview image could not be read: %s" % (mat_name, e)
        return st
    st.status, st.message = "done", ""
    return st


def _load_icon(st, png):
    if _previews is None:
        return
    if st.icon_name and st.icon_name in _previews:
        del _previews[st.icon_name]
    _counter[0] += 1
    st.icon_name = "swatch%d" % _counter[0]
    st.icon = _previews.load(st.icon_name, png, "IMAGE").icon_id


def _poll(mat_name):
    st = _states.get(mat_name)
    if st is None or st.proc is None:
        return None
    if st.proc.poll() is None:
        return POLL_SECONDS
    st.poller = None
    try:
        _finish(mat_name)
    except Exception as e:  # noqa: BLE001  (a timer must never raise)
        st.status, st.message = "error", "%s: the preview failed: %s" % (mat_name, e)
    _tag_redraw()
    return None


def render(mat, wait=None, scene=None):
    """Render the material's swatch preview. wait=None: wait in background
    Blender (no timers run there), else poll from a timer. Returns the
    state (status, message, image, icon)."""
    st = start(mat)
    if st.status != "running":
        _tag_redraw()
        return st
    if wait is None:
        wait = bpy.app.background
    if wait:
        st.proc.wait()
        return _finish(mat.name, scene)
    fn = functools.partial(_poll, mat.name)
    st.poller = fn
    bpy.app.timers.register(fn, first_interval=POLL_SECONDS)
    return st


def _debounced(mat_name):
    st = _states.get(mat_name)
    if st is not None:
        st.timer = None
    mat = bpy.data.materials.get(mat_name)
    if mat is None or st is None:
        return None
    try:
        if material_key(mat) != st.key:
            render(mat, wait=False)
    except Exception as e:  # noqa: BLE001
        st.status, st.message = "error", "%s: the preview failed: %s" % (mat_name, e)
    _tag_redraw()
    return None


def notice_edit(mat):
    """Called when the panel draws: a material with a preview whose settings
    changed gets a new one a second after the last change."""
    st = _states.get(mat.name)
    p = prefs()
    if st is None or st.status == "none" or (p is not None and not p.auto_refresh) or bpy.app.background:
        return
    if st.status == "error" and not st.key:
        return
    key = material_key(mat)
    if not key or key == st.key:
        return
    if st.timer is not None and bpy.app.timers.is_registered(st.timer):
        return  # one already waits (it compares the key again when it runs)
    st.timer = functools.partial(_debounced, mat.name)
    bpy.app.timers.register(st.timer, first_interval=DEBOUNCE_SECONDS)


# ---- operator and panel --------------------------------------------------

class KNITSHADE_OT_preview_swatch(bpy.types.Operator):
    """Render a swatch of the material with the knitshade CLI (in its own process) and show it here"""

    bl_idname = "knitshade.preview_swatch"
    bl_label = "Render Preview"
    bl_options = {"REGISTER"}

    material: StringProperty(name="Material", description="The material (default: the one in context)",
                             options={"SKIP_SAVE"})

    def execute(self, context):
        mat = bpy.data.materials.get(self.material) if self.material else getattr(context, "material", None)
        if mat is None:
            obj = getattr(context, "object", None)
            mat = obj.active_material if obj is not None else None
        if mat is None or nodes.knit_node(mat) is None:
            self.report({"ERROR"}, "no Knit Fabric material %s" % (("'%s'" % self.material) if self.material
                                                                    else "in context"))
            return {"CANCELLED"}
        st = render(mat)
        if st.status == "error":
            self.report({"WARNING"}, st.message)
            return {"CANCELLED"}
        if st.status == "done":
            self.report({"INFO"}, "%s: swatch preview rendered in %.1f s" % (mat.name, st.seconds))
        return {"FINISHED"}


def draw_preview(layout, context, mat):
    st = _states.get(mat.name)
    cli, why = find_cli()
    row = layout.row(align=True)
    op = row.operator(KNITSHADE_OT_preview_swatch.bl_idname, icon="RENDER_STILL",
                      text="Render Preview" if st is None or st.status == "none" else "Refresh")
    op.material = mat.name
    p = prefs()
    if p is not None:
        row.prop(p, "auto_refresh", text="", icon="FILE_REFRESH")
    if not cli:
        box = layout.box()
        for line in _wrap(why, 55):
            box.label(text=line, icon="BLANK1")
        return
    if st is None:
        return
    notice_edit(mat)
    if st.icon:
        layout.template_icon(icon_value=st.icon, scale=9.0)
    if st.status == "running":
        layout.label(text="Rendering the swatch... %.0f s" % (time.time() - st.t0), icon="TIME")
    elif st.status == "done":
        layout.label(text="%d x %d, %d samples, %.1f s; %s" % (kswatch.SIZE, kswatch.SIZE, kswatch.SPP, st.seconds,
                                                              st.stamp), icon="IMAGE_DATA")
    elif st.status == "error":
        box = layout.box()
        box.alert = True
        for i, line in enumerate(_wrap(st.message, 55)):
            box.label(text=line, icon="ERROR" if i == 0 else "BLANK1")


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


class KNITSHADE_PT_material_preview(bpy.types.Panel):
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "material"
    bl_label = "Swatch Preview"
    bl_parent_id = "KNITSHADE_PT_material"
    bl_order = 0

    @classmethod
    def poll(cls, context):
        mat = getattr(context, "material", None)
        return mat is not None and nodes.knit_node(mat) is not None

    def draw(self, context):
        try:
            draw_preview(self.layout, context, context.material)
        except Exception as e:  # noqa: BLE001  (a panel never shows a traceback)
            self.layout.label(text="Preview: %s" % e, icon="ERROR")


_classes = (KNITSHADE_AP_preferences, KNITSHADE_OT_preview_swatch, KNITSHADE_PT_material_preview)


def register():
    global _previews
    from bpy.utils import previews
    _previews = previews.new()
    for cls in _classes:
        bpy.utils.register_class(cls)


def unregister():
    global _previews, _mesh_dir
    for cls in reversed(_classes):
        try:
            bpy.utils.unregister_class(cls)
        except RuntimeError:
            pass
    for st in _states.values():
        for fn in (st.timer, st.poller):
            if fn is not None and bpy.app.timers.is_registered(fn):
                bpy.app.timers.unregister(fn)
        if st.proc is not None and st.proc.poll() is None:
            st.proc.kill()
            st.proc.wait()
        if st.dir:
            shutil.rmtree(st.dir, ignore_errors=True)
    _states.clear()
    if _mesh_dir:
        shutil.rmtree(_mesh_dir, ignore_errors=True)
        _mesh_dir = ""
    if _previews is not None:
        from bpy.utils import previews
        previews.remove(_previews)
        _previews = None


def cycles_version():
    """4 for this Blender's Cycles before 5.0, 5 from 5.0 on: the closure
    rules the native swatch render follows (docs/scene-format.md)."""
    return 4 if tuple(bpy.app.version) < (5, 0, 0) else 5


def scene_json_for(mat):
    """The swatch scene file's text for a material (for scripts and tests)."""
    values, pat = material_values(mat)
    return json.loads(kswatch.scene_text(values, pat, "patch.obj", cycles_version=cycles_version()))

"""Yarn geometry and the swatch preview with a window (Debian's Blender under
xvfb-run, no -b): the material tab's Swatch Preview and Yarn Geometry
panels drawn; the preview started from its operator renders in the CLI's
own process while Blender keeps drawing (polled from a timer), and the
panel then shows it; a colour changed afterwards renders it again by
itself (debounced); Generate Yarn Geometry invoked as from its button
runs as a modal operator (a progress bar, the area's header) and leaves
one undo step; a screenshot of the tab with both. run.py fails the test on
any Python traceback in Blender's log (panel draws and timers print their
errors). Runs from timers, so Blender's event loop draws between steps."""
import os
import sys
import time
import traceback

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside as T  # noqa: E402

addon = None
draws = {}
state = {}


def window():
    return bpy.context.window_manager.windows[0]


def area_of(kind):
    return next((a for a in window().screen.areas if a.type == kind), None)


def override(area=None):
    win = window()
    kw = dict(window=win, screen=win.screen)
    if area is not None:
        kw["area"] = area
        kw["region"] = next(r for r in area.regions if r.type == "WINDOW")
    return bpy.context.temp_override(**kw)


def count_draws(cls_name):
    cls = getattr(bpy.types, cls_name)
    real = cls.draw

    def counted(self, context):
        draws[cls_name] = draws.get(cls_name, 0) + 1
        real(self, context)

    cls.draw = counted


def cli():
    for cand in (os.environ.get("KNIT_CLI", ""), os.path.join(T.SOURCE, "build", "knitshade")):
        if cand and os.path.isfile(cand) and os.access(cand, os.X_OK):
            return cand
    return ""


# ---- steps ---------------------------------------------------------------

def setup():
    T.say(T.blender())
    start = T.out_path("start.blend")
    bpy.ops.wm.save_as_mainfile(filepath=start)
    bpy.ops.wm.open_mainfile(filepath=start)
    return 0.5


def make_material():
    global addon
    addon = T.install()
    exe = cli()
    T.check(exe, "no knitshade CLI ($KNIT_CLI, build/knitshade)")
    bpy.context.preferences.addons[addon.__name__].preferences.cli_path = exe
    cube = bpy.data.objects["Cube"]
    bpy.context.view_layer.objects.active = cube
    cube.select_set(True)
    addon.api.add_knit_material(cube, pattern="K K P P\nP P K K", uv_scale=120.0, colours=[(0.55, 0.1, 0.08)])
    props = area_of("PROPERTIES")
    props.spaces.active.context = "MATERIAL"
    for name in ("KNITSHADE_PT_material_preview", "KNITSHADE_PT_material_yarns"):
        count_draws(name)
    with override(props):
        bpy.ops.screen.screen_full_area()
    return 0.5


def start_preview():
    T.check(draws.get("KNITSHADE_PT_material_preview"), "the Swatch Preview panel was not drawn: %s" % draws)
    T.check(draws.get("KNITSHADE_PT_material_yarns"), "the Yarn Geometry panel was not drawn: %s" % draws)
    mat = bpy.data.objects["Cube"].active_material
    with override(area_of("PROPERTIES")):
        T.equal(bpy.ops.knitshade.preview_swatch("INVOKE_DEFAULT", material=mat.name), {"FINISHED"},
                "preview_swatch")
    st = addon.preview.state(mat.name)
    T.equal(st.status, "running", "the preview after the operator (in the CLI's own process)")
    state["t0"] = time.time()
    state["draws0"] = draws.get("KNITSHADE_PT_material_preview", 0)
    return 0.3


def wait_preview():
    mat = bpy.data.objects["Cube"].active_material
    st = addon.preview.state(mat.name)
    if st.status == "running":
        T.check(time.time() - state["t0"] < 120, "the preview did not end in 2 minutes")
        area_of("PROPERTIES").tag_redraw()
        STEPS.insert(0, wait_preview)
        return 0.3
    T.equal((st.status, st.message), ("done", ""), "the preview")
    drawn = draws.get("KNITSHADE_PT_material_preview", 0) - state["draws0"]
    T.say("preview: %.1f s in the CLI's process, the panel drawn %d times meanwhile; icon %d (%s)"
          % (st.seconds, drawn, st.icon, st.stamp))
    T.check(st.icon > 0, "no preview icon")
    return 0.5


def edit_colour():
    """A setting changed after a preview: the panel notices it when it
    redraws and renders again a second after the last change."""
    mat = bpy.data.objects["Cube"].active_material
    st = addon.preview.state(mat.name)
    state["key0"] = st.key
    addon.api.set_parameters(mat, yarn0=(0.1, 0.3, 0.6))
    area_of("PROPERTIES").tag_redraw()
    state["t2"] = time.time()
    return 0.3


def wait_refresh():
    mat = bpy.data.objects["Cube"].active_material
    st = addon.preview.state(mat.name)
    if st.key == state["key0"] or st.status == "running":
        T.check(time.time() - state["t2"] < 120, "the preview was not refreshed after the edit (status %s)"
                % st.status)
        area_of("PROPERTIES").tag_redraw()
        STEPS.insert(0, wait_refresh)
        return 0.3
    T.equal((st.status, st.message), ("done", ""), "the refreshed preview")
    T.equal(st.key, addon.preview.material_key(mat), "the refreshed preview's settings")
    T.say("preview refreshed by itself after the edit: %.1f s after it" % (time.time() - state["t2"]))
    return 0.3


def generate():
    cube = bpy.data.objects["Cube"]
    with override(area_of("PROPERTIES")):
        bpy.ops.ed.undo_push(message="before the yarns")
        r = bpy.ops.knitshade.generate_yarns("INVOKE_DEFAULT", object=cube.name)
    T.equal(r, {"RUNNING_MODAL"}, "generate_yarns invoked from the panel")
    state["t1"] = time.time()
    return 0.2


def wait_yarns():
    yarns = [o for o in bpy.data.objects if o.get("knitshade_yarns")]
    if not yarns:
        T.check(time.time() - state["t1"] < 60, "the yarns were not made in a minute")
        STEPS.insert(0, wait_yarns)
        return 0.2
    info = yarns[0]["knitshade_yarns"]
    T.say("yarns made by the modal operator in %.1f s: %d curves, %d points"
          % (time.time() - state["t1"], info["curves"], info["points"]))
    area_of("PROPERTIES").tag_redraw()
    return 0.5


def hide_surface():
    """Cycles' Surface panel lists every input of the group above the Knit
    Fabric panel: for the screenshot its poll says no (as test_ui.py does)."""
    surf = getattr(bpy.types, "CYCLES_MATERIAL_PT_surface", None)
    if surf is not None:
        state["surface"] = (surf, surf.__dict__.get("poll"))
        surf.poll = classmethod(lambda cls, context: False)
    area_of("PROPERTIES").tag_redraw()
    return 0.5


def screenshot():
    path = T.out_path("material_tab_yarns_preview.png")
    with override():
        T.equal(bpy.ops.screen.screenshot(filepath=path), {"FINISHED"}, "screenshot")
    T.check(os.path.getsize(path) > 10000, "the screenshot is (nearly) empty")
    T.say("screenshot: " + path)
    surf, poll = state.pop("surface", (None, None))
    if surf is not None:
        if poll is None:
            del surf.poll
        else:
            surf.poll = poll
    return 0.3


def undo():
    with override(area_of("PROPERTIES")):
        T.equal(bpy.ops.ed.undo(), {"FINISHED"}, "undo")
    T.equal([o.name for o in bpy.data.objects if o.get("knitshade_yarns")], [], "yarn objects after undo")
    T.check(not bpy.data.objects["Cube"].hide_render, "the cube is still hidden in renders after undo")
    T.say("the yarns undone in one step")
    return 0.3


STEPS = [setup, make_material, start_preview, wait_preview, edit_colour, wait_refresh, generate, wait_yarns,
         hide_surface, screenshot, undo]


def runner():
    try:
        if not STEPS:
            T.say("all checks passed")
            bpy.ops.wm.quit_blender()
            return None
        step = STEPS.pop(0)
        return step()
    except Exception:
        traceback.print_exc()
        T.say("FAILED")
        sys.stdout.flush()
        os._exit(1)


if bpy.app.background:
    T.say("SKIP: this test needs a window (run it without -b, under xvfb-run)")
else:
    bpy.app.timers.register(runner, first_interval=0.5, persistent=True)

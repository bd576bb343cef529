"""Helpers for the add-on tests that run inside Blender (Debian's Blender 3.4
with `blender -b --python`, PyPI's bpy 5.0 as a module). run.py starts
them; docs/testing.md says how.

Environment (set by run.py):
  KNIT_ADDON_ZIP   the built add-on zip (build/knitshade_blender-<version>.zip)
  KNIT_TEST_OUT    this test's output folder (build/test-output/blender/<test>)
  KNIT_SOURCE_DIR  the repository
  BLENDER_USER_SCRIPTS, BLENDER_USER_EXTENSIONS, BLENDER_USER_CONFIG: empty
                   folders under KNIT_TEST_OUT, so nothing of the user's is seen

Every check raises AssertionError with what was expected and what was
found; finish() prints the line run.py looks for.
"""
import os
import sys
import time
import traceback

import bpy  # first: the bpy module makes addon_utils importable
import addon_utils  # noqa: E402

ZIP = os.environ.get("KNIT_ADDON_ZIP", "")
OUT = os.environ.get("KNIT_TEST_OUT", "")
SOURCE = os.environ.get("KNIT_SOURCE_DIR", "")
USER = os.environ.get("BLENDER_USER_SCRIPTS", "")
MODULE = "knitshade_blender"
_t0 = time.time()


def say(msg):
    print("knit-test: %s" % msg, flush=True)


def check(cond, msg):
    if not cond:
        raise AssertionError(msg)


def equal(got, want, what):
    if got != want:
        raise AssertionError("%s: expected %r, got %r" % (what, want, got))


def close(got, want, what, tol=1e-5):
    if abs(got - want) > tol * max(1.0, abs(want)):
        raise AssertionError("%s: expected %r, got %r" % (what, want, got))


def raises(exc, fn, *args, contains="", **kw):
    """Call fn; it must raise `exc` whose text contains `contains`; returns the text."""
    try:
        fn(*args, **kw)
    except exc as e:
        text = str(e)
        if contains and contains not in text:
            raise AssertionError("%s raised %s without %r: %s" % (getattr(fn, "__name__", fn), exc.__name__,
                                                                 contains, text))
        return text
    raise AssertionError("%s did not raise %s" % (getattr(fn, "__name__", fn), exc.__name__))


def op_fails(fn, contains="", **kw):
    """An operator call that must report an error (RuntimeError from bpy.ops);
    returns the message."""
    return raises(RuntimeError, fn, contains=contains, **kw)


def blender():
    return "Blender %s (Python %s)" % (bpy.app.version_string, sys.version.split()[0])


def install(mode="addon"):
    """Install the built zip into the empty user folder and enable it.
    mode "addon": Preferences > Add-ons > Install (every version);
    "extension": the 4.2+ extension route (bl_ext.user_default.*).
    Returns the add-on's module, loaded from the user folder."""
    check(ZIP and os.path.isfile(ZIP), "the add-on zip %r does not exist (build the addon_zip target)" % ZIP)
    check(USER and not os.path.exists(os.path.join(USER, "addons", MODULE)),
          "the user scripts folder %r is not empty of the add-on" % USER)
    if mode == "extension":
        r = bpy.ops.extensions.package_install_files(repo="user_default", filepath=ZIP, enable_on_install=False)
        equal(r, {"FINISHED"}, "extensions.package_install_files")
        name = "bl_ext.user_default." + MODULE
    else:
        r = bpy.ops.preferences.addon_install(filepath=ZIP)
        equal(r, {"FINISHED"}, "preferences.addon_install")
        name = MODULE
    return enable(name)


def enable(name=MODULE):
    """Enable the add-on; addon_utils.enable swallows exceptions (prints
    them, returns None), so its result is checked."""
    mod = addon_utils.enable(name, default_set=True, handle_error=None)
    check(mod is not None, "addon_utils.enable(%r) returned None: the add-on failed to load (see above)" % name)
    check(name in bpy.context.preferences.addons, "%s is not in the enabled add-ons" % name)
    path = os.path.realpath(mod.__file__)
    roots = [os.path.realpath(p) for p in (USER, os.environ.get("BLENDER_USER_EXTENSIONS", "")) if p]
    check(any(path.startswith(r + os.sep) for r in roots),
          "the add-on was loaded from %s, not from the empty user folder" % path)
    check(hasattr(bpy.types.Material, "knitshade"), "Material.knitshade is not registered")
    check(hasattr(bpy.ops.knitshade, "add_material"), "knitshade.add_material is not registered")
    return mod


def disable(name=MODULE):
    addon_utils.disable(name, default_set=True, handle_error=None)
    check(name not in bpy.context.preferences.addons, "%s still enabled after disable" % name)
    check(not hasattr(bpy.types.Material, "knitshade"), "Material.knitshade left registered after disable")
    check(not hasattr(bpy.types, "KNITSHADE_OT_add_material"), "knitshade.add_material left registered")
    check(not hasattr(bpy.types, "KNITSHADE_PT_material"), "the Knit Fabric panel left registered")


def window_context():
    """A context override under which undo works (a window and its screen;
    in background mode too)."""
    wm = bpy.context.window_manager
    if len(wm.windows):
        win = wm.windows[0]
        return bpy.context.temp_override(window=win, screen=win.screen)
    return bpy.context.temp_override(screen=bpy.data.screens[0])


def fresh_scene():
    """Factory settings with the add-on still enabled: an empty scene."""
    bpy.ops.wm.read_homefile(use_empty=True)
    for o in list(bpy.data.objects):
        bpy.data.objects.remove(o)


def plane(name="Plane", size=2.0, location=(0, 0, 0)):
    bpy.ops.mesh.primitive_plane_add(size=size, location=location)
    obj = bpy.context.active_object
    obj.name = name
    return obj


def out_path(name):
    os.makedirs(OUT, exist_ok=True)
    return os.path.join(OUT, name)


def run(main):
    """Run the test's main(); any failure ends Blender with status 1 (with
    --python-exit-code 1) or the bpy module's Python with 1."""
    try:
        main()
    except Exception:
        traceback.print_exc()
        say("FAILED after %.1f s" % (time.time() - _t0))
        sys.stdout.flush()
        if "bpy" in sys.modules and not bpy.app.background:
            os._exit(1)
        raise
    say("all checks passed (%.1f s)" % (time.time() - _t0))

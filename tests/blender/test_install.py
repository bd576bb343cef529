"""The built zip installed into an empty user folder: enable (asserting on
addon_utils.enable's result), disable, enable again; the native module
loads from inside the package; registration leaves nothing behind. In a
Blender with extensions (4.2+) the same zip also installs, enables and
disables as an extension (bl_ext.user_default.knitshade_blender)."""
import os
import shutil
import sys

import bpy  # first: the bpy module makes addon_utils importable
import addon_utils  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside as T  # noqa: E402


def handlers_of(mod):
    found = []
    for name in ("load_post", "undo_post", "redo_post"):
        found += [name for fn in getattr(bpy.app.handlers, name) if fn.__module__.startswith(mod.__name__)]
    return found


def menu_entries(mod):
    n = 0
    for menu in mod.compat.shader_add_menus():
        funcs = getattr(menu.draw, "_draw_funcs", [])
        n += sum(1 for f in funcs if getattr(f, "__module__", "").startswith(mod.__name__))
    return n


def exercise(mod, name):
    """Enabled: the parts are there, the module loads, a material can be made."""
    T.check(mod.native.AVAILABLE, "the native module did not load from the zip: %s" % mod.native.status())
    so = os.path.realpath(mod.native.module.__file__)
    T.check("/native/knitshade." in so and so.startswith(os.path.realpath(os.environ["KNIT_TEST_OUT"])),
            "the native module came from %s, not from inside an installed package" % so)
    T.check(mod.native.__name__ == name + ".native", "native module package named %s" % mod.native.__name__)
    T.equal(sorted(set(handlers_of(mod))), ["load_post", "redo_post", "undo_post"], "handlers added")
    T.equal(len(handlers_of(mod)), 3, "handlers (each once)")
    T.equal(menu_entries(mod), 1, "Add > Shader > Knit Fabric entries")
    T.fresh_scene()
    obj = T.plane()
    T.equal(bpy.ops.knitshade.add_material(), {"FINISHED"}, "add_material")
    T.check(obj.active_material is not None and mod.nodes.knit_node(obj.active_material) is not None,
            "the plane has no Knit Fabric material")
    T.say("%s: enabled from %s; %s" % (name, os.path.dirname(mod.__file__), mod.native.status()))


def left_behind(mod):
    T.equal(handlers_of(mod), [], "handlers left after disable")
    T.equal(menu_entries(mod), 0, "menu entries left after disable")


def main():
    T.say(T.blender())
    mod = T.install("addon")
    exercise(mod, "knitshade_blender")
    T.disable()
    left_behind(mod)
    mod = T.enable()
    exercise(mod, "knitshade_blender")
    T.disable()
    left_behind(mod)
    T.say("installed as an add-on: enable, disable, enable, disable")

    if bpy.app.version >= (4, 2, 0):
        # (preferences.addon_remove needs an area in 5.0: remove the folder)
        shutil.rmtree(os.path.join(T.USER, "addons", "knitshade_blender"))
        addon_utils.modules_refresh()
        name = "bl_ext.user_default.knitshade_blender"
        mod = T.install("extension")
        exercise(mod, name)
        T.check(mod.__name__ == name, "extension module named %s" % mod.__name__)
        T.disable(name)
        left_behind(mod)
        mod = T.enable(name)
        exercise(mod, name)
        T.disable(name)
        T.say("installed as an extension: enable, disable, enable, disable")


T.run(main)

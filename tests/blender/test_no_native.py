"""The add-on without its compiled module (as in a Blender whose Python is not
3.11): the built zip with native/knitshade.*.so taken out, installed into an
empty user folder. It registers, makes a material, edits, imports and saves
a pattern, checks a, h, d, r with its own basic checks in the library's
words, and says what the module would add and how to get it."""
import os
import sys
import zipfile

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside as T  # noqa: E402


def stripped_zip():
    out = T.out_path("knitshade_blender-no-native.zip")
    with zipfile.ZipFile(T.ZIP) as src, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        names = src.namelist()
        T.check(any("/native/knitshade." in n for n in names), "the built zip has no native module to take out")
        for n in names:
            if "/native/knitshade." not in n:
                dst.writestr(src.getinfo(n), src.read(n))
    return out


def main():
    T.say(T.blender())
    T.ZIP = stripped_zip()
    addon = T.install()
    native = addon.native
    T.check(not native.AVAILABLE, "the native module loaded from a zip without it")
    T.check(native.status().startswith("Native module not loaded"), "status: %r" % native.status())
    T.check(native.ADDS and "StitchParams" not in native.HOW_TO_GET and "addon_zip" in native.HOW_TO_GET,
            "what the module adds / how to get it")
    T.say("without the module: %s" % native.status())
    T.fresh_scene()
    T.plane("Swatch")
    T.equal(bpy.ops.knitshade.add_material(name="Knit"), {"FINISHED"}, "add_material")
    mat = bpy.data.materials["Knit"]
    T.equal(bpy.ops.knitshade.paint_cell(material="Knit", row=0, col=0), {"FINISHED"}, "paint_cell")
    T.equal(addon.api.get_pattern(mat).to_storage().split()[0], "PKKK", "edited pattern")
    msg = T.op_fails(bpy.ops.knitshade.set_stitch, material="Knit", a=0.0,
                     contains="stitch parameter a (loop roundness) must be > 0, got 0")
    T.say("basic check: " + msg.strip())
    # the clearance check needs the library: without it r = 0.9 passes
    T.equal(bpy.ops.knitshade.set_stitch(material="Knit", r=0.9), {"FINISHED"}, "set_stitch r = 0.9")
    path = T.out_path("pattern.knit")
    T.equal(bpy.ops.knitshade.export_pattern(material="Knit", filepath=path), {"FINISHED"}, "export")
    T.equal(bpy.ops.knitshade.import_pattern(material="Knit", filepath=path), {"CANCELLED"},
            "import of the same pattern")
    bpy.ops.knitshade.mirror(material="Knit")
    T.equal(bpy.ops.knitshade.import_pattern(material="Knit", filepath=path), {"FINISHED"}, "import")
    T.equal(addon.api.get_pattern(mat).to_storage().split()[0], "PKKK", "imported pattern")
    text = addon.nodes.script_node(addon.nodes.knit_node(mat).node_tree).script.as_string()
    T.equal(text, addon.core.shader.osl_source(addon.api.get_pattern(mat)), "the shader text")
    T.equal(bpy.ops.wm.save_as_mainfile(filepath=T.out_path("no_native.blend")), {"FINISHED"}, "save")
    T.disable()
    T.enable()
    T.disable()


T.run(main)

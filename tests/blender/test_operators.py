"""Every knitshade operator with valid and with invalid input, called with
arguments as a script calls them. A refused call raises RuntimeError with
the operator's one report line (naming the material and the value, and the
parser's or the library's message) and leaves the data as it was."""
import math
import os
import sys
import time

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside as T  # noqa: E402

ops = bpy.ops.knitshade
MAT = "Knit"


def mat():
    return bpy.data.materials[MAT]


def stored(addon, m=None):
    return addon.api.get_pattern(m or mat()).to_storage()


def rows(addon, m=None):
    return stored(addon, m).split("colors:")[0].split()


def fresh(**kw):
    """A new material MAT on the Swatch plane (the old one removed)."""
    if MAT in bpy.data.materials:
        bpy.data.materials.remove(bpy.data.materials[MAT])
    T.equal(ops.add_material(name=MAT, objects="Swatch", **kw), {"FINISHED"}, "add_material %r" % kw)
    return mat()


def unchanged(addon, before, what):
    T.equal(stored(addon), before, "pattern after a refused %s" % what)


def test_add_material(addon):
    obj = T.plane("Swatch")
    T.equal(ops.add_material(), {"FINISHED"}, "add_material on the selection")
    m = obj.active_material
    T.check(m is not None and m.name.startswith("Knit Fabric"), "the selected plane got %r" % m)
    node = addon.nodes.knit_node(m)
    T.check(node is not None, "no Knit Fabric node in the new material")
    T.equal(addon.api.get_pattern(m).to_storage(), "KKKK\nKKKK\nKKKK\nKKKK\n", "default pattern (stockinette)")
    # defaults that look like knitwear: worsted yarn, 18 stitches per 10 cm on the 2 m plane
    p = addon.api.get_parameters(m)
    T.close(p["uv_scale"], 2 * math.pi * 18 * 10 * 2.0, "default UV scale on a 2 m plane", 1e-4)
    T.equal((p["a"], p["h"], p["d"]), (1.5, 4.0, 1.0), "default a, h, d")
    T.close(p["r"], 0.65, "default r")
    T.check(0.2 < sum(p["yarn0"]) / 3 < 0.6, "yarn colour 0 %r is not a mid tone" % (p["yarn0"],))
    T.equal(bpy.context.scene.render.engine, "CYCLES", "render engine after add_material")
    T.check(bpy.context.scene.cycles.shading_system, "Cycles' OSL is not on after add_material")
    T.check(addon.geometry.read_curvature(obj) is not None, "no curvature attribute on the plane")

    # with arguments: named objects, pattern text, yarn weight, stitch, colours, uv scale
    T.plane("Other", location=(3, 0, 0))
    if MAT in bpy.data.materials:
        bpy.data.materials.remove(bpy.data.materials[MAT])
    r = ops.add_material(name=MAT, objects="Swatch,Other", pattern="K P\nP K\ncolors:\n0 1\n1 0",
                         yarn_weight="chunky", r=0.7, uv_scale=500.0, colour=(0.1, 0.2, 0.6),
                         contrast_colour=(0.9, 0.9, 0.1))
    T.equal(r, {"FINISHED"}, "add_material with arguments")
    m = mat()
    T.equal(bpy.data.objects["Other"].active_material, m, "Other's material")
    T.equal(bpy.data.objects["Swatch"].active_material, m, "Swatch's material (replaced in its active slot)")
    T.equal(len(bpy.data.objects["Swatch"].material_slots), 1, "Swatch's slots (replaced, not added)")
    p = addon.api.get_parameters(m)
    T.equal(stored(addon), "KP\nPK\ncolors:\n01\n10\n", "pattern from text")
    T.close(p["d"], 1.2, "chunky d")
    T.close(p["r"], 0.7, "r given")
    T.equal(p["ply_count"], 2, "chunky ply count")
    T.close(p["uv_scale"], 500.0, "uv_scale given")
    T.check(all(abs(a - b) < 1e-6 for a, b in zip(p["yarn0"], (0.1, 0.2, 0.6))), "colour given: %r" % (p["yarn0"],))
    T.check(all(abs(a - b) < 1e-6 for a, b in zip(p["yarn1"], (0.9, 0.9, 0.1))), "contrast colour: %r" % (p["yarn1"],))
    ops.add_material(name="Preset", objects="Other", preset="rib_2x2")
    T.equal(rows(addon, bpy.data.materials["Preset"])[0], "KKPPKKPP", "preset rib_2x2's first row")

    # invalid: nothing is made
    n_mats = len(bpy.data.materials)
    msg = T.op_fails(ops.add_material, pattern="K P\nK X", contains="<pattern>:2:3: unknown stitch code 'X'")
    T.say("add_material with a bad pattern: " + msg.strip())
    T.op_fails(ops.add_material, a=0.0, contains="stitch parameter a (loop roundness) must be > 0, got 0")
    msg = T.op_fails(ops.add_material, r=5.0, contains="r = 5 makes yarn tubes pass through each other")
    T.say("add_material with r = 5: " + msg.strip())
    T.op_fails(ops.add_material, objects="Nope", contains="no object named 'Nope'")
    T.op_fails(ops.add_material, pattern="\n".join(["K" * 300]), contains="at most 256 x 256")
    T.raises(TypeError, ops.add_material, yarn_weight="lace")
    T.equal(len(bpy.data.materials), n_mats, "materials after refused add_material calls")


def test_add_node(addon):
    m = bpy.data.materials.new("Plain")
    addon.compat.ensure_node_tree(m)
    win = bpy.context.window_manager.windows[0]
    area = max(win.screen.areas, key=lambda a: a.width * a.height)
    old = area.type
    area.type = "NODE_EDITOR"
    area.ui_type = "ShaderNodeTree"
    space = area.spaces.active
    space.node_tree = m.node_tree
    region = next(r for r in area.regions if r.type == "WINDOW")
    with bpy.context.temp_override(window=win, screen=win.screen, area=area, region=region, space_data=space):
        T.check(ops.add_node.poll(), "add_node cannot run in a shader editor")
        T.equal(ops.add_node(location=(200.0, 100.0)), {"FINISHED"}, "add_node")
    knit = [n for n in m.node_tree.nodes if addon.nodes.is_knit_node(n)]
    T.equal(len(knit), 1, "Knit Fabric nodes added")
    T.equal(tuple(knit[0].location), (200.0, 100.0), "the node's location")
    area.type = old
    # invalid: outside a shader editor the operator does not run
    T.check(not ops.add_node.poll(), "add_node polls true without a shader editor")
    T.op_fails(ops.add_node, contains="poll")


def test_pattern_edits(addon):
    # (compiling each edit is tested by test_material and test_render; here
    # the edits wait for one compile at the end, as a script may choose)
    addon.nodes.compile_edits_in_background = False
    fresh(preset="stockinette")
    base = stored(addon)
    T.equal(ops.paint_cell(material=MAT, row=0, col=1), {"FINISHED"}, "paint_cell cycle")
    T.equal(rows(addon)[0], "KPKK", "cycled K -> P")
    ops.paint_cell(material=MAT, row=0, col=1)
    ops.paint_cell(material=MAT, row=0, col=1)
    T.equal(rows(addon)[0], "KBKK", "cycled P -> F -> B")
    ops.paint_cell(material=MAT, row=0, col=1)
    T.equal(stored(addon), base, "cycled B -> K")
    ops.paint_cell(material=MAT, row=3, col=3, tool="STITCH", stitch="F")
    T.equal(rows(addon)[3], "KKKF", "painted F")
    ops.paint_cell(material=MAT, row=2, col=0, tool="COLOUR", colour=3)
    T.check(stored(addon).endswith("colors:\n0000\n0000\n3000\n0000\n"), "painted colour 3: %r" % stored(addon))
    before = stored(addon)
    msg = T.op_fails(ops.paint_cell, material=MAT, row=9, col=0, contains="cell (9, 0) is outside the 4x4 pattern")
    T.check(msg.startswith("Error: Knit: "), "the report does not open with the material: %r" % msg)
    T.op_fails(ops.paint_cell, material=MAT, row=0, col=0, tool="COLOUR", colour=9,
               contains="the palette has colours 0 to 7")
    T.op_fails(ops.paint_cell, material="Nope", row=0, col=0, contains="there is no material 'Nope'")
    bare = bpy.data.materials.new("Bare")
    T.op_fails(ops.paint_cell, material=bare.name, row=0, col=0,
               contains="material 'Bare' has no Knit Fabric node")
    unchanged(addon, before, "paint_cell")
    T.check(mat().knitshade.message.startswith("Knit: "), "the panel's message after a refusal: %r"
            % mat().knitshade.message)

    ops.clear_colours(material=MAT)
    T.check("colors:" not in stored(addon), "clear_colours left colours")
    T.equal(ops.clear_colours(material=MAT), {"CANCELLED"}, "clear_colours without colours (nothing to do)")

    ops.set_pattern(material=MAT, text="K P K P\nK K K K\nP P P P")
    T.equal(ops.fill(material=MAT, stitch="B"), {"FINISHED"}, "fill")
    T.equal(set("".join(rows(addon))), {"B"}, "filled with B")
    ops.fill(material=MAT, colour=2, rect=(1, 1, 2, 2))
    T.check(stored(addon).endswith("colors:\n0000\n0220\n0220\n"), "fill a rectangle with colour 2: %r"
            % stored(addon))
    before = stored(addon)
    T.op_fails(ops.fill, material=MAT, stitch="K", rect=(2, 2, 3, 3), contains="is not inside the 3x4 pattern")
    T.op_fails(ops.fill, material=MAT, contains="nothing to fill")
    T.op_fails(ops.fill, material=MAT, colour=8, contains="the palette has colours 0 to 7")
    unchanged(addon, before, "fill")

    ops.set_pattern(material=MAT, text="K P F B\nP K K K")
    ops.shift(material=MAT, dx=1, dy=0)
    T.equal(rows(addon), ["BKPF", "KPKK"], "shift right by 1")
    ops.shift(material=MAT, dx=0, dy=1)
    T.equal(rows(addon), ["KPKK", "BKPF"], "shift down by 1")
    ops.shift(material=MAT, dx=-1, dy=-1)
    T.equal(rows(addon), ["KPFB", "PKKK"], "shift back")
    T.equal(ops.shift(material=MAT, dx=4, dy=2), {"CANCELLED"}, "a whole-period shift (no change)")
    ops.mirror(material=MAT)
    T.equal(rows(addon), ["BFPK", "KKKP"], "mirror")
    ops.mirror(material=MAT)
    ops.flip(material=MAT)
    T.equal(rows(addon), ["PKKK", "KPFB"], "flip")
    ops.flip(material=MAT)
    T.op_fails(ops.mirror, material="Nope", contains="no material 'Nope'")
    T.op_fails(ops.flip, material="Bare", contains="no Knit Fabric node")
    T.op_fails(ops.shift, material="Nope", contains="no material 'Nope'")

    T.equal(ops.resize(material=MAT, rows=3, cols=5), {"FINISHED"}, "resize")
    T.equal(rows(addon), ["KPFBK", "PKKKK", "KKKKK"], "resized 3 x 5")
    before = stored(addon)
    T.op_fails(ops.resize, material=MAT, rows=300, cols=5, contains="the shader takes patterns of at most 256 x 256")
    unchanged(addon, before, "resize")

    ops.insert_row(material=MAT, index=0)
    T.equal(rows(addon)[:2], ["KKKKK", "KPFBK"], "row inserted at the top")
    ops.insert_row(material=MAT)
    T.equal(len(rows(addon)), 5, "row appended")
    ops.remove_row(material=MAT, index=0)
    ops.remove_row(material=MAT)
    T.equal(stored(addon), before, "rows removed again")
    ops.insert_column(material=MAT, index=1)
    T.equal(rows(addon)[0], "KKPFBK", "column inserted at 1")
    ops.remove_column(material=MAT, index=1)
    T.equal(stored(addon), before, "column removed again")
    T.op_fails(ops.remove_row, material=MAT, index=7, contains="row index 7 out of range 0..2")
    T.op_fails(ops.insert_column, material=MAT, index=9, contains="column index 9 out of range 0..5")
    ops.set_pattern(material=MAT, text="K")
    T.op_fails(ops.remove_row, material=MAT, index=0, contains="cannot remove the only row")
    T.op_fails(ops.remove_column, material=MAT, index=0, contains="cannot remove the only column")

    for ident, _name, _desc in addon.api.pattern_presets():
        ops.load_preset(material=MAT, preset=ident)
        want = addon.core.presets.load_preset(ident)
        T.equal(addon.api.get_pattern(mat()), want, "pattern after load_preset %s" % ident)
    T.raises(TypeError, ops.load_preset, material=MAT, preset="argyle")

    before = stored(addon)
    msg = T.op_fails(ops.set_pattern, material=MAT, text="K P\nK", contains="<text>:2:2: row has 1 cells, expected 2")
    T.say("set_pattern with a ragged pattern: " + msg.strip())
    unchanged(addon, before, "set_pattern")

    # two materials sharing one group; make_single_user separates them
    m2 = mat().copy()
    m2.name = "Knit Copy"
    T.equal(addon.nodes.knit_node(m2).node_tree, addon.nodes.knit_node(mat()).node_tree, "a copied material's group")
    T.equal(ops.make_single_user(material="Knit Copy"), {"FINISHED"}, "make_single_user")
    ops.set_pattern(material="Knit Copy", text="P")
    T.equal(stored(addon), before, "the original's pattern after editing the copy")
    T.op_fails(ops.make_single_user, material="Nope", contains="no material 'Nope'")
    if addon.compat.with_osl():
        T.check(addon.nodes.pending(), "no edit waits to be compiled")
    addon.nodes.flush_pending()
    T.equal(addon.nodes.pending(), [], "edits still waiting after flush_pending")
    if addon.compat.with_osl():
        T.check(not addon.nodes.needs_compile(addon.nodes.knit_node(mat()).node_tree), "the edits were not compiled")
    addon.nodes.compile_edits_in_background = True


def test_import_export(addon):
    fresh(pattern="K P\nP K")
    good = T.out_path("good.knit")
    with open(good, "w") as f:
        f.write("# a test pattern\nK K P P\nP P K K\ncolours:\n0 0 1 1\n1 1 0 0\n")
    T.equal(ops.import_pattern(material=MAT, filepath=good), {"FINISHED"}, "import_pattern")
    T.equal(rows(addon), ["KKPP", "PPKK"], "imported rows")
    bad = T.out_path("bad.knit")
    with open(bad, "w") as f:
        f.write("K K P P\nP P K\n")
    before = stored(addon)
    msg = T.op_fails(ops.import_pattern, material=MAT, filepath=bad,
                     contains="%s:2:6: row has 3 cells, expected 4 like the first row (line 1)" % bad)
    T.say("import of a bad .knit: " + msg.strip())
    T.check(bad + ":2:6:" in mat().knitshade.message, "the panel's message: %r" % mat().knitshade.message)
    unchanged(addon, before, "import")
    T.op_fails(ops.import_pattern, material=MAT, filepath=T.out_path("missing.knit"),
               contains="cannot open pattern file")
    # a valid import clears the panel's message
    ops.import_pattern(material=MAT, filepath=good)
    T.equal(mat().knitshade.message, "", "the panel's message after a good import")

    out = T.out_path("exported.knit")
    T.equal(ops.export_pattern(material=MAT, filepath=out), {"FINISHED"}, "export_pattern")
    again = addon.core.pattern.load(out)
    T.equal(again, addon.api.get_pattern(mat()), "exported pattern read back")
    T.op_fails(ops.export_pattern, material=MAT, filepath=T.out_path("no/such/dir/x.knit"), contains="cannot write")


def test_settings(addon):
    fresh()
    T.equal(ops.set_stitch(material=MAT, a=1.3, r=0.5), {"FINISHED"}, "set_stitch")
    p = addon.api.get_parameters(mat())
    T.close(p["a"], 1.3, "a")
    T.close(p["r"], 0.5, "r")
    msg = T.op_fails(ops.set_stitch, material=MAT, r=0.9, contains="r = 0.9 makes yarn tubes pass through each other")
    T.say("set_stitch r = 0.9: " + msg.strip())
    T.op_fails(ops.set_stitch, material=MAT, d=0.0, contains="stitch parameter d (loop depth) must be non-zero")
    T.close(addon.api.get_parameters(mat())["r"], 0.5, "r after refusals")

    # the panel's fields: a refused value keeps the last valid one and says why
    s = mat().knitshade
    s.r = 0.55
    T.close(s.r, 0.55, "r set through the panel property")
    s.r = 2.0
    T.close(s.r, 0.55, "r after a refused panel value")
    T.check("makes yarn tubes pass through each other" in mat().knitshade.message,
            "the panel's message: %r" % mat().knitshade.message)
    s.roughness = 0.3
    T.close(s.roughness, 0.3, "roughness")
    T.equal(mat().knitshade.message, "", "the message after a valid change")
    s.mode = "MULTI_SCALE"
    T.equal(s.mode, "MULTI_SCALE", "mode")
    s.yarn2 = (0.1, 0.5, 0.2)
    T.check(abs(s.yarn2[1] - 0.5) < 1e-6, "yarn2 through the panel: %r" % (tuple(s.yarn2),))

    for ident, _name, _desc in addon.api.yarn_weights():
        T.equal(ops.yarn_weight(material=MAT, weight=ident), {"FINISHED"}, "yarn_weight %s" % ident)
        w = addon.core.presets.yarn_weight(ident)
        p = addon.api.get_parameters(mat())
        T.close(p["r"], w["r"], "r of %s" % ident)
        T.equal(p["ply_count"], w["ply_count"], "ply count of %s" % ident)
    T.raises(TypeError, ops.yarn_weight, material=MAT, weight="lace")

    bpy.context.view_layer.objects.active = bpy.data.objects["Swatch"]
    T.equal(ops.gauge(material=MAT, stitches_per_10cm=20.0, object="Swatch"), {"FINISHED"}, "gauge")
    T.close(addon.api.get_parameters(mat())["uv_scale"], 2 * math.pi * 20 * 10 * 2.0, "uv scale for 20 st/10 cm", 1e-4)
    bpy.ops.mesh.primitive_cube_add()
    cube = bpy.context.active_object
    cube.name = "NoUV"
    cube.data.uv_layers.remove(cube.data.uv_layers[0])
    T.op_fails(ops.gauge, material=MAT, object="NoUV", contains="NoUV has no UV map")

    scene = bpy.context.scene
    scene.render.engine = "BLENDER_EEVEE" if "BLENDER_EEVEE" in {i.identifier for i in
                                                                scene.render.bl_rna.properties["engine"].enum_items} \
        else scene.render.engine
    scene.cycles.shading_system = False
    scene.cycles.device = "GPU"  # (no OptiX here: a GPU device that cannot run OSL)
    T.equal(ops.setup_scene(), {"FINISHED"}, "setup_scene")
    T.equal((scene.render.engine, scene.cycles.shading_system, scene.cycles.device), ("CYCLES", True, "CPU"),
            "engine, OSL, device after setup_scene")

    T.equal(ops.compile(material=MAT), {"FINISHED"}, "compile")
    T.op_fails(ops.compile, material="Nope", contains="no material 'Nope'")


def test_curvature(addon):
    bpy.ops.mesh.primitive_uv_sphere_add(radius=2.0, segments=64, ring_count=32)
    sphere = bpy.context.active_object
    sphere.name = "Ball"
    T.equal(ops.refresh_curvature(objects="Ball"), {"FINISHED"}, "refresh_curvature")
    k = addon.geometry.read_curvature(sphere)
    T.check(k is not None and len(k) == len(sphere.data.polygons), "curvature attribute per face")
    import numpy as np
    ky = np.median(k[:, 1])
    T.close(float(ky), 0.5, "median curvature along v of a radius-2 sphere", 0.05)
    sphere.scale = (2.0, 2.0, 2.0)
    ops.refresh_curvature(objects="Ball")
    T.close(float(np.median(addon.geometry.read_curvature(sphere)[:, 1])), 0.25,
            "after scaling by 2 (1 / world units)", 0.05)
    T.equal(addon.api.refresh_curvature(bpy.data.objects["Swatch"])[1], 0.0, "a flat plane's curvature")
    T.op_fails(ops.refresh_curvature, objects="NoUV", contains="NoUV has no UV map")
    bpy.ops.object.empty_add()
    bpy.context.active_object.name = "Empty"
    T.op_fails(ops.refresh_curvature, objects="Empty", contains="not a mesh")
    T.op_fails(ops.refresh_curvature, objects="Nope", contains="no object named 'Nope'")


def test_editor_state(addon):
    ed = bpy.context.window_manager.knitshade_editor
    T.equal(ops.page(rows=24, cols=24, max_row=100, max_col=10), {"FINISHED"}, "page")
    T.equal((ed.page_row, ed.page_col), (24, 10), "page clamped to the pattern")
    ops.page(rows=-100, cols=-100, max_row=100, max_col=10)
    T.equal((ed.page_row, ed.page_col), (0, 0), "page back at the top")
    T.equal(ops.brush(colour=5), {"FINISHED"}, "brush")
    T.equal((ed.tool, ed.colour), ("COLOUR", 5), "brush state")
    T.raises(TypeError, ops.brush, colour="red")


def main():
    T.say(T.blender())
    addon = T.install()
    T.fresh_scene()
    for fn in (test_add_material, test_add_node, test_pattern_edits, test_import_export, test_settings,
               test_curvature, test_editor_state):
        t0 = time.time()
        fn(addon)
        T.say("%s passed (%.1f s)" % (fn.__name__, time.time() - t0))


T.run(main)

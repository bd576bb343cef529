"""A Knit Fabric material as Blender data: the node group's structure and
the shader text it holds, sockets against core.shader's PARAMS and OUTPUTS,
a socket change that leaves the shader alone, pattern edits that write the
text once each and compile once per pause, save and reload, append into
another file, a file without bytecode compiled on load (where Blender has
OSL), and undo and redo of a pattern edit."""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside as T  # noqa: E402

PATTERN = "K P K P\nP K P K\nK K P P\ncolors:\n0 0 1 1\n1 1 0 0\n0 1 0 1\n"
COLOURS = [(0.55, 0.1, 0.08), (0.85, 0.82, 0.7)]


def group_of(addon, mat):
    return addon.nodes.knit_node(mat).node_tree


def check_structure(addon, mat):
    shader, nodes, compat = addon.core.shader, addon.nodes, addon.compat
    nt = mat.node_tree
    node = nodes.knit_node(mat)
    out = next(n for n in nt.nodes if n.bl_idname == "ShaderNodeOutputMaterial")
    surf = out.inputs["Surface"].links
    T.check(len(surf) == 1 and surf[0].from_node == node and surf[0].from_socket.name == "BSDF",
            "the Knit Fabric node's BSDF does not feed the material output's Surface")
    tree = node.node_tree
    T.check(nodes.is_knit_group(tree), "the group is not marked as Knit Fabric")
    kinds = sorted(n.bl_idname for n in tree.nodes)
    T.equal(kinds, sorted(["NodeGroupInput", "NodeGroupOutput", "ShaderNodeUVMap", "ShaderNodeAttribute",
                           "ShaderNodeScript"]), "the group's nodes")
    script = nodes.script_node(tree)
    T.equal(script.mode, "INTERNAL", "Script node mode")
    text = script.script.as_string()
    pat = addon.api.get_pattern(mat)
    T.equal(text, shader.osl_source(pat), "the Script node's text against core.shader.osl_source(pattern)")
    T.check("#include" not in text and "shader %s(" % shader.SHADER_NAME in text,
            "the shader text is not self-contained")
    T.check("KNIT_PATTERN_ROWS %d" % pat.rows in text, "the pattern's size is not in the text")
    uv = tree.nodes[nodes.UV_NODE]
    T.equal(uv.uv_map, "", "UV Map node's map (the active render UV)")
    attr = tree.nodes[nodes.CURVATURE_NODE]
    T.equal((attr.attribute_type, attr.attribute_name), ("GEOMETRY", shader.CURVATURE_ATTRIBUTE),
            "Attribute node")

    params = [p for p in shader.PARAMS if not p.linked]
    ins = compat.group_sockets(tree, "INPUT")
    outs = compat.group_sockets(tree, "OUTPUT")
    T.equal([s.name for s in ins], [p.label for p in params], "group inputs (labels, in order)")
    T.equal([s.name for s in outs], [o[0] for o in shader.OUTPUTS], "group outputs")
    T.equal(outs[0].bl_socket_idname if hasattr(outs[0], "bl_socket_idname") else outs[0].bl_socket_idname,
            "NodeSocketShader", "BSDF output socket type")
    for s, p in zip(ins, params):
        T.equal(s.description, compat.short_description(p.description), "%s's tooltip" % p.name)
        if p.kind in ("float", "int"):
            if p.min is not None:
                T.close(s.min_value, p.min, "%s min" % p.name)
            if p.max is not None:
                T.close(s.max_value, p.max, "%s max" % p.name)

    gin = tree.nodes[nodes.INPUT_NODE]
    gout = tree.nodes[nodes.OUTPUT_NODE]
    ids = tree[nodes.SOCKETS_KEY]
    for p in shader.PARAMS:
        dst = compat.socket_by_identifier(script.inputs, p.name)
        T.check(dst is not None, "the Script node has no input %s" % p.name)
        T.equal(len(dst.links), 1, "links into the Script node's %s" % p.name)
        src = dst.links[0].from_socket
        if p.name == "UV":
            T.check(src.node == uv and src.name == "UV", "UV comes from %s.%s" % (src.node.name, src.name))
        elif p.name == "Curvature":
            T.check(src.node == attr and src.name == "Vector", "Curvature comes from %s" % src.node.name)
        else:
            T.check(src.node == gin and src.identifier == ids[p.name], "%s comes from %s.%s"
                    % (p.name, src.node.name, src.name))
    for name, _kind, _d in shader.OUTPUTS:
        src = compat.socket_by_identifier(script.outputs, name)
        T.check(src is not None and len(src.links) == 1 and src.links[0].to_node == gout,
                "the Script node's output %s does not reach the group output" % name)

    if compat.with_osl():
        T.check(len(script.bytecode) > 1000, "no bytecode in the compiled Script node")
        T.equal(tree[nodes.COMPILED_KEY], nodes.text_hash(text), "the hash of the compiled text")
        T.check(not nodes.needs_compile(tree), "the group still needs compiling")
    else:
        T.equal(script.bytecode, "", "bytecode where Blender has no OSL")
    return tree, script


def compiles_counter(addon):
    calls = []
    real = addon.compat.compile_script_node

    def counted(node, report):
        calls.append(node.id_data.name)
        return real(node, report)

    addon.compat.compile_script_node = counted
    return calls, lambda: setattr(addon.compat, "compile_script_node", real)


def main():
    T.say(T.blender())
    addon = T.install()
    api, nodes = addon.api, addon.nodes
    osl = addon.compat.with_osl()
    T.say("OSL: %s" % osl)
    T.fresh_scene()
    obj = T.plane("Swatch")
    mat = api.add_knit_material(obj, pattern=PATTERN, colours=COLOURS, a=1.4, h=4.2, d=1.1, r=0.55,
                                name="Knit")
    T.equal(mat.name, "Knit", "material name")
    T.equal(obj.active_material, mat, "the plane's material")
    tree, script = check_structure(addon, mat)
    T.say("node group: %d inputs, %d outputs, %d links, shader text %d lines"
          % (len(addon.compat.group_sockets(tree, "INPUT")), len(addon.compat.group_sockets(tree, "OUTPUT")),
             len(tree.links), script.script.as_string().count("\n")))
    p = api.get_parameters(mat)
    T.close(p["a"], 1.4, "a")
    T.close(p["r"], 0.55, "r")
    T.close(p["yarn1"][0], 0.85, "colour 1")

    # a socket change leaves the shader (text and bytecode) alone
    text0, hash0 = script.script.as_string(), script.bytecode_hash
    calls, restore = compiles_counter(addon)
    api.set_parameters(mat, r=0.5, uv_scale=900.0, yarn0=(0.2, 0.3, 0.6), roughness=0.25)
    T.equal(script.script.as_string(), text0, "the shader text after socket changes")
    T.equal(script.bytecode_hash, hash0, "the bytecode after socket changes")
    T.equal(calls, [], "compiles after socket changes")
    T.raises(ValueError, api.set_parameters, mat, r=0.5, roughness=7.0, contains="Sheen Roughness 7 is outside")
    T.close(api.get_parameters(mat)["r"], 0.5, "r after a refused set_parameters")
    T.raises(ValueError, api.set_parameters, mat, r=3.0, contains="makes yarn tubes pass through each other")
    T.raises(KeyError, api.set_parameters, mat, wool=1)

    # pattern edits: the text once per edit and, in background Blender (no
    # timers), one compile per edit where there is OSL
    writes = []
    real_set = nodes.set_pattern

    def counting_set(tree_, pat, compile="now", report=None):
        writes.append(pat)
        return real_set(tree_, pat, compile, report)

    nodes.set_pattern = counting_set
    try:
        for c in range(3):
            T.equal(bpy.ops.knitshade.paint_cell(material="Knit", row=0, col=c, tool="STITCH", stitch="F"),
                    {"FINISHED"}, "paint_cell")
    finally:
        nodes.set_pattern = real_set
    T.equal(len(writes), 3, "shader texts written for 3 edits")
    T.equal(script.script.as_string(), addon.core.shader.osl_source(api.get_pattern(mat)),
            "the text after the edits")
    T.equal(len(calls), 3 if osl else 0, "compiles for 3 edits in background Blender")
    if osl:
        T.check(script.bytecode_hash != hash0 and not nodes.needs_compile(tree), "the bytecode after the edits")
        # the interface's pause: compiles asked for in a row make one
        api.set_pattern(mat, "K")
        del calls[:]
        script.script.from_string(addon.core.shader.osl_source(api.get_pattern(mat)) + "\n// edited\n")
        for _ in range(3):
            nodes.schedule_compile(tree)
        T.equal(nodes.pending(), [tree.name], "groups waiting to compile")
        nodes.flush_pending()
        T.equal(len(calls), 1, "compiles for 3 requests in a pause")
        T.check(not nodes.needs_compile(tree), "still stale after the pause's compile")
        api.set_pattern(mat, "F F F P\nP K P K\nK K P P\ncolors:\n0 0 1 1\n1 1 0 0\n0 1 0 1\n")
    restore()
    T.raises(addon.core.pattern.PatternError, api.set_pattern, mat, "K P\nP", contains="<Knit>:2:2:")
    T.raises(addon.core.shader.ShaderError, api.set_pattern, mat, "K" * 257, contains="at most 256 x 256")
    T.equal(api.get_pattern(mat).to_storage().split("\n")[0], "FFFP", "pattern after refused set_pattern")
    api.set_pattern(mat, PATTERN)
    check_structure(addon, mat)
    T.say("socket changes: no new shader; 3 pattern edits: 3 texts and as many compiles")

    # save, reload
    params = api.get_parameters(mat)
    text = script.script.as_string()
    code = script.bytecode
    path = T.out_path("knit.blend")
    T.equal(bpy.ops.wm.save_as_mainfile(filepath=path), {"FINISHED"}, "save")
    bpy.ops.wm.read_homefile(use_empty=True)
    T.check("Knit" not in bpy.data.materials, "the material outlived read_homefile")
    bpy.ops.wm.open_mainfile(filepath=path)
    mat = bpy.data.materials["Knit"]
    T.equal(api.get_parameters(mat), params, "settings after save and reload")
    T.equal(api.get_pattern(mat), addon.core.pattern.parse_text(PATTERN), "pattern after save and reload")
    tree, script = check_structure(addon, mat)
    T.equal(script.script.as_string(), text, "shader text after reload")
    T.equal(script.bytecode, code, "bytecode after reload (not compiled again)")
    T.say("saved and reloaded: %s" % path)

    # append into another file
    bpy.ops.wm.read_homefile(use_empty=True)
    r = bpy.ops.wm.append(filepath=path + "/Material/Knit", directory=path + "/Material/", filename="Knit")
    T.equal(r, {"FINISHED"}, "append")
    mat = bpy.data.materials["Knit"]
    mat.use_fake_user = True  # (no object uses it: kept by the saves below)
    T.equal(api.get_parameters(mat), params, "settings of the appended material")
    check_structure(addon, mat)
    api.set_pattern(mat, "P K")
    check_structure(addon, mat)
    T.say("appended into a new file and edited there")

    # a file whose Script node holds no bytecode (saved where Blender has no
    # OSL) gets it on load where Blender has OSL
    tree = group_of(addon, mat)
    script = nodes.script_node(tree)
    script.bytecode = ""
    script.bytecode_hash = ""
    tree[nodes.COMPILED_KEY] = ""
    path2 = T.out_path("no_bytecode.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path2)
    bpy.ops.wm.read_homefile(use_empty=True)
    bpy.ops.wm.open_mainfile(filepath=path2)
    tree = group_of(addon, bpy.data.materials["Knit"])
    if osl:
        T.check(len(nodes.script_node(tree).bytecode) > 1000, "no bytecode after loading where OSL is")
        check_structure(addon, bpy.data.materials["Knit"])
        T.say("a file without bytecode compiled on load")
    else:
        T.equal(nodes.script_node(tree).bytecode, "", "bytecode after loading without OSL")

    # undo and redo of a pattern edit (one undo step each)
    bpy.ops.wm.open_mainfile(filepath=path)
    with T.window_context():
        bpy.ops.ed.undo_push(message="knit test start")
        before = api.get_pattern(bpy.data.materials["Knit"])
        r = bpy.ops.knitshade.paint_cell("EXEC_DEFAULT", True, material="Knit", row=1, col=1, tool="STITCH",
                                         stitch="B")
        T.equal(r, {"FINISHED"}, "paint_cell with an undo step")
        r = bpy.ops.knitshade.mirror("EXEC_DEFAULT", True, material="Knit")
        edited = api.get_pattern(bpy.data.materials["Knit"])
        T.check(edited != before, "the edits changed nothing")
        T.equal(bpy.ops.ed.undo(), {"FINISHED"}, "undo")
        T.equal(bpy.ops.ed.undo(), {"FINISHED"}, "undo")
        mat = bpy.data.materials["Knit"]
        T.equal(api.get_pattern(mat), before, "pattern after two undos")
        check_text = nodes.script_node(group_of(addon, mat)).script.as_string()
        T.equal(check_text, addon.core.shader.osl_source(before), "shader text after undo")
        T.equal(bpy.ops.ed.redo(), {"FINISHED"}, "redo")
        T.equal(bpy.ops.ed.redo(), {"FINISHED"}, "redo")
        T.equal(api.get_pattern(bpy.data.materials["Knit"]), edited, "pattern after two redos")
        r0 = api.get_parameters(bpy.data.materials["Knit"])["r"]
        T.equal(bpy.ops.knitshade.set_stitch("EXEC_DEFAULT", True, material="Knit", r=0.45), {"FINISHED"},
                "set_stitch with an undo step")
        T.close(api.get_parameters(bpy.data.materials["Knit"])["r"], 0.45, "r")
        T.equal(bpy.ops.ed.undo(), {"FINISHED"}, "undo of a setting")
        T.close(api.get_parameters(bpy.data.materials["Knit"])["r"], r0, "r after undo")
        nodes.flush_pending()
        check_structure(addon, bpy.data.materials["Knit"])
    T.say("undo and redo of pattern edits")


T.run(main)

"""Generate Yarn Geometry (issue 54), in Debian's Blender 3.4 and bpy 5.0.

Every check compares with a reference made here, independently of the
add-on's core/yarn_layout.py: the library's explicit_yarns() for the whole
tiled area at once (the add-on makes one band and moves it), each point
located on the mesh with mathutils (a BVH over the UV triangles, the
barycentric transform into the triangle in space and into its corner
normals), placed at P + ((z - shell_top) / S) N with S computed from the
triangle's own dP/du and dP/dv. On a UV-mapped plane (moved, turned and
scaled) and on the half cylinder of the examples:
  - the curve count, the total length and the radius agree;
  - every point lies at its stated height above the surface, and on the
    normal through its surface point, within 1e-4 of the stitch width;
then: yarns split at a UV seam (and do not at a connected UV edge); the
errors and warnings name the object (no UV map, no Knit Fabric, degenerate
triangles, UV islands of different scales); without the native module the
operator is disabled with its message; generating again replaces the
object's data; the scarf example's yarns within 10 s; a Cycles CPU render
of the yarns is not empty and differs between two patterns.
"""
import math
import os
import sys
import time

import bpy
import mathutils
import numpy as np
from mathutils import Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside as T  # noqa: E402

SAMPLES = 16


# ---- the reference -------------------------------------------------------

def corner_normals(mesh):
    n = np.empty(3 * len(mesh.loops), dtype=np.float32)
    if hasattr(mesh, "corner_normals"):
        mesh.corner_normals.foreach_get("vector", n)
    else:
        mesh.calc_normals_split()
        mesh.loops.foreach_get("normal", n)
    return n.reshape(-1, 3)


def reference(mod, obj, mat, samples=SAMPLES):
    """The yarns as this test expects them: curves of world points and radii."""
    K = mod.native.module
    prm = mod.api.get_parameters(mat)
    pat = mod.api.get_pattern(mat)
    kp = K.Pattern.from_text(pat.to_text(), "<test>")
    sp = K.StitchParams(a=prm["a"], h=prm["h"], d=prm["d"], r=prm["r"])
    surf = K.KnitSurface(kp, sp, 1.0)
    px, py = surf.period
    top = surf.shell_top
    us = prm["uv_scale"]
    mesh = obj.data
    mesh.calc_loop_triangles()
    M = obj.matrix_world
    M3 = M.to_3x3()
    NM = M3.inverted().transposed()
    nor = corner_normals(mesh)  # (first: in 3.x it reallocates the loops' data)
    uvl = np.empty(2 * len(mesh.loops), dtype=np.float32)
    mesh.uv_layers.active.data.foreach_get("uv", uvl)
    uvl = uvl.reshape(-1, 2)
    tris = []
    for lt in mesh.loop_triangles:
        P = [M @ mesh.vertices[v].co for v in lt.vertices]
        UV = [Vector((float(uvl[lo][0]), float(uvl[lo][1]), 0.0)) for lo in lt.loops]
        Nn = [(NM @ Vector(nor[lo])).normalized() for lo in lt.loops]
        e1, e2 = P[1] - P[0], P[2] - P[0]
        d1, d2 = UV[1] - UV[0], UV[2] - UV[0]
        det = d1.x * d2.y - d1.y * d2.x
        dpdu = (e1 * d2.y - e2 * d1.y) / det
        dpdv = (e2 * d1.x - e1 * d2.x) / det
        S = us / math.sqrt(dpdu.length * dpdv.length)
        tris.append((P, UV, Nn, S))
    bvh = mathutils.bvhtree.BVHTree.FromPolygons([v for t in tris for v in t[1]],
                                                 [(3 * i, 3 * i + 1, 3 * i + 2) for i in range(len(tris))],
                                                 epsilon=0.0)
    uvs = np.array([[t[1][k].x, t[1][k].y] for t in tris for k in range(3)])
    lo, hi = uvs.min(axis=0), uvs.max(axis=0)
    tx0, ty0 = math.floor(us * lo[0] / px), math.floor(us * lo[1] / py)
    tu, tv = max(1, math.ceil(us * hi[0] / px) - tx0), max(1, math.ceil(us * hi[1] / py) - ty0)
    y = K.explicit_yarns(kp, sp, tu, tv, samples)
    curves, radii, heights = [], [], []
    for c in y["curves"]:
        run, rrun, hrun = [], [], []
        for x, yy, z in c:
            uv = Vector(((x + tx0 * px) / us, (yy + ty0 * py) / us, 0.0))
            hit = bvh.find_nearest(uv)
            inside = hit[0] is not None and hit[3] <= 1e-6  # (the BVH works in single precision)
            if inside:
                P, UV, Nn, S = tris[hit[2]]
                p = mathutils.geometry.barycentric_transform(uv, UV[0], UV[1], UV[2], P[0], P[1], P[2])
                n = mathutils.geometry.barycentric_transform(uv, UV[0], UV[1], UV[2],
                                                             Nn[0], Nn[1], Nn[2]).normalized()
                run.append((p, n, (z - top) / S))
                rrun.append(y["radius"] / S)
            elif run:
                if len(run) >= 2:
                    curves.append(run)
                    radii.append(rrun)
                run, rrun = [], []
        if len(run) >= 2:
            curves.append(run)
            radii.append(rrun)
    stitch_width = 2.0 * math.pi / np.median([t[3] for t in tris])
    return curves, radii, stitch_width


def generated(yo):
    """(curves as lists of world points, radii, world scale) of a yarn object."""
    cv = yo.data
    n = len(cv.points)
    p = np.empty(3 * n, dtype=np.float32)
    cv.attributes["position"].data.foreach_get("vector", p)
    r = np.empty(n, dtype=np.float32)
    cv.attributes["radius"].data.foreach_get("value", r)
    off = np.empty(len(cv.curves) + 1, dtype=np.int32)
    cv.curve_offset_data.foreach_get("value", off)
    M = np.array(yo.matrix_world)
    pw = p.reshape(-1, 3).astype(np.float64) @ M[:3, :3].T + M[:3, 3]
    scale = abs(np.linalg.det(M[:3, :3])) ** (1 / 3)
    return [pw[off[i]:off[i + 1]] for i in range(len(off) - 1)], \
        [r[off[i]:off[i + 1]] * scale for i in range(len(off) - 1)]


def length(curves):
    return sum(float(np.linalg.norm(np.diff(np.asarray(c), axis=0), axis=1).sum()) for c in curves)


def compare(mod, obj, mat, what):
    yo = yarn_object(obj)
    gen, grad = generated(yo)
    ref, rrad, sw = reference(mod, obj, mat)
    T.equal(len(gen), len(ref), "%s: yarn curves" % what)
    worst_pos = worst_h = worst_r = 0.0
    for g, gr, rc, rr in zip(gen, grad, ref, rrad):
        T.equal(len(g), len(rc), "%s: points of a curve" % what)
        P = np.array([[*x[0]] for x in rc])
        N = np.array([[*x[1]] for x in rc])
        H = np.array([x[2] for x in rc])
        d = g - P
        h = (d * N).sum(axis=1)
        worst_h = max(worst_h, float(np.abs(h - H).max()))
        worst_pos = max(worst_pos, float(np.linalg.norm(d - h[:, None] * N, axis=1).max()))
        worst_r = max(worst_r, float(np.abs(gr - np.array(rr)).max()))
    ref_pts = [np.array([[*x[0]] for x in rc]) + np.array([[*x[1]] for x in rc]) * np.array([x[2] for x in rc])[:, None]
               for rc in ref]
    lg, lr = length(gen), length(ref_pts)
    T.say("%s: %d curves, %d points, length %.6g (reference %.6g); worst: height %.2e, off the normal %.2e, "
          "radius %.2e of the stitch width %.4g" % (what, len(gen), sum(len(c) for c in gen), lg, lr,
                                                    worst_h / sw, worst_pos / sw, worst_r / sw, sw))
    T.check(worst_h <= 1e-4 * sw, "%s: a point's height above the surface is off by %.3g stitch widths"
            % (what, worst_h / sw))
    T.check(worst_pos <= 1e-4 * sw, "%s: a point lies %.3g stitch widths off its surface point's normal"
            % (what, worst_pos / sw))
    T.check(worst_r <= 1e-4 * sw, "%s: a radius is off by %.3g stitch widths" % (what, worst_r / sw))
    T.close(lg, lr, "%s: total length" % what, tol=1e-5)
    return len(gen)


# ---- scenes --------------------------------------------------------------

def yarn_object(obj):
    found = [o for o in bpy.data.objects if (o.get("knitshade_yarns") or {}).get("source") == obj.name]
    T.equal(len(found), 1, "yarn objects of %s" % obj.name)
    return found[0]


def import_obj(path):
    before = set(bpy.data.objects)
    if hasattr(bpy.ops.wm, "obj_import"):
        bpy.ops.wm.obj_import(filepath=path, forward_axis="NEGATIVE_Z", up_axis="Y")
    else:
        bpy.ops.import_scene.obj(filepath=path)
    return [o for o in bpy.data.objects if o not in before][0]


def mesh_object(name, verts, faces, uvs):
    """A mesh from vertices, faces and per-corner UVs (face by face)."""
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    layer = me.uv_layers.new(name="UVMap")
    k = 0
    for f in me.polygons:
        for li in f.loop_indices:
            layer.data[li].uv = uvs[k]
            k += 1
    me.update()
    obj = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def two_quads(name, left_uv, right_uv):
    """Two unit quads side by side (x 0..1 and 1..2), sharing an edge."""
    verts = [(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 1, 0), (1, 1, 0), (2, 1, 0)]
    faces = [(0, 1, 4, 3), (1, 2, 5, 4)]
    (a0, a1), (b0, b1) = left_uv, right_uv
    uvs = [(a0, 0), (a1, 0), (a1, 1), (a0, 1), (b0, 0), (b1, 0), (b1, 1), (b0, 1)]
    return mesh_object(name, verts, faces, uvs)


def collect():
    got = []
    return got, (lambda kind, text: got.append((set(kind), text)))


# ---- the checks ----------------------------------------------------------

def check_plane(mod):
    T.fresh_scene()
    obj = T.plane("Swatch")
    obj.location = (0.3, -0.2, 0.5)
    obj.rotation_euler = (math.radians(20), math.radians(10), math.radians(30))
    obj.scale = (1.5, 1.5, 1.5)
    bpy.context.view_layer.update()
    mat = mod.api.add_knit_material(obj, pattern="K P P\nP K K", uv_scale=45.0, colours=[(0.7, 0.2, 0.1)],
                                    setup_scene=False)
    T.equal(bpy.ops.knitshade.generate_yarns(object=obj.name, samples=SAMPLES), {"FINISHED"}, "generate_yarns")
    n = compare(mod, obj, mat, "plane")
    yo = yarn_object(obj)
    T.check(yo.parent == obj and yo.type == "CURVES", "the yarns are a Curves object parented to the mesh")
    T.check(obj.hide_render, "the mesh is hidden in renders")
    T.equal(bpy.context.scene.cycles_curves.shape, "THICK", "Cycles curve shape")
    cols = np.empty(4 * len(yo.data.points), dtype=np.float32)
    yo.data.attributes[mod.yarns.COLOUR_ATTR].data.foreach_get("color", cols)
    T.check(np.allclose(cols.reshape(-1, 4)[:, :3], (0.7, 0.2, 0.1), atol=1e-6), "the yarn colour attribute")
    T.equal([m.name for m in yo.data.materials], [mat.name + " Yarn"], "the yarn material")
    # again: the same object, its data replaced
    data_before = yo.data.name
    n_objects = len(bpy.data.objects)
    mod.api.set_pattern(mat, "K K\nP P")
    T.equal(bpy.ops.knitshade.generate_yarns(object=obj.name, samples=SAMPLES), {"FINISHED"}, "generate again")
    T.equal(len(bpy.data.objects), n_objects, "objects after generating again")
    T.equal(len(bpy.data.hair_curves), 1, "curves datablocks after generating again (%s before)" % data_before)
    compare(mod, obj, mat, "plane, second pattern")
    # saved and opened again: the same curves (a Curves datablock Blender reads back)
    path = T.out_path("plane_yarns.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    before = generated(yarn_object(obj))[0]
    bpy.ops.wm.open_mainfile(filepath=path)
    after = generated(yarn_object(bpy.data.objects["Swatch"]))[0]
    T.equal(len(after), len(before), "curves after reload")
    T.check(all(np.array_equal(x, y) for x, y in zip(before, after)), "the curves changed in the saved file")
    return n


def check_half_cylinder(mod):
    T.fresh_scene()
    obj = import_obj(os.path.join(T.SOURCE, "examples", "scenes", "meshes", "half_cylinder.obj"))
    mat = mod.api.add_knit_material(obj, pattern="K K P P", uv_scale=40.0, setup_scene=False)
    T.equal(bpy.ops.knitshade.generate_yarns(object=obj.name, samples=SAMPLES), {"FINISHED"}, "generate_yarns")
    compare(mod, obj, mat, "half cylinder")


def max_step(curves):
    return max(float(np.linalg.norm(np.diff(c, axis=0), axis=1).max()) for c in curves)


def check_seam(mod):
    T.fresh_scene()
    joined = two_quads("Joined", (0.0, 0.5), (0.5, 1.0))
    seam = two_quads("Seamed", (0.5, 1.0), (0.0, 0.5))  # each quad's UVs where the other's are
    for o in (joined, seam):
        mod.api.add_knit_material(o, pattern="K", uv_scale=30.0, setup_scene=False)
        T.equal(bpy.ops.knitshade.generate_yarns(object=o.name, samples=SAMPLES), {"FINISHED"}, o.name)
    cj, _ = generated(yarn_object(joined))
    cs, _ = generated(yarn_object(seam))
    step_j, step_s = max_step(cj), max_step(cs)
    T.say("UV seam: %d curves without it, %d with it; longest step %.3g and %.3g"
          % (len(cj), len(cs), step_j, step_s))
    crossing = lambda cs_: sum(1 for c in cs_ if c[:, 0].min() < 0.9 and c[:, 0].max() > 1.1)  # noqa: E731
    T.check(crossing(cj) >= 5, "without a seam, only %d curves cross the shared edge" % crossing(cj))
    T.equal(crossing(cs), 0, "curves crossing the seam")
    T.check(len(cs) > len(cj), "the seam splits the rows: %d curves against %d" % (len(cs), len(cj)))
    T.check(step_s < 0.2 and step_j < 0.2, "a yarn jumps across the mesh (a step of %.3g)" % max(step_j, step_s))


def check_errors(mod):
    T.fresh_scene()
    # no UV map
    obj = T.plane("Bare")
    mod.api.add_knit_material(obj, setup_scene=False)
    obj.data.uv_layers.remove(obj.data.uv_layers[0])
    msg = T.op_fails(bpy.ops.knitshade.generate_yarns, object="Bare", contains="Bare has no UV map")
    T.say("no UVs: " + msg.splitlines()[0][:160])
    # no Knit Fabric
    T.plane("Plain")
    T.op_fails(bpy.ops.knitshade.generate_yarns, object="Plain", contains="Plain has no Knit Fabric material")
    T.op_fails(bpy.ops.knitshade.generate_yarns, object="Nothing", contains="there is no object 'Nothing'")
    # degenerate triangles: warned, skipped, the rest generated
    verts = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (2, 0, 0)]
    faces = [(0, 1, 2, 3), (1, 4, 2)]
    uvs = [(0, 0), (1, 0), (1, 1), (0, 1), (1, 0), (1, 0), (1, 1)]  # the second face has no UV area
    deg = mesh_object("Degenerate", verts, faces, uvs)
    mod.api.add_knit_material(deg, uv_scale=30.0, setup_scene=False)
    got, report = collect()
    mod.yarns.generate(deg, report=report)
    T.check(any("Degenerate" in t and "degenerate" in t and "1 of 3 triangles" in t for _k, t in got),
            "no warning about the degenerate triangle: %r" % got)
    T.say("degenerate: " + got[0][1])
    # UV islands of very different scales
    isl = two_quads("Islands", (0.0, 0.5), (0.6, 0.7))
    mod.api.add_knit_material(isl, uv_scale=30.0, setup_scene=False)
    got, report = collect()
    mod.yarns.generate(isl, report=report)
    T.check(any("Islands" in t and "UV islands of very different scales" in t for _k, t in got),
            "no warning about the islands' scales: %r" % got)
    T.say("islands: " + [t for _k, t in got if "islands" in t][0])
    # without the native module: the operator is disabled and says why
    ny = mod.yarns.nyarns
    saved = ny.AVAILABLE
    try:
        ny.AVAILABLE = False
        ny.available = lambda: False
        T.check(not bpy.ops.knitshade.generate_yarns.poll(), "the operator runs without the native module")
        msg = T.op_fails(bpy.ops.knitshade.generate_yarns, object="Islands")
        T.say("no native module: " + msg.splitlines()[0][:200])
        T.check("native module" in ny.why_not(), "the panel's message: %r" % ny.why_not())
    finally:
        ny.AVAILABLE = saved
        ny.available = lambda: ny.AVAILABLE


def check_scarf(mod):
    """The scarf example (examples/scenes/scarf.json: its mesh and material)."""
    T.fresh_scene()
    obj = import_obj(os.path.join(T.SOURCE, "examples", "scenes", "meshes", "scarf.obj"))
    obj.name = "scarf"
    import importlib
    kpattern = importlib.import_module(mod.__name__ + ".core.pattern")
    pat = kpattern.load(os.path.join(T.SOURCE, "examples", "patterns", "rib_1x1.knit"))
    mat = mod.api.add_knit_material(obj, pattern=pat, colours=[(0.12, 0.28, 0.62)], a=1.5, h=4.0, d=1.0, r=0.65,
                                    uv_scale=500.0, body_energy=0.85, body_reflect=0.7, optical_depth=1.0,
                                    setup_scene=False)
    t0 = time.perf_counter()
    T.equal(bpy.ops.knitshade.generate_yarns(object=obj.name), {"FINISHED"}, "scarf")
    dt = time.perf_counter() - t0
    info = yarn_object(obj)["knitshade_yarns"]
    T.say("scarf: %d curves, %d points, %.2f s (%d points per stitch); shader material: %s"
          % (info["curves"], info["points"], dt, info["samples"], mat.name))
    T.check(dt < 10.0, "the scarf's yarns took %.1f s (at most 10)" % dt)


class FakeOperator:
    """Stands in for the operator's instance to drive its modal() without a
    window (background Blender has no event loop)."""

    def __init__(self, op_class, job):
        self._job_, self._timer, self._area, self.reports = job, None, None, []
        self._end = lambda context: op_class._end(self, context)
        self._done = lambda job_: op_class._done(self, job_)

    def report(self, kind, text):
        self.reports.append((set(kind), text))


def check_modal(mod):
    """The modal steps: a timer event lays a part of the yarns, Esc stops
    with nothing changed; run to the end, the object is made."""
    T.fresh_scene()
    obj = T.plane("Big")
    mod.api.add_knit_material(obj, pattern="K P", uv_scale=900.0, setup_scene=False)
    Op = mod.yarns.KNITSHADE_OT_generate_yarns
    ev = lambda kind: type("Event", (), {"type": kind})()  # noqa: E731
    job = mod.yarns.YarnJob(bpy.context, obj, "", SAMPLES)
    T.say("estimate: " + job.describe_estimate())
    T.check(not mod.yarns.needs_confirmation(job), "a small job asks for confirmation")
    job.estimate = dict(job.estimate, points=mod.yarns.CONFIRM_POINTS + 1)
    T.check(mod.yarns.needs_confirmation(job), "a big job does not ask for confirmation")
    fake = FakeOperator(Op, mod.yarns.YarnJob(bpy.context, obj, "", SAMPLES))
    T.equal(Op.modal(fake, bpy.context, ev("TIMER")), {"RUNNING_MODAL"}, "modal after a timer event")
    T.check(0 < fake._job_.layout.band < fake._job_.layout.bands, "no progress after a step")
    T.equal(Op.modal(fake, bpy.context, ev("ESC")), {"CANCELLED"}, "modal after Esc")
    T.check(any("cancelled" in t for _k, t in fake.reports), "no report of the cancel: %r" % fake.reports)
    T.equal([o for o in bpy.data.objects if o.type == "CURVES"], [], "curves after a cancel")
    fake = FakeOperator(Op, mod.yarns.YarnJob(bpy.context, obj, "", SAMPLES))
    steps = 0
    while True:
        r = Op.modal(fake, bpy.context, ev("TIMER"))
        steps += 1
        if r != {"RUNNING_MODAL"}:
            break
    T.equal(r, {"FINISHED"}, "modal at the end")
    T.say("modal: %d timer steps; %s" % (steps, fake.reports[-1][1]))
    T.check(steps >= 2, "the job ran in %d step(s)" % steps)
    yarn_object(obj)


def check_render(mod):
    T.fresh_scene()
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 8
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.render.resolution_x = scene.render.resolution_y = 64
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    scene.view_settings.view_transform = "Standard"
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    cam.location = (0.0, -0.5, 1.1)
    cam.rotation_euler = (math.radians(25.0), 0.0, 0.0)
    scene.camera = cam
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", "SUN"))
    sun.data.energy = 4.0
    scene.collection.objects.link(sun)
    obj = T.plane("Swatch")
    mat = mod.api.add_knit_material(obj, pattern="K", uv_scale=50.0, colours=[(0.8, 0.3, 0.1)], setup_scene=False)
    images = []
    for text in ("K", "K P\nP K"):
        mod.api.set_pattern(mat, text)
        T.equal(bpy.ops.knitshade.generate_yarns(object=obj.name, samples=SAMPLES), {"FINISHED"}, "generate")
        path = T.out_path("yarns_%d.png" % len(images))
        scene.render.filepath = path
        scene.render.image_settings.file_format = "PNG"
        t0 = time.time()
        bpy.ops.render.render(write_still=True)
        img = bpy.data.images.load(path)
        a = np.array(img.pixels[:], dtype=np.float32).reshape(img.size[1], img.size[0], 4)[..., :3]
        bpy.data.images.remove(img)
        lit = float((a.sum(axis=2) > 0.05).mean())
        T.say("render of '%s': %.1f s, %.0f%% of the pixels lit, mean %.3f" % (text.replace("\n", "/"),
                                                                              time.time() - t0, 100 * lit, a.mean()))
        T.check(lit > 0.5, "the yarns' render is nearly empty (%.0f%% lit)" % (100 * lit))
        T.check(a[..., 0].mean() > 1.5 * a[..., 2].mean(), "the yarn colour does not show")
        images.append(a)
    diff = float(np.abs(images[0] - images[1]).mean())
    T.say("the two patterns' renders differ by %.3f per pixel" % diff)
    T.check(diff > 0.01, "the renders of two patterns do not differ (%.4f)" % diff)


def main():
    T.say(T.blender())
    mod = T.install()
    T.check(mod.native.AVAILABLE, "the native module did not load: %s" % mod.native.status())
    for fn in (check_plane, check_half_cylinder, check_seam, check_errors, check_modal, check_scarf, check_render):
        t0 = time.time()
        fn(mod)
        T.say("%s: %.1f s" % (fn.__name__, time.time() - t0))


T.run(main)

"""Figures of the knit shader in a real Cycles (PyPI's bpy, whose Cycles has
OSL); run with that Python:

    ~/.cache/knitshade/bpy-5.0.1/bin/python bench/cycles_bench.py OUT.json

  size       the generated shader's size and Cycles' compile time
             (_cycles.osl_compile) for a 48 x 48 and a 128 x 128 pattern;
             the JIT at render start (a tiny render's time less the same
             render's with a Diffuse BSDF).
  overhead   near field: the knit shader's sampling time over a plain
             Diffuse BSDF twin's (same plane, light, samples), a close view.
  far view   multi-scale against near field at equal quality: stitches a
             third of a pixel; each mode's RMSE against a high-sample render
             of its own, at rising sample counts; the time each needs to
             reach the near field's error at N_EQ samples, interpolated in
             log-log. The ratio is near field's time over multi-scale's.

Times are wall times of bpy.ops.render.render with the scene's threads (2
here). Cycles redoes the shader's JIT for every render, so sampling costs are
differences of two renders of different sample counts.
"""
import json
import math
import os
import sys
import time

import bpy
import _cycles
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "addon", "knitshade_blender"))
sys.path.append(os.path.join(bpy.utils.resource_path("LOCAL"), "python", "lib",
                             f"python{sys.version_info.major}.{sys.version_info.minor}", "site-packages"))
import cycles.osl  # noqa: E402
from core import pattern as core_pattern  # noqa: E402
from core import shader  # noqa: E402

OUT_DIR = os.path.join(os.environ.get("TMPDIR", "/tmp"), "knit-cycles-bench")
os.makedirs(OUT_DIR, exist_ok=True)


def scene_setup(res, samples):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    s = bpy.context.scene
    s.render.engine = "CYCLES"
    s.cycles.shading_system = True
    s.cycles.device = "CPU"
    s.cycles.samples = samples
    s.cycles.use_adaptive_sampling = False
    s.cycles.use_denoising = False
    s.render.resolution_x = s.render.resolution_y = res
    s.render.resolution_percentage = 100
    s.view_settings.view_transform = "Standard"
    s.render.image_settings.file_format = "OPEN_EXR"
    s.render.image_settings.color_depth = "32"
    s.render.threads_mode = "FIXED"
    s.render.threads = 2
    bpy.ops.mesh.primitive_plane_add(size=2.0)
    plane = bpy.context.object
    sun = bpy.data.lights.new("sun", "SUN")
    sun.energy = 3.0
    so = bpy.data.objects.new("sun", sun)
    so.rotation_euler = (math.radians(30.0), math.radians(15.0), 0.0)
    s.collection.objects.link(so)
    world = bpy.data.worlds.new("w")
    s.world = world
    world.color = (0.05, 0.05, 0.06)
    return s, plane


def camera(s, location, tilt_deg, lens=50.0):
    cam = bpy.data.cameras.new("cam")
    cam.lens = lens
    co = bpy.data.objects.new("cam", cam)
    s.collection.objects.link(co)
    co.location = location
    co.rotation_euler = (math.radians(tilt_deg), 0.0, 0.0)
    s.camera = co


def knit_material(source, uv_scale, mode=0):
    mat = bpy.data.materials.new("knit")
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    sn = nt.nodes.new("ShaderNodeScript")
    text = bpy.data.texts.new("knit.osl")
    text.write(source)
    sn.mode = "INTERNAL"
    sn.script = text
    cycles.osl.update_script_node(sn, lambda kind, msg: None)
    uv = nt.nodes.new("ShaderNodeUVMap")
    nt.links.new(uv.outputs["UV"], sn.inputs["UV"])
    sn.inputs["UVScale"].default_value = uv_scale
    sn.inputs["Mode"].default_value = mode
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(sn.outputs["BSDF"], out.inputs["Surface"])
    return mat, sn


def diffuse_material():
    mat = bpy.data.materials.new("diffuse")
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (0.5, 0.36, 0.25, 1.0)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(d.outputs["BSDF"], out.inputs["Surface"])
    return mat


def render(s, name, seed=0):
    s.cycles.seed = seed
    s.render.filepath = os.path.join(OUT_DIR, name + ".exr")
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    secs = time.perf_counter() - t0
    img = bpy.data.images.load(s.render.filepath)
    w, h = img.size
    a = np.array(img.pixels[:], dtype=np.float64).reshape(h, w, 4)[..., :3]
    bpy.data.images.remove(img)
    return a, secs


def random_pattern(side, seed):
    rng = np.random.default_rng(seed)
    return core_pattern.Pattern.from_rows(rng.integers(0, 2, size=(side, side)).tolist(),
                                          colors=rng.integers(0, 4, size=(side, side)).tolist())


def size_figures():
    out = {}
    for side in (48, 128):
        src = shader.osl_source(random_pattern(side, side))
        path = os.path.join(OUT_DIR, f"knit_{side}.osl")
        with open(path, "w") as f:
            f.write(src)
        t0 = time.perf_counter()
        ok = _cycles.osl_compile(path, path + ".oso")
        compile_s = time.perf_counter() - t0
        s, plane = scene_setup(32, 1)
        camera(s, (0.0, -1.5, 2.0), 37.0)
        mat, _ = knit_material(src, 40.0)
        plane.data.materials.append(mat)
        _, knit_s = render(s, f"jit_{side}_knit")
        plane.data.materials[0] = diffuse_material()
        _, diffuse_s = render(s, f"jit_{side}_diffuse")
        out[f"{side}x{side}"] = {"bytes": len(src), "lines": src.count("\n"), "compiled": bool(ok),
                                 "compile_s": round(compile_s, 3), "tiny_render_knit_s": round(knit_s, 3),
                                 "tiny_render_diffuse_s": round(diffuse_s, 3), "jit_s": round(knit_s - diffuse_s, 3)}
        print("size", side, out[f"{side}x{side}"], flush=True)
    return out


def sampling_seconds(s, name, low, high):
    """Seconds per render of `high - low` samples: the difference of two
    renders, so that what every render pays once (scene sync, the shader's
    JIT, which Cycles redoes for each render here) drops out."""
    s.cycles.samples = low
    _, t_low = render(s, name + f"_{low}")
    s.cycles.samples = high
    _, t_high = render(s, name + f"_{high}")
    return t_high - t_low, t_low, t_high


def overhead_figures(res=256, low=8, high=40):
    src = shader.osl_source(core_pattern.load(os.path.join(ROOT, "examples", "patterns", "stockinette.knit")))
    s, plane = scene_setup(res, low)
    camera(s, (0.0, -1.2, 1.8), 34.0)
    knit, _ = knit_material(src, 60.0)
    plane.data.materials.append(knit)
    t_knit, k_low, k_high = sampling_seconds(s, "overhead_knit", low, high)
    plane.data.materials[0] = diffuse_material()
    t_diff, d_low, d_high = sampling_seconds(s, "overhead_diffuse", low, high)
    r = {"resolution": res, "samples": [low, high], "knit_render_s": [round(k_low, 2), round(k_high, 2)],
         "diffuse_render_s": [round(d_low, 2), round(d_high, 2)], "knit_sampling_s": round(t_knit, 3),
         "diffuse_sampling_s": round(t_diff, 3), "ratio": round(t_knit / t_diff, 2)}
    print("overhead", r, flush=True)
    return r


def rmse(a, b):
    return float(np.sqrt(np.mean((a - b) ** 2)))


def far_view_figures(res=64, ref_spp=256, counts=(1, 2, 4, 8, 16, 32), n_eq=16):
    src = shader.osl_source(core_pattern.load(os.path.join(ROOT, "examples", "patterns", "seed.knit")))
    results = {}
    for mode, label in ((0, "near_field"), (1, "multi_scale")):
        s, plane = scene_setup(res, ref_spp)
        camera(s, (0.0, -1.6, 2.4), 34.0)
        mat, _ = knit_material(src, 1200.0, mode)
        plane.data.materials.append(mat)
        ref, t_ref = render(s, f"far_{label}_ref", seed=1000)
        s.cycles.samples = 1
        _, t_one = render(s, f"far_{label}_1")
        per_sample = (t_ref - t_one) / (ref_spp - 1)
        rows = []
        for n in counts:
            s.cycles.samples = n
            errs = []
            for seed in (1, 2):
                img, _ = render(s, f"far_{label}_{n}_{seed}", seed=seed)
                errs.append(rmse(img, ref))
            rows.append({"samples": n, "rmse": float(np.mean(errs)), "seconds": n * per_sample})
            print("far", label, rows[-1], flush=True)
        results[label] = {"reference_spp": ref_spp, "reference_s": round(t_ref, 2),
                          "per_sample_s": per_sample, "runs": rows, "mean": float(ref.mean())}
    # Time to the near field's error at n_eq samples, log-log interpolation.
    target = next(r["rmse"] for r in results["near_field"]["runs"] if r["samples"] == n_eq)

    def time_to(runs, err):
        e = np.log([r["rmse"] for r in runs])
        t = np.log([r["seconds"] for r in runs])
        order = np.argsort(e)
        if not e.min() <= np.log(err) <= e.max():
            # outside the measured counts interp would clamp: say so
            print(f"warning: error {err:.4g} outside the measured range "
                  f"{np.exp(e.min()):.4g}-{np.exp(e.max()):.4g}; the ratio is a bound", flush=True)
        return float(np.exp(np.interp(np.log(err), e[order], t[order])))

    t_nf = time_to(results["near_field"]["runs"], target)
    t_ms = time_to(results["multi_scale"]["runs"], target)
    ms_errs = [r["rmse"] for r in results["multi_scale"]["runs"]]
    results["equal_quality"] = {"target_rmse": target, "near_field_s": round(t_nf, 3),
                                "multi_scale_s": round(t_ms, 3), "ratio": round(t_nf / t_ms, 2),
                                "within_measured_range": bool(min(ms_errs) <= target <= max(ms_errs)),
                                "mean_difference": round(results["multi_scale"]["mean"] /
                                                         results["near_field"]["mean"] - 1.0, 4)}
    print("equal quality", results["equal_quality"], flush=True)
    return results


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(OUT_DIR, "cycles_bench.json")
    figures = {"bpy": bpy.app.version_string, "osl": _cycles.osl_version_string,
               "date": time.strftime("%Y-%m-%d %H:%M"), "size": size_figures(), "overhead": overhead_figures(),
               "far_view": far_view_figures()}
    with open(out, "w") as f:
        json.dump(figures, f, indent=2)
    print("wrote", out)


if __name__ == "__main__":
    main()

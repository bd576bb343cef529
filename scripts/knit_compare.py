#!/usr/bin/python3
"""The knit model against explicit yarns on the example scenes (docs/results.md):
renders each case with the model and with --explicit-yarns, twice each with
different seeds (the difference of the two estimates the noise; the explicit
yarns' seeds are not the model's, since renders of one seed share their
pixel jitter and their noise is then correlated), compares
the averages in linear space (RMSE, mean absolute error, bias; per pixel and
over 4x4-pixel blocks) and writes a side-by-side PNG (model | explicit |
4 x |difference|) per case.

  /usr/bin/python3 scripts/knit_compare.py BUILD_DIR OUT_DIR [SIZE] [SPP] [IMAGES_DIR]
                   [--bsdf-model exact|cycles] [--against REFS] [--cases NAMES]

--bsdf-model sets every knit material's "bsdf_model" for the model's renders
(default: as the scene has it). --against names the references, comma-separated
(default: explicit):
  explicit           the scene with --explicit-yarns (the ground truth)
  exact              the scene with "bsdf_model": "exact" and its other
                     settings as they are (the native renderer's default)
  exact_like_cycles  "exact" with what bsdf_model "cycles" changes besides the
                     BSDF (docs/cycles.md): no self-shadowing, the curvature
                     frames, and in multi-scale mode every footprint marched
                     (no class table, also below a cell), centred at its
                     sample; the BSDF is then all that differs from "cycles"
                     in the near field (the footprint's shape too in
                     multi-scale mode)
With the default reference the JSON is as it always was, one entry per case;
otherwise each case holds {"against": {REF: {pixels, blocks4, noise_rmse}}},
and with explicit among the references, each other one's own comparison with
explicit yarns in {"reference_vs_explicit": {pixels, blocks4}}.
--cases: comma-separated names of CASES (default: the first five).
"""
import argparse
import json
import math
import os
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_knit import load  # noqa: E402

# name -> (scene file, add the back light, mode to set or None)
CASES = {
    "half_cylinder_far": ("half_cylinder_front.json", True, None),
    "half_cylinder_closeup": ("half_cylinder_closeup.json", False, None),
    "swatch_far_multiscale": ("swatch_far.json", False, None),
    "swatch_far_nearfield": ("swatch_far.json", False, "near_field"),
    "swatch_closeup": ("swatch_closeup.json", False, None),
    "half_cylinder_far_multiscale": ("half_cylinder_front.json", True, "multi_scale"),
}
DEFAULT_CASES = ["half_cylinder_far", "half_cylinder_closeup", "swatch_far_multiscale", "swatch_far_nearfield",
                 "swatch_closeup"]
REFERENCES = ("explicit", "exact", "exact_like_cycles")


def knit_materials(scene):
    return [m for m in scene["materials"].values() if m.get("type") == "knit"]


def like_cycles(scene):
    """bsdf_model "exact" with the rest of what "cycles" changes (parse_knit.cpp, KnitMaterialParams::effective)."""
    for m in knit_materials(scene):
        m["bsdf_model"] = "exact"
        m["self_shadowing"] = False
        m.setdefault("frames", "curvature")
        if m.get("mode") == "multi_scale":
            m["footprint_table"] = False
            m["near_field_below_cell"] = False
            m.setdefault("footprint_centre", "sample")
    return scene


def main():
    ap = argparse.ArgumentParser(usage=__doc__)
    ap.add_argument("build")
    ap.add_argument("out")
    ap.add_argument("size", nargs="?", type=int, default=128)
    ap.add_argument("spp", nargs="?", type=int, default=1024)
    ap.add_argument("images", nargs="?", default=None)
    ap.add_argument("--bsdf-model", choices=("exact", "cycles"), default=None)
    ap.add_argument("--against", default="explicit")
    ap.add_argument("--cases", default=",".join(DEFAULT_CASES))
    a = ap.parse_args()
    refs = a.against.split(",")
    for r in refs:
        if r not in REFERENCES:
            ap.error(f"--against: unknown reference '{r}' (known: {', '.join(REFERENCES)})")
    cases = a.cases.split(",")
    for c in cases:
        if c not in CASES:
            ap.error(f"--cases: unknown case '{c}' (known: {', '.join(CASES)})")
    cli = os.path.join(a.build, "knitshade")
    out, size, spp, images = a.out, a.size, a.spp, a.images
    os.makedirs(out, exist_ok=True)
    classic = refs == ["explicit"]
    results = {}

    def run(args):
        return subprocess.run([cli] + args, check=True, capture_output=True, text=True).stdout

    def render(name, method, scene, seeds, explicit=False):
        """Two half-sample renders of `scene` with the given seeds: (their average's path, the noise RMSE of
        the average, seconds)."""
        path = os.path.join(out, f"{name}_{method}.json")
        with open(path, "w") as f:
            json.dump(scene, f, indent=1)
        halves, seconds = [], 0.0
        for seed in seeds:
            img = os.path.join(out, f"{name}_{method}_{seed}.exr")
            rep = img + ".report.json"
            args = ["render", path, "-o", img, "--spp", str(spp // 2), "--seed", str(seed), "--quiet",
                    "--report", rep]
            if explicit:
                args.append("--explicit-yarns")
            run(args)
            seconds += json.load(open(rep))["seconds"]["render"]
            halves.append(img)
        avg = os.path.join(out, f"{name}_{method}.exr")
        subprocess.run(["oiiotool", halves[0], halves[1], "--add", "--mulc", "0.5", "-o", avg], check=True)
        noise = json.loads(run(["compare", halves[0], halves[1]]))["rmse"] / 2
        return avg, noise, seconds

    for name in cases:
        scene_file, back_light, mode = CASES[name]
        scene = load(scene_file)
        scene["film"]["width"] = scene["film"]["height"] = size
        if back_light:
            scene["lights"].append({"type": "directional", "to_light": [-0.25, 0.3, -1],
                                    "irradiance": [2.4, 2.35, 2.3]})
        for m in knit_materials(scene):
            if mode:
                m["mode"] = mode
        model_scene = json.loads(json.dumps(scene))
        if a.bsdf_model:
            for m in knit_materials(model_scene):
                m["bsdf_model"] = a.bsdf_model
        model, model_noise, model_seconds = render(name, "model", model_scene, (1, 2))
        seconds = {"model": model_seconds}
        against = {}
        for seed0, ref in enumerate(refs):
            seeds = (3 + 2 * seed0, 4 + 2 * seed0)
            if ref == "explicit":
                img, noise, secs = render(name, "explicit", scene, seeds, explicit=True)
            elif ref == "exact":
                s = json.loads(json.dumps(scene))
                for m in knit_materials(s):
                    m["bsdf_model"] = "exact"
                img, noise, secs = render(name, "exact", s, seeds)
            else:
                img, noise, secs = render(name, ref, like_cycles(json.loads(json.dumps(scene))), seeds)
            seconds[ref] = secs
            px = json.loads(run(["compare", model, img]))
            bl = json.loads(run(["compare", model, img, "--block", "4"]))
            against[ref] = {"pixels": px, "blocks4": bl, "noise_rmse": math.sqrt(model_noise ** 2 + noise ** 2)}
            print(f"{name} against {ref}: RMSE {px['rmse']:.4f} (rel {px['rel_rmse']:.3f}), MAE {px['mae']:.4f} "
                  f"(rel {px['rel_mae']:.3f}), bias {px['bias']:+.4f} (rel {px['rel_bias']:+.3f}); "
                  f"4x4 blocks RMSE {bl['rmse']:.4f} (rel {bl['rel_rmse']:.3f}); "
                  f"noise RMSE {against[ref]['noise_rmse']:.4f}; mean {px['mean_b']:.4f}", flush=True)
            if images:
                os.makedirs(images, exist_ok=True)
                diff = os.path.join(out, f"{name}_{ref}_diff.exr")
                subprocess.run(["oiiotool", model, img, "--sub", "--abs", "--mulc", "4", "-o", diff], check=True)
                tag = name if classic else f"{name}_{a.bsdf_model or 'model'}_vs_{ref}"
                subprocess.run(["oiiotool", model, img, diff, "--mosaic", "3x1",
                                "--tocolorspace", "sRGB", "-d", "uint8",
                                "-o", os.path.join(images, f"compare_{tag}.png")], check=True)
        if "explicit" in refs:
            # The other references against the ground truth too: what each departs from it by.
            for ref in refs:
                if ref == "explicit":
                    continue
                a_img = os.path.join(out, f"{name}_{ref}.exr")
                e_img = os.path.join(out, f"{name}_explicit.exr")
                against[ref]["reference_vs_explicit"] = {
                    "pixels": json.loads(run(["compare", a_img, e_img])),
                    "blocks4": json.loads(run(["compare", a_img, e_img, "--block", "4"]))}
        if classic:
            r = against["explicit"]
            results[name] = {"size": size, "spp": spp, "pixels": r["pixels"], "blocks4": r["blocks4"],
                             "noise_rmse": r["noise_rmse"], "seconds": seconds}
        else:
            results[name] = {"size": size, "spp": spp, "bsdf_model": a.bsdf_model or "as the scene",
                             "against": against, "seconds": seconds}
    with open(os.path.join(out, "knit_compare.json"), "w") as f:
        json.dump(results, f, indent=2)


if __name__ == "__main__":
    main()

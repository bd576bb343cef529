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
"""
import json
import math
import os
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_knit import load  # noqa: E402

CASES = [
    ("half_cylinder_far", "half_cylinder_front.json", True),  # + the back light
    ("half_cylinder_closeup", "half_cylinder_closeup.json", False),
    ("swatch_far_multiscale", "swatch_far.json", False),
    ("swatch_far_nearfield", "swatch_far.json", False),
    ("swatch_closeup", "swatch_closeup.json", False),
]


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        sys.exit(2)
    cli = os.path.join(sys.argv[1], "knitshade")
    out = sys.argv[2]
    size = int(sys.argv[3]) if len(sys.argv) > 3 else 128
    spp = int(sys.argv[4]) if len(sys.argv) > 4 else 1024
    images = sys.argv[5] if len(sys.argv) > 5 else None
    os.makedirs(out, exist_ok=True)
    results = {}

    def run(args):
        return subprocess.run([cli] + args, check=True, capture_output=True, text=True).stdout

    for name, scene_file, back_light in CASES:
        scene = load(scene_file)
        scene["film"]["width"] = scene["film"]["height"] = size
        if back_light:
            scene["lights"].append({"type": "directional", "to_light": [-0.25, 0.3, -1],
                                    "irradiance": [2.4, 2.35, 2.3]})
        if name.endswith("nearfield"):
            scene["materials"]["wool"]["mode"] = "near_field"
        path = os.path.join(out, name + ".json")
        with open(path, "w") as f:
            json.dump(scene, f, indent=1)
        avg, noise, seconds = {}, {}, {}
        for method in ("model", "explicit"):
            halves = []
            seconds[method] = 0.0
            for seed in ((1, 2) if method == "model" else (3, 4)):
                img = os.path.join(out, f"{name}_{method}_{seed}.exr")
                rep = img + ".report.json"
                args = ["render", path, "-o", img, "--spp", str(spp // 2), "--seed", str(seed), "--quiet",
                        "--report", rep]
                if method == "explicit":
                    args.append("--explicit-yarns")
                run(args)
                seconds[method] += json.load(open(rep))["seconds"]["render"]
                halves.append(img)
            a = os.path.join(out, f"{name}_{method}.exr")
            subprocess.run(["oiiotool", halves[0], halves[1], "--add", "--mulc", "0.5", "-o", a], check=True)
            avg[method] = a
            noise[method] = json.loads(run(["compare", halves[0], halves[1]]))["rmse"] / 2
        px = json.loads(run(["compare", avg["model"], avg["explicit"]]))
        bl = json.loads(run(["compare", avg["model"], avg["explicit"], "--block", "4"]))
        res = {"size": size, "spp": spp, "pixels": px, "blocks4": bl,
               "noise_rmse": math.sqrt(noise["model"] ** 2 + noise["explicit"] ** 2),
               "seconds": seconds}
        results[name] = res
        print(f"{name}: RMSE {px['rmse']:.4f} (rel {px['rel_rmse']:.3f}), MAE {px['mae']:.4f} "
              f"(rel {px['rel_mae']:.3f}), bias {px['bias']:+.4f} (rel {px['rel_bias']:+.3f}); "
              f"4x4 blocks RMSE {bl['rmse']:.4f} (rel {bl['rel_rmse']:.3f}); noise RMSE {res['noise_rmse']:.4f}; "
              f"mean {px['mean_b']:.4f}", flush=True)
        if images:
            os.makedirs(images, exist_ok=True)
            diff = os.path.join(out, f"{name}_diff.exr")
            subprocess.run(["oiiotool", avg["model"], avg["explicit"], "--sub", "--abs", "--mulc", "4", "-o", diff],
                           check=True)
            subprocess.run(["oiiotool", avg["model"], avg["explicit"], diff, "--mosaic", "3x1",
                            "--tocolorspace", "sRGB", "-d", "uint8",
                            "-o", os.path.join(images, f"compare_{name}.png")], check=True)
    with open(os.path.join(out, "knit_compare.json"), "w") as f:
        json.dump(results, f, indent=2)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Multi-scale with table_min_cells 0.25 and 0.5 and the near field, each
against explicit yarns, on three scenes at sizes where most footprints are a
quarter to half a stitch cell (docs/multiscale.md, "Footprints of a quarter
cell"): the half cylinder at 512 x 512 (front and back light), the far
swatch and the scarf at their example sizes.

Every method renders twice with different seeds, so each image's noise
(the RMSE between its two renders over sqrt 2) can be taken out of its RMSE
against explicit yarns in quadrature. A method's render of seed 1 is
compared with the explicit render of seed 2 and the other way round (the
mean of the two squared RMSEs): two renders of one seed share their pixel
jitter, and their correlated noise made the near field's RMSE look 13%
smaller than independent noise would. What is left is the systematic error,
printed per pixel and over 4 x 4 blocks, relative to the mean, with the bias
and the share of knit hits the class table served. About 25 minutes on 2
cores at the default 128 samples.

A method name ending in "_sample" centres the multi-scale footprints at
each sample's hit instead of its pixel's centre (footprint_centre).

  /usr/bin/python3 scripts/quarter_cells_compare.py BUILD_DIR OUT_DIR [SPP]
      [--scenes half_cylinder_512,swatch_far,scarf]
      [--methods near_field,multi_scale_0.5,multi_scale_0.25]
      [--size 512] [--no-ply]

--size sets the half cylinder's size (its scene is named half_cylinder_SIZE);
--no-ply turns off the ply detail of every knit material, in the explicit
yarns too.
"""
import argparse
import json
import math
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_knit import load, sized  # noqa: E402

BACK_LIGHT = {"type": "directional", "to_light": [-0.25, 0.3, -1], "irradiance": [2.4, 2.35, 2.3]}


def scenes(size=512):
    hc = sized(load("half_cylinder_front.json"), size, size)
    hc["lights"].append(BACK_LIGHT)
    return {f"half_cylinder_{size}": hc, "swatch_far": load("swatch_far.json"), "scarf": load("scarf.json")}


def variant(scene, method, ply=True):
    s = json.loads(json.dumps(scene))
    for m in s["materials"].values():
        if m["type"] != "knit":
            continue
        if not ply:
            m.setdefault("ply", {})["enabled"] = False
        if method == "near_field":
            m["mode"] = "near_field"
        elif method.startswith("multi_scale"):
            m["mode"] = "multi_scale"
            m["table_min_cells"] = 0.25 if "0.25" in method else 0.5
            m["footprint_centre"] = "sample" if method.endswith("_sample") else "pixel"
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("build")
    ap.add_argument("out")
    ap.add_argument("spp", nargs="?", type=int, default=128)
    ap.add_argument("--scenes", default="half_cylinder_512,swatch_far,scarf")
    ap.add_argument("--methods", default="near_field,multi_scale_0.5,multi_scale_0.25")
    ap.add_argument("--size", type=int, default=512, help="the half cylinder's width and height in pixels")
    ap.add_argument("--no-ply", action="store_true", help="every knit material without ply detail")
    args = ap.parse_args()
    cli = os.path.join(args.build, "knitshade")
    out, spp = args.out, args.spp
    methods = args.methods.split(",")
    os.makedirs(out, exist_ok=True)

    def compare(a, b, block):
        r = subprocess.run([cli, "compare", a, b, "--block", str(block)], check=True, capture_output=True, text=True)
        return json.loads(r.stdout)

    results = {}
    for name, scene in scenes(args.size).items():
        if name not in args.scenes.split(","):
            continue
        renders = {}
        for method in ["explicit"] + methods:
            path = os.path.join(out, f"{name}_{method}.json")
            with open(path, "w") as f:
                json.dump(variant(scene, method, not args.no_ply), f, indent=1)
            runs = []
            for seed in (1, 2):
                img = os.path.join(out, f"{name}_{method}_{seed}.exr")
                rep = img + ".report.json"
                cmd = [cli, "render", path, "-o", img, "--spp", str(spp), "--seed", str(seed), "--quiet",
                       "--report", rep, "--cache-dir", os.path.join(out, "table-cache")]
                if method == "explicit":
                    cmd.append("--explicit-yarns")
                subprocess.run(cmd, check=True)
                with open(rep) as f:
                    r = json.load(f)
                runs.append({"image": img, "seconds": r["seconds"]["render"],
                             "table_share": r["knit"]["table_hits"] / max(r["knit"]["hits"], 1)})
            renders[method] = runs
            print(f"{name} {method}: {[round(x['seconds'], 2) for x in runs]} s, "
                  f"table share {runs[0]['table_share']:.3f}", flush=True)
        res = {"spp": spp, "seconds": {m: [x["seconds"] for x in v] for m, v in renders.items()},
               "table_share": {m: v[0]["table_share"] for m, v in renders.items()}}
        for block in (1, 4):
            noise = {m: compare(v[0]["image"], v[1]["image"], block)["rmse"] / math.sqrt(2)
                     for m, v in renders.items()}
            for method in methods:
                d = compare(renders[method][0]["image"], renders["explicit"][1]["image"], block)
                d2 = compare(renders[method][1]["image"], renders["explicit"][0]["image"], block)
                d["rmse"] = math.sqrt(0.5 * (d["rmse"] ** 2 + d2["rmse"] ** 2))
                d["rel_bias"] = 0.5 * (d["rel_bias"] + d2["rel_bias"])
                left = d["rmse"] ** 2 - noise[method] ** 2 - noise["explicit"] ** 2
                systematic = math.sqrt(left) if left > 0 else None  # None: within the noise
                entry = {"rmse": d["rmse"], "noise": noise[method], "noise_explicit": noise["explicit"],
                         "systematic": systematic,
                         "relative_systematic": systematic / d["mean_b"] if systematic else None,
                         "relative_bias": d["rel_bias"]}
                res[f"{method}_block{block}"] = entry
                rel = f"{entry['relative_systematic']:.4f}" if systematic else "within the noise"
                print(f"  {method}, block {block}: RMSE {d['rmse']:.5f}, systematic {rel} of the mean, "
                      f"bias {d['rel_bias']:+.4f}", flush=True)
        results[name] = res
    with open(os.path.join(out, "quarter_cells_compare.json"), "w") as f:
        json.dump(results, f, indent=2)
    print("wrote", os.path.join(out, "quarter_cells_compare.json"))


if __name__ == "__main__":
    main()

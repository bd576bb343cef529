#!/usr/bin/python3
"""Multi-scale with table_min_cells 0.25 and 0.5 and the near field, each
against explicit yarns, on three scenes at sizes where most footprints are a
quarter to half a stitch cell (docs/multiscale.md, "Footprints of a quarter
cell"): the half cylinder at 512 x 512 (front and back light), the far
swatch and the scarf at their example sizes.

Every method renders twice with different seeds, so each image's noise
(the RMSE between its two renders over sqrt 2) can be taken out of its RMSE
against explicit yarns in quadrature; what is left is the systematic error,
printed per pixel and over 4 x 4 blocks, relative to the mean, with the bias
and the share of knit hits the class table served. About 25 minutes on 2
cores at the default 128 samples.

  /usr/bin/python3 scripts/quarter_cells_compare.py BUILD_DIR OUT_DIR [SPP]
"""
import json
import math
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_knit import load, sized  # noqa: E402

BACK_LIGHT = {"type": "directional", "to_light": [-0.25, 0.3, -1], "irradiance": [2.4, 2.35, 2.3]}


def scenes():
    hc = sized(load("half_cylinder_front.json"), 512, 512)
    hc["lights"].append(BACK_LIGHT)
    return {"half_cylinder_512": hc, "swatch_far": load("swatch_far.json"), "scarf": load("scarf.json")}


def variant(scene, method):
    s = json.loads(json.dumps(scene))
    for m in s["materials"].values():
        if m["type"] != "knit":
            continue
        if method == "near_field":
            m["mode"] = "near_field"
        elif method.startswith("multi_scale"):
            m["mode"] = "multi_scale"
            m["table_min_cells"] = 0.25 if method.endswith("0.25") else 0.5
    return s


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        sys.exit(2)
    cli = os.path.join(sys.argv[1], "knitshade")
    out = sys.argv[2]
    spp = int(sys.argv[3]) if len(sys.argv) > 3 else 128
    os.makedirs(out, exist_ok=True)

    def compare(a, b, block):
        r = subprocess.run([cli, "compare", a, b, "--block", str(block)], check=True, capture_output=True, text=True)
        return json.loads(r.stdout)

    results = {}
    for name, scene in scenes().items():
        renders = {}
        for method in ("explicit", "near_field", "multi_scale_0.5", "multi_scale_0.25"):
            path = os.path.join(out, f"{name}_{method}.json")
            with open(path, "w") as f:
                json.dump(variant(scene, method), f, indent=1)
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
            for method in ("near_field", "multi_scale_0.5", "multi_scale_0.25"):
                d = compare(renders[method][0]["image"], renders["explicit"][0]["image"], block)
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

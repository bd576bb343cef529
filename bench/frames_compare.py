#!/usr/bin/env python3
"""The error of the curvature estimate the OSL shader marches with (a
constant normal curvature per triangle, from the vertex normals: the native
renderer's `frames: "curvature"`, docs/shader.md) against exact frame
lookups on the mesh (`frames: "exact"`), on the half cylinder close-up and
a whole sphere.

    /usr/bin/python3 bench/frames_compare.py BUILD_DIR OUT_DIR [--size N] [--spp N]

Each scene is rendered with exact frames at seeds 1 and 2 and with the
estimate at seed 1. Renders of one seed share their random numbers, so the
estimate against exact at seed 1 is the frames' difference alone; exact
against exact is the noise for scale. Prints and writes OUT_DIR/frames.json:
relative RMSE per pixel and over 4 x 4 blocks, and the relative bias.
"""
import argparse
import copy
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "examples", "scenes")


def scenes(size, spp):
    with open(os.path.join(SCENES, "half_cylinder_closeup.json")) as f:
        base = json.load(f)
    base["materials"]["wool"]["pattern"] = os.path.join(SCENES, base["materials"]["wool"]["pattern"])
    base["objects"][0]["mesh"] = os.path.join(SCENES, base["objects"][0]["mesh"])
    base["film"].update(width=size, height=size, spp=spp)
    sphere = copy.deepcopy(base)
    sphere["objects"][0]["mesh"] = os.path.join(SCENES, "meshes", "sphere.obj")
    sphere["camera"] = {"position": [0.0, 0.4, 3.4], "look_at": [0.0, 0.0, 0.0], "fov": 40}
    sphere["materials"]["wool"]["uv_scale"] = 240
    return {"half_cylinder_closeup": base, "sphere": sphere}


def render(cli, scene, frames, seed, out):
    s = copy.deepcopy(scene)
    s["materials"]["wool"]["frames"] = frames
    s["film"]["seed"] = seed
    path = out + ".json"
    with open(path, "w") as f:
        json.dump(s, f)
    subprocess.run([cli, "render", path, "-o", out + ".exr", "--no-cache"], check=True, capture_output=True)
    return out + ".exr"


def compare(cli, a, b, block=None):
    cmd = [cli, "compare", a, b] + (["--block", str(block)] if block else [])
    return json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build")
    ap.add_argument("out")
    ap.add_argument("--size", type=int, default=240)
    ap.add_argument("--spp", type=int, default=64)
    args = ap.parse_args()
    cli = os.path.join(args.build, "knitshade")
    os.makedirs(args.out, exist_ok=True)
    results = {}
    for name, scene in scenes(args.size, args.spp).items():
        exact1 = render(cli, scene, "exact", 1, os.path.join(args.out, f"{name}_exact_1"))
        exact2 = render(cli, scene, "exact", 2, os.path.join(args.out, f"{name}_exact_2"))
        curv1 = render(cli, scene, "curvature", 1, os.path.join(args.out, f"{name}_curvature_1"))
        r = {}
        for label, (a, b) in {"estimate": (curv1, exact1), "noise": (exact2, exact1)}.items():
            px, bl = compare(cli, a, b), compare(cli, a, b, 4)
            r[label] = {"rel_rmse": px["rel_rmse"], "block_rel_rmse": bl["rel_rmse"], "rel_bias": px["rel_bias"]}
        results[name] = r
        e, n = r["estimate"], r["noise"]
        print(f"{name}: curvature estimate against exact frames {e['rel_rmse'] * 100:.1f}% per pixel, "
              f"{e['block_rel_rmse'] * 100:.2f}% over 4x4 blocks, bias {e['rel_bias'] * 100:+.3f}% "
              f"(noise between seeds: {n['rel_rmse'] * 100:.1f}%, {n['block_rel_rmse'] * 100:.2f}%)")
    with open(os.path.join(args.out, "frames.json"), "w") as f:
        json.dump({"size": args.size, "spp": args.spp, "scenes": results}, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())

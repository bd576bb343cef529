"""An exported scene rendered by the standalone Cycles app (Cycles 4.2 with
OSL), where one is found: $KNIT_CYCLES (or $KNITSHADE_CYCLES), else `cycles`
on PATH. Without one it says plainly that it did not run and exits 77.

    render_standalone.py --cli KNITSHADE --out DIR

A small knit swatch (two colours, holes, a sun and a sky) is exported with
`knitshade export-cycles` and rendered with
`cycles --shadingsys osl --samples 16 --width 96 --height 72`; the image
must exist, be finite and not black, and its mean within 50% of the native
renderer's image of the same scene rendered as Cycles does
(`bsdf_model: "cycles"`): a gross check of units, camera and shader
hook-up, not a comparison within the noise.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def find_cycles():
    for var in ("KNIT_CYCLES", "KNITSHADE_CYCLES"):
        path = os.environ.get(var)
        if path:
            return path if os.access(path, os.X_OK) else None
    return shutil.which("cycles")


def mean_of(cli, image):
    r = subprocess.run([cli, "compare", image, image], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"knitshade compare {image}: {r.stderr.strip()}")
    return json.loads(r.stdout)["mean_a"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    cycles = find_cycles()
    if not cycles:
        print("No standalone Cycles found (set KNIT_CYCLES, or put `cycles` on PATH): "
              "the Cycles render of an exported scene did NOT run.")
        return 77
    os.makedirs(a.out, exist_ok=True)
    scene = {
        "version": 1,
        "film": {"width": 96, "height": 72, "spp": 16, "seed": 1},
        "camera": {"position": [0, -0.25, 0.45], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
        "integrator": {"max_depth": 6},
        "lights": [{"type": "environment", "color": [0.15, 0.16, 0.2]},
                   {"type": "directional", "to_light": [0.3, -0.4, 1], "irradiance": [3, 2.9, 2.8]}],
        "materials": {"wool": {"type": "knit", "pattern": ["KKPP", "KKPP", "PPKK", "PPKK"],
                               "colors": [[0, 0, 1, 1], [0, 0, 1, 1], [1, 1, 0, 0], [1, 1, 0, 0]],
                               "uv_scale": 60, "r": 0.5, "yarn_colors": [[0.75, 0.3, 0.15], [0.85, 0.8, 0.7]],
                               "bsdf_model": "cycles"}},
        "objects": [{"name": "swatch", "mesh": os.path.join(ROOT, "examples", "scenes", "meshes", "quad.obj"),
                     "material": "wool"}],
    }
    path = os.path.join(a.out, "swatch.json")
    with open(path, "w") as f:
        json.dump(scene, f, indent=1)
    xml = os.path.join(a.out, "swatch.xml")
    r = subprocess.run([a.cli, "export-cycles", path, "-o", xml], capture_output=True, text=True)
    if r.returncode != 0:
        print(f"export failed: {r.stderr.strip()}")
        return 1
    image = os.path.join(a.out, "swatch_cycles.exr")
    if os.path.exists(image):
        os.remove(image)
    cmd = [cycles, "--shadingsys", "osl", "--samples", "16", "--width", "96", "--height", "72", "--output", image, xml]
    t0 = time.time()
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=1200)
    print(f"{' '.join(cmd)}: exit {r.returncode} after {time.time() - t0:.1f} s")
    if r.returncode != 0 or not os.path.exists(image):
        print(r.stdout[-3000:], r.stderr[-3000:])
        print("FAIL: Cycles wrote no image")
        return 1
    m_cycles = mean_of(a.cli, image)
    native = os.path.join(a.out, "swatch_native.exr")
    r = subprocess.run([a.cli, "render", path, "-o", native, "--quiet", "--no-cache"], capture_output=True, text=True)
    if r.returncode != 0:
        print(f"native render failed: {r.stderr.strip()}")
        return 1
    m_native = mean_of(a.cli, native)
    print(f"mean radiance: Cycles {m_cycles:.5g}, native (bsdf_model cycles) {m_native:.5g}")
    ok = True
    if not (m_cycles == m_cycles and m_cycles > 1e-3 * max(m_native, 1e-6)):
        print("FAIL: the Cycles image is black or not finite")
        ok = False
    elif abs(m_cycles / m_native - 1) > 0.5:
        print(f"FAIL: the Cycles image's mean is {m_cycles / m_native:.3f} x the native one's")
        ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

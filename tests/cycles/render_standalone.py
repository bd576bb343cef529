"""Exported scenes rendered by the standalone Cycles app (Cycles 4.2 with
OSL) against the native renderer's model of Cycles, where such an app is
found: $KNIT_CYCLES (or $KNITSHADE_CYCLES), else `cycles` on PATH. Without
one it says plainly that it did not run and exits 77.

    render_standalone.py --cli KNITSHADE --out DIR [--figures OUT.json]
                         [--cycles-version 4|5]

The scenes of comparison_scenes.py (the flat swatch, the swatch over a
floor, the half cylinder and the sphere) are exported with `knitshade
export-cycles`, rendered by `cycles --shadingsys osl` and by `knitshade
render` (their knit materials have "bsdf_model": "cycles" and the
"cycles_version" of the app's `cycles --version`, or of
--cycles-version), each with seeds 1 and 2. From the four renders (linear
radiance):

- noise: sqrt((RMSE(C1, C2)^2 + RMSE(N1, N2)^2) / 2), what RMSE(Ci, Nj)
  would be were the two renderers' expectations equal;
- the systematic difference D = sqrt(mean RMSE(Ci, Nj)^2 - noise^2);
- "x the noise" = sqrt(1 + 2 D^2 / noise^2): the RMSE between the
  two-seed means over the noise of that difference, the figure
  tests/osl/native_vs_cycles.py prints for Blender's Cycles;
- bias: mean(C) / mean(N) - 1.

A scene passes when it is below 1.3 x the noise and its bias within 3%
(96 x 96 pixels, 16 samples; --figures: 192 x 192, 64 samples, figures
written, nothing asserted). Cycles' own errors (an .oso it cannot find, a
shader it cannot compile) are printed as they come. Each scene's knit
render is timed against its diffuse twin (the knit material replaced by a
diffuse one of the mean yarn colour), both with OSL, at 64 samples: the
time per sample after the first (which carries the shader's JIT), and the
set-up time before the first sample.
"""
import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from comparison_scenes import diffuse_twin, scenes  # noqa: E402

ERROR_LINE = re.compile(r"^.*(error|No \.oso|not supported|could not|failed).*$", re.IGNORECASE | re.MULTILINE)


def find_cycles():
    for var in ("KNIT_CYCLES", "KNITSHADE_CYCLES"):
        path = os.environ.get(var)
        if path:
            if not os.access(path, os.X_OK):
                print(f"{var}={path} is not an executable file")
                return None
            return path
    return shutil.which("cycles")


def cycles_major(cycles):
    """4 for the Cycles before 5.0, 5 for 5.0 and later, from `cycles --version`."""
    out = subprocess.run([cycles, "--version"], capture_output=True, text=True, timeout=60).stdout
    m = re.match(r"\s*(\d+)\.", out)
    if not m:
        raise SystemExit(f"{cycles} --version printed {out.strip()!r}, not a version: "
                         "name the Cycles with --cycles-version 4 or 5")
    return 4 if int(m.group(1)) < 5 else 5


def write_json(path, data):
    with open(path, "w") as f:
        json.dump(data, f, indent=1)


def export(cli, scene, path_json):
    write_json(path_json, scene)
    xml = path_json[:-5] + ".xml"
    r = subprocess.run([cli, "export-cycles", path_json, "-o", xml], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"knitshade export-cycles {path_json}: {r.stderr.strip()}")
    return xml


class CyclesError(RuntimeError):
    pass


def render_cycles(cycles, xml, image, size, spp):
    """Renders xml to image; returns (set-up seconds, seconds per sample
    after the first). Raises CyclesError with Cycles' own messages."""
    if os.path.exists(image):
        os.remove(image)
    cmd = [cycles, "--shadingsys", "osl", "--background", "--threads", "2", "--samples", str(spp),
           "--width", str(size), "--height", str(size), "--output", image, xml]
    t0 = time.time()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, cwd=os.path.dirname(xml))
    text, marks = b"", {}
    while True:
        chunk = os.read(p.stdout.fileno(), 65536)
        if not chunk:
            break
        text += chunk
        now = time.time() - t0
        for key in (b"Sample 0/", b"Sample 1/", b"Writing image"):
            if key in text and key not in marks:
                marks[key] = now
    rc = p.wait()
    out = text.decode(errors="replace")
    errors = sorted(set(m.group(0).strip()[-300:] for m in ERROR_LINE.finditer(out.replace("\r", "\n"))))
    if rc != 0 or not os.path.exists(image) or errors:
        detail = "\n  ".join(errors) if errors else out[-2000:]
        raise CyclesError(f"`{' '.join(cmd)}` exited {rc}" +
                          ("" if os.path.exists(image) else ", no image written") + f"; Cycles said:\n  {detail}")
    setup = marks.get(b"Sample 0/", float("nan"))
    first, done = marks.get(b"Sample 1/"), marks.get(b"Writing image")
    per_sample = (done - first) / (spp - 1) if first is not None and done is not None and spp > 1 else float("nan")
    return setup, per_sample


def render_native(cli, path_json, image):
    r = subprocess.run([cli, "render", path_json, "-o", image, "--quiet", "--no-cache"],
                       capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"knitshade render {path_json}: {r.stderr.strip()}")


def stats(cli, a, b, block=1):
    cmd = [cli, "compare", a, b] + (["--block", str(block)] if block > 1 else [])
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"knitshade compare {a} {b}: {r.stderr.strip()}")
    s = json.loads(r.stdout)
    for key in ("rmse", "mean_a", "mean_b"):
        if not math.isfinite(s[key]):
            raise RuntimeError(f"knitshade compare {a} {b}: {key} is {s[key]} (NaN or infinite pixels)")
    return s


def compare(cli, c, n, block=1):
    """c, n: the Cycles and the native images of seeds 1 and 2."""
    cc = stats(cli, c[0], c[1], block)
    nn = stats(cli, n[0], n[1], block)
    cross = [stats(cli, ci, nj, block) for ci in c for nj in n]
    noise2 = 0.5 * (cc["rmse"] ** 2 + nn["rmse"] ** 2)
    cross2 = sum(s["rmse"] ** 2 for s in cross) / len(cross)
    d2 = max(0.0, cross2 - noise2)
    mean_c = 0.5 * (cc["mean_a"] + cc["mean_b"])
    mean_n = 0.5 * (nn["mean_a"] + nn["mean_b"])
    return {"mean_cycles": mean_c, "mean_native": mean_n, "bias": mean_c / mean_n - 1.0,
            "noise": math.sqrt(noise2), "systematic": math.sqrt(d2), "rel_systematic": math.sqrt(d2) / mean_n,
            "over_noise": math.sqrt(1.0 + 2.0 * d2 / noise2) if noise2 > 0 else float("inf")}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--figures", help="render larger, write the figures to this JSON file, assert nothing")
    ap.add_argument("--cycles-version", type=int, choices=(4, 5),
                    help="the Cycles whose closure rules the native renders follow (default: the app's own)")
    a = ap.parse_args()
    cycles = find_cycles()
    if not cycles:
        print("No standalone Cycles found (set KNIT_CYCLES, or put `cycles` on PATH): "
              "the Cycles renders of exported scenes did NOT run.")
        return 77
    if a.cycles_version is None:
        a.cycles_version = cycles_major(cycles)
    print(f"{cycles}: the native renders follow Cycles {a.cycles_version}'s closure rules", flush=True)
    os.makedirs(a.out, exist_ok=True)
    size, spp = (192, 64) if a.figures else (96, 16)
    timing_spp = 64
    results, failures = {}, []
    for name, scene in scenes(size, spp, a.cycles_version).items():
        c, n = [], []
        try:
            for seed in (1, 2):
                s = json.loads(json.dumps(scene))
                s["film"]["seed"] = seed
                base = os.path.join(a.out, f"{name}_{seed}.json")
                xml = export(a.cli, s, base)
                c.append(base[:-5] + "_cycles.exr")
                render_cycles(cycles, xml, c[-1], size, spp)
                n.append(base[:-5] + "_native.exr")
                render_native(a.cli, base, n[-1])
            r = compare(a.cli, c, n)
            r["blocks_4x4"] = compare(a.cli, c, n, block=4)
            knit_xml = export(a.cli, scene, os.path.join(a.out, f"{name}_time.json"))
            twin_xml = export(a.cli, diffuse_twin(scene), os.path.join(a.out, f"{name}_diffuse_twin.json"))
            setup_k, per_k = render_cycles(cycles, knit_xml, knit_xml[:-4] + ".exr", size, timing_spp)
            setup_d, per_d = render_cycles(cycles, twin_xml, twin_xml[:-4] + ".exr", size, timing_spp)
        except (CyclesError, RuntimeError) as e:
            print(f"FAIL: {name}: {e}", flush=True)
            failures.append(name)
            continue
        r.update({"ms_per_sample_knit": 1e3 * per_k, "ms_per_sample_diffuse": 1e3 * per_d,
                  "knit_over_diffuse": per_k / per_d, "setup_s_knit": setup_k, "setup_s_diffuse": setup_d})
        results[name] = r
        ok = r["over_noise"] < 1.3 and abs(r["bias"]) < 0.03
        print(("ok:   " if ok or a.figures else "FAIL: ") +
              f"{name}: standalone Cycles against native 'cycles' at {size} px, {spp} spp: "
              f"{r['over_noise']:.2f} x the noise (4x4 blocks {r['blocks_4x4']['over_noise']:.2f} x), "
              f"systematic {100 * r['rel_systematic']:.1f}% of the mean per pixel, bias {100 * r['bias']:+.2f}% "
              f"(means {r['mean_cycles']:.4f}, {r['mean_native']:.4f})", flush=True)
        print(f"      time at {size} px, {timing_spp} spp: knit {1e3 * per_k:.1f} ms per sample, diffuse twin "
              f"{1e3 * per_d:.1f} ms: {per_k / per_d:.1f} x; set-up before the first sample {setup_k:.1f} s "
              f"(twin {setup_d:.1f} s)", flush=True)
        if not ok and not a.figures:
            failures.append(name)
    if a.figures:
        write_json(a.figures, {"size": size, "spp": spp, "timing_spp": timing_spp, "cycles": cycles,
                               "cycles_version": a.cycles_version,
                               "scenes": results})
    if failures:
        print(f"{len(failures)} scene(s) failed: {', '.join(failures)}; images in {a.out}")
        return 1
    print("The standalone Cycles renders the exported scenes as the native 'cycles' option does, within the noise")
    return 0


if __name__ == "__main__":
    sys.exit(main())

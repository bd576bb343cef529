#!/usr/bin/python3
"""Benchmarks of the knit model in the native renderer (docs/results.md).

Runs `knitshade render` with --report and `knitshade compare`; everything is
measured in one run, on this machine, and written as JSON (and a Markdown
summary) to OUT_DIR.

  equal quality   the model and explicit yarns (and, in far view, the
                  multi-scale and near-field model) each render a
                  high-sample reference of their own, then a ladder of sample
                  counts; the time each needs to reach the same RMSE against
                  its own reference is interpolated (log-log) on the ladder,
                  and, less noisy, the samples it needs (interpolated the
                  same way; seeded errors are deterministic) times the cost
                  of a sample pass timed on its reference render. Both
                  count sample passes only; the ratios with each
                  method's set-up added (parsing, meshes, the class
                  tables or the explicit yarns and their BVH) are given
                  beside them, cold (a first render: the class tables
                  built) and warm (a later one: read from the class-table
                  cache, a folder of the run's own under OUT_DIR).
  memory          the model's state (KnitMaterial::state_bytes) and the
                  renderer's per-mesh tables, against the explicit yarns'
                  geometry, shading data and Embree BVH.
  overhead        the knit model against a plain diffuse material of the same
                  colour on the same mesh and lights, same samples (64),
                  rendered in turn three times (--repeats N: N times): the
                  ratio of the fastest, of the medians, and the median of
                  the ratios of each knit render to the diffuse one right
                  after it (the two of a pair share the machine's phase),
                  and the same with set-up, cold and warm.
  instructions    (not in the default set) the same pairs at the same size
                  (so the same footprints) and 2 spp on one thread, counted
                  in instructions of the render loop by callgrind (Debian's
                  valgrind): the overhead without the timer's noise, about 4
                  minutes.

  /usr/bin/python3 scripts/bench_knit.py BUILD_DIR OUT_DIR [--quick] [--paper-far-view] [--only PARTS]
                                        [--repeats N]

PARTS: comma-separated, of half_cylinder, garment, garment_alone, far_view,
close_up, overhead (all by default), instructions and resolution (only when
named; --paper-far-view adds the environment-only far views).

  resolution      (not in the default set, about 20 minutes) the half
                  cylinder's equal quality against explicit yarns at 256 and
                  512 pixels (the example's own is 480), near field and
                  multi-scale with table_min_cells 0.5 (the default before
                  2026-12-05) and 0.25 (the default since): where the
                  footprints fall below table_min_cells, multi-scale shades
                  them as the near field, and its lead over explicit yarns
                  goes with them. References of 256 samples, ladder 1 to
                  32; and the overhead of the 0.25 material against its
                  diffuse twin (16 samples).

On the garment (the scarf over a bar, on a floor) the error is measured twice:
over the whole image, where the floor and bar's lighting noise (the same for
every method) dominates, and over the fabric alone (pixels the scarf covers at
least half of, from `knitshade render --mask-object scarf`).
"""
import json
import math
import os
import shutil
import subprocess
import sys
import time

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
SCENES = os.path.join(ROOT, "examples", "scenes")


def absolutise(scene):
    """Scene paths relative to examples/scenes, made absolute (the scene is written elsewhere)."""
    def fix(p):
        return p if os.path.isabs(p) else os.path.normpath(os.path.join(SCENES, p))
    for o in scene["objects"]:
        o["mesh"] = fix(o["mesh"])
    for light in scene["lights"]:
        if "file" in light:
            light["file"] = fix(light["file"])
    for m in scene["materials"].values():
        if isinstance(m.get("pattern"), str):
            m["pattern"] = fix(m["pattern"])
        if m.get("frames") not in (None, "exact", "curvature"):
            m["frames"] = fix(m["frames"])
    return scene


def load(name):
    with open(os.path.join(SCENES, name)) as f:
        return absolutise(json.load(f))


class Bench:
    def __init__(self, build, out, quick):
        self.cli = os.path.join(build, "knitshade")
        self.out = out
        self.quick = quick
        os.makedirs(out, exist_ok=True)
        self.cache_root = os.path.join(out, "table-cache")
        shutil.rmtree(self.cache_root, ignore_errors=True)
        self.results = {"machine": os.uname().nodename, "cpus": os.cpu_count(), "started": time.ctime()}

    def scene_file(self, tag, scene):
        """Writes the scene to OUT_DIR/tag.json (for the CLI, and to look at later); returns its path."""
        path = os.path.join(self.out, tag + ".json")
        with open(path, "w") as f:
            json.dump(scene, f, indent=1)
        return path

    def render(self, tag, scene, spp, seed=1, explicit=False, cache=None):
        """Renders the scene; returns the image's path and the report. The class-table cache is a folder
        of this run's own per `cache` (default: the tag), empty when the run starts, so the first render
        of a method builds its tables (the cold set-up) and the later ones read them (the warm one)."""
        path = self.scene_file(tag, scene)
        img = os.path.join(self.out, f"{tag}_{spp}_{seed}.exr")
        rep = os.path.join(self.out, f"{tag}_{spp}_{seed}.report.json")
        cmd = [self.cli, "render", path, "-o", img, "--spp", str(spp), "--seed", str(seed), "--quiet",
               "--report", rep, "--cache-dir", os.path.join(self.cache_root, cache or tag)]
        if explicit:
            cmd.append("--explicit-yarns")
        subprocess.run(cmd, check=True)
        with open(rep) as f:
            return img, json.load(f)

    def compare(self, a, b, mask=None):
        cmd = [self.cli, "compare", a, b] + (["--mask", mask] if mask else [])
        r = subprocess.run(cmd, check=True, capture_output=True, text=True)
        return json.loads(r.stdout)

    def mask(self, tag, scene, obj):
        """Coverage mask of object `obj` (knitshade render --mask-object), for errors over the fabric alone."""
        path = self.scene_file(tag, scene)
        img = os.path.join(self.out, tag + "_mask.exr")
        subprocess.run([self.cli, "render", path, "-o", img, "--spp", "64", "--quiet", "--mask-object", obj,
                        "--cache-dir", os.path.join(self.cache_root, tag)], check=True)
        return img

    def convergence(self, tag, scene, ladder, ref_spp, explicit=False, mask=None):
        """Render time and RMSE against the method's own reference along the ladder. The renders are
        cached by tag; the errors by tag and mask (RMSE over the pixels the mask selects)."""
        if not hasattr(self, "_renders"):
            self._renders, self._conv = {}, {}
        if tag not in self._renders:
            ref, ref_rep = self.render(tag + "_ref", scene, ref_spp, seed=1000, explicit=explicit, cache=tag)
            imgs, setups = [], [setup_seconds(ref_rep)]
            for spp in ladder:
                img, rep = self.render(tag, scene, spp, seed=1, explicit=explicit, cache=tag)
                imgs.append((spp, img, rep["seconds"]["render"]))
                setups.append(setup_seconds(rep))
            self._renders[tag] = (ref, ref_rep, imgs, setups)
        key = (tag, mask)
        if key in self._conv:
            return self._conv[key]
        ref, ref_rep, imgs, setups = self._renders[tag]
        points = []
        for spp, img, seconds in imgs:
            c = self.compare(img, ref, mask)
            points.append({"spp": spp, "seconds": seconds, "rmse": c["rmse"], "mean": c["mean_a"]})
            print(f"  {tag}{' (masked)' if mask else ''}: {spp:5d} spp  {seconds:8.3f} s  RMSE {c['rmse']:.5f}",
                  flush=True)
        # The reference's own noise: RMSE(1 spp) / sqrt(ref_spp), removed in quadrature.
        e1 = points[0]["rmse"] * math.sqrt(points[0]["spp"])
        ref_noise = e1 / math.sqrt(ref_spp)
        for p in points:
            p["rmse_corrected"] = math.sqrt(max(p["rmse"] ** 2 - ref_noise ** 2, 1e-30))
        # Set-up (everything before the first sample: parsing, meshes, the class tables or the explicit
        # yarns and their BVH): cold is the reference's, the first render of the method, which builds the
        # class tables; warm the least of the ladder's, which read them from the cache.
        self._conv[key] = {"reference": ref, "reference_spp": ref_spp,
                           "reference_seconds": ref_rep["seconds"]["render"], "reference_noise": ref_noise,
                           "points": points, "report": ref_rep,
                           "setup_cold": setups[0], "setup_warm": min(setups[1:])}
        return self._conv[key]

    @staticmethod
    def to_error(conv, target, key):
        """`key` ("seconds" of render time, or "spp") needed to reach RMSE `target`, interpolated
        log-log on the ladder; outside it, extrapolated with error ~ 1 / sqrt(key) from the nearest
        end. (The errors of a seeded render are deterministic; only the times are noisy.)"""
        pts = conv["points"]
        for a, b in zip(pts, pts[1:]):
            ea, eb = a["rmse_corrected"], b["rmse_corrected"]
            if ea >= target >= eb and ea > eb:
                f = (math.log(ea) - math.log(target)) / (math.log(ea) - math.log(eb))
                return math.exp(math.log(a[key]) + f * (math.log(b[key]) - math.log(a[key])))
        p = pts[0] if target > pts[0]["rmse_corrected"] else pts[-1]
        return p[key] * (p["rmse_corrected"] / target) ** 2

    def equal_quality(self, name, scene_a, scene_b, label_a, label_b, ladder, ref_spp, explicit_b=False,
                      tag_a=None, tag_b=None, mask=None):
        print(f"equal quality: {name}", flush=True)
        a = self.convergence(tag_a or f"{name}_{label_a}", scene_a, ladder, ref_spp, mask=mask)
        b = self.convergence(tag_b or f"{name}_{label_b}", scene_b, ladder, ref_spp, explicit=explicit_b, mask=mask)
        # Target: the error method A reaches at the middle of the ladder, if B reaches it too.
        mid = a["points"][len(ladder) // 2]["rmse_corrected"]
        target = max(mid, b["points"][-1]["rmse_corrected"])
        ta, tb = self.to_error(a, target, "seconds"), self.to_error(b, target, "seconds")
        mean = a["points"][-1]["mean"]
        res = {"target_rmse": target, "target_relative": target / mean if mean else None,
               label_a: {"seconds": ta, "ladder": a["points"], "reference_spp": ref_spp,
                         "reference_seconds": a["reference_seconds"]},
               label_b: {"seconds": tb, "ladder": b["points"], "reference_spp": ref_spp,
                         "reference_seconds": b["reference_seconds"]},
               "speedup": tb / ta}
        # The same from the samples each needs and the cost of a sample pass timed on its reference
        # (ref_spp samples, seconds long): the ladder's renders at the target take a tenth of a second,
        # where the timer's noise is 10-30%.
        for label, conv in ((label_a, a), (label_b, b)):
            spp = self.to_error(conv, target, "spp")
            per_pass = conv["reference_seconds"] / ref_spp
            res[label].update({"samples_to_target": spp, "seconds_per_pass": per_pass,
                               "seconds_by_passes": spp * per_pass})
        res["speedup_by_passes"] = res[label_b]["seconds_by_passes"] / res[label_a]["seconds_by_passes"]
        # The same with each method's set-up added: a first render (cold: the class tables built) and a
        # later one of the same material (warm: read from the class-table cache). Explicit yarns are
        # built again for every render.
        for label, conv in ((label_a, a), (label_b, b)):
            res[label].update({"setup_cold": conv["setup_cold"], "setup_warm": conv["setup_warm"]})
        for kind in ("cold", "warm"):
            res["speedup_with_setup_" + kind] = ((tb + res[label_b]["setup_" + kind]) /
                                                 (ta + res[label_a]["setup_" + kind]))
        ma, mb = a["report"]["memory_bytes"], b["report"]["memory_bytes"]
        res["memory"] = {label_a: ma, label_b: mb}
        res["knit"] = {label_a: a["report"]["knit"], label_b: b["report"]["knit"]}
        # The converged images against each other (the model's error, not noise).
        res["references_compared"] = self.compare(a["reference"], b["reference"], mask)
        if mask:
            res["mask"] = mask
        print(f"  -> target RMSE {target:.5f}: {label_a} {ta:.2f} s, {label_b} {tb:.2f} s, "
              f"{label_b}/{label_a} = {tb / ta:.2f}; by passes: {label_a} "
              f"{res[label_a]['samples_to_target']:.1f} spp x {1e3 * res[label_a]['seconds_per_pass']:.2f} ms, "
              f"{label_b} {res[label_b]['samples_to_target']:.1f} spp x "
              f"{1e3 * res[label_b]['seconds_per_pass']:.2f} ms, {label_b}/{label_a} = "
              f"{res['speedup_by_passes']:.2f}; with set-up, cold {res['speedup_with_setup_cold']:.2f} "
              f"({label_a} {res[label_a]['setup_cold']:.2f} s, {label_b} {res[label_b]['setup_cold']:.2f} s), "
              f"warm {res['speedup_with_setup_warm']:.2f}", flush=True)
        return res

    def overhead(self, name, scene, spp, repeats=3):
        """Render time of the scene against the same scene with its knit materials replaced by diffuse ones
        of their first yarn colour. The two are rendered in turn `repeats` times (the same seed, so the same
        images); the ratio is of the fastest of each, the least disturbed by the rest of the machine. On a
        shared VM whose speed drifts over minutes, each knit render and the diffuse one right after it
        share a phase: the median of those pairs' ratios is given too, with their range."""
        print(f"overhead: {name}", flush=True)
        diffuse = diffuse_twin(scene)
        tk, td, sk, sd = [], [], [], []
        for _ in range(max(1, repeats)):
            _, rk = self.render(name + "_knit", scene, spp)
            _, rd = self.render(name + "_diffuse", diffuse, spp)
            tk.append(rk["seconds"]["render"])
            td.append(rd["seconds"]["render"])
            sk.append(setup_seconds(rk))
            sd.append(setup_seconds(rd))
        pairs = [k / d for k, d in zip(tk, td)]
        res = {"spp": spp, "knit_seconds": min(tk), "diffuse_seconds": min(td), "ratio": min(tk) / min(td),
               "knit_seconds_all": tk, "diffuse_seconds_all": td,
               "ratio_of_medians": median(tk) / median(td),
               "pair_ratios": pairs, "ratio_of_pairs_median": median(pairs),
               "knit_rays": rk["rays"]["total"], "diffuse_rays": rd["rays"]["total"], "knit": rk["knit"],
               # Whole renders, set-up included: the first knit render builds its class tables (cold),
               # the later ones read them from the cache (warm).
               "knit_setup_all": sk, "diffuse_setup_all": sd,
               "ratio_with_setup_cold": (min(tk) + sk[0]) / (min(td) + min(sd))}
        if len(sk) > 1:
            res["ratio_with_setup_warm"] = (min(tk) + min(sk[1:])) / (min(td) + min(sd))
        print(f"  -> knit {res['knit_seconds']:.2f} s, diffuse {res['diffuse_seconds']:.2f} s (fastest of "
              f"{len(tk)}), ratio {res['ratio']:.2f} (of medians {res['ratio_of_medians']:.2f}; pairs' median "
              f"{res['ratio_of_pairs_median']:.2f}, {min(pairs):.2f}-{max(pairs):.2f}); with set-up, "
              f"cold {res['ratio_with_setup_cold']:.2f} (knit {sk[0]:.2f} s, diffuse {min(sd):.2f} s)"
              + (f", warm {res['ratio_with_setup_warm']:.2f}" if len(sk) > 1 else ""), flush=True)
        return res

    # The render loop's lambda in knit::render::render_image: callgrind counts from its entry only, so
    # parsing, the class table's build and image output stay out of the count.
    RENDER_LOOP = ("knit::render::render_image(knit::render::Scene const&, knit::render::RenderSettings "
                   "const&)::{lambda(int)#1}::operator()(int) const")

    def instructions(self, name, scene, spp=2):
        """Instructions of the render loop (callgrind, one thread) for the scene and its diffuse twin (see
        overhead), at the same size (the pixel footprints decide between the class table and marching) and
        `spp` samples: the overhead's ratio, deterministic."""
        print(f"instructions: {name}", flush=True)
        counts = {}
        for label, sc in (("knit", scene), ("diffuse", diffuse_twin(scene))):
            path = self.scene_file(f"{name}_{label}_instr", sc)
            cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
                   "--toggle-collect=" + self.RENDER_LOOP, self.cli, "render", path, "-o",
                   os.path.join(self.out, f"{name}_{label}_instr.exr"), "--spp", str(spp), "--threads", "1",
                   "--quiet", "--cache-dir", os.path.join(self.cache_root, f"{name}_{label}_instr")]
            r = subprocess.run(cmd, check=True, capture_output=True, text=True)
            found = [line for line in r.stderr.splitlines() if "Collected :" in line]
            n = int(found[-1].split(":")[-1]) if found else 0
            if n <= 0:
                raise RuntimeError(f"callgrind counted nothing in {self.RENDER_LOOP!r}: has render_image changed?")
            counts[label] = n
        res = {"width": scene["film"]["width"], "height": scene["film"]["height"], "spp": spp,
               "knit_instructions": counts["knit"], "diffuse_instructions": counts["diffuse"],
               "ratio": counts["knit"] / counts["diffuse"]}
        print(f"  -> knit {counts['knit'] / 1e6:.0f} M, diffuse {counts['diffuse'] / 1e6:.0f} M instructions, "
              f"ratio {res['ratio']:.2f}", flush=True)
        return res


def setup_seconds(report):
    """A render's time before its first sample: all of it but the sample passes and the image's output."""
    sec = report["seconds"]
    return sec["total"] - sec["render"] - sec["write"]


def median(values):
    """The median (the mean of the middle two for an even count)."""
    v = sorted(values)
    n = len(v)
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def diffuse_twin(scene):
    """The scene with its knit materials replaced by diffuse ones of their first yarn colour."""
    diffuse = json.loads(json.dumps(scene))
    for key, m in diffuse["materials"].items():
        if m["type"] == "knit":
            diffuse["materials"][key] = {"type": "diffuse", "albedo": m["yarn_colors"][0]}
    return diffuse


def sized(scene, w, h):
    s = json.loads(json.dumps(scene))
    s["film"]["width"], s["film"]["height"] = w, h
    return s


def main():
    if len(sys.argv) < 3:
        print(__doc__)
        sys.exit(2)
    quick = "--quick" in sys.argv
    b = Bench(sys.argv[1], sys.argv[2], quick)
    parts = {"half_cylinder", "garment", "garment_alone", "far_view", "close_up", "overhead"}
    if "--only" in sys.argv:
        parts = set(sys.argv[sys.argv.index("--only") + 1].split(","))
    repeats = 3
    if "--repeats" in sys.argv:
        try:
            repeats = int(sys.argv[sys.argv.index("--repeats") + 1])
        except (IndexError, ValueError):
            sys.exit("bench_knit: --repeats takes a whole number of rounds (1 or more)")
        if repeats < 1:
            sys.exit(f"bench_knit: --repeats {repeats}: give 1 or more rounds")
    size = 64 if quick else 128
    ladder = [1, 2, 4, 8, 16] if quick else [1, 2, 4, 8, 16, 32, 64]
    ref_spp = 128 if quick else 1024

    # 1. The half cylinder of Figure 7 (200 yarns), far view, front and back light.
    hc = sized(load("half_cylinder_front.json"), size, size)
    hc["lights"].append({"type": "directional", "to_light": [-0.25, 0.3, -1], "irradiance": [2.4, 2.35, 2.3]})
    if "half_cylinder" in parts:
        b.results["half_cylinder"] = b.equal_quality("half_cylinder", hc, hc, "model", "explicit", ladder, ref_spp,
                                                     explicit_b=True)

    # 2. A garment: the scarf at a real gauge (125 stitches across 25 cm, 1400 rows over 2 m).
    scarf = sized(load("scarf.json"), size, int(size * 1.2))
    scarf["materials"]["wool"]["uv_scale"] = 3142
    if "garment" in parts:
        b.results["garment_scarf"] = b.equal_quality("garment", scarf, scarf, "model", "explicit", ladder, ref_spp,
                                                     explicit_b=True)

    # 1b, 2b. The same two scenes with the model in multi-scale mode (its
    # far-field form: footprints of a stitch cell or more come from the class
    # table), against the same explicit-yarn runs.
    def multi_scale(scene):
        s = json.loads(json.dumps(scene))
        s["materials"]["wool"]["mode"] = "multi_scale"
        return s
    if "half_cylinder" in parts:
        b.results["half_cylinder_multi_scale"] = b.equal_quality(
            "half_cylinder_ms", multi_scale(hc), hc, "model_multi_scale", "explicit", ladder, ref_spp,
            explicit_b=True, tag_b="half_cylinder_explicit")
    if "garment" in parts:
        b.results["garment_scarf_multi_scale"] = b.equal_quality(
            "garment_ms", multi_scale(scarf), scarf, "model_multi_scale", "explicit", ladder, ref_spp,
            explicit_b=True, tag_b="garment_explicit")
        # The same renders, the error over the fabric alone.
        fabric = b.mask("garment_fabric", scarf, "scarf")
        b.results["garment_scarf_fabric"] = b.equal_quality(
            "garment_fabric", scarf, scarf, "model", "explicit", ladder, ref_spp, explicit_b=True,
            tag_a="garment_model", tag_b="garment_explicit", mask=fabric)
        b.results["garment_scarf_multi_scale_fabric"] = b.equal_quality(
            "garment_ms_fabric", multi_scale(scarf), scarf, "model_multi_scale", "explicit", ladder, ref_spp,
            explicit_b=True, tag_a="garment_ms_model_multi_scale", tag_b="garment_explicit", mask=fabric)

    # 2c. The garment alone: the scarf in the same view and light, without
    # the floor and the bar, whose paths cost the same for every scarf model
    # and bound the speed-up of 2 (docs/results.md).
    if "garment_alone" in parts:
        alone = json.loads(json.dumps(scarf))
        alone["objects"] = [o for o in alone["objects"] if o.get("name") == "scarf"]
        b.results["garment_alone"] = b.equal_quality("garment_alone", alone, alone, "model", "explicit", ladder,
                                                     ref_spp, explicit_b=True)
        b.results["garment_alone_multi_scale"] = b.equal_quality(
            "garment_alone_ms", multi_scale(alone), alone, "model_multi_scale", "explicit", ladder, ref_spp,
            explicit_b=True, tag_b="garment_alone_explicit")

    # 3. Far view: multi-scale against near field (the flat swatch far away).
    far = sized(load("swatch_far.json"), size, int(size * 0.75))
    near = json.loads(json.dumps(far))
    near["materials"]["wool"]["mode"] = "near_field"
    # (footprint_points: 4 by default; 16, the earlier default, as a variant)
    far16 = json.loads(json.dumps(far))
    far16["materials"]["wool"]["footprint_points"] = 16
    if "far_view" in parts:
        b.results["far_view"] = b.equal_quality("far_view", far, near, "multi_scale", "near_field", ladder,
                                                ref_spp, tag_b="far_near_field")
        b.results["far_view_16_points"] = b.equal_quality("far_view16", far16, near, "multi_scale", "near_field",
                                                          ladder, ref_spp, tag_b="far_near_field")

    # 3b. (--paper-far-view, about 15 more minutes) The same under environment
    # light only, as in the paper's Figure 13, with the seed pattern and with
    # the two-colour diamond blocks (where which yarn a sample hits changes
    # its colour, the noise multi-scale aggregation removes).
    if "--paper-far-view" in sys.argv:
        def env_only(scene, two_colour):
            s = json.loads(json.dumps(scene))
            s["lights"] = [light for light in s["lights"] if light["type"] == "environment"]
            s["lights"][0]["strength"] = 1.0
            if two_colour:
                m = s["materials"]["wool"]
                m["pattern"] = os.path.join(ROOT, "examples", "patterns", "diamond_blocks_2colour.knit")
                m["yarn_colors"] = [[0.72, 0.18, 0.14], [0.85, 0.82, 0.75]]
            return s
        for name, two in (("env", False), ("env_2colour", True)):
            ms = env_only(far, two)
            nf = env_only(near, two)
            ms16 = json.loads(json.dumps(ms))
            ms16["materials"]["wool"]["footprint_points"] = 16
            b.results["far_view_" + name] = b.equal_quality(
                "far_" + name, ms, nf, "multi_scale", "near_field", ladder, ref_spp, tag_b="far_nf_" + name)
            b.results["far_view_" + name + "_16_points"] = b.equal_quality(
                "far16_" + name, ms16, nf, "multi_scale", "near_field", ladder, ref_spp, tag_b="far_nf_" + name)

    # 3c. Close-ups (the paper's Table 2 rows ii): the near field against
    # explicit yarns where a pixel sees a fraction of a stitch, on the half
    # cylinder's close-up (front and back light) and the flat swatch's.
    if "close_up" in parts:
        hcc = sized(load("half_cylinder_closeup.json"), size, size)
        b.results["close_up_half_cylinder"] = b.equal_quality(
            "closeup_half_cylinder", hcc, hcc, "model", "explicit", ladder, ref_spp, explicit_b=True)
        swc = sized(load("swatch_closeup.json"), size, int(size * 0.75))
        b.results["close_up_swatch"] = b.equal_quality(
            "closeup_swatch", swc, swc, "model", "explicit", ladder, ref_spp, explicit_b=True)

    # 3d. (only when named) The half cylinder at higher resolutions: the
    # share of footprints the class table serves falls with the pixel, and
    # the model's speed against explicit yarns with it.
    if "resolution" in parts:
        for px in (256, 512):
            hr = sized(hc, px, px)
            rladder, rref = [1, 2, 4, 8, 16, 32], 256
            half = multi_scale(hr)
            half["materials"]["wool"]["table_min_cells"] = 0.5
            b.results[f"resolution_{px}_multi_scale"] = b.equal_quality(
                f"res{px}_ms", half, hr, "model_multi_scale", "explicit", rladder, rref,
                explicit_b=True, tag_b=f"res{px}_explicit")
            quarter = multi_scale(hr)
            quarter["materials"]["wool"]["table_min_cells"] = 0.25
            b.results[f"resolution_{px}_multi_scale_quarter"] = b.equal_quality(
                f"res{px}_ms25", quarter, hr, "model_multi_scale_quarter", "explicit", rladder, rref,
                explicit_b=True, tag_b=f"res{px}_explicit")
            b.results[f"resolution_{px}_near_field"] = b.equal_quality(
                f"res{px}_nf", hr, hr, "model", "explicit", rladder, rref, explicit_b=True,
                tag_b=f"res{px}_explicit")
            # and the overhead of the quarter cells against the diffuse twin, 16 samples
            b.results[f"resolution_{px}_overhead_quarter"] = b.overhead(f"oh_res{px}_ms25", quarter, 16, repeats)

    # 4. Overhead of the knit material against diffuse, same mesh, lights and samples.
    overhead_scenes = {
        "half_cylinder": ("oh_half_cylinder", hc),
        "swatch_closeup": ("oh_swatch", sized(load("swatch_closeup.json"), size, size)),
        "scarf": ("oh_scarf", sized(load("scarf.json"), size, int(size * 1.2))),
        "half_cylinder_multi_scale": ("oh_half_cylinder_ms", multi_scale(hc)),
        "swatch_far_multi_scale": ("oh_swatch_far", far),
        "scarf_multi_scale": ("oh_scarf_ms", multi_scale(sized(load("scarf.json"), size, int(size * 1.2)))),
    }
    if "overhead" in parts:
        # 64 spp: the diffuse renders then take about a second, not a tenth.
        oh = 16 if quick else 64
        b.results["overhead"] = {key: b.overhead(tag, sc, oh, repeats) for key, (tag, sc) in overhead_scenes.items()}
    # 4b. The same pairs in instructions (only when asked for: callgrind is slow).
    if "instructions" in parts:
        if shutil.which("valgrind") is None:
            sys.exit("bench_knit: the instructions part needs callgrind: apt-get install valgrind")
        b.results["overhead_instructions"] = {key: b.instructions(tag + "_instr", sc)
                                              for key, (tag, sc) in overhead_scenes.items()}
    b.results["finished"] = time.ctime()
    with open(os.path.join(b.out, "bench_knit.json"), "w") as f:
        json.dump(b.results, f, indent=2)
    print("wrote", os.path.join(b.out, "bench_knit.json"))


if __name__ == "__main__":
    main()

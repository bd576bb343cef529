#!/usr/bin/env python3
"""The whole generated knit shader under OSL's testshade, point by point
against the C++ library (issue 52: "over a testshade grid the shader's
outputs equal the C++ library's at the same points within 1e-4, near field
and multi-scale, flat and curved").

What runs. knitshade.osl_source() of examples/patterns/diamond_blocks_2colour.knit
(48 x 48 stitches, two colours, the default stitch a, h, d, r, which leaves
holes between the loops), compiled with oslc, is shaded by testshade on a
32 x 32 grid in four cases: near field flat, near field curved, multi-scale
flat, multi-scale curved (Curvature = (1.6, -0.8) per world unit, a saddle
of radii 40 and 80 pattern units). UVScale is 64, a power of two, so that
the scalings between UV and pattern units are exact on both sides.

The host, as testshade sets it up. testshade puts the grid on the plane
z = 1: u, v run over the grid (--offsetst, --scaleuv; testshade 1.13's
--offsetuv is parsed but never applied), P = (u, v, 1), Dx(P) = (du, 0, 0),
Dy(P) = (0, dv, 0), Dx(u) = du, Dy(v) = dv, N = Ng = (0, 0, 1), not
backfacing, and I = (0, 0, 0), which would give the shader no view at all.
A small layer in front of the shader (knit_grid_host, below) therefore
writes I (the globals are shared by the group's layers), a view 0 to 57
degrees off the normal that changes over the grid, and links UV = (u, v, 0)
into the shader's UV input. The shader's base frame is then exactly
t = (1, 0, 0), b = (0, 1, 0), n = (0, 0, 1) with |dP/du| = |dP/dv| = 1, so
pattern units per world unit are UVScale. The layer also outputs what the
C++ side needs bit for bit: the UV, its differentials, normalize(I) (the
shader's own view) and hashnoise() at P, the Cranley-Patterson shift the
shader computes for its multi-scale points. testshade writes every output
as 32-bit floats (FITS files), so nothing is lost in printing.

The C++ reference, through the knitshade module, at the same points:
KnitMaterial.shade(..., bsdf_model="cycles") with that frame, pattern units
per world unit, curvature, and in multi-scale the footprint the shader
builds (knitshade.footprint_isotropic from the UV differentials and the
view) and the same shift; KnitSurface.aggregate with the material's CAPM
settings (its segment shortened on a curved base as the material's is) for
the multi-scale means the shader outputs as they are (layer
count, steps, the colour index of one hit picked by the shift).
The material has no ply detail: the ply profile changes the shading frame,
not the tube normal and tangent the shader outputs.

Compared, at every point: Coverage, Height, YarnNormal, YarnTangent,
Layers, ColourIndex, Steps and Error (0). Where neither side meets yarn the
shader must leave its yarn outputs at 0. Tolerance: 1e-4 absolute for every
output (all are of order 1; the larger ones, Steps and ColourIndex, are
counts and must then be equal). A point that misses it is tested again on
the C++ side a hair away: moved by up to 1e-4 pattern units (1/6,000 of a
stitch), or its view turned by up to 1e-6 rad. If the C++ results there
agree with the shader in every output, the point sits on a discontinuity of
the model (a yarn's edge, the view passing from one tube to another, a
multi-scale point doing so, the crossing's Newton search stopping one step
earlier or later) where single-precision results of two compilers (OSL's
sin and cos are its fast approximations) may fall on either side, and it
is counted as a boundary point. Any other mismatch fails, and so do
boundary points beyond 5% of a case's points (51 of 1,024; docs/testing.md
gives the measured counts). The test prints, per case and output, the
largest difference away from boundary points and over all points, the
points beyond 1e-4, and the boundary points.

Run (exit 0 pass, 1 fail, 77 did not run: no oslc or testshade, or no
knitshade module):

  OSLC=/path/to/oslc PYTHONPATH=build/python /usr/bin/python3 tests/osl/shader_grid.py

oslc comes from $OSLC, else PATH; testshade from beside it, else PATH.
KNIT_PYTHON_DIR, when set, is where the knitshade module is looked for
first. The CTest name is osl.shader_grid.
"""
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

TOL = 1e-4              # absolute, every output
GRID = 32               # points per side, per case
UV_SCALE = 64.0         # pattern units per UV unit (a power of two)
NUDGE = 1e-4            # pattern units: how far the boundary check moves a point,
NUDGE_VIEW = 1e-6       # radians: and turns its view
MAX_BOUNDARY = 0.05     # of a case's points
PATTERN = os.path.join(ROOT, "examples", "patterns", "diamond_blocks_2colour.knit")
# The material's CAPM settings, the shader's KNIT_MAX_SEGMENT, KNIT_MAX_BEND
# and CapmSteps default.
MAX_SEGMENT, MAX_BEND, MAX_STEPS = 6.2832, 0.05, 32

# (name, Mode, Curvature (kx, ky) per world unit, grid origin in UV, side
# in UV (a power of two: u = side * i / 31 + origin is rounded once)). The
# near-field grid covers 2.5 x 3.6 stitches across a corner of the colour
# blocks; the multi-scale grid 41 x 57 stitches, its footprints over a
# stitch wide.
CASES = (
    ("near field, flat", 0, (0.0, 0.0), (0.3, 0.16), 0.25),
    ("near field, curved", 0, (1.6, -0.8), (0.3, 0.16), 0.25),
    ("multi-scale, flat", 1, (0.0, 0.0), (0.0, 0.0), 4.0),
    ("multi-scale, curved", 1, (1.6, -0.8), (0.0, 0.0), 4.0),
)

# The host: testshade's I is (0, 0, 0), so this layer sets it. The shift
# lines repeat the shader's (checked against its text below).
HOST = r"""
shader knit_grid_host(float u0 = 0, float v0 = 0, float side = 1,
    output point uv_grid = 0, output vector duv_x = 0, output vector duv_y = 0, output vector view = 0,
    output float shift_x = 0, output float shift_y = 0)
{
    I = vector(1.2 * (2.0 * (u - u0) / side - 1.0), 1.0 * (2.0 * (v - v0) / side - 1.0), 1.0);
    view = normalize(I);
    uv_grid = point(u, v, 0);
    duv_x = Dx(uv_grid);
    duv_y = Dy(uv_grid);
    shift_x = hashnoise(P);
    shift_y = hashnoise(P + vector(0.5, 0.25, 0.125));
}
"""
SHADER_SHIFT = "float shift_x = hashnoise(P), shift_y = hashnoise(P + vector(0.5, 0.25, 0.125));"

HOST_OUTPUTS = ("uv_grid", "duv_x", "duv_y", "view", "shift_x", "shift_y")
SHADER_OUTPUTS = ("Coverage", "Height", "YarnNormal", "YarnTangent", "Layers", "ColourIndex", "Steps", "Error")


def find_tools():
    oslc = os.environ.get("OSLC") or shutil.which("oslc")
    if not oslc or not os.path.exists(oslc):
        return None, None
    beside = os.path.join(os.path.dirname(oslc), "testshade")
    testshade = beside if os.path.exists(beside) else shutil.which("testshade")
    return oslc, testshade


def read_fits(path, np):
    """A testshade output written as 32-bit FITS: (points, channels), point
    index x + GRID * y. FITS keeps rows bottom first; the data are the last
    bytes of the file (this OIIO writes a row of padding before them)."""
    with open(path, "rb") as f:
        data = f.read()
    head = data[:2880].decode("ascii")
    cards = {head[i:i + 8].strip(): head[i + 10:i + 80].split("/")[0].strip() for i in range(0, 2880, 80)}
    dims = [int(cards["NAXIS%d" % (k + 1)]) for k in range(int(cards["NAXIS"]))]
    count = int(np.prod(dims))
    values = np.frombuffer(data[len(data) - 4 * count:], dtype=">f4").astype(np.float32)
    channels = dims[0] if len(dims) == 3 else 1
    return values.reshape(GRID, GRID, channels)[::-1].reshape(GRID * GRID, channels)


def run_shader(testshade, work, mode, curvature, origin, side, np):
    """testshade over the case's grid; a dict of outputs, or an error text."""
    cmd = [testshade, "-t", "1", "-g", str(GRID), str(GRID), "--offsetst", repr(origin[0]), repr(origin[1]),
           "--scaleuv", repr(side), repr(side), "-d", "float"]
    for name in HOST_OUTPUTS + SHADER_OUTPUTS:
        cmd += ["-o", name, name + ".fits"]
    cmd += ["--param", "u0", repr(origin[0]), "--param", "v0", repr(origin[1]), "--param", "side", repr(side),
            "--shader", "knit_grid_host", "host",
            "--param", "UVScale", repr(UV_SCALE), "--param", "Mode", str(mode),
            "--param:type=vector", "Curvature", f"{curvature[0]!r} {curvature[1]!r} 0",
            "--shader", "knit_fabric", "knit", "--connect", "host", "uv_grid", "knit", "UV"]
    for name in HOST_OUTPUTS + SHADER_OUTPUTS:
        path = os.path.join(work, name + ".fits")
        if os.path.exists(path):
            os.remove(path)
    r = subprocess.run(cmd, cwd=work, capture_output=True, text=True)
    if r.returncode != 0:
        return f"testshade failed ({r.returncode}): {(r.stdout + r.stderr)[-2000:]}"
    try:
        out = {name: read_fits(os.path.join(work, name + ".fits"), np) for name in HOST_OUTPUTS + SHADER_OUTPUTS}
    except (OSError, KeyError, ValueError) as e:
        return f"testshade's outputs could not be read ({e}): {(r.stdout + r.stderr)[-1000:]}"
    # The layout check: the UV read back is the grid testshade was given.
    q = np.arange(GRID, dtype=np.float32) / np.float32(GRID - 1)
    eu = np.float32(side) * q + np.float32(origin[0])
    ev = np.float32(side) * q + np.float32(origin[1])
    want = np.stack([np.tile(eu, GRID), np.repeat(ev, GRID)], axis=1)
    if not np.array_equal(out["uv_grid"][:, :2], want):
        return "the UV read back from testshade's FITS output is not the grid it was given (layout?)"
    return out


class Reference:
    """The C++ library's outputs for one case, at chosen points."""

    def __init__(self, knitshade, np, pattern, mode, curvature):
        self.np, self.mode = np, mode
        self.kx, self.ky = float(np.float32(curvature[0])), float(np.float32(curvature[1]))
        stitch = knitshade.StitchParams()
        colours = [(0.50, 0.36, 0.25), (0.80, 0.78, 0.72)]
        self.material = knitshade.KnitMaterial(
            pattern, stitch, bsdf={"reflect_colors": colours}, mode="multi_scale" if mode else "near_field",
            capm=True, ply_detail=False, footprint_points=4, uv_scale=UV_SCALE, max_steps=MAX_STEPS,
            max_segment=MAX_SEGMENT, max_bend=MAX_BEND, bsdf_model="cycles")
        self.surface = knitshade.KnitSurface(pattern, stitch, UV_SCALE)
        self.top = self.material.shell_top

    def segment(self):
        """The march's segment on this base: max_segment, shortened so the
        base turns by at most max_bend along it (pattern units), the rule
        the shader and KnitMaterial both follow."""
        kmax = max(abs(self.kx), abs(self.ky)) / UV_SCALE
        return min(MAX_SEGMENT, MAX_BEND / kmax) if kmax > 0 else MAX_SEGMENT

    def __call__(self, u, v, view, footprint, shift):
        """Outputs as the shader names them, at UV points u, v seen from
        view (N, 3); footprint (N, 4) and shift (N, 2) in multi-scale."""
        np = self.np
        kw = dict(t=[1.0, 0.0, 0.0], b=[0.0, 1.0, 0.0], n=[0.0, 0.0, 1.0], pattern_per_world=UV_SCALE,
                  kx=self.kx, ky=self.ky)
        if self.mode:
            kw.update(footprint=footprint, shift=shift)
        s = self.material.shade(u, v, -view, **kw)
        hit = ~np.asarray(s["pass_through"])
        h = hit[:, None]
        out = {
            "Coverage": 1.0 - np.asarray(s["p_delta"]),
            "Height": np.where(hit, UV_SCALE * np.nan_to_num(np.asarray(s["offset"])[:, 2]) + self.top, 0.0),
            "YarnNormal": np.where(h, np.nan_to_num(np.asarray(s["sn"])), 0.0),
            "YarnTangent": np.where(h, np.nan_to_num(np.asarray(s["st"])), 0.0),
            "Error": np.zeros(len(u)),
        }
        if not self.mode:
            out["Layers"] = np.where(hit, np.asarray(s["layers"]), 0).astype(float)
            out["ColourIndex"] = np.where(hit, np.asarray(s["color"]), 0).astype(float)
            out["Steps"] = np.asarray(s["steps"]).astype(float)
            return out, None
        # The means the shader outputs, from the aggregate behind shade().
        agg = {k: [] for k in ("layers", "steps", "color_pick", "p_delta")}
        for i in range(len(u)):
            a = self.surface.aggregate(u[i], v[i], footprint[i, :2], footprint[i, 2:], view[i], n_points=4,
                                       shift_x=shift[i, 0], shift_y=shift[i, 1], kx=self.kx / UV_SCALE,
                                       ky=self.ky / UV_SCALE, max_segment=self.segment(), max_steps=MAX_STEPS)
            for k in agg:
                agg[k].append(a[k][0])
        agg = {k: np.array(x, dtype=float) for k, x in agg.items()}
        out["Layers"] = agg["layers"]
        out["ColourIndex"] = np.where(agg["color_pick"] >= 0, agg["color_pick"], 0.0)
        out["Steps"] = agg["steps"]
        return out, agg["p_delta"]


def differences(got, ref, np):
    """Per output, the largest absolute difference of each point (N,)."""
    d = {}
    for name in SHADER_OUTPUTS:
        a = got[name].astype(np.float64)
        b = np.asarray(ref[name], dtype=np.float64).reshape(len(a), -1)
        d[name] = np.abs(a - b).max(axis=1)
    return d


def main():
    oslc, testshade = find_tools()
    if not oslc or not testshade:
        print("oslc or testshade not found (set OSLC=/path/to/oslc with testshade beside it, or put both on "
              "PATH): the shader grid comparison did NOT run")
        return 77
    try:
        import numpy as np
    except ImportError:
        print("numpy is missing: the shader grid comparison did NOT run")
        return 77
    # KNIT_PYTHON_DIR first, else PYTHONPATH, else build/python.
    if os.environ.get("KNIT_PYTHON_DIR"):
        sys.path.insert(0, os.environ["KNIT_PYTHON_DIR"])
    try:
        import knitshade
    except ImportError:
        sys.path.append(os.path.join(ROOT, "build", "python"))
        try:
            import knitshade
        except ImportError as e:
            print(f"the knitshade module is not built ({e}): the shader grid comparison did NOT run")
            return 77
    if not hasattr(knitshade, "footprint_isotropic"):
        print("FAIL: this knitshade module has no footprint_isotropic (built before it was added): rebuild it")
        return 1

    start = time.perf_counter()
    pattern = knitshade.Pattern.from_file(PATTERN)
    source = knitshade.osl_source(pattern)
    if SHADER_SHIFT not in source:
        print("FAIL: the shader no longer draws its multi-scale shift as this test's host layer does "
              f"({SHADER_SHIFT!r}); update HOST")
        return 1
    work = tempfile.mkdtemp(prefix="knit-shader-grid-")
    for name, text in (("knit_fabric", source), ("knit_grid_host", HOST)):
        with open(os.path.join(work, name + ".osl"), "w", encoding="utf-8") as f:
            f.write(text)
        r = subprocess.run([oslc, "-o", name + ".oso", name + ".osl"], cwd=work, capture_output=True, text=True)
        if r.returncode != 0:
            print(r.stdout + r.stderr)
            print(f"FAIL: oslc could not compile {name}.osl (in {work})")
            return 1
    print(f"{os.path.basename(PATTERN)}: {pattern.rows} x {pattern.cols} stitches, {pattern.num_colors} colours; "
          f"{GRID} x {GRID} points a case; tolerance {TOL:g} absolute; work folder {work}")

    failures = []
    for name, mode, curvature, origin, side in CASES:
        t0 = time.perf_counter()
        got = run_shader(testshade, work, mode, curvature, origin, side, np)
        if isinstance(got, str):
            print(f"FAIL: {name}: {got}")
            failures.append(name)
            continue
        secs_shader = time.perf_counter() - t0
        n = GRID * GRID
        u = got["uv_grid"][:, 0].astype(np.float64)
        v = got["uv_grid"][:, 1].astype(np.float64)
        view = got["view"].astype(np.float64)
        shift = np.stack([got["shift_x"][:, 0], got["shift_y"][:, 0]], axis=1).astype(np.float64)
        footprint = None
        if mode:
            # The shader's footprint: knit_footprint_isotropic of |Dx(UV)|,
            # |Dy(UV)| (lengths as the shader takes them, in float).
            lx = np.sqrt(np.sum(got["duv_x"] * got["duv_x"], axis=1, dtype=np.float32))
            ly = np.sqrt(np.sum(got["duv_y"] * got["duv_y"], axis=1, dtype=np.float32))
            footprint = np.array([np.concatenate(knitshade.footprint_isotropic(float(a), float(b), w, UV_SCALE))
                                  for a, b, w in zip(lx, ly, view)]) / UV_SCALE
        reference = Reference(knitshade, np, pattern, mode, curvature)
        ref, p_delta_agg = reference(u, v, view, footprint, shift)
        if mode and not np.array_equal(p_delta_agg, 1.0 - ref["Coverage"]):
            print(f"FAIL: {name}: the C++ reference is not self-consistent (KnitSurface.aggregate's p_delta "
                  "differs from KnitMaterial.shade's)")
            failures.append(name)
        diff = differences(got, ref, np)
        bad = np.zeros(n, dtype=bool)
        for k in SHADER_OUTPUTS:
            bad |= ~(diff[k] <= TOL)

        # Points beyond the tolerance: the C++ side a hair away.
        boundary = np.zeros(n, dtype=bool)
        idx = np.nonzero(bad)[0]
        if len(idx):
            step = NUDGE / UV_SCALE
            eight = [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, -1), (1, -1), (-1, 1)]
            corners = [(a, b, c) for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]
            nudges = [((a * s, b * s), (0, 0, 0)) for s in (step / 16, step / 4, step) for a, b in eight]
            nudges += [((0, 0), (a * e, b * e, c * e)) for e in (NUDGE_VIEW / 10, NUDGE_VIEW / 3, NUDGE_VIEW)
                       for a, b, c in corners]
            for (du, dv), dw in nudges:
                todo = idx[~boundary[idx]]
                if not len(todo):
                    break
                w = view[todo] + np.array(dw) / np.sqrt(3.0)
                w = (w / np.linalg.norm(w, axis=1)[:, None]).astype(np.float32).astype(np.float64)
                r2, _ = reference(u[todo] + du, v[todo] + dv, w, None if footprint is None else footprint[todo],
                                  shift[todo])
                sub = {k: got[k][todo] for k in SHADER_OUTPUTS}
                d2 = differences(sub, r2, np)
                ok = np.ones(len(todo), dtype=bool)
                for k in SHADER_OUTPUTS:
                    ok &= d2[k] <= TOL
                boundary[todo[ok]] = True
        genuine = bad & ~boundary
        secs = time.perf_counter() - t0

        cov = got["Coverage"][:, 0]
        hits = ref["Coverage"] > 0
        colours = sorted(set(got["ColourIndex"][:, 0][cov > 0].astype(int)))
        print(f"\n{name}: Mode {mode}, Curvature {curvature}, UV from {origin} over {side} "
              f"(points {UV_SCALE * side / (GRID - 1):.2f} pattern units apart); "
              f"testshade {secs_shader:.1f} s, all {secs:.1f} s")
        if mode:
            print(f"  coverage mean {cov.mean():.4f} (C++ {ref['Coverage'].mean():.4f}), partial at "
                  f"{np.mean((cov > 0) & (cov < 1)) * 100:.0f}% of the points; colour indices seen {colours}")
        else:
            print(f"  yarn at {hits.mean() * 100:.1f}% of the points (C++), holes at {(~hits).mean() * 100:.1f}%; "
                  f"colour indices seen {colours}")
        for k in SHADER_OUTPUTS:
            keep = ~boundary
            m_all = diff[k].max()
            m_keep = diff[k][keep].max() if keep.any() else 0.0
            print(f"  {k:12s} max |OSL - C++| {m_keep:.2e} away from boundaries, {m_all:.2e} at all points; "
                  f"{int(np.sum(diff[k] > TOL))} points beyond {TOL:g}")
        print(f"  {int(bad.sum())} points beyond the tolerance: {int(boundary.sum())} boundary points (the C++ "
              f"results within {NUDGE:g} pattern units or {NUDGE_VIEW:g} rad of view agree with the shader), "
              f"{int(genuine.sum())} mismatches")
        for i in np.nonzero(genuine)[0][:5]:
            worst = max(SHADER_OUTPUTS, key=lambda k: diff[k][i])
            print(f"    point ({i % GRID}, {i // GRID}) UV ({u[i]:.7g}, {v[i]:.7g}) view {np.round(view[i], 4)}: "
                  + ", ".join(f"{k} OSL {np.round(got[k][i].astype(float), 5).tolist()} C++ "
                    f"{np.round(np.atleast_1d(ref[k][i]).astype(float), 5).tolist()}"
                              for k in SHADER_OUTPUTS if diff[k][i] > TOL)
                  + f" (worst {worst})")
        checks = [
            (not genuine.any(), f"{int(genuine.sum())} points differ by more than {TOL:g}"),
            (boundary.sum() <= MAX_BOUNDARY * n, f"{int(boundary.sum())} boundary points, more than "
                                                 f"{MAX_BOUNDARY * 100:g}%"),
            (not np.any(got["Error"]), "the shader reported an error"),
            (len(colours) >= 2, "fewer than two colours seen"),
            (mode or 0.02 < (~hits).mean() < 0.5, "the grid does not see both yarn and holes"),
            (not mode or np.mean((cov > 0) & (cov < 1)) > 0.1, "multi-scale coverage is hardly ever partial"),
        ]
        for ok, what in checks:
            if not ok:
                print(f"  FAIL: {what}")
                failures.append(name)

    secs = time.perf_counter() - start
    print(f"\n{len(CASES)} cases, {len(CASES) * GRID * GRID} points, {secs:.1f} s")
    if failures:
        print(f"FAIL: {', '.join(sorted(set(failures)))}")
        return 1
    print("OK: the shader's outputs equal the C++ library's within 1e-4")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The add-on's yarn layout and swatch scene (core/yarn_layout.py,
core/swatch.py) without bpy and without the C++ module: point location in
UV space against a brute-force search, UV islands, splitting at borders
and seams, the scale per triangle, the tiling, placing points on a curved
mesh, and the swatch's scene file.

    /usr/bin/python3 -m unittest -v test_yarn_layout     (CTest: addon_core.yarn_layout)
"""
import json
import math
import os
import pathlib
import sys
import types
import unittest

import numpy as np

ROOT = pathlib.Path(os.environ.get("KNIT_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
if "knitshade_blender" not in sys.modules:
    _pkg = types.ModuleType("knitshade_blender")
    _pkg.__path__ = [str(ROOT / "addon" / "knitshade_blender")]
    sys.modules["knitshade_blender"] = _pkg
from knitshade_blender.core import pattern as kpattern  # noqa: E402
from knitshade_blender.core import swatch as kswatch  # noqa: E402
from knitshade_blender.core import yarn_layout as L  # noqa: E402


def grid_mesh(nu, nv, width=2.0, height=1.0, bend=0.0):
    """A (nu x nv)-quad sheet, triangulated, UVs 0..1, optionally bent into
    an arc of a cylinder of `bend` radians about y; returns the Surface's
    inputs (pos, normals, uv, vertices)."""
    vid = np.arange((nu + 1) * (nv + 1)).reshape(nv + 1, nu + 1)
    u, v = np.meshgrid(np.linspace(0, 1, nu + 1), np.linspace(0, 1, nv + 1))
    if bend:
        R = width / bend
        phi = (u - 0.5) * bend
        P = np.stack([R * np.sin(phi), v * height, R * np.cos(phi)], axis=-1)
        N = np.stack([np.sin(phi), 0 * phi, np.cos(phi)], axis=-1)
    else:
        P = np.stack([u * width, v * height, 0 * u], axis=-1)
        N = np.stack([0 * u, 0 * u, 1 + 0 * u], axis=-1)
    UV = np.stack([u, v], axis=-1)
    tris = []
    for j in range(nv):
        for i in range(nu):
            a, b, c, d = vid[j, i], vid[j, i + 1], vid[j + 1, i + 1], vid[j + 1, i]
            tris += [(a, b, c), (a, c, d)]
    tris = np.array(tris)
    P, N, UV = P.reshape(-1, 3), N.reshape(-1, 3), UV.reshape(-1, 2)
    return P[tris], N[tris], UV[tris], tris


class UvGridTest(unittest.TestCase):
    def test_locate_matches_brute_force(self):
        rng = np.random.default_rng(3)
        pos, nor, uv, vid = grid_mesh(7, 5)
        grid = L.UvGrid(uv, np.ones(len(uv), dtype=bool))
        pts = rng.random((5000, 2)) * 1.2 - 0.1
        tri, bary = grid.locate(pts)
        for k in range(0, 5000, 7):
            p = pts[k]
            inside = []
            for t, (a, b, c) in enumerate(uv):
                m = np.array([b - a, c - a]).T
                l1, l2 = np.linalg.solve(m, p - a)
                if min(l1, l2, 1 - l1 - l2) >= -1e-9:
                    inside.append((t, (1 - l1 - l2, l1, l2)))
            if not inside:
                self.assertEqual(tri[k], -1, "point %s is outside" % p)
            else:
                self.assertEqual(tri[k], inside[0][0], "the first triangle in mesh order")
                np.testing.assert_allclose(bary[k], inside[0][1], atol=1e-9)
                np.testing.assert_allclose((uv[tri[k]] * bary[k][:, None]).sum(axis=0), p, atol=1e-12)

    def test_degenerate_triangles_are_skipped(self):
        pos, nor, uv, vid = grid_mesh(2, 1)
        uv[1] = [uv[1][0], uv[1][0], uv[1][0]]  # no UV area
        s = L.Surface(pos, nor, uv, vid, 10.0)
        self.assertEqual(s.degenerate, 1)
        self.assertEqual(s.first_degenerate, 1)
        self.assertEqual(s.grid.count, len(uv) - 1)


class IslandsTest(unittest.TestCase):
    def test_connected_and_seamed(self):
        pos, nor, uv, vid = grid_mesh(4, 2)
        self.assertEqual(L.uv_islands(vid, uv).max(), 0)
        # move the right half's UVs: same vertices, other UVs -> two islands
        uv2 = uv.copy()
        right = pos[:, :, 0].mean(axis=1) > 1.0
        uv2[right] += [3.0, 0.0]
        isl = L.uv_islands(vid, uv2)
        self.assertEqual(isl.max(), 1)
        self.assertTrue(np.all(isl[right] == isl[right][0]) and np.all(isl[~right] == isl[~right][0]))
        self.assertNotEqual(isl[right][0], isl[~right][0])

    def test_split_pieces(self):
        island = np.array([0, 0, 1, 1])
        tri = np.array([0, 1, 1, -1, 2, 3, 3, 0, 1, -1, 0])
        # runs: [0..3) island 0, [4..7) island 1, [7..9) island 0, [10] alone (dropped)
        self.assertEqual(L.split_pieces(tri, island).tolist(), [[0, 3], [4, 7], [7, 9]])
        self.assertEqual(L.split_pieces(np.array([-1, -1]), island).tolist(), [])


class PlacementTest(unittest.TestCase):
    def test_scale_of_a_plane(self):
        pos, nor, uv, vid = grid_mesh(3, 3, width=2.0, height=1.0)
        s = L.Surface(pos, nor, uv, vid, 40.0)
        np.testing.assert_allclose(s.scale, 40.0 / math.sqrt(2.0 * 1.0))
        self.assertIn("different scales", L.Surface(*self._two_scales(), 40.0).scale_warning("Obj"))
        self.assertEqual(s.scale_warning("Obj"), "")

    @staticmethod
    def _two_scales():
        pos, nor, uv, vid = grid_mesh(2, 1)
        uv = uv.copy()
        right = pos[:, :, 0].mean(axis=1) > 1.0
        uv[right] = (uv[right] - [0.5, 0.0]) * 0.3 + [2.0, 0.0]
        return pos, nor, uv, vid

    def test_points_on_a_cylinder(self):
        bend = 1.2
        pos, nor, uv, vid = grid_mesh(64, 4, width=1.0, height=1.0, bend=bend)
        s = L.Surface(pos, nor, uv, vid, 30.0)
        s.shell_top = 1.65
        rng = np.random.default_rng(5)
        pts = np.column_stack([rng.random(500) * 30.0, rng.random(500) * 30.0, rng.uniform(-1.65, 1.65, 500)])
        tri, p, n, S = s.place(pts)
        self.assertTrue(np.all(tri >= 0))
        R = 1.0 / bend
        phi = (pts[:, 0] / 30.0 - 0.5) * bend
        # the faceted surface point, up to the chord's sag, and the interpolated normal
        h = (pts[:, 2] - 1.65) / S
        base = p - h[:, None] * n
        radial = np.hypot(base[:, 0], base[:, 2])
        self.assertLess(np.abs(radial - R).max(), R * (1 - math.cos(bend / 128)) + 1e-9)
        self.assertLess(np.abs(np.arctan2(n[:, 0], n[:, 2]) - phi).max(), 1e-6)  # (lerp, not slerp)
        np.testing.assert_allclose(base[:, 1], pts[:, 1] / 30.0, atol=1e-12)

    def test_tiles_and_layout(self):
        self.assertEqual(L.tiles((0.0, 0.0), (1.0, 1.0), 40.0, (4 * math.pi, 9.0)), (0, 0, 4, 5))
        self.assertEqual(L.tiles((-0.5, 0.25), (0.5, 1.0), 40.0, (4 * math.pi, 9.0)), (-2, 1, 4, 4))
        pos, nor, uv, vid = grid_mesh(4, 4, width=1.0, height=1.0)
        s = L.Surface(pos, nor, uv, vid, 10.0)
        # one straight "yarn" per band row at y = 1 and 3, from x = 0 to 12 (past the mesh's 10)
        x = np.linspace(0.0, 12.0, 25)
        curves = [np.column_stack([x, np.full_like(x, yy), np.zeros_like(x)]) for yy in (1.0, 3.0)]
        colors = [np.zeros(25, dtype=int), np.ones(25, dtype=int)]
        lay = L.Layout(s, curves, colors, (12.0, 4.0), 1.0, 0.5, 0, 0, 3)  # 3 bands, 4 units tall
        res = lay.run()
        # rows at y = 1, 3, 5, 7, 9 land (11 is above the mesh); each keeps x <= 10: 21 points
        self.assertEqual(res["sizes"].tolist(), [21] * 5)
        self.assertEqual(res["colour"].tolist(), ([0] * 21 + [1] * 21) * 2 + [0] * 21)
        np.testing.assert_allclose(res["positions"][:, 2], (0.0 - 1.0) / 10.0)
        np.testing.assert_allclose(res["radius"], 0.05)
        self.assertAlmostEqual(L.polyline_length(res["positions"], res["sizes"]), 5 * 1.0)


class SwatchTest(unittest.TestCase):
    def test_scene(self):
        pat = kpattern.parse_text("K P\nP K\ncolors:\n0 1\n1 2", "<t>")
        values = {"A": 1.2, "H": 3.5, "D": -0.8, "R": 0.6, "Yarn0": (1, 0, 0), "Yarn1": (0, 1, 0),
                  "Yarn2": (0, 0, 1), "TransmitTint": (0.5, 0.5, 0.5), "Mode": 1, "CAPM": False, "PlyDetail": 0}
        sc = json.loads(kswatch.scene_text(values, pat, "patch.obj"))
        km = sc["materials"]["knit"]
        self.assertEqual(km["pattern"], ["KP", "PK"])
        self.assertEqual(km["colors"], [[0, 1], [1, 2]])
        self.assertEqual(km["yarn_colors"], [[1, 0, 0], [0, 1, 0], [0, 0, 1]])
        self.assertEqual(km["transmit_colors"][0], [0.5, 0, 0])
        self.assertEqual((km["a"], km["h"], km["d"], km["r"]), (1.2, 3.5, -0.8, 0.6))
        self.assertEqual((km["mode"], km["capm"], km["ply"]["enabled"]), ("multi_scale", False, False))
        self.assertAlmostEqual(km["uv_scale"], 2 * math.pi * 8, places=4)  # 2 columns: 4 repeats, 8 stitches
        self.assertNotEqual(kswatch.settings_key(values, pat), kswatch.settings_key(dict(values, R=0.61), pat))

    def test_patch(self):
        lines = kswatch.patch_obj(8, 4).splitlines()
        v = np.array([[float(x) for x in ln.split()[1:]] for ln in lines if ln.startswith("v ")])
        self.assertEqual(len(v), 9 * 5)
        self.assertEqual(sum(1 for ln in lines if ln.startswith("f ")), 2 * 8 * 4)
        arc = np.linalg.norm(np.diff(v[:9][:, [0, 2]], axis=0), axis=1).sum()
        self.assertAlmostEqual(arc, 1.0, places=2)
        self.assertEqual([kswatch.stitches_across(c) for c in (1, 2, 3, 5, 16, 30, 48)], [8, 8, 9, 10, 16, 24, 24])


if __name__ == "__main__":
    unittest.main()

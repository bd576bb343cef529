"""Python bindings of the stitch geometry: StitchParams, KnitSurface (query,
crossings, capm), frames and explicit_yarns. Accuracy is checked against a
ray cast of the explicit yarns done here in numpy (independent of the C++
kernel): the first surface of a union of spheres centred on the dense curve.
"""
import math
import unittest

import numpy as np

import knitshade


def seed_pattern():
    return knitshade.Pattern.from_rows([[0, 1], [1, 0]])


def explicit_top(curves, r, x, y):
    """Height of the first tube surface seen from above at (x, y): the
    maximum over curve points c within r of (x, y) of c.z + sqrt(r^2 - rho^2)."""
    best = -np.inf
    for c in curves:
        d2 = (c[:, 0] - x) ** 2 + (c[:, 1] - y) ** 2
        m = d2 < r * r
        if m.any():
            best = max(best, float(np.max(c[m, 2] + np.sqrt(r * r - d2[m]))))
    return best


class StitchParamsTest(unittest.TestCase):
    def test_defaults_and_fields(self):
        p = knitshade.StitchParams()
        self.assertAlmostEqual(p.a, 1.5)
        self.assertAlmostEqual(p.h, 4.0)
        self.assertAlmostEqual(p.d, 1.0)
        self.assertAlmostEqual(p.r, 0.65, places=6)
        self.assertAlmostEqual(p.row_spacing, 4.5)
        self.assertGreater(p.clearance(), 2 * p.r)

    def test_invalid_values_name_the_parameter(self):
        cases = [
            (dict(a=-1.0), "a (loop roundness) must be > 0, got -1"),
            (dict(h=0.0), "h (loop height) must be > 0, got 0"),
            (dict(d=0.0), "d (loop depth) must be non-zero"),
            (dict(r=-0.5), "r (yarn radius) must be > 0, got -0.5"),
            (dict(a=float("nan")), "a must be finite, got nan"),
            (dict(r=0.8), "pass through each other"),
        ]
        for kwargs, message in cases:
            with self.subTest(kwargs=kwargs):
                with self.assertRaises(ValueError) as cm:
                    knitshade.StitchParams(**kwargs)
                self.assertIn(message, str(cm.exception))


class QueryTest(unittest.TestCase):
    def setUp(self):
        self.params = knitshade.StitchParams()
        self.surf = knitshade.KnitSurface(seed_pattern(), self.params)

    def test_vectorised_shapes_and_keys(self):
        u = np.linspace(5, 30, 101)
        v = np.linspace(3, 17, 101)
        q = self.surf.query(u, v)
        for key in ("hit", "z", "position", "normal", "tangent", "layers", "stitch", "color", "row", "col"):
            self.assertIn(key, q)
        self.assertEqual(q["hit"].shape, (101,))
        self.assertEqual(q["normal"].shape, (101, 3))
        hit = q["hit"]
        self.assertTrue(hit.any() and (~hit).any())
        self.assertTrue(np.all(np.isnan(q["z"][~hit])))
        n = q["normal"][hit]
        np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-4)
        self.assertTrue(np.all(n[:, 2] > -1e-3), "the first surface seen from above faces up")
        self.assertTrue(np.all(q["layers"][hit] >= 1))
        self.assertTrue(set(np.unique(q["stitch"][hit])) <= {0, 1})

    def test_height_matches_explicit_yarns(self):
        y = knitshade.explicit_yarns(seed_pattern(), self.params, 4, 4, 512)
        self.assertAlmostEqual(y["radius"], self.params.r, places=6)
        rng = np.random.default_rng(4)
        u = rng.uniform(8, 17, 300)
        v = rng.uniform(8, 22, 300)
        q = self.surf.query(u, v)
        errs = []
        agree = 0
        for i in range(len(u)):
            top = explicit_top(y["curves"], y["radius"], u[i], v[i])
            if np.isfinite(top) == bool(q["hit"][i]):
                agree += 1
            if np.isfinite(top) and q["hit"][i]:
                errs.append(abs(top - q["z"][i]))
        self.assertGreaterEqual(agree, 0.98 * len(u))
        self.assertLess(np.mean(errs) / self.params.r, 0.01)

    def test_uv_scale_maps_uv_to_pattern_space(self):
        s2 = knitshade.KnitSurface(seed_pattern(), self.params, uv_scale=10.0)
        a = s2.query(np.array([1.3]), np.array([0.7]))
        b = self.surf.query(np.array([13.0]), np.array([7.0]))
        np.testing.assert_allclose(a["position"], b["position"], atol=1e-4)

    def test_crossings_list_both_layers(self):
        found_two = False
        for x in np.linspace(0, 12.5, 60):
            cr = self.surf.crossings(float(x), 6.75)
            for c in cr:
                self.assertGreaterEqual(c["z_top"], c["z_bottom"])
                self.assertIn(c["layer"], (0, 1))
            if len({c["layer"] for c in cr}) == 2:
                found_two = True
            tops = [c["z_top"] for c in cr]
            self.assertEqual(tops, sorted(tops, reverse=True))
        self.assertTrue(found_two, "some vertical line must cross tubes of both row layers")

    def test_bad_input_is_rejected(self):
        with self.assertRaises(ValueError) as cm:
            self.surf.query(np.array([1.0, float("nan")]), np.array([1.0, 2.0]))
        self.assertIn("u[1] must be finite", str(cm.exception))
        with self.assertRaises(ValueError):
            self.surf.query(np.zeros(3), np.zeros(4))
        with self.assertRaises(ValueError):
            knitshade.KnitSurface(seed_pattern(), self.params, uv_scale=0.0)
        # Beyond +-32768 pattern units single precision no longer resolves the
        # yarns: rejected, naming the value, for every entry point.
        with self.assertRaises(ValueError) as cm:
            self.surf.query(np.array([1.0, 1e8]), np.array([1.0, 2.0]))
        self.assertIn("u[1] = 1e+08 maps to pattern coordinate", str(cm.exception))
        with self.assertRaises(ValueError):
            self.surf.crossings(1.0, -4e4)
        with self.assertRaises(ValueError):
            self.surf.capm(np.array([5e4]), np.array([1.0]), np.array([0.0, 0.0, 1.0]))
        # A segment's query costs in proportion to its length: the longest
        # accepted is 1000 pattern units, as in the scene format.
        for bad in (1001.0, 1e9, float("inf"), float("nan"), 0.0):
            with self.assertRaises(ValueError) as cm:
                self.surf.capm(np.array([1.0]), np.array([1.0]), np.array([0.0, 0.0, 1.0]), max_segment=bad)
            self.assertIn("max_segment must be > 0 and at most 1000", str(cm.exception))
        far = knitshade.KnitSurface(seed_pattern(), self.params, uv_scale=100.0)
        with self.assertRaises(ValueError) as cm:
            far.query(400.0, 1.0)
        self.assertIn("(uv_scale 100)", str(cm.exception))
        # Just inside the limit the answer still matches the same point one
        # whole number of pattern periods nearer the origin.
        period_u = seed_pattern().cols * 2 * math.pi / 100.0
        u_far = 300.0 + 0.013 * np.arange(40)
        u_near = u_far - round(300.0 / period_u) * period_u
        a, b = far.query(u_far, 1.0), far.query(u_near, 1.0)
        np.testing.assert_array_equal(a["hit"], b["hit"])
        both = a["hit"] & b["hit"]
        self.assertGreater(int(both.sum()), 20)
        self.assertLess(float(np.max(np.abs(a["z"][both] - b["z"][both]))), 0.02)


class CapmTest(unittest.TestCase):
    def setUp(self):
        self.params = knitshade.StitchParams()
        self.surf = knitshade.KnitSurface(seed_pattern(), self.params)

    def test_normal_incidence_equals_height_query(self):
        rng = np.random.default_rng(2)
        u = rng.uniform(0, 40, 200)
        v = rng.uniform(0, 40, 200)
        c = self.surf.capm(u, v, np.array([0.0, 0.0, 1.0]))
        q = self.surf.query(u, v)
        np.testing.assert_array_equal(c["hit"], q["hit"])
        np.testing.assert_allclose(c["position"][c["hit"]], q["position"][q["hit"]], atol=1e-3)
        self.assertTrue(np.all(c["steps"] == 1))

    def test_oblique_rays_land_on_the_explicit_tube_surface(self):
        y = knitshade.explicit_yarns(seed_pattern(), self.params, 6, 6, 256)
        pts = np.concatenate(y["curves"])
        rng = np.random.default_rng(9)
        th = np.radians(60)
        n = 150
        ph = rng.uniform(0, 2 * np.pi, n)
        wi = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.full(n, np.cos(th))], 1)
        u = rng.uniform(20, 50, n)
        v = rng.uniform(20, 50, n)
        c = self.surf.capm(u, v, wi)
        self.assertGreater(c["hit"].mean(), 0.7)
        err = np.array([abs(np.min(np.linalg.norm(pts - p, axis=1)) - self.params.r)
                        for p in c["position"][c["hit"]]]) / self.params.r
        # Entry points lie on the tube surface (to the polyline's sampling
        # error); a few grazing entries converge less (see docs/geometry.md).
        self.assertGreaterEqual(np.mean(err < 0.02), 0.95)
        self.assertLess(err.max(), 0.2)
        self.assertLessEqual(int(c["steps"].max()), 32)

    def test_cylinder_bends_rays_away_at_the_silhouette(self):
        # Grazing rays across a tight cylinder leave the shell: fewer hits than flat.
        rng = np.random.default_rng(1)
        n = 300
        wi = np.tile([math.sin(math.radians(88)), 0.0, math.cos(math.radians(88))], (n, 1))
        u = rng.uniform(0, 40, n)
        v = rng.uniform(0, 40, n)
        flat = self.surf.capm(u, v, wi)
        cyl = self.surf.capm(u, v, wi, frame=knitshade.CylinderFrame(15.0))
        self.assertLess(cyl["hit"].sum(), flat["hit"].sum())

    def test_rejects_directions_into_the_surface(self):
        with self.assertRaises(ValueError) as cm:
            self.surf.capm(np.array([1.0]), np.array([1.0]), np.array([0.0, 0.0, -1.0]))
        self.assertIn("z > 0", str(cm.exception))
        with self.assertRaises(ValueError):
            knitshade.CylinderFrame(-1.0)

    def test_a_non_finite_direction_is_named_by_its_row_and_component(self):
        wi = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [0.1, math.nan, 1.0]])
        with self.assertRaises(ValueError) as cm:
            self.surf.capm(np.zeros(3), np.zeros(3), wi)
        self.assertIn("wi_local[2] must be finite, got nan in component 1", str(cm.exception))
        with self.assertRaises(ValueError) as cm:
            self.surf.capm(1.0, 1.0, np.array([0.0, 0.0, math.inf]))
        self.assertIn("wi_local must be finite, got inf in component 2", str(cm.exception))


class ParallelBatchTest(unittest.TestCase):
    """Batches of 1024 points or more run on every core (TBB): each row must
    come out exactly as when the point is asked alone, in the calling
    thread."""

    def setUp(self):
        self.surf = knitshade.KnitSurface(seed_pattern(), knitshade.StitchParams())
        rng = np.random.default_rng(21)
        self.n = 3000
        self.u = rng.uniform(0, 60, self.n)
        self.v = rng.uniform(0, 60, self.n)
        th = rng.uniform(0, 1.4, self.n)
        ph = rng.uniform(0, 2 * math.pi, self.n)
        self.wi = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=1)
        self.rows = list(range(0, self.n, 97))

    def assert_rows_equal(self, batch, single, i):
        for key, value in single.items():
            np.testing.assert_array_equal(batch[key][i], value[0], err_msg=f"{key}[{i}]")

    def test_query(self):
        q = self.surf.query(self.u, self.v)
        self.assertTrue(q["hit"].any() and (~q["hit"]).any())
        for i in self.rows:
            self.assert_rows_equal(q, self.surf.query(self.u[i:i + 1], self.v[i:i + 1]), i)

    def test_query_path(self):
        # knit and purl only: a vector path where the CPU has one; slip
        # stitches (codes 2 and 3) always take the scalar kernel
        self.assertIn(self.surf.query_path, ("avx512", "avx2", "scalar"))
        slip = knitshade.KnitSurface(knitshade.Pattern.from_rows([[0, 2], [3, 0]]), knitshade.StitchParams())
        self.assertEqual(slip.query_path, "scalar")
        print(f"query_path here: {self.surf.query_path}")

    def test_capm_on_a_cylinder(self):
        frame = knitshade.CylinderFrame(40.0)
        c = self.surf.capm(self.u, self.v, self.wi, frame=frame)
        self.assertTrue(c["hit"].any() and (~c["hit"]).any())
        for i in self.rows:
            self.assert_rows_equal(c, self.surf.capm(self.u[i:i + 1], self.v[i:i + 1], self.wi[i], frame=frame), i)

    def test_material_shade(self):
        # The appearance functions share the same row loop.
        m = knitshade.KnitMaterial(seed_pattern(), knitshade.StitchParams(), uv_scale=1.0)
        d = -self.wi
        sh = m.shade(self.u, self.v, d)
        self.assertTrue(sh["pass_through"].any() and (~sh["pass_through"]).any())
        for i in self.rows:
            single = m.shade(self.u[i:i + 1], self.v[i:i + 1], d[i:i + 1])
            for key, value in single.items():
                np.testing.assert_array_equal(sh[key][i], value[0], err_msg=f"{key}[{i}]")

    def test_aggregate(self):
        args = ([3.0, 0.5], [0.4, 2.5], [0.3, 0.2, 0.93], 8, 0.3, 0.7)
        a = self.surf.aggregate(self.u, self.v, *args)
        self.assertTrue((a["hits"] > 0).any())
        for i in self.rows:
            self.assert_rows_equal(a, self.surf.aggregate(self.u[i:i + 1], self.v[i:i + 1], *args), i)


class ExplicitYarnsTest(unittest.TestCase):
    def test_shapes_and_extent(self):
        p = knitshade.Pattern.from_rows([[0, 1, 0], [1, 1, 0]])
        y = knitshade.explicit_yarns(p, knitshade.StitchParams(), 2, 3, 32)
        self.assertEqual(len(y["curves"]), 2 * 3)
        for c, col in zip(y["curves"], y["colors"]):
            self.assertEqual(c.shape, (3 * 2 * 32 + 1, 3))
            self.assertEqual(col.shape, (c.shape[0],))
        self.assertAlmostEqual(y["width"], 2 * math.pi * 6, places=4)
        self.assertAlmostEqual(y["height"], 4.5 * 6, places=4)
        self.assertEqual(y["rows"], list(range(6)))
        self.assertAlmostEqual(y["t_step"], 2 * math.pi / 32, places=12)
        # Point i lies at curve parameter i t_step: a stitch (2 pi of t) is
        # 32 points, so the curves repeat every 3 * 32 points in x by one
        # pattern width (the pattern repeats along the row).
        c = y["curves"][0]
        np.testing.assert_allclose(c[96:, 0] - c[:-96, 0], 2 * math.pi * 3, atol=1e-9)

    def test_rejects_bad_tiles(self):
        with self.assertRaises(ValueError):
            knitshade.explicit_yarns(seed_pattern(), knitshade.StitchParams(), 0, 1)


if __name__ == "__main__":
    unittest.main()

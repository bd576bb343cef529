"""Python bindings of the appearance model: YarnBSDF (and its lobes),
PlyProfile and KnitMaterial.

The BSDF checks are done in numpy from the outside: sample/eval/pdf agreement,
a white furnace, an independent albedo estimate by uniform integration of
eval, closed-form albedos where they exist, and a histogram of sampled
cos(theta) against the pdf integrated over the bins. Ply shadowing is checked
against a 2D ray cast of the ply discs done here; KnitMaterial against
KnitSurface (capm, query, aggregate), which the geometry tests check against
explicit yarns.
"""
import math
import pathlib
import pickle
import unittest

import numpy as np

import knitshade

TWO_PI = 2 * math.pi


def unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def random_dirs(rng, n):
    return unit(rng.normal(size=(n, 3)))


def direction(theta_deg, azimuth=0.9):
    t = math.radians(theta_deg)
    return np.array([math.sin(t) * math.cos(azimuth), math.sin(t) * math.sin(azimuth), math.cos(t)])


def sphere(mu, phi):
    s = np.sqrt(np.maximum(0.0, 1.0 - mu * mu))
    return np.stack([s * np.cos(phi), s * np.sin(phi), mu], -1)


WHITE = dict(reflect_colors=[[1.0, 1.0, 1.0]], optical_depth=0.0)

# Parameter sets used by several tests: defaults, index-matched, pure body,
# nearly smooth, very rough and dense, anisotropic.
PARAM_SETS = [
    {},
    dict(eta=1.0),
    dict(body_energy=1.0, body_reflect=0.0),
    dict(roughness_x=0.02, roughness_y=0.04, trans_roughness_x=0.02, trans_roughness_y=0.03),
    dict(eta=3.0, roughness_x=1.0, roughness_y=1.0, optical_depth=5.0),
    dict(roughness_x=0.6, roughness_y=0.1, body_energy=0.2, body_reflect=0.9),
]


class YarnBSDFConstruction(unittest.TestCase):
    def test_defaults_match_the_documented_table(self):
        b = knitshade.YarnBSDF()
        expected = dict(roughness_x=0.15, roughness_y=0.45, trans_roughness_x=0.30, trans_roughness_y=0.60,
                        eta=1.55, body_energy=0.7, body_reflect=0.6, optical_depth=1.0)
        for name, value in expected.items():
            self.assertAlmostEqual(getattr(b, name), value, places=6, msg=name)
        np.testing.assert_allclose(b.reflect_colors, [[0.8, 0.8, 0.8]], rtol=1e-6)
        np.testing.assert_allclose(b.transmit_colors, [[0.8, 0.8, 0.8]], rtol=1e-6)
        self.assertEqual(b.num_colors, 1)

    def test_keywords_set_every_field(self):
        cols = np.array([[1.0, 0.5, 0.0], [0.1, 0.2, 0.3]])
        b = knitshade.YarnBSDF(roughness_x=0.2, roughness_y=0.3, trans_roughness_x=0.4, trans_roughness_y=0.5,
                               eta=1.3, body_energy=0.25, body_reflect=0.75, optical_depth=2.5,
                               reflect_colors=cols, transmit_colors=[[0.0, 0.0, 1.0], (0.5, 0.5, 0.5)])
        for name, value in dict(roughness_x=0.2, roughness_y=0.3, trans_roughness_x=0.4, trans_roughness_y=0.5,
                                eta=1.3, body_energy=0.25, body_reflect=0.75, optical_depth=2.5).items():
            self.assertAlmostEqual(getattr(b, name), value, places=6, msg=name)
        np.testing.assert_allclose(b.reflect_colors, cols, rtol=1e-6)
        np.testing.assert_allclose(b.transmit_colors, [[0, 0, 1], [0.5, 0.5, 0.5]], rtol=1e-6)
        self.assertEqual(b.num_colors, 2)
        # transmit_colors defaults to the reflect colours; one triple is one colour
        b2 = knitshade.YarnBSDF(reflect_colors=cols)
        np.testing.assert_array_equal(b2.transmit_colors, b2.reflect_colors)
        b3 = knitshade.YarnBSDF(reflect_colors=(0.2, 0.4, 0.6))
        np.testing.assert_allclose(b3.reflect_colors, [[0.2, 0.4, 0.6]], rtol=1e-6)
        # params() rebuilds the same BSDF; so does pickling
        b4 = knitshade.YarnBSDF(**b.params())
        b5 = pickle.loads(pickle.dumps(b))
        for other in (b4, b5):
            self.assertEqual(other.params().keys(), b.params().keys())
            for key, value in b.params().items():
                np.testing.assert_array_equal(other.params()[key], value, err_msg=key)

    def test_invalid_parameters_carry_the_cpp_message(self):
        cases = [
            (dict(eta=0.5), "YarnBsdfParams.eta = 0.5: must be finite and in [1, 3]"),
            (dict(roughness_x=0.0), "YarnBsdfParams.roughness_x = 0: must be finite and in (0, 1]"),
            (dict(trans_roughness_y=1.5), "YarnBsdfParams.trans_roughness_y = 1.5"),
            (dict(body_energy=float("nan")), "YarnBsdfParams.body_energy = nan"),
            (dict(body_reflect=-0.1), "YarnBsdfParams.body_reflect = -0.1"),
            (dict(optical_depth=51.0), "YarnBsdfParams.optical_depth = 51: must be finite and in [0, 50]"),
            (dict(reflect_colors=[[0.5, 0.5, 0.5], [0.2, 1.5, 0.0]]),
             "YarnBsdfParams.reflect_colors[1].g = 1.5: must be finite and in [0, 1]"),
            (dict(reflect_colors=[[0.5, 0.5, 0.5]], transmit_colors=[[0.5, 0.5, -1.0]]),
             "YarnBsdfParams.transmit_colors[0].b = -1"),
            (dict(reflect_colors=[[1, 1, 1], [1, 1, 1]], transmit_colors=[[1, 1, 1]]),
             "YarnBsdfParams.transmit_colors.size() = 1: must equal reflect_colors.size()"),
            (dict(reflect_colors=np.zeros((0, 3))), "YarnBsdfParams.reflect_colors.size() = 0: must be in [1, 256]"),
            (dict(reflect_colors=np.zeros((257, 3))), "YarnBsdfParams.reflect_colors.size() = 257"),
            (dict(reflect_colors=[[1, 1], [1, 1]]), "reflect_colors must be a list of RGB triples"),
        ]
        for kwargs, message in cases:
            with self.subTest(kwargs=kwargs):
                with self.assertRaises(ValueError) as cm:
                    knitshade.YarnBSDF(**kwargs)
                self.assertIn(message, str(cm.exception))

    def test_arguments_are_keywords_only(self):
        with self.assertRaises(TypeError):
            knitshade.YarnBSDF(0.2)
        with self.assertRaises(TypeError):
            knitshade.YarnBSDF(roughnes_x=0.2)  # misspelt
        with self.assertRaises(TypeError):
            knitshade.YarnBSDF(reflect_colors=[["a", "b", "c"]])

    def test_flag_constants(self):
        self.assertEqual((knitshade.BSDF_REFLECT, knitshade.BSDF_TRANSMIT, knitshade.BSDF_DELTA), (1, 2, 4))
        self.assertEqual(int(knitshade.Lobe.SPECULAR_REFLECTION), 0)
        self.assertEqual(int(knitshade.Lobe.BODY_TRANSMISSION), 3)


class YarnBSDFContract(unittest.TestCase):
    """eval / pdf / sample agree; eval includes the cosine; the lobes add up."""

    def test_sample_agrees_with_eval_and_pdf(self):
        rng = np.random.default_rng(11)
        n = 20000
        for kwargs in PARAM_SETS:
            b = knitshade.YarnBSDF(**kwargs)
            for p_delta in (0.0, 0.35):
                with self.subTest(params=kwargs, p_delta=p_delta):
                    point = dict(p_delta=p_delta, layers=2, shadow=0.7)
                    wo = random_dirs(rng, n)  # both sides of the surface
                    s = b.sample(wo, rng.random((n, 3)), **point)
                    self.assertEqual(s["wi"].shape, (n, 3))
                    self.assertEqual(s["weight"].shape, (n, 3))
                    self.assertEqual(s["pdf"].shape, (n,))
                    self.assertEqual(s["flags"].shape, (n,))
                    self.assertEqual(s["valid"].dtype, np.bool_)
                    valid = s["valid"]
                    self.assertGreater(valid.mean(), 0.7)
                    np.testing.assert_array_equal(valid, (s["flags"] != 0) & (s["pdf"] > 0))
                    # failed samples carry nothing
                    self.assertTrue(np.all(s["weight"][~valid] == 0))
                    self.assertTrue(np.all(s["pdf"][~valid] == 0))
                    delta = (s["flags"] & knitshade.BSDF_DELTA) != 0
                    ok = valid & ~delta
                    wi = s["wi"][ok]
                    np.testing.assert_allclose(np.linalg.norm(wi, axis=1), 1.0, atol=1e-5)
                    e = b.eval(wo[ok], wi, **point)
                    p = b.pdf(wo[ok], wi, **point)
                    self.assertTrue(np.all(p > 0))
                    np.testing.assert_allclose(s["weight"][ok], e / p[:, None], rtol=1e-5, atol=1e-9)
                    np.testing.assert_allclose(s["pdf"][ok], p, rtol=1e-6)
                    # reflect/transmit flags agree with the sides of wo and wi
                    side = wo[ok, 2] * wi[:, 2]
                    reflect = (s["flags"][ok] & knitshade.BSDF_REFLECT) != 0
                    transmit = (s["flags"][ok] & knitshade.BSDF_TRANSMIT) != 0
                    np.testing.assert_array_equal(reflect, side > 0)
                    np.testing.assert_array_equal(transmit, side < 0)
                    # pass-through events: wi = -wo, weight 1, pdf = p_delta, with frequency p_delta
                    if p_delta == 0:
                        self.assertFalse(delta.any())
                    else:
                        np.testing.assert_array_equal(s["flags"][delta],
                                                      knitshade.BSDF_TRANSMIT | knitshade.BSDF_DELTA)
                        np.testing.assert_allclose(s["wi"][delta], -wo[delta], atol=1e-7)
                        np.testing.assert_allclose(s["weight"][delta], 1.0)
                        np.testing.assert_allclose(s["pdf"][delta], p_delta, rtol=1e-6)
                        sigma = math.sqrt(p_delta * (1 - p_delta) / n)
                        self.assertLess(abs(delta.mean() - p_delta), 5 * sigma)

    def test_eval_includes_the_cosine(self):
        # Index-matched yarn (eta = 1: no Fresnel), all body energy, tau = 1:
        # only Lambertian body transmission (r = 0) or Lommel-Seeliger body
        # reflection (r = 1) remain, with closed forms. eval = f |wi.z|.
        k = np.array([0.9, 0.5, 0.2])
        rng = np.random.default_rng(5)
        wo = random_dirs(rng, 500)
        wi = random_dirs(rng, 500)
        wo[:, 2] = np.abs(wo[:, 2]) + 0.05
        wo = unit(wo)
        wi[:, 2] = np.abs(wi[:, 2]) + 0.05
        wi = unit(wi)
        cos_i, cos_o = wi[:, 2], wo[:, 2]
        trans = knitshade.YarnBSDF(eta=1.0, body_energy=1.0, body_reflect=0.0, optical_depth=0.0,
                                   reflect_colors=[k], transmit_colors=[k])
        wi_below = wi * np.array([1, 1, -1])
        np.testing.assert_allclose(trans.eval(wo, wi_below), k[None, :] * cos_i[:, None] / math.pi, rtol=1e-5)
        np.testing.assert_allclose(trans.eval(wo, wi), 0.0, atol=1e-7)
        refl = knitshade.YarnBSDF(eta=1.0, body_energy=1.0, body_reflect=1.0, optical_depth=0.0,
                                  reflect_colors=[k], transmit_colors=[k])
        ls = 1.0 / (TWO_PI * (cos_i + cos_o))
        np.testing.assert_allclose(refl.eval(wo, wi), k[None, :] * (ls * cos_i)[:, None], rtol=1e-5)
        # the shadow G and p_delta scale the body lobes linearly
        np.testing.assert_allclose(refl.eval(wo, wi, shadow=0.25, p_delta=0.5),
                                   0.125 * refl.eval(wo, wi), rtol=1e-5)

    def test_eval_lobe_sums_to_eval(self):
        rng = np.random.default_rng(2)
        names = ["specular_reflection", "specular_transmission", "body_reflection", "body_transmission"]
        for kwargs in PARAM_SETS:
            b = knitshade.YarnBSDF(**kwargs)
            with self.subTest(params=kwargs):
                wo = random_dirs(rng, 3000)
                wi = random_dirs(rng, 3000)
                point = dict(layers=3, shadow=0.6)
                lobes = [b.eval_lobe(name, wo, wi, **point) for name in names]
                total = b.eval(wo, wi, **point)
                np.testing.assert_allclose(sum(lobes), total, rtol=1e-5, atol=1e-7)
                # the enum names the same lobes
                for name, lobe in zip(names, [knitshade.Lobe.SPECULAR_REFLECTION,
                                              knitshade.Lobe.SPECULAR_TRANSMISSION,
                                              knitshade.Lobe.BODY_REFLECTION, knitshade.Lobe.BODY_TRANSMISSION]):
                    np.testing.assert_array_equal(b.eval_lobe(lobe, wo, wi, **point),
                                                  lobes[names.index(name)])
                # reflection lobes vanish in transmission and vice versa
                refl = wo[:, 2] * wi[:, 2] > 0
                self.assertTrue(np.all(lobes[1][refl] == 0) and np.all(lobes[3][refl] == 0))
                self.assertTrue(np.all(lobes[0][~refl] == 0) and np.all(lobes[2][~refl] == 0))
                # eval_lobe ignores p_delta; eval scales by 1 - p_delta
                np.testing.assert_allclose(b.eval(wo, wi, p_delta=0.4, **point), 0.6 * total, rtol=1e-5, atol=1e-8)
                np.testing.assert_array_equal(b.eval_lobe("body_reflection", wo, wi, p_delta=0.4, **point),
                                              lobes[2])

    def test_lobe_probabilities(self):
        rng = np.random.default_rng(4)
        wo = random_dirs(rng, 500)
        q = knitshade.YarnBSDF().lobe_probabilities(wo)
        self.assertEqual(q.shape, (500, 4))
        np.testing.assert_allclose(q.sum(1), 1.0, atol=1e-5)
        self.assertTrue(np.all(q > 0))
        # lobes that cannot contribute are never chosen
        self.assertTrue(np.all(knitshade.YarnBSDF(eta=1.0).lobe_probabilities(wo)[:, 0] == 0))
        self.assertTrue(np.all(knitshade.YarnBSDF(body_energy=1.0).lobe_probabilities(wo)[:, 1] == 0))
        self.assertTrue(np.all(knitshade.YarnBSDF(body_reflect=1.0).lobe_probabilities(wo)[:, 3] == 0))
        self.assertTrue(np.all(knitshade.YarnBSDF(body_reflect=0.0).lobe_probabilities(wo)[:, 2] == 0))
        self.assertTrue(np.all(knitshade.YarnBSDF().lobe_probabilities(wo, shadow=0.0)[:, 2:] == 0))
        # higher Fresnel reflectance at grazing view: the specular reflection lobe is picked more often
        q2 = knitshade.YarnBSDF().lobe_probabilities(np.array([direction(0), direction(85)]))
        self.assertGreater(q2[1, 0], q2[0, 0])

    def test_reciprocity_and_two_sidedness(self):
        rng = np.random.default_rng(8)
        for kwargs in PARAM_SETS:
            b = knitshade.YarnBSDF(**kwargs)
            with self.subTest(params=kwargs):
                wo = random_dirs(rng, 2000)
                wi = random_dirs(rng, 2000)
                keep = (np.abs(wo[:, 2]) > 0.05) & (np.abs(wi[:, 2]) > 0.05)
                wo, wi = wo[keep], wi[keep]
                f = b.eval(wo, wi, layers=2) / np.abs(wi[:, 2:3])
                g = b.eval(wi, wo, layers=2) / np.abs(wo[:, 2:3])
                np.testing.assert_allclose(f, g, rtol=2e-4, atol=1e-6)
                flip = np.array([1.0, 1.0, -1.0])
                np.testing.assert_allclose(b.eval(wo * flip, wi * flip, layers=2), b.eval(wo, wi, layers=2),
                                           rtol=1e-5, atol=1e-7)


class YarnBSDFEnergy(unittest.TestCase):
    """White furnace and albedo checks by Monte Carlo in numpy."""

    N = 60000
    THETAS = (0, 30, 60, 80, 89)

    def setUp(self):
        self.rng = np.random.default_rng(2024)

    def albedo(self, b, wo, **point):
        s = b.sample(wo, self.rng.random((self.N, 3)), **point)
        w = s["weight"][:, 1]  # white: all channels alike
        return w.mean(), w.std() / math.sqrt(self.N)

    def test_white_furnace(self):
        # Colours 1, B = 1, tau = 1 (optical depth 0), G = 1: the directional
        # albedo, the mean sample weight, must not exceed 1.
        worst = 0.0
        for eta in (1.0, 1.55):
            for r in (0.0, 0.5, 1.0):
                b = knitshade.YarnBSDF(eta=eta, body_energy=1.0, body_reflect=r, **WHITE)
                for th in self.THETAS:
                    for side in (1.0, -1.0):
                        wo = direction(th) * np.array([1, 1, side])
                        mean, sigma = self.albedo(b, wo)
                        with self.subTest(eta=eta, r=r, theta=th, side=side):
                            self.assertLessEqual(mean, 1.0 + 3 * sigma + 1e-5)
                            self.assertGreater(mean, 0.2)
                        worst = max(worst, mean)
                        if eta == 1.0:
                            # Index-matched: body lobes only, closed form
                            # r A(mu_o) + (1 - r), A = 1 - mu ln(1 + 1/mu).
                            mu = max(abs(wo[2]), 1e-7)
                            expected = r * (1 - mu * math.log1p(1 / mu)) + (1 - r)
                            with self.subTest(eta=eta, r=r, theta=th, side=side, closed_form=expected):
                                self.assertLess(abs(mean - expected), 5 * sigma + 1e-5)
        self.assertLessEqual(worst, 1.0 + 1e-4)
        # with gaps, the pass-through events (weight 1) mix in: p + (1 - p) albedo
        b = knitshade.YarnBSDF(eta=1.0, body_energy=1.0, body_reflect=1.0, **WHITE)
        mu = math.cos(math.radians(30))
        mean, sigma = self.albedo(b, direction(30), p_delta=0.4)
        self.assertLess(abs(mean - (0.4 + 0.6 * (1 - mu * math.log1p(1 / mu)))), 5 * sigma)

    def test_sampled_albedo_matches_uniform_integration_of_eval(self):
        # An estimator that never calls sample(): 4 pi E[eval(wo, w)] over
        # uniform directions w. Both estimate the same directional albedo.
        for kwargs in (dict(roughness_x=0.4, roughness_y=0.6, trans_roughness_x=0.5, trans_roughness_y=0.7),
                       dict(eta=1.3, roughness_x=0.8, roughness_y=0.5, body_energy=0.4, body_reflect=0.3,
                            optical_depth=2.0)):
            b = knitshade.YarnBSDF(**kwargs)
            for th in (20, 70):
                wo = direction(th)
                mean, sigma = self.albedo(b, wo, layers=2)
                w = random_dirs(self.rng, self.N)
                e = 4 * math.pi * b.eval(wo, w, layers=2)[:, 0]
                mean_u, sigma_u = e.mean(), e.std() / math.sqrt(self.N)
                with self.subTest(params=kwargs, theta=th):
                    self.assertLess(abs(mean - mean_u), 4.5 * math.hypot(sigma, sigma_u))

    def test_cos_theta_histogram_matches_pdf(self):
        # Fraction of N samples per cos(theta) bin against the integral of
        # pdf over the bin (midpoint rule, 16 x 512 points per bin). Failed
        # samples count in no bin; pdf integrates to the success rate.
        # Tolerance per bin: 5 binomial standard deviations + 3e-4 for the
        # quadrature.
        bins, sub, nphi = 40, 16, 512
        mu = (np.arange(bins * sub) + 0.5) / (bins * sub) * 2 - 1
        phi = (np.arange(nphi) + 0.5) / nphi * TWO_PI
        grid = sphere(*np.meshgrid(mu, phi, indexing="ij"))
        edges = np.linspace(-1, 1, bins + 1)
        n = 200000
        cases = [({}, 45), ({}, 85), (dict(roughness_x=0.05, roughness_y=0.1), 30),
                 (dict(eta=1.0, body_energy=0.3), 60), (dict(body_reflect=1.0), 0)]
        for kwargs, th in cases:
            b = knitshade.YarnBSDF(**kwargs)
            wo = direction(th)
            s = b.sample(wo, self.rng.random((n, 3)), layers=2)
            observed = np.histogram(s["wi"][s["valid"], 2], edges)[0] / n
            pdf = b.pdf(wo, grid.reshape(-1, 3), layers=2).reshape(grid.shape[:2])
            expected = (pdf.sum(1) * (2.0 / (bins * sub)) * (TWO_PI / nphi)).reshape(bins, sub).sum(1)
            tol = 5 * np.sqrt(expected * (1 - expected) / n) + 3e-4
            with self.subTest(params=kwargs, theta=th):
                bad = np.abs(observed - expected) > tol
                self.assertFalse(bad.any(), "bins %s: observed %s expected %s" % (
                    np.nonzero(bad)[0], observed[bad], expected[bad]))
                self.assertLess(abs(s["valid"].mean() - expected.sum()), 5 * math.sqrt(0.25 / n) + 1e-3)
                self.assertLessEqual(expected.sum(), 1.0 + 1e-3)


class YarnBSDFBroadcasting(unittest.TestCase):
    def setUp(self):
        self.b = knitshade.YarnBSDF(reflect_colors=[[1, 0, 0], [0, 0, 1]])
        rng = np.random.default_rng(1)
        self.wo = random_dirs(rng, 7)
        self.wi = random_dirs(rng, 7)

    def test_shapes_broadcast(self):
        b, wo, wi = self.b, self.wo, self.wi
        self.assertEqual(b.eval(wo, wi).shape, (7, 3))
        self.assertEqual(b.pdf(wo, wi).shape, (7,))
        self.assertEqual(b.eval([0, 0, 1], [0, 0, 1]).shape, (1, 3))
        self.assertEqual(b.lobe_probabilities(wo).shape, (7, 4))
        # a single direction is used for every row
        one = b.eval(wo[2], wi)
        np.testing.assert_array_equal(one, b.eval(np.tile(wo[2], (7, 1)), wi))
        np.testing.assert_array_equal(b.pdf(wo, wi[3]), b.pdf(wo, np.tile(wi[3], (7, 1))))
        s = b.sample(wo[0], np.full((5, 3), 0.3))
        self.assertEqual(s["wi"].shape, (5, 3))
        self.assertTrue(np.all(s["wi"] == s["wi"][0]))
        # per-row point arguments
        colors = np.array([0, 1, 0, 1, 0, 1, 0])
        per_row = b.eval_lobe("body_reflection", wo, np.abs(wi) * np.sign(wo), color=colors)
        fixed0 = b.eval_lobe("body_reflection", wo, np.abs(wi) * np.sign(wo), color=0)
        fixed1 = b.eval_lobe("body_reflection", wo, np.abs(wi) * np.sign(wo), color=1)
        np.testing.assert_array_equal(per_row[colors == 0], fixed0[colors == 0])
        np.testing.assert_array_equal(per_row[colors == 1], fixed1[colors == 1])
        self.assertTrue(np.all(fixed0[:, 0] > 0) and np.all(fixed0[:, 1:] == 0), "colour 0 is red")
        self.assertTrue(np.all(fixed1[:, 2] > 0) and np.all(fixed1[:, :2] == 0), "colour 1 is blue")
        layered = b.eval(wo, wi, layers=[1, 2, 3, 4, 5, 6, 7], shadow=np.linspace(0, 1, 7), p_delta=0.1)
        self.assertEqual(layered.shape, (7, 3))
        # lists work like arrays
        np.testing.assert_array_equal(b.eval(wo.tolist(), wi.tolist()), b.eval(wo, wi))

    def test_more_layers_attenuate_transmission_only(self):
        b = knitshade.YarnBSDF(optical_depth=2.0)
        wo = direction(20)
        wt = -direction(40, azimuth=2.0)
        wr = direction(40, azimuth=2.0)
        t1, t2 = b.eval(wo, wt, layers=1)[0, 0], b.eval(wo, wt, layers=2)[0, 0]
        self.assertLess(t2, t1)
        self.assertEqual(b.eval(wo, wr, layers=1)[0, 0], b.eval(wo, wr, layers=2)[0, 0])

    def test_errors_name_the_argument_row_and_value(self):
        b, wo, wi = self.b, self.wo, self.wi
        bad_wi = wi.copy()
        bad_wi[2] *= 1.1
        cases = [
            (lambda: b.eval(wo, bad_wi), ValueError, "wi[2] must be a unit vector"),
            (lambda: b.eval([1.0, 1.0, 0.0], wi), ValueError, "wo must be a unit vector"),
            (lambda: b.pdf(wo, np.array([[0, 0, np.nan]])), ValueError, "wi[0] must be finite, got nan"),
            (lambda: b.eval(wo, wi[:3]), ValueError, "wi has 3 rows but wo has 7"),
            (lambda: b.eval(wo[:, :2], wi), ValueError, "wo must have shape (3,) or (N, 3), got (7, 2)"),
            (lambda: b.eval(np.zeros((2, 2, 3)), wi), ValueError, "wo must have shape (3,) or (N, 3)"),
            (lambda: b.sample(wo, [[0.5, 0.5, 1.0]] * 7), ValueError, "u[0, 2] = 1: must be in [0, 1)"),
            (lambda: b.sample(wo, [0.5, -0.1, 0.5]), ValueError, "u[1] = -0.1: must be in [0, 1)"),
            (lambda: b.eval(wo, wi, color=2), ValueError, "color = 2: must be a colour index in [0, 2)"),
            (lambda: b.eval(wo, wi, color=[0, 1, 0, 1, 0, 1, 5]), ValueError, "color[6] = 5"),
            (lambda: b.eval(wo, wi, color=0.5), ValueError, "color = 0.5: must be an integer"),
            (lambda: b.eval(wo, wi, layers=0), ValueError, "layers = 0: must be >= 1"),
            (lambda: b.eval(wo, wi, shadow=1.5), ValueError, "shadow = 1.5: must be finite and in [0, 1]"),
            (lambda: b.pdf(wo, wi, p_delta=-0.1), ValueError, "p_delta = -0.1"),
            (lambda: b.eval(wo, wi, p_delta=[0.1, 0.2]), ValueError, "p_delta has 2 rows but wo has 7"),
            (lambda: b.eval_lobe("diffuse", wo, wi), ValueError, "lobe = 'diffuse': must be"),
            (lambda: b.eval_lobe(2, wo, wi), TypeError, "lobe must be a str or a knitshade.Lobe"),
            (lambda: b.eval("up", wi), TypeError, "wo must be a number or an array of numbers"),
        ]
        for call, error, message in cases:
            with self.subTest(message=message):
                with self.assertRaises(error) as cm:
                    call()
                self.assertIn(message, str(cm.exception))

    def test_u_just_below_one_is_accepted(self):
        # 1 - 1e-12 rounds to 1.0f in float32; the binding keeps it below 1.
        s = self.b.sample(self.wo, np.full((7, 3), 1 - 1e-12))
        self.assertEqual(s["wi"].shape, (7, 3))


def ply_disc_visibility(n_plies, a, psi, rays=4096):
    """Cosine-weighted 2D visibility of the point on ply 0's boundary on the
    radial line at angle psi, over the half-plane above its normal, against
    the other plies (discs of radius a on a ring of radius 1 - a), by ray
    casting. Also returns the tilt of ply 0's normal from the radial line."""
    c = 1.0 - a
    rho = c * math.cos(psi) + math.sqrt(max(a * a - (c * math.sin(psi)) ** 2, 0.0))
    p = np.array([rho * math.cos(psi), rho * math.sin(psi)])
    normal = (p - np.array([c, 0.0])) / a
    theta = math.atan2(normal[1], normal[0])
    # directions at angle x from the normal, cosine weighted: sample sin(x) uniformly
    s = (np.arange(rays) + 0.5) / rays * 2 - 1
    ang = theta + np.arcsin(s)
    d = np.stack([np.cos(ang), np.sin(ang)], 1)
    blocked = np.zeros(rays, bool)
    for k in range(1, n_plies):
        ck = c * np.array([math.cos(TWO_PI * k / n_plies), math.sin(TWO_PI * k / n_plies)])
        m = ck - p
        t = d @ m
        dist2 = m @ m - t * t
        blocked |= (t > 0) & (dist2 < a * a)
    delta = (theta - psi + math.pi) % TWO_PI - math.pi
    return 1.0 - blocked.mean(), delta


class PlyProfileTest(unittest.TestCase):
    def test_defaults_and_packed_radius(self):
        p = knitshade.PlyProfile()
        self.assertEqual((p.ply_count, p.fiber_count), (3, 40))
        self.assertAlmostEqual(p.ply_radius, math.sin(math.pi / 3) / (1 + math.sin(math.pi / 3)), places=6)
        self.assertAlmostEqual(p.ply_twist, 0.5, places=6)
        self.assertAlmostEqual(p.fiber_twist, -0.35, places=6)
        self.assertAlmostEqual(p.yarn_radius, 0.75, places=6)
        # without ply_radius, the plies are packed for the count asked for
        self.assertAlmostEqual(knitshade.PlyProfile(ply_count=5).ply_radius, knitshade.PlyProfile.packed_radius(5),
                               places=6)
        self.assertEqual(knitshade.PlyProfile.packed_radius(1), 1.0)
        again = pickle.loads(pickle.dumps(knitshade.PlyProfile(ply_count=4, fiber_twist=0.2)))
        self.assertEqual(again.params(), knitshade.PlyProfile(ply_count=4, fiber_twist=0.2).params())

    def test_table_storage(self):
        p = knitshade.PlyProfile()
        self.assertEqual(knitshade.PlyProfile.table_bytes, 3072)
        self.assertEqual(p.table_bytes, 3072)
        t = p.table
        self.assertEqual((t.shape, t.dtype), ((3, 256), np.float32))
        self.assertEqual(t.nbytes, p.table_bytes)
        self.assertTrue(np.all((t[0] >= 0) & (t[0] <= 1)) and np.all((t[2] >= 0) & (t[2] <= 1)))
        np.testing.assert_allclose(t[0], t[0][::-1], atol=1e-5)  # the ply shadow is symmetric
        np.testing.assert_allclose(t[1], -t[1][::-1], atol=1e-5)  # the tilt antisymmetric

    def test_lookup_matches_procedural(self):
        rng = np.random.default_rng(7)
        phi = rng.uniform(-10, 10, 50000)
        s = rng.uniform(-50, 50, 50000)
        for kwargs in (dict(ply_count=2), {}, dict(ply_count=4), dict(ply_count=5, fiber_count=100),
                       dict(ply_twist=-1.2, fiber_twist=1.0, yarn_radius=2.0)):
            p = knitshade.PlyProfile(**kwargs)
            a, b = p.lookup(phi, s), p.procedural(phi, s)
            with self.subTest(params=kwargs):
                for key in ("shadow", "ply_shadow", "fiber_shadow"):
                    self.assertEqual(a[key].shape, (50000,))
                err = np.abs(a["shadow"] - b["shadow"])
                # packed plies: docs/bsdf.md measures max 0.0043, mean 6e-5
                self.assertLess(err.max(), 0.01)
                self.assertLess(err.mean(), 2e-4)
                np.testing.assert_allclose(a["shadow"], a["ply_shadow"] * a["fiber_shadow"], atol=1e-6)
                # normals agree except exactly at a groove, where the two plies' tilts meet
                ang = np.arccos(np.clip(np.sum(a["normal"] * b["normal"], 1), -1, 1))
                self.assertLess(np.quantile(ang, 0.9999), 2e-3)

    def test_frame_is_orthonormal(self):
        rng = np.random.default_rng(3)
        r = knitshade.PlyProfile(ply_count=4).lookup(rng.uniform(-5, 5, 1000), rng.uniform(0, 30, 1000))
        n, t, b = r["normal"], r["tangent"], r["bitangent"]
        for v in (n, t, b):
            np.testing.assert_allclose(np.linalg.norm(v, axis=1), 1, atol=1e-5)
        np.testing.assert_allclose(np.sum(n * t, 1), 0, atol=1e-5)
        np.testing.assert_allclose(np.cross(n, t), b, atol=1e-5)
        self.assertTrue(np.all(n[:, 0] == 0), "the normal tilts about the yarn axis")

    def test_ply_shadow_and_tilt_match_a_ray_cast_of_the_plies(self):
        # No fibres, no twist: at s = 0 the ply phase is phi.
        for n_plies in (2, 3, 5):
            p = knitshade.PlyProfile(ply_count=n_plies, fiber_count=0, ply_twist=0.0)
            a = p.ply_radius
            psis = np.linspace(-0.98, 0.98, 15) * math.pi / n_plies
            r = p.procedural(psis, 0.0)
            for i, psi in enumerate(psis):
                vis, delta = ply_disc_visibility(n_plies, a, psi)
                with self.subTest(plies=n_plies, psi=psi):
                    self.assertLess(abs(r["ply_shadow"][i] - vis), 2e-3)
                    self.assertLess(abs(r["normal"][i, 1] - math.sin(delta)), 1e-4)
            # crest fully visible; groove between touching plies dark
            self.assertAlmostEqual(float(p.lookup(0.0, 0.0)["shadow"][0]), 1.0, places=5)
            groove = p.procedural(math.pi / n_plies * (1 - 1e-4), 0.0)["ply_shadow"][0]
            self.assertLess(groove, 0.03)

    def test_plies_turn_with_the_twist(self):
        p = knitshade.PlyProfile(fiber_count=0)
        rate = p.kernel_params["ply_rate"]
        self.assertAlmostEqual(rate, math.tan(0.5) / 0.75, places=5)
        phi = np.linspace(-3, 3, 101)
        a = p.procedural(phi, 0.0)
        b = p.procedural(phi + rate * 2.0, 2.0)
        c = p.procedural(phi + TWO_PI / 3, 0.0)
        np.testing.assert_allclose(a["shadow"], b["shadow"], atol=2e-4)
        np.testing.assert_allclose(a["shadow"], c["shadow"], atol=2e-4)

    def test_single_smooth_ply(self):
        r = knitshade.PlyProfile(ply_count=1, fiber_count=0).lookup(np.linspace(-3, 3, 50), 1.0)
        np.testing.assert_array_equal(r["shadow"], 1.0)
        np.testing.assert_allclose(r["normal"], np.tile([0, 0, 1.0], (50, 1)), atol=1e-7)

    def test_errors(self):
        cases = [
            (dict(ply_count=0), "PlyParams.ply_count = 0: must be in [1, 16]"),
            (dict(ply_radius=1.0), "PlyParams.ply_radius = 1: must be finite and in (0, 1)"),
            (dict(ply_twist=2.0), "PlyParams.ply_twist = 2"),
            (dict(fiber_count=-1), "PlyParams.fiber_count = -1"),
            (dict(yarn_radius=0.0), "PlyParams.yarn_radius = 0"),
        ]
        for kwargs, message in cases:
            with self.subTest(kwargs=kwargs):
                with self.assertRaises(ValueError) as cm:
                    knitshade.PlyProfile(**kwargs)
                self.assertIn(message, str(cm.exception))
        p = knitshade.PlyProfile()
        with self.assertRaises(ValueError) as cm:
            p.lookup([0.0, float("inf")], 0.0)
        self.assertIn("phi[1] must be finite", str(cm.exception))
        with self.assertRaises(ValueError) as cm:
            p.procedural(np.zeros(3), np.zeros(4))
        self.assertIn("s has 4 rows but phi has 3", str(cm.exception))


def seed_pattern():
    return knitshade.Pattern.from_rows([[0, 1], [1, 0]])


def random_view(rng, n, max_theta=1.3):
    th = rng.uniform(0, max_theta, n)
    ph = rng.uniform(0, TWO_PI, n)
    return np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], 1)


class KnitMaterialNearField(unittest.TestCase):
    def setUp(self):
        self.stitch = knitshade.StitchParams()
        self.surf = knitshade.KnitSurface(seed_pattern(), self.stitch)
        self.rng = np.random.default_rng(12)

    def material(self, **kwargs):
        kwargs.setdefault("uv_scale", 1.0)
        return knitshade.KnitMaterial(seed_pattern(), self.stitch, **kwargs)

    def test_flat_base_agrees_with_capm(self):
        m = self.material(ply_detail=False)
        n = 1500
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        wi = random_view(self.rng, n)
        sh = m.shade(u, v, -wi)
        c = self.surf.capm(u, v, wi)
        np.testing.assert_array_equal(sh["pass_through"], ~c["hit"])
        self.assertTrue(c["hit"].any() and (~c["hit"]).any())
        self.assertFalse(sh["from_back"].any())
        h = c["hit"]
        pos = np.stack([u, v, np.full(n, m.shell_top)], 1) + sh["offset"]
        np.testing.assert_allclose(pos[h], c["position"][h], atol=1e-4)
        # (the same kernel march; float rounding of the start moves a few
        # entry points along the tube by ~1e-4, turning the normal by ~1e-3)
        np.testing.assert_allclose(sh["sn"][h], unit(c["normal"][h]), atol=2e-3)
        self.assertLess(np.mean(np.abs(sh["sn"][h] - unit(c["normal"][h]))), 1e-5)
        # With self-shadowing (the default) the yarns under the hit are in the
        # traced path: one layer for the attenuation; without, the count.
        np.testing.assert_array_equal(sh["layers"][h], 1)
        self.assertTrue((c["layers"][h] > 1).any())
        sh_count = self.material(ply_detail=False, self_shadowing=False).shade(u, v, -wi)
        np.testing.assert_array_equal(sh_count["layers"][h], c["layers"][h])
        np.testing.assert_array_equal(sh["steps"], c["steps"])
        np.testing.assert_array_equal(sh["color"][h], c["color"][h])
        # the world shading frame is orthonormal and faces the viewer
        st, sb, sn = sh["st"][h], sh["sb"][h], sh["sn"][h]
        np.testing.assert_allclose(np.cross(sn, st), sb, atol=1e-5)
        np.testing.assert_allclose(np.sum(st * sn, 1), 0, atol=1e-5)
        self.assertTrue(np.all(np.sum(sn * wi[h], 1) > -0.05))
        # near field: base roughness and palette colour, no pass-through probability
        np.testing.assert_allclose(sh["alpha"][h], np.tile([0.15, 0.45, 0.30, 0.60], (h.sum(), 1)), rtol=1e-6)
        np.testing.assert_allclose(sh["kd_r"][h], 0.8, rtol=1e-6)
        np.testing.assert_array_equal(sh["p_delta"][h], 0.0)
        np.testing.assert_array_equal(sh["shadow"][h], 1.0)
        # rows without a hit have no shading point
        self.assertTrue(np.all(np.isnan(sh["sn"][~h])) and np.all(sh["color"][~h] == -1))
        np.testing.assert_array_equal(sh["p_delta"][~h], 1.0)
        np.testing.assert_array_equal(m.transmittance(u, v, -wi), (~h).astype(float))

    def test_ply_detail_perturbs_the_frame_not_the_hit(self):
        plain, plied = self.material(ply_detail=False), self.material(ply_detail=True)
        n = 800
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        d = -random_view(self.rng, n)
        a, b = plain.shade(u, v, d), plied.shade(u, v, d)
        np.testing.assert_array_equal(a["pass_through"], b["pass_through"])
        h = ~a["pass_through"]
        np.testing.assert_allclose(a["offset"][h], b["offset"][h], atol=1e-6)
        g = b["shadow"][h]
        self.assertTrue(np.all((g >= 0) & (g <= 1)) and g.min() < 0.5)
        tilt = np.degrees(np.arccos(np.clip(np.sum(a["sn"][h] * b["sn"][h], 1), -1, 1)))
        self.assertGreater(tilt.max(), 10.0)
        np.testing.assert_allclose(np.cross(b["sn"][h], b["st"][h]), b["sb"][h], atol=1e-5)

    def test_no_parallax_uses_the_height_at_the_hit(self):
        m = self.material(capm=False, ply_detail=False)
        n = 500
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        sh = m.shade(u, v, unit([0.6, 0.1, -0.5]))
        q = self.surf.query(u, v)
        np.testing.assert_array_equal(sh["pass_through"], ~q["hit"])
        h = q["hit"]
        np.testing.assert_allclose(sh["offset"][h, :2], 0, atol=1e-5)
        np.testing.assert_allclose(sh["offset"][h, 2], q["z"][h] - m.shell_top, atol=1e-4)
        np.testing.assert_array_equal(sh["steps"], 1)

    def test_world_scale_and_frame(self):
        m = self.material(ply_detail=False)
        n = 300
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        wi = random_view(self.rng, n, 1.0)
        base = m.shade(u, v, -wi)
        h = ~base["pass_through"]
        # pattern_per_world scales world offsets only
        scaled = m.shade(u, v, -wi, pattern_per_world=4.0)
        np.testing.assert_array_equal(scaled["pass_through"], base["pass_through"])
        np.testing.assert_allclose(scaled["offset"][h], base["offset"][h] / 4.0, atol=1e-6)
        # a rotated base frame rotates every world output
        c, s = math.cos(0.7), math.sin(0.7)
        R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        rot = m.shade(u, v, -wi @ R.T, t=R[:, 0], b=R[:, 1], n=R[:, 2])
        np.testing.assert_array_equal(rot["pass_through"], base["pass_through"])
        for key in ("st", "sb", "sn", "offset"):
            np.testing.assert_allclose(rot[key][h], base[key][h] @ R.T, atol=2e-3, err_msg=key)
            self.assertLess(np.mean(np.abs(rot[key][h] - base[key][h] @ R.T)), 2e-5, key)

    def test_rays_from_behind(self):
        m = self.material(ply_detail=False)
        n = 800
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        d = random_view(self.rng, n, 1.2)  # travelling up: the viewer is behind the fabric
        sh = m.shade(u, v, d)
        self.assertTrue(sh["from_back"].all())
        h = ~sh["pass_through"]
        self.assertGreater(h.mean(), 0.6)
        self.assertTrue(np.all(np.sum(sh["sn"][h] * d[h], 1) < 0.05), "the hit faces the incoming ray")
        self.assertTrue(np.all(sh["offset"][h, 2] < 0))

    def test_curved_base_follows_the_frame_provider(self):
        m = self.material(ply_detail=False)
        cyl = knitshade.CylinderFrame(15.0)
        n = 400
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        wi = np.array([math.sin(math.radians(88)), 0.0, math.cos(math.radians(88))])
        c = self.surf.capm(u, v, wi, frame=cyl)
        T = np.stack([np.cos(u / 15), 0 * u, -np.sin(u / 15)], 1)
        B = np.tile([0.0, 1.0, 0.0], (n, 1))
        N = np.stack([np.sin(u / 15), 0 * u, np.cos(u / 15)], 1)
        ray = -(wi[0] * T + wi[1] * B + wi[2] * N)
        implicit = m.shade(u, v, ray, frame=cyl)  # t, b, n from the frame provider
        explicit = m.shade(u, v, ray, t=T, b=B, n=N, frame=cyl)
        by_curvature = m.shade(u, v, ray, t=T, b=B, n=N, kx=1 / 15.0)
        for sh in (implicit, explicit, by_curvature):
            np.testing.assert_array_equal(sh["pass_through"], ~c["hit"])
        flat = m.shade(u, v, ray, t=T, b=B, n=N)
        self.assertLess((~implicit["pass_through"]).sum(), (~flat["pass_through"]).sum(),
                        "grazing rays bend away from the cylinder: fewer hits than flat")

    def test_colours_come_from_the_palette(self):
        stripes = knitshade.Pattern.from_rows([[0], [0]], colors=[[0], [1]])
        m = knitshade.KnitMaterial(stripes, uv_scale=1.0,
                                   bsdf=dict(reflect_colors=[[1, 0, 0], [0, 0, 1]],
                                             transmit_colors=[[0.5, 0, 0], [0, 0, 0.5]]))
        n = 400
        sh = m.shade(self.rng.uniform(0, 30, n), self.rng.uniform(0, 30, n), [0, 0, -1.0])
        h = ~sh["pass_through"]
        self.assertEqual(set(np.unique(sh["color"][h])), {0, 1})
        palette_r = np.array([[1, 0, 0], [0, 0, 1]])
        np.testing.assert_array_equal(sh["kd_r"][h], palette_r[sh["color"][h]])
        np.testing.assert_array_equal(sh["kd_t"][h], 0.5 * palette_r[sh["color"][h]])


class KnitMaterialMultiScale(unittest.TestCase):
    def setUp(self):
        self.stitch = knitshade.StitchParams()
        self.surf = knitshade.KnitSurface(seed_pattern(), self.stitch)
        # The class table for whole cells only (table_min_cells=1): below a
        # cell, the near field (test_sub_cells_come_from_the_table has the
        # default's sub-cells).
        self.m = knitshade.KnitMaterial(seed_pattern(), self.stitch, mode="multi_scale", uv_scale=1.0,
                                        table_min_cells=1.0)
        # The marched aggregate also below a stitch cell (by default those
        # footprints are shaded as the near field).
        self.agg = knitshade.KnitMaterial(seed_pattern(), self.stitch, mode="multi_scale", uv_scale=1.0,
                                          table_bsdf=False,
                                          near_field_below_cell=False, table_min_cells=1.0)
        self.rng = np.random.default_rng(21)

    def test_footprints_below_a_cell_are_the_near_field(self):
        # A footprint below a stitch cell in either direction (the cell is
        # 2 pi x (h + 0.5) pattern units here) is shaded as the near field
        # at the hit: the same values as the near-field material, bit for
        # bit, whatever the shift. A cell or more in both: the aggregate.
        self.assertTrue(self.m.near_field_below_cell)
        self.assertFalse(self.agg.near_field_below_cell)
        near = knitshade.KnitMaterial(seed_pattern(), self.stitch, uv_scale=1.0)
        n = 300
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        d = -random_view(self.rng, n, 1.2)
        nf = near.shade(u, v, d)
        for fp in ([0.5, 0.1, -0.1, 0.5], [5.0, 0.0, 0.0, 4.0], [30.0, 0.0, 0.0, 3.0], [3.0, 0.0, 0.0, 30.0]):
            with self.subTest(footprint=fp):
                sh = self.m.shade(u, v, d, footprint=fp, shift=self.rng.random((n, 2)))
                for key in nf:
                    np.testing.assert_array_equal(sh[key], nf[key], err_msg=key)
                np.testing.assert_array_equal(self.m.transmittance(u, v, d, footprint=fp), nf["p_delta"])
                ag = self.agg.shade(u, v, d, footprint=fp, shift=[0.3, 0.7])
                self.assertFalse(np.array_equal(ag["sn"], nf["sn"], equal_nan=True))
        big = self.m.shade(u, v, d, footprint=[7.0, 0.0, 0.0, 5.0], shift=[0.3, 0.7])
        self.assertTrue(np.all(big["steps"] == 0), "a cell or more in both directions: the class table")

    def test_table_bsdf_is_the_default_and_can_be_turned_off(self):
        # The class table's footprints are shaded with its tabulated BSDF
        # (docs/multiscale.md): no widened lobes are reported then; with
        # table_bsdf=False the mean normal's LEAN-widened lobes are.
        m = knitshade.KnitMaterial(seed_pattern(), self.stitch, mode="multi_scale", uv_scale=1.0)
        lean = knitshade.KnitMaterial(seed_pattern(), self.stitch, mode="multi_scale", uv_scale=1.0,
                                      table_bsdf=False)
        self.assertTrue(m.table_bsdf)
        self.assertFalse(lean.table_bsdf)
        self.assertGreater(m.state_bytes, lean.state_bytes + 2 * 144 * 144 * 8 - 1)
        n = 200
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        d = np.tile(-direction(30), (n, 1))
        fp = [12.0, 0.0, 0.0, 10.0]
        a = m.shade(u, v, d, footprint=fp, shift=[0.3, 0.7])
        b = lean.shade(u, v, d, footprint=fp, shift=[0.3, 0.7])
        np.testing.assert_array_equal(a["p_delta"], b["p_delta"])  # the same geometry
        h = ~b["pass_through"]
        self.assertTrue(h.any())
        # widened by the slopes' spread (the tabulated shading reports the yarn's own lobes)
        self.assertGreater(np.mean(b["alpha"][h, 0] * b["alpha"][h, 1]), 1.5 * 0.15 * 0.45)
        np.testing.assert_allclose(a["alpha"][h, 0] * a["alpha"][h, 1], 0.15 * 0.45, rtol=1e-5)
        with self.assertRaises(TypeError):
            knitshade.KnitMaterial(seed_pattern(), self.stitch, mode="multi_scale", table_bsdf="yes")
        # The walk folded into the table (one colour index) is the default;
        # table_fold=False keeps the table of single scattering, at the same
        # size but for the folded table's sampling values: per view node and
        # entry (the seed stitch's two classes), 16 rows as floats and 144
        # nodes as bfloat16.
        walk = knitshade.KnitMaterial(seed_pattern(), self.stitch, mode="multi_scale", uv_scale=1.0,
                                      table_fold=False)
        self.assertTrue(m.table_fold)
        self.assertFalse(walk.table_fold)
        self.assertEqual(m.state_bytes, walk.state_bytes + 144 * 2 * (16 * 4 + 144 * 2))
        with self.assertRaises(TypeError):
            knitshade.KnitMaterial(seed_pattern(), self.stitch, mode="multi_scale", table_fold="no")

    def test_sub_cells_come_from_the_table(self):
        # With table_min_cells=0.5 a footprint of half a cell to a cell
        # comes from the class table's sub-cells: no march, and not the
        # near field; below half a cell, the near field.
        m = knitshade.KnitMaterial(seed_pattern(), self.stitch, mode="multi_scale", uv_scale=1.0,
                                   table_min_cells=0.5)
        self.assertAlmostEqual(m.table_min_cells, 0.5)
        near = knitshade.KnitMaterial(seed_pattern(), self.stitch, uv_scale=1.0)
        n = 300
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        d = -random_view(self.rng, n, 1.2)
        nf = near.shade(u, v, d)
        sub = m.shade(u, v, d, footprint=[5.0, 0.0, 0.0, 4.0])  # 0.80 x 0.89 cells
        self.assertTrue(np.all(sub["steps"] == 0))
        self.assertFalse(np.array_equal(sub["sn"], nf["sn"], equal_nan=True))
        pd = m.transmittance(u, v, d, footprint=[5.0, 0.0, 0.0, 4.0])
        self.assertTrue(np.all((pd >= 0) & (pd <= 1)))
        self.assertGreater(np.ptp(pd), 0.05)  # the sub-cells differ from place to place
        small = m.shade(u, v, d, footprint=[2.0, 0.0, 0.0, 1.5])  # 0.32 x 0.33 cells: the near field
        for key in nf:
            np.testing.assert_array_equal(small[key], nf[key], err_msg=key)
        # table_min_cells=0.25, the sub-cells' own size and the default:
        # that footprint from the table too.
        quarter = knitshade.KnitMaterial(seed_pattern(), self.stitch, mode="multi_scale", uv_scale=1.0)
        self.assertAlmostEqual(quarter.table_min_cells, 0.25)
        self.assertTrue(np.all(quarter.shade(u, v, d, footprint=[2.0, 0.0, 0.0, 1.5])["steps"] == 0))
        self.assertFalse(np.array_equal(quarter.shade(u, v, d, footprint=[2.0, 0.0, 0.0, 1.5])["sn"],
                                        nf["sn"], equal_nan=True))
        for bad in (0.2, 1.5, float("nan")):
            with self.assertRaisesRegex(ValueError, "table_min_cells"):
                knitshade.KnitMaterial(seed_pattern(), mode="multi_scale", table_min_cells=bad)

    def test_footprint_offset_moves_the_footprint_not_the_point(self):
        # footprint_offset centres a multi-scale footprint away from (u, v):
        # its aggregate is the one of a footprint centred there (compared
        # with the material's own result at the moved point), and a hit
        # shaded as the near field keeps (u, v).
        m = knitshade.KnitMaterial(seed_pattern(), self.stitch, mode="multi_scale", uv_scale=1.0)
        n = 200
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        d = -random_view(self.rng, n, 1.2)
        fp = np.array([5.0, 0.4, -0.3, 4.0])  # 0.8 x 0.9 cells: the sub-cells
        j = self.rng.uniform(-0.5, 0.5, (n, 2))
        off = -(j[:, :1] * fp[[0, 1]] + j[:, 1:] * fp[[2, 3]])
        moved = m.shade(u, v, d, footprint=fp, footprint_offset=off)
        there = m.shade(u + off[:, 0], v + off[:, 1], d, footprint=fp)
        np.testing.assert_allclose(moved["p_delta"], there["p_delta"], rtol=0, atol=1e-6)
        np.testing.assert_allclose(m.transmittance(u, v, d, footprint=fp, footprint_offset=off),
                                   there["p_delta"], rtol=0, atol=1e-6)
        # (the offset is not a no-op: the footprints differ)
        self.assertGreater(np.max(np.abs(moved["p_delta"] - m.shade(u, v, d, footprint=fp)["p_delta"])), 0.01)
        small = [1.0, 0.0, 0.0, 0.8]  # below a quarter cell, the near field: the offset changes nothing
        a = m.shade(u, v, d, footprint=small, footprint_offset=[-0.5, 0.3])
        b = m.shade(u, v, d, footprint=small)
        for key in a:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)
        with self.assertRaisesRegex(ValueError, "footprint_offset needs footprint"):
            m.shade(u, v, d, footprint_offset=[0.1, 0.0])
        with self.assertRaisesRegex(ValueError, r"footprint_offset in row 3 = \(3, 0\): puts \(u, v\) outside"):
            bad = np.zeros((n, 2))
            bad[3] = [3.0, 0.0]
            m.shade(u, v, d, footprint=fp, footprint_offset=bad)
        with self.assertRaisesRegex(ValueError, "footprint_offset"):
            m.shade(u, v, d, footprint=fp, footprint_offset=[float("nan"), 0.0])
        with self.assertRaisesRegex(ValueError, "no area"):
            m.shade(u, v, d, footprint=[0.0, 0.0, 0.0, 0.0], footprint_offset=[0.1, 0.0])
        with self.assertRaisesRegex(ValueError, "footprint_offset has 5 rows but footprint has 3"):
            m.shade(1.0, 2.0, [0.0, 0.0, -1.0], footprint=np.tile(fp, (3, 1)), footprint_offset=np.zeros((5, 2)))

    def test_p_delta_is_a_probability_and_equals_transmittance(self):
        n = 300
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        d = -random_view(self.rng, n, 1.2)
        shift = self.rng.random((n, 2))
        for width in (0.5, 3.0, 20.0):
            fp = [width, 0.3 * width, -0.2 * width, width]
            sh = self.agg.shade(u, v, d, footprint=fp, shift=shift)
            tr = self.agg.transmittance(u, v, d, footprint=fp, shift=shift)
            with self.subTest(width=width):
                self.assertTrue(np.all((sh["p_delta"] >= 0) & (sh["p_delta"] <= 1)))
                np.testing.assert_array_equal(sh["p_delta"], tr)
                fractional = (sh["p_delta"] > 0) & (sh["p_delta"] < 1)
                if width < 1:
                    # a hundredth of a stitch cell: one point, the near-field ray
                    self.assertFalse(fractional.any())
                else:
                    self.assertTrue(fractional.any(), "a footprint over gaps and yarns gives 0 < p_delta < 1")
                np.testing.assert_array_equal(sh["pass_through"], tr == 1)
                h = ~sh["pass_through"]
                # LEAN widening (C = Sigma + diag(alpha^2 / 2), Sigma >= 0) never makes a lobe
                # sharper than the yarn's own roughness along either principal axis (Weyl);
                # alpha[:, 0] is the major axis, along st.
                for lobe, base in ((sh["alpha"][h, :2], (0.15, 0.45)), (sh["alpha"][h, 2:], (0.30, 0.60))):
                    self.assertTrue(np.all(lobe.min(1) >= min(base) * (1 - 1e-5)))
                    self.assertTrue(np.all(lobe.max(1) >= max(base) * (1 - 1e-5)))
                    self.assertTrue(np.all(lobe <= 1.0))
                    np.testing.assert_array_equal(lobe[:, 0], lobe.max(1))

    def test_p_delta_is_the_aggregate_of_the_footprint(self):
        n = 120
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        wi = direction(35)
        sh = self.agg.shade(u, v, -wi, footprint=[2.5, 0.0, 0.0, 2.0], shift=[0.3, 0.7])
        # Below a stitch cell (without near_field_below_cell) the material
        # marches the share of its footprint_points that the footprint's
        # area covers (at least one).
        cell = 2 * math.pi * (self.stitch.h + 0.5)
        self.assertEqual(self.agg.footprint_points, 4)
        points = math.ceil(self.agg.footprint_points * 2.5 * 2.0 / cell)
        self.assertEqual(points, 1)
        many = knitshade.KnitMaterial(seed_pattern(), self.stitch, mode="multi_scale", uv_scale=1.0,
                                      footprint_points=16, near_field_below_cell=False, table_min_cells=1.0)
        self.assertEqual(math.ceil(16 * 2.5 * 2.0 / cell), 3)
        sh16 = many.shade(u, v, -wi, footprint=[2.5, 0.0, 0.0, 2.0], shift=[0.3, 0.7])
        ag16 = self.surf.aggregate(u, v, [2.5, 0.0], [0.0, 2.0], wi, 3, 0.3, 0.7)
        np.testing.assert_array_equal(sh16["p_delta"][~sh16["pass_through"]], ag16["p_delta"][~sh16["pass_through"]])
        ag = self.surf.aggregate(u, v, [2.5, 0.0], [0.0, 2.0], wi, points, 0.3, 0.7)
        np.testing.assert_array_equal(sh["p_delta"][~sh["pass_through"]], ag["p_delta"][~sh["pass_through"]])
        np.testing.assert_array_equal(sh["pass_through"], ag["hits"] == 0)

    def test_footprints_of_cells_use_the_class_table(self):
        # Footprints of a stitch cell or more: the class table (no marching)
        # by default, the marched aggregate with footprint_table=False; the
        # two agree on average.
        marched = knitshade.KnitMaterial(seed_pattern(), self.stitch, mode="multi_scale", uv_scale=1.0,
                                         footprint_table=False)
        n = 400
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        wi = direction(35)
        fp = [20.0, 0.0, 0.0, 18.0]
        t = self.m.shade(u, v, -wi, footprint=fp, shift=[0.3, 0.7])
        m = marched.shade(u, v, -wi, footprint=fp, shift=[0.3, 0.7])
        self.assertTrue(np.all(t["steps"] == 0))
        self.assertTrue(np.all(m["steps"] > 0))
        ag = self.surf.aggregate(u, v, fp[:2], fp[2:], wi, marched.footprint_points, 0.3, 0.7)
        np.testing.assert_array_equal(m["p_delta"], ag["p_delta"])
        # One shift places every footprint's points alike; with random shifts
        # the marched p_delta is unbiased, and the table's should match it.
        m = marched.shade(u, v, -wi, footprint=fp, shift=self.rng.random((n, 2)))
        sigma = m["p_delta"].std() / math.sqrt(n)
        self.assertLess(abs(t["p_delta"].mean() - m["p_delta"].mean()), 4 * sigma + 0.01)

    def test_point_footprint_reduces_to_the_near_field(self):
        near = knitshade.KnitMaterial(seed_pattern(), self.stitch, uv_scale=1.0, ply_detail=False)
        n = 300
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        d = -random_view(self.rng, n, 1.0)
        # (the aggregate's own limit: by default such a footprint is the near
        # field outright, test_footprints_below_a_cell_are_the_near_field)
        far = self.agg.shade(u, v, d, footprint=[1e-5, 0, 0, 1e-5])
        nf = near.shade(u, v, d)
        agree = far["pass_through"] == nf["pass_through"]
        self.assertGreaterEqual(agree.mean(), 0.99)
        h = ~far["pass_through"] & agree
        self.assertTrue(np.all(far["p_delta"][h] == 0))
        np.testing.assert_allclose(far["sn"][h], nf["sn"][h], atol=2e-3)
        # Each specular lobe as a frame-independent roughness tensor in the
        # tangent plane, ax^2 st st^T + ay^2 sb sb^T: multi-scale may turn its
        # axes (major axis first) but must describe the same lobe.
        def tensor(sh, cols):
            st, sb = sh["st"][h], sh["sb"][h]
            ax, ay = sh["alpha"][h, cols[0]], sh["alpha"][h, cols[1]]
            return (ax ** 2)[:, None, None] * np.einsum("ni,nj->nij", st, st) + \
                (ay ** 2)[:, None, None] * np.einsum("ni,nj->nij", sb, sb)
        for cols in ((0, 1), (2, 3)):
            np.testing.assert_allclose(tensor(far, cols), tensor(nf, cols), atol=5e-3, err_msg=str(cols))

    def test_random_shifts_make_p_delta_unbiased(self):
        # Averaged over shading points with random Cranley-Patterson shifts,
        # p_delta estimates the fraction of the fabric a ray passes through,
        # which the near-field query measures point by point.
        n = 3000
        u, v = self.rng.uniform(0, 40, n), self.rng.uniform(0, 40, n)
        miss = 1.0 - self.surf.query(u, v)["hit"].mean()
        sigma_miss = math.sqrt(miss * (1 - miss) / n)
        for width in (2.0, 20.0):  # below one stitch cell and over several (cell-stratified)
            sh = self.agg.shade(u, v, [0.0, 0.0, -1.0], footprint=[width, 0, 0, width],
                                shift=self.rng.random((n, 2)))
            pd = sh["p_delta"]
            with self.subTest(width=width):
                self.assertLess(abs(pd.mean() - miss), 4 * math.hypot(sigma_miss, pd.std() / math.sqrt(n)))

    def test_colours_mix_over_the_footprint(self):
        stripes = knitshade.Pattern.from_rows([[0], [0]], colors=[[0], [1]])
        m = knitshade.KnitMaterial(stripes, mode="multi_scale", uv_scale=1.0,
                                   bsdf=dict(reflect_colors=[[1, 0, 0], [0, 0, 1]]))
        sh = m.shade([50.0, 61.0], [50.0, 47.0], [0, 0, -1.0], footprint=[30, 0, 0, 30], shift=[0.3, 0.7])
        self.assertFalse(sh["pass_through"].any())
        np.testing.assert_allclose(sh["kd_r"][:, 0] + sh["kd_r"][:, 2], 1.0, atol=1e-5)
        self.assertTrue(np.all(np.abs(sh["kd_r"][:, 0] - 0.5) < 0.15))
        self.assertTrue(np.all(sh["kd_r"][:, 1] == 0))


class KnitMaterialInterface(unittest.TestCase):
    def test_properties(self):
        ply = knitshade.PlyProfile(ply_count=4)
        bsdf = knitshade.YarnBSDF(eta=1.4)
        m = knitshade.KnitMaterial(seed_pattern(), knitshade.StitchParams(r=0.6), bsdf=bsdf, ply=ply,
                                   mode="multi_scale", capm=False, ply_detail=False, footprint_points=8,
                                   uv_scale=12.5)
        self.assertEqual(m.mode, "multi_scale")
        self.assertEqual((m.capm, m.ply_detail, m.footprint_points), (False, False, 8))
        self.assertAlmostEqual(m.uv_scale, 12.5)
        self.assertAlmostEqual(m.stitch.r, 0.6, places=6)
        self.assertAlmostEqual(m.bsdf.eta, 1.4, places=6)
        self.assertEqual(m.ply.ply_count, 4)
        self.assertEqual(m.pattern, seed_pattern())
        self.assertAlmostEqual(m.shell_top, 1.0 + 0.6, places=5)
        d = knitshade.KnitMaterial(knitshade.Pattern())
        self.assertEqual((d.mode, d.capm, d.ply_detail, d.footprint_points), ("near_field", True, True, 4))
        self.assertTrue(d.footprint_table)
        self.assertFalse(knitshade.KnitMaterial(knitshade.Pattern(), footprint_table=False).footprint_table)
        self.assertTrue(d.self_shadowing)
        self.assertTrue(d.near_field_below_cell)
        self.assertFalse(knitshade.KnitMaterial(knitshade.Pattern(), near_field_below_cell=False).near_field_below_cell)
        self.assertFalse(knitshade.KnitMaterial(knitshade.Pattern(), self_shadowing=False).self_shadowing)
        self.assertAlmostEqual(d.uv_scale, 40.0)
        # bsdf_model 'cycles' (docs/cycles.md): what Cycles cannot do is off
        self.assertEqual(d.bsdf_model, "exact")
        c = knitshade.KnitMaterial(knitshade.Pattern(), mode="multi_scale", bsdf_model="cycles")
        self.assertEqual(c.bsdf_model, "cycles")
        self.assertEqual((c.footprint_table, c.table_bsdf, c.near_field_below_cell, c.self_shadowing),
                         (False, False, False, False))
        with self.assertRaisesRegex(ValueError, "bsdf_model = 'osl': must be 'exact' or 'cycles'"):
            knitshade.KnitMaterial(knitshade.Pattern(), bsdf_model="osl")
        # bsdf and ply as dicts of keyword arguments
        m2 = knitshade.KnitMaterial(knitshade.Pattern(), bsdf=dict(eta=1.2), ply=dict(ply_count=2))
        self.assertAlmostEqual(m2.bsdf.eta, 1.2, places=6)
        self.assertEqual(m2.ply.ply_count, 2)

    def test_state_bytes(self):
        small = knitshade.KnitMaterial(knitshade.Pattern())
        big = knitshade.KnitMaterial(knitshade.Pattern.from_rows([[0] * 48] * 48))
        self.assertGreater(small.state_bytes, knitshade.PlyProfile.table_bytes)
        self.assertGreaterEqual(big.state_bytes - small.state_bytes, 2 * 4 * (48 * 48 - 1))
        self.assertLess(big.state_bytes, 32 * 1024)

    def test_uv_scale_maps_uv_to_pattern_space(self):
        a = knitshade.KnitMaterial(seed_pattern(), uv_scale=10.0, ply_detail=False)
        b = knitshade.KnitMaterial(seed_pattern(), uv_scale=1.0, ply_detail=False)
        rng = np.random.default_rng(1)
        u, v = rng.uniform(0, 4, 200), rng.uniform(0, 4, 200)
        sa = a.shade(u, v, [0.0, 0.0, -1.0])
        sb = b.shade(10 * u, 10 * v, [0.0, 0.0, -1.0])
        np.testing.assert_array_equal(sa["pass_through"], sb["pass_through"])
        h = ~sa["pass_through"]
        np.testing.assert_allclose(sa["sn"][h], sb["sn"][h], atol=2e-3)
        self.assertLess(np.mean(np.abs(sa["sn"][h] - sb["sn"][h])), 2e-5)

    def test_construction_errors(self):
        two_colours = knitshade.Pattern.from_rows([[0, 1]], colors=[[0, 1]])
        cases = [
            (lambda: knitshade.KnitMaterial(knitshade.Pattern(), mode="far_field"), ValueError,
             "mode = 'far_field': must be 'near_field' or 'multi_scale'"),
            (lambda: knitshade.KnitMaterial(knitshade.Pattern(), uv_scale=-2.0), ValueError,
             "KnitMaterialParams.uv_scale = -2"),
            (lambda: knitshade.KnitMaterial(knitshade.Pattern(), footprint_points=0), ValueError,
             "KnitMaterialParams.footprint_points = 0"),
            (lambda: knitshade.KnitMaterial(knitshade.Pattern(), max_steps=0), ValueError,
             "KnitMaterialParams.capm_options.max_steps = 0"),
            (lambda: knitshade.KnitMaterial(knitshade.Pattern(), max_segment=5000.0), ValueError,
             "KnitMaterialParams.capm_options.max_segment = 5000: must be > 0 and at most 1000"),
            (lambda: knitshade.KnitMaterial(two_colours), ValueError,
             "the pattern uses 2 colour indices but 1 yarn colours are given"),
            (lambda: knitshade.KnitMaterial(knitshade.Pattern(), bsdf=dict(eta=9.0)), ValueError,
             "YarnBsdfParams.eta = 9"),
            (lambda: knitshade.KnitMaterial(knitshade.Pattern(), ply=dict(ply_count=40)), ValueError,
             "PlyParams.ply_count = 40"),
            (lambda: knitshade.KnitMaterial(knitshade.Pattern(), bsdf="wool"), TypeError,
             "bsdf must be a knitshade.YarnBSDF"),
        ]
        for call, error, message in cases:
            with self.subTest(message=message):
                with self.assertRaises(error) as cm:
                    call()
                self.assertIn(message, str(cm.exception))

    def test_shade_errors_name_the_argument(self):
        m = knitshade.KnitMaterial(seed_pattern(), uv_scale=1.0)
        u = np.array([1.0, 2.0, 3.0])
        down = [0.0, 0.0, -1.0]
        cases = [
            (dict(u=[1.0, np.nan, 2.0]), "u[1] must be finite, got nan"),
            (dict(u=[1.0, 4e4, 2.0]), "u[1] = 40000: must be finite and in [-32768, 32768]"),
            (dict(v=np.zeros(2)), "v has 2 rows but u has 3"),
            (dict(ray_dir=[[0, 0, -1.0], [0, 0, -2.0], [0, 0, -1.0]]), "ray_dir[1] must be a unit vector"),
            (dict(ray_dir=[0.0, -1.0]), "ray_dir must have shape (3,) or (N, 3), got (2,)"),
            (dict(t=[1.0, 0, 0]), "t, b and n must be given together"),
            (dict(t=[1.0, 0, 0], b=[0.6, 0.8, 0], n=[0, 0, 1.0]), "must be orthonormal: t . b = 0.6"),
            (dict(pattern_per_world=[1.0, 0.0, 1.0]), "pattern_per_world[1] = 0: must be > 0"),
            (dict(kx=np.inf), "kx must be finite, got inf"),
            (dict(footprint=[1.0, 0, 0]), "footprint must have shape (4,) or (N, 4), got (3,)"),
            (dict(footprint=[1.0, 0, 0, np.nan]), "footprint must be finite, got nan in component 3"),
            (dict(shift=[0.5, 1.0]), "shift[1] = 1: must be in [0, 1)"),
            (dict(shift=[[0.5, 0.5]] * 2), "shift has 2 rows but u has 3"),
        ]
        for override, message in cases:
            args = dict(u=u, v=u, ray_dir=down)
            args.update(override)
            for method in (m.shade, m.transmittance):
                with self.subTest(message=message, method=method.__name__):
                    with self.assertRaises(ValueError) as cm:
                        method(args["u"], args["v"], args["ray_dir"],
                               **{k: val for k, val in args.items() if k not in ("u", "v", "ray_dir")})
                    self.assertIn(message, str(cm.exception))


class TableCacheTest(unittest.TestCase):
    """knitshade.set_table_cache: the second multi-scale material of the same
    pattern and parameters reads its class table from the folder and shades
    as the first, bit for bit; None turns the cache off."""

    def tearDown(self):
        knitshade.set_table_cache(None)

    def test_second_material_reads_the_first_ones_table(self):
        import tempfile
        stockinette = knitshade.Pattern.from_rows([[0]])
        with tempfile.TemporaryDirectory() as tmp:
            self.assertIsNone(knitshade.table_cache())
            knitshade.set_table_cache(pathlib.Path(tmp))
            self.assertEqual(knitshade.table_cache(), tmp)
            first = knitshade.KnitMaterial(stockinette, mode="multi_scale", uv_scale=1.0)
            second = knitshade.KnitMaterial(stockinette, mode="multi_scale", uv_scale=1.0)
            self.assertFalse(first.table_from_cache)
            self.assertTrue(second.table_from_cache)
            self.assertEqual(first.table_cache_note, "")
            # Three entries: the finished tables, their marches and their shadows.
            self.assertEqual(len(list(pathlib.Path(tmp).glob("*.knittable"))), 3)
            self.assertLess(second.table_seconds, first.table_seconds)
            # Other colours: finished from the cached marches, not marched again.
            red = knitshade.KnitMaterial(stockinette, mode="multi_scale", uv_scale=1.0,
                                         bsdf={"reflect_colors": [[0.8, 0.1, 0.1]]})
            self.assertFalse(red.table_from_cache)
            self.assertTrue(red.table_marches_from_cache)
            self.assertFalse(second.table_marches_from_cache)
            self.assertLess(red.table_seconds, first.table_seconds)
            # Another roughness: marched from the cached shadows.
            rough = knitshade.KnitMaterial(stockinette, mode="multi_scale", uv_scale=1.0,
                                           bsdf={"roughness_x": 0.5})
            self.assertFalse(rough.table_from_cache)
            self.assertFalse(rough.table_marches_from_cache)
            self.assertTrue(rough.table_shadows_from_cache)
            # Footprints of several cells, from the class table: the same shading.
            rng = np.random.default_rng(5)
            n = 64
            u, v = rng.uniform(0, 30, n), rng.uniform(0, 30, n)
            d = -random_view(rng, n)
            fp = [20.0, 0.0, 0.0, 20.0]
            a = first.shade(u, v, d, footprint=fp, shift=[0.3, 0.7])
            b = second.shade(u, v, d, footprint=fp, shift=[0.3, 0.7])
            self.assertTrue(np.all(a["steps"] == 0), "a cell or more in both directions: the class table")
            for key in a:
                np.testing.assert_array_equal(a[key], b[key], err_msg=key)
            knitshade.set_table_cache(None)
            self.assertIsNone(knitshade.table_cache())
            third = knitshade.KnitMaterial(stockinette, mode="multi_scale", uv_scale=1.0)
            self.assertFalse(third.table_from_cache)

    def test_build_progress_callback(self):
        """knitshade.set_table_build_progress: (done, total) from 0 to total, never
        decreasing, on the constructing thread; nothing for tables from the cache; an
        exception in the callback raised by the constructor."""
        import tempfile
        import threading
        stockinette = knitshade.Pattern.from_rows([[0]])
        calls = []
        me = threading.get_ident()

        def record(done, total):
            calls.append((done, total, threading.get_ident()))

        try:
            with tempfile.TemporaryDirectory() as tmp:
                knitshade.set_table_cache(tmp)
                knitshade.set_table_build_progress(record)
                knitshade.KnitMaterial(stockinette, mode="multi_scale", uv_scale=1.0)
                self.assertGreaterEqual(len(calls), 2)
                total = calls[0][1]
                self.assertEqual(total, 24 + 2 * 144)  # one class: its jobs' units
                self.assertEqual(calls[0][0], 0)
                self.assertEqual(calls[-1][:2], (total, total))
                dones = [c[0] for c in calls]
                self.assertEqual(dones, sorted(dones))
                self.assertTrue(all(c[1] == total and c[2] == me for c in calls))
                calls.clear()
                second = knitshade.KnitMaterial(stockinette, mode="multi_scale", uv_scale=1.0)
                self.assertTrue(second.table_from_cache)
                self.assertEqual(calls, [])

                def fail(done, total):
                    raise RuntimeError("stop at %d of %d" % (done, total))

                knitshade.set_table_build_progress(fail)
                with self.assertRaisesRegex(RuntimeError, "stop at 0 of"):
                    knitshade.KnitMaterial(stockinette, mode="multi_scale", uv_scale=1.0, footprint_points=8,
                                           stitch=knitshade.StitchParams(r=0.6))
                with self.assertRaises(TypeError):
                    knitshade.set_table_build_progress(3)
        finally:
            knitshade.set_table_build_progress(None)
            knitshade.set_table_cache(None)

    def test_bad_arguments(self):
        with self.assertRaises(ValueError):
            knitshade.set_table_cache("")
        with self.assertRaises(ValueError):
            knitshade.set_table_cache("/tmp", max_bytes=0)
        self.assertIsInstance(knitshade.default_table_cache_dir(), str)


if __name__ == "__main__":
    unittest.main()

"""Explicit yarns from the compiled module (issue 54): the one place the
yarn geometry calls native code. The module itself is imported by
native/__init__.py; this file only uses it.

band(pattern, a, h, d, r, tiles_u, samples) gives one vertical repeat of
the pattern (all its rows, `tiles_u` repeats wide) as the library's
explicit_yarns() returns it, with the pattern's period and the yarn shell's
top; the other repeats are the same curves moved by whole periods
(core.yarn_layout.Layout).
"""
from . import AVAILABLE, status
from . import module as _module

# What the panel says when the module is missing.
NEEDS = ("Yarn geometry needs the native module: install the knitshade_blender zip built for this "
         "platform in a Blender whose Python is 3.11 (Blender 3.4 to 5.0)")


def available():
    return AVAILABLE


def why_not():
    """'' when the module is loaded, else a sentence for the panel."""
    return "" if AVAILABLE else "%s (%s)" % (NEEDS, status())


def native_pattern(pattern, source="<pattern>"):
    """The module's Pattern for a core.pattern.Pattern (through its text)."""
    return _module.Pattern.from_text(pattern.to_text(), source)


def stitch(a, h, d, r):
    return _module.StitchParams(a=float(a), h=float(h), d=float(d), r=float(r))


def band(pattern, a, h, d, r, tiles_u, samples, source="<pattern>"):
    """{curves, colors, radius, period (px, py), shell_top, t_step} of one
    vertical repeat, `tiles_u` repeats wide, `samples` points per stitch.
    ValueError with the library's message for parameters it refuses."""
    if not AVAILABLE:
        raise RuntimeError(why_not())
    p = native_pattern(pattern, source)
    sp = stitch(a, h, d, r)
    surf = _module.KnitSurface(p, sp, 1.0)
    y = _module.explicit_yarns(p, sp, int(tiles_u), 1, int(samples))
    return {
        "curves": y["curves"], "colors": y["colors"], "radius": float(y["radius"]),
        "period": tuple(float(x) for x in surf.period), "shell_top": float(surf.shell_top),
        "t_step": float(y["t_step"]),
    }


def period(pattern, a, h, d, r, source="<pattern>"):
    """(px, py, shell_top) of a pattern with these stitch parameters."""
    if not AVAILABLE:
        raise RuntimeError(why_not())
    surf = _module.KnitSurface(native_pattern(pattern, source), stitch(a, h, d, r), 1.0)
    px, py = surf.period
    return float(px), float(py), float(surf.shell_top)


# Lobe albedos of a white yarn, averaged over view directions: the yarn
# material's weights (yarns.yarn_material). What bsdf_cycles.h does per view
# direction for the OSL shader, done once per material here: each lobe of
# the exact yarn BSDF becomes the Blender closure that stands for it, weighted
# by its directional albedo, averaged over the hemisphere of view directions
# (cosine-weighted, 6 Gauss-Legendre angles, 4,000 samples each).
_GAUSS6 = ((0.0337652428984240, 0.0856622461895852), (0.1693953067668677, 0.1803807865240693),
           (0.3806904069584015, 0.2339569672863455), (0.6193095930415985, 0.2339569672863455),
           (0.8306046932331323, 0.1803807865240693), (0.9662347571015760, 0.0856622461895852))


def yarn_weights(roughness=0.15, roughness_across=0.45, ior=1.55, body_energy=0.7, body_reflect=0.6,
                 optical_depth=1.0, ply_detail=True, ply_count=3, ply_twist=28.65, fiber_count=40,
                 fiber_twist=-20.05, r=0.65, samples=4000, seed=1):
    """{spec, body_r, body_t, through, shadow}: the albedos of the yarn
    BSDF's specular reflection, body reflection and body transmission (per
    unit of yarn colour) and of its thin-slab transmission (light through
    the yarn), for a white yarn with the ply detail's mean shadowing,
    averaged over the view directions with weight cos(theta)."""
    if not AVAILABLE:
        raise RuntimeError(why_not())
    import math

    import numpy as np
    m = _module
    shadow = 1.0
    if ply_detail:
        ply = m.PlyProfile(ply_count=int(ply_count), ply_twist=math.radians(ply_twist),
                           fiber_count=int(fiber_count), fiber_twist=math.radians(fiber_twist),
                           yarn_radius=float(r))
        phi, s = np.meshgrid(np.linspace(-math.pi, math.pi, 64, endpoint=False), np.linspace(0.0, 40.0, 64))
        shadow = float(ply.procedural(phi.ravel(), s.ravel())["shadow"].mean())
    bsdf = m.YarnBSDF(roughness_x=float(roughness), roughness_y=float(roughness_across), eta=float(ior),
                      body_energy=float(body_energy), body_reflect=float(body_reflect),
                      optical_depth=float(optical_depth), reflect_colors=[[1.0, 1.0, 1.0]])
    rng = np.random.default_rng(seed)
    lobes = ("specular_reflection", "body_reflection", "body_transmission", "specular_transmission")
    acc = dict.fromkeys(lobes, 0.0)
    wsum = 0.0
    for x, w in _GAUSS6:  # mu = cos(theta) in (0, 1); weight mu
        mu = x
        wo = np.array([math.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu])
        smp = bsdf.sample(wo, rng.random((samples, 3)), shadow=shadow)
        ok = smp["valid"] & ((smp["flags"] & m.BSDF_DELTA) == 0)
        wi = smp["wi"][ok]
        if len(wi) == 0:
            continue
        pdf = bsdf.pdf(wo, wi, shadow=shadow)
        good = pdf > 0
        for lobe in lobes:
            e = bsdf.eval_lobe(lobe, wo, wi[good], shadow=shadow)[:, 0]
            acc[lobe] += w * mu * float((e / pdf[good]).sum() / samples)
        wsum += w * mu
    out = {k: v / wsum for k, v in acc.items()}
    return {"spec": out["specular_reflection"], "body_r": out["body_reflection"],
            "body_t": out["body_transmission"], "through": out["specular_transmission"], "shadow": shadow}

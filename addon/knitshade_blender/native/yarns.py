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

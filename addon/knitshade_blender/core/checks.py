"""Checks of the material's settings that need no native code.

`stitch(a, h, d, r)` refuses what knit::StitchParams::validate refuses
without its clearance search, with the library's words
(native/src/params.cpp): non-finite values, magnitudes above 1000, a <= 0,
h <= 0, d == 0, r <= 0. The one check it cannot make is the yarn clearance
(tubes passing through each other): where the compiled module loads the
add-on asks the library instead (native.check_stitch).

`value(param, v)` refuses a shader setting outside its parameter's range
(core.shader.PARAMS min/max), naming the setting by its label.
"""
import math

STITCH_NAMES = {"a": "loop roundness", "h": "loop height", "d": "loop depth", "r": "yarn radius"}


def _fmt(v):
    return "%.6g" % v


def stitch(a, h, d, r):
    """Raise ValueError with the library's message for (a, h, d, r) it would
    refuse on its basic checks."""
    values = (("a", a), ("h", h), ("d", d), ("r", r))
    for name, v in values:
        v = float(v)
        if not math.isfinite(v):
            raise ValueError("stitch parameter %s must be finite, got %s" % (name, _fmt(v)))
        if abs(v) > 1e3:
            raise ValueError("stitch parameter %s must be at most 1000 in magnitude, got %s"
                             % (name, _fmt(v)))
    if not float(a) > 0:
        raise ValueError("stitch parameter a (loop roundness) must be > 0, got " + _fmt(float(a)))
    if not float(h) > 0:
        raise ValueError("stitch parameter h (loop height) must be > 0, got " + _fmt(float(h)))
    if float(d) == 0:
        raise ValueError("stitch parameter d (loop depth) must be non-zero, got 0")
    if not float(r) > 0:
        raise ValueError("stitch parameter r (yarn radius) must be > 0, got " + _fmt(float(r)))


def value(param, v):
    """Raise ValueError when `v` is not a valid setting of shader parameter
    `param` (a core.shader.ShaderParam); returns the value as the socket
    takes it (float, int, bool or a tuple)."""
    kind = param.kind
    if kind in ("color", "point", "vector"):
        try:
            t = tuple(float(x) for x in v)
        except TypeError:
            raise ValueError("%s must be 3 numbers, got %r" % (param.label, v)) from None
        if len(t) == 4 and kind == "color":
            t = t[:3]
        if len(t) != 3 or not all(math.isfinite(x) for x in t):
            raise ValueError("%s must be 3 finite numbers, got %r" % (param.label, v))
        if kind == "color" and min(t) < 0:
            raise ValueError("%s must not be negative, got %s" % (param.label, ", ".join(_fmt(x) for x in t)))
        return t
    if kind == "bool":
        if isinstance(v, str):
            raise ValueError("%s must be True or False, got %r" % (param.label, v))
        return bool(v)
    if kind == "enum":
        items = param.items or ()
        for ident, label, number in items:
            if v in (ident, number) and not isinstance(v, bool):
                return int(number)
        raise ValueError("%s must be one of %s, got %r"
                         % (param.label, ", ".join("'%s'" % i[0] for i in items), v))
    try:
        x = float(v)
    except (TypeError, ValueError):
        raise ValueError("%s must be a number, got %r" % (param.label, v)) from None
    if not math.isfinite(x):
        raise ValueError("%s must be finite, got %s" % (param.label, _fmt(x)))
    if kind == "int":
        if x != int(x):
            raise ValueError("%s must be a whole number, got %s" % (param.label, _fmt(x)))
        x = int(x)
    lo, hi = param.min, param.max
    if (lo is not None and x < lo) or (hi is not None and x > hi):
        raise ValueError("%s %s is outside %s..%s" % (param.label, _fmt(x), _fmt(lo), _fmt(hi)))
    return x

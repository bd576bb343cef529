"""Checking and writing a Knit Fabric material's settings (bpy glue over
core.checks and the native module).

Every way of changing a setting goes through apply(): the panel's fields
(props.py), the operators and the Python API. It checks all the changes
together (each against its parameter's range; a, h, d, r together with the
library's StitchParams where the native module loads, else with
core.checks.stitch) and writes them only if all pass, so a refused change
leaves every setting as it was.
"""
import re

from . import native, nodes
from .core import checks
from .core import shader as kshader

_SNAKE1 = re.compile(r"([A-Z]+)([A-Z][a-z])")
_SNAKE2 = re.compile(r"([a-z0-9])([A-Z])")


def snake(name):
    """The Python name of a shader parameter: UVScale -> uv_scale, A -> a,
    RoughnessAcross -> roughness_across, CAPM -> capm, Yarn0 -> yarn0."""
    return _SNAKE2.sub(r"\1_\2", _SNAKE1.sub(r"\1_\2", name)).lower()


def names():
    """{python name: shader parameter name} for every setting."""
    return {snake(p.name): p.name for p in nodes.params()}


STITCH = ("A", "H", "D", "R")


def resolve(changes):
    """{shader parameter name: value} from keyword arguments that use either
    the Python names (uv_scale, a, yarn0, ...) or the shader's (UVScale, A,
    Yarn0, ...); `colours`/`colors` (a list of up to 8 colours) sets
    Yarn0, Yarn1, ...; `yarn_weight` is not handled here. KeyError naming
    the unknown ones."""
    by_snake = names()
    shader_names = set(by_snake.values())
    out, unknown = {}, []
    for key, value in changes.items():
        if key in ("colours", "colors"):
            cols = list(value)
            if len(cols) > kshader.PALETTE_SIZE:
                raise ValueError("%d colours given; the palette has %d" % (len(cols), kshader.PALETTE_SIZE))
            for i, c in enumerate(cols):
                out["Yarn%d" % i] = c
        elif key in shader_names:
            out[key] = value
        elif key in by_snake:
            out[by_snake[key]] = value
        else:
            unknown.append(key)
    if unknown:
        raise KeyError("unknown Knit Fabric setting%s %s (known: %s)"
                       % ("s" if len(unknown) > 1 else "", ", ".join(unknown), ", ".join(sorted(by_snake))))
    return out


def check(changes, current):
    """The changes, checked and converted ({name: value}); ValueError with
    the first refusal. a, h, d, r are checked first, together, in the
    library's words (its StitchParams where the native module loads, else
    core.checks.stitch); then every value against its parameter's range.
    `current(name)` gives a setting's value before the change."""
    if any(n in changes for n in STITCH):
        a, h, d, r = (changes[n] if n in changes else current(n) for n in STITCH)
        try:
            a, h, d, r = (float(x) for x in (a, h, d, r))
        except (TypeError, ValueError):
            raise ValueError("a, h, d, r must be numbers, got %r, %r, %r, %r" % (a, h, d, r)) from None
        checks.stitch(a, h, d, r)
        native.check_stitch(a, h, d, r)
    return {name: checks.value(nodes.param(name), value) for name, value in changes.items()}


def apply(material, changes, node=None):
    """Check `changes` ({shader parameter name: value}) against the Knit
    Fabric node of `material` and write them all, or raise ValueError (or
    nodes.KnitError) and write none."""
    node = node or nodes.knit_node(material)
    if node is None:
        raise nodes.KnitError("material '%s' has no Knit Fabric node" % material.name)
    good = check(changes, lambda n: nodes.get_value(node, n))
    for name, value in good.items():
        nodes.set_value(node, name, value)
    return good


def describe(changes):
    """'a = 1.2, r = 3' for a message."""
    parts = []
    for name, value in changes.items():
        if isinstance(value, float):
            value = "%.6g" % value
        elif isinstance(value, tuple):
            value = "(" + ", ".join("%.3g" % v for v in value) + ")"
        parts.append("%s = %s" % (snake(name), value))
    return ", ".join(parts)

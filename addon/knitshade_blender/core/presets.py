"""Presets: the pattern presets (the .knit files of examples/patterns) and the
yarn weights (stitch parameters and a gauge per weight of yarn).

Pattern presets are files, so a new example is a new preset. In the
installed add-on the files are copied to `knitshade_blender/patterns/`
inside the package; in the source tree they are read from
`<repo>/examples/patterns`, found relative to this file.
"""

import math
import os

from .pattern import PatternError, load

__all__ = [
    "YARN_WEIGHTS",
    "load_preset",
    "pattern_presets",
    "patterns_dir",
    "preset_path",
    "rows_per_10cm",
    "uv_scale_for_gauge",
    "yarn_weight",
    "yarn_weight_presets",
]

_HERE = os.path.dirname(os.path.abspath(__file__))
_PACKAGE_PATTERNS = os.path.join(os.path.dirname(_HERE), "patterns")
# core -> knitshade_blender -> addon -> the repository
_SOURCE_PATTERNS = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(_HERE))),
                                "examples", "patterns")
_SUFFIX = ".knit"


def patterns_dir():
    """The folder the pattern presets are read from: the package's
    `patterns/` when the add-on is installed, else the source tree's
    `examples/patterns`."""
    if os.path.isdir(_PACKAGE_PATTERNS):
        return _PACKAGE_PATTERNS
    return _SOURCE_PATTERNS


def _display_name(identifier):
    # "rib_2x2" -> "Rib 2x2", "diamond_blocks_2colour" -> "Diamond blocks 2colour"
    words = identifier.replace("_", " ").replace("-", " ").split()
    text = " ".join(words)
    return text[:1].upper() + text[1:]


def _description(path):
    """The first sentence of the file's opening comment: its first comment
    line, continued over the comment lines after it until the sentence ends
    (the examples wrap sentences over lines). Empty without a comment."""
    words = []
    try:
        with open(path, "rb") as f:
            lines = f.read(64 * 1024).decode("utf-8", "replace").split("\n")
    except OSError:
        return ""
    for line in lines:
        line = line.strip().lstrip("\ufeff")
        if not line.startswith("#"):
            if words or line:
                break  # the comment block is over (or the file opens with cells)
            continue
        text = line.lstrip("#").strip()
        if not text:
            if words:
                break
            continue
        for word in text.split():
            words.append(word)
            if word.endswith((".", "!", "?")):
                return " ".join(words)
    return " ".join(words)


def pattern_presets():
    """The pattern presets as (identifier, display name, description),
    sorted by identifier: the file name without `.knit`, a name made from
    it ("rib_2x2" -> "Rib 2x2"), and the first sentence of the file's
    opening comment. Ready for a Blender EnumProperty's items."""
    folder = patterns_dir()
    try:
        names = os.listdir(folder)
    except OSError:
        return []
    out = []
    for name in sorted(names):
        if not name.endswith(_SUFFIX) or name.startswith("."):
            continue
        path = os.path.join(folder, name)
        if not os.path.isfile(path):
            continue
        identifier = name[:-len(_SUFFIX)]
        out.append((identifier, _display_name(identifier), _description(path)))
    return out


def preset_path(identifier):
    """The file of a pattern preset; PatternError for an identifier that is
    not one (only the names pattern_presets() lists, so no path escapes the
    folder)."""
    known = [p[0] for p in pattern_presets()]
    if identifier not in known:
        raise PatternError(patterns_dir(), 0, 0,
                           "no pattern preset '%s' (the presets: %s)"
                           % (identifier, ", ".join(known) or "none"))
    return os.path.join(patterns_dir(), identifier + _SUFFIX)


def load_preset(identifier):
    """The Pattern of a preset (errors as load(): the file, line and column)."""
    return load(preset_path(identifier))


# -- yarn weights ------------------------------------------------------------
#
# The stitch geometry is in pattern units relative to the stitch (a stitch is
# 2 pi wide and h + 1/2 tall, docs/scene-format.md "knit"), so a heavier yarn
# does not make the loop bigger: it makes the yarn thicker relative to the
# loop (r), and the loop bends deeper around the thicker yarn of the rows it
# interlocks with (d), while the loop's shape (a, h) stays the library's.
# The size of the stitches on the object is the gauge: `stitches_per_10cm` is
# the middle of the Craft Yarn Council's stockinette range for the weight;
# uv_scale_for_gauge() turns it into the material's UV scale.
#
# Every r here is below half the yarn clearance the library computes for the
# preset's a, h, d (knit::StitchParams::validate; tests/addon_core checks
# that knitshade.StitchParams accepts each), with a margin:
#
#   weight      d     r     r limit (clearance / 2)
#   fingering   0.8   0.50  0.582
#   sport       0.9   0.57  0.640
#   dk          1.0   0.62  0.693
#   worsted     1.0   0.65  0.693   the library's defaults
#   chunky      1.2   0.74  0.774
#
# ply_count is the number of plies drawn by the ply and fibre detail (1..16;
# the library's default is 3): a typical construction for the weight, not
# the weight's "N ply" name.

YARN_WEIGHTS = {
    "fingering": {
        "name": "Fingering",
        "description": "Thin sock and shawl yarn (UK 4 ply): fine, crisp stitches, "
                       "about 28 stitches to 10 cm",
        "a": 1.5, "h": 4.0, "d": 0.8, "r": 0.50, "ply_count": 4, "stitches_per_10cm": 28.0,
    },
    "sport": {
        "name": "Sport",
        "description": "Light baby and sweater yarn (UK 5 ply): about 24 stitches to 10 cm",
        "a": 1.5, "h": 4.0, "d": 0.9, "r": 0.57, "ply_count": 3, "stitches_per_10cm": 24.0,
    },
    "dk": {
        "name": "DK",
        "description": "Double knitting (UK DK, 8 ply): everyday garments, "
                       "about 22 stitches to 10 cm",
        "a": 1.5, "h": 4.0, "d": 1.0, "r": 0.62, "ply_count": 4, "stitches_per_10cm": 22.0,
    },
    "worsted": {
        "name": "Worsted",
        "description": "Medium sweater yarn (UK aran, 10 ply): the library's defaults, "
                       "about 18 stitches to 10 cm",
        "a": 1.5, "h": 4.0, "d": 1.0, "r": 0.65, "ply_count": 3, "stitches_per_10cm": 18.0,
    },
    "chunky": {
        "name": "Chunky (bulky)",
        "description": "Thick yarn (UK chunky, 12 ply): plump, deep stitches, "
                       "about 14 stitches to 10 cm",
        "a": 1.5, "h": 4.0, "d": 1.2, "r": 0.74, "ply_count": 2, "stitches_per_10cm": 14.0,
    },
}

_PATTERN_UNITS_PER_STITCH = 2.0 * math.pi


def yarn_weight_presets():
    """The yarn weights as (identifier, name, description), thinnest first;
    ready for a Blender EnumProperty's items."""
    return [(k, v["name"], v["description"]) for k, v in YARN_WEIGHTS.items()]


def yarn_weight(identifier):
    """A copy of a yarn weight's settings: a, h, d, r (stitch parameters,
    pattern units), ply_count, stitches_per_10cm, name, description.
    KeyError naming the known weights for an unknown identifier."""
    try:
        return dict(YARN_WEIGHTS[identifier])
    except KeyError:
        raise KeyError("no yarn weight '%s' (the weights: %s)"
                       % (identifier, ", ".join(YARN_WEIGHTS))) from None


def uv_scale_for_gauge(stitches_per_10cm, metres_per_uv_unit=1.0):
    """The material's uv_scale (pattern units per UV unit) that gives
    `stitches_per_10cm` stitches across 10 cm of a mesh on which one UV unit
    spans `metres_per_uv_unit` metres (a 2 m plane unwrapped to 0..1: 2.0).

    A stitch is 2 pi pattern units wide, so
    uv_scale = 2 pi * stitches_per_10cm * 10 * metres_per_uv_unit.
    """
    if not stitches_per_10cm > 0:
        raise ValueError("stitches_per_10cm must be > 0, got %r" % (stitches_per_10cm,))
    if not metres_per_uv_unit > 0:
        raise ValueError("metres_per_uv_unit must be > 0, got %r" % (metres_per_uv_unit,))
    return _PATTERN_UNITS_PER_STITCH * stitches_per_10cm * 10.0 * metres_per_uv_unit


def rows_per_10cm(stitches_per_10cm, h=4.0):
    """The rows in 10 cm that go with a stitch gauge: a row is h + 1/2
    pattern units tall against a stitch's 2 pi (about 1.4 rows per stitch
    with h = 4, as in hand-knitted stockinette)."""
    return stitches_per_10cm * _PATTERN_UNITS_PER_STITCH / (h + 0.5)

"""The knit shader's text for one material, and its parameters.

`osl/knit_fabric.osl` includes the shared kernel (`native/kernel/`) and a
pattern header. The *template* is that shader with every ``#include "..."``
replaced by the file it names (each file once), except the pattern header,
whose line stays as the place where a material's pattern goes. The
generator fills it in: the result is one self-contained OSL text, with no
``#include`` and nothing outside it, the same bytes for the same pattern.

The template is built from the sources once (`python3 shader.py --template
OUT`, run by the build, which ships it in the add-on as
``shader/knit_fabric_template.osl`` and embeds it in the C++ library for
``knitshade osl``); in a source checkout it is assembled from the sources
on first use. The shader's parameters (names, types, defaults, ranges,
labels, tooltips) are read from the template, so the .osl file is their only
definition.

No bpy here: this runs in any Python from 3.10 on.
"""
import collections
import os
import re
import sys

SHADER_NAME = "knit_fabric"
MAX_SIDE = 256  # rows and columns a shader's pattern may have
PALETTE_SIZE = 8  # yarn colours the shader takes (Yarn0..Yarn7)
CURVATURE_ATTRIBUTE = "knit_curvature"
PATTERN_HEADER = "knit_pattern.h"
PATTERN_LINE = '#include "knit_pattern.h"'
TEMPLATE_FILE = "knit_fabric_template.osl"

HERE = os.path.dirname(os.path.abspath(__file__))


class ShaderError(ValueError):
    """A pattern the shader cannot take, or a template that cannot be built."""


ShaderParam = collections.namedtuple(
    "ShaderParam",
    "name kind default min max soft_min soft_max label description items linked")

# (name, kind, description) of the shader's outputs, in order.
ShaderOutput = collections.namedtuple("ShaderOutput", "name kind description")


# ---- the template --------------------------------------------------------

def source_dirs():
    """The folders of the shader's sources in a source checkout: (osl/,
    native/kernel/), or None when they are not there (an installed add-on)."""
    root = os.path.normpath(os.path.join(HERE, "..", "..", ".."))
    osl_dir = os.path.join(root, "osl")
    kernel_dir = os.path.join(root, "native", "kernel")
    if os.path.isfile(os.path.join(osl_dir, SHADER_NAME + ".osl")) and os.path.isdir(kernel_dir):
        return osl_dir, kernel_dir
    return None


_INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"\s*$')


def build_template(osl_dir, kernel_dir):
    """knit_fabric.osl with its includes inlined (each file once, in the order
    first met), the pattern header's line kept."""
    seen = set()
    out = []

    def expand(path):
        with open(path, "r", encoding="utf-8") as f:
            text = f.read()
        for line in text.splitlines():
            m = _INCLUDE.match(line)
            if not m:
                out.append(line)
                continue
            name = m.group(1)
            if name == PATTERN_HEADER:
                out.append(PATTERN_LINE)
                continue
            found = None
            for folder in (os.path.dirname(path), osl_dir, kernel_dir):
                cand = os.path.join(folder, name)
                if os.path.isfile(cand):
                    found = os.path.normpath(cand)
                    break
            if found is None:
                raise ShaderError(f"{path}: #include \"{name}\": no such file in {osl_dir} or {kernel_dir}")
            if found in seen:
                continue
            seen.add(found)
            out.append(f"/* ---- {name} ---- */")
            expand(found)
            out.append(f"/* ---- end of {name} ---- */")

    banner = ("/* Knitshade knit fabric shader, self-contained: the shared kernel (native/kernel/) is\n"
              " * inlined and the material's pattern compiled in as constant arrays. Generated; edit\n"
              " * osl/knit_fabric.osl and the kernel instead. */")
    out.append(banner)
    expand(os.path.join(osl_dir, SHADER_NAME + ".osl"))
    if out.count(PATTERN_LINE) != 1:
        raise ShaderError(f"{osl_dir}/{SHADER_NAME}.osl must include {PATTERN_HEADER} exactly once")
    return "\n".join(out) + "\n"


_template_cache = None


def template_text():
    """The template: the add-on's bundled copy, else built from the sources."""
    global _template_cache
    if _template_cache is None:
        bundled = os.path.join(HERE, "..", "shader", TEMPLATE_FILE)
        if os.path.isfile(bundled):
            with open(bundled, "r", encoding="utf-8") as f:
                _template_cache = f.read()
        else:
            dirs = source_dirs()
            if dirs is None:
                raise ShaderError(f"the shader template {os.path.normpath(bundled)} is missing, and the "
                                  "shader's sources are not beside this add-on: reinstall the add-on")
            _template_cache = build_template(*dirs)
    return _template_cache


# ---- the pattern block ---------------------------------------------------

def _array_lines(values, rows, cols):
    lines = []
    for r in range(rows):
        row = ", ".join(str(v) for v in values[r * cols:(r + 1) * cols])
        lines.append("  " + row + (", \\" if r + 1 < rows else " }"))
    return lines


def pattern_block(pattern):
    """The lines that replace the pattern header's include: the size, whether
    slip stitches occur, the codes and the colour indices, row 0 first."""
    rows, cols = int(pattern.rows), int(pattern.cols)
    codes = [int(c) for c in pattern.codes]
    colors = pattern.colors
    colours = [0] * (rows * cols) if colors is None else [int(c) for c in colors]
    if rows < 1 or cols < 1 or rows > MAX_SIDE or cols > MAX_SIDE:
        raise ShaderError(f"the pattern is {rows} x {cols} stitches; the shader takes patterns of at most "
                          f"{MAX_SIDE} x {MAX_SIDE}")
    if len(codes) != rows * cols or len(colours) != rows * cols:
        raise ShaderError(f"the pattern's {len(codes)} codes and {len(colours)} colour indices do not fill "
                          f"{rows} x {cols} cells")
    bad = [c for c in codes if c not in (0, 1, 2, 3)]
    if bad:
        raise ShaderError(f"stitch code {bad[0]} is not one of 0 (K), 1 (P), 2 (F), 3 (B)")
    top = max(colours)
    if min(colours) < 0 or top >= PALETTE_SIZE:
        raise ShaderError(f"the pattern uses colour index {top if top >= PALETTE_SIZE else min(colours)}; the "
                          f"shader's palette has {PALETTE_SIZE} yarn colours, indices 0 to {PALETTE_SIZE - 1}")
    has_floats = 1 if any(c in (2, 3) for c in codes) else 0
    lines = [f"/* Pattern: {rows} x {cols} stitches, row 0 at the top. */",
             f"#define KNIT_PATTERN_ROWS {rows}",
             f"#define KNIT_PATTERN_COLS {cols}",
             f"#define KNIT_PATTERN_CELLS {rows * cols}",
             f"#define KNIT_PATTERN_HAS_FLOATS {has_floats}",
             "#define KNIT_PATTERN_CODES { \\"]
    lines += _array_lines(codes, rows, cols)
    lines.append("#define KNIT_PATTERN_COLOURS { \\")
    lines += _array_lines(colours, rows, cols)
    return "\n".join(lines)


def osl_source(pattern):
    """The self-contained shader text for `pattern` (anything with rows,
    cols, codes and colors as core.pattern.Pattern has them)."""
    return template_text().replace(PATTERN_LINE, pattern_block(pattern), 1)


# ---- parameters, read from the shader's declaration ----------------------

_PARAM = re.compile(r"^\s*(output\s+)?(closure\s+color|float|int|color|point|vector|normal)\s+(\w+)\s*=\s*"
                    r"(.*?)\s*(\[\[(.*?)\]\])?\s*[,)]\s*$", re.S)
_META = re.compile(r'(string|float|int)\s+(\w+)\s*=\s*("(?:[^"\\]|\\.)*"|[-+0-9.eE]+)')


def _declaration(text):
    """The parameter list of `shader knit_fabric(...)`, split into one
    string per parameter (metadata may span lines)."""
    start = text.index(f"shader {SHADER_NAME}(")
    i = start + len(f"shader {SHADER_NAME}(")
    depth, brackets, item, items = 1, 0, [], []
    while depth > 0:
        ch = text[i]
        if ch == "[":
            brackets += 1
        elif ch == "]":
            brackets -= 1
        elif ch == "(" and brackets == 0:
            depth += 1
        elif ch == ")" and brackets == 0:
            depth -= 1
        if brackets == 0 and (ch == "," and depth == 1 or depth == 0):
            items.append("".join(item).strip() + ch)
            item = []
        else:
            item.append(ch)
        i += 1
    return items


def _value(kind, text):
    text = text.strip()
    if kind in ("float",):
        return float(text)
    if kind in ("int", "bool", "enum"):
        return int(text)
    m = re.match(r"(?:color|point|vector|normal)\s*\((.*)\)$", text)
    if not m:
        raise ShaderError(f"cannot read the default {text!r}")
    parts = [float(p) for p in m.group(1).split(",")]
    return tuple(parts * 3) if len(parts) == 1 else tuple(parts)


def _parse_params(text):
    params, outputs = [], []
    for item in _declaration(text):
        m = _PARAM.match(item)
        if not m:
            raise ShaderError(f"cannot read the shader parameter {item!r}")
        is_output, ctype, name, default, meta_text = m.group(1), m.group(2), m.group(3), m.group(4), m.group(6)
        meta = {}
        for mm in _META.finditer(meta_text or ""):
            kind, key, val = mm.groups()
            meta[key] = val[1:-1] if kind == "string" else (float(val) if kind == "float" else int(val))
        if is_output:
            outputs.append(ShaderOutput(name, "closure" if ctype.startswith("closure") else ctype,
                                        meta.get("help", "")))
            continue
        kind = ctype
        items = None
        if ctype == "int" and meta.get("widget") == "checkBox":
            kind = "bool"
        elif ctype == "int" and meta.get("widget") == "mapper":
            kind = "enum"
            items = tuple((lab.upper().replace(" ", "_").replace("-", "_"), lab, int(v))
                          for lab, v in (o.split(":") for o in meta["options"].split("|")))
        value = _value(kind, default)
        params.append(ShaderParam(
            name=name, kind=kind, default=value,
            min=meta.get("min"), max=meta.get("max"),
            soft_min=meta.get("slidermin", meta.get("min")), soft_max=meta.get("slidermax", meta.get("max")),
            label=meta.get("label", name), description=meta.get("help", ""), items=items,
            linked=name in ("UV", "Curvature")))
    return tuple(params), tuple(outputs)


_params_cache = None


def _params():
    global _params_cache
    if _params_cache is None:
        _params_cache = _parse_params(template_text())
    return _params_cache


def __getattr__(name):
    # PARAMS and OUTPUTS are read from the template when first asked for.
    if name == "PARAMS":
        return _params()[0]
    if name == "OUTPUTS":
        return _params()[1]
    raise AttributeError(name)


def main(argv):
    if len(argv) == 3 and argv[1] == "--template":
        dirs = source_dirs()
        if dirs is None:
            print("shader.py: osl/ and native/kernel/ are not beside this file", file=sys.stderr)
            return 1
        text = build_template(*dirs)
        tmp = argv[2] + ".tmp"
        with open(tmp, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
        os.replace(tmp, argv[2])
        return 0
    print("usage: shader.py --template OUT.osl", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))

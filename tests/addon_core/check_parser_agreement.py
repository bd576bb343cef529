#!/usr/bin/env python3
"""The add-on's pure-Python pattern parser (addon/knitshade_blender/core/
pattern.py) against the C++ one (knit::Pattern through the module
`knitshade`).

For every file of tests/fuzz/corpus/pattern and examples/patterns, read both
as a file (same path) and as bytes (same source name): both accept or both
reject; a rejection has the same message (str(e), and source, line, column,
message); an acceptance the same shape, codes, colour matrix (or none),
num_colors and to_text(). Then:

- mutations of those files (bytes and tokens of tests/fuzz/pattern.dict
  inserted, deleted, repeated; fixed seed), compared the same way;
- the editing operations on every accepted pattern of at most 4096 cells,
  each result checked against numpy on the C++ arrays, and its to_text()
  and to_storage() read back by the C++ parser to an equal pattern;
- the pattern presets load as knitshade.Pattern.from_file loads them, and
  every yarn weight passes knitshade.StitchParams and knitshade.PlyProfile.

Prints the counts and exits 1 on any disagreement, listing the first ones
with both sides. Without the module (KNIT_PYTHON_DIR, else build/python) it
says so and exits 77 (CTest: skipped).
"""
import os
import pathlib
import random
import sys
import types

HERE = pathlib.Path(__file__).resolve().parent
ROOT = pathlib.Path(os.environ.get("KNIT_SOURCE_DIR", HERE.parents[1]))
MODULE_DIR = os.environ.get("KNIT_PYTHON_DIR") or str(ROOT / "build" / "python")
sys.path.insert(0, MODULE_DIR)

try:
    import numpy as np
    import knitshade
except ImportError as e:
    print("the knitshade module is not importable from %s (%s): build it with "
          "-DKNIT_BUILD_PYTHON=ON. The parser agreement check did NOT run." % (MODULE_DIR, e))
    sys.exit(77)

if "knitshade_blender" not in sys.modules:
    # The core without the add-on's __init__.py (which imports bpy).
    _package = types.ModuleType("knitshade_blender")
    _package.__path__ = [str(ROOT / "addon" / "knitshade_blender")]
    sys.modules["knitshade_blender"] = _package
from knitshade_blender.core import pattern as core  # noqa: E402
from knitshade_blender.core import presets  # noqa: E402

CORPUS = ROOT / "tests" / "fuzz" / "corpus" / "pattern"
EXAMPLES = ROOT / "examples" / "patterns"
DICT = ROOT / "tests" / "fuzz" / "pattern.dict"
MUTATIONS = 4000
SHOW = 8  # disagreements listed


class Tally:
    def __init__(self):
        self.compared = 0
        self.accepted = 0
        self.rejected = 0
        self.problems = []

    def problem(self, what, cpp, py):
        self.problems.append((what, cpp, py))


def run(call):
    """("ok", pattern) or ("error", exception) for a PatternError."""
    try:
        return "ok", call()
    except (knitshade.PatternError, core.PatternError) as e:
        return "error", e


def cpp_arrays(p):
    codes = p.codes().ravel().tolist()
    colors = p.colors().ravel().tolist() if p.has_colors else None
    return codes, colors


def same_pattern(cpp, py):
    """None when the C++ and Python patterns agree, else what differs."""
    codes, colors = cpp_arrays(cpp)
    if (cpp.rows, cpp.cols) != (py.rows, py.cols):
        return "shape %dx%d against %dx%d" % (cpp.rows, cpp.cols, py.rows, py.cols)
    if codes != list(py.codes):
        return "codes differ"
    if colors != (list(py.colors) if py.colors is not None else None):
        return "colours differ (C++ has_colors %s)" % cpp.has_colors
    if (cpp.has_colors, cpp.num_colors) != (py.has_colors, py.num_colors):
        return "has_colors/num_colors %s against %s" % ((cpp.has_colors, cpp.num_colors),
                                                        (py.has_colors, py.num_colors))
    if cpp.to_text() != py.to_text():
        return "to_text() differs"
    return None


def error_fields(e):
    return (str(e), e.source, e.line, e.column, e.message)


def compare(tally, label, cpp, py, count=True):
    """Compares two run() results; returns the Python pattern when both accept."""
    if count:
        tally.compared += 1
    if cpp[0] != py[0]:
        tally.problem(label, "%s: %s" % cpp, "%s: %s" % py)
        return None
    if cpp[0] == "error":
        if count:
            tally.rejected += 1
        if error_fields(cpp[1]) != error_fields(py[1]):
            tally.problem(label, error_fields(cpp[1]), error_fields(py[1]))
        return None
    if count:
        tally.accepted += 1
    diff = same_pattern(cpp[1], py[1])
    if diff:
        tally.problem(label, diff, "")
        return None
    # The storage form is pattern text too: the C++ parser reads it back equal.
    back = run(lambda: knitshade.Pattern.from_text(py[1].to_storage(), "<storage>"))
    if back[0] != "ok" or same_pattern(back[1], py[1]):
        tally.problem(label + " (to_storage read by C++)", back, py[1].to_storage()[:200])
    return py[1]


def check_files(paths, tally):
    accepted = []
    for path in paths:
        name = str(path)
        compare(tally, name + " (file)",
                run(lambda: knitshade.Pattern.from_file(name)), run(lambda: core.load(name)))
        data = path.read_bytes()
        source = path.name
        p = compare(tally, name + " (text)",
                    run(lambda: knitshade.Pattern.from_text(data, source)),
                    run(lambda: core.parse_text(data, source)), count=False)
        if p is not None:
            accepted.append((name, p))
    return accepted


def dictionary_tokens():
    tokens = []
    for line in DICT.read_text().splitlines():
        line = line.strip()
        if line.startswith('"') and line.endswith('"'):
            tokens.append(line[1:-1].encode("latin-1").decode("unicode_escape").encode("latin-1"))
    return tokens + [b"\x00", b"\xff", b"\xc3", b"\x01", b"\xe2\x82", b"\xf0\x9f\x98\x80", b"\x0b",
                     b"-0", b"007", b"99999999999", b"\xe2\x84\xaa"]


def mutate(data, tokens, rng):
    data = bytearray(data)
    for _ in range(rng.randint(1, 4)):
        op = rng.randrange(6)
        at = rng.randint(0, len(data))
        if op == 0 and data:  # delete a few bytes
            del data[at:at + rng.randint(1, 3)]
        elif op == 1:  # insert a token
            data[at:at] = rng.choice(tokens)
        elif op == 2 and data:  # overwrite a byte
            data[min(at, len(data) - 1)] = rng.randrange(256)
        elif op == 3 and data:  # repeat a line
            lines = bytes(data).split(b"\n")
            k = rng.randrange(len(lines))
            lines.insert(k, lines[k])
            data = bytearray(b"\n".join(lines))
        elif op == 4:  # a token repeated
            data[at:at] = rng.choice(tokens) * rng.randint(2, 6)
        else:  # truncate
            del data[at:]
    return bytes(data)


def check_mutations(paths, tally):
    rng = random.Random(20261206)
    tokens = dictionary_tokens()
    sources = [p.read_bytes() for p in paths]
    sources = [s for s in sources if len(s) < 20000]
    for i in range(MUTATIONS):
        data = mutate(rng.choice(sources), tokens, rng)
        compare(tally, "mutation %d %r" % (i, data[:80]),
                run(lambda: knitshade.Pattern.from_text(data, "<mutated>")),
                run(lambda: core.parse_text(data, "<mutated>")))


def edits_of(p, rng):
    """(label, Python result, numpy reference codes, reference colours or None)."""
    codes = np.array(p.codes, dtype=np.int64).reshape(p.rows, p.cols)
    colors = np.array(p.colors, dtype=np.int64).reshape(p.rows, p.cols) if p.has_colors else None
    zeros = colors if colors is not None else np.zeros_like(codes)
    R, C = p.rows, p.cols
    r, c = rng.randrange(R), rng.randrange(C)
    s, k = rng.randrange(4), rng.randrange(256)
    out = []

    def put(a, rr, cc, v):
        a = a.copy()
        a[rr, cc] = v
        return a

    out.append(("with_stitch", p.with_stitch(r, c, s), put(codes, r, c, s), colors))
    out.append(("cycled", p.cycled(r, c), put(codes, r, c, (codes[r, c] + 1) % 4), colors))
    out.append(("with_color", p.with_color(r, c, k), codes, put(zeros, r, c, k)))
    top, left = rng.randrange(R), rng.randrange(C)
    h, w = rng.randint(1, R - top), rng.randint(1, C - left)
    a, b = codes.copy(), zeros.copy()
    a[top:top + h, left:left + w] = s
    b[top:top + h, left:left + w] = k
    out.append(("filled", p.filled(stitch=s, color=k, rect=(top, left, h, w)), a, b))
    out.append(("filled all", p.filled(stitch=s), np.full_like(codes, s), colors))
    dx, dy = rng.randint(-2 * C, 2 * C), rng.randint(-2 * R, 2 * R)
    roll = (lambda m: np.roll(m, (dy, dx), axis=(0, 1)))
    out.append(("shifted", p.shifted(dx, dy), roll(codes),
                roll(colors) if colors is not None else None))
    out.append(("mirrored", p.mirrored(), codes[:, ::-1],
                colors[:, ::-1] if colors is not None else None))
    out.append(("flipped", p.flipped(), codes[::-1],
                colors[::-1] if colors is not None else None))
    nr, nc = rng.randint(1, 2 * R + 1), rng.randint(1, 2 * C + 1)

    def resize(m):
        z = np.zeros((nr, nc), dtype=np.int64)
        z[:min(R, nr), :min(C, nc)] = m[:min(R, nr), :min(C, nc)]
        return z

    out.append(("resized", p.resized(nr, nc), resize(codes),
                resize(colors) if colors is not None else None))
    i = rng.randint(0, R)
    if R < core.MAX_ROWS:  # at the limit the edit raises (test_pattern_core checks it)
        out.append(("with_row_inserted", p.with_row_inserted(i, s, k),
                    np.insert(codes, i, s, axis=0), np.insert(zeros, i, k, axis=0)))
        out.append(("with_row_inserted (no colour)", p.with_row_inserted(i),
                    np.insert(codes, i, 0, axis=0),
                    np.insert(colors, i, 0, axis=0) if colors is not None else None))
    j = rng.randint(0, C)
    if C < core.MAX_COLS:
        out.append(("with_col_inserted", p.with_col_inserted(j, s, k),
                    np.insert(codes, j, s, axis=1), np.insert(zeros, j, k, axis=1)))
    if R > 1:
        out.append(("with_row_removed", p.with_row_removed(r), np.delete(codes, r, axis=0),
                    np.delete(colors, r, axis=0) if colors is not None else None))
    if C > 1:
        out.append(("with_col_removed", p.with_col_removed(c), np.delete(codes, c, axis=1),
                    np.delete(colors, c, axis=1) if colors is not None else None))
    out.append(("without_colors", p.without_colors(), codes, None))
    return out


def check_edits(accepted, tally):
    rng = random.Random(4096)
    count = 0
    for name, p in accepted:
        if p.rows * p.cols > 4096:
            continue
        for label, q, want_codes, want_colors in edits_of(p, rng):
            count += 1
            where = "%s: %s" % (name, label)
            if q.code_rows() != want_codes.tolist():
                tally.problem(where, "codes (numpy) %s" % want_codes.tolist()[:4],
                              q.code_rows()[:4])
                continue
            got_colors = q.color_rows()
            if (got_colors is None) != (want_colors is None) or (
                    got_colors is not None and got_colors != want_colors.tolist()):
                tally.problem(where, "colours (numpy)", "differ")
                continue
            for form, text in (("to_text", q.to_text()), ("to_storage", q.to_storage())):
                back = run(lambda: knitshade.Pattern.from_text(text, "<edit>"))
                if back[0] != "ok":
                    tally.problem(where + " " + form + " read by C++", str(back[1]), text[:200])
                    continue
                diff = same_pattern(back[1], q)
                if diff:
                    tally.problem(where + " " + form + " read by C++", diff, text[:200])
    return count


def check_presets(tally):
    n = 0
    for identifier, _, _ in presets.pattern_presets():
        n += 1
        path = presets.preset_path(identifier)
        diff = same_pattern(knitshade.Pattern.from_file(path), presets.load_preset(identifier))
        if diff:
            tally.problem("preset " + identifier, diff, "")
    for identifier, _, _ in presets.yarn_weight_presets():
        n += 1
        w = presets.yarn_weight(identifier)
        try:
            sp = knitshade.StitchParams(w["a"], w["h"], w["d"], w["r"])
            knitshade.PlyProfile(ply_count=w["ply_count"], yarn_radius=w["r"])
        except ValueError as e:
            tally.problem("yarn weight " + identifier, str(e), w)
            continue
        # a margin: the weight stays valid under float rounding of a UI field
        if w["r"] > 0.99 * sp.clearance() / 2:
            tally.problem("yarn weight " + identifier,
                          "r = %g within 1%% of the limit %g" % (w["r"], sp.clearance() / 2), w)
    return n


def main():
    paths = sorted(p for p in CORPUS.iterdir() if p.is_file()) + sorted(EXAMPLES.glob("*.knit"))
    files = Tally()
    accepted = check_files(paths, files)
    mutations = Tally()
    check_mutations(paths, mutations)
    other = Tally()
    edits = check_edits(accepted, other)
    preset_count = check_presets(other)

    print("files: %d compared (%d corpus, %d examples), %d accepted, %d rejected, "
          "%d disagreements" % (files.compared, sum(1 for p in paths if p.parent == CORPUS),
                                sum(1 for p in paths if p.parent == EXAMPLES), files.accepted,
                                files.rejected, len(files.problems)))
    print("mutations: %d compared, %d accepted, %d rejected, %d disagreements"
          % (mutations.compared, mutations.accepted, mutations.rejected,
             len(mutations.problems)))
    print("edits: %d results checked against numpy and read back by C++; presets and yarn "
          "weights: %d checked; %d disagreements" % (edits, preset_count, len(other.problems)))
    problems = files.problems + mutations.problems + other.problems
    for what, cpp, py in problems[:SHOW]:
        print("DISAGREE %s\n  C++:    %s\n  Python: %s" % (what, cpp, py))
    if problems:
        print("%d disagreements" % len(problems))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

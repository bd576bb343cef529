"""The shader generator, without OSL: the add-on's pure-Python generator
(addon/knitshade_blender/core/shader.py), the C++ library's
(knitshade.osl_source) and the CLI's (`knitshade osl`) give the same bytes;
the text is self-contained and deterministic, holds the pattern as arrays of
its size, and refuses what the shader cannot take with the same message
from Python and C++. Needs the module (KNIT_PYTHON_DIR) and the CLI
(KNIT_CLI); exits 77 without the module."""
import os
import re
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.environ.get("KNIT_PYTHON_DIR", os.path.join(ROOT, "build", "python")))
sys.path.insert(0, os.path.join(ROOT, "addon", "knitshade_blender"))

try:
    import knitshade
except ImportError as e:
    print(f"the knitshade module is not built ({e}): the generator checks did NOT run")
    sys.exit(77)

from core import pattern as core_pattern  # noqa: E402
from core import shader  # noqa: E402

PATTERNS = os.path.join(ROOT, "examples", "patterns")
CLI = os.environ.get("KNIT_CLI", os.path.join(ROOT, "build", "knitshade"))


def array_values(text, name):
    m = re.search(r"#define %s \{ \\\n(.*?) \}" % name, text, re.S)
    return [int(v) for v in re.findall(r"-?\d+", m.group(1))]


class Generator(unittest.TestCase):
    def test_python_cpp_and_cli_agree_on_every_example(self):
        names = sorted(f for f in os.listdir(PATTERNS) if f.endswith(".knit"))
        self.assertGreaterEqual(len(names), 10)
        for name in names:
            path = os.path.join(PATTERNS, name)
            py = shader.osl_source(core_pattern.load(path))
            cpp = knitshade.osl_source(knitshade.Pattern.from_file(path))
            self.assertEqual(py, cpp, name)
            with tempfile.TemporaryDirectory() as d:
                out = os.path.join(d, "k.osl")
                r = subprocess.run([CLI, "osl", path, "-o", out], capture_output=True, text=True)
                self.assertEqual(r.returncode, 0, r.stderr)
                with open(out, encoding="utf-8") as f:
                    self.assertEqual(f.read(), py, name)

    def test_self_contained_deterministic_and_sized(self):
        p = knitshade.Pattern.from_rows([[0, 1, 2], [3, 1, 0]], colors=[[0, 7, 1], [2, 0, 5]])
        a = knitshade.osl_source(p)
        self.assertEqual(a, knitshade.osl_source(p))
        self.assertNotIn("#include", a)
        self.assertEqual(array_values(a, "KNIT_PATTERN_CODES"), [0, 1, 2, 3, 1, 0])
        self.assertEqual(array_values(a, "KNIT_PATTERN_COLOURS"), [0, 7, 1, 2, 0, 5])
        self.assertIn("#define KNIT_PATTERN_CELLS 6\n", a)
        self.assertIn("#define KNIT_PATTERN_HAS_FLOATS 1\n", a)
        # Another pattern changes the pattern block only.
        b = knitshade.osl_source(knitshade.Pattern.from_rows([[1]]))
        head = a.index("/* Pattern:")
        self.assertEqual(a[:head], b[:head])
        tail_a = a[a.index("#define KNIT_PATTERN_COLOURS"):]
        tail_b = b[b.index("#define KNIT_PATTERN_COLOURS"):]
        self.assertEqual(tail_a[tail_a.index("}") + 1:], tail_b[tail_b.index("}") + 1:])
        self.assertIn("#define KNIT_PATTERN_HAS_FLOATS 0\n", b)

    def test_random_patterns_agree(self):
        import random
        rng = random.Random(11)
        for _ in range(20):
            rows, cols = rng.randint(1, 40), rng.randint(1, 40)
            codes = [[rng.randint(0, 3) for _ in range(cols)] for _ in range(rows)]
            colours = [[rng.randint(0, 7) for _ in range(cols)] for _ in range(rows)] if rng.random() < 0.5 else None
            cp = knitshade.Pattern.from_rows(codes, colors=colours) if colours else knitshade.Pattern.from_rows(codes)
            pp = core_pattern.Pattern.from_rows(codes, colors=colours)
            self.assertEqual(shader.osl_source(pp), knitshade.osl_source(cp))

    def test_limits_refused_with_the_same_message(self):
        cases = [([[0] * 257], None), ([[0]] * 257, None), ([[0, 1]], [[0, 8]])]
        for codes, colours in cases:
            cp = knitshade.Pattern.from_rows(codes, colors=colours) if colours else knitshade.Pattern.from_rows(codes)
            pp = core_pattern.Pattern.from_rows(codes, colors=colours)
            with self.assertRaises(ValueError) as c_err:
                knitshade.osl_source(cp)
            with self.assertRaises(shader.ShaderError) as p_err:
                shader.osl_source(pp)
            self.assertEqual(str(c_err.exception), str(p_err.exception))
            self.assertRegex(str(p_err.exception), r"256 x 256|palette has 8")
        side = knitshade.Pattern.from_rows([[0] * 256] * 256)
        self.assertIn("#define KNIT_PATTERN_CELLS 65536\n", knitshade.osl_source(side))

    def test_parameters_read_from_the_shader(self):
        names = [p.name for p in shader.PARAMS]
        self.assertEqual(names[:7], ["UV", "Curvature", "UVScale", "A", "H", "D", "R"])
        self.assertEqual([n for n in names if n.startswith("Yarn")], [f"Yarn{i}" for i in range(shader.PALETTE_SIZE)])
        for p in shader.PARAMS:
            self.assertTrue(p.label and p.description, p.name)
            if p.kind in ("float", "int"):
                self.assertTrue(p.min <= p.default <= p.max, p.name)
        mode = next(p for p in shader.PARAMS if p.name == "Mode")
        self.assertEqual([v for _, _, v in mode.items], [0, 1])
        self.assertEqual([o.name for o in shader.OUTPUTS][0], "BSDF")
        # The defaults are the native library's.
        sp = knitshade.StitchParams()
        defaults = {p.name: p.default for p in shader.PARAMS}
        self.assertEqual((defaults["A"], defaults["H"], defaults["D"], defaults["R"]),
                         (sp.a, sp.h, sp.d, round(sp.r, 6)))


if __name__ == "__main__":
    unittest.main(verbosity=2)

"""`knitshade yarns PATTERN -o FILE`: the explicit yarn curves written by the
CLI are the ones knitshade.explicit_yarns returns, in both formats; bad input
gives one clear error and a non-zero exit."""
import os
import subprocess
import tempfile
import unittest

import numpy as np

import knitshade

CLI = os.environ.get("KNIT_CLI", "knitshade")
SRC = os.environ.get("KNIT_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
SEED = os.path.join(SRC, "examples", "patterns", "seed.knit")


def run(*args):
    return subprocess.run([CLI, "yarns", *args], capture_output=True, text=True)


class CliYarnsTest(unittest.TestCase):
    def test_obj_matches_python(self):
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "y.obj")
            r = run(SEED, "-o", out, "--tiles", "2", "1", "--samples", "16")
            self.assertEqual(r.returncode, 0, r.stderr)
            verts, lines, radius = [], [], None
            with open(out) as f:
                for line in f:
                    if line.startswith("v "):
                        verts.append([float(x) for x in line.split()[1:]])
                    elif line.startswith("l "):
                        lines.append([int(x) - 1 for x in line.split()[1:]])
                    elif line.startswith("# radius"):
                        radius = float(line.split()[2])
        p = knitshade.Pattern.from_file(SEED)
        ref = knitshade.explicit_yarns(p, knitshade.StitchParams(), 2, 1, 16)
        self.assertEqual(len(lines), len(ref["curves"]))
        self.assertAlmostEqual(radius, ref["radius"], places=5)
        verts = np.array(verts)
        for idx, curve in zip(lines, ref["curves"]):
            np.testing.assert_allclose(verts[idx], curve, atol=1e-5)

    def test_txt_format_carries_colours(self):
        with tempfile.TemporaryDirectory() as d:
            out = os.path.join(d, "y.txt")
            pat = os.path.join(SRC, "examples", "patterns", "stripes_two_colour.knit")
            r = run(pat, "-o", out, "--samples", "8")
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(out) as f:
                lines = f.read().splitlines()
        self.assertEqual(lines[0], "# knitshade yarns v1")
        colours = {int(l.split()[3]) for l in lines[3:] if len(l.split()) == 4 and not l.startswith("curve")}
        self.assertEqual(colours, {0, 1})

    def test_errors_name_the_problem(self):
        with tempfile.TemporaryDirectory() as d:
            bad = os.path.join(d, "bad.knit")
            with open(bad, "w") as f:
                f.write("KKP\nKX\n")
            r = run(bad, "-o", os.path.join(d, "o.obj"))
            self.assertEqual(r.returncode, 1)
            self.assertIn("bad.knit:2:", r.stderr)
            r = run(SEED, "-o", os.path.join(d, "o.obj"), "--r", "0.9")
            self.assertEqual(r.returncode, 2)
            self.assertIn("pass through each other", r.stderr)
            r = run(SEED, "-o", os.path.join(d, "o.obj"), "--tiles", "0", "1")
            self.assertEqual(r.returncode, 2)
            r = run(os.path.join(d, "missing.knit"), "-o", os.path.join(d, "o.obj"))
            self.assertEqual(r.returncode, 1)
            self.assertIn("missing.knit", r.stderr)


if __name__ == "__main__":
    unittest.main()

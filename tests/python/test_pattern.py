"""knitshade.Pattern and knitshade.PatternError: the Python binding of knit::Pattern."""
import os
import pathlib
import pickle
import tempfile
import unittest

import numpy as np

import knitshade

SOURCE_DIR = pathlib.Path(os.environ.get("KNIT_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
EXAMPLES = SOURCE_DIR / "examples" / "patterns"
UNKNOWN = " (expected 0-3 or K, P, F, B)"


class FromText(unittest.TestCase):
    def test_properties_and_cells(self):
        p = knitshade.Pattern.from_text("K P F\nB k p\n")
        self.assertEqual((p.rows, p.cols), (2, 3))
        self.assertFalse(p.has_colors)
        self.assertEqual(p.num_colors, 1)
        self.assertEqual([p.stitch(0, c) for c in range(3)], [0, 1, 2])
        self.assertEqual([p.stitch(1, c) for c in range(3)], [3, 0, 1])
        self.assertEqual(p.color(1, 2), 0)

    def test_compact_commas_comments_and_colors(self):
        p = knitshade.Pattern.from_text("# rib\nKKPP\n0,0 , 1,1\ncolours:\n0123\n3 2 1 0\n")
        self.assertTrue(p.has_colors)
        self.assertEqual(p.num_colors, 4)
        np.testing.assert_array_equal(p.codes(), [[0, 0, 1, 1], [0, 0, 1, 1]])
        np.testing.assert_array_equal(p.colors(), [[0, 1, 2, 3], [3, 2, 1, 0]])

    def test_arrays_are_int32_rows_by_cols(self):
        p = knitshade.Pattern.from_text("KPF\nBKP\nKKK\nPPP")
        for a in (p.codes(), p.colors()):
            self.assertEqual(a.dtype, np.int32)
            self.assertEqual(a.shape, (4, 3))
        self.assertEqual(p.codes()[1, 0], 3)
        self.assertFalse(p.colors().any())  # no colour matrix: zeros

    def test_arrays_are_copies(self):
        p = knitshade.Pattern.from_text("KP")
        a = p.codes()
        a[0, 0] = 3
        self.assertEqual(p.stitch(0, 0), 0)

    def test_default_is_one_knit_cell(self):
        p = knitshade.Pattern()
        self.assertEqual((p.rows, p.cols, p.stitch(0, 0)), (1, 1, 0))


class FromRows(unittest.TestCase):
    def test_lists(self):
        p = knitshade.Pattern.from_rows([[0, 1], [2, 3]], colors=[[1, 0], [0, 7]])
        np.testing.assert_array_equal(p.codes(), [[0, 1], [2, 3]])
        self.assertEqual(p.color(1, 1), 7)
        self.assertEqual(p.num_colors, 8)
        self.assertEqual(p, knitshade.Pattern.from_text("K P\nF B\ncolors:\n1 0\n0 7"))

    def test_numpy_and_tuples(self):
        codes = np.array([[0, 1, 1], [1, 0, 0]], dtype=np.int64)
        p = knitshade.Pattern.from_rows(codes, np.zeros((2, 3), dtype=np.uint8))
        q = knitshade.Pattern.from_rows(((0, 1, 1), (1, 0, 0)), [[0, 0, 0], [0, 0, 0]])
        self.assertEqual(p, q)
        self.assertTrue(p.has_colors)

    def test_validation_errors_name_row_and_column(self):
        with self.assertRaises(knitshade.PatternError) as cm:
            knitshade.Pattern.from_rows([[0, 1], [0]])
        e = cm.exception
        self.assertEqual((e.source, e.line, e.column), ("<rows>", 2, 2))
        self.assertEqual(e.message, "stitch row 2 has 1 cells, expected 2 like row 1")
        with self.assertRaises(knitshade.PatternError) as cm:
            knitshade.Pattern.from_rows([[0, 1]], colors=[[0, 256]])
        self.assertEqual(str(cm.exception), "<rows>:1:2: colour index 256 out of range 0..255")
        with self.assertRaises(knitshade.PatternError) as cm:
            knitshade.Pattern.from_rows([[0, 2**70]])
        self.assertEqual((cm.exception.line, cm.exception.column), (1, 2))
        self.assertIn("unknown stitch code", cm.exception.message)

    def test_type_errors(self):
        with self.assertRaisesRegex(TypeError, "stitch row 1, column 2: expected an integer, got float"):
            knitshade.Pattern.from_rows([[0, 1.0]])
        with self.assertRaises(TypeError):
            knitshade.Pattern.from_rows(["KP"])
        with self.assertRaises(TypeError):
            knitshade.Pattern.from_rows(5)
        with self.assertRaisesRegex(TypeError, "colour row 1, column 1"):
            knitshade.Pattern.from_rows([[0]], colors=[["a"]])

    def test_size_limit(self):
        self.assertEqual(knitshade.Pattern.MAX_ROWS, 4096)
        self.assertEqual(knitshade.Pattern.from_rows([[1] * 4096]).cols, 4096)
        with self.assertRaises(knitshade.PatternError) as cm:
            knitshade.Pattern.from_rows([[1] * 4097])
        self.assertEqual(str(cm.exception), "<rows>:1:4097: more than 4096 columns (the limit)")
        with self.assertRaises(knitshade.PatternError):
            knitshade.Pattern.from_rows([[1]] * 4097)


class Errors(unittest.TestCase):
    def test_pattern_error_is_a_value_error_with_position(self):
        self.assertTrue(issubclass(knitshade.PatternError, ValueError))
        with self.assertRaises(ValueError) as cm:
            knitshade.Pattern.from_text("K P\nK X\n", source="rib.knit")
        e = cm.exception
        self.assertIsInstance(e, knitshade.PatternError)
        self.assertEqual((e.source, e.line, e.column), ("rib.knit", 2, 3))
        self.assertEqual(e.message, "unknown stitch code 'X'" + UNKNOWN)
        self.assertEqual(str(e), "rib.knit:2:3: unknown stitch code 'X'" + UNKNOWN)

    def test_default_source_and_positionless_errors(self):
        with self.assertRaises(knitshade.PatternError) as cm:
            knitshade.Pattern.from_text("# nothing\n")
        e = cm.exception
        self.assertEqual((e.source, e.line, e.column), ("<string>", 0, 0))
        self.assertEqual(e.message, "empty pattern (no stitch rows)")

    def test_not_text(self):
        with self.assertRaises(knitshade.PatternError) as cm:
            knitshade.Pattern.from_text("KP\nK\x00")
        self.assertEqual((cm.exception.line, cm.exception.column), (2, 2))
        self.assertEqual(cm.exception.message, "input is not text (NUL byte)")

    def test_index_error_outside_the_pattern(self):
        p = knitshade.Pattern.from_text("KP\nPK")
        for r, c in ((2, 0), (0, 2), (-1, 0), (0, -1)):
            with self.assertRaises(IndexError):
                p.stitch(r, c)
            with self.assertRaises(IndexError):
                p.color(r, c)


class Files(unittest.TestCase):
    def test_examples_load_with_str_and_pathlib(self):
        p = knitshade.Pattern.from_file(str(EXAMPLES / "rib_2x2.knit"))
        self.assertEqual((p.rows, p.cols), (4, 8))
        self.assertEqual(p, knitshade.Pattern.from_file(EXAMPLES / "rib_2x2.knit"))
        blocks = knitshade.Pattern.from_file(EXAMPLES / "diamond_blocks_2colour.knit")
        self.assertEqual((blocks.rows, blocks.cols, blocks.num_colors), (48, 48, 2))
        self.assertEqual(set(np.unique(blocks.colors())), {0, 1})

    def test_every_example_round_trips(self):
        files = sorted(EXAMPLES.glob("*.knit"))
        self.assertGreaterEqual(len(files), 12)
        for f in files:
            p = knitshade.Pattern.from_file(f)
            self.assertEqual(knitshade.Pattern.from_text(p.to_text()), p, f.name)

    def test_missing_file_names_path_and_os_error(self):
        path = str(EXAMPLES / "no-such-pattern.knit")
        with self.assertRaises(knitshade.PatternError) as cm:
            knitshade.Pattern.from_file(path)
        e = cm.exception
        self.assertEqual((e.source, e.line, e.column), (path, 0, 0))
        self.assertEqual(e.message, f"cannot open pattern file '{path}': No such file or directory")

    def test_file_errors_name_the_file(self):
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "bad.knit")
            with open(path, "w") as f:
                f.write("KP\ncolors:\n0\n")
            with self.assertRaises(knitshade.PatternError) as cm:
                knitshade.Pattern.from_file(path)
        self.assertEqual(str(cm.exception),
                         f"{path}:3:2: colour row has 1 cells, expected 2 like the pattern")


class Value(unittest.TestCase):
    def test_to_text_is_canonical_and_round_trips(self):
        p = knitshade.Pattern.from_text("kpfb\ncolors:\n0,1,2,30")
        self.assertEqual(p.to_text(), "K P F B\ncolors:\n0 1 2 30\n")
        self.assertEqual(knitshade.Pattern.from_text(p.to_text()), p)

    def test_equality(self):
        a = knitshade.Pattern.from_text("KP")
        self.assertEqual(a, knitshade.Pattern.from_rows([[0, 1]]))
        self.assertNotEqual(a, knitshade.Pattern.from_rows([[1, 0]]))
        self.assertNotEqual(a, knitshade.Pattern.from_rows([[0], [1]]))
        self.assertNotEqual(a, knitshade.Pattern.from_rows([[0, 1]], [[0, 0]]))
        self.assertNotEqual(a, "K P\n")
        self.assertFalse(a == 0)

    def test_repr(self):
        self.assertEqual(repr(knitshade.Pattern.from_text("KP\nPK")),
                         "<knitshade.Pattern 2x2 without colors>")
        self.assertEqual(repr(knitshade.Pattern.from_text("KP\ncolors:\n0 4")),
                         "<knitshade.Pattern 1x2 with 5 colors>")

    def test_pickle(self):
        p = knitshade.Pattern.from_file(EXAMPLES / "stripes_two_colour.knit")
        self.assertEqual(pickle.loads(pickle.dumps(p)), p)

    def test_random_round_trip(self):
        rng = np.random.default_rng(5)
        for _ in range(50):
            rows, cols = rng.integers(1, 30, size=2)
            codes = rng.integers(0, 4, size=(rows, cols))
            colors = rng.integers(0, 256, size=(rows, cols))
            p = knitshade.Pattern.from_rows(codes.tolist(), colors.tolist())
            np.testing.assert_array_equal(p.codes(), codes)
            np.testing.assert_array_equal(p.colors(), colors)
            self.assertEqual(knitshade.Pattern.from_text(p.to_text()), p)


if __name__ == "__main__":
    unittest.main()

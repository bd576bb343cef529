"""The add-on's pattern core (addon/knitshade_blender/core) without bpy and
without the C++ module: parsing and its exact error messages, the limits,
the canonical text and storage forms, every editing operation, and the
presets.

Run with Debian's python3 from this folder:
    /usr/bin/python3 -m unittest -v test_pattern_core
(CTest: addon_core.pattern_core). check_parser_agreement.py compares the
parser with the C++ one through the module.
"""
import os
import pathlib
import pickle
import sys
import tempfile
import types
import unittest

ROOT = pathlib.Path(os.environ.get("KNIT_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
ADDON = ROOT / "addon"


def import_core():
    """knitshade_blender.core without running the add-on's own __init__.py,
    which imports bpy: the package is entered as a bare namespace."""
    if "knitshade_blender" not in sys.modules:
        package = types.ModuleType("knitshade_blender")
        package.__path__ = [str(ADDON / "knitshade_blender")]
        sys.modules["knitshade_blender"] = package
    from knitshade_blender.core import pattern, presets
    return pattern, presets


pattern, presets = import_core()
Pattern = pattern.Pattern
PatternError = pattern.PatternError
parse = pattern.parse_text
EXAMPLES = ROOT / "examples" / "patterns"
UNKNOWN = " (expected 0-3 or K, P, F, B)"
UNKNOWN_VALUE = " (expected 0-3: 0 knit, 1 purl, 2 front, 3 back)"


class ErrorAssertions(unittest.TestCase):
    def assertParseFails(self, text, line, column, message, source="<string>"):
        with self.assertRaises(PatternError) as cm:
            parse(text, source) if source != "<string>" else parse(text)
        e = cm.exception
        where = source + (":%d:%d" % (line, column) if line else "")
        self.assertEqual(str(e), where + ": " + message, repr(text[:60]))
        self.assertEqual((e.source, e.line, e.column, e.message), (source, line, column, message))

    def assertEditFails(self, call, message):
        with self.assertRaises(PatternError) as cm:
            call()
        self.assertEqual(str(cm.exception), message)


class Parse(ErrorAssertions):
    def test_cells_rows_and_properties(self):
        p = parse("K P F\nB k p\n")
        self.assertEqual((p.rows, p.cols), (2, 3))
        self.assertEqual(p.codes, (0, 1, 2, 3, 0, 1))
        self.assertIsNone(p.colors)
        self.assertFalse(p.has_colors)
        self.assertEqual(p.num_colors, 1)
        self.assertEqual(p.stitch(1, 0), 3)
        self.assertEqual(p.color(1, 2), 0)
        self.assertEqual(p.colors_or_zero(), (0,) * 6)

    def test_compact_commas_comments_and_colours(self):
        p = parse("# rib\nKKPP\n0,0 , 1,1 # same row\ncolours:\n0123\n3 2 1 0\n")
        self.assertEqual(p.code_rows(), [[0, 0, 1, 1], [0, 0, 1, 1]])
        self.assertEqual(p.color_rows(), [[0, 1, 2, 3], [3, 2, 1, 0]])
        self.assertTrue(p.has_colors)
        self.assertEqual(p.num_colors, 4)

    def test_line_ends_bom_and_spaces(self):
        want = parse("K P\nP K\n")
        self.assertEqual(parse("K P\r\nP K\r\n"), want)
        self.assertEqual(parse(b"\xef\xbb\xbfK P\nP K"), want)
        self.assertEqual(parse("\ufeffK\tP\n\vP\fK\r"), want)
        self.assertEqual(parse("K, P,\n  P ,K  # trailing comma and spaces\n\n"), want)

    def test_colour_header_spellings(self):
        for header in ("colors:", "COLOURS:", "Colors:   # comment", "  colours:"):
            p = parse("KP\n%s\n0 1\n" % header)
            self.assertEqual(p.colors, (0, 1), header)

    def test_colour_index_forms(self):
        p = parse("KKKK\ncolors:\n+5 007 -0 255\n")
        self.assertEqual(p.colors, (5, 7, 0, 255))
        self.assertEqual(p.num_colors, 256)

    def test_one_column_colour_rows_are_one_index(self):
        p = parse("K\nP\ncolors:\n12\n3\n")
        self.assertEqual(p.colors, (12, 3))
        # with two columns the same line is two single digits
        self.assertEqual(parse("KP\ncolors:\n12\n").colors, (1, 2))

    def test_source_name(self):
        self.assertParseFails("Q", 1, 1, "unknown stitch code 'Q'" + UNKNOWN,
                              source="patterns/rib.knit")
        self.assertParseFails("Q", 1, 1, "unknown stitch code 'Q'" + UNKNOWN)

    def test_str_and_bytes_agree(self):
        text = "# é ✓\nK P\ncolors:\n1 2\n"
        self.assertEqual(parse(text), parse(text.encode("utf-8")))
        with self.assertRaises(TypeError):
            parse(12)


class ParseErrors(ErrorAssertions):
    """The messages of tests/native/test_pattern_errors.cpp, to the byte."""

    def test_ragged_rows(self):
        msg = "row has %d cells, expected %d like the first row (line %d)"
        self.assertParseFails("K P\nK P K\n", 2, 5, msg % (3, 2, 1))
        self.assertParseFails("# c\n\nKPK\nKPK\nKP\n", 5, 3, msg % (2, 3, 3))
        self.assertParseFails("K,P\nKPP\n", 2, 3, msg % (3, 2, 1))

    def test_unknown_codes(self):
        self.assertParseFails("K P\nK X\n", 2, 3, "unknown stitch code 'X'" + UNKNOWN)
        self.assertParseFails("0 4", 1, 3, "unknown stitch code '4'" + UNKNOWN)
        self.assertParseFails("K PP K", 1, 3, "unknown stitch code 'PP'" + UNKNOWN)
        self.assertParseFails("K, é", 1, 4, "unknown stitch code 'é'" + UNKNOWN)
        self.assertParseFails("colors : x", 1, 1, "unknown stitch code 'colors'" + UNKNOWN)
        self.assertParseFails("KKXK", 1, 3, "unknown stitch code 'X'" + UNKNOWN)
        self.assertParseFails("Kä", 1, 2, "unknown stitch code 'ä'" + UNKNOWN)
        self.assertParseFails("colors", 1, 1, "unknown stitch code 'c'" + UNKNOWN)
        # the Kelvin sign is not a K (str.lower() would say it is)
        self.assertParseFails("K\u212a", 1, 2, "unknown stitch code '\u212a'" + UNKNOWN)
        self.assertParseFails("K " + "x" * 100, 1, 3,
                              "unknown stitch code '" + "x" * 24 + "...'" + UNKNOWN)

    def test_commas(self):
        self.assertParseFails("K,,P", 1, 3, "empty cell (two commas in a row)")
        self.assertParseFails("K, ,P", 1, 4, "empty cell (two commas in a row)")
        self.assertParseFails("KP\n ,K", 2, 2, "empty cell (a comma with no cell before it)")
        self.assertParseFails(",", 1, 1, "empty cell (a comma with no cell before it)")
        self.assertParseFails("K,P,,", 1, 5, "empty cell (two commas in a row)")

    def test_empty(self):
        for text in ("", "\n\n   \n", "# only a comment\n# K P\n", b"\xef\xbb\xbf"):
            self.assertParseFails(text, 0, 0, "empty pattern (no stitch rows)")

    def test_colour_matrix_shape(self):
        self.assertParseFails("KP\nPK\ncolors:\n0 1\n", 3, 1,
                              "colour matrix has 1 rows, expected 2 like the pattern")
        self.assertParseFails("KP\n\n  colors:\n", 3, 1,
                              "colour matrix has 0 rows, expected 1 like the pattern")
        self.assertParseFails("KP\ncolors:\n0 1\n  1 0\n", 4, 3,
                              "colour matrix has more rows than the pattern (1)")
        self.assertParseFails("KP\ncolors:\n0 1\nK P\n", 4, 1,
                              "colour matrix has more rows than the pattern (1)")
        self.assertParseFails("KP\ncolors:\n0 1 1\n", 3, 5,
                              "colour row has 3 cells, expected 2 like the pattern")
        self.assertParseFails("KPK\nPKP\ncolors:\n0 1 0\n01\n", 5, 3,
                              "colour row has 2 cells, expected 3 like the pattern")

    def test_colour_indices(self):
        self.assertParseFails("KP\ncolors:\n0 256", 3, 3, "colour index '256' out of range 0..255")
        self.assertParseFails("KP\ncolors:\n-1,0", 3, 1, "colour index '-1' out of range 0..255")
        self.assertParseFails("KP\ncolors:\n0 99999999999999999999999", 3, 3,
                              "colour index '99999999999999999999999' out of range 0..255")
        self.assertParseFails("KP\ncolors:\n0 a", 3, 3, "colour index 'a' is not an integer")
        self.assertParseFails("KP\ncolors:\n1.5 0", 3, 1, "colour index '1.5' is not an integer")
        self.assertParseFails("KP\ncolors:\n0 +", 3, 3, "colour index '+' is not an integer")
        self.assertParseFails("KPK\ncolors:\n0k1", 3, 2, "colour index 'k' is not an integer")
        self.assertParseFails("K\ncolors:\nK", 3, 1, "colour index 'K' is not an integer")
        # a digit that is not ASCII is not a digit to the C++ parser
        self.assertParseFails("K\ncolors:\n\u0663", 3, 1, "colour index '\u0663' is not an integer")
        # ten thousand digits: out of range, not Python's int() digit limit
        self.assertParseFails("K\ncolors:\n" + "9" * 10000, 3, 1,
                              "colour index '" + "9" * 24 + "...' out of range 0..255")

    def test_colour_headers(self):
        self.assertParseFails("# no rows yet\n  colors:\n0\n", 2, 3,
                              "colour section without a pattern (no stitch rows before it)")
        self.assertParseFails("K\ncolors:\n0\nColours:\n0\n", 4, 1,
                              "second colour section (the first is at line 2)")
        self.assertParseFails(
            "K\ncolors: 0\n", 2, 8,
            "unexpected text after 'colors:' (the colour matrix starts on the next line)")
        self.assertParseFails(
            "K\nCOLOURS:0\n", 2, 9,
            "unexpected text after 'COLOURS:' (the colour matrix starts on the next line)")

    def test_not_text(self):
        self.assertParseFails(b"K\x00P", 1, 2, "input is not text (NUL byte)")
        self.assertParseFails(b"KP\n# \xff", 2, 3, "input is not text (invalid UTF-8 byte 0xFF)")
        self.assertParseFails(b"K\x01", 1, 2, "input is not text (control byte 0x01)")
        self.assertParseFails(b"K\x7f", 1, 2, "input is not text (control byte 0x7F)")
        self.assertParseFails(b"KP\xc3", 1, 3, "input is not text (invalid UTF-8 byte 0xC3)")
        self.assertParseFails(b"\xc0\xaf", 1, 1, "input is not text (invalid UTF-8 byte 0xC0)")
        self.assertParseFails(b"\xed\xa0\x80", 1, 1, "input is not text (invalid UTF-8 byte 0xED)")
        self.assertParseFails(b"\xf4\x90\x80\x80", 1, 1,
                              "input is not text (invalid UTF-8 byte 0xF4)")
        self.assertParseFails(b"X\n\n\x02", 3, 1, "input is not text (control byte 0x02)")
        # the column counts code points; the first bad byte wins over later ones
        self.assertParseFails("K # é ✓\x01", 1, 8, "input is not text (control byte 0x01)")
        self.assertParseFails(b"K\xe2\x82\x01\x00", 1, 2,
                              "input is not text (invalid UTF-8 byte 0xE2)")
        self.assertParseFails(b"\xef\xbb\xbfK X", 1, 3, "unknown stitch code 'X'" + UNKNOWN)
        # a lone surrogate in a str is the bytes the C++ parser would refuse
        self.assertParseFails("K\ud800", 1, 2, "input is not text (invalid UTF-8 byte 0xED)")


class Limits(ErrorAssertions):
    def test_rows(self):
        ok = "KP\n" * 4096
        self.assertEqual(parse(ok).rows, 4096)
        self.assertParseFails("# header\n" + ok + "PK\n", 4098, 1,
                              "more than 4096 rows (the limit)")

    def test_columns(self):
        self.assertEqual(parse("K" * 4096).cols, 4096)
        msg = "row has more than 4096 cells (the limit)"
        self.assertParseFails("K" * 4097, 1, 4097, msg)
        sep = "P " * 4097
        self.assertParseFails(sep, 1, 8193, msg)
        self.assertEqual(parse(sep[:2 * 4096]).cols, 4096)
        self.assertParseFails("F" * (1 << 20), 1, 4097, msg)
        self.assertParseFails("K" * 4096 + "\ncolors:\n" + "1" * 4097, 3, 4097, msg)
        # a comma error after the 4097th cell comes first, as in C++
        self.assertParseFails("K " * 4096 + "K,,", 1, 8195, "empty cell (two commas in a row)")

    def test_input_size(self):
        big = b" " * ((128 << 20) + 1)
        self.assertParseFails(big, 0, 0, "input is 134217729 bytes, more than the 128 MiB limit")
        self.assertParseFails(big[:-1], 0, 0, "empty pattern (no stitch rows)")


class Files(ErrorAssertions):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name

    def tearDown(self):
        self.tmp.cleanup()

    def test_reads_a_file(self):
        path = os.path.join(self.dir, "ok.knit")
        with open(path, "w") as f:
            f.write("# 1x1 rib\nK P\nK P\n")
        self.assertEqual(pattern.load(path), Pattern.from_rows([[0, 1], [0, 1]]))
        self.assertEqual(pattern.load(pathlib.Path(path)), Pattern.from_rows([[0, 1], [0, 1]]))

    def test_errors_name_the_path(self):
        path = os.path.join(self.dir, "bad.knit")
        with open(path, "w") as f:
            f.write("K P\nK Z\n")
        with self.assertRaises(PatternError) as cm:
            pattern.load(path)
        self.assertEqual(str(cm.exception), path + ":2:3: unknown stitch code 'Z'" + UNKNOWN)

    def test_missing_file_and_directory(self):
        path = os.path.join(self.dir, "does-not-exist.knit")
        self.assertEditFails(lambda: pattern.load(path),
                             "%s: cannot open pattern file '%s': No such file or directory"
                             % (path, path))
        self.assertEditFails(lambda: pattern.load(self.dir),
                             "%s: cannot read pattern file '%s': Is a directory"
                             % (self.dir, self.dir))

    def test_oversized_file(self):
        path = os.path.join(self.dir, "huge.knit")
        with open(path, "w") as f:
            f.write("K\n")
        os.truncate(path, (128 << 20) + 4096)  # sparse
        self.assertEditFails(lambda: pattern.load(path),
                             "%s: pattern file '%s' is larger than the 128 MiB limit"
                             % (path, path))


class Construction(ErrorAssertions):
    def test_default_and_codes(self):
        self.assertEqual(Pattern(), Pattern(1, 1, [0]))
        p = Pattern(2, 2, [0, 1, 2, 3], [0, 0, 0, 9])
        self.assertEqual((p.stitch(1, 1), p.color(1, 1), p.num_colors), (3, 9, 10))
        self.assertEqual(Pattern(2, 3).codes, (0,) * 6)
        self.assertIsNone(Pattern(1, 2, [0, 1], []).colors)  # empty: no colour matrix

    def test_constructor_errors(self):
        self.assertEditFails(lambda: Pattern(0, 3), "<pattern>: empty pattern (0x3)")
        self.assertEditFails(lambda: Pattern(4097, 1),
                             "<pattern>: pattern has 4097 rows, more than 4096 (the limit)")
        self.assertEditFails(lambda: Pattern(1, 10**9),
                             "<pattern>: pattern has 1000000000 columns, "
                             "more than 4096 (the limit)")
        self.assertEditFails(lambda: Pattern(2, 2, [0, 1, 0]),
                             "<pattern>: code array has 3 entries, expected 4 for a 2x2 pattern")
        self.assertEditFails(lambda: Pattern(2, 2, [0] * 4, [1]),
                             "<pattern>: colour array has 1 entries, expected 4 for a 2x2 pattern")
        self.assertEditFails(lambda: Pattern(2, 2, [0, 0, 0, 7]),
                             "<pattern>:2:2: unknown stitch code 7" + UNKNOWN_VALUE)
        self.assertEditFails(lambda: Pattern(1, 2, [0, 0], [0, 300]),
                             "<pattern>:1:2: colour index 300 out of range 0..255")
        with self.assertRaises(TypeError):
            Pattern(1, 1, ["K"])

    def test_from_rows(self):
        p = Pattern.from_rows([[0, 1], [2, 3]], colors=[[1, 0], [0, 7]])
        self.assertEqual(p, parse("K P\nF B\ncolors:\n1 0\n0 7"))
        self.assertIsNone(Pattern.from_rows([[0]], colors=[]).colors)
        self.assertEditFails(lambda: Pattern.from_rows([]),
                             "<rows>: empty pattern (no rows or an empty first row)")
        self.assertEditFails(lambda: Pattern.from_rows([[], [0]]),
                             "<rows>: empty pattern (no rows or an empty first row)")
        self.assertEditFails(lambda: Pattern.from_rows([[0, 1], [0]]),
                             "<rows>:2:2: stitch row 2 has 1 cells, expected 2 like row 1")
        self.assertEditFails(lambda: Pattern.from_rows([[0, 1], [0, 1, 1]]),
                             "<rows>:2:3: stitch row 2 has 3 cells, expected 2 like row 1")
        self.assertEditFails(lambda: Pattern.from_rows([[0, 1], [1, 4]]),
                             "<rows>:2:2: unknown stitch code 4" + UNKNOWN_VALUE)
        self.assertEditFails(lambda: Pattern.from_rows([[0, 1]], colors=[[0, 256]]),
                             "<rows>:1:2: colour index 256 out of range 0..255")
        self.assertEditFails(lambda: Pattern.from_rows([[0], [0]], colors=[[0]]),
                             "<rows>:2:1: colour matrix has 1 rows, expected 2 like the pattern")
        self.assertEditFails(lambda: Pattern.from_rows([[0]] * 4097),
                             "<rows>:4097:1: more than 4096 rows (the limit)")
        self.assertEditFails(lambda: Pattern.from_rows([[0] * 4097]),
                             "<rows>:1:4097: more than 4096 columns (the limit)")
        with self.assertRaises(TypeError) as cm:
            Pattern.from_rows([[0, "K"]])
        self.assertEqual(str(cm.exception), "stitch row 1, column 2: expected an integer, got str")

    def test_cell_access_out_of_range(self):
        p = parse("KP\nPK")
        for r, c in ((2, 0), (0, 2), (-1, 0), (0, -1)):
            with self.assertRaises(IndexError):
                p.stitch(r, c)
            with self.assertRaises(IndexError):
                p.color(r, c)

    def test_patterns_are_values(self):
        p = parse("KP")
        with self.assertRaises(AttributeError):
            p.rows = 3
        with self.assertRaises(TypeError):
            p.codes[0] = 1


class TextForms(unittest.TestCase):
    CASES = [
        "K P F B\nB F P K\n",
        "KKPP\nPPKK\ncolors:\n0 1 2 3\n3 2 1 0\n",
        "K\nP\nF\ncolors:\n12\n0\n255\n",  # one column, indices above 9
        "KP\ncolors:\n0 0\n",  # an explicit all-zero matrix
        "K",
        "KPFB\ncolors:\n10 11 12 200\n",
    ]

    def test_canonical_text(self):
        p = parse("# x\nkpfb\n0,1,2,3\ncolours:\n0 1 2 3\n12 0 0 0\n")
        self.assertEqual(p.to_text(), "K P F B\nK P F B\ncolors:\n0 1 2 3\n12 0 0 0\n")
        self.assertEqual(parse("KP\nPK").to_text(), "K P\nP K\n")

    def test_round_trips(self):
        for text in self.CASES:
            p = parse(text)
            canonical = p.to_text()
            self.assertEqual(parse(canonical), p, text)
            self.assertEqual(parse(canonical).to_text(), canonical, text)  # a fixed point
            self.assertEqual(Pattern.from_storage(p.to_storage()), p, text)
            self.assertEqual(pickle.loads(pickle.dumps(p)), p, text)

    def test_storage_is_compact(self):
        p = parse("KPFB\nBFPK\ncolors:\n0123\n3210\n")
        self.assertEqual(p.to_storage(), "KPFB\nBFPK\ncolors:\n0123\n3210\n")
        self.assertEqual(parse("KP\ncolors:\n0 10").to_storage(), "KP\ncolors:\n0 10\n")
        self.assertEqual(parse("K\ncolors:\n7").to_storage(), "K\ncolors:\n7\n")

    def test_equality(self):
        self.assertEqual(parse("K P"), parse("0,1"))
        self.assertNotEqual(parse("K P"), parse("K P\ncolors:\n0 0"))  # zeros are not "none"
        self.assertNotEqual(parse("K P"), parse("K\nP"))
        self.assertNotEqual(parse("K P"), "K P\n")
        self.assertEqual(hash(parse("K P")), hash(parse("0 1")))
        self.assertEqual(parse("K\ncolors:\n0").num_colors, 1)

    def test_error_pickles(self):
        e = PatternError("f.knit", 2, 3, "oops")
        e2 = pickle.loads(pickle.dumps(e))
        self.assertEqual((str(e2), e2.line, e2.column, e2.message),
                         ("f.knit:2:3: oops", 2, 3, "oops"))
        self.assertEqual(str(PatternError("s", 4, 0, "m")), "s:4: m")
        self.assertIsInstance(e, ValueError)


class Edits(ErrorAssertions):
    def setUp(self):
        # 3 rows x 4 columns, colours 0..11 row-major
        self.p = parse("K P F B\nP K B F\nK K P P\ncolors:\n0 1 2 3\n4 5 6 7\n8 9 10 11\n")
        self.plain = parse("KPFB\nPKBF\nKKPP")

    def test_with_stitch(self):
        q = self.p.with_stitch(1, 2, "p")
        self.assertEqual(q.stitch(1, 2), 1)
        self.assertEqual(self.p.stitch(1, 2), 3)  # the original is untouched
        self.assertEqual(q.colors, self.p.colors)
        self.assertEqual(self.p.with_stitch(0, 0, 3).stitch(0, 0), 3)
        self.assertEqual(self.p.with_stitch(0, 0, "F").with_stitch(0, 0, 0), self.p)
        self.assertEditFails(lambda: self.p.with_stitch(3, 0, 0),
                             "with_stitch: cell (3, 0) is outside the 3x4 pattern "
                             "(rows 0..2, columns 0..3)")
        self.assertEditFails(lambda: self.p.with_stitch(0, -1, 0),
                             "with_stitch: cell (0, -1) is outside the 3x4 pattern "
                             "(rows 0..2, columns 0..3)")
        self.assertEditFails(lambda: self.p.with_stitch(0, 0, 4),
                             "with_stitch: unknown stitch code 4" + UNKNOWN_VALUE)
        self.assertEditFails(lambda: self.p.with_stitch(0, 0, "X"),
                             "with_stitch: unknown stitch code 'X'" + UNKNOWN)

    def test_cycled(self):
        q = self.p
        seen = []
        for _ in range(4):
            q = q.cycled(2, 3)
            seen.append(q.stitch(2, 3))
        self.assertEqual(seen, [2, 3, 0, 1])  # P -> F -> B -> K -> P
        self.assertEqual(q, self.p)
        self.assertEqual(parse("K").cycled(0, 0).to_text(), "P\n")
        self.assertEditFails(lambda: self.p.cycled(0, 4),
                             "cycled: cell (0, 4) is outside the 3x4 pattern "
                             "(rows 0..2, columns 0..3)")

    def test_with_color(self):
        q = self.plain.with_color(2, 1, 5)
        self.assertTrue(q.has_colors)
        self.assertEqual(q.color_rows(), [[0] * 4, [0] * 4, [0, 5, 0, 0]])
        self.assertEqual(q.num_colors, 6)
        self.assertTrue(self.plain.with_color(0, 0, 0).has_colors)  # explicit colour: a matrix
        self.assertEqual(self.p.with_color(0, 0, 255).num_colors, 256)
        self.assertEditFails(lambda: self.p.with_color(0, 0, 256),
                             "with_color: colour index 256 out of range 0..255")
        self.assertEditFails(lambda: self.p.with_color(0, 0, -1),
                             "with_color: colour index -1 out of range 0..255")
        self.assertEqual(q.without_colors(), self.plain)

    def test_filled(self):
        self.assertEqual(self.p.filled(stitch="K").codes, (0,) * 12)
        self.assertEqual(self.p.filled(stitch="K").colors, self.p.colors)
        q = self.p.filled(stitch=1, color=20, rect=(1, 1, 2, 2))
        self.assertEqual(q.code_rows(), [[0, 1, 2, 3], [1, 1, 1, 2], [0, 1, 1, 1]])
        self.assertEqual(q.color_rows(), [[0, 1, 2, 3], [4, 20, 20, 7], [8, 20, 20, 11]])
        c = self.plain.filled(color=3, rect=(0, 3, 3, 1))
        self.assertEqual(c.codes, self.plain.codes)
        self.assertEqual(c.color_rows(), [[0, 0, 0, 3]] * 3)
        self.assertEditFails(lambda: self.p.filled(),
                             "filled: nothing to fill: give a stitch, a colour or both")
        self.assertEditFails(lambda: self.p.filled(stitch=0, rect=(2, 2, 2, 1)),
                             "filled: rectangle of 2x1 cells at (2, 2) "
                             "is not inside the 3x4 pattern")
        self.assertEditFails(lambda: self.p.filled(stitch=0, rect=(0, 0, 0, 1)),
                             "filled: rectangle of 0x1 cells at (0, 0) "
                             "is not inside the 3x4 pattern")
        self.assertEditFails(lambda: self.p.filled(color=999),
                             "filled: colour index 999 out of range 0..255")

    def test_shifted(self):
        q = self.p.shifted(1, 0)  # one column to the right
        self.assertEqual(q.code_rows()[0], [3, 0, 1, 2])
        self.assertEqual(q.color_rows()[0], [3, 0, 1, 2])
        q = self.p.shifted(0, 1)  # one row down: the bottom row comes to the top
        self.assertEqual(q.code_rows(), [[0, 0, 1, 1], [0, 1, 2, 3], [1, 0, 3, 2]])
        self.assertEqual(q.color_rows()[0], [8, 9, 10, 11])
        self.assertEqual(self.p.shifted(4, 3), self.p)
        self.assertEqual(self.p.shifted(-5, 7), self.p.shifted(3, 1))
        self.assertEqual(self.p.shifted(2, 1).shifted(-2, -1), self.p)
        self.assertEqual(self.plain.shifted(1, 1).colors, None)
        for dy in range(3):
            for dx in range(4):
                q = self.p.shifted(dx, dy)
                for r in range(3):
                    for c in range(4):
                        self.assertEqual(q.stitch((r + dy) % 3, (c + dx) % 4), self.p.stitch(r, c))

    def test_mirrored_and_flipped(self):
        m = self.p.mirrored()
        self.assertEqual(m.code_rows(), [[3, 2, 1, 0], [2, 3, 0, 1], [1, 1, 0, 0]])
        self.assertEqual(m.color_rows()[2], [11, 10, 9, 8])
        self.assertEqual(m.mirrored(), self.p)
        f = self.p.flipped()
        self.assertEqual(f.code_rows(), [[0, 0, 1, 1], [1, 0, 3, 2], [0, 1, 2, 3]])
        self.assertEqual(f.color_rows()[0], [8, 9, 10, 11])
        self.assertEqual(f.flipped(), self.p)
        self.assertIsNone(self.plain.mirrored().colors)
        self.assertIsNone(self.plain.flipped().colors)

    def test_resized(self):
        q = self.p.resized(4, 5)
        self.assertEqual(q.code_rows(), [[0, 1, 2, 3, 0], [1, 0, 3, 2, 0], [0, 0, 1, 1, 0],
                                         [0] * 5])
        self.assertEqual(q.color_rows()[3], [0] * 5)
        self.assertEqual(q.color_rows()[1], [4, 5, 6, 7, 0])
        s = self.p.resized(2, 2)
        self.assertEqual(s.code_rows(), [[0, 1], [1, 0]])
        self.assertEqual(s.color_rows(), [[0, 1], [4, 5]])
        self.assertEqual(self.p.resized(3, 4), self.p)
        self.assertEqual(self.p.resized(5, 7).resized(3, 4), self.p)
        self.assertIsNone(self.plain.resized(1, 1).colors)
        self.assertEqual(parse("K").resized(4096, 1).rows, 4096)
        self.assertEqual(parse("K").resized(1, 4096).cols, 4096)
        self.assertEditFails(lambda: self.p.resized(0, 4),
                             "resized: rows 0 out of range 1..4096 (the limit)")
        self.assertEditFails(lambda: self.p.resized(4097, 4),
                             "resized: rows 4097 out of range 1..4096 (the limit)")
        self.assertEditFails(lambda: self.p.resized(1, 5000),
                             "resized: columns 5000 out of range 1..4096 (the limit)")

    def test_rows_inserted_and_removed(self):
        q = self.p.with_row_inserted(1, "P", color=9)
        self.assertEqual(q.rows, 4)
        self.assertEqual(q.code_rows()[1], [1] * 4)
        self.assertEqual(q.color_rows()[1], [9] * 4)
        self.assertEqual(q.color_rows()[2], [4, 5, 6, 7])
        self.assertEqual(q.with_row_removed(1), self.p)
        self.assertEqual(self.p.with_row_inserted(3).code_rows()[3], [0] * 4)  # at the bottom
        self.assertEqual(self.p.with_row_inserted(0).color_rows()[0], [0] * 4)
        self.assertIsNone(self.plain.with_row_inserted(0).colors)  # no colour: none added
        self.assertEqual(self.plain.with_row_inserted(0, color=2).color_rows()[0], [2] * 4)
        self.assertEqual(self.p.with_row_removed(0).code_rows(), self.p.code_rows()[1:])
        self.assertEqual(self.p.with_row_removed(2).color_rows(), self.p.color_rows()[:2])
        self.assertEditFails(lambda: self.p.with_row_inserted(4),
                             "with_row_inserted: row index 4 out of range 0..3")
        self.assertEditFails(lambda: self.p.with_row_removed(3),
                             "with_row_removed: row index 3 out of range 0..2")
        self.assertEditFails(lambda: parse("KP").with_row_removed(0),
                             "with_row_removed: cannot remove the only row "
                             "(a pattern has at least one)")
        full = parse("K").resized(4096, 1)
        self.assertEditFails(lambda: full.with_row_inserted(0),
                             "with_row_inserted: the pattern already has 4096 rows (the limit)")

    def test_columns_inserted_and_removed(self):
        q = self.p.with_col_inserted(2, "B")
        self.assertEqual(q.cols, 5)
        self.assertEqual(q.code_rows()[0], [0, 1, 3, 2, 3])
        self.assertEqual(q.color_rows()[2], [8, 9, 0, 10, 11])
        self.assertEqual(q.with_col_removed(2), self.p)
        self.assertEqual(self.p.with_col_inserted(4).code_rows()[1], [1, 0, 3, 2, 0])
        self.assertIsNone(self.plain.with_col_inserted(0).colors)
        self.assertEqual(self.plain.with_col_inserted(0, color=1).color_rows()[1], [1, 0, 0, 0, 0])
        self.assertEqual(self.p.with_col_removed(0).code_rows()[0], [1, 2, 3])
        self.assertEqual(self.p.with_col_removed(3).color_rows()[1], [4, 5, 6])
        self.assertEditFails(lambda: self.p.with_col_inserted(-1),
                             "with_col_inserted: column index -1 out of range 0..4")
        self.assertEditFails(lambda: self.p.with_col_removed(4),
                             "with_col_removed: column index 4 out of range 0..3")
        self.assertEditFails(lambda: parse("K\nP").with_col_removed(0),
                             "with_col_removed: cannot remove the only column "
                             "(a pattern has at least one)")
        full = parse("K" * 4096)
        self.assertEditFails(lambda: full.with_col_inserted(4096),
                             "with_col_inserted: the pattern already has 4096 columns (the limit)")
        self.assertEditFails(lambda: self.p.with_col_inserted(0, color=256),
                             "with_col_inserted: colour index 256 out of range 0..255")

    def test_edits_round_trip_through_text(self):
        p = self.p
        edits = [p.with_stitch(0, 0, "B"), p.cycled(1, 1), p.with_color(2, 3, 200),
                 p.filled(stitch="F", rect=(0, 0, 1, 4)), p.shifted(3, 2), p.mirrored(),
                 p.flipped(), p.resized(1, 1), p.resized(6, 9), p.with_row_inserted(2),
                 p.with_row_removed(1), p.with_col_inserted(1, "P", 3), p.with_col_removed(0),
                 self.plain.with_col_inserted(2), self.plain.with_color(0, 0, 0)]
        for q in edits:
            self.assertEqual(parse(q.to_text()), q)
            self.assertEqual(Pattern.from_storage(q.to_storage()), q)


class Presets(unittest.TestCase):
    def test_pattern_presets_are_the_examples(self):
        items = presets.pattern_presets()
        files = sorted(f[:-5] for f in os.listdir(EXAMPLES) if f.endswith(".knit"))
        self.assertEqual([i[0] for i in items], files)
        self.assertEqual(pathlib.Path(presets.patterns_dir()).resolve(), EXAMPLES.resolve())
        for identifier, name, description in items:
            self.assertTrue(name and description, identifier)
            self.assertEqual(presets.load_preset(identifier),
                             pattern.load(EXAMPLES / (identifier + ".knit")))
        by_id = {i[0]: i for i in items}
        self.assertEqual(by_id["rib_2x2"][1:],
                         ("Rib 2x2", "2x2 rib: knit 2, purl 2, stacked in columns."))
        # a sentence wrapped over two comment lines is read whole
        self.assertTrue(by_id["linen_stitch"][2].endswith("plain knit rows between."))

    def test_preset_shapes(self):
        self.assertEqual((presets.load_preset("rib_2x2").rows,
                          presets.load_preset("rib_2x2").cols), (4, 8))
        d = presets.load_preset("diamond_blocks_2colour")
        self.assertEqual((d.rows, d.cols, d.num_colors), (48, 48, 2))

    def test_unknown_preset(self):
        with self.assertRaises(PatternError) as cm:
            presets.load_preset("../../etc/passwd")
        self.assertIn("no pattern preset '../../etc/passwd' (the presets: basketweave,",
                      str(cm.exception))

    def test_yarn_weights(self):
        ids = [i[0] for i in presets.yarn_weight_presets()]
        self.assertEqual(ids, ["fingering", "sport", "dk", "worsted", "chunky"])
        weights = [presets.yarn_weight(i) for i in ids]
        for w in weights:
            self.assertTrue(set("a h d r ply_count stitches_per_10cm name description".split())
                            <= set(w))
            self.assertTrue(w["r"] > 0 and w["a"] > 0 and w["h"] > 0 and w["d"] != 0)
            self.assertTrue(1 <= w["ply_count"] <= 16)
            self.assertNotIn("\n", w["description"])
        worsted = presets.yarn_weight("worsted")
        self.assertEqual((worsted["a"], worsted["h"], worsted["d"], worsted["r"],
                          worsted["ply_count"]), (1.5, 4.0, 1.0, 0.65, 3))  # the library defaults
        radii = [w["r"] for w in weights]
        gauges = [w["stitches_per_10cm"] for w in weights]
        self.assertEqual(radii, sorted(radii))  # heavier: thicker relative to the loop
        self.assertEqual(gauges, sorted(gauges, reverse=True))  # heavier: fewer stitches
        presets.yarn_weight("dk")["r"] = 99  # a copy
        self.assertEqual(presets.yarn_weight("dk")["r"], 0.62)
        with self.assertRaises(KeyError):
            presets.yarn_weight("lace")

    def test_gauge(self):
        import math
        self.assertAlmostEqual(presets.uv_scale_for_gauge(18), 2 * math.pi * 180)
        self.assertAlmostEqual(presets.uv_scale_for_gauge(20, metres_per_uv_unit=0.5),
                               2 * math.pi * 100)
        self.assertAlmostEqual(presets.rows_per_10cm(18), 18 * 2 * math.pi / 4.5)
        with self.assertRaises(ValueError):
            presets.uv_scale_for_gauge(0)


if __name__ == "__main__":
    unittest.main()

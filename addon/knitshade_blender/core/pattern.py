"""Knit patterns in pure Python: knit::Pattern, its text format and the edits
the add-on's pattern editor makes.

A pattern is a rectangular matrix of stitch codes, row 0 at the top as
written, with an optional second matrix of the same shape giving a colour
index per cell (docs/patterns.md). Codes: 0 knit (K), 1 purl (P), 2 front
slip (F, float in front), 3 back slip (B, float behind).

This module mirrors the C++ library one for one (native/include/knit/pattern.h,
native/src/pattern.cpp, native/src/pattern_parse.cpp):

- `parse_text` and `load` accept and reject exactly what `Pattern::parse` and
  `Pattern::from_file` accept and reject, and a rejection raises
  `PatternError` whose text is the C++ exception's `what()` to the byte
  ("source:line:column: message"); tests/addon_core/check_parser_agreement.py
  checks this on the fuzz corpus and the examples.
- `Pattern.to_text()` is the C++ canonical form, equality is the C++
  equality (shape, codes, and the colour matrix including whether there is
  one), `num_colors` and `has_colors` as in C++.

Patterns are values: a `Pattern` never changes after it is made. Every edit
(`with_stitch`, `cycled`, `filled`, `shifted`, `resized`, ...) returns a new
pattern and leaves its argument as it was, so an operator computes the new
pattern, stores it (`to_storage()`), and Blender's undo step holds the old
one. Edits that cannot be made raise `PatternError` naming the operation and
the value at fault, with the pattern untouched.
"""

import operator
import os
import re

__all__ = [
    "BACK",
    "FRONT",
    "KNIT",
    "LETTERS",
    "MAX_COLORS",
    "MAX_COLS",
    "MAX_ROWS",
    "MAX_TEXT_BYTES",
    "PURL",
    "Pattern",
    "PatternError",
    "load",
    "parse_text",
]

# Limits, as knit::Pattern::kMaxRows, kMaxCols, kMaxColors, kMaxTextBytes.
MAX_ROWS = 4096
MAX_COLS = 4096
MAX_COLORS = 256
MAX_TEXT_BYTES = 128 << 20  # 128 MiB: parse_text and load read no more

KNIT, PURL, FRONT, BACK = 0, 1, 2, 3
LETTERS = "KPFB"  # LETTERS[code]: the letter to_text() writes

_QUOTE_MAX = 24  # code points quoted from a bad token
_SPACES = " \t\r\v\f"  # what the parser counts as spaces ('\n' ends a line)
_SEPS = _SPACES + ","
_BOM = b"\xef\xbb\xbf"
_UNKNOWN_TOKEN = " (expected 0-3 or K, P, F, B)"
_UNKNOWN_VALUE = " (expected 0-3: 0 knit, 1 purl, 2 front, 3 back)"

# Stitch cells as the parser reads them: one ASCII character, any case.
_CODE_OF = {}
for _code, _chars in enumerate(("0kK", "1pP", "2fF", "3bB")):
    for _ch in _chars:
        _CODE_OF[_ch] = _code
del _code, _chars, _ch

# Colour cells written the plain way ("0".."255"); anything else goes
# through _colour_index, which knows the rest of the rules.
_PLAIN_COLOUR = {str(i): i for i in range(MAX_COLORS)}

# The C++ lower() folds A-Z only; str.lower() would also fold, for instance,
# the Kelvin sign into 'k'.
_ASCII_LOWER = str.maketrans("ABCDEFGHIJKLMNOPQRSTUVWXYZ", "abcdefghijklmnopqrstuvwxyz")

# Bytes that are not text: NUL and the controls other than \t \n \v \f \r.
_CONTROL_BYTE = re.compile(rb"[\x00-\x08\x0e-\x1f\x7f]")
_HAS_SEP = re.compile(r"[ \t\r\v\f,]")
_TWO_COMMAS = re.compile(r",[ \t\r\v\f]*,")
_TOKEN = re.compile(r"[^ \t\r\v\f,]+")


class PatternError(ValueError):
    """A pattern that does not parse, validate or take an edit.

    str(e) reads "source:line:column: message", or "source: message" when
    the error is not tied to a place (line and column 0), as
    knit::PatternError::what(). Attributes `source`, `line`, `column`
    (1-based, 0 when not tied to a position) and `message`, as the
    attributes of knitshade.PatternError. For a parse error `source` is the
    source name or file path; for an edit it is the edit's name
    ("resized", "with_stitch", ...), so an operator can report str(e) as is
    or `e.message` alone.
    """

    def __init__(self, source, line, column, message):
        self.source = source
        self.line = line
        self.column = column
        self.message = message
        super().__init__(_error_text(source, line, column, message))

    def __reduce__(self):
        return (type(self), (self.source, self.line, self.column, self.message))


def _error_text(source, line, column, message):
    # pattern_error_text in pattern.cpp
    at = source
    if line > 0:
        at += ":%d" % line
        if column > 0:
            at += ":%d" % column
    return at + ": " + message


def _quote(token):
    """A token in quotes, cut after 24 code points (quote() in pattern_parse.cpp)."""
    if len(token) > _QUOTE_MAX:
        return "'" + token[:_QUOTE_MAX] + "...'"
    return "'" + token + "'"


def _colour_index(token):
    """The colour index a cell spells, or the message saying why it spells
    none (colour_index() in pattern_parse.cpp: an optional '+' or '-', then
    ASCII digits; "-0" and leading zeros are fine)."""
    sign = token[0] if token[0] in "+-" else ""
    digits = token[len(sign):]
    if not digits or not (digits.isascii() and digits.isdigit()):
        return "colour index " + _quote(token) + " is not an integer"
    significant = digits.lstrip("0")
    # Six digits are enough to know an index is out of range (and int() of a
    # very long digit string is limited in Python 3.11).
    value = int(significant or "0") if len(significant) <= 6 else 10**6
    if sign == "-":
        value = -value
    if value < 0 or value >= MAX_COLORS:
        return "colour index %s out of range 0..%d" % (_quote(token), MAX_COLORS - 1)
    return value


class _Parser:
    """Pattern::parse line by line. Offsets are code points into the current
    line, so an offset plus one is the column the C++ parser reports.

    Every line goes through a fast path (regular expressions and list
    comprehensions) that only decides "no error here" and yields the cells;
    whenever that is not certain, `_split_exact` (a transcription of
    Parser::split) and the row checks find the error the C++ parser reports,
    with its position.
    """

    def __init__(self, data, source):
        self.data = data
        self.source = source
        self.line = ""
        self.line_no = 0
        self.rows = 0
        self.cols = 0
        self.first_line = 0
        self.in_colors = False
        self.colors_line = 0
        self.color_rows = 0
        self.codes = []
        self.colors = []

    def fail(self, offset, message):
        raise PatternError(self.source, self.line_no, offset + 1, message)

    def run(self):
        data = self.data
        if len(data) > MAX_TEXT_BYTES:
            raise PatternError(
                self.source, 0, 0,
                "input is %d bytes, more than the %d MiB limit" % (len(data), MAX_TEXT_BYTES >> 20))
        if data[:3] == _BOM:
            data = data[3:]
        text = self.check_text(data)
        for line_no, line in enumerate(text.split("\n"), 1):
            self.line = line
            self.line_no = line_no
            self.parse_line()
        return self.finish()

    def check_text(self, data):
        """Decodes the input, or rejects it as Parser::check_text does: at the
        first NUL, control byte other than whitespace, or byte that does not
        start a well-formed UTF-8 sequence (Python's strict decoder follows
        RFC 3629 as utf8_len() does, and reports the sequence's first byte)."""
        match = _CONTROL_BYTE.search(data)
        bad = match.start() if match else len(data)
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as e:
            bad = min(bad, e.start)
            text = None
        if bad == len(data):
            return text
        byte = data[bad]
        if byte == 0:
            what = "NUL byte"
        elif byte < 0x80:
            what = "control byte 0x%02X" % byte
        else:
            what = "invalid UTF-8 byte 0x%02X" % byte
        line_start = data.rfind(b"\n", 0, bad) + 1
        self.line_no = data.count(b"\n", 0, bad) + 1
        self.fail(len(data[line_start:bad].decode("utf-8")), "input is not text (" + what + ")")

    def parse_line(self):
        line = self.line
        hash_at = line.find("#")
        content = line if hash_at < 0 else line[:hash_at]
        body = content.strip(_SPACES)
        if not body:
            return  # blank or comment only
        base = len(content) - len(content.lstrip(_SPACES))
        head = body[:8].translate(_ASCII_LOWER)
        if head.startswith("colors:") or head.startswith("colours:"):
            length = 8 if head[4] == "u" else 7
            if len(body) > length:
                self.fail(base + length,
                          "unexpected text after '" + body[:length]
                          + "' (the colour matrix starts on the next line)")
            self.start_colors(base)
            return
        tokens = self.split_fast(body)
        if tokens is None:
            tokens = [text for _, text in self.split_exact(body, base)]
        if self.in_colors:
            self.colour_row(body, base, tokens)
        else:
            self.pattern_row(body, base, tokens)

    def start_colors(self, offset):
        if self.in_colors:
            self.fail(offset, "second colour section (the first is at line %d)" % self.colors_line)
        if self.rows == 0:
            self.fail(offset, "colour section without a pattern (no stitch rows before it)")
        self.in_colors = True
        self.colors_line = self.line_no

    def split_fast(self, body):
        """The cells of a row body when splitting it cannot fail, else None."""
        if _HAS_SEP.search(body):
            # The body starts with no space (stripped); a leading comma or
            # two commas in one run of separators is an error.
            if body[0] == "," or _TWO_COMMAS.search(body):
                return None
            tokens = _TOKEN.findall(body)
        elif self.in_colors and self.cols == 1:
            tokens = [body]  # one column: a colour row is one index
        else:
            tokens = list(body)  # compact: one code point per cell
        return tokens if len(tokens) <= MAX_COLS else None

    def split_exact(self, body, base):
        """Parser::split: (offset in the line, text) per cell, failing where
        the C++ parser fails, in the same order."""
        cells = []
        separated = _HAS_SEP.search(body) is not None
        one_token = self.in_colors and self.cols == 1
        n = len(body)
        i = 0
        while i < n:
            start = i
            if separated or one_token:
                if body[i] == ",":
                    self.fail(base + i, "empty cell (a comma with no cell before it)")
                while i < n and body[i] not in _SEPS:
                    i += 1
                commas = 0
                while i < n and body[i] in _SEPS:
                    if body[i] == ",":
                        commas += 1
                        if commas > 1:
                            self.fail(base + i, "empty cell (two commas in a row)")
                    i += 1
            else:
                i += 1
            if len(cells) == MAX_COLS:
                self.fail(base + start, "row has more than %d cells (the limit)" % MAX_COLS)
            end = start
            while end < i and body[end] not in _SEPS:
                end += 1
            cells.append((base + start, body[start:end]))
        return cells

    def check_count(self, body, base, tokens, what, like):
        want = self.cols
        if len(tokens) == want:
            return
        cells = self.split_exact(body, base)
        if len(cells) > want:
            offset = cells[want][0]
        else:
            offset = cells[-1][0] + len(cells[-1][1])
        self.fail(offset, "%s has %d cells, expected %d %s" % (what, len(cells), want, like))

    def pattern_row(self, body, base, tokens):
        if self.rows == MAX_ROWS:
            self.fail(base, "more than %d rows (the limit)" % MAX_ROWS)
        if self.rows == 0:
            self.cols = len(tokens)
            self.first_line = self.line_no
        self.check_count(body, base, tokens, "row",
                         "like the first row (line %d)" % self.first_line)
        codes = list(map(_CODE_OF.get, tokens))
        if None in codes:
            k = codes.index(None)
            offset, text = self.split_exact(body, base)[k]
            self.fail(offset, "unknown stitch code " + _quote(text) + _UNKNOWN_TOKEN)
        self.codes.extend(codes)
        self.rows += 1

    def colour_row(self, body, base, tokens):
        if self.color_rows == self.rows:
            self.fail(base, "colour matrix has more rows than the pattern (%d)" % self.rows)
        self.check_count(body, base, tokens, "colour row", "like the pattern")
        values = list(map(_PLAIN_COLOUR.get, tokens))
        if None in values:
            for k, token in enumerate(tokens):
                if values[k] is None:
                    value = _colour_index(token)
                    if isinstance(value, str):
                        self.fail(self.split_exact(body, base)[k][0], value)
                    values[k] = value
        self.colors.extend(values)
        self.color_rows += 1

    def finish(self):
        if self.rows == 0:
            raise PatternError(self.source, 0, 0, "empty pattern (no stitch rows)")
        if self.in_colors and self.color_rows != self.rows:
            raise PatternError(
                self.source, self.colors_line, 1,
                "colour matrix has %d rows, expected %d like the pattern"
                % (self.color_rows, self.rows))
        colors = tuple(self.colors) if self.in_colors else None
        return Pattern._trusted(self.rows, self.cols, tuple(self.codes), colors)


def parse_text(text, source_name="<string>"):
    """Parses the pattern text format (Pattern::parse).

    `text` is a str or bytes-like (bytes are read as the C++ parser reads
    them: UTF-8, an optional byte order mark, \\n or \\r\\n line ends).
    Raises PatternError naming `source_name`, line and column.
    """
    if isinstance(text, str):
        # Lone surrogates become the bytes the C++ parser would reject.
        data = text.encode("utf-8", "surrogatepass")
    elif isinstance(text, (bytes, bytearray, memoryview)):
        data = bytes(text)
    else:
        raise TypeError("pattern text must be str or bytes, not " + type(text).__name__)
    return _Parser(data, str(source_name)).run()


def load(path):
    """Reads a pattern file (Pattern::from_file): errors name the path as
    given (str or os.PathLike), then the line and column in the file."""
    name = os.fsdecode(path)
    try:
        # os.open as fopen(path, "rb"): a directory opens and fails to read.
        fd = os.open(name, os.O_RDONLY | getattr(os, "O_BINARY", 0))
    except OSError as e:
        raise PatternError(name, 0, 0, "cannot open pattern file '%s': %s"
                           % (name, os.strerror(e.errno))) from None
    chunks = []
    size = 0
    try:
        while True:
            chunk = os.read(fd, 1 << 20)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
            if size > MAX_TEXT_BYTES:
                raise PatternError(name, 0, 0, "pattern file '%s' is larger than the %d MiB limit"
                                   % (name, MAX_TEXT_BYTES >> 20))
    except OSError as e:
        raise PatternError(name, 0, 0, "cannot read pattern file '%s': %s"
                           % (name, os.strerror(e.errno))) from None
    finally:
        os.close(fd)
    return _Parser(b"".join(chunks), name).run()


def _as_int(value, what):
    try:
        return operator.index(value)
    except TypeError:
        raise TypeError("%s: expected an integer, got %s" % (what, type(value).__name__)) from None


def _shape(rows, cols):
    return "%dx%d" % (rows, cols)


class Pattern:
    """A knit pattern: `rows` x `cols` stitch codes, row-major with row 0 at
    the top, and optionally a colour index per cell.

    Pattern(rows=1, cols=1, codes=None, colors=None) validates as the C++
    constructor does (errors from source "<pattern>"): 1..4096 rows and
    columns, `codes` a flat sequence of rows*cols values 0..3 (None: all
    knit), `colors` None (no colour matrix) or rows*cols indices 0..255 (an
    empty sequence counts as None, as the empty vector does in C++).

    Attributes (read-only): `rows`, `cols`, `codes` (tuple of ints),
    `colors` (tuple of ints, or None without a colour matrix).
    """

    __slots__ = ("_rows", "_cols", "_codes", "_colors")

    def __init__(self, rows=1, cols=1, codes=None, colors=None):
        source = "<pattern>"
        rows = _as_int(rows, "rows")
        cols = _as_int(cols, "cols")
        codes = list(codes) if codes is not None else None
        colors = list(colors) if colors is not None else []
        _check_shape(source, rows, cols, rows * cols if codes is None else len(codes),
                     "code array")
        if codes is None:
            codes = [KNIT] * (rows * cols)
        if colors:
            _check_shape(source, rows, cols, len(colors), "colour array")
        codes = [_as_int(x, "code array entry %d" % i) for i, x in enumerate(codes)]
        colors = [_as_int(x, "colour array entry %d" % i) for i, x in enumerate(colors)]
        _check_values(source, cols, codes, False)
        _check_values(source, cols, colors, True)
        self._rows = rows
        self._cols = cols
        self._codes = tuple(codes)
        self._colors = tuple(colors) if colors else None

    @classmethod
    def _trusted(cls, rows, cols, codes, colors):
        """A pattern from values already valid (tuples; colors None or full)."""
        p = cls.__new__(cls)
        p._rows = rows
        p._cols = cols
        p._codes = codes
        p._colors = colors
        return p

    @classmethod
    def from_rows(cls, rows, colors=None):
        """From a list of rows of codes and an optional list of rows of colour
        indices (Pattern::from_rows: errors from source "<rows>", naming the
        row and column, 1-based, as line and column)."""
        source = "<rows>"
        code_rows = _matrix(rows, "stitch")
        colour_rows = _matrix(colors, "colour") if colors is not None else []
        if not code_rows or not code_rows[0]:
            raise PatternError(source, 0, 0, "empty pattern (no rows or an empty first row)")
        if len(code_rows) > MAX_ROWS:
            raise PatternError(source, MAX_ROWS + 1, 1, "more than %d rows (the limit)" % MAX_ROWS)
        if len(code_rows[0]) > MAX_COLS:
            raise PatternError(source, 1, MAX_COLS + 1,
                               "more than %d columns (the limit)" % MAX_COLS)
        cols = len(code_rows[0])
        flat_codes = _append_rows(source, code_rows, cols, "stitch")
        flat_colors = []
        if colour_rows:
            if len(colour_rows) != len(code_rows):
                raise PatternError(source, min(len(colour_rows), len(code_rows)) + 1, 1,
                                   "colour matrix has %d rows, expected %d like the pattern"
                                   % (len(colour_rows), len(code_rows)))
            flat_colors = _append_rows(source, colour_rows, cols, "colour")
        _check_values(source, cols, flat_codes, False)
        _check_values(source, cols, flat_colors, True)
        return cls._trusted(len(code_rows), cols, tuple(flat_codes),
                            tuple(flat_colors) if flat_colors else None)

    # -- reading ------------------------------------------------------------

    @property
    def rows(self):
        return self._rows

    @property
    def cols(self):
        return self._cols

    @property
    def codes(self):
        """Stitch codes, row-major, row 0 first (a tuple)."""
        return self._codes

    @property
    def colors(self):
        """Colour indices, row-major (a tuple), or None without a colour matrix."""
        return self._colors

    @property
    def has_colors(self):
        return self._colors is not None

    @property
    def num_colors(self):
        """1 + the largest colour index (1 without a colour matrix)."""
        return 1 + max(self._colors) if self._colors is not None else 1

    def colors_or_zero(self):
        """Colour indices, row-major; zeros without a colour matrix (the array
        the kernel reads)."""
        if self._colors is None:
            return (0,) * len(self._codes)
        return self._colors

    def _index(self, row, col):
        if not (0 <= row < self._rows and 0 <= col < self._cols):
            raise IndexError("Pattern: cell (%d, %d) outside the %s pattern"
                             % (row, col, _shape(self._rows, self._cols)))
        return row * self._cols + col

    def stitch(self, row, col):
        """The stitch code (0-3) of a cell; IndexError outside the pattern
        (negative indices too, as in C++)."""
        return self._codes[self._index(row, col)]

    def color(self, row, col):
        """The colour index of a cell (0 without a colour matrix)."""
        i = self._index(row, col)
        return self._colors[i] if self._colors is not None else 0

    def uses(self, code):
        """Whether any cell has this stitch code."""
        return code in self._codes

    def code_rows(self):
        """The codes as a list of rows (lists), row 0 first."""
        c = self._cols
        return [list(self._codes[r * c:(r + 1) * c]) for r in range(self._rows)]

    def color_rows(self):
        """The colour indices as a list of rows, or None without a colour matrix."""
        if self._colors is None:
            return None
        c = self._cols
        return [list(self._colors[r * c:(r + 1) * c]) for r in range(self._rows)]

    # -- text ---------------------------------------------------------------

    def to_text(self):
        """The canonical text (Pattern::to_text): letters K P F B separated by
        single spaces, one row per line, then "colors:" and the indices
        separated by spaces if there is a colour matrix."""
        c = self._cols
        letters = [LETTERS[x] for x in self._codes]
        out = [" ".join(letters[r * c:(r + 1) * c]) + "\n" for r in range(self._rows)]
        if self._colors is not None:
            out.append("colors:\n")
            numbers = [str(x) for x in self._colors]
            out.extend(" ".join(numbers[r * c:(r + 1) * c]) + "\n" for r in range(self._rows))
        return "".join(out)

    def to_storage(self):
        """A compact text for a Blender string property: the pattern text
        format with compact rows ("KKPP"), and compact colour rows when every
        index is a single digit (spaces between indices otherwise; one
        column: one index per line). Both this parser and the C++ one read it
        back to an equal pattern; about half the size of to_text()."""
        c = self._cols
        letters = "".join(LETTERS[x] for x in self._codes)
        out = [letters[r * c:(r + 1) * c] + "\n" for r in range(self._rows)]
        if self._colors is not None:
            out.append("colors:\n")
            if c > 1 and max(self._colors) < 10:
                digits = "".join(map(str, self._colors))
                out.extend(digits[r * c:(r + 1) * c] + "\n" for r in range(self._rows))
            else:
                numbers = [str(x) for x in self._colors]
                out.extend(" ".join(numbers[r * c:(r + 1) * c]) + "\n" for r in range(self._rows))
        return "".join(out)

    @classmethod
    def from_storage(cls, text, source_name="<storage>"):
        """The pattern to_storage() wrote (any pattern text is accepted)."""
        return parse_text(text, source_name)

    # -- comparison ---------------------------------------------------------

    def __eq__(self, other):
        if not isinstance(other, Pattern):
            return NotImplemented
        return (self._rows == other._rows and self._cols == other._cols
                and self._codes == other._codes and self._colors == other._colors)

    def __hash__(self):
        return hash((self._rows, self._cols, self._codes, self._colors))

    def __repr__(self):
        s = "<Pattern %s" % _shape(self._rows, self._cols)
        if self._colors is None:
            return s + " without colors>"
        return s + " with %d colors>" % self.num_colors

    def __reduce__(self):
        return (_from_text_for_pickle, (self.to_storage(),))

    # -- edits: each returns a new pattern ----------------------------------

    def _cell(self, op, row, col):
        row = _as_int(row, op + ": row")
        col = _as_int(col, op + ": column")
        if not (0 <= row < self._rows and 0 <= col < self._cols):
            raise PatternError(op, 0, 0,
                               "cell (%d, %d) is outside the %s pattern (rows 0..%d, columns 0..%d)"
                               % (row, col, _shape(self._rows, self._cols),
                                  self._rows - 1, self._cols - 1))
        return row * self._cols + col

    def _colors_for_edit(self):
        """The colour matrix as a list, zeros when there is none (an edit that
        sets a colour gives the pattern a colour matrix)."""
        return list(self._colors) if self._colors is not None else [0] * len(self._codes)

    def with_stitch(self, row, col, stitch):
        """The pattern with cell (row, col) set to `stitch` (0-3 or a letter
        K P F B, any case). Rows and columns count from 0."""
        i = self._cell("with_stitch", row, col)
        code = _stitch_arg("with_stitch", stitch)
        codes = list(self._codes)
        codes[i] = code
        return Pattern._trusted(self._rows, self._cols, tuple(codes), self._colors)

    def cycled(self, row, col):
        """The pattern with cell (row, col) turned to the next stitch:
        K -> P -> F -> B -> K."""
        i = self._cell("cycled", row, col)
        codes = list(self._codes)
        codes[i] = (codes[i] + 1) % 4
        return Pattern._trusted(self._rows, self._cols, tuple(codes), self._colors)

    def with_color(self, row, col, color):
        """The pattern with cell (row, col) of colour `color` (0..255). A
        pattern without a colour matrix gets one (zeros elsewhere)."""
        i = self._cell("with_color", row, col)
        index = _color_arg("with_color", color)
        colors = self._colors_for_edit()
        colors[i] = index
        return Pattern._trusted(self._rows, self._cols, self._codes, tuple(colors))

    def without_colors(self):
        """The pattern without its colour matrix (every cell colour 0)."""
        return Pattern._trusted(self._rows, self._cols, self._codes, None)

    def filled(self, stitch=None, color=None, rect=None):
        """The pattern with every cell, or the cells of `rect`, set to
        `stitch` and/or `color` (at least one of them). `rect` is
        (row, col, rows, cols): the top-left cell and the size, inside the
        pattern. Giving a colour gives the pattern a colour matrix."""
        op = "filled"
        if stitch is None and color is None:
            raise PatternError(op, 0, 0, "nothing to fill: give a stitch, a colour or both")
        code = _stitch_arg(op, stitch) if stitch is not None else None
        index = _color_arg(op, color) if color is not None else None
        top, left, height, width = self._rect(op, rect)
        codes = list(self._codes)
        colors = self._colors_for_edit() if index is not None else None
        c = self._cols
        for r in range(top, top + height):
            a, b = r * c + left, r * c + left + width
            if code is not None:
                codes[a:b] = [code] * width
            if colors is not None:
                colors[a:b] = [index] * width
        return Pattern._trusted(self._rows, c, tuple(codes),
                                tuple(colors) if colors is not None else self._colors)

    def _rect(self, op, rect):
        if rect is None:
            return 0, 0, self._rows, self._cols
        try:
            top, left, height, width = (_as_int(v, op + ": rect") for v in rect)
        except ValueError:
            raise PatternError(op, 0, 0, "rect must be (row, col, rows, cols), got %r"
                               % (rect,)) from None
        if (height < 1 or width < 1 or top < 0 or left < 0
                or top + height > self._rows or left + width > self._cols):
            raise PatternError(op, 0, 0,
                               "rectangle of %s cells at (%d, %d) is not inside the %s pattern"
                               % (_shape(height, width), top, left,
                                  _shape(self._rows, self._cols)))
        return top, left, height, width

    def shifted(self, dx=0, dy=0):
        """The pattern moved by dx columns to the right and dy rows down (row
        0 is the top), wrapping around: cell (r, c) of the result is cell
        ((r - dy) mod rows, (c - dx) mod cols) of this pattern."""
        dx = _as_int(dx, "shifted: dx") % self._cols
        dy = _as_int(dy, "shifted: dy") % self._rows

        def move(values):
            c = self._cols
            rows = [values[r * c:(r + 1) * c] for r in range(self._rows)]
            rows = rows[self._rows - dy:] + rows[:self._rows - dy]
            out = []
            for row in rows:
                out.extend(row[c - dx:] + row[:c - dx])
            return tuple(out)

        return Pattern._trusted(self._rows, self._cols, move(self._codes),
                                move(self._colors) if self._colors is not None else None)

    def mirrored(self):
        """The pattern mirrored left-right (column c becomes cols - 1 - c)."""

        def mirror(values):
            c = self._cols
            out = []
            for r in range(self._rows):
                out.extend(reversed(values[r * c:(r + 1) * c]))
            return tuple(out)

        return Pattern._trusted(self._rows, self._cols, mirror(self._codes),
                                mirror(self._colors) if self._colors is not None else None)

    def flipped(self):
        """The pattern flipped top-bottom (row r becomes rows - 1 - r)."""

        def flip(values):
            c = self._cols
            out = []
            for r in reversed(range(self._rows)):
                out.extend(values[r * c:(r + 1) * c])
            return tuple(out)

        return Pattern._trusted(self._rows, self._cols, flip(self._codes),
                                flip(self._colors) if self._colors is not None else None)

    def resized(self, rows, cols):
        """The pattern as `rows` x `cols` (1..4096 each): the top-left part
        kept, new cells knit and colour 0."""
        rows = _check_count("resized", "rows", rows, MAX_ROWS)
        cols = _check_count("resized", "columns", cols, MAX_COLS)

        def resize(values):
            c = self._cols
            keep = min(c, cols)
            out = []
            for r in range(rows):
                if r < self._rows:
                    out.extend(values[r * c:r * c + keep])
                    out.extend([0] * (cols - keep))
                else:
                    out.extend([0] * cols)
            return tuple(out)

        return Pattern._trusted(rows, cols, resize(self._codes),
                                resize(self._colors) if self._colors is not None else None)

    def with_row_inserted(self, index, stitch=KNIT, color=None):
        """The pattern with a new row before row `index` (0..rows; rows
        appends at the bottom), all `stitch`, colour `color` (None: colour 0,
        and no colour matrix is added)."""
        op = "with_row_inserted"
        index = _check_index(op, "row", index, self._rows)
        if self._rows == MAX_ROWS:
            raise PatternError(op, 0, 0,
                               "the pattern already has %d rows (the limit)" % MAX_ROWS)
        code = _stitch_arg(op, stitch)
        at = index * self._cols
        codes = self._codes[:at] + (code,) * self._cols + self._codes[at:]
        colors = self._colors
        if color is not None or colors is not None:
            index_value = _color_arg(op, color) if color is not None else 0
            base = tuple(self._colors_for_edit())
            colors = base[:at] + (index_value,) * self._cols + base[at:]
        return Pattern._trusted(self._rows + 1, self._cols, codes, colors)

    def with_row_removed(self, index):
        """The pattern without row `index` (0..rows-1); a pattern keeps at
        least one row."""
        op = "with_row_removed"
        index = _check_index(op, "row", index, self._rows - 1)
        if self._rows == 1:
            raise PatternError(op, 0, 0, "cannot remove the only row (a pattern has at least one)")
        a, b = index * self._cols, (index + 1) * self._cols
        colors = self._colors[:a] + self._colors[b:] if self._colors is not None else None
        return Pattern._trusted(self._rows - 1, self._cols, self._codes[:a] + self._codes[b:],
                                colors)

    def with_col_inserted(self, index, stitch=KNIT, color=None):
        """The pattern with a new column before column `index` (0..cols; cols
        appends at the right), all `stitch`, colour `color` (None: colour 0,
        and no colour matrix is added)."""
        op = "with_col_inserted"
        index = _check_index(op, "column", index, self._cols)
        if self._cols == MAX_COLS:
            raise PatternError(op, 0, 0,
                               "the pattern already has %d columns (the limit)" % MAX_COLS)
        code = _stitch_arg(op, stitch)
        c = self._cols

        def insert(values, value):
            out = []
            for r in range(self._rows):
                row = values[r * c:(r + 1) * c]
                out.extend(row[:index])
                out.append(value)
                out.extend(row[index:])
            return tuple(out)

        colors = self._colors
        if color is not None or colors is not None:
            index_value = _color_arg(op, color) if color is not None else 0
            colors = insert(self._colors_for_edit(), index_value)
        return Pattern._trusted(self._rows, c + 1, insert(self._codes, code), colors)

    def with_col_removed(self, index):
        """The pattern without column `index` (0..cols-1); a pattern keeps at
        least one column."""
        op = "with_col_removed"
        index = _check_index(op, "column", index, self._cols - 1)
        if self._cols == 1:
            raise PatternError(op, 0, 0,
                               "cannot remove the only column (a pattern has at least one)")
        c = self._cols

        def remove(values):
            out = []
            for r in range(self._rows):
                out.extend(values[r * c:r * c + index])
                out.extend(values[r * c + index + 1:(r + 1) * c])
            return tuple(out)

        colors = remove(self._colors) if self._colors is not None else None
        return Pattern._trusted(self._rows, c - 1, remove(self._codes), colors)


def _from_text_for_pickle(text):
    return parse_text(text, "<pickle>")


# -- validation shared by the constructor, from_rows and the edits ------------


def _check_shape(source, rows, cols, n, what):
    # check_shape() in pattern.cpp
    if rows < 1 or cols < 1:
        raise PatternError(source, 0, 0, "empty pattern (%s)" % _shape(rows, cols))
    if rows > MAX_ROWS:
        raise PatternError(source, 0, 0, "pattern has %d rows, more than %d (the limit)"
                           % (rows, MAX_ROWS))
    if cols > MAX_COLS:
        raise PatternError(source, 0, 0, "pattern has %d columns, more than %d (the limit)"
                           % (cols, MAX_COLS))
    if n != rows * cols:
        raise PatternError(source, 0, 0, "%s has %d entries, expected %d for a %s pattern"
                           % (what, n, rows * cols, _shape(rows, cols)))


def _check_values(source, cols, values, colour):
    # check_values() in pattern.cpp: the first bad value, by row and column.
    top = MAX_COLORS - 1 if colour else 3
    for i, x in enumerate(values):
        if 0 <= x <= top:
            continue
        line, column = i // cols + 1, i % cols + 1
        if colour:
            raise PatternError(source, line, column,
                               "colour index %d out of range 0..%d" % (x, MAX_COLORS - 1))
        raise PatternError(source, line, column, "unknown stitch code %d%s" % (x, _UNKNOWN_VALUE))


def _matrix(obj, what):
    """A list of lists of ints from a sequence of sequences; TypeError as the
    binding's from_rows raises it."""
    if isinstance(obj, (str, bytes)) or not hasattr(obj, "__iter__"):
        raise TypeError("%s: expected a sequence of rows (a list of lists)" % what)
    out = []
    for r, row in enumerate(obj):
        if isinstance(row, (str, bytes)) or not hasattr(row, "__iter__"):
            raise TypeError("%s row %d: expected a sequence of integers" % (what, r + 1))
        out.append([_as_int(x, "%s row %d, column %d" % (what, r + 1, c + 1))
                    for c, x in enumerate(row)])
    return out


def _append_rows(source, rows, cols, what):
    # append_row() in pattern.cpp, for every row
    out = []
    for r, row in enumerate(rows):
        if len(row) != cols:
            raise PatternError(source, r + 1, min(len(row), cols) + 1,
                               "%s row %d has %d cells, expected %d like row 1"
                               % (what, r + 1, len(row), cols))
        out.extend(row)
    return out


def _stitch_arg(op, stitch):
    """A stitch code from 0-3 or a letter (K P F B, any case) or digit string."""
    if isinstance(stitch, str):
        code = _CODE_OF.get(stitch)
        if code is None:
            raise PatternError(op, 0, 0, "unknown stitch code " + _quote(stitch) + _UNKNOWN_TOKEN)
        return code
    code = _as_int(stitch, op + ": stitch")
    if not 0 <= code <= 3:
        raise PatternError(op, 0, 0, "unknown stitch code %d%s" % (code, _UNKNOWN_VALUE))
    return code


def _color_arg(op, color):
    index = _as_int(color, op + ": colour")
    if not 0 <= index < MAX_COLORS:
        raise PatternError(op, 0, 0, "colour index %d out of range 0..%d" % (index, MAX_COLORS - 1))
    return index


def _check_count(op, what, n, limit):
    n = _as_int(n, "%s: %s" % (op, what))
    if not 1 <= n <= limit:
        raise PatternError(op, 0, 0, "%s %d out of range 1..%d (the limit)" % (what, n, limit))
    return n


def _check_index(op, what, index, last):
    index = _as_int(index, "%s: %s" % (op, what))
    if not 0 <= index <= last:
        raise PatternError(op, 0, 0, "%s index %d out of range 0..%d" % (what, index, last))
    return index

"""Runs every ```python block of docs/python.md, each in a fresh namespace,
so the documented examples keep working."""
import contextlib
import io
import os
import pathlib
import re
import unittest

SOURCE_DIR = pathlib.Path(os.environ.get("KNIT_SOURCE_DIR", pathlib.Path(__file__).parents[2]))
DOC = SOURCE_DIR / "docs" / "python.md"


def python_blocks(text):
    return [m.group(1) for m in re.finditer(r"^```python\n(.*?)^```", text, re.S | re.M)]


class DocExamples(unittest.TestCase):
    def test_every_python_block_runs(self):
        blocks = python_blocks(DOC.read_text(encoding="utf-8"))
        self.assertGreaterEqual(len(blocks), 8, "docs/python.md has an example per area")
        for i, code in enumerate(blocks):
            with self.subTest(block=i, first_line=code.splitlines()[0]):
                out = io.StringIO()
                with contextlib.redirect_stdout(out):
                    exec(compile(code, "%s block %d" % (DOC.name, i), "exec"), {})
                self.assertTrue(out.getvalue(), "each example prints what it shows")


if __name__ == "__main__":
    unittest.main()

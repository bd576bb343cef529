"""The Python examples of docs/blender.md, run in order in one namespace
inside Blender with the add-on installed from the zip (every ```python
block of the page). A block that raises fails the test."""
import os
import re
import sys

import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside as T  # noqa: E402


def blocks(path):
    text = open(path, encoding="utf-8").read()
    return re.findall(r"^```python\n(.*?)^```", text, re.S | re.M)


def main():
    T.say(T.blender())
    T.install()
    T.fresh_scene()
    doc = os.path.join(T.SOURCE, "docs", "blender.md")
    code = blocks(doc)
    T.check(len(code) >= 4, "docs/blender.md has %d python blocks" % len(code))
    ns = {"__name__": "__docs__"}
    for i, block in enumerate(code, 1):
        first = block.strip().splitlines()[0]
        try:
            exec(compile(block, "%s (block %d)" % (doc, i), "exec"), ns)
        except Exception as e:
            raise AssertionError("docs/blender.md block %d (%s) raised %s: %s"
                                 % (i, first, type(e).__name__, e)) from e
        T.say("block %d ran: %s" % (i, first))
    mat = bpy.data.materials["Rib Scarf"]
    api = ns["api"]
    T.check(api.get_pattern(mat).rows >= 1, "the examples left no pattern")
    T.close(api.get_parameters(mat)["r"], ns["mod"].core.presets.yarn_weight("chunky")["r"],
            "r after the examples' yarn_weight chunky")


T.run(main)

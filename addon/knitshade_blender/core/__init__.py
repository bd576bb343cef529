"""The add-on's pure-Python core: no bpy, standard library only.

Runs in every Blender the add-on supports (3.4 with Python 3.10/3.11 up to
5.1+ with Python 3.13) and under plain Python, where tests/addon_core tests
it. Modules:

- pattern: knit patterns (knit::Pattern in Python), the .knit text parser
  with the C++ library's errors to the byte, and the editing operations.
- presets: the pattern presets (examples/patterns) and the yarn weights.
"""

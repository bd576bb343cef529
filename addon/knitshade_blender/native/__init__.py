"""The compiled `knitshade` module: imported here and nowhere else.

The add-on's zip carries the module built for this platform's CPython 3.11
(Blender 3.4 to 5.0) as native/knitshade.cpython-311-<platform>.so. It is
optional: the material, the pattern editor, .knit import and export and the
shader text are pure Python (core/). Where the module loads it adds what
needs native code:

- the library's own check of the stitch parameters, with its message
  (tubes that would pass through each other are caught; without the module
  only the basic checks of core.checks run);
- explicit yarn geometry and the swatch preview (issue 54).

A Blender whose Python is not 3.11 (5.1 and later embed 3.13) or an add-on
zip built on another platform does not load it; the panel says so.
"""
import sys

module = None
error = ""
shared_from = ""  # the other copy's name when an already loaded module is reused


def _loaded_elsewhere():
    """A `knitshade` module some other package already loaded in this process
    (the add-on installed both as a legacy add-on and as an extension, or
    the build tree's module on sys.path): pybind11 registers its types once
    per process, so a second copy of the .so cannot load; reuse the first."""
    for name, mod in list(sys.modules.items()):
        if mod is None or name == __name__ + ".knitshade":
            continue
        if (name == "knitshade" or name.endswith(".native.knitshade")) and hasattr(mod, "StitchParams"):
            return name, mod
    return "", None


shared_from, module = _loaded_elsewhere()
if module is None:
    try:
        from . import knitshade as module  # noqa: F401  (the one import of the compiled module)
    except ImportError as e:  # not shipped, other Python, other platform, a missing library
        module = None
        error = str(e) or type(e).__name__
    except Exception as e:  # a broken build must not stop the add-on from registering
        module = None
        error = "%s: %s" % (type(e).__name__, e)

AVAILABLE = module is not None

# What the module adds, and how to get it: shown in the panel when it is missing.
ADDS = ("the library's check of a, h, d, r (yarn tubes passing through each other)",
        "explicit yarn geometry for Blenders without OSL, and the swatch preview")
HOW_TO_GET = ("install the knitshade_blender zip built on this platform (cmake --build build "
              "--target addon_zip) in a Blender whose Python is 3.11 (3.4 to 5.0)")


def _shipped():
    """The compiled module files in this folder."""
    import os
    here = os.path.dirname(os.path.abspath(__file__))
    try:
        return sorted(n for n in os.listdir(here) if n.startswith("knitshade.") and n.endswith((".so", ".pyd")))
    except OSError:
        return []


def status():
    """One line for the panel: the module's version, or why it is missing."""
    if AVAILABLE:
        where = " (the copy %s loaded first)" % shared_from if shared_from else ""
        return "Native module %s loaded%s" % (getattr(module, "__version__", "?"), where)
    import importlib.machinery
    files = _shipped()
    if not files:
        return "Native module not loaded: this add-on was packed without it"
    if not any(f.endswith(tuple(importlib.machinery.EXTENSION_SUFFIXES)) for f in files):
        return ("Native module not loaded: %s is not for this Blender's Python %d.%d on this platform"
                % (files[0], sys.version_info[0], sys.version_info[1]))
    return "Native module not loaded: %s" % error


def check_stitch(a, h, d, r):
    """Raise ValueError with the library's message when knit::StitchParams
    refuses (a, h, d, r). Returns False without the module (nothing checked
    here), True when it accepted them."""
    if module is None:
        return False
    module.StitchParams(a=float(a), h=float(h), d=float(d), r=float(r))
    return True

#!/usr/bin/env python3
"""The native module inside the add-on zip links the knit core and the C and
C++ runtimes only: none of Embree, OpenImageIO, OpenColorIO or assimp
(official Blender builds carry their own versions of those, and a second
copy in the same process breaks one of them). oneTBB is allowed as
libtbb.so.12: the knit core's table builds run on it, and every Blender
from 3.4 on loads a libtbb.so.12 of its own that the module then shares.

    check_native_deps.py build/knitshade_blender-<version>.zip

Lists the module's NEEDED entries (readelf -d) and what ldd resolves them to.
"""
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile

FORBIDDEN = {
    "Embree": re.compile(r"embree", re.I),
    "OpenImageIO": re.compile(r"openimageio|libOpenImageIO", re.I),
    "OpenColorIO": re.compile(r"opencolorio", re.I),
    "assimp": re.compile(r"assimp", re.I),
}
ALLOWED = re.compile(r"^(libtbb\.so\.12|libstdc\+\+\.so\.6|libm\.so\.6|libgcc_s\.so\.1|libc\.so\.6|"
                     r"ld-linux-x86-64\.so\.2|libpthread\.so\.0|libdl\.so\.2)$")


def needed(path):
    readelf = shutil.which("readelf")
    if readelf:
        out = subprocess.run([readelf, "-d", path], capture_output=True, text=True, check=True).stdout
        return re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", out)
    out = subprocess.run(["ldd", path], capture_output=True, text=True, check=True).stdout
    return [ln.split()[0] for ln in out.splitlines() if "=>" in ln]


def main(argv):
    if len(argv) != 2:
        print(__doc__)
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        with zipfile.ZipFile(argv[1]) as z:
            names = [n for n in z.namelist() if re.match(r"knitshade_blender/native/knitshade\..*\.so$", n)]
            if len(names) != 1:
                print("FAIL: the zip holds %d native modules (expected 1): %s" % (len(names), names))
                return 1
            path = z.extract(names[0], tmp)
        libs = needed(path)
        ldd = subprocess.run(["ldd", path], capture_output=True, text=True).stdout
    print("%s NEEDED:" % names[0])
    for lib in libs:
        print("  " + lib)
    print("ldd:\n" + "\n".join("  " + ln.strip() for ln in ldd.splitlines()))
    bad = ["%s (%s)" % (lib, what) for lib in libs for what, rx in FORBIDDEN.items() if rx.search(lib)]
    if bad:
        print("FAIL: the module links %s; it must link the knit core and the C/C++ runtimes only "
              "(native/python/CMakeLists.txt)" % ", ".join(bad))
        return 1
    other = [lib for lib in libs if not ALLOWED.match(lib)]
    if other:
        print("FAIL: unexpected dependencies %s: Blender may not carry them (allowed: the C/C++ runtimes "
              "and libtbb.so.12)" % ", ".join(other))
        return 1
    if "not found" in ldd:
        print("FAIL: ldd cannot resolve a dependency here")
        return 1
    print("OK: %d dependencies, none of Embree, OpenImageIO, OpenColorIO, assimp%s"
          % (len(libs), "; oneTBB as libtbb.so.12" if "libtbb.so.12" in libs else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

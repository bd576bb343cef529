#!/usr/bin/env python3
"""Build the Blender add-on's installable zip (CMake target addon_zip).

    make_zip.py --source addon/knitshade_blender --native build/python/knitshade.cpython-311-....so
                --template build/osl/knit_fabric_template.osl --patterns examples/patterns
                --version 0.1.0 --out build/knitshade_blender-0.1.0.zip

The zip holds one folder, knitshade_blender/: the package's .py files and
blender_manifest.toml (no caches), native/<the compiled module>,
patterns/*.knit (the presets) and shader/knit_fabric_template.osl. It
installs as a legacy add-on (Blender 3.4 to 4.1: Preferences > Add-ons >
Install) and as an extension (4.2 and later). The same inputs give the same
bytes (sorted entries, fixed times). The versions in bl_info and in the
manifest must equal --version (the project's), or the build fails.
"""
import argparse
import ast
import os
import re
import sys
import zipfile

PACKAGE = "knitshade_blender"
STAMP = (2024, 1, 1, 0, 0, 0)


def package_files(source):
    out = []
    for root, dirs, files in os.walk(source):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__" and not d.startswith("."))
        for name in sorted(files):
            if name.endswith((".py", ".toml")) and not name.startswith("."):
                path = os.path.join(root, name)
                out.append((path, os.path.relpath(path, source)))
    return out


def bl_info_version(init_py):
    tree = ast.parse(open(init_py, encoding="utf-8").read())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "bl_info" for t in node.targets):
            info = ast.literal_eval(node.value)
            return ".".join(str(x) for x in info["version"])
    raise SystemExit("make_zip: no bl_info in %s" % init_py)


def manifest_version(toml):
    m = re.search(r'^version\s*=\s*"([^"]+)"', open(toml, encoding="utf-8").read(), re.M)
    if not m:
        raise SystemExit("make_zip: no version in %s" % toml)
    return m.group(1)


def add(z, path, arcname, mode=0o644):
    info = zipfile.ZipInfo(PACKAGE + "/" + arcname.replace(os.sep, "/"), STAMP)
    info.compress_type = zipfile.ZIP_DEFLATED
    info.external_attr = (0o100000 | mode) << 16
    with open(path, "rb") as f:
        z.writestr(info, f.read())


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--source", required=True)
    ap.add_argument("--native", help="the compiled knitshade module (omit to build a zip without it)")
    ap.add_argument("--template", required=True)
    ap.add_argument("--patterns", required=True)
    ap.add_argument("--version", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)

    versions = {"bl_info": bl_info_version(os.path.join(a.source, "__init__.py")),
                "blender_manifest.toml": manifest_version(os.path.join(a.source, "blender_manifest.toml"))}
    wrong = {k: v for k, v in versions.items() if v != a.version}
    if wrong:
        raise SystemExit("make_zip: the add-on's version (%s) differs from the project's %s: update them together"
                         % (", ".join("%s %s" % kv for kv in wrong.items()), a.version))
    patterns = sorted(n for n in os.listdir(a.patterns) if n.endswith(".knit"))
    if not patterns:
        raise SystemExit("make_zip: no .knit files in %s" % a.patterns)
    tmp = a.out + ".tmp"
    with zipfile.ZipFile(tmp, "w") as z:
        for path, rel in package_files(a.source):
            add(z, path, rel)
        if a.native:
            add(z, a.native, os.path.join("native", os.path.basename(a.native)), 0o755)
        for name in patterns:
            add(z, os.path.join(a.patterns, name), os.path.join("patterns", name))
        add(z, a.template, os.path.join("shader", "knit_fabric_template.osl"))
    os.replace(tmp, a.out)
    print("make_zip: %s (%d bytes)" % (a.out, os.path.getsize(a.out)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

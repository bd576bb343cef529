"""`knitshade export-cycles` refusals and warnings (no Cycles needed).

    check_errors.py --cli KNITSHADE --out DIR

What the standalone Cycles cannot be given is refused with exit code 1 and
one line on stderr naming the scene file, the field (with its line and
column) and the value: more than 8 yarn colours, a pattern over the
shader's 256 x 256, transmission colours that are not the yarn colours
times one tint, a ply radius other than the packed one. The limits
themselves (8 colours, 256 x 256) export. The parser's and loaders' errors
come through the same way; bad usage exits 2; an unwritable output exits 1
naming the file. --no-curvature on a curved knit mesh: one warning line
naming the object, and no curvature link.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
MESHES = os.path.join(ROOT, "examples", "scenes", "meshes")

FAILURES = []


def check(ok, what):
    if not ok:
        FAILURES.append(what)
        print("FAIL:", what)
    return ok


def scene(**wool):
    m = {"type": "knit", "pattern": ["KKPP", "PPKK"], "uv_scale": 40, "yarn_colors": [[0.7, 0.2, 0.1]]}
    m.update(wool)
    return {"version": 1, "film": {"width": 32, "height": 24, "spp": 1},
            "camera": {"position": [0, 0, 2], "look_at": [0, 0, 0]},
            "lights": [{"type": "environment", "color": [1, 1, 1]}],
            "materials": {"wool": m},
            "objects": [{"name": "swatch", "mesh": os.path.join(MESHES, "quad.obj"), "material": "wool"}]}


def write(out, name, s):
    path = os.path.join(out, name + ".json")
    with open(path, "w") as f:
        if isinstance(s, str):
            f.write(s)
        else:
            json.dump(s, f, indent=1)
    return path


def run(cli, *args):
    return subprocess.run([cli, "export-cycles", *args], capture_output=True, text=True)


def refused(cli, out, name, s, field, *words):
    """Exit 1, one line: '<file>:<line>:<col>: <field>: ...' holding `words`."""
    path = write(out, name, s)
    r = run(cli, path, "-o", os.path.join(out, name + ".xml"))
    lines = r.stderr.strip().splitlines()
    what = f"{name}: exit {r.returncode}, stderr {r.stderr.strip()!r}"
    check(r.returncode == 1, what)
    if not check(len(lines) == 1, what + ": not one line"):
        return
    m = re.match(r"knitshade export-cycles: error: (.+?):(\d+):(\d+): (\S+): (.*)$", lines[0])
    if check(m is not None, what + ": not 'file:line:column: field: message'"):
        check(m.group(1) == path, what + ": names another file")
        check(m.group(4) == field, what + f": field {m.group(4)}, not {field}")
        for w in words:
            check(w in m.group(5), what + f": no {w!r} in the message")
    check(not os.path.exists(os.path.join(out, name + ".xml")), f"{name}: an XML was written")
    print(f"{name}: refused: {lines[0] if lines else ''}")


def exports(cli, out, name, s, *extra):
    path = write(out, name, s)
    xml = os.path.join(out, name + ".xml")
    r = run(cli, path, "-o", xml, *extra)
    check(r.returncode == 0, f"{name}: exit {r.returncode}: {r.stderr.strip()}")
    print(f"{name}: exported")
    return r, xml


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    cli, out = a.cli, a.out
    os.makedirs(out, exist_ok=True)

    nine = [[0.1 * i, 0.5, 0.5] for i in range(9)]
    refused(cli, out, "nine_colours", scene(yarn_colors=nine), "materials.wool.yarn_colors", "9 yarn colours", "8")
    # (its colour matrix uses index 8: without it the parser accepts 9 colours too)
    refused(cli, out, "nine_colours_used", scene(pattern=["KKKKKKKKK"], colors=[list(range(9))], yarn_colors=nine),
            "materials.wool.yarn_colors", "9 yarn colours")
    refused(cli, out, "pattern_257", scene(pattern=["K" * 257]), "materials.wool.pattern", "1 x 257", "256 x 256")
    refused(cli, out, "pattern_257_rows", scene(pattern=["KP"] * 257), "materials.wool.pattern", "257 x 2")
    refused(cli, out, "two_tints",
            scene(pattern=["KP"], colors=[[0, 1]], yarn_colors=[[0.5, 0.5, 0.5], [0.4, 0.2, 0.2]],
                  transmit_colors=[[0.25, 0.25, 0.25], [0.4, 0.2, 0.2]]),
            "materials.wool.transmit_colors[1]", "(0.4, 0.2, 0.2)", "one tint")
    refused(cli, out, "tint_over_zero", scene(yarn_colors=[[0.5, 0, 0.5]], transmit_colors=[[0.5, 0.1, 0.5]]),
            "materials.wool.transmit_colors[0]", "zero channel")
    refused(cli, out, "ply_radius", scene(ply={"ply_count": 3, "ply_radius": 0.3}), "materials.wool.ply.ply_radius",
            "0.3", "0.464")
    # Errors of the parser and the loaders come through as the renderer's.
    refused(cli, out, "parser_error", scene(widht=3), "materials.wool.widht", "unknown key")
    s = scene()
    s["objects"][0]["mesh"] = os.path.join(MESHES, "nope.obj")
    refused(cli, out, "missing_mesh", s, "objects[0].mesh", "file not found")

    # The limits themselves export.
    eight = [[0.1 * i, 0.5, 0.5] for i in range(8)]
    exports(cli, out, "eight_colours", scene(pattern=["KKKKPPPP"], colors=[list(range(8))], yarn_colors=eight))
    r, xml = exports(cli, out, "pattern_256", scene(pattern=["KP" * 128] * 256))
    if r.returncode == 0:
        with open(os.path.join(out, "pattern_256_wool.osl")) as f:
            text = f.read()
        check("#define KNIT_PATTERN_CELLS 65536\n" in text, "pattern_256: not a 256 x 256 shader")
    exports(cli, out, "one_tint", scene(pattern=["KP"], colors=[[0, 1]], yarn_colors=[[0.5, 0.4, 0.2], [0.2, 0.2, 0.4]],
                                        transmit_colors=[[0.25, 0.4, 0.1], [0.1, 0.2, 0.2]]))

    # Usage and output errors.
    path = write(out, "plain", scene())
    r = run(cli, path)
    check(r.returncode == 2 and "-o" in r.stderr, f"no -o: exit {r.returncode}, {r.stderr.strip()!r}")
    r = run(cli, path, "-o", os.path.join(out, "no_such_folder", "x.xml"))
    lines = r.stderr.strip().splitlines()
    check(r.returncode == 1 and len(lines) == 1 and "no_such_folder" in lines[0] and "cannot write" in lines[0],
          f"unwritable output: exit {r.returncode}, {r.stderr.strip()!r}")
    r = run(cli, "--help")
    check(r.returncode == 0 and "export-cycles" in r.stdout and "--no-curvature" in r.stdout, "--help")

    # --no-curvature: a warning per curved knit mesh, no curvature anywhere.
    s = scene()
    s["objects"][0]["mesh"] = os.path.join(MESHES, "half_cylinder.obj")
    r, xml = exports(cli, out, "no_curvature", s, "--no-curvature")
    warns = [w for w in r.stderr.splitlines() if "warning" in w]
    check(len(warns) == 1 and "objects[0] (swatch)" in warns[0] and "Curvature" in warns[0],
          f"--no-curvature: warnings {warns}")
    if r.returncode == 0:
        root = ET.parse(xml).getroot()
        check(root.find(".//attribute") is None and root.find(".//mesh").get("tangent") is None,
              "--no-curvature: curvature written")
    r, xml = exports(cli, out, "with_curvature", s)
    check(not [w for w in r.stderr.splitlines() if "warning" in w], f"curvature carried: warnings {r.stderr}")

    if FAILURES:
        print(f"{len(FAILURES)} failures")
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())

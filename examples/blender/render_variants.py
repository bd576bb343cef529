"""Batch renders of pattern x palette variants of a Knit Fabric material.

    blender -b SCENE.blend -P examples/blender/render_variants.py -- --variants LIST.json --out DIR
            [--samples N] [--resolution WxH] [--mode auto|shader|yarns] [--no-blend] [--addon-zip ZIP]

For every variant of LIST: the material's pattern, colours and settings
set through the add-on's API, the scene rendered with the scene's own
camera and render settings (as PNG) to DIR/<variant>.png, and saved as a
self-contained DIR/<variant>.blend (images packed; the knit shader's
bytecode compiled into it where this Blender has OSL, or the yarn curves in
it where it has not), which renders on a machine without the add-on. One
progress line per variant, a summary at the end, and DIR/contact_sheet.png
with every variant, labelled with its name. The exit status is 1 when a
variant failed (the others are still rendered), 2 when the list is wrong
(nothing rendered).

--mode: shader renders the knit shader (Cycles with OSL: Blender 4.2 and
later official builds), yarns lays explicit yarn geometry on the objects
using the material (Generate Yarn Geometry; every Blender from 3.4 with
the add-on's native module) and renders that; auto (the default) takes the
shader where this Blender has OSL, else the yarns.

The variants list (JSON; relative paths are relative to the list's folder):

    {
      "material": "wool",
      "patterns": {"rib": "../../examples/patterns/rib_1x1.knit",
                   "seed": "preset:seed",
                   "checks": "K K P P\\nK K P P\\nP P K K\\nP P K K"},
      "palettes": {"navy": [[0.10, 0.15, 0.40]],
                   "cream and red": [[0.85, 0.80, 0.70], [0.55, 0.08, 0.08]]},
      "settings": {"r": 0.6},
      "variants": [{"name": "rib-navy", "pattern": "rib", "palette": "navy", "settings": {"a": 1.3}}]
    }

- material: the Knit Fabric material to vary (default: the first one an
  object of the scene uses);
- patterns: name -> a .knit file, "preset:<name>" (the add-on's presets:
  stockinette, rib_1x1, seed, ...), or pattern text;
- palettes: name -> up to 8 linear RGB colours (colour index 0 first);
- settings: add-on settings (a, h, d, r, uv_scale, roughness, ...: see
  knitshade_blender.api) for every variant;
- variants: optional; without it every pattern is rendered with every
  palette, named "<pattern>-<palette>". A variant's own "settings" add to
  the list's. Names become file names (characters other than letters,
  digits, '-', '_' and '.' are replaced by '_').
"""
import argparse
import json
import math
import os
import re
import sys
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import scene_json  # noqa: E402


class VariantError(ValueError):
    pass


# ---- the list ------------------------------------------------------------

def safe_name(name):
    return re.sub(r"[^A-Za-z0-9._-]", "_", str(name)).strip("._") or "variant"


def load_list(path):
    """The variants: [{name, pattern (name), palette (name), settings}] and
    the list's patterns, palettes and material."""
    with open(path, "r", encoding="utf-8") as f:
        try:
            spec = json.load(f)
        except json.JSONDecodeError as e:
            raise VariantError("%s: line %d, column %d: %s" % (path, e.lineno, e.colno, e.msg)) from None
    if not isinstance(spec, dict):
        raise VariantError("%s: the list must be a JSON object" % path)
    unknown = set(spec) - {"material", "patterns", "palettes", "settings", "variants"}
    if unknown:
        raise VariantError("%s: unknown key%s %s (expected material, patterns, palettes, settings, variants)"
                           % (path, "s" if len(unknown) > 1 else "", ", ".join(sorted(unknown))))
    patterns = spec.get("patterns") or {}
    palettes = spec.get("palettes") or {}
    common = spec.get("settings") or {}
    if "variants" in spec:
        variants = []
        for i, v in enumerate(spec["variants"]):
            if "name" not in v:
                raise VariantError("%s: variants[%d] has no name" % (path, i))
            for key, table in (("pattern", patterns), ("palette", palettes)):
                if key in v and v[key] not in table:
                    raise VariantError("%s: variants[%d] (%s): unknown %s '%s' (known: %s)"
                                       % (path, i, v["name"], key, v[key], ", ".join(table) or "none"))
            variants.append({"name": str(v["name"]), "pattern": v.get("pattern"), "palette": v.get("palette"),
                             "settings": dict(common, **(v.get("settings") or {}))})
    else:
        if not patterns and not palettes:
            raise VariantError("%s: no patterns, palettes or variants" % path)
        variants = [{"name": "%s-%s" % (p, c) if p and c else (p or c), "pattern": p, "palette": c,
                     "settings": dict(common)}
                    for p in (list(patterns) or [None]) for c in (list(palettes) or [None])]
    names = [safe_name(v["name"]) for v in variants]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise VariantError("%s: variant names that give the same file name: %s" % (path, ", ".join(dup)))
    return {"material": spec.get("material", ""), "patterns": patterns, "palettes": palettes,
            "variants": variants, "base": os.path.dirname(os.path.abspath(path))}


def resolve_pattern(ks, value, base):
    """A Pattern from a list's pattern value (file, preset:<name>, or text)."""
    import importlib
    kpattern = importlib.import_module(ks.__name__ + ".core.pattern")
    kpresets = importlib.import_module(ks.__name__ + ".core.presets")
    if not isinstance(value, str):
        raise VariantError("a pattern must be a file name, preset:<name> or pattern text, got %r" % (value,))
    if value.startswith("preset:"):
        return kpresets.load_preset(value[len("preset:"):])
    path = os.path.join(base, value)
    if "\n" not in value and (value.endswith(".knit") or os.path.isfile(path)):
        return kpattern.load(path)
    return kpattern.parse_text(value, "<variants list>")


# ---- the scene -----------------------------------------------------------

def find_material(ks, name=""):
    if name:
        mat = bpy.data.materials.get(name)
        if mat is None or ks.nodes.knit_node(mat) is None:
            known = [m.name for m in bpy.data.materials if ks.nodes.knit_node(m) is not None]
            raise VariantError("the scene has no Knit Fabric material '%s' (it has: %s)"
                               % (name, ", ".join(known) or "none"))
        return mat
    for obj in bpy.context.scene.objects:
        for slot in getattr(obj, "material_slots", ()):
            if slot.material is not None and ks.nodes.knit_node(slot.material) is not None:
                return slot.material
    raise VariantError("no object of the scene uses a Knit Fabric material")


def objects_with(ks, mat):
    return [o for o in bpy.context.scene.objects
            if o.type == "MESH" and any(s.material == mat for s in o.material_slots)]


def yarn_objects(ks, mat):
    key = ks.yarns.YARN_KEY
    return [o for o in bpy.data.objects if (o.get(key) or {}).get("material") == mat.name]


def show_mode(ks, mat, mode):
    """Render the material's objects as the shader (the meshes) or as their
    yarns (the curves), not both."""
    for o in yarn_objects(ks, mat):
        o.hide_render = mode != "yarns"
    for o in objects_with(ks, mat):
        o.hide_render = mode == "yarns"


# ---- the contact sheet ---------------------------------------------------

# A 5 x 7 pixel font: 7 rows of 5 bits per character (upper case; lower
# case is drawn upper case).
_FONT = {
    "A": (14, 17, 17, 31, 17, 17, 17), "B": (30, 17, 17, 30, 17, 17, 30), "C": (14, 17, 16, 16, 16, 17, 14),
    "D": (30, 17, 17, 17, 17, 17, 30), "E": (31, 16, 16, 30, 16, 16, 31), "F": (31, 16, 16, 30, 16, 16, 16),
    "G": (14, 17, 16, 23, 17, 17, 15), "H": (17, 17, 17, 31, 17, 17, 17), "I": (14, 4, 4, 4, 4, 4, 14),
    "J": (7, 2, 2, 2, 2, 18, 12), "K": (17, 18, 20, 24, 20, 18, 17), "L": (16, 16, 16, 16, 16, 16, 31),
    "M": (17, 27, 21, 21, 17, 17, 17), "N": (17, 17, 25, 21, 19, 17, 17), "O": (14, 17, 17, 17, 17, 17, 14),
    "P": (30, 17, 17, 30, 16, 16, 16), "Q": (14, 17, 17, 17, 21, 18, 13), "R": (30, 17, 17, 30, 20, 18, 17),
    "S": (15, 16, 16, 14, 1, 1, 30), "T": (31, 4, 4, 4, 4, 4, 4), "U": (17, 17, 17, 17, 17, 17, 14),
    "V": (17, 17, 17, 17, 17, 10, 4), "W": (17, 17, 17, 21, 21, 21, 10), "X": (17, 17, 10, 4, 10, 17, 17),
    "Y": (17, 17, 10, 4, 4, 4, 4), "Z": (31, 1, 2, 4, 8, 16, 31), "0": (14, 17, 19, 21, 25, 17, 14),
    "1": (4, 12, 4, 4, 4, 4, 14), "2": (14, 17, 1, 2, 4, 8, 31), "3": (31, 2, 4, 2, 1, 17, 14),
    "4": (2, 6, 10, 18, 31, 2, 2), "5": (31, 16, 30, 1, 1, 17, 14), "6": (6, 8, 16, 30, 17, 17, 14),
    "7": (31, 1, 2, 4, 8, 8, 8), "8": (14, 17, 17, 14, 17, 17, 14), "9": (14, 17, 17, 15, 1, 2, 12),
    "-": (0, 0, 0, 31, 0, 0, 0), "_": (0, 0, 0, 0, 0, 0, 31), ".": (0, 0, 0, 0, 0, 12, 12),
    " ": (0, 0, 0, 0, 0, 0, 0),
}


def draw_text(img, text, x0, y0, scale=2, colour=(1.0, 1.0, 1.0)):
    """Draw `text` into an (H, W, 4) array (row 0 at the top) at (x0, y0)."""
    h, w = img.shape[:2]
    x = x0
    for ch in text:
        glyph = _FONT.get(ch.upper(), _FONT["_"])
        for r, bits in enumerate(glyph):
            for c in range(5):
                if bits & (16 >> c):
                    ya, xa = y0 + r * scale, x + c * scale
                    if 0 <= ya and ya + scale <= h and 0 <= xa and xa + scale <= w:
                        img[ya:ya + scale, xa:xa + scale, :3] = colour
        x += 6 * scale
        if x + 5 * scale > w:
            break


def read_png(path):
    import numpy as np
    img = bpy.data.images.load(path, check_existing=False)
    try:
        w, h = img.size
        a = np.array(img.pixels[:], dtype=np.float32).reshape(h, w, 4)[::-1]  # row 0 at the top
    finally:
        bpy.data.images.remove(img)
    return a


def contact_sheet(entries, path, max_tile=320, label_scale=2):
    """One image of the variants' renders, [(name, png path)], in a grid,
    each labelled with its name; written as PNG to `path`."""
    import numpy as np
    tiles = [(n, read_png(p)) for n, p in entries if p and os.path.isfile(p)]
    if not tiles:
        return None
    th = max(t.shape[0] for _n, t in tiles)
    tw = max(t.shape[1] for _n, t in tiles)
    step = max(1, int(math.ceil(max(th, tw) / max_tile)))
    th, tw = int(math.ceil(th / step)), int(math.ceil(tw / step))
    label_h = 7 * label_scale + 6
    pad = 4
    cols = int(math.ceil(math.sqrt(len(tiles))))
    rows = int(math.ceil(len(tiles) / cols))
    W = cols * (tw + pad) + pad
    H = rows * (th + label_h + pad) + pad
    sheet = np.zeros((H, W, 4), dtype=np.float32)
    sheet[..., :3] = 0.12
    sheet[..., 3] = 1.0
    for i, (name, t) in enumerate(tiles):
        r, c = divmod(i, cols)
        y, x = pad + r * (th + label_h + pad), pad + c * (tw + pad)
        small = t[::step, ::step]
        sheet[y:y + small.shape[0], x:x + small.shape[1]] = small
        sheet[y:y + small.shape[0], x:x + small.shape[1], 3] = 1.0
        draw_text(sheet, name, x + 2, y + th + 3, label_scale)
    img = bpy.data.images.new("Contact Sheet", W, H, alpha=False)
    try:
        img.pixels.foreach_set(sheet[::-1].ravel())
        img.filepath_raw = path
        img.file_format = "PNG"
        img.save()
    finally:
        bpy.data.images.remove(img)
    return path, (W, H)


# ---- rendering -----------------------------------------------------------

def apply_variant(ks, mat, v, lst, original, original_pattern):
    """Set the material to the variant: the list's settings over the
    material's own, and its pattern (else the material's own)."""
    pat = resolve_pattern(ks, lst["patterns"][v["pattern"]], lst["base"]) if v["pattern"] else original_pattern
    changes = {}
    if v["palette"]:
        cols = lst["palettes"][v["palette"]]
        if not isinstance(cols, list) or not cols or len(cols) > 8:
            raise VariantError("palette '%s' must be a list of 1 to 8 colours" % v["palette"])
        for i, c in enumerate(cols):
            changes["yarn%d" % i] = tuple(c)
    changes.update(v["settings"])
    ks.api.set_parameters(mat, **original)  # what the previous variant changed, back
    ks.api.set_parameters(mat, **changes)
    if pat != ks.api.get_pattern(mat):
        ks.api.set_pattern(mat, pat)  # (compiles the shader where Blender has OSL)
    return pat


def main(argv=None):
    if argv is None:
        argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="render_variants.py")
    ap.add_argument("--variants", required=True, help="the variants list (JSON)")
    ap.add_argument("--out", required=True, help="folder for the images, the .blend files and the contact sheet")
    ap.add_argument("--samples", type=int, default=0, help="render samples (default: the scene's)")
    ap.add_argument("--resolution", default="", help="WxH (default: the scene's)")
    ap.add_argument("--mode", choices=("auto", "shader", "yarns"), default="auto")
    ap.add_argument("--yarn-samples", type=int, default=0, help="yarn points per stitch (default: the add-on's)")
    ap.add_argument("--no-blend", action="store_true", help="do not save a .blend per variant")
    ap.add_argument("--addon-zip", default="", help="install the add-on from this zip if it is not installed")
    a = ap.parse_args(argv)
    t_start = time.time()
    ks = scene_json.ensure_addon(a.addon_zip)
    lst = load_list(a.variants)
    mat = find_material(ks, lst["material"])
    for v in lst["variants"]:  # every pattern read before anything renders
        if v["pattern"]:
            try:
                resolve_pattern(ks, lst["patterns"][v["pattern"]], lst["base"])
            except (ValueError, OSError) as e:
                raise VariantError("%s: pattern '%s': %s" % (a.variants, v["pattern"], e)) from None
    mode = a.mode if a.mode != "auto" else ("shader" if ks.api.has_osl() else "yarns")
    if mode == "shader" and not ks.api.has_osl():
        raise SystemExit("render_variants: --mode shader needs a Blender whose Cycles has OSL (this one has not)")
    scene = bpy.context.scene
    if a.samples and scene.render.engine == "CYCLES":
        scene.cycles.samples = a.samples
    if a.resolution:
        w, h = (int(x) for x in a.resolution.lower().split("x"))
        scene.render.resolution_x, scene.render.resolution_y = w, h
        scene.render.resolution_percentage = 100
    if mode == "shader":
        ks.nodes.ensure_scene_renders_osl(scene)
    scene.render.image_settings.file_format = "PNG"
    os.makedirs(a.out, exist_ok=True)
    original = ks.api.get_parameters(mat)
    original_pattern = ks.api.get_pattern(mat)
    meshes = objects_with(ks, mat)
    print("render_variants: Blender %s, %d variants of '%s' on %s, mode %s (%s), %d x %d, %s samples"
          % (bpy.app.version_string, len(lst["variants"]), mat.name, ", ".join(o.name for o in meshes) or "nothing",
             mode, "the knit shader in Cycles' OSL" if mode == "shader" else "explicit yarn geometry",
             scene.render.resolution_x, scene.render.resolution_y,
             scene.cycles.samples if scene.render.engine == "CYCLES" else "?"), flush=True)
    done, failed, render_time = [], [], 0.0
    n = len(lst["variants"])
    for i, v in enumerate(lst["variants"]):
        name = safe_name(v["name"])
        t0 = time.time()
        try:
            pat = apply_variant(ks, mat, v, lst, original, original_pattern)
            what = "the knit shader"
            if mode == "yarns":
                curves = 0
                kw = {"samples": a.yarn_samples} if a.yarn_samples else {}
                for o in meshes:
                    yo = ks.yarns.generate(o, material=mat.name, **kw)
                    curves += int(yo[ks.yarns.YARN_KEY]["curves"])
                what = "%s yarn curves" % format(curves, ",")
            show_mode(ks, mat, mode)
            png = os.path.join(a.out, name + ".png")
            scene.render.filepath = png
            t1 = time.time()
            bpy.ops.render.render(write_still=True)
            dt = time.time() - t1
            render_time += dt
            blend = ""
            if not a.no_blend:
                blend = os.path.join(a.out, name + ".blend")
                try:
                    bpy.ops.file.pack_all()
                except RuntimeError:
                    pass
                bpy.ops.wm.save_as_mainfile(filepath=blend, copy=True, compress=True)
            print("[%d/%d] %s: pattern %s (%d x %d), palette %s, %s; rendered in %.1f s (%.1f s in all) -> %s%s"
                  % (i + 1, n, name, v["pattern"] or "as is", pat.rows, pat.cols, v["palette"] or "as is", what,
                     dt, time.time() - t0, png, (" and " + os.path.basename(blend)) if blend else ""), flush=True)
            done.append((name, png))
        except (ValueError, RuntimeError, OSError) as e:
            first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
            print("[%d/%d] %s: FAILED: %s" % (i + 1, n, name, first), flush=True)
            failed.append((name, first))
    # the scene as it was
    try:
        ks.api.set_parameters(mat, **original)
        ks.api.set_pattern(mat, original_pattern)
    except ValueError:
        pass
    sheet = contact_sheet(done, os.path.join(a.out, "contact_sheet.png"))
    print("render_variants: %d of %d variants rendered in %.1f s (rendering %.1f s), mode %s; %s; %s"
          % (len(done), n, time.time() - t_start, render_time, mode,
             "contact sheet %s (%d x %d)" % (sheet[0], sheet[1][0], sheet[1][1]) if sheet else "no contact sheet",
             "failed: " + ", ".join(f[0] for f in failed) if failed else "none failed"), flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    try:
        status = main()
    except VariantError as e:
        print("render_variants: %s" % e, flush=True)
        status = 2
    if status:
        sys.exit(status)

"""The swatch preview (issue 54), in Debian's Blender 3.4 and bpy 5.0: the
knitshade CLI ($KNIT_CLI, else <source>/build/knitshade) set in the add-on's
preferences renders the material's swatch; the scene file it is given
carries the material's settings; the image is loaded and made displayable
through the scene's view transform; a colour change changes it; the
polled (non-waiting) path ends the same way; a missing CLI and a failing
one give the panel's message, and the operator a warning, not a traceback.
"""
import json
import os
import stat
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import inside as T  # noqa: E402


def cli():
    for cand in (os.environ.get("KNIT_CLI", ""), os.path.join(T.SOURCE, "build", "knitshade")):
        if cand and os.path.isfile(cand) and os.access(cand, os.X_OK):
            return cand
    return ""


def pixels(img):
    w, h = img.size
    return np.array(img.pixels[:], dtype=np.float32).reshape(h, w, 4)[..., :3]


def main():
    T.say(T.blender())
    mod = T.install()
    pv = mod.preview
    prefs = bpy.context.preferences.addons[mod.__name__].preferences
    T.fresh_scene()
    obj = T.plane()
    mat = mod.api.add_knit_material(obj, pattern="K K P P\nK K P P\nP P K K\nP P K K\ncolors:\n0 0 1 1\n0 0 1 1\n"
                                    "1 1 0 0\n1 1 0 0", colours=[(0.7, 0.1, 0.08), (0.85, 0.8, 0.7)], a=1.4,
                                    r=0.7, setup_scene=False)

    # a missing CLI: the panel's message, the operator's warning
    prefs.cli_path = os.path.join(T.OUT, "no-such-knitshade")
    st = pv.render(mat)
    T.equal(st.status, "error", "preview with a missing CLI")
    T.check("does not exist" in st.message and "no-such-knitshade" in st.message, "message: %r" % st.message)
    T.equal(bpy.ops.knitshade.preview_swatch(material=mat.name), {"CANCELLED"}, "the operator with no CLI")
    T.say("missing CLI: " + st.message)
    prefs.cli_path = ""
    path, why = pv.find_cli()
    T.say("no preference: %s" % (path or why))

    # a failing CLI: its exit status and last words
    fake = T.out_path("fake-knitshade")
    with open(fake, "w") as f:
        f.write("#!/bin/sh\necho 'knitshade: cannot open the display of doom' >&2\nexit 3\n")
    os.chmod(fake, os.stat(fake).st_mode | stat.S_IXUSR)
    prefs.cli_path = fake
    st = pv.render(mat)
    T.equal(st.status, "error", "preview with a failing CLI")
    T.check("exit status 3" in st.message and "display of doom" in st.message, "message: %r" % st.message)
    T.say("failing CLI: " + st.message)

    exe = cli()
    if not exe:
        T.say("SKIP: no knitshade CLI ($KNIT_CLI or build/knitshade): the preview's render did not run")
        return
    prefs.cli_path = exe
    t0 = time.time()
    st = pv.render(mat)
    dt = time.time() - t0
    T.equal((st.status, st.message), ("done", ""), "preview")
    T.say("preview rendered in %.1f s (%s)" % (dt, st.stamp))
    with open(os.path.join(st.dir, "swatch.json")) as f:
        scene = json.load(f)
    km = scene["materials"]["knit"]
    T.equal(km["pattern"], ["KKPP", "KKPP", "PPKK", "PPKK"], "the swatch's pattern")
    T.equal(km["colors"], [[0, 0, 1, 1], [0, 0, 1, 1], [1, 1, 0, 0], [1, 1, 0, 0]], "the swatch's colour matrix")
    T.check(np.allclose(km["yarn_colors"], [(0.7, 0.1, 0.08), (0.85, 0.8, 0.7)], atol=1e-6), "yarn colours")
    T.check(abs(km["a"] - 1.4) < 1e-6 and abs(km["r"] - 0.7) < 1e-6, "a, r: %r, %r" % (km["a"], km["r"]))
    T.equal(km["bsdf_model"], "cycles", "bsdf_model")
    T.equal(km["cycles_version"], 4 if bpy.app.version[0] < 5 else 5, "the Cycles whose rules the swatch follows")
    img = bpy.data.images.get(pv.IMAGE_PREFIX + mat.name)
    T.check(img is not None and tuple(img.size) == (192, 192), "the preview image datablock")
    a = pixels(img)
    T.check(float(a.std()) > 0.01, "the swatch image is flat")
    T.check(os.path.isfile(os.path.join(st.dir, "swatch_display.png")), "the display PNG")
    shutil_copy(os.path.join(st.dir, "swatch_display.png"), T.out_path("swatch_1.png"))

    # another colour: another image, through the polled path
    mod.api.set_parameters(mat, yarn0=(0.1, 0.2, 0.7))
    key = pv.material_key(mat)
    T.check(key != st.key, "the settings key did not change with the colour")
    st = pv.render(mat, wait=False)
    T.equal(st.status, "running", "the polled preview")
    t0 = time.time()
    while pv._poll(mat.name) is not None:
        time.sleep(0.05)
        T.check(time.time() - t0 < 120, "the CLI did not end in 2 minutes")
    T.equal((st.status, st.message), ("done", ""), "the polled preview")
    T.equal(st.key, key, "the preview's key")
    b = pixels(bpy.data.images[pv.IMAGE_PREFIX + mat.name])
    yarn = np.abs(a - b).sum(axis=2) > 0.03  # where the colour change shows: the red yarn's pixels
    T.check(yarn.mean() > 0.05, "the colour change shows in %.1f%% of the swatch's pixels" % (100 * yarn.mean()))
    ma, mb = a[yarn].mean(axis=0), b[yarn].mean(axis=0)
    T.say("yarn colour 0 red, then blue: %.1f%% of the pixels change, from %s to %s"
          % (100 * yarn.mean(), np.round(ma, 3), np.round(mb, 3)))
    T.check(ma[0] > ma[2] and mb[2] > mb[0] and (ma[0] - ma[2]) - (mb[0] - mb[2]) > 0.02,
            "the swatches do not show their yarn colours")
    shutil_copy(os.path.join(st.dir, "swatch_display.png"), T.out_path("swatch_2.png"))
    T.equal(bpy.ops.knitshade.preview_swatch(material=mat.name), {"FINISHED"}, "the operator")


def shutil_copy(a, b):
    import shutil
    shutil.copyfile(a, b)


T.run(main)

"""Cycles' closure weights (native/kernel/bsdf_cycles.h) and the isotropic
multi-scale footprint (knit_footprint_isotropic, multiscale.h) computed by
OSL inside a real Cycles against the same kernel compiled as C++: a plane
under an orthographic camera, one sample a pixel, a Script node whose
shader (the kernel headers inlined) turns the UV into a view direction and
outputs the weights, rendered as emission pass by pass (the same seed, so
the same sample positions; the UV is one of the passes). The C++ side is
a small program built here with the system's C++ compiler.

  KNIT_BPY_PYTHON tests/osl/cycles_weights_bpy.py     (scripts/setup-bpy.sh)

Exits 77 when bpy, its OSL or a C++ compiler is missing; 1 when a value
differs by more than 1e-4 (relative, 1e-6 absolute); measured 1.5e-5
with bpy 5.0.1 (docs/cycles.md).
"""
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
KERNEL = os.path.join(ROOT, "native", "kernel")

try:
    import bpy  # noqa: F401
    import _cycles
except ImportError as e:
    print(f"bpy is not importable here ({e}): the check did NOT run (scripts/setup-bpy.sh, KNIT_BPY_PYTHON)")
    sys.exit(77)
if not getattr(_cycles, "with_osl", False):
    print("this bpy's Cycles has no OSL: the check did NOT run")
    sys.exit(77)
CXX = shutil.which(os.environ.get("CXX", "c++"))
if not CXX:
    print("no C++ compiler for the reference: the check did NOT run")
    sys.exit(77)

import numpy as np  # noqa: E402

sys.path.insert(0, HERE)
import cycles_bpy as cb  # noqa: E402  (its scene helpers)

OUT = tempfile.mkdtemp(prefix="knit-cycles-weights-")

# One yarn BSDF (two layers, ply shadow 0.9) and the view direction from the
# UV: theta = 88 u degrees, phi = 360 v degrees; footprint lengths from u.
SHADER = r"""
shader cycles_weights(point UV = point(0, 0, 0),
    output float spec = 0, output float through = 0, output float br = 0, output float bt = 0, output float p3 = 0,
    output float fxx = 0, output float fxy = 0, output float fyy = 0, output float uu = 0, output float vv = 0) {
  float th = radians(88.0) * UV[0], ph = radians(360.0) * UV[1];
  vector wo = vector(sin(th) * cos(ph), sin(th) * sin(ph), cos(th));
  KYarnBsdf yb = yarn_bsdf_make(bsdf_mf_make(0.15, 0.45, 1.55), bsdf_mf_make(0.06, 0.1, 1.55), vector(0.8, 0.5, 0.3),
                                vector(0.8, 0.5, 0.3), 0.7, 0.6, 0.9, bsdf_att_make(1.0, 2));
  KCyclesLobes l = yarn_cycles_lobes(yb, wo);
  KYarnCycles m = yarn_cycles_make(yb, wo);
  spec = l.spec; through = l.through; br = KX(l.body_r); bt = KX(l.body_t); p3 = m.p3;
  KFootprintAxes f = knit_footprint_isotropic(0.01 + 0.02 * UV[0], 0.03, wo, 40.0);
  fxx = KX(f.fx); fxy = KY(f.fx); fyy = KY(f.fy);
  uu = UV[0]; vv = UV[1];
}
"""

REFERENCE = r"""
#include <cmath>
#include <cstdio>
#include "knit/kernel.h"
using namespace knit::k;
int main() {
  KYarnBsdf yb = yarn_bsdf_make(bsdf_mf_make(0.15f, 0.45f, 1.55f), bsdf_mf_make(0.06f, 0.1f, 1.55f),
                                kv3(0.8f, 0.5f, 0.3f), kv3(0.8f, 0.5f, 0.3f), 0.7f, 0.6f, 0.9f, bsdf_att_make(1.0f, 2));
  float u, v;
  while (std::scanf("%f %f", &u, &v) == 2) {
    const float th = 88.0f * 0.017453292519943295f * u, ph = 360.0f * 0.017453292519943295f * v;
    const kvec3 wo = kv3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
    const KCyclesLobes l = yarn_cycles_lobes(yb, wo);
    const KYarnCycles m = yarn_cycles_make(yb, wo);
    const KFootprintAxes f = knit_footprint_isotropic(0.01f + 0.02f * u, 0.03f, wo, 40.0f);
    std::printf("%.9g %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", l.spec, l.through, l.body_r.x, l.body_t.x, m.p3,
                f.fx.x, f.fx.y, f.fy.y);
  }
}
"""
NAMES = ["spec", "through", "br", "bt", "p3", "fxx", "fxy", "fyy"]


def shader_source():
    """The OSL host header and the kernel headers in knit_kernel.h's order, inlined, then the shader."""
    with open(os.path.join(KERNEL, "knit_kernel.h")) as f:
        order = [line.split('"')[1] for line in f if line.startswith("#include")]
    parts = [open(os.path.join(ROOT, "osl", "knit_osl_host.h")).read()]
    parts += [open(os.path.join(KERNEL, h)).read() for h in order]
    text = "\n".join(parts)
    text = "\n".join(line for line in text.split("\n") if not line.strip().startswith("#include"))
    return text + SHADER


def reference(u, v):
    src = os.path.join(OUT, "reference.cpp")
    exe = os.path.join(OUT, "reference")
    with open(src, "w") as f:
        f.write(REFERENCE)
    subprocess.run([CXX, "-O2", "-std=c++17", "-I", os.path.join(ROOT, "native", "include"), "-I", KERNEL, src,
                    "-o", exe], check=True)
    text = "\n".join(f"{a:.9g} {b:.9g}" for a, b in zip(u, v))
    out = subprocess.run([exe], input=text, capture_output=True, text=True, check=True).stdout
    return np.array([[float(x) for x in line.split()] for line in out.split("\n") if line])


def main():
    res = 24
    scene = cb.new_scene(res)
    ob = cb.plane_with_uvs()
    cam = bpy.data.cameras.new("cam")
    cam.type = "ORTHO"
    cam.ortho_scale = 1.9
    co = bpy.data.objects.new("cam", cam)
    scene.collection.objects.link(co)
    co.location = (0.0, 0.0, 3.0)
    scene.camera = co
    mat = bpy.data.materials.new("weights")
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    sn, reports = cb.script_node(nt, "weights.osl", shader_source())
    if [s.identifier for s in sn.outputs] != NAMES + ["uu", "vv"]:
        print(f"FAIL: the shader did not compile ({reports})")
        return 1
    uvn = nt.nodes.new("ShaderNodeUVMap")
    nt.links.new(uvn.outputs["UV"], sn.inputs["UV"])
    comb = nt.nodes.new("ShaderNodeCombineXYZ")
    emit = nt.nodes.new("ShaderNodeEmission")
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(comb.outputs[0], emit.inputs["Color"])
    nt.links.new(emit.outputs[0], out.inputs["Surface"])
    ob.data.materials.append(mat)
    got = {}
    passes = (("uu", "vv", "p3"), ("spec", "through", "br"), ("bt", "fxx", "fxy"), ("fyy", None, None))
    for i, names in enumerate(passes):
        for slot, name in zip("XYZ", names):
            for link in list(comb.inputs[slot].links):
                nt.links.remove(link)
            comb.inputs[slot].default_value = 0.0
            if name:
                nt.links.new(sn.outputs[name], comb.inputs[slot])
        img = cb.render_to_array(scene, os.path.join(OUT, f"pass_{i}.exr"))
        for c, name in enumerate(names):
            if name:
                got[name] = img[..., c].ravel()
    u, v = got["uu"], got["vv"]
    on = (u > 0.001) & (u < 0.999) & (v > 0.001) & (v < 0.999)
    ref = reference(u[on], v[on])
    bad = 0
    for j, name in enumerate(NAMES):
        d = np.abs(got[name][on] - ref[:, j])
        rel = d / np.maximum(np.abs(ref[:, j]), 1e-2)
        ok = bool(np.all((rel <= 1e-4) | (d <= 1e-6)))
        bad += not ok
        print(f"{'ok:  ' if ok else 'FAIL:'} {name:8s} OSL in Cycles against C++ over {on.sum()} pixels: "
              f"max |difference| {d.max():.2e}, relative {rel.max():.2e} (values {ref[:, j].min():.4g} to "
              f"{ref[:, j].max():.4g})")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

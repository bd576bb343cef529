#!/usr/bin/python3
"""Writes a procedural lat-long sky (Radiance .hdr, RGBE) for the examples and
the golden tests: a blue-to-white sky, a dim brownish ground below the
horizon and a small bright sun disk, in the renderer's convention (+y up,
image centre toward -z, u growing toward +x; docs/scene-format.md).

Standard library only:
  /usr/bin/python3 scripts/make_envmap.py OUT.hdr [WIDTH [SUN_ELEVATION_DEG [SUN_AZIMUTH_DEG]]]
"""
import math
import struct
import sys


def rgbe(r, g, b):
    v = max(r, g, b)
    if v < 1e-32:
        return b"\0\0\0\0"
    m, e = math.frexp(v)
    scale = m * 256.0 / v
    return struct.pack("BBBB", min(255, int(r * scale)), min(255, int(g * scale)), min(255, int(b * scale)), e + 128)


def direction(u, v):
    phi, theta = 2 * math.pi * (u - 0.5), math.pi * v
    return (math.sin(theta) * math.sin(phi), math.cos(theta), -math.sin(theta) * math.cos(phi))


def sky(d, sun, sun_cos, sun_radiance):
    if d[1] < 0:
        k = min(1.0, -d[1] * 4)
        return (0.20 - 0.08 * k, 0.17 - 0.07 * k, 0.13 - 0.06 * k)
    t = d[1] ** 0.5
    r, g, b = 0.95 - 0.65 * t, 0.97 - 0.47 * t, 1.0 - 0.1 * t
    c = d[0] * sun[0] + d[1] * sun[1] + d[2] * sun[2]
    glow = 0.6 * max(0.0, c) ** 32
    r, g, b = r + glow, g + glow * 0.85, b + glow * 0.6
    if c >= sun_cos:
        return (sun_radiance, sun_radiance * 0.92, sun_radiance * 0.8)
    return (r, g, b)


def main():
    out = sys.argv[1]
    width = int(sys.argv[2]) if len(sys.argv) > 2 else 256
    elev = math.radians(float(sys.argv[3]) if len(sys.argv) > 3 else 35.0)
    azim = math.radians(float(sys.argv[4]) if len(sys.argv) > 4 else 40.0)
    height = width // 2
    sun = (math.cos(elev) * math.sin(azim), math.sin(elev), -math.cos(elev) * math.cos(azim))
    sun_radius = math.radians(4.0)
    sun_cos = math.cos(sun_radius)
    sun_radiance = 160.0
    with open(out, "wb") as f:
        f.write(b"#?RADIANCE\n# procedural sky from scripts/make_envmap.py\nFORMAT=32-bit_rle_rgbe\n\n")
        f.write(f"-Y {height} +X {width}\n".encode("ascii"))
        for j in range(height):
            row = bytearray()
            for i in range(width):
                # 4 x 4 supersampling so the small sun keeps its energy at low resolution.
                acc = [0.0, 0.0, 0.0]
                for sj in range(4):
                    for si in range(4):
                        d = direction((i + (si + 0.5) / 4) / width, (j + (sj + 0.5) / 4) / height)
                        c = sky(d, sun, sun_cos, sun_radiance)
                        acc = [acc[k] + c[k] / 16 for k in range(3)]
                row += rgbe(*acc)
            f.write(row)
    print(f"wrote {out}: {width}x{height}, sun at elevation {math.degrees(elev):.0f} deg, azimuth {math.degrees(azim):.0f} deg")


if __name__ == "__main__":
    main()

"""Explicit yarns laid on a mesh through its UVs (numpy, no bpy).

The native library's explicit_yarns() gives the yarn centre curves in
pattern space (x along the course, y along the wale, z out of the fabric,
stitch-curve units). A curve point (x, y, z) goes where the knit shader
would show it (docs/scene-format.md "knit", native/render/yarn_tubes.cpp):

    UV     (u, v) = (x, y) / uv_scale
    world  P(u, v) + ((z - shell_top) / S) N(u, v),   radius r / S

with P and N the surface point and its interpolated (shading) normal at
that UV, and S = uv_scale / sqrt(|dP/du| |dP/dv|) the pattern units per
world unit of the triangle holding it. The mesh is the top of the yarn
shell: the yarns hang below it, on the side opposite its normals.

A point outside every UV triangle ends its polyline, and so does a step
from one UV island to another (two triangles are in one island when they
share an edge whose two corners have the same UVs in both): yarns stop at
seams instead of jumping across the mesh.

Everything here takes and returns numpy arrays; the Blender side
(yarns.py) gathers the mesh and builds the curves object.
"""
import math

import numpy as np

# A triangle whose UV area is below this share of the UV bounding box's
# area, or whose world area is below this share of the mesh's bounding
# box's squared diagonal, is degenerate: skipped (no yarn lands on it).
DEGENERATE_REL = 1e-12
# Barycentric slack: a point on a shared edge belongs to both triangles
# (the first in mesh order takes it), a point on the border to its triangle.
INSIDE_EPS = 1e-9
# UV islands whose median stitch scales differ by more than this are
# worth a warning (stitches of visibly different sizes).
ISLAND_SCALE_WARN = 1.5
# Bytes per curve point in Blender's Curves data (position 12, radius 4,
# colour 16: a float colour, the type Cycles 3.4 reads on curves) and per
# curve (offset 4, type 1): estimate() and the report.
BLENDER_BYTES_PER_POINT = 32
BLENDER_BYTES_PER_CURVE = 5
# Cycles' copy for rendering, per point: key and radius (16), the colour
# attribute (16), the BVH's curve segments; measured on the scarf (docs/
# blender-yarns.md): 92 bytes a point in Cycles 5.0.1, 167 in 3.4.1.
CYCLES_BYTES_PER_POINT = 170


class LayoutError(ValueError):
    """A mesh the yarns cannot be laid on (no UV area at all)."""


# ---- the surface ---------------------------------------------------------

def triangle_scales(pos, uv, uv_scale):
    """S per triangle: uv_scale / sqrt(|dP/du| |dP/dv|) (pattern units per
    world unit), from (T, 3, 3) corner positions and (T, 3, 2) corner UVs;
    nan where the UV or the world triangle is degenerate."""
    e1, e2 = pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0]
    d1, d2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        dpdu = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) / det[:, None]
        dpdv = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) / det[:, None]
        lu = np.linalg.norm(dpdu, axis=1)
        lv = np.linalg.norm(dpdv, axis=1)
        s = uv_scale / np.sqrt(lu * lv)
    s[~np.isfinite(s) | (s <= 0)] = np.nan
    return s


def uv_islands(tri_vertices, tri_uv):
    """Island id per triangle (0..n-1, numbered in order of first
    appearance): triangles sharing an edge with the same vertices and the
    same UVs at both ends are one island."""
    t = len(tri_vertices)
    if t == 0:
        return np.zeros(0, dtype=np.int64)
    # the 3 edges of every triangle, as (vertex a, vertex b, uv a, uv b) with a < b
    a = tri_vertices[:, [0, 1, 2]].reshape(-1)
    b = tri_vertices[:, [1, 2, 0]].reshape(-1)
    ua = tri_uv[:, [0, 1, 2]].reshape(-1, 2).astype(np.float32)
    ub = tri_uv[:, [1, 2, 0]].reshape(-1, 2).astype(np.float32)
    swap = a > b
    a2, b2 = np.where(swap, b, a), np.where(swap, a, b)
    ua2 = np.where(swap[:, None], ub, ua)
    ub2 = np.where(swap[:, None], ua, ub)
    key = np.empty((len(a2), 6), dtype=np.int64)
    key[:, 0], key[:, 1] = a2, b2
    key[:, 2:4] = ua2.view(np.int32)
    key[:, 4:6] = ub2.view(np.int32)
    _, inverse = np.unique(key, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    tri_of_edge = np.repeat(np.arange(t), 3)
    order = np.argsort(inverse, kind="stable")
    inv_sorted = inverse[order]
    same = inv_sorted[1:] == inv_sorted[:-1]
    pa = tri_of_edge[order[:-1][same]]
    pb = tri_of_edge[order[1:][same]]
    labels = np.arange(t)
    while True:  # min-label propagation with pointer jumping
        m = np.minimum(labels[pa], labels[pb])
        new = labels.copy()
        np.minimum.at(new, pa, m)
        np.minimum.at(new, pb, m)
        new = new[new]
        if np.array_equal(new, labels):
            break
        labels = new
    _, first, ids = np.unique(labels, return_index=True, return_inverse=True)
    # number islands in order of their first triangle
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first)] = np.arange(len(first))
    return rank[ids.reshape(-1)]


class UvGrid:
    """Point location in UV space: a uniform grid over the triangles' UV
    bounding box, each cell listing (in mesh order) the triangles whose UV
    bounds overlap it. locate() is vectorised over points."""

    def __init__(self, tri_uv, valid):
        self.tri_uv = np.asarray(tri_uv, dtype=np.float64)
        idx = np.nonzero(valid)[0]
        self.count = len(idx)
        if self.count == 0:
            self.lo = self.hi = np.zeros(2)
            self.nx = self.ny = 1
            self.start = np.zeros(2, dtype=np.int64)
            self.tris = np.zeros(0, dtype=np.int64)
            return
        uv = self.tri_uv[idx]
        tlo, thi = uv.min(axis=1), uv.max(axis=1)
        self.lo, self.hi = tlo.min(axis=0), thi.max(axis=0)
        ext = np.maximum(self.hi - self.lo, 1e-12)
        cells = max(1, min(4 * 1024 * 1024, self.count))
        aspect = ext[0] / ext[1]
        nx = int(max(1, min(4096, round(math.sqrt(cells * aspect)))))
        ny = int(max(1, min(4096, round(cells / nx))))
        self.nx, self.ny = nx, ny
        self.scale = np.array([nx, ny], dtype=np.float64) / ext
        c0 = self._cell(tlo)
        c1 = self._cell(thi)
        wx = c1[:, 0] - c0[:, 0] + 1
        wy = c1[:, 1] - c0[:, 1] + 1
        n = wx * wy
        total = int(n.sum())
        rep = np.repeat(np.arange(len(idx)), n)
        j = np.arange(total) - np.repeat(np.cumsum(n) - n, n)
        cx = c0[rep, 0] + j % wx[rep]
        cy = c0[rep, 1] + j // wx[rep]
        cell = cy * nx + cx
        order = np.lexsort((rep, cell))  # by cell, then mesh order
        self.tris = idx[rep[order]]
        counts = np.bincount(cell, minlength=nx * ny)
        self.start = np.concatenate([[0], np.cumsum(counts)])

    def _cell(self, uv):
        c = np.floor((uv - self.lo) * self.scale).astype(np.int64)
        c[:, 0] = np.clip(c[:, 0], 0, self.nx - 1)
        c[:, 1] = np.clip(c[:, 1], 0, self.ny - 1)
        return c

    def locate(self, uv):
        """(triangle index or -1, barycentrics (N, 3)) of (N, 2) UV points:
        the first triangle in mesh order that contains the point."""
        uv = np.asarray(uv, dtype=np.float64)
        n = len(uv)
        tri = np.full(n, -1, dtype=np.int64)
        bary = np.zeros((n, 3))
        if self.count == 0 or n == 0:
            return tri, bary
        inside_box = np.all((uv >= self.lo - 1e-9) & (uv <= self.hi + 1e-9), axis=1)
        pts = np.nonzero(inside_box)[0]
        if len(pts) == 0:
            return tri, bary
        cell = self._cell(uv[pts])
        cell = cell[:, 1] * self.nx + cell[:, 0]
        first = self.start[cell]
        cnt = self.start[cell + 1] - first
        s = 0
        todo = np.nonzero(cnt > 0)[0]
        while len(todo):
            cand = self.tris[first[todo] + s]
            t = self.tri_uv[cand]
            p = uv[pts[todo]]
            d1, d2, dp = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0], p - t[:, 0]
            det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
            b1 = (dp[:, 0] * d2[:, 1] - dp[:, 1] * d2[:, 0]) / det
            b2 = (d1[:, 0] * dp[:, 1] - d1[:, 1] * dp[:, 0]) / det
            b0 = 1.0 - b1 - b2
            ok = (b0 >= -INSIDE_EPS) & (b1 >= -INSIDE_EPS) & (b2 >= -INSIDE_EPS)
            hit = todo[ok]
            tri[pts[hit]] = cand[ok]
            bary[pts[hit]] = np.stack([b0[ok], b1[ok], b2[ok]], axis=1)
            s += 1
            todo = todo[~ok]
            todo = todo[cnt[todo] > s]
        return tri, bary


class Surface:
    """A triangle mesh with UVs, ready to take yarns.

    pos      (T, 3, 3) world positions of the triangles' corners
    normals  (T, 3, 3) their shading normals (world; normalised or not)
    uv       (T, 3, 2) their UVs
    vertices (T, 3)    their vertex indices (for the UV islands)
    uv_scale pattern units per UV unit

    Attributes: scale (S per triangle, nan on degenerate ones), island (per
    triangle), degenerate (count), grid (UvGrid of the valid triangles),
    uv_area (of the valid triangles)."""

    def __init__(self, pos, normals, uv, vertices, uv_scale):
        self.pos = np.asarray(pos, dtype=np.float64).reshape(-1, 3, 3)
        self.normals = np.asarray(normals, dtype=np.float64).reshape(-1, 3, 3)
        self.uv = np.asarray(uv, dtype=np.float64).reshape(-1, 3, 2)
        self.vertices = np.asarray(vertices, dtype=np.int64).reshape(-1, 3)
        self.uv_scale = float(uv_scale)
        t = len(self.pos)
        self.triangles = t
        d1, d2 = self.uv[:, 1] - self.uv[:, 0], self.uv[:, 2] - self.uv[:, 0]
        uv_area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
        area = 0.5 * np.linalg.norm(np.cross(self.pos[:, 1] - self.pos[:, 0], self.pos[:, 2] - self.pos[:, 0]),
                                    axis=1)
        if t:
            uvext = self.uv.reshape(-1, 2).max(axis=0) - self.uv.reshape(-1, 2).min(axis=0)
            ext = self.pos.reshape(-1, 3).max(axis=0) - self.pos.reshape(-1, 3).min(axis=0)
            uv_tol = DEGENERATE_REL * max(float(uvext[0] * uvext[1]), 1e-30)
            tol = DEGENERATE_REL * max(float(ext @ ext), 1e-30)
        else:
            uv_tol = tol = 0.0
        self.scale = triangle_scales(self.pos, self.uv, self.uv_scale)
        valid = (uv_area > uv_tol) & (area > tol) & np.isfinite(self.scale) \
            & np.all(np.isfinite(self.uv.reshape(t, -1)), axis=1) \
            & np.all(np.isfinite(self.pos.reshape(t, -1)), axis=1)
        self.valid = valid
        self.degenerate = int(t - valid.sum())
        self.first_degenerate = int(np.argmin(valid)) if self.degenerate else -1
        self.uv_area = float(uv_area[valid].sum())
        self.area = float(area[valid].sum())
        self.island = uv_islands(self.vertices, self.uv)
        self.islands = int(self.island.max()) + 1 if t else 0
        self.grid = UvGrid(self.uv, valid)
        self._uv_area_tri = uv_area

    @property
    def uv_min(self):
        return self.grid.lo

    @property
    def uv_max(self):
        return self.grid.hi

    def island_scales(self):
        """[(island, median S weighted by UV area, UV area)] of the islands
        with valid triangles, largest first."""
        out = []
        for i in range(self.islands):
            m = (self.island == i) & self.valid
            if not m.any():
                continue
            s, w = self.scale[m], self._uv_area_tri[m]
            order = np.argsort(s)
            cw = np.cumsum(w[order])
            med = float(s[order][np.searchsorted(cw, 0.5 * cw[-1])])
            out.append((i, med, float(w.sum())))
        out.sort(key=lambda x: -x[2])
        return out

    def scale_warning(self, name):
        """A sentence when UV islands of a noticeable size (1% of the UV
        area or more) differ in stitch scale by more than ISLAND_SCALE_WARN;
        "" otherwise."""
        isl = [x for x in self.island_scales() if x[2] >= 0.01 * self.uv_area]
        if len(isl) < 2:
            return ""
        lo = min(isl, key=lambda x: x[1])
        hi = max(isl, key=lambda x: x[1])
        ratio = hi[1] / lo[1]
        if ratio <= ISLAND_SCALE_WARN:
            return ""
        return ("%s: UV islands of very different scales: stitches %.1fx larger on island %d "
                "(%.4g pattern units per world unit) than on island %d (%.4g); rescale the UV islands "
                "(Average Islands Scale) for stitches of one size" % (name, ratio, lo[0], lo[1], hi[0], hi[1]))

    def place(self, pts):
        """Lay pattern-space points (N, 3) on the surface. Returns (tri,
        position (N, 3), normal (N, 3), S (N,)); tri is -1 (and the rest
        nan) for points outside every UV triangle."""
        pts = np.asarray(pts, dtype=np.float64)
        top = getattr(self, "shell_top", None)
        if top is None:
            raise LayoutError("Surface.shell_top is not set")
        uv = pts[:, :2] / self.uv_scale
        tri, b = self.grid.locate(uv)
        ok = tri >= 0
        n = len(pts)
        pos = np.full((n, 3), np.nan)
        nor = np.full((n, 3), np.nan)
        s = np.full(n, np.nan)
        t = tri[ok]
        bb = b[ok][:, :, None]
        p = (self.pos[t] * bb).sum(axis=1)
        nn = (self.normals[t] * bb).sum(axis=1)
        ln = np.linalg.norm(nn, axis=1)
        fallback = self.normals[t, 0]
        nn = np.where(ln[:, None] > 1e-12, nn / np.maximum(ln, 1e-300)[:, None], fallback)
        st = self.scale[t]
        pos[ok] = p + nn * ((pts[ok, 2] - top) / st)[:, None]
        nor[ok] = nn
        s[ok] = st
        return tri, pos, nor, s


# ---- tiling and estimates ------------------------------------------------

def tiles(uv_min, uv_max, uv_scale, period):
    """(tx0, ty0, tiles_u, tiles_v): the whole pattern repeats covering the
    UV rectangle, as the native renderer takes them (yarn_tubes.cpp)."""
    px, py = period
    tx0 = int(math.floor(uv_scale * float(uv_min[0]) / px))
    tx1 = int(math.ceil(uv_scale * float(uv_max[0]) / px))
    ty0 = int(math.floor(uv_scale * float(uv_min[1]) / py))
    ty1 = int(math.ceil(uv_scale * float(uv_max[1]) / py))
    return tx0, ty0, max(1, tx1 - tx0), max(1, ty1 - ty0)


def estimate(surface, period, rows, cols, samples):
    """What laying the yarns would make, before it is done: {tiles_u,
    tiles_v, rows (knitted rows over the UV rectangle), points_total (curve
    points generated), points (those expected on the mesh: the total times
    the UV area's share of the rectangle), blender_bytes, cycles_bytes}."""
    tx0, ty0, tu, tv = tiles(surface.uv_min, surface.uv_max, surface.uv_scale, period)
    nrows = rows * tv
    total = nrows * (cols * tu * samples + 1)
    box = float(np.prod(np.maximum(surface.uv_max - surface.uv_min, 1e-30)))
    share = min(1.0, surface.uv_area / box) if box > 0 else 0.0
    pts = int(total * share)
    # rows crossing the mesh, at least once per island they cross
    curves = int(min(nrows, nrows * share + surface.islands)) + surface.islands
    return {
        "tiles_u": tu, "tiles_v": tv, "tx0": tx0, "ty0": ty0, "rows": nrows, "points_total": int(total),
        "points": pts, "curves": curves,
        "blender_bytes": pts * BLENDER_BYTES_PER_POINT + curves * BLENDER_BYTES_PER_CURVE,
        "cycles_bytes": pts * CYCLES_BYTES_PER_POINT,
    }


def human_bytes(n):
    for unit, div in (("GB", 1 << 30), ("MB", 1 << 20), ("kB", 1 << 10)):
        if n >= div:
            return "%.1f %s" % (n / div, unit)
    return "%d B" % n


# ---- splitting -----------------------------------------------------------

def split_pieces(tri, island, min_points=2):
    """Pieces of one polyline: given the triangle of every point (-1:
    outside) and the island of every triangle, the (start, end) index
    ranges of the runs of points inside one island, of at least
    `min_points` points."""
    tri = np.asarray(tri)
    n = len(tri)
    if n == 0:
        return np.zeros((0, 2), dtype=np.int64)
    ok = tri >= 0
    isl = np.where(ok, island[np.where(ok, tri, 0)], -1)
    prev_ok = np.concatenate([[False], ok[:-1]])
    prev_isl = np.concatenate([[-2], isl[:-1]])
    start = ok & (~prev_ok | (isl != prev_isl))
    nxt_ok = np.concatenate([ok[1:], [False]])
    nxt_isl = np.concatenate([isl[1:], [-2]])
    end = ok & (~nxt_ok | (isl != nxt_isl))
    s = np.nonzero(start)[0]
    e = np.nonzero(end)[0] + 1
    keep = (e - s) >= min_points
    return np.stack([s[keep], e[keep]], axis=1)


class Layout:
    """Yarns laid band by band (one band = one vertical pattern repeat of
    rows, the full width), so a caller can report progress and stop.

    band_curves: explicit_yarns(pattern, params, tiles_u, 1, samples)
    ['curves'] and ['colors'] (pattern space, x from 0), period (px, py),
    shell_top, radius r, (tx0, ty0, tiles_v) from tiles()."""

    def __init__(self, surface, band_curves, band_colors, period, shell_top, radius, tx0, ty0, tiles_v):
        self.surface = surface
        surface.shell_top = float(shell_top)
        self.curves = [np.asarray(c, dtype=np.float64) for c in band_curves]
        self.colors = [np.asarray(c, dtype=np.int64) for c in band_colors]
        self.px, self.py = period
        self.radius = float(radius)
        self.tx0, self.ty0, self.tiles_v = tx0, ty0, tiles_v
        self.band = 0
        self.pos, self.nor, self.rad, self.col, self.sizes = [], [], [], [], []
        self.src = []  # (band, curve, start, end) of every piece, for tests and diagnostics
        # all curves of a band as one array, with the curve of each point
        self._flat = np.concatenate(self.curves) if self.curves else np.zeros((0, 3))
        self._flat_col = np.concatenate(self.colors) if self.colors else np.zeros(0, dtype=np.int64)
        lens = np.array([len(c) for c in self.curves], dtype=np.int64)
        self._bounds = np.concatenate([[0], np.cumsum(lens)])
        self.points_done = 0

    @property
    def bands(self):
        return self.tiles_v

    @property
    def done(self):
        return self.band >= self.tiles_v

    def step(self, max_points=200000):
        """Lay the next bands (as many as make about `max_points` points, at
        least one); returns the share of bands done."""
        if self.done:
            return 1.0
        per = max(1, len(self._flat))
        k = int(max(1, min(self.tiles_v - self.band, max_points // per)))
        j0 = self.band
        shifts = np.zeros((k, 1, 3))
        shifts[:, 0, 0] = self.tx0 * self.px
        shifts[:, 0, 1] = (self.ty0 + j0 + np.arange(k)) * self.py
        pts = (self._flat[None, :, :] + shifts).reshape(-1, 3)
        tri, pos, nor, s = self.surface.place(pts)
        for jj in range(k):
            base = jj * per
            for ci in range(len(self.curves)):
                a, b = base + self._bounds[ci], base + self._bounds[ci + 1]
                c0 = self._bounds[ci]
                for s0, s1 in split_pieces(tri[a:b], self.surface.island):
                    self.pos.append(pos[a + s0:a + s1])
                    self.nor.append(nor[a + s0:a + s1])
                    self.rad.append(self.radius / s[a + s0:a + s1])
                    self.col.append(self._flat_col[c0 + s0:c0 + s1])
                    self.sizes.append(int(s1 - s0))
                    self.src.append((j0 + jj, ci, int(s0), int(s1)))
        self.points_done += len(pts)
        self.band += k
        return self.band / self.tiles_v

    def run(self):
        while not self.done:
            self.step()
        return self.result()

    def result(self):
        """{positions (P, 3), normals (P, 3), radius (P,), colour (P,) int,
        sizes (C,) points per curve} of everything laid so far."""
        if not self.sizes:
            return {"positions": np.zeros((0, 3)), "normals": np.zeros((0, 3)), "radius": np.zeros(0),
                    "colour": np.zeros(0, dtype=np.int64), "sizes": np.zeros(0, dtype=np.int64)}
        return {"positions": np.concatenate(self.pos), "normals": np.concatenate(self.nor),
                "radius": np.concatenate(self.rad), "colour": np.concatenate(self.col),
                "sizes": np.asarray(self.sizes, dtype=np.int64)}


def polyline_length(points, sizes):
    """Total length of the polylines (points (P, 3) laid end to end, sizes
    points per curve)."""
    points = np.asarray(points, dtype=np.float64)
    if len(points) < 2:
        return 0.0
    seg = np.linalg.norm(np.diff(points, axis=0), axis=1)
    ends = np.cumsum(sizes)[:-1] - 1  # the step from a curve's last point to the next curve's first
    mask = np.ones(len(seg), dtype=bool)
    mask[ends[ends < len(seg)]] = False
    return float(seg[mask].sum())

"""The base mesh's normal curvature per face, for the shader's Curvature input.

The knit shader bends its view-ray march with the curvature of the mesh
under the fabric (CAPM). Cycles hands it a mesh attribute
(core.shader.CURVATURE_ATTRIBUTE, face domain, float vector): the normal
curvature along +u and +v in 1 / world units (> 0 convex), third
component 0. The add-on computes it here from the mesh's positions, vertex
normals and UVs, as the native renderer does per triangle
(native/render/mesh_frame.cpp, uv_derivatives and curvature_u/v):

    [dP/du dP/dv] and [dN/du dN/dv] from the triangle's edges solved against
    its UV edges (N the vertex normals, linearly interpolated),
    kx = dot(dN/du, dP/du) / |dP/du|^2,   ky = dot(dN/dv, dP/dv) / |dP/dv|^2.

A triangle without UV area (|det| <= 1e-12) gives nothing; an n-gon takes
the mean over its fan triangles that give a value, 0 when none does. A flat
mesh gives 0 everywhere.

numpy only, no bpy (numpy ships with every Blender).
"""
import numpy as np

_DET_EPS = 1e-12


def fan_triangles(loop_start, loop_total):
    """The fan triangulation of polygons given by their first loop and loop
    count: (tri_loops (T, 3) loop indices, tri_face (T,) polygon of each)."""
    loop_start = np.asarray(loop_start, dtype=np.int64)
    loop_total = np.asarray(loop_total, dtype=np.int64)
    per_face = np.maximum(loop_total - 2, 0)
    count = int(per_face.sum())
    tri_face = np.repeat(np.arange(loop_start.size, dtype=np.int64), per_face)
    # k-th fan triangle of its face: loops (s, s + k + 1, s + k + 2)
    first = np.cumsum(per_face) - per_face
    k = np.arange(count, dtype=np.int64) - np.repeat(first, per_face)
    s = loop_start[tri_face]
    tri_loops = np.stack([s, s + k + 1, s + k + 2], axis=1)
    return tri_loops, tri_face


def face_curvature(positions, normals, loop_vertex, loop_uv, loop_start, loop_total, matrix=None):
    """Normal curvature (kx, ky, 0) per polygon, float32 array (F, 3).

    positions, normals: (V, 3) vertex positions and unit vertex normals;
    loop_vertex: (L,) vertex of each face corner; loop_uv: (L, 2) its UV;
    loop_start, loop_total: (F,) first corner and corner count per polygon;
    matrix: optional 4x4 object-to-world matrix (row-major, as Blender's
    matrix_world): positions and normals are taken to world space first, so
    the curvature is in 1 / world units.
    """
    P = np.asarray(positions, dtype=np.float64).reshape(-1, 3)
    N = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
    if matrix is not None:
        M = np.asarray(matrix, dtype=np.float64).reshape(4, 4)
        P = P @ M[:3, :3].T + M[:3, 3]
        try:
            Ninv = np.linalg.inv(M[:3, :3]).T
        except np.linalg.LinAlgError:  # a zero scale: nothing has an area
            Ninv = np.zeros((3, 3))
        N = N @ Ninv.T
        length = np.linalg.norm(N, axis=1, keepdims=True)
        N = np.divide(N, length, out=np.zeros_like(N), where=length > 0)
    lv = np.asarray(loop_vertex, dtype=np.int64)
    uv = np.asarray(loop_uv, dtype=np.float64).reshape(-1, 2)
    faces = np.asarray(loop_start).size
    out = np.zeros((faces, 3), dtype=np.float32)
    if faces == 0:
        return out
    tri, tri_face = fan_triangles(loop_start, loop_total)
    if tri.size == 0:
        return out
    v0, v1, v2 = lv[tri[:, 0]], lv[tri[:, 1]], lv[tri[:, 2]]
    t0, t1, t2 = uv[tri[:, 0]], uv[tri[:, 1]], uv[tri[:, 2]]
    du1, dv1 = t1[:, 0] - t0[:, 0], t1[:, 1] - t0[:, 1]
    du2, dv2 = t2[:, 0] - t0[:, 0], t2[:, 1] - t0[:, 1]
    det = du1 * dv2 - du2 * dv1
    e1, e2 = P[v1] - P[v0], P[v2] - P[v0]
    n1, n2 = N[v1] - N[v0], N[v2] - N[v0]
    scale = np.maximum((e1 * e1).sum(1), (e2 * e2).sum(1))
    ok = (np.abs(det) > _DET_EPS) & (scale > 0)
    safe = np.where(ok, det, 1.0)
    a, b = (dv2 / safe)[:, None], (-dv1 / safe)[:, None]
    c, e = (-du2 / safe)[:, None], (du1 / safe)[:, None]
    dpdu, dpdv = e1 * a + e2 * b, e1 * c + e2 * e
    dndu, dndv = n1 * a + n2 * b, n1 * c + n2 * e
    lu, lv2 = (dpdu * dpdu).sum(1), (dpdv * dpdv).sum(1)
    ok &= (lu > 0) & (lv2 > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        kx = (dndu * dpdu).sum(1) / np.where(ok, lu, 1.0)
        ky = (dndv * dpdv).sum(1) / np.where(ok, lv2, 1.0)
    ok &= np.isfinite(kx) & np.isfinite(ky)
    w = ok.astype(np.float64)
    sum_x = np.bincount(tri_face, weights=np.where(ok, kx, 0.0), minlength=faces)
    sum_y = np.bincount(tri_face, weights=np.where(ok, ky, 0.0), minlength=faces)
    n = np.bincount(tri_face, weights=w, minlength=faces)
    has = n > 0
    out[has, 0] = sum_x[has] / n[has]
    out[has, 1] = sum_y[has] / n[has]
    return out

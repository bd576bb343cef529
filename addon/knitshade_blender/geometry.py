"""Mesh data the knit shader reads: the curvature attribute and the UV density.

write_curvature(obj) stores the base mesh's normal curvature per face in the
attribute core.shader.CURVATURE_ATTRIBUTE (face domain, float vector; 1 /
world units at the object's current transform), which the Knit Fabric
group's Attribute node hands to the shader. It is computed once, when the
material is assigned and by "Refresh Curvature": a mesh that deforms
(armature, cloth, shape keys) or whose object is rescaled keeps the
curvature of the moment it was computed until refreshed. Meshes shared by
objects of different scales get the curvature of the one refreshed last.
"""
import math

import numpy as np

from . import compat
from .core import curvature as kcurv
from .core import shader as kshader


class MeshError(ValueError):
    pass


def _mesh_arrays(mesh):
    nv, nl, nf = len(mesh.vertices), len(mesh.loops), len(mesh.polygons)
    co = np.empty(3 * nv, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    normals = np.empty(3 * nv, dtype=np.float32)
    compat.vertex_normals(mesh, normals)
    loop_vertex = np.empty(nl, dtype=np.int32)
    mesh.loops.foreach_get("vertex_index", loop_vertex)
    loop_start = np.empty(nf, dtype=np.int32)
    loop_total = np.empty(nf, dtype=np.int32)
    mesh.polygons.foreach_get("loop_start", loop_start)
    mesh.polygons.foreach_get("loop_total", loop_total)
    return co.reshape(-1, 3), normals.reshape(-1, 3), loop_vertex, loop_start, loop_total


def _uvs(mesh):
    layer = compat.active_uv_layer(mesh)
    if layer is None:
        return None
    uv = np.empty(2 * len(mesh.loops), dtype=np.float32)
    compat.loop_uvs(mesh, layer, uv)
    return uv.reshape(-1, 2)


def _matrix(obj):
    return np.array([list(row) for row in obj.matrix_world], dtype=np.float64)


def has_uvs(obj):
    return obj is not None and obj.type == "MESH" and compat.active_uv_layer(obj.data) is not None


def write_curvature(obj):
    """Compute and store the curvature attribute of a mesh object; returns
    (faces, largest |curvature|). MeshError for an object that is not a mesh
    or has no UV map (the attribute then stays as it was)."""
    if obj is None or obj.type != "MESH":
        raise MeshError("%s is not a mesh" % (obj.name if obj else "nothing"))
    mesh = obj.data
    uv = _uvs(mesh)
    if uv is None:
        raise MeshError("%s has no UV map (unwrap it first: the knit follows the UVs)" % obj.name)
    co, normals, loop_vertex, loop_start, loop_total = _mesh_arrays(mesh)
    k = kcurv.face_curvature(co, normals, loop_vertex, uv, loop_start, loop_total, _matrix(obj))
    name = kshader.CURVATURE_ATTRIBUTE
    attr = mesh.attributes.get(name)
    if attr is not None and (attr.domain != "FACE" or attr.data_type != "FLOAT_VECTOR"):
        mesh.attributes.remove(attr)
        attr = None
    if attr is None:
        attr = mesh.attributes.new(name, "FLOAT_VECTOR", "FACE")
    if len(k):
        attr.data.foreach_set("vector", k.ravel())
    mesh.update()
    return len(k), float(np.abs(k[:, :2]).max()) if len(k) else 0.0


def read_curvature(obj):
    """The stored curvature attribute as an (F, 3) array, or None."""
    mesh = obj.data
    attr = mesh.attributes.get(kshader.CURVATURE_ATTRIBUTE)
    if attr is None:
        return None
    out = np.empty(3 * len(attr.data), dtype=np.float32)
    attr.data.foreach_get("vector", out)
    return out.reshape(-1, 3)


def metres_per_uv_unit(obj, scene=None):
    """How many metres one UV unit spans on the object, from its world-space
    area against its UV area (sqrt of the ratio); None without UVs or area."""
    if not has_uvs(obj):
        return None
    mesh = obj.data
    uv = _uvs(mesh)
    co, _n, loop_vertex, loop_start, loop_total = _mesh_arrays(mesh)
    tri, _face = kcurv.fan_triangles(loop_start, loop_total)
    if not len(tri):
        return None
    M = _matrix(obj)
    P = co.astype(np.float64) @ M[:3, :3].T + M[:3, 3]
    p0, p1, p2 = P[loop_vertex[tri[:, 0]]], P[loop_vertex[tri[:, 1]]], P[loop_vertex[tri[:, 2]]]
    area = 0.5 * np.linalg.norm(np.cross(p1 - p0, p2 - p0), axis=1).sum()
    t0, t1, t2 = uv[tri[:, 0]], uv[tri[:, 1]], uv[tri[:, 2]]
    d1, d2 = t1 - t0, t2 - t0
    uv_area = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]).sum()
    if not (area > 0 and uv_area > 0) or not math.isfinite(area / uv_area):
        return None
    unit = 1.0
    if scene is not None:
        unit = scene.unit_settings.scale_length or 1.0
    return math.sqrt(area / uv_area) * unit

"""Procedural meshes for tests, examples and benchmarks (closed, outward-wound)."""

from __future__ import annotations

import numpy as np

from .mesh import Mesh

__all__ = ["box_mesh", "cylinder_mesh", "uv_sphere_mesh", "torus_mesh", "box_triangles", "extrude_polygon"]


def box_triangles(size=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0)) -> np.ndarray:
    """``(12, 3, 3) float64`` triangles of an axis-aligned box with its min corner at ``origin``."""
    sx, sy, sz = size
    o = np.asarray(origin, dtype=np.float64)
    c = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    v = c * [sx, sy, sz] + o
    f = np.array(
        [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
         [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]]
    )
    return v[f]


def box_mesh(size=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0)) -> Mesh:
    return Mesh.from_triangles(box_triangles(size, origin), source="box")


def _grid_surface(P: np.ndarray, wrap_u: bool, wrap_v: bool) -> np.ndarray:
    """Triangles of a (nu, nv, 3) point grid; quads split along one diagonal."""
    nu, nv, _ = P.shape
    i = np.arange(nu if wrap_u else nu - 1)
    j = np.arange(nv if wrap_v else nv - 1)
    I, J = np.meshgrid(i, j, indexing="ij")
    I1, J1 = (I + 1) % nu, (J + 1) % nv
    a, b, c, d = P[I, J], P[I1, J], P[I1, J1], P[I, J1]
    t1 = np.stack([a, b, c], axis=-2)
    t2 = np.stack([a, c, d], axis=-2)
    return np.stack([t1, t2], axis=2).reshape(-1, 3, 3)


def torus_mesh(R: float = 3.0, r: float = 1.0, nu: int = 64, nv: int = 32) -> Mesh:
    u = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    v = np.linspace(0, 2 * np.pi, nv, endpoint=False)
    U, Vv = np.meshgrid(u, v, indexing="ij")
    P = np.stack([(R + r * np.cos(Vv)) * np.cos(U), (R + r * np.cos(Vv)) * np.sin(U), r * np.sin(Vv)], axis=-1)
    return Mesh.from_triangles(_grid_surface(P, True, True), source="torus")


def uv_sphere_mesh(radius: float = 1.0, n_lat: int = 32, n_lon: int = 64) -> Mesh:
    """A UV sphere: ``2 * n_lon * (n_lat - 1)`` triangles."""
    th = np.linspace(0, np.pi, n_lat + 1)
    ph = np.linspace(0, 2 * np.pi, n_lon, endpoint=False)
    T, Ph = np.meshgrid(th, ph, indexing="ij")
    P = radius * np.stack([np.sin(T) * np.cos(Ph), np.sin(T) * np.sin(Ph), np.cos(T)], axis=-1)
    P[0] = (0.0, 0.0, radius)  # exact poles, so that their copies merge into one vertex
    P[-1] = (0.0, 0.0, -radius)
    tris = _grid_surface(P[::-1], False, True)  # from south to north: outward winding
    area = np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    return Mesh.from_triangles(tris[area > 0], source="uv-sphere")


def extrude_polygon(xy: np.ndarray, height: float, z0: float = 0.0) -> np.ndarray:
    """Triangles of a prism over a star-shaped polygon (counter-clockwise ``(N, 2)``),
    capped by fans from the vertex centroid."""
    xy = np.asarray(xy, dtype=np.float64)
    n = len(xy)
    c = xy.mean(axis=0)
    tris = []
    for i in range(n):
        a, b = xy[i], xy[(i + 1) % n]
        a0, b0, a1, b1 = [*a, z0], [*b, z0], [*a, z0 + height], [*b, z0 + height]
        tris += [[a0, b0, b1], [a0, b1, a1]]
        tris += [[[*c, z0], b0, a0], [[*c, z0 + height], a1, b1]]
    return np.asarray(tris, dtype=np.float64)


def cylinder_mesh(radius: float = 1.0, height: float = 1.0, n: int = 64) -> Mesh:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return Mesh.from_triangles(extrude_polygon(np.stack([radius * np.cos(t), radius * np.sin(t)], 1), height), source="cylinder")

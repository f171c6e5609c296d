"""Procedural meshes for tests, examples and benchmarks (closed, outward-wound)."""

from __future__ import annotations

import numpy as np

from .mesh import Mesh
from .primitives import box_triangles, extrude_polygon

__all__ = ["box_mesh", "cylinder_mesh", "uv_sphere_mesh", "torus_mesh", "box_triangles", "extrude_polygon"]


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


def cylinder_mesh(radius: float = 1.0, height: float = 1.0, n: int = 64) -> Mesh:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return Mesh.from_triangles(extrude_polygon(np.stack([radius * np.cos(t), radius * np.sin(t)], 1), height), source="cylinder")

"""Points of a triangle surface as corners and barycentric weights: a vertex as such a point, such a point's
position, and the weights of points that lie on given triangles."""

from __future__ import annotations

import numpy as np


def vertex_points(vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ``vertices`` (n,) as points of the surface: corners (n, 3) (the vertex thrice) and barycentric
    weights (n, 3) (all on the first)."""
    weights = np.zeros((len(vertices), 3))
    weights[:, 0] = 1.0
    return np.repeat(vertices[:, None], 3, axis=1), weights


def on_surface(points: np.ndarray, corners: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """(k, 3): the points at ``corners`` (k, 3) with barycentric ``weights`` (k, 3) on the vertex positions
    ``points`` (N, 3)."""
    return np.einsum("kj,kji->ki", weights, np.asarray(points, dtype=float)[corners])


def barycentric(corners: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Barycentric weights (Q, 3) of ``points`` (Q, 3) in the triangles ``corners`` (Q, 3, 3),
    clipped to the triangle (the points are on it up to rounding)."""
    a = corners[:, 0]
    u, v, w = corners[:, 1] - a, corners[:, 2] - a, points - a
    uu, uv, vv = (np.einsum("ij,ij->i", x, y) for x, y in ((u, u), (u, v), (v, v)))
    wu, wv = np.einsum("ij,ij->i", w, u), np.einsum("ij,ij->i", w, v)
    determinant = uu * vv - uv * uv
    safe = np.where(determinant > 0, determinant, 1.0)
    s, t = (vv * wu - uv * wv) / safe, (uu * wv - uv * wu) / safe
    weights = np.clip(np.column_stack([1.0 - s - t, s, t]), 0.0, 1.0)
    return weights / weights.sum(axis=1, keepdims=True)

"""Batched 3x3 linear algebra used by every step: rotations, rigid fits, mirror fits.

All functions take stacks of vectors/matrices with a leading batch axis and
loop over nothing in Python.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class MirrorPlane(NamedTuple):
    """The plane {x : normal . x = offset}: ``normal`` (3,) unit vector, ``offset`` in mesh units."""

    normal: np.ndarray
    offset: float

MIRROR_X = np.diag([-1.0, 1.0, 1.0])
FLAT = 1e-9  # a point set whose smallest spread is below this fraction of its largest is flat (2D)
FLAT_SAMPLES = 20000  # points (evenly strided) that decide whether a point set is flat


def bounding_diagonal(points: np.ndarray) -> float:
    """Length of the diagonal of the axis-aligned bounding box of ``points`` (n, 3), mesh units: the scale
    every relative figure and tolerance of the package divides by (0.0 for no points)."""
    return float(np.linalg.norm(np.ptp(points, axis=0))) if len(points) else 0.0


def normalize(vectors: np.ndarray) -> np.ndarray:
    """Unit vectors of ``vectors`` (..., 3); zero vectors stay zero."""
    norms = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return np.divide(vectors, norms, out=np.zeros_like(vectors), where=norms > 0)


def cross_matrix(axis: np.ndarray) -> np.ndarray:
    """Skew matrices [a]x (n, 3, 3) of the axes ``axis`` (n, 3)."""
    zero = np.zeros(len(axis))
    a0, a1, a2 = axis.T
    return np.stack(
        [zero, -a2, a1, a2, zero, -a0, -a1, a0, zero], axis=-1
    ).reshape(-1, 3, 3)


def rotation_about_axis(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rodrigues rotations (n, 3, 3) by ``angle`` (n,) radians about unit ``axis`` (n, 3)."""
    k = cross_matrix(axis)
    s = np.sin(angle)[:, None, None]
    c = np.cos(angle)[:, None, None]
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def minimal_rotation(sources: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Smallest rotations (n, 3, 3) taking unit vectors ``sources`` (n, 3) to unit ``target`` (3,).

    The rotation is about ``source x target``; an exactly opposite source is
    turned by pi about an axis perpendicular to the target.
    """
    sources = np.atleast_2d(sources)
    axis = np.cross(sources, target)
    sin = np.linalg.norm(axis, axis=1)
    cos = sources @ target
    angle = np.arctan2(sin, cos)
    fallback = np.cross(target, np.eye(3)[np.argmin(np.abs(target))])
    axis = np.where((sin > 1e-15)[:, None], axis, fallback)
    return rotation_about_axis(normalize(axis), angle)


def proper_rotation_fit(cross_covariance: np.ndarray) -> np.ndarray:
    """Kabsch: rotations R (n, 3, 3) maximising trace(R^T H) for H = sum w b a^T (n, 3, 3).

    R is then the best proper rotation with b ~ R a (det R = +1 enforced).
    """
    u, _, vt = np.linalg.svd(cross_covariance)
    d = np.sign(np.linalg.det(u @ vt))
    d[d == 0] = 1.0
    return u @ (np.concatenate([np.ones((len(d), 2)), d[:, None]], axis=1)[:, :, None] * vt)


def rigid_fit(source: np.ndarray, target: np.ndarray, weights: np.ndarray | None = None):
    """Best rigid motion (R (3, 3), t (3,)) with target ~ source @ R.T + t (weighted least squares,
    ``weights`` (n,) >= 0, default 1)."""
    w = np.ones(len(source)) if weights is None else weights
    cs, ct = w @ source / w.sum(), w @ target / w.sum()
    h = (w[:, None] * (target - ct)).T @ (source - cs)
    rotation = proper_rotation_fit(h[None])[0]
    return rotation, ct - rotation @ cs


def similarity_fit(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """``source`` (n, 3) moved by the best similarity (rotation, scale, translation) onto ``target``."""
    cs, ct = source.mean(axis=0), target.mean(axis=0)
    a, b = source - cs, target - ct
    u, s, vt = np.linalg.svd(b.T @ a)
    d = np.ones(3)
    d[2] = np.sign(np.linalg.det(u @ vt)) or 1.0
    rotation = (u * d) @ vt
    scale = (s * d).sum() / (a * a).sum()
    return scale * a @ rotation.T + ct


def voxel_keys(positions: np.ndarray, size: float) -> np.ndarray:
    """One int64 key (n,) per cell of the grid of edge ``size`` anchored at the origin
    (a 1-D unique over keys is far faster than a unique over rows)."""
    cells = np.floor(positions / size).astype(np.int64)
    cells -= cells.min(axis=0)
    span = cells.max(axis=0) + 1
    return (cells[:, 0] * span[1] + cells[:, 1]) * span[2] + cells[:, 2]


def voxel_grid(positions: np.ndarray, target: int, steps: int = 20,
               low: float | None = None, high: float | None = None) -> np.ndarray:
    """Voxel keys (n,) of the finest grid, found by bisection on the cell size between
    ``low`` and ``high`` (default: 1e-5 and 2 x the extent), whose number of occupied
    cells does not exceed about ``target``. The count is not monotonic in the size, so
    the bounds decide which crossing is found."""
    extent = float(np.ptp(positions, axis=0).max()) or 1.0
    low = 1e-5 * extent if low is None else low
    high = 2.0 * extent if high is None else high
    for _ in range(steps):
        size = np.sqrt(low * high)
        low, high = (size, high) if len(np.unique(voxel_keys(positions, size))) > target else (low, size)
    return voxel_keys(positions, high)


def flat_normal(points: np.ndarray) -> np.ndarray | None:
    """The unit normal (3,) of the plane holding every point of ``points`` (N, 3) (a flat, 2D shape), or
    None if they span 3D. A normal within rounding of a coordinate axis is that axis exactly."""
    sample = points[:: max(1, len(points) // FLAT_SAMPLES)]
    if len(sample) < 3:
        return None
    _, spread, axes = np.linalg.svd(sample - sample.mean(axis=0), full_matrices=False)
    if len(spread) < 3 or spread[2] > FLAT * spread[0] or spread[1] <= FLAT * spread[0]:
        return None
    normal = axes[2]
    axis = int(np.argmax(np.abs(normal)))
    if abs(abs(normal[axis]) - 1.0) < 1e-12:
        normal = np.eye(3)[axis]
    return normal


def reflection_across_plane(points: np.ndarray, normal: np.ndarray, offset: float) -> np.ndarray:
    """Mirror images of ``points`` (n, 3) across the plane {x : normal . x = offset}."""
    return points - 2.0 * (points @ normal - offset)[:, None] * normal


def whitening(points: np.ndarray) -> np.ndarray:
    """Symmetric matrix W (3, 3) such that (points - mean) @ W has identity covariance.

    A mirror-symmetric shape under any affine map has an affine mirror symmetry;
    whitened, that symmetry is an orthogonal reflection again (the shape's
    covariance is invariant under its symmetry), so plane-based pairing works on
    a uniformly compressed or sheared shape.
    """
    centred = points - points.mean(axis=0)
    values, vectors = np.linalg.eigh(centred.T @ centred / len(points))
    # A flat shape has no spread along its normal: that direction is scaled as the largest one (any
    # scale keeps it at zero), so the matrix stays invertible.
    values = np.where(values > (FLAT * 10) ** 2 * values.max(), values, values.max())
    return (vectors / np.sqrt(values)) @ vectors.T


def hemisphere_directions(count: int) -> np.ndarray:
    """``count`` unit vectors (count, 3) spread evenly over the half sphere z >= 0 (a Fibonacci
    spiral): the distinct normals of planes through a point."""
    k = np.arange(count) + 0.5
    z = 1.0 - k / count
    angle = np.pi * (1.0 + np.sqrt(5.0)) * k
    ring = np.sqrt(1.0 - z**2)
    return np.column_stack([ring * np.cos(angle), ring * np.sin(angle), z])

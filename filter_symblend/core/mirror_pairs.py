"""A mirror map as a result: each vertex's twin on the surface, and how sure the map is of it.

The twin of a vertex is a point of the surface, stored as barycentric ``weights`` on the triangle
``corners``: the same material point on the input and on any embedding of the mesh (the symmetrized
output), so the twins can be placed on either (:meth:`MirrorPairs.twins_on`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .geometry import bounding_diagonal
from .mesh_quantities import farthest_point_order
from .report import MirrorMapReport
from .surface_points import on_surface

CONFIDENT = 0.5  # a twin at or above this confidence counts as confident (see auto/confidence)
APART = 0.02  # x diagonal: a landmark pair closer than this says little about the mirror and snaps ambiguously
# Below this share of the pairable surface with confident twins, a result built on the map warns: chosen on the
# FAUST half of the mirror-map benchmark, checked on its TOSCA half (docs/benchmarks.md).
DOUBTFUL_SHARE = 0.8


@dataclasses.dataclass(frozen=True)
class MirrorPairs:
    """The twins of ``vertex`` (k,) int: ``twin`` (k, 3) the twin as a point of the input surface,
    barycentric ``weights`` (k, 3) on the vertices ``corners`` (k, 3); ``confidence`` (k,) in [0, 1];
    ``n_vertices`` the mesh's vertex count; ``report``: the map's name, its coverage (share of the
    pairable vertices with a twin), consistency and confident share."""

    vertex: np.ndarray
    twin: np.ndarray
    corners: np.ndarray
    weights: np.ndarray
    confidence: np.ndarray
    n_vertices: int
    report: MirrorMapReport

    def twins_on(self, points: np.ndarray) -> np.ndarray:
        """(k, 3): the twins on another embedding ``points`` (N, 3) of the same mesh."""
        return on_surface(points, self.corners, self.weights)

    def per_vertex(self, points: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(twin (N, 3), NaN where a vertex has none; confidence (N,), 0 where none), on ``points``
        (N, 3) (default: the input)."""
        twin = np.full((self.n_vertices, 3), np.nan)
        twin[self.vertex] = self.twin if points is None else self.twins_on(points)
        confidence = np.zeros(self.n_vertices)
        confidence[self.vertex] = self.confidence
        return twin, confidence

    def confident(self, threshold: float = CONFIDENT) -> np.ndarray:
        """(k,) bool: the pairs whose confidence is at least ``threshold``."""
        return self.confidence >= threshold


def spread_left_sides(sources: np.ndarray, twins: np.ndarray, eligible: np.ndarray, count: int,
                      diagonal: float) -> np.ndarray:
    """Rows (c,) of up to ``count`` of the ``eligible`` (k,) bool pairs ``sources`` (k, 3) -> ``twins`` (k, 3)
    spread evenly (farthest-point order), each pair once, from its source on the left side of the shape.

    Pairs whose two points lie closer than ``APART`` x ``diagonal`` are left out. The side is the sign of the
    pair's gap along the principal direction of all the gaps (the mirror direction, bent shapes included, as
    long as no part is turned over)."""
    gaps = sources - twins
    rows = np.flatnonzero(eligible & (np.linalg.norm(gaps, axis=1) > APART * diagonal))
    if not len(rows):
        return rows
    direction = np.linalg.eigh(gaps[rows].T @ gaps[rows])[1][:, -1]
    left = rows[gaps[rows] @ direction >= 0]
    return left[farthest_point_order(sources[left], min(count, len(left)))]


def pairs_to_check(pairs: MirrorPairs, points: np.ndarray, count: int,
                   threshold: float = CONFIDENT) -> np.ndarray:
    """Rows into ``pairs`` (c,): up to ``count`` of the confident pairs, spread over the surface of ``points``
    (N, 3) by :func:`spread_left_sides`. When other symmetries fit about as well (``report.alternatives``),
    whose disagreement is what lowered the confidence, from every twin: the chosen symmetry's pairs, for the
    user to keep or move to the one meant."""
    points = np.asarray(points, dtype=float)
    usable = pairs.confident(0.0 if pairs.report.alternatives else threshold)
    return spread_left_sides(points[pairs.vertex], pairs.twin, usable, count, bounding_diagonal(points))

"""Twins of vertices under a mirror map: where on the surface, and whether a vertex.

For each source vertex the map predicts where its twin lies. The twin is the point of
the surface nearest that prediction (how far the prediction is from the surface is its
*landing* distance), and, if the nearest vertex is unambiguous (ratio test) and the map
sends that vertex back to the source (mutual), that vertex. A twin is sound only if the
map is consistent there: the twin point's own prediction comes back within the local
vertex spacing of the source, and the two face the mirrored way (on a thin sheet the
other face is near, but faces away).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .growth import RATIO
from .maps import MirrorMap

# A predicted twin is taken as a vertex only within a tenth of the local vertex spacing of it: a map precise
# enough finds a mirrored tessellation's twins there, while on two independently sampled sides a prediction falls
# that near a vertex by chance about once in thirty.
VERTEX_PRECISION = 0.1


@dataclasses.dataclass(frozen=True)
class Landing:
    """Where the twins of the sources (m,) land under a map, in the map's space: its ``predicted`` positions
    (m, 3); ``point`` (m, 3) the twin point, the point of the surface nearest the prediction, at ``landing``
    (m,) from it; ``corners`` (m, 3) vertices and ``weights`` (m, 3) barycentric weights of the twin point (the
    same point on any embedding of the mesh); ``returned`` (m, 3) where the map sends the twin point (the round
    trip); ``facing`` whether the prediction is finite and the twin faces the mirrored way; ``sound`` whether
    the map is also consistent there (its round trip)."""

    predicted: np.ndarray
    point: np.ndarray
    landing: np.ndarray
    corners: np.ndarray
    weights: np.ndarray
    returned: np.ndarray
    facing: np.ndarray
    sound: np.ndarray

    @classmethod
    def of(cls, mirror: MirrorMap, sources: np.ndarray, tolerance: float) -> "Landing":
        surface = mirror.surface
        positions = surface.points[sources]
        if surface.is_mesh:
            predicted, carried = mirror.twins_and_normals(positions, surface.normals[sources])
        else:
            predicted = mirror.predict(positions)
        point, landing, twin_normal, corners, weights = surface.nearest_points(predicted)
        returned = mirror.predict(point)
        back, _, _ = surface.nearest_vertices(returned)  # (a vertex: the round trip's own error is small)
        round_trip = np.linalg.norm(surface.points[back] - positions, axis=1)
        facing = np.isfinite(predicted).all(axis=1)
        if surface.is_mesh:
            facing &= np.einsum("ni,ni->n", carried, twin_normal) > 0
        sound = facing & (round_trip <= np.maximum(surface.local_spacing[sources], tolerance))
        return cls(predicted, point, landing, corners, weights, returned, facing, sound)

    def covered(self, tolerance: float) -> np.ndarray:
        """(m,) bool: sources with a sound twin landing within ``tolerance`` (mesh units)."""
        return self.sound & (self.landing <= tolerance)


@dataclasses.dataclass(frozen=True)
class Twins(Landing):
    """The :class:`Landing` of the ``sources`` (m,) (vertex indices), with their vertices: ``vertex`` (m,) the
    nearest vertex to the prediction, ``vertex_distance``, ``ratio`` (nearest / second-nearest), ``spacing`` the
    local vertex spacing there, ``mutual`` whether the map sends that vertex back to the source; ``side`` +1 for
    a source on the left (along the map's normal), -1 right."""

    sources: np.ndarray
    vertex: np.ndarray
    vertex_distance: np.ndarray
    ratio: np.ndarray
    spacing: np.ndarray
    mutual: np.ndarray
    side: np.ndarray

    def exact_vertex(self, tolerance: float = np.inf, strict: bool = True) -> np.ndarray:
        """(m,) bool: sources whose twin is a vertex: the nearest vertex to the prediction, within
        ``tolerance`` of it (mesh units: the map's precision, if known) and, if ``strict``, within VERTEX_PRECISION
        of the local spacing, unambiguous (RATIO) and mutual (a source can be its own twin, on the midline). Not
        strict: seeds for a growth that proves them (:mod:`.connectivity`)."""
        bound = np.minimum(tolerance, VERTEX_PRECISION * self.spacing) if strict else tolerance
        near = self.vertex_distance <= bound
        return self.sound & self.mutual & (self.ratio <= RATIO) & near


def find_twins(mirror: MirrorMap, sources: np.ndarray, tolerance: float) -> Twins:
    """The twins of ``sources`` (m,) (vertex indices) under ``mirror``; a round trip counts as consistent
    within the local vertex spacing or ``tolerance`` (mesh units, the landing tolerance), whichever is larger
    (on a fine scan the map's own inconsistency is the scan's asymmetry, not the vertex spacing)."""
    surface = mirror.surface
    positions = surface.points[sources]
    landed = Landing.of(mirror, sources, tolerance)
    vertex, vertex_distance, ratio = surface.nearest_vertices(landed.predicted)
    returning, _, _ = surface.nearest_vertices(mirror.predict(surface.points[vertex]))
    side = np.where((positions - landed.point) @ mirror.normal >= 0, 1, -1).astype(np.int8)
    return Twins(**vars(landed), sources=sources, vertex=vertex, vertex_distance=vertex_distance, ratio=ratio,
                 spacing=surface.local_spacing[vertex], mutual=returning == sources, side=side)


def covered_by(mirror: MirrorMap, sources: np.ndarray, tolerance: float) -> np.ndarray:
    """(m,) bool: ``Twins.covered(tolerance)`` of :func:`find_twins` ``(mirror, sources, tolerance)``, without
    the nearest vertices it does not need (a third of the work: each candidate map is scored by it)."""
    return Landing.of(mirror, sources, tolerance).covered(tolerance)

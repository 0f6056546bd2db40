"""Ground truth of a mirror-symmetric surface whose vertices need not mirror each other (remeshed, a scan
of a symmetric object): each left vertex's true twin is a point of the surface, a material point that
follows any map of the mesh; its symmetry error and hand-placed landmark pairs."""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial import cKDTree

from ..core.landmark_asymmetry import fit_mirror_plane
from ..core.mesh_quantities import farthest_point_order
from ..core.mirror_fill import TriangleSurface
from ..core.surface_points import barycentric, on_surface, vertex_points


@dataclasses.dataclass(frozen=True)
class SurfaceTruth:
    """Ground truth of a mirror-symmetric surface whose vertices need not mirror each other (remeshed, a
    scan of a symmetric object): each ``left`` (m,) vertex's twin is the point of the surface with barycentric
    ``twin_weights`` (m, 3) on the vertices ``twin_corners`` (m, 3), the reflection of its undeformed position;
    being a material point, it follows any map of the mesh."""

    points: np.ndarray
    faces: np.ndarray
    left: np.ndarray
    twin_corners: np.ndarray
    twin_weights: np.ndarray

    def twins(self, points: np.ndarray) -> np.ndarray:
        """(m, 3) the twins of the ``left`` vertices on the mesh moved to ``points`` (N, 3)."""
        return on_surface(points, self.twin_corners, self.twin_weights)

    def symmetry_error(self, points: np.ndarray) -> float:
        """RMS over the true pairs of |left - mirror(twin)| across their best plane, / diagonal of ``points``."""
        deviations = fit_mirror_plane(points[self.left], self.twins(points)).deviations
        return float(np.sqrt(np.mean(deviations**2)) / np.linalg.norm(np.ptp(points, axis=0)))

    def landmarks(self, count: int, margin: float = 0.02):
        """``count`` hand-placed pairs (left (count,), right (count,)): left vertices spread by farthest-point
        sampling at least ``margin`` x diagonal off the plane, each right one the vertex nearest its twin (as a
        user clicks it)."""
        diagonal = np.linalg.norm(np.ptp(self.points, axis=0))
        twins = self.twins(self.points)
        off_plane = np.linalg.norm(self.points[self.left] - twins, axis=1) > 2.0 * margin * diagonal
        candidates = np.flatnonzero(off_plane)
        chosen = candidates[farthest_point_order(self.points[self.left[candidates]], count, start=0)]
        return self.left[chosen], cKDTree(self.points).query(twins[chosen])[1]


def vertex_truth(points: np.ndarray, faces: np.ndarray, left: np.ndarray, right: np.ndarray) -> SurfaceTruth:
    """The :class:`SurfaceTruth` of a mesh whose ``left`` (m,) vertices have exact twins ``right`` (m,)."""
    return SurfaceTruth(points, faces, left, *vertex_points(right))


def surface_truth(points: np.ndarray, faces: np.ndarray, offset: float, on_surface: float = 2e-3) -> SurfaceTruth:
    """The :class:`SurfaceTruth` of a mesh symmetric across x = ``offset``: every vertex on the left whose
    reflection lies within ``on_surface`` x diagonal of the surface (where it is symmetric)."""
    mirrored = points * [-1.0, 1.0, 1.0] + [2.0 * offset, 0.0, 0.0]
    face, closest, distance = TriangleSurface(points, faces).nearest(mirrored)
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    left = np.flatnonzero((points[:, 0] > offset) & (distance <= on_surface * diagonal))
    corners = faces[face[left]]
    return SurfaceTruth(points, faces, left, corners, barycentric(points[corners], closest[left]))

"""A mesh as the automatic pairs see it, with everything they need computed once.

Real meshes come with loose vertices, duplicated vertices (an OBJ split along its
texture seams), degenerate triangles and several pieces. Vertices at one position are
welded: the triangles refer to the first of them, which alone can be paired, and the
others follow the warp, which moves equal positions equally. Only vertices of a
triangle with an area (every vertex of a point cloud) can be paired. Vertices the
caller excludes (a missing or broken part) are neither paired nor twins.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.spatial import cKDTree

from ..geometry import normalize
from ..mesh_geometry import vertex_normals
from ..mirror_fill import nearest_on_triangles

POINT_CLOUD_NEIGHBOURS = 8  # neighbours whose mean distance is a point cloud's local spacing


class Surface:
    """``points`` (N, 3) with ``faces`` (F, 3) (empty: a point cloud) and the vertices that may pair.

    ``usable`` (N,) bool: the vertices that may be paired (see the module doc). ``moved(points)``
    is the same surface at other positions (a symmetrized output): same triangles and vertices.
    """

    def __init__(self, points: np.ndarray, faces: np.ndarray, excluded: np.ndarray | None = None,
                 usable: np.ndarray | None = None):
        self.points = np.asarray(points, dtype=float)
        faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
        if usable is None:
            _, first, inverse = np.unique(self.points, axis=0, return_index=True, return_inverse=True)
            self.representative = first[inverse.ravel()]  # (N,) the first vertex at each vertex's position
            faces = self.representative[faces]  # welded
            self.faces = faces
            usable = np.zeros(len(self.points), dtype=bool)
            if len(faces):
                usable[faces[self._areas > 0].ravel()] = True
            else:
                usable[first] = True
            if excluded is not None:
                usable[excluded] = False
        self.faces = faces
        self.usable = usable
        self.usable_index = np.flatnonzero(usable)

    def moved(self, points: np.ndarray) -> "Surface":
        """The same surface (welded triangles, usable vertices) at the positions ``points`` (N, 3), as a
        symmetrized output is: its triangles and local vertex spacing are taken as the input's."""
        moved = Surface(points, self.faces, usable=self.usable)
        moved.representative = self.representative
        moved.__dict__.update(triangles=self.triangles, local_spacing=self.local_spacing, spacing=self.spacing)
        return moved

    @functools.cached_property
    def _areas(self) -> np.ndarray:
        corners = self.points[self.faces]
        return np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)

    @property
    def is_mesh(self) -> bool:
        return bool(len(self.faces))

    @functools.cached_property
    def triangles(self) -> np.ndarray:
        """Face indices (T,) of the triangles with an area."""
        return np.flatnonzero(self._areas > 0)

    @functools.cached_property
    def diagonal(self) -> float:
        used = self.points[self.usable_index]
        return float(np.linalg.norm(np.ptp(used, axis=0))) if len(used) else 0.0

    @functools.cached_property
    def vertex_tree(self) -> cKDTree:
        """KD-tree of the usable vertices (its indices are positions in ``usable_index``)."""
        return cKDTree(self.points[self.usable_index])

    @functools.cached_property
    def local_spacing(self) -> np.ndarray:
        """(N,) distance from each usable vertex to its nearest usable neighbour (inf elsewhere)."""
        spacing = np.full(len(self.points), np.inf)
        if len(self.usable_index) > 1:
            k = 2 if self.is_mesh else min(len(self.usable_index), POINT_CLOUD_NEIGHBOURS + 1)
            distance, _ = self.vertex_tree.query(self.points[self.usable_index], k=k)
            spacing[self.usable_index] = distance[:, 1] if self.is_mesh else distance[:, 1:].mean(axis=1)
        return spacing

    @functools.cached_property
    def spacing(self) -> float:
        """Median local spacing: the mesh's typical vertex distance (mesh units)."""
        finite = self.local_spacing[np.isfinite(self.local_spacing)]
        return float(np.median(finite)) if len(finite) else 0.0

    @functools.cached_property
    def normals(self) -> np.ndarray:
        """(N, 3) unit vertex normals (unoriented for a point cloud)."""
        faces = self.faces[self.triangles] if self.is_mesh else self.faces
        return vertex_normals(self.points, faces)[0]

    @functools.cached_property
    def face_normals(self) -> np.ndarray:
        corners = self.points[self.faces[self.triangles]]
        return normalize(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]))

    @functools.cached_property
    def adjacency(self):
        """(N, N) sparse 0/1 matrix of the edges of the triangles with an area."""
        from .connectivity import vertex_adjacency
        return vertex_adjacency(self.faces[self.triangles], len(self.points))

    @functools.cached_property
    def _triangle_corners(self) -> np.ndarray:
        return self.points[self.faces[self.triangles]]

    @functools.cached_property
    def _centroid_tree(self) -> cKDTree:
        return cKDTree(self._triangle_corners.mean(axis=1))

    def nearest_points(self, queries: np.ndarray):
        """Where the surface is nearest each query (Q, 3): (point (Q, 3), distance (Q,), unit normal
        there (Q, 3), the corner vertices (Q, 3) and barycentric weights (Q, 3) of that point). On a
        point cloud the nearest vertex, with weight 1 on it."""
        if not self.is_mesh:
            distance, nearest = self.vertex_tree.query(queries)
            vertex = self.usable_index[nearest]
            corners = np.repeat(vertex[:, None], 3, axis=1)
            weights = np.zeros((len(queries), 3))
            weights[:, 0] = 1.0
            return self.points[vertex], distance, self.normals[vertex], corners, weights
        face, point, distance = nearest_on_triangles(self._triangle_corners, self._centroid_tree, queries)
        corners = self.faces[self.triangles[face]]
        return point, distance, self.face_normals[face], corners, barycentric(self.points[corners], point)

    def nearest_vertices(self, queries: np.ndarray):
        """(nearest usable vertex (Q,), its distance (Q,), nearest / second-nearest distance (Q,))."""
        k = min(2, len(self.usable_index))
        distance, nearest = self.vertex_tree.query(queries, k=k)
        distance, nearest = distance.reshape(len(queries), k), nearest.reshape(len(queries), k)
        second = distance[:, -1] if k == 2 else np.full(len(queries), np.inf)
        ratio = np.divide(distance[:, 0], second, out=np.zeros(len(queries)), where=second > 0)
        return self.usable_index[nearest[:, 0]], distance[:, 0], ratio


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

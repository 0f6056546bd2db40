"""A mesh as the automatic pairs see it, with everything they need computed once.

Real meshes come with loose vertices, duplicated vertices (an OBJ split along its
texture seams), degenerate triangles and several pieces. Vertices at one position are
welded: the triangles refer to the first of them, which alone can be paired, and the
others follow the warp, which moves equal positions equally. Only vertices of a
triangle with an area (every vertex of a point cloud) can be paired. Vertices the
caller excludes (a missing or broken part) are neither paired nor twins.

A flat mesh (a drawing, a 2D outline triangulated) is paired by its outline: every
point inside the region mirrors onto the region whatever its shape, so only the
boundary says how symmetric the shape is (:class:`Outline`).
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.spatial import cKDTree

from ..core.geometry import bounding_diagonal, flat_normal, normalize, whitening
from ..core.mesh_graph import vertex_adjacency
from ..core.mesh_quantities import vertex_normals
from ..core.mirror_fill import TriangleSurface
from ..core.surface_points import barycentric, vertex_points

# Neighbours whose mean distance is a point cloud's local spacing.
POINT_CLOUD_NEIGHBOURS = 8


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

    def memo(self, key, compute):
        """``compute()``, computed once per hashable ``key`` for this surface: costly derived data that two
        stages need (the intrinsic mirrors)."""
        memos = self.__dict__.setdefault("_memos", {})
        if key not in memos:
            memos[key] = compute()
        return memos[key]

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
        return bounding_diagonal(used)

    @functools.cached_property
    def whitening_frame(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(centre (3,), W (3, 3), its inverse (3, 3)): x -> (x - centre) @ W whitens the usable vertices
        (covariance the identity, :func:`~filter_symblend.core.geometry.whitening`), y -> y @ W^-1 + centre
        maps back. An affine image of a mirror-symmetric shape, whitened, is symmetric by a reflection again."""
        used = self.points[self.usable_index]
        forward = whitening(used)
        return used.mean(axis=0), forward, np.linalg.pinv(forward)

    @functools.cached_property
    def vertex_tree(self) -> cKDTree:
        """KD-tree of the usable vertices (its indices are positions in ``usable_index``); unbalanced, as
        every tree here: a surface is built once per round, and such a tree builds 2.4x faster."""
        return cKDTree(self.points[self.usable_index], balanced_tree=False, compact_nodes=False)

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
        return vertex_adjacency(self.faces[self.triangles], len(self.points))

    @functools.cached_property
    def _triangle_surface(self) -> TriangleSurface:
        return TriangleSurface(self.points, self.faces[self.triangles])

    def nearest_points(self, queries: np.ndarray):
        """Where the surface is nearest each query (Q, 3): (point (Q, 3), distance (Q,), unit normal
        there (Q, 3), the corner vertices (Q, 3) and barycentric weights (Q, 3) of that point). On a
        point cloud the nearest vertex, with weight 1 on it."""
        if not self.is_mesh:
            distance, nearest = self.vertex_tree.query(queries)
            vertex = self.usable_index[nearest]
            return self.points[vertex], distance, self.normals[vertex], *vertex_points(vertex)
        face, point, distance = self._triangle_surface.nearest(queries)
        corners = self.faces[self.triangles[face]]
        return point, distance, self.face_normals[face], corners, barycentric(self.points[corners], point)

    @staticmethod
    def chance_ratio(ratio: np.ndarray) -> np.ndarray:
        """Ratio test values on the scale of a surface's chances (:meth:`Outline.chance_ratio`): themselves."""
        return ratio

    def nearest_vertices(self, queries: np.ndarray):
        """(nearest usable vertex (Q,), its distance (Q,), nearest / second-nearest distance (Q,))."""
        k = min(2, len(self.usable_index))
        distance, nearest = self.vertex_tree.query(queries, k=k)
        distance, nearest = distance.reshape(len(queries), k), nearest.reshape(len(queries), k)
        second = distance[:, -1] if k == 2 else np.full(len(queries), np.inf)
        ratio = np.divide(distance[:, 0], second, out=np.zeros(len(queries)), where=second > 0)
        return self.usable_index[nearest[:, 0]], distance[:, 0], ratio


class Outline(Surface):
    """A flat mesh seen by its outline: the boundary edges of its triangles (the edges of one triangle
    only). The outline's vertices are the ones that may pair; the nearest point of the "surface" is the
    nearest point of the outline, with the in-plane normal pointing out of the region."""

    def __init__(self, points: np.ndarray, faces: np.ndarray, normal: np.ndarray,
                 excluded: np.ndarray | None = None, edges: np.ndarray | None = None, usable: np.ndarray | None = None):
        super().__init__(points, faces, excluded, usable)
        self.flat = normal
        if edges is None:
            edges = _boundary_edges(self.faces[self.triangles], self.points, normal)
            outline = np.zeros(len(self.points), dtype=bool)
            outline[edges.ravel()] = True
            self.usable = self.usable & outline
            self.usable_index = np.flatnonzero(self.usable)
        self.edges = edges

    def moved(self, points: np.ndarray) -> "Outline":
        moved = Outline(points, self.faces, self.flat, edges=self.edges, usable=self.usable)
        moved.representative = self.representative
        moved.__dict__.update(triangles=self.triangles, local_spacing=self.local_spacing, spacing=self.spacing)
        return moved

    @functools.cached_property
    def edge_normals(self) -> np.ndarray:
        """(E, 3) unit in-plane normals of the outline's edges, pointing out of the region."""
        a, b = self.points[self.edges[:, 0]], self.points[self.edges[:, 1]]
        return normalize(np.cross(b - a, self.flat))

    @functools.cached_property
    def normals(self) -> np.ndarray:
        summed = np.zeros_like(self.points)
        for end in (0, 1):
            np.add.at(summed, self.edges[:, end], self.edge_normals)
        return normalize(summed)

    @functools.cached_property
    def adjacency(self):
        """No connectivity mirror for an outline: any closed polyline mirrors onto itself as a graph."""
        import scipy.sparse as sparse
        return sparse.csr_matrix((len(self.points), len(self.points)))

    @staticmethod
    def chance_ratio(ratio: np.ndarray) -> np.ndarray:
        """An outline's ratio test values (nearest / second-nearest vertex) put on a surface's scale: a point
        dropped at random on a polyline passes nearest <= r * second with chance 2r / (1 + r), on a
        triangulated surface (a vertex's disc in its Voronoi cell) with chance about
        (2 pi / sqrt 3) (r / (1 + r))^2; each ratio maps to the surface ratio of equal chance, so that one
        threshold says "not by chance" equally on both."""
        chance = 2.0 * ratio / (1.0 + ratio)
        share = np.sqrt(chance / (2.0 * np.pi / np.sqrt(3.0)))  # r / (1 + r) of the equal-chance surface ratio
        return np.divide(share, 1.0 - share, out=np.full(len(share), np.inf), where=share < 1.0)

    @functools.cached_property
    def _middle_tree(self) -> cKDTree:
        return cKDTree(0.5 * (self.points[self.edges[:, 0]] + self.points[self.edges[:, 1]]), balanced_tree=False,
                       compact_nodes=False)

    def nearest_points(self, queries: np.ndarray):
        a, b = self.points[self.edges[:, 0]], self.points[self.edges[:, 1]]
        k = min(8, len(self.edges))
        _, candidates = self._middle_tree.query(queries, k=k)
        candidates = candidates.reshape(len(queries), k)
        start, direction = a[candidates], b[candidates] - a[candidates]
        along = np.einsum("qki,qki->qk", queries[:, None, :] - start, direction)
        t = np.clip(along / np.maximum(np.einsum("qki,qki->qk", direction, direction), 1e-300), 0.0, 1.0)
        found = start + t[:, :, None] * direction
        gaps = np.linalg.norm(found - queries[:, None, :], axis=2)
        best = gaps.argmin(axis=1)
        rows = np.arange(len(queries))
        edge, t = candidates[rows, best], t[rows, best]
        corners = np.column_stack([self.edges[edge], self.edges[edge, 1]])
        weights = np.column_stack([1.0 - t, t, np.zeros(len(t))])
        return found[rows, best], gaps[rows, best], self.edge_normals[edge], corners, weights


def _boundary_edges(faces: np.ndarray, points: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """(E, 2) the edges of ``faces`` (F, 3) that belong to one face only, each directed so that the region
    is on its left seen from ``normal`` (3,) (its face's winding, made counter-clockwise about it)."""
    corners = points[faces]
    facing = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]) @ normal
    oriented = np.where((facing >= 0)[:, None], faces, faces[:, ::-1])
    directed = np.concatenate([oriented[:, [0, 1]], oriented[:, [1, 2]], oriented[:, [2, 0]]])
    key = np.sort(directed, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return directed[counts[inverse.ravel()] == 1]


def build_surface(points: np.ndarray, faces: np.ndarray, excluded: np.ndarray | None = None) -> Surface:
    """The :class:`Surface` of a mesh, or its :class:`Outline` if the mesh is flat."""
    surface = Surface(points, faces, excluded)
    normal = flat_normal(points[surface.usable_index]) if surface.is_mesh and len(surface.usable_index) > 2 else None
    return surface if normal is None else Outline(points, faces, normal, excluded)

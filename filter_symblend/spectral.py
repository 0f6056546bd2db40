"""Intrinsic mirror map of a mesh: Laplace-Beltrami eigenfunctions and ZoomOut.

A bend or an articulation moves the two halves of a symmetric shape apart in
space but keeps lengths along the surface, so the mirror map stays an
intrinsic isometry, and an isometry maps each Laplace-Beltrami eigenfunction
to plus or minus itself (to a mix of its eigenspace when the eigenvalue
repeats). The mirror map is therefore found in the eigenbasis: as a
functional map C (k, k) with eigenfunctions(twin(x)) ~ eigenfunctions(x) C,
refined by ZoomOut (Melzi et al., ACM TOG 2019): point map -> C on k
eigenfunctions -> point map on k + 1, starting from the map of one global
mirror plane, which is wrong in detail on a bent shape but right in its
coarse parts. C is held orthogonal (the map is an isometry).

scipy has no mesh Laplacian, so the cotangent Laplacian is written here;
the eigenproblem is scipy's ARPACK in shift-invert mode.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sparse
from scipy.sparse.linalg import ArpackError, eigsh
from scipy.spatial import cKDTree

from .errors import GeometryError
from .mesh_geometry import farthest_point_order

EIGENFUNCTIONS = 60  # largest basis of the ZoomOut
# ZoomOut starts on this many: on pymeshlab's cow the first five eigenfunctions are all
# even (the mirror map and the identity look alike on them) and ZoomOut from there
# falls into the identity; from 10 it finds the mirror map.
FIRST_EIGENFUNCTIONS = 10
MIN_VERTICES = 4 * EIGENFUNCTIONS  # fewer cannot resolve the basis
SAMPLES = 3000  # vertices (farthest-point sample) on which the point maps of the ZoomOut run


def cotangent_laplacian(points: np.ndarray, faces: np.ndarray) -> tuple[sparse.csr_matrix, np.ndarray]:
    """Cotangent stiffness matrix (N, N), positive semi-definite, and lumped vertex areas (N,)
    (a third of each adjacent triangle's area, mesh units squared)."""
    n = len(points)
    corners = points[faces]
    doubled_areas = np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    rows, columns, weights = [], [], []
    for k in range(3):  # the angle at corner k faces the edge (k + 1, k + 2)
        i, j = faces[:, (k + 1) % 3], faces[:, (k + 2) % 3]
        u, v = corners[:, (k + 1) % 3] - corners[:, k], corners[:, (k + 2) % 3] - corners[:, k]
        cotangent = np.einsum("ni,ni->n", u, v) / np.maximum(doubled_areas, np.finfo(float).tiny)
        rows += [i, j]
        columns += [j, i]
        weights += [0.5 * cotangent, 0.5 * cotangent]
    adjacency = sparse.csr_matrix((np.concatenate(weights), (np.concatenate(rows), np.concatenate(columns))),
                                  shape=(n, n))
    stiffness = sparse.diags(np.asarray(adjacency.sum(axis=1)).ravel()) - adjacency
    areas = np.bincount(faces.ravel(), weights=np.repeat(doubled_areas / 6.0, 3), minlength=n)
    return stiffness.tocsr(), areas


def laplace_eigenfunctions(points: np.ndarray, faces: np.ndarray, count: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``count`` lowest Laplace-Beltrami eigenfunctions (N, count), orthonormal under the
    vertex areas (N,) normalized to total 1, and those areas. Vertices in no triangle get a
    tiny area so the eigenproblem stays definite; their values are meaningless."""
    stiffness, areas = cotangent_laplacian(points, faces)
    areas = np.maximum(areas / areas.sum(), 1e-12 / len(points))
    try:
        _, functions = eigsh(stiffness, k=count, M=sparse.diags(areas), sigma=-1e-8, which="LM")
    except (ArpackError, RuntimeError) as error:  # no convergence; a singular factorization
        raise GeometryError(f"the Laplace-Beltrami eigenproblem failed ({error})") from None
    return functions, areas


def _orthogonal(matrix: np.ndarray) -> np.ndarray:
    u, _, vt = np.linalg.svd(matrix)
    return u @ vt


def intrinsic_mirror_map(points: np.ndarray, faces: np.ndarray, initial_twin: np.ndarray):
    """Mirror twins of a farthest-point sample of the vertices, by ZoomOut.

    ``initial_twin`` (N,): a first guess of every vertex's twin (e.g. the vertex
    nearest its reflection in a global plane). Returns (sample (S,), twin (S,)
    vertex indices, round_trip (S,) vertex indices): ``round_trip`` is the twin
    of the twin, the sample vertex itself where the map is consistent.
    """
    if len(points) < MIN_VERTICES:
        raise GeometryError(f"the mesh has {len(points)} vertices, the intrinsic map needs {MIN_VERTICES}")
    functions, areas = laplace_eigenfunctions(points, faces, EIGENFUNCTIONS)
    sample = np.arange(len(points))
    if len(points) > SAMPLES:
        sample = np.sort(farthest_point_order(points, SAMPLES))
    # Each vertex's area goes to its nearest sample vertex, so sums over the sample are integrals.
    nearest = cKDTree(points[sample]).query(points)[1]
    sample_areas = np.bincount(nearest, weights=areas, minlength=len(sample))
    twin = nearest[initial_twin[sample]]  # indices into the sample
    embedding = functions[sample]
    for k in range(FIRST_EIGENFUNCTIONS, EIGENFUNCTIONS + 1):
        basis = embedding[:, :k]
        functional_map = _orthogonal(basis.T @ (sample_areas[:, None] * basis[twin]))
        twin = cKDTree(basis).query(basis @ functional_map)[1]
    vertices = cKDTree(functions)
    twin = vertices.query(embedding @ functional_map)[1]
    round_trip = vertices.query(functions[twin] @ functional_map)[1]
    return sample, twin, round_trip

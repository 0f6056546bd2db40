"""The intrinsic mirror as a map of the surface: its vertex pairs, denoised, and between them the local maps.

The intrinsic mirror (:mod:`.spectral`) pairs the vertices of the working mesh; a smooth mirror field
fitted to those pairs (:mod:`.field`) loses what no smooth field follows, a limb swung at a joint. Used
directly, as the local affine maps of the nearest pairs (:func:`.maps.point_pairs_map`), the pairs
follow the limb: a swing is rigid on either side of the joint, and so is the mirror between the limb
and its twin.

ZoomOut's point map is right only up to a vertex or two where the shape is thin (on a cow's swung
leg, half its vertex pairs are a vertex off). Those errors point every way, while the right pairs
agree on one local map; so each pair's twin is replaced by where a robust local map of its
``NEIGHBOURS`` nearest other pairs puts it, an affine map fitted by iteratively reweighted
least squares (Tukey's biweight, cut at ``field.ROBUST_SIGMAS`` robust deviations of the neighbours'
residuals): on a mesh whose vertices mirror each other it lands within 1e-4 of the spacing of the
exact twin where the mirror is locally rigid, on one sampled independently it averages the sampling
away. Pairs the map
does not come back on (the twin's twin more than ``pair_consistency`` from the vertex) are left out,
and so are those whose own twin is farther than the landing tolerance from the robust map's (a patch
sent to the wrong place).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .config import AutoConfig
from .field import tukey_weights
from .growth import LOCAL_MAP_RIDGE, affine_mirror_maps
from .spectral import CandidateMirror, WorkingMesh, candidate_mirrors, working_mesh
from .surface import Surface

# Intrinsic vertex pairs each robust local map is fitted to: twice the 12 of a local affine map, since up to
# half of them may be a vertex off (ZoomOut on a thin limb) and the reweighting needs the right ones to outnumber
# any wrong ones that agree.
NEIGHBOURS = 24
# Rounds of Tukey reweighting of each robust local map: the pairs a vertex off lose their weight in a few;
# on a cow's swung leg, where the mirror is rigid, the maps then land within 1e-4 of the spacing of the exact twins.
ROUNDS = 8
MINIMUM_PAIRS = 4  # the fewest pairs that determine an affine map of space


def robust_twins(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Twin positions (m, 3) of ``x`` (m, 3) under robust local affine maps of the other pairs ``x`` -> ``y``
    (see the module doc)."""
    k = min(NEIGHBOURS, len(x) - 1)
    _, nearest = cKDTree(x).query(x, k=k + 1)
    neighbours = nearest[:, 1:]
    weights = np.ones((len(x), k))
    for _ in range(ROUNDS):
        predicted, _ = affine_mirror_maps(x[neighbours], y[neighbours], weights, x, LOCAL_MAP_RIDGE)
        residual = np.linalg.norm(predicted - y, axis=1)[neighbours]
        tukey = tukey_weights(residual, 1e-12 * np.ptp(x))  # per row: the neighbours' residuals
        enough = np.count_nonzero(tukey, axis=1) >= MINIMUM_PAIRS
        weights[enough] = tukey[enough]
    return affine_mirror_maps(x[neighbours], y[neighbours], weights, x, LOCAL_MAP_RIDGE)[0]


def spectral_candidates(surface: Surface, config: AutoConfig, whitened: bool = False) -> tuple[
        WorkingMesh | None, list[CandidateMirror] | None]:
    """The working mesh of ``surface`` (a mesh) and its candidate intrinsic mirrors, the best first
    (:func:`.spectral.candidate_mirrors`; None without a working mesh or a spectrum), computed once per surface
    and ``config``: the first map and the intrinsic start both ask. ``whitened``: the mirrors of the whitened
    shape (its covariance the identity), whose intrinsic symmetry a compression of the whole does not break (the
    mirror of an affine image of a symmetric shape is an isometry again once whitened, :func:`.maps.affine_map`);
    the working mesh's points are then mapped back to the shape's space."""
    def compute():
        points = surface.points
        if whitened:
            centre, forward, backward = surface.whitening_frame
            points = (points - centre) @ forward
        mesh = working_mesh(points, surface.faces[surface.triangles], surface.usable, config)
        if mesh is None:
            return None, None
        candidates = candidate_mirrors(mesh, config)
        if whitened:
            mesh = WorkingMesh(mesh.points @ backward + centre, mesh.faces, mesh.vertex_of)
        return mesh, candidates
    return surface.memo(("intrinsic mirrors", config, whitened), compute)


def input_vertices(surface: Surface, mesh: WorkingMesh) -> np.ndarray:
    """(n,) the usable input vertex each vertex of the working ``mesh`` stands for: the one nearest it."""
    return surface.usable_index[surface.vertex_tree.query(mesh.points)[1]]


def intrinsic_vertex_map(surface: Surface, config: AutoConfig) -> np.ndarray | None:
    """(N,) each usable vertex's twin vertex under the best intrinsic candidate's own vertex map, not denoised
    (-1 for the other vertices; on a coarsened working mesh, the vertex nearest the twin cluster's centre); None
    for a point cloud or a mesh without a spectrum. A vertex map does not mix parts that touch (an arm along the
    torso), as the denoised pairs, a map of space, can."""
    if not surface.is_mesh:
        return None
    mesh, candidates = spectral_candidates(surface, config)
    if not candidates:
        return None
    input_vertex = input_vertices(surface, mesh)
    partner = np.full(len(surface.points), -1)
    clustered = mesh.vertex_of >= 0
    partner[clustered] = input_vertex[candidates[0].vertex_map[mesh.vertex_of[clustered]]]
    return partner


def intrinsic_pairs(surface: Surface, config: AutoConfig, whitened: bool = False) -> tuple[np.ndarray,
                                                                                            np.ndarray] | None:
    """(positions (m, 3), twin positions (m, 3)) of the working mesh's vertices under the denoised intrinsic
    mirror (see the module doc), each pair once per direction; None for a point cloud or a mesh without a
    spectrum. Computed once per surface and ``config`` (the first map, the intrinsic start's rounds and the
    second run of the rounds all ask); ``whitened``: of the whitened shape's mirror (:func:`spectral_candidates`)."""
    if not surface.is_mesh:
        return None
    return surface.memo(("intrinsic pairs", config, whitened), lambda: _denoised_pairs(surface, config, whitened))


def _denoised_pairs(surface: Surface, config: AutoConfig, whitened: bool) -> tuple[np.ndarray, np.ndarray] | None:
    """:func:`intrinsic_pairs`, computed."""
    mesh, candidates = spectral_candidates(surface, config, whitened)
    if not candidates:  # no working mesh, or no spectrum
        return None
    twin = candidates[0].vertex_map  # the one that mirrors the most of the surface
    back = np.linalg.norm(mesh.points[twin[twin]] - mesh.points, axis=1)
    vertices = np.flatnonzero(back <= config.pair_consistency * surface.diagonal)
    if len(vertices) <= NEIGHBOURS:
        return None
    x, y = mesh.points[vertices], mesh.points[twin[vertices]]
    denoised = robust_twins(x, y)
    sound = np.linalg.norm(denoised - y, axis=1) <= config.landing_tolerance * surface.diagonal
    return x[sound], denoised[sound]

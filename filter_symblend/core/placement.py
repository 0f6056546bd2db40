"""How far the user's landmark placement error moves the restoration (a parametric bootstrap).

A hand-placed landmark lies some distance from its true place along the surface; repeated placements
measure how far (``precision``: the RMS distance, mesh units). Each of ``PLACEMENT_DRAWS`` draws moves every
landmark by an independent Gaussian step in its tangent plane with that RMS length, solves Steps 1 and 2
again (at the full solve's widths), and fits the new targets rigidly onto the full solve's (a rigid motion of
the whole is not a change of shape). The warp is not solved again: the draw's warp differs from the full one,
to first order in the steps, by the spline, at the same centres, of what the full warp leaves the moved
landmarks from their new targets (``new target - f(moved landmark)``); one spline with all draws as columns
gives every vertex's change for every draw in one evaluation (as the jackknife's, core/uncertainty). The
test suite checks this against warps solved again in full.

Per vertex, the RMS length of its change over the draws, mesh units: how far the restoration from landmarks
placed with that precision lies, typically, from the one from landmarks in their true places.
"""

from __future__ import annotations

import numpy as np

from .geometry import normalize, rigid_fit
from .landmark_pairs import LandmarkPairs
from .mesh_quantities import vertex_normals
from .solve import LandmarkTargets, landmark_targets
from .uncertainty import changes_everywhere
from .warp import thin_plate_spline

PLACEMENT_DRAWS = 100  # draws of the placement error: the RMS of 100 draws is within about 7 % of its limit
PLACEMENT_SEED = 0  # the draws are the same on every call: the same input gives the same output


def tangent_steps(normals: np.ndarray, precision: float, rng: np.random.Generator) -> np.ndarray:
    """(k, 3): a Gaussian step in the plane normal to each of ``normals`` (k, 3) (unit), isotropic in it, whose
    RMS length is ``precision``."""
    helper = np.where(np.abs(normals[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    first = normalize(np.cross(normals, helper))
    second = np.cross(normals, first)
    along = rng.standard_normal((len(normals), 2)) * precision / np.sqrt(2.0)
    return along[:, [0]] * first + along[:, [1]] * second


def placement_spread(points: np.ndarray, faces: np.ndarray, landmarks: LandmarkPairs, options: dict,
                     full: LandmarkTargets, precision: float, draws: int = PLACEMENT_DRAWS) -> np.ndarray:
    """(N,): the RMS change of each restored vertex of ``points`` (N, 3) (``faces`` (F, 3), or none for a
    point cloud) when the checked ``landmarks`` are placed with RMS error ``precision`` along the surface
    (mesh units); core ``options``, full Steps 1 and 2 ``full``; see the module doc."""
    vertices = full.vertices
    centres = points[vertices]
    if full.flat is None:
        normals = vertex_normals(points, faces)[0][vertices]
    else:  # a flat input: every step in its plane
        normals = np.tile(full.flat, (len(vertices), 1))
    warp = thin_plate_spline(centres, full.target - centres, full.flat)
    fixed = {**options, "width_spacing": full.spacing}
    rng = np.random.default_rng(PLACEMENT_SEED)
    residuals = np.empty((len(vertices), draws, 3))
    shifted = points.copy()
    for draw in range(draws):
        moved = centres + tangent_steps(normals, precision, rng)
        shifted[vertices] = moved
        targets = landmark_targets(shifted, landmarks, fixed, flat=full.flat).target  # steps keep a flat input flat
        rotation, translation = rigid_fit(targets, full.target)
        residuals[:, draw] = targets @ rotation.T + translation - moved - warp(moved)
    squares = np.zeros(len(points))
    for _, change in changes_everywhere(points, vertices, residuals, full.flat):
        squares += (change**2).sum(axis=(1, 2))
    return np.sqrt(squares / draws)

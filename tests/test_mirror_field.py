"""The mirror field's least squares (auto/field.py) against the dense systems they stand for: the fit to pairs as
one Gram solve for the three axes, the registration's normal matrix without its unweighted rows and with the
involution term added block by block, each equal to the normal equations of the explicit design matrices."""

import numpy as np
import pytest

from filter_symblend.auto.config import DEFAULT
from filter_symblend.auto.field import (INVOLUTION_WEIGHT, RIDGE, SLIDING_INVOLUTION_WEIGHT, MirrorField, fit_to_pairs,
                                        register, robust_fit, robust_tolerance)
from filter_symblend.auto.surface import build_surface
from filter_symblend.core.geometry import reflection_across_plane
from filter_symblend.testing import synthetic

pytestmark = pytest.mark.auto


def _ridge_solve(matrix: np.ndarray, right: np.ndarray, toward: np.ndarray | float = 0.0) -> np.ndarray:
    """The dense ridge solve the field's systems stand for: RIDGE x the mean diagonal added, pulling the unknowns
    toward ``toward`` (none: toward 0)."""
    ridge = RIDGE * np.trace(matrix) / len(matrix)
    return np.linalg.solve(matrix + ridge * np.eye(len(matrix)), right + ridge * toward)


def _field(rng) -> tuple[MirrorField, np.ndarray]:
    centres = rng.normal(size=(30, 3))
    field = MirrorField([1.0, 0.2, 0.0], 0.1, centres, 0.8)
    field.weights = 0.1 * rng.normal(size=(30, 3))
    return field, rng.normal(size=(200, 3))


def test_the_fit_to_pairs_is_the_dense_weighted_least_squares_of_the_kronecker_system():
    rng = np.random.default_rng(3)
    field, x = _field(rng)
    y = reflection_across_plane(x, field.normal, field.offset) + 0.05 * rng.normal(size=x.shape)
    weights = rng.uniform(0.0, 1.0, len(x)) * (rng.uniform(size=len(x)) > 0.3)
    fit_to_pairs(field, x, y, weights, RIDGE)
    kernel = field.kernel(x)
    design = np.kron(kernel, np.eye(3))  # rows (vertex, axis), unknowns (centre, axis)
    residual = (y - field.reflected(x)).reshape(-1)
    row_weights = np.repeat(weights, 3)
    expected = _ridge_solve((design * row_weights[:, None]).T @ design, design.T @ (row_weights * residual))
    np.testing.assert_allclose(field.weights.reshape(-1), expected, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("sliding", [False, True])
def test_a_registration_step_solves_the_dense_point_to_plane_and_involution_system(sliding):
    """One iteration of ``register`` on a surface: its new weights are those of the explicit design matrices,
    point-to-plane rows (K_i kron n_i^T) and the involution's point-to-point rows (K(y_i) kron I_3) at the
    candidates' weight, the ridge pulling the weights toward 0, or let slide (the chosen field's) at its weight, the
    ridge pulling them toward the step's start; every row weighted, the unweighted ones included."""
    involution = SLIDING_INVOLUTION_WEIGHT if sliding else INVOLUTION_WEIGHT
    points, faces = synthetic.icosphere(3)
    points = synthetic.bend(synthetic.bumpy(points) * [1.0, 0.7, 0.5], 0.3)
    surface = build_surface(points, faces)
    sample = surface.usable_index[::4]
    x, normals = surface.points[sample], surface.normals[sample]
    field = robust_fit(x, reflection_across_plane(x, np.array([1.0, 0.5, 0.0]) / np.hypot(1.0, 0.5), 0.15),
                       x[::10], 0.5)
    field.weights += 0.02 * np.random.default_rng(5).normal(size=field.weights.shape)  # a start off the plane
    start = field.weights.copy()
    register(field, surface, sample, 1, DEFAULT, sliding)

    before = MirrorField(field.normal, field.offset, field.centres, field.width)
    before.weights = start
    images = before(x)
    landed, distance, landed_normals, _, _ = surface.nearest_points(images)
    near = np.einsum("ij,ij->i", before.mirror_normals(normals, x), landed_normals) > 0.5
    bound = robust_tolerance(distance[near], DEFAULT.coincident * surface.diagonal)
    weights = (near & (distance <= bound)).astype(float)
    assert 0 < weights.sum() < len(weights)  # some rows weigh nothing: the case the matrix leaves them out in
    kernel = before.kernel(x)
    plane_rows = (kernel[:, :, None] * landed_normals[:, None, :]).reshape(len(x), -1)
    plane_target = np.einsum("ij,ij->i", landed_normals, landed - before.reflected(x))
    involution_rows = np.kron(before.kernel(images), np.eye(3))
    involution_target = (x - before.reflected(images)).reshape(-1)
    matrix = (plane_rows * weights[:, None]).T @ plane_rows + involution * (
        involution_rows * np.repeat(weights, 3)[:, None]).T @ involution_rows
    right = plane_rows.T @ (weights * plane_target) + involution * involution_rows.T @ (
        np.repeat(weights, 3) * involution_target)
    toward = start.reshape(-1) if sliding else 0.0
    np.testing.assert_allclose(field.weights.reshape(-1), _ridge_solve(matrix, right, toward), rtol=1e-8, atol=1e-10)

"""A smooth non-rigid mirror map: the shape's reflection moved onto the shape by coherent point drift.

A bend or a compression moves the two halves of a symmetric shape apart in a way no
single plane undoes, but smoothly: the map from the reflected shape back onto the
shape is a smooth displacement field. Coherent Point Drift (Myronenko and Song, IEEE
TPAMI 2010) finds it: the shape's sample points are the data, the reflected ones the
centres of a Gaussian mixture, fitted by EM; the centres move by a displacement field
kept smooth by a Gaussian kernel of width BETA (x the RMS radius of the sample) with
weight SMOOTHNESS, the kernel matrix replaced by its RANK leading eigenvectors (the
paper's fast variant). Vertex normals enter the mixture weights (x exp(NORMAL_WEIGHT
(cos - 1))): without them the smoothest field can simply undo the reflection, every
point its own twin.

Written here: scipy has no point-set registration, and pycpd (the Python port of the
paper) has no normal term.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist

from ..core.mesh_quantities import farthest_point_order
from .surface import Surface

BETA = 3.0  # kernel width, x the sample's RMS radius: a field smooth over a third of the shape
SMOOTHNESS = 2.0  # the paper's lambda, its default
NORMAL_WEIGHT = 3.0  # kappa of the normal term: a point facing the other way weighs e^-6 as much
OUTLIER_WEIGHT = 0.1  # the paper's w: share of the data explained by a uniform outlier term, its default
RANK = 200  # leading eigenvectors of the kernel matrix kept
TOLERANCE = 1e-5  # EM stops when the variance changes by less than this fraction
STEP = 1e-3  # and the centres move by less than this fraction of the mixture's least deviation
POOL = 20_000  # the sample is drawn from at most this many evenly strided vertices


class DisplacementField:
    """Smooth displacement y -> y + K(y, centres) W, in coordinates centred at ``centre`` and scaled by ``scale``."""

    def __init__(self, centres: np.ndarray, weights: np.ndarray, centre: np.ndarray, scale: float):
        self.centres, self.weights, self.centre, self.scale = centres, weights, centre, scale

    def __call__(self, positions: np.ndarray) -> np.ndarray:
        """Moved ``positions`` (m, 3), mesh units."""
        y = (positions - self.centre) / self.scale
        kernel = np.exp(-cdist(y, self.centres, "sqeuclidean") / (2.0 * BETA**2))
        return (y + kernel @ self.weights) * self.scale + self.centre


def registration_sample(surface: Surface, count: int) -> np.ndarray:
    """Vertex indices (at most ``count``) spread over the usable vertices by farthest-point sampling."""
    pool = surface.usable_index[:: max(1, len(surface.usable_index) // POOL)]
    return np.sort(pool[farthest_point_order(surface.points[pool], min(count, len(pool)))])


def coherent_point_drift(data: np.ndarray, centres: np.ndarray, data_normals: np.ndarray,
                         centre_normals: np.ndarray, min_deviation: float, iterations: int) -> DisplacementField:
    """The smooth field (a callable on (m, 3) positions) that moves ``centres`` (M, 3), with unit
    normals ``centre_normals`` (M, 3), onto ``data`` (N, 3) with unit normals ``data_normals`` (N, 3).
    The mixture's standard deviation is held at ``min_deviation`` (mesh units) or more; EM runs at most
    ``iterations`` times."""
    origin = data.mean(axis=0)
    scale = float(np.sqrt(np.mean(np.sum((data - origin) ** 2, axis=1)))) or 1.0
    x, y = (data - origin) / scale, (centres - origin) / scale
    (m, dimension), n = y.shape, len(x)
    kernel = np.exp(-cdist(y, y, "sqeuclidean") / (2.0 * BETA**2))
    values, vectors = np.linalg.eigh(kernel)
    keep = values[-RANK:] > 1e-8 * values[-1]
    values, vectors = values[-RANK:][keep], vectors[:, -RANK:][:, keep]
    # The mixture weights in float32 (half the memory traffic; EM needs no more digits).
    normal_term = (NORMAL_WEIGHT * (centre_normals @ data_normals.T - 1.0)).astype(np.float32)
    x32 = x.astype(np.float32)
    moved = y
    variance = cdist(y, x, "sqeuclidean").sum() / (dimension * m * n)
    squared = np.sum(x**2, axis=1)
    floor = max((min_deviation / scale) ** 2, 1e-12)
    weights = np.zeros_like(y)
    for _ in range(iterations):
        # E-step: posterior of centre m for data point n, with the uniform outlier term.
        posterior = cdist(moved.astype(np.float32), x32, "sqeuclidean").astype(np.float32)
        posterior *= np.float32(-0.5 / variance)
        posterior += normal_term
        np.exp(posterior, out=posterior)
        uniform = (2.0 * np.pi * variance) ** (dimension / 2) * OUTLIER_WEIGHT / (1.0 - OUTLIER_WEIGHT) * m / n
        column = posterior.sum(axis=0, dtype=np.float64) + uniform
        posterior *= (1.0 / column).astype(np.float32)
        mass = np.maximum(posterior.sum(axis=1, dtype=np.float64), 1e-12)
        pulled = (posterior @ x32).astype(np.float64)
        # M-step: (K + lambda variance diag(1/mass)) W = diag(1/mass) pulled - y, by Woodbury on
        # the low-rank K = V diag(values) V^T.
        inverse_diagonal = mass / (SMOOTHNESS * variance)
        right = inverse_diagonal[:, None] * (pulled / mass[:, None] - y)
        inner = np.diag(1.0 / values) + vectors.T @ (inverse_diagonal[:, None] * vectors)
        weights = right - inverse_diagonal[:, None] * (vectors @ np.linalg.solve(inner, vectors.T @ right))
        updated = y + kernel @ weights
        step, moved = np.abs(updated - moved).max(), updated
        previous = variance
        matched = posterior.sum(axis=0, dtype=np.float64)
        variance = max((matched @ squared - 2.0 * np.sum(pulled * moved)
                        + mass @ np.sum(moved**2, axis=1)) / (mass.sum() * dimension), floor)
        if abs(previous - variance) < TOLERANCE * previous and step < STEP * np.sqrt(floor):
            break
    return DisplacementField(y, weights, origin, scale)

"""A rough non-rigid mirror map: the shape's reflection moved onto the shape by coherent point drift.

A bend or a compression moves the two halves of a symmetric shape apart in a way no
single plane undoes, but smoothly: the map from the reflected shape back onto the
shape is a smooth displacement field. Coherent Point Drift (Myronenko and Song, IEEE
TPAMI 2010) finds it: the shape's sample points are the data, the reflected ones the
centres of a Gaussian mixture, fitted by EM; the centres move by a displacement field
kept smooth by a Gaussian kernel (``WIDTH`` x the RMS radius of the sample) with
weight ``SMOOTHNESS``, the kernel matrix replaced by its ``RANK`` leading
eigenvectors (the paper's fast variant). Vertex normals enter the mixture weights
(x exp(``NORMAL_WEIGHT`` (cos - 1))): without them the smoothest field can simply
undo the reflection, every point its own twin.

Its soft assignments reach twins much farther from a plane's prediction than ICP's
nearest points do (a 1.2 rad bend with a 0.65 compression), but not precisely: it is a
start for the mirror field (:mod:`.field`), which then lands the map on the surface.

Written here: scipy has no point-set registration, and pycpd (the Python port of the
paper) has no normal term. Its constants are the paper's defaults or its own stops, not tunables of the
automatic pairs (:class:`.config.AutoConfig`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist

from ..core.mesh_quantities import farthest_point_order
from .surface import Surface

SAMPLES = 1000  # points of the registration (its cost grows with their square)
POOL = 20_000  # the sample is drawn by farthest-point sampling from at most this many evenly strided vertices
# The mixture's spread never falls below this, x the mean vertex spacing: below a third of the spacing its posteriors
# pick single vertices and the drift follows the sampling, not the shape.
MIN_DEVIATION = 0.3
WIDTH = 3.0  # kernel width of the displacement field, x the sample's RMS radius: smooth over a third of the shape
SMOOTHNESS = 2.0  # weight of the field's smoothness (the paper's lambda): coherent point drift's published default
# Normal term of the mixture weights, exp(kappa (cos - 1)): a point facing the other way weighs e^-6 as much, and
# the field cannot simply undo the reflection.
NORMAL_WEIGHT = 3.0
OUTLIERS = 0.1  # share of the data explained by the uniform outlier term: coherent point drift's published default
RANK = 200  # leading eigenvectors of the kernel matrix kept (the paper's fast variant)
ITERATIONS = 100  # EM iterations at most
TOLERANCE = 1e-5  # EM stops when the mixture's variance changes by less than this fraction...
STEP = 1e-3  # ...and the centres move by less than this, x the mixture's least deviation


class DisplacementField:
    """Smooth displacement y -> y + K(y, centres) W, in coordinates centred at ``centre`` and scaled by
    ``scale``, K Gaussian of ``width`` (scaled units)."""

    def __init__(self, centres: np.ndarray, weights: np.ndarray, centre: np.ndarray, scale: float, width: float):
        self.centres, self.weights, self.centre, self.scale, self.width = centres, weights, centre, scale, width

    def __call__(self, positions: np.ndarray) -> np.ndarray:
        """Moved ``positions`` (m, 3), mesh units."""
        y = (positions - self.centre) / self.scale
        kernel = np.exp(-cdist(y, self.centres, "sqeuclidean") / (2.0 * self.width**2))
        return (y + kernel @ self.weights) * self.scale + self.centre


def registration_sample(surface: Surface, count: int, pool: int) -> np.ndarray:
    """Vertex indices (at most ``count``) spread over the usable vertices by farthest-point sampling from at most
    ``pool`` evenly strided ones."""
    pool = surface.usable_index[:: max(1, len(surface.usable_index) // pool)]
    return np.sort(pool[farthest_point_order(surface.points[pool], min(count, len(pool)))])


def coherent_point_drift(data: np.ndarray, centres: np.ndarray, data_normals: np.ndarray,
                         centre_normals: np.ndarray, min_deviation: float) -> DisplacementField:
    """The smooth field (a callable on (m, 3) positions) that moves ``centres`` (M, 3), with unit
    normals ``centre_normals`` (M, 3), onto ``data`` (N, 3) with unit normals ``data_normals`` (N, 3).
    The mixture's standard deviation is held at ``min_deviation`` (mesh units) or more; EM runs at most
    ITERATIONS times."""
    width = WIDTH
    origin = data.mean(axis=0)
    scale = float(np.sqrt(np.mean(np.sum((data - origin) ** 2, axis=1)))) or 1.0
    x, y = (data - origin) / scale, (centres - origin) / scale
    (m, dimension), n = y.shape, len(x)
    kernel = np.exp(-cdist(y, y, "sqeuclidean") / (2.0 * width**2))
    values, vectors = np.linalg.eigh(kernel)
    rank = RANK
    keep = values[-rank:] > 1e-8 * values[-1]
    values, vectors = values[-rank:][keep], vectors[:, -rank:][:, keep]
    # The mixture weights in float32 (half the memory traffic; EM needs no more digits).
    normal_term = (NORMAL_WEIGHT * (centre_normals @ data_normals.T - 1.0)).astype(np.float32)
    x32 = x.astype(np.float32)
    moved = y
    variance = cdist(y, x, "sqeuclidean").sum() / (dimension * m * n)
    squared = np.sum(x**2, axis=1)
    floor = max((min_deviation / scale) ** 2, 1e-12)
    weights = np.zeros_like(y)
    for _ in range(ITERATIONS):
        # E-step: posterior of centre m for data point n, with the uniform outlier term.
        posterior = cdist(moved.astype(np.float32), x32, "sqeuclidean").astype(np.float32)
        posterior *= np.float32(-0.5 / variance)
        posterior += normal_term
        np.exp(posterior, out=posterior)
        outliers = OUTLIERS
        uniform = (2.0 * np.pi * variance) ** (dimension / 2) * outliers / (1.0 - outliers) * m / n
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
    return DisplacementField(y, weights, origin, scale, width)

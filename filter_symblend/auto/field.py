"""A smooth mirror map of a surface onto itself, registered by symmetric non-rigid ICP.

The map is a reflection plus a smooth displacement, m(x) = reflect(x) + sum_c k(x, c) w_c, with a
Gaussian kernel k of width ``width`` around ``centres`` spread over the surface: it follows a bend, a
compression or a swung limb as far as the kernel's width allows. It is first fitted to the pairs a
rough map gives (a plane, the whitened plane, the intrinsic mirror), robustly (Tukey's biweight: the
rough map's wrong pairs do not pull it), then registered onto the surface: each iteration moves the
map's images toward the tangent planes of the surface where they land (point-to-plane ICP, which
converges in a few steps where point-to-point creeps), while the map applied twice returns to the
start (m(m(x)) = x, linearized at the current images), images landing far, or on a surface facing
the wrong way, being left out. A ridge keeps the least-squares system well posed. Let slide (the chosen
field of a shape that may be bent or compressed), the involution term weighs less and the ridge damps each
step instead of the weights, so that where the surface does not hold the map (a bend's rounded ends) nothing
pulls it back toward the plane reflection it started from.

Written here: scipy has no non-rigid registration. The coherent point drift this replaces (earlier
in this layer) needed a start near the answer and a kernel too stiff for a strong bend.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.distance import cdist

from ..core.geometry import normalize, reflection_across_plane
from ..core.landmark_asymmetry import fit_mirror_plane
from ..core.mesh_quantities import farthest_point_order
from .config import AutoConfig

# The registration stops when its images move less than this (RMS, x the diagonal) in an iteration: a
# tenth of the precision the pairs need.
CONVERGED = 1e-5
# Ridge of a mirror field's least squares, x the normal matrix's mean diagonal: enough to keep the system
# invertible where centres see no data, too little to pull a bend's large displacements back toward the plane.
# Let slide, the registration puts it on each step (toward the current weights) instead: SLIDING_INVOLUTION_WEIGHT.
RIDGE = 1e-5
# Rounds of Tukey reweighting when a field is fitted to a rough map's pairs: wrong pairs lose their weight
# in two or three.
ROBUST_ROUNDS = 4
# Distances beyond this many robust standard deviations (1.4826 x median) are outliers: the usual bound; on an
# exactly symmetric mesh it admits only exact twins.
ROBUST_SIGMAS = 3.0
# An image counts in the registration only if the surface where it lands faces within 60 degrees (this cosine)
# of the carried normal: on a thin sheet the other face is as near, but faces away.
FACING = 0.5
# Weight of m(m(x)) = x in the registration, x the point-to-plane term: without it a map may fold several regions
# onto one (each lands on the surface); as strong as the data, it holds the map where it started, and ICP creeps
# (a tenth: the median twin error on a bent cow half that at full weight). While candidates are compared it keeps a
# rough one from folding its way to a larger share.
INVOLUTION_WEIGHT = 0.1
# The same weight in the chosen field's registration, where the shape may be bent or compressed: linearized at the
# current images, the term holds them where they are, and a field that lands on the surface slides along it toward
# its twins only as far as the term lets it (the objective cannot see a slide otherwise: a mirror moved along the
# surface lands on it and is its own inverse too). A tenth of INVOLUTION_WEIGHT let the remeshed spot under Figure
# 1's map reach 86 % of its twins within 1 % of the diagonal in 10 steps a width, against 66 % (82 % in 30 steps) at
# INVOLUTION_WEIGHT; none at all did worse (84 %, and the remeshed cow bent 1.2 rad a median twin error of 0.28 %
# of the diagonal against 0.22 %; docs/benchmarks.md). Let slide, the ridge damps each step rather than the weights:
# toward none, it pulled the map toward the plane reflection every step wherever the point-to-plane term does not
# hold it (a rounded end, which a bend turns: any turn of the mirror there lands on the surface), so that a field
# fitted to the true twins of the remeshed spot bent 1.2 rad and registered left a quarter of those in the last
# tenth of its length more than 1 % of the diagonal off (damped, none; tests/test_auto_ground_truth.py).
SLIDING_INVOLUTION_WEIGHT = 0.01


class MirrorField:
    """m(x) = reflect(x) + K(x) @ weights across the plane ``normal . x = offset`` (mesh units), the
    kernel K Gaussian of ``width`` (mesh units) around ``centres`` (c, 3)."""

    def __init__(self, normal: np.ndarray, offset: float, centres: np.ndarray, width: float):
        self.normal, self.offset = normalize(np.asarray(normal, dtype=float)), float(offset)
        self.centres, self.width = centres, float(width)
        self.weights = np.zeros((len(centres), 3))
        self.reflection = np.eye(3) - 2.0 * np.outer(self.normal, self.normal)

    def kernel(self, x: np.ndarray) -> np.ndarray:
        """(m, c) kernel values at the positions ``x`` (m, 3)."""
        return np.exp(-cdist(x, self.centres, "sqeuclidean") / (2.0 * self.width**2))

    def reflected(self, x: np.ndarray) -> np.ndarray:
        return reflection_across_plane(x, self.normal, self.offset)

    def __call__(self, x: np.ndarray) -> np.ndarray:
        """Images (m, 3) of the positions ``x`` (m, 3)."""
        return self.reflected(x) + self.kernel(x) @ self.weights

    def jacobians(self, x: np.ndarray) -> np.ndarray:
        """(m, 3, 3) derivative of the map at ``x`` (m, 3): reflection - sum_c k_c w_c (x - c)^T / width^2,
        from four (m, c) x (c, 3) products."""
        k = self.kernel(x)
        pulled = k @ self.weights  # (m, 3): sum_c k_c w_c
        moments = np.stack([k @ (self.weights * self.centres[:, [j]]) for j in range(3)], axis=2)  # (m, 3, 3)
        return self.reflection[None] - (pulled[:, :, None] * x[:, None, :] - moments) / self.width**2

    def mirror_normals(self, normals: np.ndarray, positions: np.ndarray) -> np.ndarray:
        """Unit normals (m, 3) at the images of ``positions`` (m, 3) of the surface normals ``normals`` there
        (carried by the inverse transpose of the derivative)."""
        jacobians = self.jacobians(positions)
        return normalize(np.linalg.solve(np.transpose(jacobians, (0, 2, 1)), normals[:, :, None])[:, :, 0])


def robust_tolerance(values: np.ndarray, floor: float) -> float:
    """ROBUST_SIGMAS robust standard deviations of ``values`` (taken as |N(0, sigma)|), at least ``floor``."""
    return max(ROBUST_SIGMAS * 1.4826 * float(np.median(values)), floor) if len(values) else floor


def tukey_weights(misfit: np.ndarray, floor: float) -> np.ndarray:
    """Tukey's biweight of ``misfit`` (..., k): zero beyond ROBUST_SIGMAS robust deviations of the misfits
    along the last axis (the bound at least ``floor``)."""
    bound = np.maximum(ROBUST_SIGMAS * 1.4826 * np.median(misfit, axis=-1, keepdims=True), floor)
    return (1.0 - np.minimum(misfit / bound, 1.0) ** 2) ** 2


def _ridge(matrix: np.ndarray, ridge: float) -> float:
    """Add ``ridge`` x the mean diagonal of ``matrix`` (s, s) to its diagonal (in place); returns the amount added."""
    amount = ridge * np.trace(matrix) / len(matrix)
    matrix[np.diag_indices(len(matrix))] += amount
    return amount


def _gram(kernel: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """sum_i w_i K_i K_i^T (c, c) over the rows of ``kernel`` (m, c) that weigh anything."""
    used = weights > 0
    return (kernel[used] * weights[used, None]).T @ kernel[used]


def _plane_normal_matrix(kernel: np.ndarray, normals: np.ndarray, used: np.ndarray) -> np.ndarray:
    """sum_i (K_i K_i^T) kron (n_i n_i^T) over the ``used`` (m,) bool point-to-plane rows, as one product of the
    (m, 3c) design matrix with itself (numpy computes D^T D as a symmetric rank-k update, half the work of a
    general product: 25 -> 17 ms at 1,500 rows and 200 centres on one core); unknowns ordered (centre, axis)."""
    design = (kernel[used][:, :, None] * normals[used][:, None, :]).reshape(int(used.sum()), -1)
    return design.T @ design


def fit_to_pairs(field: MirrorField, x: np.ndarray, y: np.ndarray, weights: np.ndarray, ridge: float) -> None:
    """Set ``field``'s weights so that it maps ``x`` (m, 3) to ``y`` (m, 3), each pair weighing ``weights``
    (m,). Point-to-point rows do not couple the axes (the normal matrix is the Gram matrix kron I_3): one
    (c, c) solve for the three of them."""
    kernel = field.kernel(x)
    residual = y - field.reflected(x)
    gram = _gram(kernel, weights)
    _ridge(gram, ridge)
    field.weights = np.linalg.solve(gram, (kernel * weights[:, None]).T @ residual)


def robust_fit(x: np.ndarray, y: np.ndarray, centres: np.ndarray, width: float) -> MirrorField:
    """The field through the pairs ``x`` -> ``y`` (m, 3), ``width`` and ``centres`` (c, 3) given, fitted by
    iteratively reweighted least squares with Tukey's biweight at ROBUST_SIGMAS robust deviations:
    pairs far off the others' smooth map weigh nothing. Its plane is the pairs' mirror plane."""
    plane = fit_mirror_plane(x, y)
    field = MirrorField(plane.normal, plane.offset, centres, width)
    weights = np.ones(len(x))
    for _ in range(ROBUST_ROUNDS):
        fit_to_pairs(field, x, y, weights, RIDGE)
        weights = tukey_weights(np.linalg.norm(field(x) - y, axis=1), 1e-300)
    return field


def refitted(field: MirrorField, positions: np.ndarray, centres: np.ndarray, width: float) -> MirrorField:
    """A field of another ``width`` and ``centres`` that reproduces ``field`` at ``positions`` (m, 3)."""
    finer = MirrorField(field.normal, field.offset, centres, width)
    fit_to_pairs(finer, positions, field(positions), np.ones(len(positions)), RIDGE)
    return finer


def register(field: MirrorField, surface, sample: np.ndarray, iterations: int, config: AutoConfig,
             sliding: bool = False) -> MirrorField:
    """``field`` refined (in place) so that it maps the ``sample`` (m,) vertices of ``surface`` (a
    :class:`.surface.Surface`) onto the surface, by symmetric point-to-plane ICP (see the module doc), m(m(x)) = x
    weighing INVOLUTION_WEIGHT x the point-to-plane term, the ridge on the weights; ``sliding``: the chosen field
    let slide, m(m(x)) = x weighing SLIDING_INVOLUTION_WEIGHT and the ridge on each step."""
    involution = SLIDING_INVOLUTION_WEIGHT if sliding else INVOLUTION_WEIGHT
    x = surface.points[sample]
    normals = surface.normals[sample]
    kernel = field.kernel(x)
    reflected = field.reflected(x)
    floor = config.coincident * surface.diagonal
    previous = None
    for _ in range(iterations):
        images = field(x)
        if previous is not None and np.sqrt(np.mean(np.sum((images - previous) ** 2, axis=1))) < \
                CONVERGED * surface.diagonal:
            break
        previous = images
        landed, distance, landed_normals, _, _ = surface.nearest_points(images)
        facing = np.einsum("ij,ij->i", field.mirror_normals(normals, x), landed_normals)
        facing = facing if surface.is_mesh else np.abs(facing)  # a point cloud's normals are unoriented
        near = facing > FACING
        if not near.any():
            break
        used = near & (distance <= robust_tolerance(distance[near], floor))
        weights = used.astype(float)
        # A landed image z with normal n: n . (reflect(x) + K(x) W) = n . z
        target = np.einsum("ij,ij->i", landed_normals, landed - reflected)
        matrix = _plane_normal_matrix(kernel, landed_normals, used)
        right = kernel.T @ (landed_normals * (weights * target)[:, None])  # design^T (w target), as (c, 3)
        # m(m(x)) = x at the current images: reflect(y) + K(y) W = x
        image_kernel = field.kernel(images)
        blocks = matrix.reshape(len(field.centres), 3, len(field.centres), 3)
        gram = involution * _gram(image_kernel, weights)
        for axis in range(3):  # + involution (Gram kron I_3), added to the axes' diagonal blocks
            blocks[:, axis, :, axis] += gram
        matrix = blocks.reshape(matrix.shape)
        right += involution * ((image_kernel * weights[:, None]).T @ (x - field.reflected(images)))
        start = field.weights.reshape(-1) if sliding else 0.0  # what the ridge pulls the weights toward
        ridge = _ridge(matrix, RIDGE)
        field.weights = np.linalg.solve(matrix, right.reshape(-1) + ridge * start).reshape(-1, 3)
    return field


def field_centres(surface, sample: np.ndarray, count: int) -> np.ndarray:
    """(count, 3) kernel centres: ``count`` of the ``sample`` vertices by farthest-point sampling."""
    chosen = farthest_point_order(surface.points[sample], min(count, len(sample)))
    return surface.points[sample[chosen]]

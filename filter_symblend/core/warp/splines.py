"""The thin-plate-spline warp that carries the whole mesh along with the landmarks.

In 3D the thin-plate (biharmonic) kernel is r: the spline is
f(x) = sum_i w_i (-|x - c_i|) + a + B x, the same as scipy's RBFInterpolator with
kernel="linear" and degree=1, and it reproduces any affine map exactly.

Fit: the dense (k + 4) system [[-R, P], [P^T, 0]] (R_ij = |c_i - c_j|, P = [1, c]),
in coordinates centred on the landmarks and scaled by their extent, solved by
LU with partial pivoting (LAPACK, as RBFInterpolator does; the symmetric-indefinite
solver was no faster here).

Evaluation is written here because it is the filter's hot loop on large meshes:
vertices go in blocks of about BLOCK_ELEMENTS distances, one block per core at a
time; the squared distances of a block come from one matrix product
[x, 1, |x|^2] @ [-2c; |c|^2; 1] (BLAS), then one square root, then one product
with the weights. Measured 3.4x faster than RBFInterpolator's evaluation at 537k
vertices x 4,000 landmarks on 2 cores, with memory bounded by the blocks.
Expanding |x - c|^2 loses digits for x within NEAR (of the landmarks' extent) of
a landmark, so those vertices are evaluated again from coordinate differences
(scipy's cdist, a block at a time).

Beyond the landmarks an iterative solve reaches (warp/choice.py), the exact spline is out of
reach (its evaluation grows as k per vertex, each iteration step as k^2), so
``ApproximateThinPlateSpline`` takes over: the exact spline through SUBSET_CENTRES
landmarks spread by farthest-point sampling, plus what it leaves at all the
landmarks, interpolated by local splines of the same kernel on overlapping
patches blended by a smooth partition of unity. It is exact at every landmark,
continuous, and behaves like the exact spline near each landmark (a Wendland
interpolant of the same residual changed edge lengths by up to 89 % against the
exact spline on a scan; this by 1 %).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.linalg import lu_factor, lu_solve
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

from ..mesh_quantities import farthest_point_order
from ..parallel import WORKERS, blockwise, in_threads

BLOCK_ELEMENTS = 2**17  # distances per evaluation block (1 MB of float64; measured fastest of 2^15..2^22)
CHUNK_ROWS = 2**14  # vertices per task of the thread pool (fewer when that leaves a core idle)
DIRECT_ELEMENTS = 2**14  # at most this many distances (a few points): computed directly, no blocks, no threads
NEAR = 1e-4  # vertices closer than this to a landmark (fraction of their extent) are evaluated exactly
ROUNDING = 64 * np.finfo(float).eps  # keeps expanded squared distances non-negative
SUBSET_CENTRES = 6_000  # landmarks of the approximation's global part (fewer: measured worse)
CENTRES_PER_PATCH = 100  # one correction patch per this many landmarks (each holds about 500)
PATCH_REACH = 1.5  # patch radius, in the largest distance from a landmark to its nearest patch centre


class ThinPlateSpline:
    """The 3D thin-plate spline through ``values`` (k, d) at ``centres`` (k, 3), with an affine
    part, or (``affine=False``) a constant one: always solvable, even for coplanar centres."""

    def __init__(self, centres: np.ndarray, values: np.ndarray, affine: bool = True):
        self._shift = centres.mean(axis=0)
        self._scale = float(np.ptp(centres, axis=0).max()) or 1.0
        self._centres = (centres - self._shift) / self._scale
        k, terms = len(centres), 4 if affine else 1
        system = np.empty((k + terms, k + terms))
        system[:k, :k] = cdist(self._centres, self._centres)
        np.negative(system[:k, :k], out=system[:k, :k])
        system[:k, k] = system[k, :k] = 1.0
        if affine:
            system[:k, k + 1:] = self._centres
            system[k + 1:, :k] = self._centres.T
        system[k:, k:] = 0.0
        right = np.zeros((k + terms, values.shape[1]))
        right[:k] = values
        self._factors = lu_factor(system, overwrite_a=True, check_finite=False)
        coefficients = lu_solve(self._factors, right, check_finite=False)
        self._set_coefficients(coefficients[:k], coefficients[k:])
        self.description = f"exact thin-plate spline through the {k} landmarks"

    @classmethod
    def from_coefficients(cls, centres: np.ndarray, shift: np.ndarray, scale: float, weights: np.ndarray,
                          polynomial: np.ndarray, description: str) -> ThinPlateSpline:
        """The spline sum_i weights_i (-|y - centres_i|) + [1, y] @ polynomial, y = (x - shift) / scale, with
        ``centres`` (k, 3) already in y; no fit (a caller that solved for the coefficients itself)."""
        spline = cls.__new__(cls)
        spline._shift, spline._scale, spline._centres = shift, scale, centres
        spline._set_coefficients(weights, polynomial)
        spline.description = description
        return spline

    def refitted(self, values: np.ndarray) -> ThinPlateSpline:
        """The spline through ``values`` (k, d) at the same centres, from the factorization kept from the fit."""
        k = len(self._centres)
        right = np.zeros((k + len(self._polynomial), values.shape[1]))
        right[:k] = values
        coefficients = lu_solve(self._factors, right, check_finite=False)
        return ThinPlateSpline.from_coefficients(self._centres, self._shift, self._scale, coefficients[:k],
                                                 coefficients[k:], self.description)

    def kernel_weights(self) -> np.ndarray:
        """The weights (k, d) of the kernel terms -|x - c_i| in the caller's coordinates."""
        return self._weights / self._scale

    def _set_coefficients(self, weights: np.ndarray, polynomial: np.ndarray) -> None:
        self._weights, self._polynomial = weights, polynomial
        squares = np.einsum("ij,ij->i", self._centres, self._centres)
        self._expanded = np.vstack([-2.0 * self._centres.T, squares, np.ones(len(self._centres))])  # (5, k)
        self._largest_square = float(squares.max())

    def _polynomial_part(self, x: np.ndarray) -> np.ndarray:
        return np.column_stack([np.ones(len(x)), x])[:, :len(self._polynomial)] @ self._polynomial

    def __call__(self, points: np.ndarray, progress: Callable[[float], None] | None = None,
                 parallel: bool = True) -> np.ndarray:
        """The spline's values (m, d) at ``points`` (m, 3); ``progress(fraction)`` after each 5 %.
        ``parallel=False`` for a caller that runs several splines in threads itself."""
        return self._evaluate(np.ascontiguousarray((points - self._shift) / self._scale), progress, parallel)

    def at_centres(self) -> np.ndarray:
        """The spline's values (k, d) at its own centres, each centre's own term exactly 0 (the expanded
        squared distance leaves sqrt(rounding) there). The distances between centres are symmetric: each is
        computed once (the block of rows [s, e) against the centres from s on) and serves both of its
        centres, half the work of evaluating at k other points (the iterative solve's product per step)."""
        centres, weights = self._centres, self._weights
        k = len(centres)
        out = self._polynomial_part(centres)
        augmented = self._augmented(centres)
        rows = max(1, BLOCK_ELEMENTS // k)
        starts = list(range(0, k, rows))
        tasks = min(len(starts), 2 * WORKERS)  # blocks dealt round-robin: each task gets long and short rows

        def accumulate(task: int) -> np.ndarray:
            part = np.zeros_like(out)
            for start in starts[task::tasks]:
                end = min(start + rows, k)
                distances = augmented[start:end] @ self._expanded[:, start:]
                np.sqrt(distances, out=distances)
                distances[np.arange(end - start), np.arange(end - start)] = 0.0
                part[start:end] -= distances @ weights[start:]
                part[end:] -= distances[:, end - start:].T @ weights[start:end]
            return part
        for part in in_threads(accumulate, range(tasks)):
            out += part
        return self._exact_near(centres, out, own_centres=True)

    def _augmented(self, x: np.ndarray) -> np.ndarray:
        """[x, 1, |x|^2 (+ rounding)] (m, 5): its product with ``_expanded`` gives squared distances to the centres."""
        augmented = np.empty((len(x), 5))
        augmented[:, :3] = x
        augmented[:, 3] = 1.0
        squares = np.einsum("ij,ij->i", x, x)
        augmented[:, 4] = squares + ROUNDING * (squares + self._largest_square)
        return augmented

    def _evaluate(self, x: np.ndarray, progress, parallel: bool) -> np.ndarray:
        """Values (m, d) at ``x`` (m, 3) in the spline's scaled coordinates."""
        out = self._polynomial_part(x)
        if len(x) * len(self._centres) <= DIRECT_ELEMENTS:  # a few points: their distances directly, exact
            out -= cdist(x, self._centres) @ self._weights
            if progress is not None:
                progress(1.0)
            return out
        augmented = self._augmented(x)
        rows = max(1, BLOCK_ELEMENTS // len(self._centres))
        chunk = int(min(CHUNK_ROWS, max(rows, -(-len(x) // (2 * WORKERS)))))  # two tasks per core at least

        def evaluate_chunk(start: int) -> int:
            end = min(start + chunk, len(x))
            distances = np.empty((rows, len(self._centres)))
            for row in range(start, end, rows):
                block = augmented[row:min(row + rows, end)]
                here = np.matmul(block, self._expanded, out=distances[:len(block)])
                np.sqrt(here, out=here)
                out[row:row + len(block)] -= here @ self._weights
            return end

        reported = 0.0
        for end in blockwise(evaluate_chunk, range(0, len(x), chunk), parallel):
            if progress is not None and (end / len(x) >= reported + 0.05 or end == len(x)):
                reported = end / len(x)
                progress(reported)
        return self._exact_near(x, out, own_centres=False, parallel=parallel)

    def _exact_near(self, x: np.ndarray, out: np.ndarray, own_centres: bool, parallel: bool = True) -> np.ndarray:
        """``out`` (m, d) with the values at the ``x`` within NEAR of a centre (another one, for the centres
        themselves) computed again from coordinate differences (:meth:`_kernel_part`; ``parallel``: on every core)."""
        nearest = cKDTree(self._centres).query(x, k=2 if own_centres else 1, distance_upper_bound=NEAR,
                                               workers=-1)[0]
        near = np.flatnonzero((nearest[:, 1] if own_centres else nearest) <= NEAR)  # another centre that near
        if near.size:
            out[near] = self._polynomial_part(x[near]) - self._kernel_part(x[near], parallel)
        return out

    def _kernel_part(self, x: np.ndarray, parallel: bool) -> np.ndarray:
        """sum_i w_i |x - c_i| (m, d) at ``x`` (m, 3) from coordinate differences (scipy's cdist), a block of
        about BLOCK_ELEMENTS distances at a time, the blocks on every core with ``parallel``. One cdist of all
        m x k distances writes them to memory and reads them back for the product: at 5,900 landmarks, the
        vertices that are landmarks (every one of them near one) took 0.67 s where the blocks take 0.06 s."""
        rows = max(1, BLOCK_ELEMENTS // len(self._centres))

        def block(start: int) -> np.ndarray:
            return cdist(x[start:start + rows], self._centres) @ self._weights

        return np.concatenate(list(blockwise(block, range(0, len(x), rows), parallel)))


def _wendland(t: np.ndarray) -> np.ndarray:
    """Wendland's C2 function (1 - t)^4 (4t + 1) for t in [0, 1], 0 beyond: a smooth bump."""
    u = np.clip(1.0 - t, 0.0, None)
    u *= u
    return u * u * (4.0 * t + 1.0)


class ApproximateThinPlateSpline:
    """For many landmarks: the exact spline through SUBSET_CENTRES farthest-point landmarks,
    plus the residual it leaves at all ``centres`` (k, 3) interpolated on patches.

    Patch a (one per CENTRES_PER_PATCH landmarks, centres z_a by farthest-point sampling,
    radius R = PATCH_REACH x the largest distance from a landmark to its nearest z_a) holds a
    local spline (constant part) through the residuals of the landmarks within R. At x the
    correction is sum_a w_a(x) s_a(x) / max(sum_a w_a(x), floor), w_a = Wendland(|x - z_a| / R):
    at a landmark every patch that weighs it interpolates it, so ``values`` (k, d) are met
    exactly; far from the landmarks the correction fades to 0 continuously.
    """

    def __init__(self, centres: np.ndarray, values: np.ndarray):
        subset = farthest_point_order(centres, SUBSET_CENTRES, start=0)
        self.coarse = ThinPlateSpline(centres[subset], values[subset])
        self.description = (f"thin-plate spline through {len(subset)} of the {len(centres)} landmarks plus local "
                            "splines of its residual on patches, exact at all")
        residual = values - self.coarse(centres)
        residual[subset] = 0.0
        patch_centres = centres[farthest_point_order(centres, max(1, len(centres) // CENTRES_PER_PATCH), start=0)]
        self._patch_centres = patch_centres
        covering = float(cKDTree(patch_centres).query(centres, workers=-1)[0].max())
        self.radius = PATCH_REACH * covering
        self._floor = float(_wendland(np.array(1.0 / PATCH_REACH)))  # the least total weight at a landmark
        members = cKDTree(centres).query_ball_point(patch_centres, self.radius)
        self._patches = list(in_threads(
            lambda a: ThinPlateSpline(centres[members[a]], residual[members[a]], affine=False),
            range(len(patch_centres))))

    def __call__(self, points: np.ndarray, progress: Callable[[float], None] | None = None) -> np.ndarray:
        out = self.coarse(points, None if progress is None else lambda fraction: progress(0.7 * fraction))
        inside = cKDTree(points).query_ball_point(self._patch_centres, self.radius)

        def patch_part(a: int):
            vertices = np.asarray(inside[a], dtype=np.int64)
            weight = _wendland(np.linalg.norm(points[vertices] - self._patch_centres[a], axis=1) / self.radius)
            return vertices, weight, weight[:, None] * self._patches[a](points[vertices], parallel=False)

        total, weights = np.zeros_like(out), np.zeros(len(points))
        for a, (vertices, weight, part) in enumerate(in_threads(patch_part, range(len(self._patches))), start=1):
            total[vertices] += part
            weights[vertices] += weight
            if progress is not None and a % max(1, len(self._patches) // 10) == 0:
                progress(0.7 + 0.3 * a / len(self._patches))
        out += total / np.maximum(weights, self._floor)[:, None]
        if progress is not None:
            progress(1.0)
        return out


class PlanarThinPlateSpline:
    """For a flat (2D) input, the thin-plate spline of the plane (kernel r^2 log r, an affine part): the 3D
    spline's affine part is undefined on centres in one plane. ``values`` (k, 3) are displacements in
    the plane of ``centres`` (k, 3), whose unit normal is ``flat`` (3,); scipy's RBFInterpolator fits and
    evaluates it in the plane's coordinates."""

    def __init__(self, centres: np.ndarray, values: np.ndarray, flat: np.ndarray):
        from scipy.interpolate import RBFInterpolator

        self._origin = centres.mean(axis=0)
        self._basis = np.linalg.svd(np.eye(3) - np.outer(flat, flat))[0][:, :2]  # (3, 2): the plane's axes
        self._spline = RBFInterpolator((centres - self._origin) @ self._basis, values @ self._basis,
                                       kernel="thin_plate_spline", degree=1)
        self.description = f"thin-plate spline of the plane through the {len(centres)} landmarks"

    def __call__(self, points: np.ndarray, progress: Callable[[float], None] | None = None) -> np.ndarray:
        out = self._spline((points - self._origin) @ self._basis) @ self._basis.T
        if progress is not None:
            progress(1.0)
        return out

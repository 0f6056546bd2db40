"""Step 2: blend the local symmetries into one global symmetry (paper Sec. 3.1).

Minimise over the output pairs (r_i, s_i), with s = diag(-1, 1, 1) r:

  sum_ij phi_ij ( |r_i - r_j - a_ij|^2 + |s_i - s_j - b_ij|^2
                  + alpha |r_i - s_j - c_ij|^2 + alpha |s_i - r_j - e_ij|^2 )

  a_ij = Q_i M_p,i (p_i - p_j)   b_ij = Q_i M_q,i (q_i - q_j)
  c_ij = Q_i K_i (p_i - q_j)     e_ij = Q_i K_i (q_i - p_j)

Q_i is the smallest rotation taking n_i to -x. K_i (the gap transform) is the
local stretch in the affine mode, so a globally affine input is reproduced
exactly; the paper omits it, which leaves a 1e-2 residual there. With
Phi = [phi_ij] (diagonal included), D = diag(Phi 1), L = D - Phi the normal
equations decouple (derivation in the README's references):

  x:    4 [L + alpha (D + Phi)] x = rowS(a - b)_x - colS(a - b)_x + alpha [rowS(c - e)_x + colS(c - e)_x]
  y, z: 4 (1 + alpha) L y = rowS(G)_y - colS(G)_y,   G = a + b + alpha (c + e)

with rowS(X)_k = sum_j phi_kj X_kj and colS(X)_k = sum_i phi_ik X_ik. With
per-landmark weights (the paper's missing regions, Sec. 4.2) each term gets
its own weight matrix: Phi_p = Wp Phi Wp for a, Phi_q = Wq Phi Wq for b,
C = Wp Phi Wq for c and C^T for e, and with S = C + C^T the systems become

  x:    [2 L(Phi_p) + 2 L(Phi_q) + 2 alpha (diag(S 1) + S)] x = rowS_p(a) - colS_p(a) - rowS_q(b) + colS_q(b)
                                                          + alpha [rowS_C(c) + colS_C(c) - rowS_C^T(e) - colS_C^T(e)]
  y, z: [2 L(Phi_p) + 2 L(Phi_q) + 2 alpha L(S)] y = the same sums with the signs of a, b, c, e all +, rows - cols

which are the ones above when all weights are 1. Row and column sums of the
per-edge targets reduce to sparse products of the weight matrices with
per-pair vectors and 3x3 matrices, so nothing of size (number of edges, 3) is
formed. The x matrix is positive definite for alpha > 0; midline landmarks
(on_plane) have x = 0 fixed and their rows removed. The y, z matrix is a graph
Laplacian whose null space (translation) is pinned by a penalty on pair 0 (exact,
see the code) and then moved to zero mean. The solver is chosen by size (see
``_solve_positive_definite``); it starts from the input, which the solution
differs from by the symmetrizing deformation only.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import cho_factor, cho_solve
import scipy.sparse as sp

from ..errors import GeometryError
from .geometry import minimal_rotation, voxel_grid
from .local_symmetries import LocalSymmetries
from .neighbourhoods import scaled_weights
from .parallel import row_blocks, side_by_side

MINUS_X = np.array([-1.0, 0.0, 0.0])


def _apply(matrices: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    return np.einsum("nij,nj->ni", matrices, vectors)


# Below this size, or above this density, a dense Cholesky factorization is
# fastest. Measured: 1,000 pairs (18% dense) 0.06 s dense vs 0.10 s CG;
# 3,000 pairs (7% dense) 0.95 s dense vs 0.52 s CG.
DENSE_SIZE = 1500
DENSE_FRACTION = 0.2
COARSE_SIZE = 1000  # at most this many aggregates in the coarse level of the preconditioner
# Relative residual at which the iterative path stops. At 1e-10 instead of 1e-13 the output moved 1.3e-11 (10^5 pairs)
# and 2.7e-11 (10^4 pairs) of the diagonal, far inside the warp's own 1e-6, with a quarter fewer iterations
# (91 -> 70, 31 -> 24; docs/benchmarks.md, "Dense pairs").
CG_TOLERANCE = 1e-10
CG_MAX_ITERATIONS = 20000


def aggregates(positions: np.ndarray) -> np.ndarray:
    """Labels (n,) grouping ``positions`` (n, 3) into about n/10 (at most COARSE_SIZE) voxel cells."""
    target = max(1, min(len(positions) // 10, COARSE_SIZE))
    return np.unique(voxel_grid(positions, target), return_inverse=True)[1].ravel()


def _two_level_preconditioner(matrix: sp.csr_matrix, labels: np.ndarray):
    """M^-1 r = D^-1 r + P (P^T A P)^-1 P^T r: Jacobi plus an exact solve on aggregates.

    Jacobi alone needs iterations in proportion to the pair graph's diameter
    (measured on the y/z Laplacian: 246 at 10^4 pairs, 570 at 3 x 10^4); the
    coarse correction removes the smooth error Jacobi is slow on (53 and 113).
    """
    labels = np.unique(labels, return_inverse=True)[1].ravel()
    prolongation = sp.csr_matrix((np.ones(len(labels)), (np.arange(len(labels)), labels)))
    # A P first (CSR times CSR, n x k): P^T A would convert A to CSC (1.4 s at 10^5 pairs, phi width 8).
    coarse = cho_factor((prolongation.T @ (matrix @ prolongation)).toarray(), lower=True, check_finite=False)
    inverse_diagonal = 1.0 / matrix.diagonal()[:, None]

    def apply(residual):
        return inverse_diagonal * residual + prolongation @ cho_solve(coarse, prolongation.T @ residual,
                                                                      check_finite=False)
    return apply


def _solve_positive_definite(matrix: sp.csr_matrix, rhs: np.ndarray, guess: np.ndarray,
                             labels: np.ndarray) -> np.ndarray:
    """Solve a symmetric positive definite system for rhs (n, k), starting from guess (n, k).

    Small or dense systems: dense Cholesky (LAPACK). Large sparse ones: conjugate
    gradients with the two-level preconditioner over the aggregates ``labels``
    (n,), written here because it runs all k right-hand sides in one sparse
    product per iteration (scipy's cg takes one), splits that product over the
    cores, and starts from the input geometry. SuperLU was 5x slower at 10^4
    pairs (fill-in); pyamg no faster below 10^5 pairs.
    """
    n = matrix.shape[0]
    if n <= DENSE_SIZE or matrix.nnz > DENSE_FRACTION * n * n:
        return cho_solve(cho_factor(matrix.toarray(), lower=True, check_finite=False), rhs,
                         check_finite=False)
    precondition = _two_level_preconditioner(matrix, labels)
    multiply = row_blocks(matrix)
    x = guess.copy()
    residual = rhs - multiply(x)
    scale = np.linalg.norm(rhs, axis=0) + 1e-300
    z = precondition(residual)
    direction = z.copy()
    rho = np.einsum("ij,ij->j", residual, z)
    for _ in range(CG_MAX_ITERATIONS):
        if np.all(np.linalg.norm(residual, axis=0) <= CG_TOLERANCE * scale):
            return x
        product = multiply(direction)
        step = rho / np.einsum("ij,ij->j", direction, product)
        x += step * direction
        residual -= step * product
        z = precondition(residual)
        rho, previous = np.einsum("ij,ij->j", residual, z), rho
        direction = z + (rho / previous) * direction
    raise GeometryError(
        f"The global solve did not converge in {CG_MAX_ITERATIONS} iterations; lower "
        "`phi_width` or check the landmarks for near-duplicate pairs."
    )


def _edge_sums(weights: sp.csr_matrix, transposed: sp.csr_matrix, a_matrices, origins, ends):
    """Row and column sums over the edges of ``weights`` (n, n), possibly non-symmetric (``transposed``: its
    transpose, CSR), of the targets t_ij = A_i (origin_i - end_j): rowS_k = sum_j w_kj t_kj,
    colS_k = sum_i w_ik t_ik. The products are split over the cores (:func:`.parallel.row_blocks`): at 10^5
    pairs the four calls took 2.5 s on one."""
    n = len(origins)
    row_degree = np.asarray(weights.sum(axis=1)).ravel()
    row = _apply(a_matrices, row_degree[:, None] * origins - row_blocks(weights)(ends))
    stacked = row_blocks(transposed)(np.hstack([_apply(a_matrices, origins), a_matrices.reshape(n, 9)]))
    col = stacked[:, :3] - _apply(stacked[:, 3:].reshape(n, 3, 3), ends)
    return row, col


def _combination(terms: list[tuple[float, sp.csr_matrix]], diagonal: np.ndarray) -> sp.csr_matrix:
    """sum of c * M over ``terms`` plus diag(``diagonal``), adding the coefficients of a matrix
    that appears more than once first: without missing landmarks every term is phi, and the
    result is one scaled copy of it (at 10^5 pairs each extra copy is 350 MB and 0.3 s). phi's
    pattern always holds the diagonal, so it is set in place."""
    merged: dict[int, list] = {}
    for coefficient, matrix in terms:
        merged.setdefault(id(matrix), [0.0, matrix])[0] += coefficient
    out = None
    for coefficient, matrix in merged.values():
        matrix = sp.csr_matrix(matrix)
        # A scaled copy shares the matrix's index arrays (only setdiag below writes, and only to the values): at
        # 10^5 pairs 0.65 GB and about 0.6 s each not copied.
        scaled = sp.csr_matrix((coefficient * matrix.data, matrix.indices, matrix.indptr), shape=matrix.shape)
        out = scaled if out is None else out + scaled
    out.setdiag(out.diagonal() + diagonal)
    return out


def _row_sums(matrix: sp.csr_matrix) -> np.ndarray:
    return np.asarray(matrix.sum(axis=1)).ravel()


def global_solve(
    phi: sp.csr_matrix,
    left: np.ndarray,
    right: np.ndarray,
    local: LocalSymmetries,
    alpha: float,
    *,
    weights: tuple[np.ndarray, np.ndarray] | None = None,
    on_plane: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Symmetric output pairs (r, s), each (n, 3), with s = r mirrored across x = 0.

    phi (n, n): symmetric pair weights, diagonal included. left, right (n, 3):
    input pairs in a frame where the mean local normal is about -x. local:
    Step 1 output in the same frame. alpha > 0. weights: (left (n,), right (n,))
    in [0, 1], how much each landmark's input geometry counts (0: missing or
    broken, that side becomes the mirror image of the other; default all 1).
    on_plane (n,) bool: midline landmarks (left = right), held on x = 0.
    """
    n = len(left)
    phi = sp.csr_matrix(phi)
    wl, wr = (np.ones(n), np.ones(n)) if weights is None else weights
    if np.all(wl == 1) and np.all(wr == 1):
        phi_left = phi_right = phi_gap = phi_gap_t = phi
    else:
        phi_left, phi_right = scaled_weights(phi, wl, wl), scaled_weights(phi, wr, wr)
        phi_gap = scaled_weights(phi, wl, wr)  # the r_i - s_j terms; s_i - r_j use its transpose
        phi_gap_t = sp.csr_matrix(phi_gap.T)
    rotations = minimal_rotation(local.normals, MINUS_X)
    a_left = rotations @ local.left_transforms
    a_right = rotations @ local.right_transforms
    a_gap = rotations @ local.gap_transforms

    row_a, col_a = _edge_sums(phi_left, phi_left, a_left, left, left)  # phi_left and phi_right are symmetric
    row_b, col_b = _edge_sums(phi_right, phi_right, a_right, right, right)
    row_c, col_c = _edge_sums(phi_gap, phi_gap_t, a_gap, left, right)
    row_e, col_e = _edge_sums(phi_gap_t, phi_gap, a_gap, right, left)

    rhs_x = (row_a - col_a - row_b + col_b + alpha * (row_c + col_c - row_e - col_e))[:, 0]
    rhs_yz = (row_a - col_a + row_b - col_b + alpha * (row_c - col_c + row_e - col_e))[:, 1:]

    # side = 2 L(Phi_p) + 2 L(Phi_q), S = C + C^T; x: side + 2 alpha (diag(S 1) + S); y, z: side + 2 alpha L(S)
    degrees = 2.0 * (_row_sums(phi_left) + _row_sums(phi_right))
    gap_degrees = 2.0 * alpha * (_row_sums(phi_gap) + _row_sums(phi_gap_t))
    sides = [(-2.0, phi_left), (-2.0, phi_right)]
    x_matrix = _combination([*sides, (2.0 * alpha, phi_gap), (2.0 * alpha, phi_gap_t)], degrees + gap_degrees)
    free = np.ones(n, dtype=bool) if on_plane is None else ~on_plane
    labels = aggregates(0.5 * (left + right)) if n > DENSE_SIZE else np.zeros(n, dtype=np.int64)
    if not free.all():
        x_matrix = x_matrix[free][:, free]
    # The y/z rows sum to zero, and so does rhs_yz: adding any lam > 0 at (0, 0) leaves the solution
    # with y_0 = 0 a solution, and makes the matrix positive definite (no row and column to cut).
    pin = np.zeros(n)
    pin[0] = degrees[0]
    yz_matrix = _combination([*sides, (-2.0 * alpha, phi_gap), (-2.0 * alpha, phi_gap_t)],
                             degrees + gap_degrees + pin)
    guess = 0.5 * (left + right)[:, 1:] - 0.5 * (left + right)[0, 1:]
    solve_x = lambda: _solve_positive_definite(x_matrix, rhs_x[free, None], left[free, :1], labels[free])  # noqa: E731
    solve_yz = lambda: _solve_positive_definite(yz_matrix, rhs_yz, guess, labels)  # noqa: E731
    # Large systems: the two share nothing, so they run side by side (10^5 pairs: 23 s -> 15 s).
    x_free, yz = (solve_x(), solve_yz()) if n <= DENSE_SIZE else side_by_side(solve_x, solve_yz)
    x = np.zeros(n)
    x[free] = x_free[:, 0]
    yz -= yz.mean(axis=0)

    r = np.column_stack([x, yz])
    return r, r * np.array([-1.0, 1.0, 1.0])

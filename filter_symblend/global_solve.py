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

with rowS(X)_k = sum_j phi_kj X_kj and colS(X)_k = sum_i phi_ik X_ik. Both row
and column sums of the per-edge targets reduce to sparse products of Phi with
per-pair vectors and 3x3 matrices, so nothing of size (number of edges, 3) is
formed. The x matrix is positive definite for alpha > 0; the y, z matrix is a
graph Laplacian whose null space (translation) is pinned by fixing pair 0 and
then moving the solution to zero mean. The solver is chosen by size (see
``_solve_positive_definite``); it starts from the input, which the solution
differs from by the symmetrizing deformation only.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.linalg import cho_factor, cho_solve

from .geometry import minimal_rotation
from .local_symmetries import LocalSymmetries

MINUS_X = np.array([-1.0, 0.0, 0.0])


def _apply(matrices: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    return np.einsum("nij,nj->ni", matrices, vectors)


# Below this size, or above this density, a dense Cholesky factorization is
# fastest (at the paper's widths a few thousand pairs are nearly all connected).
DENSE_SIZE = 3000
DENSE_FRACTION = 0.2
CG_TOLERANCE = 1e-13  # relative residual of the iterative path
CG_MAX_ITERATIONS = 20000


def _solve_positive_definite(matrix: sp.csr_matrix, rhs: np.ndarray, guess: np.ndarray) -> np.ndarray:
    """Solve a symmetric positive definite system for rhs (n, k), starting from guess (n, k).

    Small or dense systems: dense Cholesky (LAPACK). Large sparse ones: Jacobi-
    preconditioned conjugate gradients, written here because it runs all k
    right-hand sides in one sparse product per iteration (scipy's cg takes one)
    and starts from the input geometry. Measured on 10^4 pairs it is 5x faster
    than SuperLU, whose fill-in grows with the pair count; pyamg's smoothed
    aggregation needed fewer iterations but was no faster below 10^5 pairs.
    """
    n = matrix.shape[0]
    if n <= DENSE_SIZE or matrix.nnz > DENSE_FRACTION * n * n:
        return cho_solve(cho_factor(matrix.toarray(), lower=True, check_finite=False), rhs,
                         check_finite=False)
    inverse_diagonal = 1.0 / matrix.diagonal()[:, None]
    x = guess.copy()
    residual = rhs - matrix @ x
    scale = np.linalg.norm(rhs, axis=0) + 1e-300
    z = inverse_diagonal * residual
    direction = z.copy()
    rho = np.einsum("ij,ij->j", residual, z)
    for _ in range(CG_MAX_ITERATIONS):
        if np.all(np.linalg.norm(residual, axis=0) <= CG_TOLERANCE * scale):
            return x
        product = matrix @ direction
        step = rho / np.einsum("ij,ij->j", direction, product)
        x += step * direction
        residual -= step * product
        z = inverse_diagonal * residual
        rho, previous = np.einsum("ij,ij->j", residual, z), rho
        direction = z + (rho / previous) * direction
    raise ArithmeticError(
        f"The global solve did not converge in {CG_MAX_ITERATIONS} iterations; lower "
        "`phi_width` or check the landmarks for near-duplicate pairs."
    )


def global_solve(
    phi: sp.csr_matrix,
    left: np.ndarray,
    right: np.ndarray,
    local: LocalSymmetries,
    alpha: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Symmetric output pairs (r, s), each (n, 3), with s = r mirrored across x = 0.

    phi (n, n): symmetric pair weights, diagonal included. left, right (n, 3):
    input pairs in a frame where the mean local normal is about -x. local:
    Step 1 output in the same frame. alpha > 0.
    """
    n = len(left)
    rotations = minimal_rotation(local.normals, MINUS_X)
    a_left = rotations @ local.left_transforms
    a_right = rotations @ local.right_transforms
    a_gap = rotations @ local.gap_transforms
    degree = np.asarray(phi.sum(axis=1)).ravel()

    blocks = [left, right, _apply(a_left, left), _apply(a_right, right), _apply(a_gap, left),
              _apply(a_gap, right), a_left.reshape(n, 9), a_right.reshape(n, 9),
              a_gap.reshape(n, 9)]
    sums = np.split(phi @ np.hstack(blocks), np.cumsum([b.shape[1] for b in blocks])[:-1], axis=1)
    phi_p, phi_q, phi_ap, phi_bq, phi_cp, phi_cq = sums[:6]
    phi_a, phi_b, phi_c = (m.reshape(n, 3, 3) for m in sums[6:])

    row_a = _apply(a_left, degree[:, None] * left - phi_p)
    col_a = phi_ap - _apply(phi_a, left)
    row_b = _apply(a_right, degree[:, None] * right - phi_q)
    col_b = phi_bq - _apply(phi_b, right)
    row_c = _apply(a_gap, degree[:, None] * left - phi_q)
    col_c = phi_cp - _apply(phi_c, right)
    row_e = _apply(a_gap, degree[:, None] * right - phi_p)
    col_e = phi_cq - _apply(phi_c, left)

    rhs_x = (row_a - row_b - col_a + col_b + alpha * (row_c - row_e + col_c - col_e))[:, 0]
    rhs_yz = (row_a + row_b - col_a - col_b + alpha * (row_c + row_e - col_c - col_e))[:, 1:]

    degree_matrix = sp.diags(degree)
    x_matrix = sp.csr_matrix(4.0 * ((1.0 + alpha) * degree_matrix - (1.0 - alpha) * phi))
    x = _solve_positive_definite(x_matrix, rhs_x[:, None], left[:, :1])[:, 0]
    laplacian = sp.csr_matrix(4.0 * (1.0 + alpha) * (degree_matrix - phi))
    yz = np.zeros((n, 2))
    guess = 0.5 * (left + right)[1:, 1:] - 0.5 * (left + right)[0, 1:]
    yz[1:] = _solve_positive_definite(laplacian[1:, 1:], rhs_yz[1:], guess)
    yz -= yz.mean(axis=0)

    r = np.column_stack([x, yz])
    return r, r * np.array([-1.0, 1.0, 1.0])

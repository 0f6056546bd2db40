"""Gaussian pair weights (the paper's phi and theta) as sparse matrices.

phi_ij = min(exp(-|p_i - p_j|^2 / h^2), exp(-|q_i - q_j|^2 / h^2))   (Eq. 1)

The Gaussian is truncated at ``TRUNCATION`` x h (weight exp(-9) ~ 1.2e-4 there),
so each row holds only the pairs near pair i and every system stays sparse.
Truncation changes the weights, not the exactness properties: a symmetric or
globally affine input is still reproduced exactly for any weights.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, minimum_spanning_tree
from scipy.spatial import cKDTree

from ..errors import DisconnectedPairsError, id_list
from .parallel import blockwise

TRUNCATION = 3.0


def mean_nearest_spacing(landmarks: np.ndarray) -> float:
    """Mean distance from each landmark (m, 3) to its nearest other landmark."""
    distances, _ = cKDTree(landmarks).query(landmarks, k=2)
    return float(distances[:, 1].mean())


def _pair_distances(left: np.ndarray, right: np.ndarray, radius: float):
    """Index pairs i < j (k,), (k,) with max(|p_i-p_j|, |q_i-q_j|) < radius, and that max (k,): the pairs a k-d
    tree finds close on the left, kept where the right side is close too, in blocks of DISTANCE_BLOCK pairs on every
    core (at 10^5 pairs, 5 x 10^7 pairs, the selection took 1.7 s on one). The indices come out as int32 when n
    allows: every later pass (the weight matrices' arrays) moves half the bytes, and scipy takes them without
    converting them (1.7 s at 10^5 pairs)."""
    pairs = cKDTree(left).query_pairs(radius, output_type="ndarray")
    index_type = np.int32 if len(left) < 2**31 else np.int64

    def block(start: int):
        rows, columns = pairs[start:start + DISTANCE_BLOCK, 0], pairs[start:start + DISTANCE_BLOCK, 1]
        distance = _block_distance(left, right, rows, columns)
        keep = distance < radius
        return rows[keep].astype(index_type), columns[keep].astype(index_type), distance[keep]
    parts = list(blockwise(block, range(0, len(pairs), DISTANCE_BLOCK), limit_blas=False))
    if not parts:
        return np.empty(0, dtype=index_type), np.empty(0, dtype=index_type), np.empty(0)
    return tuple(np.concatenate(column) for column in zip(*parts))


DISTANCE_BLOCK = 2**18  # index pairs per block of the pair distances: their temporaries stay in cache (1.4x faster)


def _max_side_distance(left: np.ndarray, right: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """max(|p_i - p_j|, |q_i - q_j|) (k,) for index pairs i, j (k,) (:func:`_block_distance`), in blocks of
    DISTANCE_BLOCK pairs on every core (numpy's gathers and einsum release the GIL)."""
    out = np.empty(len(i))

    def block(start: int) -> None:
        end = start + DISTANCE_BLOCK
        out[start:end] = _block_distance(left, right, i[start:end], j[start:end])
    for _ in blockwise(block, range(0, len(i), DISTANCE_BLOCK), limit_blas=False):
        pass
    return out


def _block_distance(left: np.ndarray, right: np.ndarray, rows: np.ndarray, columns: np.ndarray) -> np.ndarray:
    """max(|p_i - p_j|, |q_i - q_j|) for the index pairs ``rows``, ``columns``, by einsum on squared lengths (4x
    faster than np.linalg.norm at 10^7 pairs)."""
    largest = None
    for side in (left, right):
        difference = side[rows] - side[columns]
        squared = np.einsum("ij,ij->i", difference, difference)
        largest = squared if largest is None else np.maximum(largest, squared, out=largest)
    return np.sqrt(largest, out=largest)


def pair_weights(left: np.ndarray, right: np.ndarray, width: float) -> sp.csr_matrix:
    """Symmetric sparse weights (n, n), diagonal 1, for pairs (left[i], right[i]) at width h."""
    return pair_weights_at(left, right, [width])[0]


def pair_weights_at(left: np.ndarray, right: np.ndarray, widths: list[float]) -> list[sp.csr_matrix]:
    """:func:`pair_weights` at each of ``widths``, from one neighbour search at the largest (phi and theta
    share it: the narrower one's pairs are a subset; 10^4 pairs, widths 8 and 5: 1.25 -> 1.0 s)."""
    n = len(left)
    i, j, distance = _pair_distances(left, right, TRUNCATION * max(widths))
    matrices = {}
    for width in widths:
        if width not in matrices:  # the same width twice: one matrix
            if width == max(widths):  # every pair found (at 10^5 pairs, 5 x 10^7 of them: no copies)
                rows, columns, weight = i, j, distance / width
            else:
                keep = distance < TRUNCATION * width
                rows, columns, weight = i[keep], j[keep], distance[keep] / width
            weight *= weight  # exp(-(d / h)^2), in place
            np.exp(np.negative(weight, out=weight), out=weight)
            matrices[width] = _symmetric(n, rows, columns, weight)
    return [matrices[width] for width in widths]


def _symmetric(n: int, i: np.ndarray, j: np.ndarray, weight: np.ndarray) -> sp.csr_matrix:
    """The symmetric (n, n) CSR matrix with ``weight`` at (i, j) and (j, i) for i < j and 1 on the diagonal, its
    rows' columns in the order they come. No entry repeats (the pairs i < j are distinct), so scipy's conversion
    is told so (``has_canonical_format``) and skips summing duplicates, which sorts every row: its counting sort
    of the rows alone, in a probe with 10^4 pairs of 800 neighbours 3x faster than the full conversion (0.24 ->
    0.08 s a matrix) and 10x faster than numpy's radix sort of the rows; at 10^5 pairs the two matrices 12 -> 6 s."""
    diagonal = np.arange(n, dtype=i.dtype)
    entries = sp.coo_matrix((np.concatenate([weight, weight, np.ones(n)]),
                             (np.concatenate([i, j, diagonal]), np.concatenate([j, i, diagonal]))), shape=(n, n))
    entries.has_canonical_format = True
    return entries.tocsr()


def scaled_weights(weights: sp.csr_matrix, row: np.ndarray, column: np.ndarray) -> sp.csr_matrix:
    """diag(row) @ weights @ diag(column), by scaling the stored values (building
    scipy.sparse.diags for this was a measured hotspot)."""
    out = sp.csr_matrix(weights, copy=True)
    out.data *= np.repeat(row, np.diff(out.indptr)) * column[out.indices]
    return out


def require_connected(
    weights: sp.csr_matrix,
    left: np.ndarray,
    right: np.ndarray,
    pair_ids: np.ndarray,
    spacing: float,
    parameter: str,
    multiple: float,
) -> None:
    """Raise DisconnectedPairsError naming the isolated pairs and the width that would connect them.

    ``multiple`` is the width as given (a multiple of ``spacing``), for the message.
    """
    count, labels = connected_components(weights, directed=False)
    if count == 1:
        return
    main = np.argmax(np.bincount(labels))
    isolated = pair_ids[labels != main]
    needed = connecting_width(left, right) / spacing
    raise DisconnectedPairsError(
        f"The landmark pairs fall apart into {count} groups at `{parameter}` = "
        f"{multiple:g}: pairs {id_list(isolated)} are not connected to the other "
        f"{int(np.sum(labels == main))}. Set `{parameter}` to {needed:.3g} or more, "
        f"or place pairs between the groups. A pair whose two landmarks are not near its "
        f"neighbours' landmarks on both sides (e.g. joined to the wrong vertex) is isolated "
        f"too: check it.", needed)


def connecting_width(left: np.ndarray, right: np.ndarray) -> float:
    """A Gaussian width h whose truncated graph connects every pair (1% above the smallest).

    The longest edge of the minimum spanning tree under the pair distance
    max(|p_i-p_j|, |q_i-q_j|), found on a k-nearest-neighbour graph of the
    stacked (p, q) coordinates, grown until it is connected: exact when that
    graph holds the shortest bridge between the groups, an upper bound otherwise.
    """
    n = len(left)
    stacked = np.hstack([left, right])
    k = min(n - 1, 16)
    while True:
        _, nearest = cKDTree(stacked).query(stacked, k=k + 1)
        i = np.repeat(np.arange(n), k)
        j = nearest[:, 1:].ravel()
        graph = sp.csr_matrix((_max_side_distance(left, right, i, j) + 1e-300, (i, j)), shape=(n, n))
        if connected_components(graph, directed=False)[0] == 1 or k == n - 1:
            break
        k = min(n - 1, 4 * k)
    return float(minimum_spanning_tree(graph).data.max()) / TRUNCATION * 1.01

"""Twins of a patch of vertices at once, by a minimum-cost assignment.

Where the mirror map bends sharply (the joint of a swung limb), the twins of
the vertices there are predicted too far off to accept one by one (by the local
mirror maps of the pairs around: 0.1-0.7 edge lengths, against the 0.1 of a
mirrored tessellation; by the connectivity, see ``mesh_twins``: 0.26 at the
median, 0.56 for 90 %). Their errors are alike from one vertex to the next,
though, and the sum of squared distances between predictions and twins does
not change when every prediction moves by the same amount. So the twins are
chosen together: the pairing of the patch with itself that puts the twins
closest to the predictions, both ways (scipy's ``linear_sum_assignment``, with
"stay unpaired" open to every vertex at a fixed cost).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sparse
from scipy.optimize import linear_sum_assignment
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

# Largest block of points that can pair with one another solved at once (its dense cost matrix:
# 8 bytes x this squared); larger blocks stay unpaired. scipy's sparse solver
# (min_weight_full_bipartite_matching) looped forever on a 361-point block of the cow with a limb
# swung 0.3 rad (float costs; cf. scipy issue 17269), hence the dense one on each block.
BLOCK_LIMIT = 4000


def assigned_twins(points: np.ndarray, predicted: np.ndarray, allowed, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (a (k,), b (k,)) of the rows of ``points`` (n, 3), a < b, chosen together.

    ``predicted`` (n, 3): where each point's twin is predicted. A point and a candidate
    twin must lie within ``radius`` of each other's prediction and pass ``allowed(rows
    (m,), columns (m,)) -> (m,) bool`` (e.g. facing the mirrored way); the cost of a pair is
    the sum of both squared prediction errors, that of staying unpaired 2 radius^2.
    Blocks of points linked by candidate pairs are solved one by one, up to BLOCK_LIMIT points.
    """
    n = len(points)
    candidates = cKDTree(points).query_ball_point(predicted, radius)
    rows = np.repeat(np.arange(n), [len(c) for c in candidates])
    columns = np.concatenate([np.asarray(c, dtype=np.int64) for c in candidates]) if n else rows
    keep = rows != columns
    rows, columns = rows[keep], columns[keep]
    keep = allowed(rows, columns)
    rows, columns = rows[keep], columns[keep]
    both_ways = np.isin(rows * n + columns, columns * n + rows)
    rows, columns = rows[both_ways], columns[both_ways]
    cost = (np.sum((predicted[rows] - points[columns]) ** 2, axis=1)
            + np.sum((predicted[columns] - points[rows]) ** 2, axis=1))
    links = sparse.csr_matrix((np.ones(len(rows)), (rows, columns)), shape=(n, n))
    blocks, block = connected_components(links, directed=False)
    # Points and candidate pairs grouped by block, so that each block costs its own size only.
    members_of = np.split(np.argsort(block, kind="stable"), np.cumsum(np.bincount(block, minlength=blocks))[:-1])
    by_block = np.argsort(block[rows], kind="stable")
    pairs_of = np.split(by_block, np.cumsum(np.bincount(block[rows], minlength=blocks))[:-1])
    match = np.arange(n)
    for members, pairs in zip(members_of, pairs_of):
        if len(members) < 2 or len(members) > BLOCK_LIMIT:
            continue
        matrix = np.full((len(members), len(members)), 4.0 * radius**2)  # no candidate: dearer than unpaired
        np.fill_diagonal(matrix, 2.0 * radius**2)
        # members is sorted (a stable sort of the block labels), so searchsorted gives local indices.
        matrix[np.searchsorted(members, rows[pairs]), np.searchsorted(members, columns[pairs])] = cost[pairs]
        match[members] = members[linear_sum_assignment(matrix)[1]]
    a = np.flatnonzero((match[match] == np.arange(n)) & (match > np.arange(n)))  # the 2-cycles, once each
    return a, match[a]

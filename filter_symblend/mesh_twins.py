"""Mirror twins read off a mesh's connectivity, where it is itself mirror-symmetric.

A mirrored model, or a symmetric template warped onto a specimen, has triangles
that mirror each other: the mirror map is then a map of the mesh onto itself
that sends neighbours to neighbours, whatever the bend or articulation did to
the geometry. So once the neighbours of a vertex are paired, its twin is the
vertex next to all of their twins, and a pair whose neighbours all pair with the
twin's neighbours is right however far the local geometry is from a mirror image
(a bent joint). A scan whose two sides are tessellated differently has no such
vertex: nothing here applies to it.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sparse

# Share of the closed rings (paired vertices with every neighbour paired) that must map onto their
# twins' rings. With the true twins: spot 94 % (its midline strip is tessellated one way only),
# pymeshlab's cow 19 % (its quads are split along mirrored diagonals on only part of it).
MIRRORED_RINGS = 0.8
# An unpaired vertex gets a twin from at least this many paired neighbours: with one, every unpaired
# neighbour of that neighbour's twin would fit.
LEAST_PAIRED_NEIGHBOURS = 2


def vertex_adjacency(faces: np.ndarray, count: int) -> sparse.csr_matrix:
    """Symmetric (count, count) 0/1 matrix of the mesh edges of ``faces`` (F, 3)."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    edges = np.concatenate([edges, edges[:, ::-1]])
    adjacency = sparse.csr_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(count, count))
    adjacency.data[:] = 1.0  # an edge shared by two triangles was summed twice
    return adjacency


def _edges(adjacency: sparse.csr_matrix) -> tuple[np.ndarray, np.ndarray]:
    rows = np.repeat(np.arange(adjacency.shape[0]), np.diff(adjacency.indptr))
    return rows, adjacency.indices


def _adjacent(adjacency: sparse.csr_matrix, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(k,) bool: whether vertices a[i] and b[i] share an edge."""
    return np.asarray(adjacency[a, b]).ravel() > 0


def ring_consistent(adjacency: sparse.csr_matrix, partner: np.ndarray) -> np.ndarray:
    """(N,) bool: paired vertices whose every neighbour is paired with a neighbour of their twin,
    and whose twin has as many neighbours (``partner`` (N,): twin index, itself on the
    midline, -1 unpaired)."""
    source, neighbour = _edges(adjacency)
    degree = np.diff(adjacency.indptr)
    paired = partner >= 0
    edge_ok = paired[source] & paired[neighbour]
    check = np.flatnonzero(edge_ok)
    edge_ok[check] = _adjacent(adjacency, partner[source[check]], partner[neighbour[check]])
    bad = np.bincount(source[~edge_ok], minlength=len(partner)) > 0
    return paired & ~bad & (degree == degree[np.maximum(partner, 0)])


def mirrored_tessellation(adjacency: sparse.csr_matrix, partner: np.ndarray) -> bool:
    """Whether the pairs ``partner`` (N,) say the tessellation mirrors itself: at least
    MIRRORED_RINGS of the paired vertices whose neighbours are all paired are ``ring_consistent``."""
    source, neighbour = _edges(adjacency)
    open_ring = np.bincount(source[partner[neighbour] < 0], minlength=len(partner)) > 0
    closed = (partner >= 0) & ~open_ring
    return bool(closed.any()) and float(np.mean(ring_consistent(adjacency, partner)[closed])) >= MIRRORED_RINGS


def connectivity_twins(adjacency: sparse.csr_matrix, partner: np.ndarray):
    """Twins the connectivity implies for unpaired vertices: (sources (k,), twins (k,)).

    A source is an unpaired vertex with LEAST_PAIRED_NEIGHBOURS paired neighbours or more, and
    its twin the one unpaired vertex adjacent to all of their twins (the source itself if they
    are its own neighbours: a midline vertex); kept only where the twin's own candidate is the
    source.
    """
    n = len(partner)
    source, neighbour = _edges(adjacency)
    useful = (partner[source] < 0) & (partner[neighbour] >= 0)
    source, twin_of_neighbour = source[useful], partner[neighbour[useful]]
    known = sparse.csr_matrix((np.ones(len(source)), (source, twin_of_neighbour)), shape=(n, n))
    counts = np.asarray(known.sum(axis=1)).ravel()
    # reach[u, v]: how many twins of u's paired neighbours are adjacent to v.
    reach = (known @ adjacency).tocoo()
    fits = (reach.data == counts[reach.row]) & (counts[reach.row] >= LEAST_PAIRED_NEIGHBOURS) & (partner[reach.col] < 0)
    rows, columns = reach.row[fits], reach.col[fits]
    unique = np.bincount(rows, minlength=n) == 1
    keep = unique[rows]
    rows, columns = rows[keep], columns[keep]
    candidate = np.full(n, -1)
    candidate[rows] = columns
    mutual = candidate[columns] == rows
    return rows[mutual], columns[mutual]

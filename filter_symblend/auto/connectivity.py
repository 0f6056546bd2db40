"""The mirror map of a tessellation that mirrors itself, read off its connectivity.

A mirrored model, or a symmetric template warped onto a specimen, has triangles that
mirror each other: the mirror map is then an automorphism of the mesh graph, sending
neighbours to neighbours, whatever a bend or an articulation did to the geometry. Once
the neighbours of a vertex are paired, its twin is the one vertex next to all of their
twins; grown outward from one right pair and its ring this way, the map covers the
whole mesh (Blender's "topology mirror" rests on the same property). Grown from a wrong
pair, slid by a row along a regular patch (where a geometric map can slide coherently),
it stops at the first vertex of another valence. So one right pair among many wrong
ones is enough. A scan, whose two sides are tessellated independently, has no such map.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sparse

from ..core.mesh_graph import one_pair_per_vertex

# A growth of the tessellation's mirror must pair this share of the vertices: all but a strip along the
# midline, where a symmetric model may be triangulated one way only.
MIRROR_COVERAGE = 0.95
# Growths tried at most per group of pieces, each from a pair the ones before do not explain: one right
# seed among many wrong ones is enough.
SEED_GROWTHS = 12
# A vertex's twin is read off the connectivity once this many of its neighbours are paired: with one,
# every unpaired neighbour of that neighbour's twin would fit.
LEAST_PAIRED_NEIGHBOURS = 2


def _neighbours(adjacency: sparse.csr_matrix, vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The edges leaving ``vertices`` (k,): (position in ``vertices``, neighbour), with numpy alone."""
    starts = adjacency.indptr[vertices]
    lengths = adjacency.indptr[vertices + 1] - starts
    position = np.repeat(np.arange(len(vertices)), lengths)
    offsets = np.arange(len(position)) - np.repeat(np.cumsum(lengths) - lengths, lengths)
    return position, adjacency.indices[np.repeat(starts, lengths) + offsets]


def _adjacent(adjacency: sparse.csr_matrix, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(k,) bool: whether vertices a[i] and b[i] share an edge (sorted edge keys, one search)."""
    n = adjacency.shape[0]
    adjacency.sort_indices()
    keys = np.repeat(np.arange(n, dtype=np.int64), np.diff(adjacency.indptr)) * n + adjacency.indices
    wanted = a.astype(np.int64) * n + b
    position = np.minimum(np.searchsorted(keys, wanted), max(len(keys) - 1, 0))
    return (keys[position] == wanted) if len(keys) else np.zeros(len(wanted), dtype=bool)


def ring_consistent(adjacency: sparse.csr_matrix, partner: np.ndarray) -> np.ndarray:
    """(N,) bool: paired vertices whose every neighbour is paired with a neighbour of their twin, and whose
    twin has as many neighbours (``partner`` (N,): twin index, itself on the midline, -1 unpaired)."""
    source, neighbour = _neighbours(adjacency, np.arange(len(partner)))
    degree = np.diff(adjacency.indptr)
    paired = partner >= 0
    edge_ok = paired[source] & paired[neighbour]
    check = np.flatnonzero(edge_ok)
    edge_ok[check] = _adjacent(adjacency, partner[source[check]], partner[neighbour[check]])
    bad = np.bincount(source[~edge_ok], minlength=len(partner)) > 0
    return paired & ~bad & (degree == degree[np.maximum(partner, 0)])


def connectivity_twins(adjacency: sparse.csr_matrix, partner: np.ndarray, candidates: np.ndarray, least: int):
    """Twins the connectivity implies for the unpaired ``candidates`` (m,): (sources (k,), twins (k,)).

    A source has ``least`` paired neighbours or more; its twin is the one unpaired candidate
    adjacent to all of their twins (the source itself on the midline), kept only where that twin's own
    twin is the source.
    """
    candidates = np.unique(candidates[partner[candidates] < 0])
    m, n = len(candidates), len(partner)
    source, neighbour = _neighbours(adjacency, candidates)
    useful = partner[neighbour] >= 0
    source, twin_of_neighbour = source[useful], partner[neighbour[useful]]
    counts = np.bincount(source, minlength=m)
    entry, near_twin = _neighbours(adjacency, twin_of_neighbour)
    reach, hits = np.unique(source[entry] * n + near_twin, return_counts=True)
    sources, twins = reach // n, reach % n
    fits = (hits == counts[sources]) & (counts[sources] >= least)
    sources, twins = sources[fits], twins[fits]
    position = np.searchsorted(candidates, twins)
    inside = position < m
    inside[inside] = candidates[position[inside]] == twins[inside]
    sources, position = sources[inside], position[inside]
    unique = np.bincount(sources, minlength=m) == 1
    sources, position = sources[unique[sources]], position[unique[sources]]
    candidate = np.full(m, -1)
    candidate[sources] = position
    mutual = candidate[position] == sources
    return candidates[sources[mutual]], candidates[position[mutual]]


def grow_by_connectivity(adjacency: sparse.csr_matrix, partner: np.ndarray, least: int) -> np.ndarray:
    """``partner`` (N,) extended by :func:`connectivity_twins` wave after wave until it stalls (a new array)."""
    partner = partner.copy()
    added = np.flatnonzero(partner >= 0)
    while len(added):
        sources, twins = connectivity_twins(adjacency, partner, np.unique(_neighbours(adjacency, added)[1]), least)
        sources, twins = one_pair_per_vertex(sources, twins)
        partner[sources], partner[twins] = twins, sources
        added = np.concatenate([sources, twins])
    return partner


def tessellation_mirror(adjacency: sparse.csr_matrix, partner: np.ndarray, usable: np.ndarray) -> np.ndarray | None:
    """The mirror automorphism of a tessellation that mirrors itself, grown from single ring-consistent
    pairs of ``partner`` (N,) with their rings, or None.

    A growth stays in the pieces (connected components) its seed pair joins, a piece and its mirror
    piece, or one piece its own mirror. For each such group the growth kept is the one that pairs
    ``MIRROR_COVERAGE`` of its ``usable`` (N,) bool vertices and agrees with the most pairs of ``partner``;
    seeds are tried until every seed is explained or ``SEED_GROWTHS`` growths have run per group.
    The groups' maps together must pair that share of all the usable vertices.
    """
    from scipy.sparse.csgraph import connected_components

    n = len(partner)
    index = np.arange(n)
    _, piece = connected_components(adjacency, directed=False)
    seeds = np.flatnonzero(ring_consistent(adjacency, partner) & (partner != index))
    best: dict[tuple[int, int], tuple[int, np.ndarray]] = {}
    tries: dict[tuple[int, int], int] = {}
    while len(seeds):
        seed = seeds[len(seeds) // 2]
        group = (min(piece[seed], piece[partner[seed]]), max(piece[seed], piece[partner[seed]]))
        tries[group] = tries.get(group, 0) + 1
        ring = np.concatenate([[seed], adjacency.indices[adjacency.indptr[seed]:adjacency.indptr[seed + 1]]])
        start = np.full(n, -1)
        start[ring], start[partner[ring]] = partner[ring], ring
        grown = grow_by_connectivity(adjacency, start, LEAST_PAIRED_NEIGHBOURS)
        members = usable & np.isin(piece, group)
        agreement = int(np.count_nonzero((grown == partner) & (partner >= 0)))
        if np.mean(grown[members] >= 0) >= MIRROR_COVERAGE and agreement > best.get(group, (-1, None))[0]:
            best[group] = (agreement, grown)
        seeds = seeds[(grown[seeds] != partner[seeds])]
        exhausted = [g for g, count in tries.items() if count >= SEED_GROWTHS]
        if exhausted:
            stuck = np.isin(piece[seeds], [g[0] for g in exhausted]) | np.isin(piece[seeds], [g[1] for g in exhausted])
            seeds = seeds[~stuck]
    if not best:
        return None
    mirrored = np.full(n, -1)
    for _, grown in best.values():
        mirrored = np.where(mirrored >= 0, mirrored, grown)
    return mirrored if np.mean(mirrored[usable] >= 0) >= MIRROR_COVERAGE else None

"""Mirror twins read off a mesh's connectivity, where it is itself mirror-symmetric.

A mirrored model, or a symmetric template warped onto a specimen, has triangles
that mirror each other: the mirror map is then a map of the mesh onto itself
that sends neighbours to neighbours, whatever the bend or articulation did to
the geometry. So once the neighbours of a vertex are paired, its twin is the
vertex next to all of their twins, and a pair whose neighbours all pair with the
twin's neighbours is right however far the local geometry is from a mirror image
(a bent joint). A scan whose two sides are tessellated differently has no such
vertex: nothing here applies to it.

The same map, grown outward from one pair and its ring by the connectivity alone,
covers nearly the whole mesh when that pair is right, and stops early when it is
wrong (slid by a row along a regular tessellation, it runs into vertices of other
valence): so one right seed among many wrong ones is enough (``tessellation_mirror``;
Blender's "topology mirror" option rests on the same property of such meshes).

Where the triangles nearly mirror (quads split along opposite diagonals on the two
sides, like pymeshlab's cow), harmonic functions of the mesh graph still carry the
pairs around an unpaired patch across it, close to where the twins are
(``harmonic_twin_coordinates``).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sparse
from scipy.sparse.csgraph import connected_components
from scipy.sparse.linalg import splu

# Share of the closed rings (paired vertices with every neighbour paired) that must map onto their
# twins' rings. With the true twins: spot 94 % (its midline strip is tessellated one way only),
# pymeshlab's cow 19 % (its quads are split along mirrored diagonals on only part of it).
MIRRORED_RINGS = 0.8
# An unpaired vertex gets a twin from at least this many paired neighbours: with one, every unpaired
# neighbour of that neighbour's twin would fit.
LEAST_PAIRED_NEIGHBOURS = 2
# Share of the vertices the connectivity must pair, grown from one seed, for its map to be taken as
# the mirror of the tessellation (the share depends on the mesh, not on how it is deformed). Measured:
# spot (bent 1.2 rad, the Figure 1 map) from a right seed 96.4-97.4 % (the rest is its midline strip),
# from a wrong one at most 66 %; the icosphere-based test blob 100 %, and from seeds slid by a row up to
# 92 % (only its 12 vertices of valence 5 stop a slide).
MIRROR_COVERAGE = 0.95
# Seeds grown at most: each growth explains the seeds it pairs alike, and the next is taken among the
# others. On spot bent 1.2 rad, 9 growths explained every ring-consistent pair of the registration, 10
# of the intrinsic map.
SEED_GROWTHS = 12


def vertex_adjacency(faces: np.ndarray, count: int) -> sparse.csr_matrix:
    """Symmetric (count, count) 0/1 matrix of the mesh edges of ``faces`` (F, 3)."""
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    edges = np.concatenate([edges, edges[:, ::-1]])
    adjacency = sparse.csr_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(count, count))
    adjacency.data[:] = 1.0  # an edge shared by two triangles was summed twice
    return adjacency


def _neighbours(adjacency: sparse.csr_matrix, vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The edges leaving ``vertices`` (k,): (position in ``vertices``, neighbour), with numpy alone
    (scipy's row indexing costs more than the work on a small frontier of a large mesh)."""
    starts = adjacency.indptr[vertices]
    lengths = adjacency.indptr[vertices + 1] - starts
    position = np.repeat(np.arange(len(vertices)), lengths)
    offsets = np.arange(len(position)) - np.repeat(np.cumsum(lengths) - lengths, lengths)
    return position, adjacency.indices[np.repeat(starts, lengths) + offsets]


def _adjacent(adjacency: sparse.csr_matrix, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(k,) bool: whether vertices a[i] and b[i] share an edge."""
    return np.asarray(adjacency[a, b]).ravel() > 0


def ring_consistent(adjacency: sparse.csr_matrix, partner: np.ndarray) -> np.ndarray:
    """(N,) bool: paired vertices whose every neighbour is paired with a neighbour of their twin,
    and whose twin has as many neighbours (``partner`` (N,): twin index, itself on the
    midline, -1 unpaired)."""
    source, neighbour = _neighbours(adjacency, np.arange(len(partner)))
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
    source, neighbour = _neighbours(adjacency, np.arange(len(partner)))
    open_ring = np.bincount(source[partner[neighbour] < 0], minlength=len(partner)) > 0
    closed = (partner >= 0) & ~open_ring
    return bool(closed.any()) and float(np.mean(ring_consistent(adjacency, partner)[closed])) >= MIRRORED_RINGS


def connectivity_twins(adjacency: sparse.csr_matrix, partner: np.ndarray, candidates: np.ndarray | None = None):
    """Twins the connectivity implies for unpaired vertices: (sources (k,), twins (k,)).

    A source is an unpaired vertex with LEAST_PAIRED_NEIGHBOURS paired neighbours or more, and
    its twin the one unpaired vertex adjacent to all of their twins (the source itself if they
    are its own neighbours: a midline vertex); kept only where the twin's own candidate is the
    source. ``candidates`` (m,): the vertices that may be sources or twins (default: all); the
    work grows with their number, not the mesh's.
    """
    candidates = np.flatnonzero(partner < 0) if candidates is None else np.unique(candidates[partner[candidates] < 0])
    m, n = len(candidates), len(partner)
    source, neighbour = _neighbours(adjacency, candidates)  # source: position in candidates
    useful = partner[neighbour] >= 0
    source, twin_of_neighbour = source[useful], partner[neighbour[useful]]
    counts = np.bincount(source, minlength=m)  # the twins are distinct: one per paired neighbour
    # How many twins of each source's paired neighbours each vertex is adjacent to.
    entry, near_twin = _neighbours(adjacency, twin_of_neighbour)
    reach, hits = np.unique(source[entry] * n + near_twin, return_counts=True)
    sources, twins = reach // n, reach % n
    fits = (hits == counts[sources]) & (counts[sources] >= LEAST_PAIRED_NEIGHBOURS)
    sources, twins = sources[fits], twins[fits]
    position = np.searchsorted(candidates, twins)
    inside = position < m
    inside[inside] = candidates[position[inside]] == twins[inside]  # the twin is unpaired and a candidate
    sources, position = sources[inside], position[inside]
    unique = np.bincount(sources, minlength=m) == 1
    sources, position = sources[unique[sources]], position[unique[sources]]
    candidate = np.full(m, -1)
    candidate[sources] = position
    mutual = candidate[position] == sources
    return candidates[sources[mutual]], candidates[position[mutual]]


def single_pairs(count, sources, twin, votes):
    """The pairs (sources, twin, votes) with each vertex in one pair only: a pair found from both
    of its ends counts once, a vertex in two different pairs waits for the next wave. None if none."""
    low, high = np.minimum(sources, twin), np.maximum(sources, twin)
    _, first = np.unique(low * count + high, return_index=True)
    sources, twin, votes = sources[first], twin[first], votes[first]
    ends, uses = np.unique(np.concatenate([sources, twin[twin != sources]]), return_counts=True)
    single = (uses[np.searchsorted(ends, sources)] == 1) & (uses[np.searchsorted(ends, twin)] == 1)
    if not single.any():
        return None
    return sources[single], twin[single], votes[single]


def connectivity_growth(adjacency: sparse.csr_matrix, partner: np.ndarray, side: np.ndarray):
    """``partner``, ``side`` (N,) (see :func:`ring_consistent`; side +1 left, -1 right, 0 midline or
    unpaired) extended by :func:`connectivity_twins` wave after wave until it stalls; a new pair
    takes the side its source's paired neighbours hold most (none where they are tied). Returns new
    arrays."""
    partner, side = partner.copy(), side.copy()
    n = len(partner)
    added = np.flatnonzero(partner >= 0)
    while True:
        # Only the unpaired neighbours of the pairs added last can be new sources, or their twins.
        sources, twins = connectivity_twins(adjacency, partner, np.unique(_neighbours(adjacency, added)[1]))
        position, neighbour = _neighbours(adjacency, sources)
        votes = np.sign(np.bincount(position, weights=side[neighbour], minlength=len(sources))).astype(np.int8)
        keep = (sources == twins) | (votes != 0)
        found = single_pairs(n, sources[keep], twins[keep], votes[keep])
        if found is None:
            return partner, side
        sources, twins, votes = found
        partner[sources], partner[twins] = twins, sources
        added = np.concatenate([sources, twins])
        midline = sources == twins
        side[sources], side[twins] = np.where(midline, 0, votes), np.where(midline, 0, -votes)


def tessellation_mirror(adjacency: sparse.csr_matrix, partner: np.ndarray, side: np.ndarray):
    """The mirror map of a mirrored tessellation, grown (:func:`connectivity_growth`) from single
    seeds: the ``ring_consistent`` pairs of ``partner`` (N,) (with ``side`` (N,)), each with its
    ring. Growths are tried until every seed is explained by one (paired alike) or SEED_GROWTHS
    have run. Of those that pair MIRROR_COVERAGE of the vertices or more, returns the one that
    agrees with the most pairs of ``partner`` as (partner, side); None if there is none. (A
    regular tessellation can have other mirror maps, e.g. an icosphere's: the pairs found from the
    geometry choose among them.)"""
    n = len(partner)
    seeds = np.flatnonzero(ring_consistent(adjacency, partner) & (side != 0))
    best, best_agreement, tried = None, -1, 0
    while len(seeds) and tried < SEED_GROWTHS:
        seed = seeds[len(seeds) // 2]
        ring = np.concatenate([[seed], adjacency.indices[adjacency.indptr[seed]:adjacency.indptr[seed + 1]]])
        twins = partner[ring]
        start_partner, start_side = np.full(n, -1), np.zeros(n, dtype=np.int8)
        start_partner[ring], start_partner[twins] = twins, ring
        start_side[ring], start_side[twins] = side[ring], side[twins]
        grown = connectivity_growth(adjacency, start_partner, start_side)
        agreement = np.count_nonzero((grown[0] == partner) & (partner >= 0))
        if np.mean(grown[0] >= 0) >= MIRROR_COVERAGE and agreement > best_agreement:
            best, best_agreement = grown, agreement
        seeds = seeds[grown[0][seeds] != partner[seeds]]
        tried += 1
    return best


def harmonic_twin_coordinates(adjacency: sparse.csr_matrix, partner: np.ndarray, points: np.ndarray):
    """Where the mirror map sends the unpaired vertices, by the connectivity and the pairs around them:
    (unpaired (u,), mirrored (u, 3), own (u, 3)).

    Both are harmonic in the mesh graph over the unpaired vertices (each at the mean of its
    neighbours), ``mirrored`` equal to the twin's position ``points`` (N, 3) on the paired vertices,
    ``own`` to their own position. Where the tessellation mirrors itself the mirror map takes one
    problem into the other, so the twin's ``own`` is the vertex's ``mirrored``, however the geometry
    between the pairs is deformed. Where it nearly does (pymeshlab's cow, quads split along opposite
    diagonals on its two sides), at its joint swung 0.6 rad 86 % of the unpaired vertices have their
    twin's ``own`` nearest their ``mirrored``, and 47 % their twin nearest the thin-plate spline of the
    pairs' mirror map. Only unpaired vertices connected to a paired one through unpaired ones are
    returned.
    """
    paired = partner >= 0
    unpaired = np.flatnonzero(~paired)
    rows = adjacency[unpaired]
    inner, boundary = rows[:, unpaired], rows[:, np.flatnonzero(paired)]
    count, component = connected_components(inner, directed=False)
    touching = np.bincount(component, weights=np.asarray(boundary.sum(axis=1)).ravel(), minlength=count) > 0
    kept = touching[component]
    unpaired, inner, boundary = unpaired[kept], inner[kept][:, kept], boundary[kept]
    if not len(unpaired):
        return unpaired, np.zeros((0, 3)), np.zeros((0, 3))
    degree = np.asarray(rows[kept].sum(axis=1)).ravel()
    solve = splu((sparse.diags(degree) - inner).tocsc()).solve
    twins = partner[paired]
    return unpaired, solve(boundary @ points[twins]), solve(boundary @ points[paired])


def kept_edge_share(adjacency: sparse.csr_matrix, before: np.ndarray, after: np.ndarray) -> float:
    """Share of the mesh edges from a vertex paired in ``after`` (N,) but not ``before`` (N,) to a paired
    vertex whose twins share an edge too: 1 for a mirrored tessellation's true twins, less where quads
    are split along opposite diagonals, less still where the twins slide. Measured on the cow's joint
    swung 0.6 rad: the connectivity's twins (10 of 184 wrong) 0.85, the spline's (66 of 186) 0.69; on
    its whole leg swung 0.3 rad, unpaired on the output of 20 landmarks: the spline's (6 of 328) 0.84,
    the connectivity's (128 of 320) 0.75."""
    new = np.flatnonzero((before < 0) & (after >= 0))
    source, neighbour = _neighbours(adjacency, new)
    paired = after[neighbour] >= 0
    kept = _adjacent(adjacency, after[new[source[paired]]], after[neighbour[paired]])
    return float(np.mean(kept)) if len(kept) else 0.0

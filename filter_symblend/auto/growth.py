"""Vertex twins grown from sure ones by local mirror maps, and the ones their neighbours contradict dropped.

On a mesh whose vertices mirror each other, a global map (a plane, a registration)
gives exact twins only where it is accurate. Around any set of exact pairs, though,
the mirror map is locally an affine map, fitted to the nearest pairs: it predicts
the twin of an unpaired vertex nearby, and the twin is taken when it passes the same
tests as a global map's (unambiguous nearest vertex, mutual, facing the mirrored way).
Wave after wave the pairs spread over the surface, following a bend or a twist as
far as the surface carries it.

Then each pair is checked against the local map of its other neighbours, on the
input's geometry (a symmetrized output is exactly symmetric at the pairs it was made
from, and would vouch for any of them): its twin must be where that map puts it,
nearly as precisely as the neighbouring pairs fit their own maps (``local_precision``
times their median misfit). On an exactly symmetric mesh this admits only exact twins
(a vertex with no exact twin lands between vertices, far beyond a precision of rounding
errors); on a bent one, the precision follows the local curvature. A pair that fails is
dropped (one wrong pair, made exactly symmetric by the solve, distorts its whole
neighbourhood) and its vertices are not grown again.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..core.geometry import MIRROR_X, proper_rotation_fit
from ..core.mesh_graph import one_pair_per_vertex
from .config import AutoConfig
from .surface import Surface

# A predicted twin is taken as a vertex only if that vertex is the unambiguous nearest one (Lowe's ratio test,
# nearest / second-nearest distance): within the inner half of its neighbourhood, whatever the local sampling.
RATIO = 0.5
# Unpaired vertices this close to a pair (x the median vertex spacing) are tried in a wave of the growth:
# the ring around the pairs and the next.
FRONTIER = 3.0
# Pull of each local affine mirror map toward its best improper rigid map, x the neighbourhood's spread:
# keeps a map of a nearly flat patch determined without stiffening a curved one.
LOCAL_MAP_RIDGE = 0.05
# Pairs each local map of a growth wave is fitted to: exact vertex pairs carry no noise, so fewer than the
# ``config.local_neighbours`` of the other local maps (whose pairs may be a vertex off) keep a map local enough to
# follow a joint that turns fast, still twice the four that determine an affine map. Measured (--corpus): the exact
# cow's leg swung 0.3 rad 0.60x -> 0.34x the error of 100 landmark pairs (0.6 rad 0.93x -> 0.96x, its 90th
# percentile 0.016 -> 0.010 %), Figure 1's cow 0.085x -> 0.083x, every other row the same; the 40 BCICP shapes the
# same but michael0 0.98x -> 0.97x and wolf2 1.61x -> 1.59x (docs/benchmarks.md).
GROWTH_NEIGHBOURS = 8
# Prune-and-grow passes at most: each removes what the one before grew wrong, and none was needed beyond
# the third.
PASSES = 4


def local_maps(points: np.ndarray, partner: np.ndarray, queries: np.ndarray, paired: np.ndarray,
               tree: cKDTree, config: AutoConfig, leave_out: bool = False):
    """Predicted twins (m, 3) of the positions ``queries`` (m, 3) and the improper rigid part (m, 3, 3) of
    their local maps: affine maps fitted to the ``config.local_neighbours`` nearest paired vertices ``paired``
    (``tree`` holds their positions ``points[paired]``, ``partner`` their twins), pulled toward the best
    improper rigid map by ``LOCAL_MAP_RIDGE`` (x the neighbourhood's spread); ``leave_out``: the queries
    are the paired vertices' own positions, and each map is fitted without the query's own pair. The pairs
    weigh alike, so a map depends only on its set of pairs: queries that share one (most of a dense mesh
    between sparser pairs: 10^6 vertices among 6,000 pairs) share one fit."""
    k = min(config.local_neighbours + int(leave_out), len(paired))
    predicted, rigid, _ = _local_maps(points, partner, queries, paired, tree, k, leave_out)
    return predicted, rigid


def _local_maps(points: np.ndarray, partner: np.ndarray, queries: np.ndarray, paired: np.ndarray,
                tree: cKDTree, k: int, leave_out: bool = False):
    """:func:`local_maps` on the ``k`` nearest pairs, and the reach (m,) of each map: the distance from its
    query to the farthest of them (a pair added farther away leaves the map as it is)."""
    distance, nearest = tree.query(queries, k=k)
    neighbours = np.sort(paired[nearest.reshape(len(queries), k)[:, int(leave_out):]], axis=1)
    sets, fit_of = np.unique(neighbours, axis=0, return_inverse=True)
    x, y = points[sets], points[partner[sets]]
    linear, cx, cy, rigid = affine_mirror_fits(x, y, np.ones(x.shape[:2]), LOCAL_MAP_RIDGE)
    fit_of = fit_of.reshape(-1)
    predicted = np.einsum("nij,nj->ni", linear[fit_of], queries - cx[fit_of]) + cy[fit_of]
    return predicted, rigid[fit_of], distance.reshape(len(queries), k)[:, -1]


def affine_mirror_maps(x: np.ndarray, y: np.ndarray, weights: np.ndarray, queries: np.ndarray, ridge: float):
    """Where the weighted affine maps fitted to pairs ``x`` (m, k, 3) -> ``y`` (m, k, 3) with ``weights``
    (m, k) put ``queries`` (m, 3), and their improper rigid parts (m, 3, 3); each map pulled toward the best
    improper rigid map by ``ridge`` (x the neighbourhood's spread)."""
    linear, cx, cy, rigid = affine_mirror_fits(x, y, weights, ridge)
    return np.einsum("nij,nj->ni", linear, queries - cx) + cy, rigid


def affine_mirror_fits(x: np.ndarray, y: np.ndarray, weights: np.ndarray, ridge: float):
    """The maps of :func:`affine_mirror_maps` as (linear parts (m, 3, 3), centres of ``x`` (m, 3), centres of
    ``y`` (m, 3), improper rigid parts (m, 3, 3)): a point q goes to linear (q - cx) + cy."""
    total = weights.sum(axis=1, keepdims=True)
    cx, cy = np.einsum("nk,nki->ni", weights, x) / total, np.einsum("nk,nki->ni", weights, y) / total
    x, y = x - cx[:, None], y - cy[:, None]
    cross = np.einsum("nk,nki,nkj->nij", weights, y, x)
    spread = np.einsum("nk,nki,nkj->nij", weights, x, x)
    rigid = proper_rotation_fit(cross @ MIRROR_X) @ MIRROR_X  # best y ~ R J x, R proper
    ridge = ridge * np.trace(spread, axis1=1, axis2=2)[:, None, None] / 3.0 + 1e-300
    linear = (cross + ridge * rigid) @ np.linalg.inv(spread + ridge * np.eye(3))
    return linear, cx, cy, rigid


def grow(surface: Surface, partner: np.ndarray, eligible: np.ndarray, twins: np.ndarray, own_twin: np.ndarray,
         config: AutoConfig) -> int:
    """Pair ``eligible`` (N,) bool vertices, with ``twins`` (N,) bool vertices (each with itself only where
    ``own_twin`` (N,) bool allows it: on the midline), wave by wave from the pairs in ``partner`` (N,) (twin index,
    itself on the midline, -1 unpaired; updated in place). Returns the number of waves.

    A wave tries the unpaired vertices near the pairs: the local map of a source's nearest pairs predicts its
    twin, which is taken if its nearest vertex is unambiguous, unpaired, faces the mirrored way, and the local
    map there sends it back to the source. A source that fails is not tried again until a new pair falls within
    the reach of the maps that decided it (its own, and the one at the vertex it named): until then the same
    maps give the same answer. On two sides sampled independently the growth creeps, a few chance pairs a
    wave among some two thousand sources: trying them all again each wave cost 2.7-3.5x as much (the same
    pairs)."""
    points = surface.points
    count = len(points)
    failed = np.zeros(count, dtype=bool)  # sources whose failure stands until a new pair comes within reach
    reach, named, named_reach = np.zeros(count), np.zeros(count, dtype=np.int64), np.zeros(count)
    waves = 0
    while True:
        paired = np.flatnonzero(partner >= 0)
        if len(paired) < 4:
            return waves
        tree = cKDTree(points[paired])
        unpaired = np.flatnonzero(eligible & (partner < 0))
        gap, _ = tree.query(points[unpaired], distance_upper_bound=FRONTIER * surface.spacing)
        sources = unpaired[np.isfinite(gap)]
        sources = sources[~failed[sources]]
        if not len(sources):
            return waves
        k = min(GROWTH_NEIGHBOURS, len(paired))
        predicted, rigid, source_reach = _local_maps(points, partner, points[sources], paired, tree, k)
        vertex, _, ratio = surface.nearest_vertices(predicted)
        ok = (ratio <= RATIO) & (partner[vertex] < 0) & twins[vertex] & ((vertex != sources) | own_twin[sources])
        if surface.is_mesh:
            ok &= np.einsum("nij,nj,ni->n", rigid, surface.normals[sources], surface.normals[vertex]) > 0
        tried_back = np.flatnonzero(ok)
        back, _, back_reach = _local_maps(points, partner, points[vertex[tried_back]], paired, tree, k)
        ok[tried_back] = surface.nearest_vertices(back)[0] == sources[tried_back]
        lost = sources[~ok]
        failed[lost], reach[lost], named[lost], named_reach[lost] = True, source_reach[~ok], vertex[~ok], -np.inf
        named_reach[sources[tried_back]] = back_reach  # the failures among them: the back map decided
        sources, vertex = one_pair_per_vertex(sources[ok], vertex[ok])
        if not len(sources):
            return waves
        partner[sources], partner[vertex] = vertex, sources
        waves += 1
        if k < GROWTH_NEIGHBOURS:  # every pair is in every map: a new one changes them all
            failed[:] = False
            continue
        waiting = np.flatnonzero(failed)
        near_new = cKDTree(points[np.concatenate([sources, vertex])])
        changed = (near_new.query(points[waiting])[0] <= reach[waiting]) | \
            (near_new.query(points[named[waiting]])[0] <= named_reach[waiting])
        failed[waiting[changed]] = False


def prune(surface: Surface, partner: np.ndarray, fixed: np.ndarray, config: AutoConfig, floor: float) -> np.ndarray:
    """Unpair (in place) the pairs whose twin is not where the local map of their other neighbouring pairs
    puts it (see the module doc), except ``fixed`` (N,) bool vertices. Returns the vertices dropped (N,)
    bool. ``floor`` (mesh units): the least precision asked (rounding)."""
    wrong = np.zeros(len(partner), dtype=bool)
    paired = np.flatnonzero(partner >= 0)
    if len(paired) <= config.local_neighbours:
        return wrong
    tree = cKDTree(surface.points[paired])
    predicted, rigid = local_maps(surface.points, partner, surface.points[paired], paired, tree, config,
                                  leave_out=True)
    misfit = np.linalg.norm(predicted - surface.points[partner[paired]], axis=1)
    # The neighbouring pairs' own misfits, midline points left out: a row of vertices just off the
    # midline, each wrongly its own twin, would vouch for one another.
    crossing = np.flatnonzero(partner[paired] != paired)
    if len(crossing) <= config.local_neighbours:
        return wrong
    _, nearest = cKDTree(surface.points[paired[crossing]]).query(surface.points[paired], k=config.local_neighbours + 1)
    neighbours = np.where((crossing[nearest[:, :1]] == np.arange(len(paired))[:, None]), nearest[:, 1:], nearest[:, :-1])
    local = np.median(misfit[crossing[neighbours]], axis=1)
    precise = misfit <= np.maximum(config.local_precision * local, floor)
    vertex, _, ratio = surface.nearest_vertices(predicted)
    agrees = precise & (vertex == partner[paired]) & (ratio <= RATIO)
    if surface.is_mesh:
        agrees &= np.einsum("nij,nj,ni->n", rigid, surface.normals[paired], surface.normals[partner[paired]]) > 0
    wrong[paired[~agrees]] = True
    wrong |= wrong[np.maximum(partner, 0)] & (partner >= 0)
    wrong &= ~fixed
    partner[wrong] = -1
    return wrong


def grow_and_prune(space: Surface, geometry: Surface, partner: np.ndarray, eligible: np.ndarray,
                   twins: np.ndarray, own_twin: np.ndarray, fixed: np.ndarray, config: AutoConfig) -> dict:
    """:func:`prune` the seeds in ``partner`` on ``geometry`` (the input), :func:`grow` in ``space`` (where
    the map predicts: the input, or a symmetrized output; ``eligible`` (N,) bool vertices, with ``twins``
    (N,) bool ones, with themselves where ``own_twin`` (N,) bool), prune again, and grow again without what was
    dropped, until nothing changes (at most ``PASSES``). The least precision the prune asks is
    ``config.coincident`` x the diagonal."""
    floor = config.coincident * space.diagonal
    dropped = np.zeros(len(partner), dtype=bool)
    waves = 0
    for _ in range(PASSES):
        removed = prune(geometry, partner, fixed, config, floor)
        dropped |= removed
        grown = grow(space, partner, eligible & ~dropped, twins & ~dropped, own_twin, config)
        waves += grown
        if not removed.any() and not grown:
            break
    return {"growth_waves": waves, "dropped": int(np.count_nonzero(dropped))}

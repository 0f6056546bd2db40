"""The pairs one round finds under a mirror map, and how they join the paper's solve.

Each vertex of a spread sample gets its twin under the map (:mod:`.twins`); twins the map is not
consistent about (it does not come back, the two do not face the mirrored way) or that land off the
surface are dropped, and the share kept of those that landed is the round's ``consistency``. Then:

- On a mesh whose vertices mirror each other (a mirrored model, a symmetric template warped onto a
  specimen), the twins that are vertices (unambiguous, mutual, within ``twins.VERTEX_PRECISION`` of the local
  spacing) seed a growth along the surface by local mirror maps, pairs their neighbours contradict are
  pruned (:mod:`.growth`), and the tessellation's own mirror (:mod:`.connectivity`) pairs what the
  geometry cannot. If that pairs ``vertex_share`` of the vertices, the pairs are these vertex pairs,
  exact.
- Otherwise (a scan, a remeshed surface: the two sides sampled independently) a vertex's twin is a
  point of the surface, inside a triangle: the pair joins the solve as the vertex and that point (a
  barycentric combination of the triangle's corners, the same material point on the input as on any
  embedding of the mesh). Snapping it to the nearest vertex would leave every pair up to half an edge
  off along the surface, an error the solve then makes symmetric.

Vertices whose twin is themselves (within half the local vertex spacing) are midline points. The pairs
go through :func:`~filter_symblend.core.solve.check_landmarks`, the same checks as a user's.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
from scipy.spatial import cKDTree

from ..core.geometry import bounding_diagonal, voxel_grid
from ..core.landmark_pairs import LandmarkPairs, check_landmarks
from ..core.mesh_graph import one_pair_per_vertex
from ..core.surface_points import on_surface, vertex_points
from ..errors import GeometryError
from .config import AutoConfig
from .connectivity import ring_consistent, tessellation_mirror
from .growth import FRONTIER, RATIO, grow_and_prune
from .maps import MirrorMap
from .report import PairSearch
from .surface import Surface
from .twins import find_twins


@dataclasses.dataclass(frozen=True)
class AutomaticPairs:
    """Pairs found in one round, each side a point of the surface: barycentric ``left_weights`` (n, 3) on the
    vertices ``left_corners`` (n, 3), likewise ``right_weights`` and ``right_corners`` (weight 1 on one corner:
    that vertex); midline vertices ``midline`` (m,); ``search``, what the round reports of the search (None: pairs
    no search found, the intrinsic start's)."""

    left_corners: np.ndarray
    left_weights: np.ndarray
    right_corners: np.ndarray
    right_weights: np.ndarray
    midline: np.ndarray
    search: PairSearch | None


@dataclasses.dataclass(frozen=True)
class Constraints:
    """What every round's pairs obey: checked on ``geometry`` (the input surface), anchored by ``fixed`` (the
    user's landmarks, or None), none on or toward a ``forbidden`` (N,) bool vertex (a landmark, an excluded
    part), by the thresholds of ``config``."""

    geometry: Surface
    fixed: LandmarkPairs | None
    forbidden: np.ndarray
    config: AutoConfig


def spread(points: np.ndarray, vertices: np.ndarray, count: int) -> np.ndarray:
    """At most about ``count`` of ``vertices`` spread evenly (one per cell of a voxel grid), in order."""
    if len(vertices) <= count:
        return vertices
    keys = voxel_grid(points[vertices], count, steps=16)
    _, first = np.unique(keys, return_index=True)
    return vertices[np.sort(first)]


@dataclasses.dataclass(frozen=True)
class FoundPairs:
    """Every pair one search under a map found (``search``: what the round reports), before ``count`` of them
    are spread over the surface (:meth:`chosen`): a round takes ``round_pairs`` of them (``auto_pair_count`` if
    it is the last), the last solve ``auto_pair_count`` from the kept round's search. ``partner`` (N,): where the
    twins are exact vertices, each vertex's twin (-1: unpaired); else None."""

    search: PairSearch
    _chosen: Callable[[int], AutomaticPairs]
    partner: np.ndarray | None = None

    def chosen(self, count: int) -> AutomaticPairs:
        """About ``count`` of the pairs, spread evenly over the surface."""
        return self._chosen(count)


def search_pairs(mirror: MirrorMap, sources: np.ndarray, constraints: Constraints,
                 exact: bool | None = None) -> FoundPairs:
    """The pairs under ``mirror`` for ``sources`` (sorted vertex indices; see the module doc), under the round's
    ``constraints``. ``exact``: whether the twins are to be exact vertices; None: decided here, by the share of
    the twins that are (on a symmetrized output the pairs it was made from always are, so the later rounds pass
    the first round's answer)."""
    surface, config, forbidden = mirror.surface, constraints.config, constraints.forbidden
    tolerance = config.landing_tolerance * constraints.geometry.diagonal
    twins = find_twins(mirror, sources, tolerance)
    landed = twins.landing <= tolerance
    covered = twins.covered(tolerance) & ~forbidden[twins.corners].any(axis=1)
    if not covered.any():
        raise GeometryError("Automatic pairing found no vertex whose mirror image lies on the surface.")
    # Seeds within VERTEX_PRECISION of the local spacing, with no bound from the map's precision over the
    # whole surface: that varies (exact on a cow's body, 1e-5 of the spacing on its swung leg under the
    # intrinsic map), and the growth, the prune and the vertex share verify every seed.
    seeds = twins.exact_vertex() & covered & ~forbidden[twins.vertex]
    beyond_chance = seeds & (surface.chance_ratio(twins.ratio) <= RATIO)
    search = PairSearch(mirror.name, float(np.mean(covered)),
                        float(np.count_nonzero(covered) / max(np.count_nonzero(landed), 1)),
                        float(np.count_nonzero(beyond_chance) / np.count_nonzero(covered)))
    if exact is not False and (exact or np.count_nonzero(seeds) > config.local_neighbours):
        # Vertex twins, perhaps: the growth from them proves it by pairing most of the vertices, which it
        # cannot do on two sides sampled independently (their vertices miss each other's local maps).
        found = _exact_pairs(mirror, sources, twins, seeds, constraints, search)
        if exact or found.search.vertex_share >= config.vertex_share:
            return found
    candidates = sources[covered & ~forbidden[sources]]
    search = dataclasses.replace(search, twins_are="points of the surface", candidates=len(candidates))

    def chosen(count: int) -> AutomaticPairs:
        rows = np.searchsorted(sources, spread(surface.points, candidates, count))
        return AutomaticPairs(*_point_pairs(surface, sources, twins, rows), search)
    return FoundPairs(search, chosen)


def keeping_unreached(pairs: AutomaticPairs, solved_from: AutomaticPairs | None,
                      surface: Surface) -> tuple[AutomaticPairs, int]:
    """(``pairs`` with the pairs of ``solved_from`` that none of them comes near, how many those are): both sides
    farther than growth.FRONTIER x the vertex spacing from every side of ``pairs`` on ``surface`` (the input).
    ``solved_from``: the pairs the current output was solved from (None: none, the first round of a map of
    space). Each round solves on the input, so a region its search does not reach would fall back to its input
    pose: a swung limb the intrinsic start's pairs restored, which the exact vertex growth of the next round
    does not enter where the joint turns faster than a local affine map follows. It keeps the pairs that
    restored it instead."""
    if solved_from is None or not len(solved_from.left_corners):
        return pairs, 0

    def sides(found: AutomaticPairs) -> list[np.ndarray]:
        return [on_surface(surface.points, corners, weights)
                for corners, weights in ((found.left_corners, found.left_weights),
                                         (found.right_corners, found.right_weights))]
    near = cKDTree(np.vstack([*sides(pairs), surface.points[pairs.midline]]))
    reach = FRONTIER * surface.spacing
    far = np.logical_and(*(near.query(side)[0] > reach for side in sides(solved_from)))
    if not far.any():
        return pairs, 0
    joined = {name: np.vstack([getattr(pairs, name), getattr(solved_from, name)[far]])
              for name in ("left_corners", "left_weights", "right_corners", "right_weights")}
    return dataclasses.replace(pairs, **joined), int(np.count_nonzero(far))


def _point_pairs(surface: Surface, sources: np.ndarray, twins, rows: np.ndarray):
    """(left corners, left weights, right corners, right weights, midline) of the ``rows`` of ``sources``
    (m,) with their twin points: the left one first; the sources that are their own twin (within half the
    local spacing) on the midline."""
    itself = _own_twins(surface, sources[rows], twins.point[rows])
    midline, rows = sources[rows[itself]], rows[~itself]
    own_corners, own_weights = vertex_points(sources[rows])
    left = twins.side[rows] > 0
    pick = lambda a, b: np.where(left[:, None], a, b)  # noqa: E731
    return (pick(own_corners, twins.corners[rows]), pick(own_weights, twins.weights[rows]),
            pick(twins.corners[rows], own_corners), pick(twins.weights[rows], own_weights), midline)


def _own_twins(surface: Surface, sources: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(m,) bool: the ``sources`` (m,) whose twin ``points`` (m, 3) lie within half their local vertex spacing of
    them: midline points."""
    return np.linalg.norm(points - surface.points[sources], axis=1) <= 0.5 * surface.local_spacing[sources]


def _exact_pairs(mirror: MirrorMap, sources: np.ndarray, twins, exact_twins: np.ndarray,
                 constraints: Constraints, search: PairSearch) -> FoundPairs:
    """Exact vertex pairs grown from the exact twins (see the module doc); ``search`` gains what the growth
    did and ``vertex_share``, the share of the usable vertices it paired. Where the growth does not reach
    (the tip of a horn) nothing is paired: the map's twin points there would carry its tangential error
    into the solve (on a bent cow, 3x the symmetry error of leaving them to the warp)."""
    surface, geometry, config = mirror.surface, constraints.geometry, constraints.config
    fixed, forbidden = constraints.fixed, constraints.forbidden
    n = len(surface.points)
    index = np.arange(n)
    partner = np.full(n, -1)
    _hold_landmarks(partner, fixed)
    seeds, twin = one_pair_per_vertex(sources[exact_twins], twins.vertex[exact_twins])
    partner[seeds], partner[twin] = twin, seeds
    in_sample = np.zeros(n, dtype=bool)
    in_sample[sources] = True
    # A vertex is grown into its own twin only where the map puts it on the midline too: near the plane, in a thin
    # part (a cow's tail under Figure 1's map), local maps can take a vertex two spacings off it for its own twin.
    own_twin = np.zeros(n, dtype=bool)
    own_twin[sources] = _own_twins(surface, sources, twins.point)
    growth = grow_and_prune(surface, geometry, partner, in_sample & ~forbidden, surface.usable & ~forbidden,
                            own_twin, forbidden, config)
    tessellation = None
    if surface.is_mesh:
        mirrored = tessellation_mirror(surface.adjacency, partner, surface.usable & ~forbidden)
        tessellation = mirrored is not None
        if mirrored is not None:
            # Where the tessellation stops mirroring (a midline strip triangulated one way), its pairs can be
            # wrong: those are left to the geometric growth from the pairs whose rings map whole, which are
            # exact whatever the geometry around them (a joint), and so are not pruned.
            whole = ring_consistent(surface.adjacency, mirrored) & ~forbidden
            partner[:] = np.where(whole, mirrored, -1)
            _hold_landmarks(partner, fixed)
            growth = grow_and_prune(surface, geometry, partner, in_sample & ~forbidden,
                                    surface.usable & ~forbidden, own_twin, forbidden | whole, config)
    automatic = (partner >= 0) & ~forbidden
    vertex_share = float(np.count_nonzero(automatic & surface.usable) /
                         max(np.count_nonzero(surface.usable & ~forbidden), 1))
    gap = surface.points - surface.points[np.maximum(partner, 0)]
    left = np.flatnonzero(automatic & (partner != index) & (gap @ mirror.normal > 0))
    midline = np.flatnonzero(automatic & (partner == index))
    candidates = np.concatenate([left, midline])
    search = dataclasses.replace(search, twins_are="exact vertices", candidates=len(candidates), **growth,
                                 tessellation_mirror=tessellation, vertex_share=vertex_share)

    def chosen(count: int) -> AutomaticPairs:
        spread_out = spread(surface.points, candidates, count)
        on_plane = partner[spread_out] == spread_out
        off_plane = spread_out[~on_plane]
        return AutomaticPairs(*vertex_points(off_plane), *vertex_points(partner[off_plane]), spread_out[on_plane],
                              search)
    return FoundPairs(search, chosen, np.where(automatic, partner, -1))


def _hold_landmarks(partner: np.ndarray, fixed: LandmarkPairs | None) -> None:
    """Set (in place) the user's landmark pairs and midline points in ``partner`` (N,)."""
    if fixed is not None:
        partner[fixed.left], partner[fixed.right], partner[fixed.midline] = fixed.right, fixed.left, fixed.midline


def _on_points(points: np.ndarray, corners: np.ndarray, weights: np.ndarray, first: int):
    """Indices (n,) of the points the sides (``corners``, ``weights`` (n, 3)) stand at: the vertex where the
    weight is all on one, else ``first`` + k for the k-th point inside a triangle; and those points (k, 3)."""
    on_vertex = weights.max(axis=1) >= 1.0 - 1e-12
    inside = np.flatnonzero(~on_vertex)
    index = corners[np.arange(len(corners)), np.argmax(weights, axis=1)]
    index[inside] = first + np.arange(len(inside))
    return index, on_surface(points, corners[inside], weights[inside])


def as_landmarks(points: np.ndarray, pairs: AutomaticPairs, user: LandmarkPairs | None,
                 priority: float, coincident: float) -> tuple[np.ndarray, LandmarkPairs]:
    """The points the solve runs on ((N + k, 3): the vertices, then the k pair sides inside triangles) and the
    user's and the automatic pairs as checked landmarks on them (automatic pairs touching a landmark's vertex,
    or on a position another landmark holds, are left out); the user's weigh ``priority`` times more."""
    keep = np.ones(len(pairs.left_corners), dtype=bool)
    midline = pairs.midline
    if user is not None:
        taken = np.concatenate([user.left, user.right, user.midline])
        keep = ~np.isin(pairs.left_corners, taken).any(axis=1) & ~np.isin(pairs.right_corners, taken).any(axis=1)
        midline = midline[~np.isin(midline, taken)]
    left, inside_left = _on_points(points, pairs.left_corners[keep], pairs.left_weights[keep], len(points))
    right, inside_right = _on_points(points, pairs.right_corners[keep], pairs.right_weights[keep],
                                     len(points) + len(inside_left))
    solved = np.vstack([points, inside_left, inside_right])
    left, right, midline = _distinct(solved, left, right, midline, user, coincident)
    first = 1 if user is None or not len(user.ids) else int(np.max(user.ids)) + 1
    ids = np.arange(first, first + len(left))
    ones = np.ones(len(left))
    if user is None:
        return solved, check_landmarks(solved, left, right, ids, midline, ones, ones)
    both = check_landmarks(solved, np.concatenate([user.left, left]), np.concatenate([user.right, right]),
                           np.concatenate([user.ids, ids]), np.concatenate([user.midline, midline]))
    return solved, dataclasses.replace(both, left_weights=np.concatenate([priority * user.left_weights, ones]),
                                       right_weights=np.concatenate([priority * user.right_weights, ones]))


def _distinct(points, left, right, midline, user, coincident):
    """The pairs and midline points whose positions no landmark before them holds (``coincident`` x the
    landmarks' diagonal apart), the user's landmarks first: of two pairs whose twins fall on one point (a
    point cloud's vertex), the first is kept."""
    fixed = np.zeros(0, dtype=np.int64) if user is None else np.concatenate([user.left, user.right, user.midline])
    used = np.concatenate([fixed, left, right, midline])
    scale = coincident * (bounding_diagonal(points[used]) or 1.0)
    cells = np.round(points[used] / scale).astype(np.int64)
    _, first = np.unique(cells, axis=0, return_index=True)
    alone = np.zeros(len(used), dtype=bool)
    alone[first] = True  # the first landmark at its position
    alone = alone[len(fixed):]
    n = len(left)
    pair_kept = alone[:n] & alone[n:2 * n]
    return left[pair_kept], right[pair_kept], midline[alone[2 * n:]]

"""Automatic mirror pairs: a dense vertex-to-vertex mirror correspondence found by the surface itself.

Seeds come from a global mirror plane (vertices whose reflection lands on
another vertex, mutual nearest neighbours, facing the mirrored way), from the
plane of the whitened shape (compression, shear), from the reflection registered
onto the shape (bends, bends with compression; see ``registration``), or from the
intrinsic mirror map of the Laplace-Beltrami eigenfunctions (articulation; see
``spectral``). The correspondence then grows in waves from the seeds: around
each unpaired vertex, the pairs already found give a local mirror map (an
affine map fitted to its nearest paired vertices, pulled toward the best
improper rigid map), which predicts where the vertex's twin lies. The nearest
vertex there is accepted if it is close to the prediction, faces the mirrored
way, and predicts the vertex back. Finally, pairs that the local maps of their
neighbours do not confirm are dropped: one wrong pair, forced symmetric by the
solve, distorts its whole neighbourhood.

Units: ``spacing`` is the mean edge length (mean nearest-neighbour distance
for a point cloud); distances below are multiples of it.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial import cKDTree

from .errors import GeometryError
from .geometry import MIRROR_X, hemisphere_directions, normalize, proper_rotation_fit, reflection_across_plane, whitening
from .mesh_geometry import farthest_point_order, mean_spacing, vertex_normals
from .registration import registered_mirror_map
from .spectral import intrinsic_mirror_map
from .surface_symmetry import fit_surface_mirror_plane, promising_normals

# Acceptance distance, x spacing: twice the median distance from a reflected vertex to its
# mutual nearest neighbour, within these bounds. On pymeshlab's cow symmetrized from 100
# landmarks, 0.1 pairs 96.6 % of vertices correctly and 0.5 only 94 % (a wrong pair is
# forced symmetric by the next solve, so strictness pays); a scan whose two sides are
# tessellated differently needs up to about 0.5 to find pairs at all.
MIN_MATCH_DISTANCE = 0.1
MAX_MATCH_DISTANCE = 0.5
# x spacing: a vertex is its own twin (a midline point) only if its mirror image lies this
# close to it, i.e. it is within 0.05 edge lengths of the mirror plane. With the general
# acceptance distance instead, vertices up to half an edge off the plane of the cow became
# midline points, were pulled onto the plane by the solve, and left the symmetry error of
# the cow bent by 0.2 rad at 0.05 % instead of 0.002 % with the true pairs.
MIDLINE_DISTANCE = 0.1
# x spacing: a pair is dropped when its twin is this much farther than the local mirror map
# of its neighbours predicts. On the cow bent by 0.2 rad, the intrinsic pairs that are
# right stay within 0.11-0.15 edges for 99 %, the wrong ones (near the midline, or on the
# few vertices without an exact twin) are 0.23-0.5 edges off; dropping those took the
# symmetry error of the solve from 0.019 % to 0.0024 % (0.0021 % with the true pairs).
OUTLIER = 0.15
SEED_COSINE = 0.9  # normals of a seed pair agree under the reflection at least this well
MATCH_COSINE = 0.7  # the same for grown pairs
NEIGHBOURS = 12  # paired vertices fitting each local mirror map
FRONTIER = 3.0  # x spacing: vertices this close to the paired region are tried in a wave
# x spacing: an intrinsic seed is kept where the local mirror map of its neighbouring seeds
# predicts its twin this closely. On the cow bent by 1.2 rad, the twins of the eigenfunction
# map alone are within 2.5 edges for 90 % of the pairs and up to 11 edges off; grown from
# the seeds kept (and outliers dropped), 90 % are within 0.6 edges, over half the vertices.
SEED_AGREEMENT = 0.5
# x spacing: intrinsic seeds this short are not used (the eigenfunctions cannot tell a vertex
# near the midline from its twin a few edges away). On spot bent by 0.2 rad, 70 such pairs
# were wrong by 0.2-0.4 edges yet agreed with each other, and left the symmetry error at
# 0.11 %; at 4 edges it is 0.005 % (the cow: 0.002 % either way).
SHORT_PAIR = 4.0
# x spacing: a map's correspondence, once grown, is grown again from its pairs longer than this.
# The first growth fills the band around the midline by predicting from seeds at least
# SHORT_PAIR / 2 edges away; on the cow bent by 0.4 rad and compressed to 0.85, where vertices
# crowd 0.3 edges apart along the midline, it paired 4 midline vertices with a neighbour (and one
# pair with the vertex next to a twin), and those 10 wrong vertices left the symmetry error at
# 0.031 % (0.005 % without them; with 1000 automatic pairs). Grown again, the band is predicted from
# pairs within half an edge on both sides: 0.006 %. From the pairs longer than 2 edges, 4 wrong
# vertices stayed (0.025 %). With every pair in the solve: 0.032 % without this, 0.0009 % with it.
REGROW = 1.0
RIDGE = 0.05  # pull of the local affine map toward the rigid one, x the neighbourhood's spread
# Largest mesh for the intrinsic candidate: its eigenproblem took 15 s and 0.6 GB (peak RSS
# growth) at 134k vertices (Igea); above this, the two plane candidates keep a
# million-vertex run near 3 minutes.
INTRINSIC_VERTEX_LIMIT = 300_000
# Starting planes of the reflection ICP on the whitened shape: the best WHITENED_STARTS of
# WHITENED_DIRECTIONS spread directions. On the sheared cow (compression 0.6 along (1, 1, 0),
# shear 0.2) the planes normal to the mapped principal axes end in wrong local minima, and
# 12 fixed spread directions find the plane in one pose but not in another.
WHITENED_DIRECTIONS = 200
WHITENED_STARTS = 6


@dataclasses.dataclass(frozen=True)
class MirrorCorrespondence:
    """Mirror twin of every vertex.

    partner (N,): index of the vertex's twin, itself on the midline, -1 if unpaired.
    side (N,): +1 left, -1 right, 0 on the midline or unpaired (consistent along the
    surface: the seeds' side of the global plane, carried along as the pairing grows).
    seeds: number of vertices paired by the global plane (both sides and midline).
    waves: number of growth waves.
    """

    partner: np.ndarray
    side: np.ndarray
    seeds: int
    waves: int

    @property
    def paired_fraction(self) -> float:
        return float(np.mean(self.partner >= 0))


def _agreement(mapped_normals: np.ndarray, normals: np.ndarray, oriented: bool) -> np.ndarray:
    cosine = np.einsum("ni,ni->n", normalize(mapped_normals), normals)
    return cosine if oriented else np.abs(cosine)


def _seed(points, normals, oriented, tree, spacing, plane_normal, plane_offset):
    """(partner, side, acceptance distance) of the vertices a single mirror plane pairs reliably."""
    n = len(points)
    distance, nearest = tree.query(reflection_across_plane(points, plane_normal, plane_offset))
    index = np.arange(n)
    mutual = nearest[nearest] == index
    if not mutual.any():
        return np.full(n, -1), np.zeros(n, dtype=np.int8), MIN_MATCH_DISTANCE * spacing
    tolerance = spacing * np.clip(2.0 * np.median(distance[mutual]) / spacing,
                                  MIN_MATCH_DISTANCE, MAX_MATCH_DISTANCE)
    mirrored_normals = reflection_across_plane(normals, plane_normal, 0.0)  # directions: through the origin
    good = (mutual & (distance < np.where(nearest == index, MIDLINE_DISTANCE * spacing, tolerance))
            & (_agreement(mirrored_normals, normals[nearest], oriented) > SEED_COSINE))
    partner = np.where(good, nearest, -1)
    height = points @ plane_normal - plane_offset
    side = np.where(good & (nearest != index), np.sign(height), 0).astype(np.int8)
    return partner, side, tolerance


def _local_maps(points, partner, sources, paired_tree, paired, leave_out=False):
    """Local mirror maps around ``sources`` (m,): (linear (m, 3, 3), centre (m, 3), image centre (m, 3),
    improper rigid part (m, 3, 3), neighbour indices (m, k)) fitted on the nearest paired vertices
    (``leave_out``: sources are paired vertices, each map fitted without the source's own pair)."""
    k = min(NEIGHBOURS + leave_out, len(paired))
    _, nearest = paired_tree.query(points[sources], k=k)
    neighbours = paired[nearest.reshape(len(sources), k)[:, int(leave_out):]]
    x, y = points[neighbours], points[partner[neighbours]]
    cx, cy = x.mean(axis=1), y.mean(axis=1)
    x, y = x - cx[:, None], y - cy[:, None]
    cross = np.einsum("nki,nkj->nij", y, x)
    spread = np.einsum("nki,nkj->nij", x, x)
    rigid = proper_rotation_fit(cross @ MIRROR_X) @ MIRROR_X  # best y ~ R J x, R proper
    ridge = RIDGE * np.trace(spread, axis1=1, axis2=2)[:, None, None] / 3.0
    linear = (cross + ridge * rigid) @ np.linalg.inv(spread + ridge * np.eye(3))
    return linear, cx, cy, rigid, neighbours


def _predicted_twins(points, partner, sources, paired_tree, paired, leave_out=False):
    """Predicted twin position (m, 3) of ``sources``, the improper rigid part of their local maps
    (m, 3, 3) and the paired vertices the maps were fitted on (m, k)."""
    linear, cx, cy, rigid, neighbours = _local_maps(points, partner, sources, paired_tree, paired, leave_out)
    return np.einsum("nij,nj->ni", linear, points[sources] - cx) + cy, rigid, neighbours


def _predict(points, normals, partner, sources, paired_tree, paired):
    """Predicted twin position (m, 3), mapped normal (m, 3) and the paired vertices the map was
    fitted on (m, k) for ``sources``."""
    predicted, rigid, neighbours = _predicted_twins(points, partner, sources, paired_tree, paired)
    return predicted, np.einsum("nij,nj->ni", rigid, normals[sources]), neighbours


def mirror_correspondence(points: np.ndarray, faces: np.ndarray, plane_normal, plane_offset: float,
                          fixed_pairs: tuple[np.ndarray, np.ndarray] | None = None,
                          fixed_midline: np.ndarray | None = None,
                          seed_pairs: tuple[np.ndarray, np.ndarray] | None = None) -> MirrorCorrespondence:
    """Mirror twins of the vertices ``points`` (N, 3) of a mesh (``faces`` (F, 3), may be empty).

    ``plane_normal`` (3,), ``plane_offset``: the global mirror plane the seeds come
    from (normal . x = offset; the normal points to the left side). ``fixed_pairs``
    (left (n,), right (n,)) and ``fixed_midline`` (m,): vertex indices of known pairs
    (the user's landmarks), seeded as given and always kept. ``seed_pairs`` (left (k,),
    right (k,)): seeds found otherwise (e.g. by the intrinsic map), used instead of the
    plane's (the plane still sets the acceptance distance). At the end, pairs that
    disagree with the local mirror map of their neighbours are dropped (see ``OUTLIER``).
    """
    points = np.asarray(points, dtype=float)
    plane_normal = normalize(np.asarray(plane_normal, dtype=float))
    normals, oriented = vertex_normals(points, faces)
    spacing = mean_spacing(points, faces)
    tree = cKDTree(points)
    partner, side, tolerance = _seed(points, normals, oriented, tree, spacing, plane_normal, plane_offset)
    if seed_pairs is not None:
        partner[:], side[:] = -1, 0
        partner[seed_pairs[0]], partner[seed_pairs[1]] = seed_pairs[1], seed_pairs[0]
        side[seed_pairs[0]], side[seed_pairs[1]] = 1, -1
    fixed = np.zeros(len(points), dtype=bool)
    if fixed_pairs is not None:
        left, right = fixed_pairs
        stale = np.isin(partner, np.concatenate([left, right]))  # vertices seeded onto a landmark
        partner[stale], side[stale] = -1, 0
        partner[left], partner[right] = right, left
        side[left], side[right] = 1, -1
        fixed[left] = fixed[right] = True
    if fixed_midline is not None:
        partner[fixed_midline], side[fixed_midline] = fixed_midline, 0
        fixed[fixed_midline] = True
    seeds = int(np.count_nonzero(partner >= 0))
    waves = 0
    added = np.flatnonzero(partner >= 0)
    while seeds >= 4:
        paired = np.flatnonzero(partner >= 0)
        paired_tree = cKDTree(points[paired])
        # Only vertices near the pairs added last can get a new prediction: the others' nearest
        # pairs, hence their local maps and their failures, are those of the wave before.
        unpaired = np.flatnonzero(partner < 0)
        gap, _ = cKDTree(points[added]).query(points[unpaired], distance_upper_bound=FRONTIER * spacing)
        sources = unpaired[np.isfinite(gap)]
        if len(sources) == 0:
            break
        predicted, mapped_normals, neighbours = _predict(points, normals, partner, sources, paired_tree, paired)
        distance, twin = tree.query(predicted)
        good = ((distance < np.where(twin == sources, MIDLINE_DISTANCE * spacing, tolerance))
                & ((partner[twin] < 0) | (twin == sources))
                & ((twin == sources) | (_agreement(mapped_normals, normals[twin], oriented) > MATCH_COSINE)))
        sources, twin, distance = sources[good], twin[good], distance[good]
        # One source per twin (the closest), then the twin must predict the source back.
        order = np.lexsort((distance, twin))
        first = np.ones(len(order), dtype=bool)
        first[1:] = twin[order][1:] != twin[order][:-1]
        sources, twin = sources[order[first]], twin[order[first]]
        back, _, _ = _predict(points, normals, partner, twin, paired_tree, paired)
        mutual = (twin == sources) | (tree.query(back)[1] == sources)
        sources, twin, neighbours = sources[mutual], twin[mutual], neighbours[good][order[first]][mutual]
        # A vertex that is its own twin is on the midline; the others claim sides from their neighbours.
        votes = np.sign(side[neighbours].sum(axis=1)).astype(np.int8)
        pairs = twin != sources
        keep = ~pairs | (votes != 0)
        sources, twin, votes = sources[keep], twin[keep], votes[keep]
        # The same pair found from both ends counts once; a vertex in two different pairs
        # waits for the next wave.
        low, high = np.minimum(sources, twin), np.maximum(sources, twin)
        _, first = np.unique(low * len(points) + high, return_index=True)
        sources, twin, votes = sources[first], twin[first], votes[first]
        uses = np.bincount(np.concatenate([sources, twin[twin != sources]]), minlength=len(points))
        single = (uses[sources] == 1) & (uses[twin] == 1)
        s, t, v = sources[single], twin[single], votes[single]
        if len(s) == 0:
            break
        partner[s], partner[t] = t, s
        side[s], side[t] = np.where(s == t, 0, v), np.where(s == t, 0, -v)
        added = np.unique(np.concatenate([s, t]))
        waves += 1
    outliers = _outliers(points, partner, spacing) & ~fixed
    outliers |= outliers[np.maximum(partner, 0)] & (partner >= 0)  # both ends of a pair
    partner[outliers], side[outliers] = -1, 0
    return MirrorCorrespondence(partner, side, seeds, waves)


def _misfits(points, partner) -> tuple[np.ndarray, np.ndarray]:
    """(paired vertices (n,), misfit (n,)): how far each paired vertex's twin is from where the
    local mirror map of the neighbouring pairs, fitted without the pair itself, puts it."""
    paired = np.flatnonzero(partner >= 0)
    if len(paired) <= NEIGHBOURS:
        return paired, np.zeros(len(paired))
    predicted, _, _ = _predicted_twins(points, partner, paired, cKDTree(points[paired]), paired, leave_out=True)
    return paired, np.linalg.norm(predicted - points[partner[paired]], axis=1)


def _outliers(points, partner, spacing) -> np.ndarray:
    """Paired vertices (N,) bool whose misfit (see ``_misfits``) exceeds OUTLIER x spacing, or
    twice the median misfit where the pairs agree less well (scans whose two sides are
    tessellated differently)."""
    paired, misfit = _misfits(points, partner)
    outliers = np.zeros(len(points), dtype=bool)
    if len(paired):
        outliers[paired] = misfit > max(OUTLIER * spacing, 2.0 * np.median(misfit))
    return outliers


def spread_pairs(points: np.ndarray, correspondence: MirrorCorrespondence, count: int,
                 exclude: np.ndarray | None = None):
    """About ``count`` pairs and midline vertices spread over the surface by farthest-point
    sampling of the left and midline vertices. Returns (left (n,), right (n,), midline (m,)).
    ``exclude``: vertices not to use (e.g. those already holding a landmark)."""
    partner, side = correspondence.partner, correspondence.side
    usable = (side > 0) | ((partner >= 0) & (partner == np.arange(len(points))))
    if exclude is not None:
        usable[exclude] = False
        usable[partner[exclude][partner[exclude] >= 0]] = False
    candidates = np.flatnonzero(usable)
    if len(candidates) > count:
        candidates = np.sort(candidates[farthest_point_order(points[candidates], count)])
    on_midline = side[candidates] == 0
    left = candidates[~on_midline]
    return left, partner[left], candidates[on_midline]


def intrinsic_correspondence(points: np.ndarray, faces: np.ndarray, plane_normal,
                             plane_offset: float) -> MirrorCorrespondence:
    """Mirror twins for a bent or articulated mesh, seeded by the intrinsic mirror map
    (Laplace-Beltrami eigenfunctions, see ``spectral``) started from the plane's map."""
    initial = cKDTree(points).query(reflection_across_plane(points, normalize(np.asarray(plane_normal, dtype=float)),
                                                            plane_offset))[1]
    return mapped_correspondence(points, faces, plane_normal, plane_offset,
                                 *intrinsic_mirror_map(points, faces, initial))


def registered_correspondence(points: np.ndarray, faces: np.ndarray, plane_normal,
                              plane_offset: float) -> MirrorCorrespondence:
    """Mirror twins for a bent, compressed or articulated mesh, seeded by registering its
    reflection onto it (coherent point drift, see ``registration``)."""
    return mapped_correspondence(points, faces, plane_normal, plane_offset,
                                 *registered_mirror_map(points, faces, plane_normal, plane_offset))


def mapped_correspondence(points: np.ndarray, faces: np.ndarray, plane_normal, plane_offset: float,
                          sample: np.ndarray, twin: np.ndarray, round_trip: np.ndarray) -> MirrorCorrespondence:
    """Mirror twins grown (as in :func:`mirror_correspondence`) from the twins ``twin`` (S,) that a
    mirror map gives a sample (S,) of the vertices, kept where the map is its own inverse
    (``round_trip`` (S,): the twin of the twin) and agrees with the local mirror map of the
    neighbouring seeds, then grown again from the pairs longer than REGROW edges (the band
    around the midline predicted from both sides). The plane tells left from right: a twin
    lies on the side its partner's gap points from."""
    points = np.asarray(points, dtype=float)
    plane_normal = normalize(np.asarray(plane_normal, dtype=float))
    spacing = mean_spacing(points, faces)
    consistent = np.linalg.norm(points[round_trip] - points[sample], axis=1) < spacing
    sample, twin = sample[consistent], twin[consistent]
    # A map's pairs this short (and its midline points) are not used; the growth finds them from
    # the pairs around. The eigenfunctions cannot tell a vertex near the midline from its twin a
    # few edges away; the registration's pairs are kept to the same rule.
    far = np.linalg.norm(points[twin] - points[sample], axis=1) > SHORT_PAIR * spacing
    sample, twin = sample[far], twin[far]
    leftward = (points[sample] - points[twin]) @ plane_normal > 0
    pairs = np.unique(np.column_stack([np.where(leftward, sample, twin), np.where(leftward, twin, sample)]),
                      axis=0)  # a pair found from both of its ends counts once
    pairs = pairs[(np.bincount(pairs.ravel(), minlength=len(points))[pairs] == 1).all(axis=1)]  # no vertex in two
    left, right = pairs.T
    partner = np.full(len(points), -1)
    partner[left], partner[right] = right, left
    paired, misfit = _misfits(points, partner)
    agrees = np.zeros(len(points), dtype=bool)
    agrees[paired] = misfit < SEED_AGREEMENT * spacing
    both = agrees[left] & agrees[right]
    grown = mirror_correspondence(points, faces, plane_normal, plane_offset, seed_pairs=(left[both], right[both]))
    left = np.flatnonzero(grown.side > 0)
    right = grown.partner[left]
    long = np.linalg.norm(points[right] - points[left], axis=1) > REGROW * spacing
    return mirror_correspondence(points, faces, plane_normal, plane_offset, seed_pairs=(left[long], right[long]))


def first_correspondences(points: np.ndarray, faces: np.ndarray, normal: np.ndarray, offset: float):
    """Candidate mirror correspondences of a shape with no landmarks, for the first round.

    ``normal`` (3,), ``offset``: the surface's best mirror plane. Yields (name,
    correspondence or the GeometryError that stopped it): 'mirror plane' (right
    for a shape symmetric up to noise), 'whitened mirror plane' (the same after
    whitening: right for a uniformly compressed or sheared one), 'registration'
    (the reflection registered onto the shape: bent, compressed and bent,
    articulated) and, for meshes up to ``INTRINSIC_VERTEX_LIMIT`` vertices,
    'intrinsic' (bent or articulated ones).
    """
    yield "mirror plane", mirror_correspondence(points, faces, normal, offset)
    matrix = whitening(points)
    white = (points - points.mean(axis=0)) @ matrix
    # Whitened, the principal axes say nothing (all variances are 1): start from the most
    # promising of many directions spread over the half sphere.
    starts = promising_normals(white, hemisphere_directions(WHITENED_DIRECTIONS), WHITENED_STARTS)
    white_normal, white_offset = fit_surface_mirror_plane(white, axes=starts)
    yield "whitened mirror plane", mirror_correspondence(white, faces, white_normal, white_offset)
    try:
        yield "registration", registered_correspondence(points, faces, normal, offset)
    except GeometryError as error:
        yield "registration", error
    if not len(faces):
        yield "intrinsic", GeometryError("the intrinsic candidate needs triangles; this is a point cloud")
    elif len(points) > INTRINSIC_VERTEX_LIMIT:
        yield "intrinsic", GeometryError(f"skipped: the mesh has {len(points):,} vertices, the intrinsic "
                                         f"candidate is tried up to {INTRINSIC_VERTEX_LIMIT:,}")
    else:
        try:
            yield "intrinsic", intrinsic_correspondence(points, faces, normal, offset)
        except GeometryError as error:
            yield "intrinsic", error

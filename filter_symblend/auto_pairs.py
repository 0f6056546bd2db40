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
way, and predicts the vertex back. Where that stalls on a mesh whose tessellation
mirrors itself, its own mirror map, grown by the connectivity alone from one right
pair among the seeds, replaces the pairs (a strong bend leaves most seeds slid by a
row; see ``mesh_twins``), and the twins the connectivity implies are taken. Then
pairs that the local maps of their neighbours do not confirm are dropped: one
wrong pair, forced symmetric by the solve, distorts its whole neighbourhood.
Last, on a mesh whose two sides' vertices mirror each other, the vertices still
unpaired (the joint of a swung limb, where the local maps predict too far off)
are paired together by an assignment (see ``twin_assignment``) on where the
connectivity and the pairs around put their twins (``mesh_twins.harmonic_twin_coordinates``).

Units: ``spacing`` is the mean edge length (mean nearest-neighbour distance
for a point cloud); distances below are multiples of it.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.interpolate import RBFInterpolator
from scipy.spatial import cKDTree

from .errors import GeometryError
from .geometry import MIRROR_X, hemisphere_directions, normalize, proper_rotation_fit, reflection_across_plane, whitening
from .mesh_geometry import farthest_point_order, mean_spacing, vertex_normals
from .twin_assignment import assigned_twins
from .mesh_twins import (connectivity_twins, harmonic_twin_coordinates, kept_edge_share, mirrored_tessellation,
                         ring_consistent, single_pairs, tessellation_mirror, vertex_adjacency)
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
# The completion of the correspondence by assignment (``_complete_by_assignment``), for meshes whose
# two sides' vertices mirror each other:
# x spacing: the pairs say so when their median misfit is below this. Measured (edges): the cow and
# spot, symmetric, bent up to 0.6 rad or with a limb swung, 0-0.004; pairs that are wrong in places
# 0.18-0.33; the Igea scan 0.31. Right pairs of spot bent 1.2 rad: about 0.05 after the whitening, where the
# local affine maps follow the bend less well (there the tessellation says so instead).
VERTEX_EXACT_MISFIT = 0.05
# The completion's two twin predictors (see ``_complete_by_assignment``), and the radius (x spacing) its
# candidate twins lie within: the thin-plate spline through the mirror map of the SPLINE_NEIGHBOURS
# nearest pairs (measured when it was the only one, on the cow's joint swung 0.6 rad: 44 wrong twins
# with 32, 52 with 64 or 200, 76 with the local maps instead; radius 1.5: 88, 2.5: 48, 5: 120); and the
# connectivity, in the harmonic coordinates of ``mesh_twins.harmonic_twin_coordinates`` (that joint:
# symmetry error 0.063 % with 1.0 or 1.2, 0.100 % with 1.5).
SPLINE_NEIGHBOURS = 32
SPLINE_RADIUS = 2.5
HARMONIC_RADIUS = 1.2
# The connectivity's twins are taken only if they keep this much more of the mesh's edges than the
# spline's (see ``mesh_twins.kept_edge_share``): a slide keeps edges too, and in a broad hole the spline is right more
# often (recovering a band of known pairs around the holes: 94-98 % against 70-80 %). Measured, the
# connectivity's share minus the spline's: the cow's joint swung 0.6 rad +0.16 (10 wrong twins against
# 66); its whole leg swung 0.3 rad on the output of 20 landmarks -0.09 (128 against 6); the cow bent 0.4
# or 0.6 rad on the output of 10 or 20 landmarks, a first completion of 450-890 vertices +0.03 and +0.04
# (both a quarter wrong or more, the spline fewer: 0.469 % and 0.167 % where taking the larger share
# gave 0.606 % and 0.216 %), the next one +0.13 (the connectivity fewer wrong).
HARMONIC_MARGIN = 0.1
# x spacing: the completion makes no pair this short. pymeshlab's cow has 107 vertices near its
# midline without an exact twin; paired to each other (pairs of 0.6-2.02 edges) they left the
# exactly symmetric cow's shape error at 0.097 % instead of 0.003 %. Pairs across a joint are
# 2.35 edges and longer.
ASSIGNMENT_SHORT = 2.2
# Nor a pair whose twin lies farther from where the local mirror map puts it than ASSIGNMENT_ERROR x
# spacing, or than ASSIGNMENT_RATIO x the distance from there to the vertex itself, whichever is
# larger (a twin must be clearly better than being on the midline). On the cow, the vertices without
# an exact twin got twins 2.2-4.6 edges away, 1.8-5.6 edges from the prediction (ratio 0.6 or more,
# 1 or more for 90 %): they took the exactly symmetric cow's shape error to 0.33 % (0.003 % with
# the bounds). Right twins at a joint swung 0.6 rad lie up to 2.1 edges off (ratio up to 0.65): there
# the symmetry error is 0.063 % with a ratio of 0.7 or 0.8, 0.076 % with 0.6, 0.098 % with 0.5.
ASSIGNMENT_ERROR = 1.0
ASSIGNMENT_RATIO = 0.7
# The completion's normal test: facing the mirrored way at all. With MATCH_COSINE, 4 pairs of the
# exactly symmetric cow whose vertex normals differ from their twins' (its two sides are
# triangulated differently) took each other's twins, 0.4 edges off (shape error 0.021 %).
ASSIGNMENT_COSINE = 0.0
# Share of the vertices that :func:`unmoved_pairs` must pair: a part the deformation left as it was.
# Measured: the cow and spot with a limb swung 0.6 rad, 80 % and 90 %, every pair right (22 of the
# cow's 105 midline points are vertices without an exact twin, within 0.05 edges of the plane); bent
# 0.2 rad or more, with or without a compression, under 1 % (spot bent 0.2 rad: 3 pairs and 11 midline
# points, 1 and 3 of them wrong; without the neighbours' test 36 and 25, 17 and 9 wrong). Holding them
# took the cow with a limb swung 0.6 rad from 0.094 % to 0.063 %.
UNMOVED_SHARE = 0.2
# x spacing: a twin the connectivity implies is taken if the local mirror map puts it this close
# (a sanity bound: on spot with a limb swung 0.6 rad these twins are all right).
CONNECTED_MATCH_DISTANCE = 2.0
FRONTIER = 3.0  # x spacing: vertices this close to the paired region are tried in a wave
# x spacing: an intrinsic seed is kept where the local mirror map of its neighbouring seeds
# predicts its twin this closely. On the cow bent by 1.2 rad, the twins of the eigenfunction
# map alone are within 2.5 edges for 90 % of the pairs and up to 11 edges off; grown from
# the seeds kept (and outliers dropped), 90 % are within 0.6 edges, over half the vertices.
SEED_AGREEMENT = 0.5
# x spacing: intrinsic seeds this short are not used (the eigenfunctions cannot tell a vertex
# near the midline from its twin a few edges away). On spot bent by 0.2 rad, 70 such pairs
# were wrong by 0.2-0.4 edges yet agreed with each other, and left the symmetry error at
# 0.11 %; at 4 edges it is 0.005 % (the cow: 0.002 % either way). The registration's seeds are
# all kept: on the cow under the Figure 1 map (oblique compression crowds the vertices near the
# midline), growing the band instead left 38 vertices paired with a neighbour of their twin, and
# the symmetry error at 0.070 % (with them kept it is exact, the 21 wrong ones among them failing the
# registration's round trip).
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
    exact_twins: whether the pairs say the two sides' vertices mirror each other (median misfit
    below VERTEX_EXACT_MISFIT, see ``_misfits``; or ``tessellated``).
    assigned: number of vertices paired by ``_complete_by_assignment`` after the growth.
    tessellated: whether the pairs are the mesh's own mirror map, read off its connectivity
    (``mesh_twins.tessellation_mirror``).
    """

    partner: np.ndarray
    side: np.ndarray
    seeds: int
    waves: int
    exact_twins: bool = False
    assigned: int = 0
    tessellated: bool = False

    @property
    def paired_fraction(self) -> float:
        return float(np.mean(self.partner >= 0))

    @property
    def grown_fraction(self) -> float:
        """Fraction of the vertices paired by the seeds and the growth alone."""
        return float(np.count_nonzero(self.partner >= 0) - self.assigned) / len(self.partner)


def _agreement(mapped_normals: np.ndarray, normals: np.ndarray, oriented: bool) -> np.ndarray:
    cosine = np.einsum("ni,ni->n", normalize(mapped_normals), normals)
    return cosine if oriented else np.abs(cosine)


def _seed(points, normals, oriented, tree, spacing, plane_normal, plane_offset, exact=False):
    """(partner, side, acceptance distance) of the vertices a single mirror plane pairs reliably
    (``exact``: with the acceptance distance MIN_MATCH_DISTANCE)."""
    n = len(points)
    distance, nearest = tree.query(reflection_across_plane(points, plane_normal, plane_offset))
    index = np.arange(n)
    mutual = nearest[nearest] == index
    if not mutual.any():
        return np.full(n, -1), np.zeros(n, dtype=np.int8), MIN_MATCH_DISTANCE * spacing
    tolerance = spacing * (MIN_MATCH_DISTANCE if exact else np.clip(2.0 * np.median(distance[mutual]) / spacing,
                                                                     MIN_MATCH_DISTANCE, MAX_MATCH_DISTANCE))
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


def _geometric_wave(points, normals, oriented, tree, spacing, tolerance, partner, side, added, paired_tree, paired):
    """New pairs (sources, twins, sides of the sources) near the pairs ``added`` last, where the local
    mirror map predicts a twin within ``tolerance``; None if none."""
    # Only vertices near the pairs added last can get a new prediction: the others' nearest
    # pairs, hence their local maps and their failures, are those of the wave before.
    unpaired = np.flatnonzero(partner < 0)
    gap, _ = cKDTree(points[added]).query(points[unpaired], distance_upper_bound=FRONTIER * spacing)
    sources = unpaired[np.isfinite(gap)]
    if len(sources) == 0:
        return None
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
    keep = (twin == sources) | (votes != 0)
    return single_pairs(len(points), sources[keep], twin[keep], votes[keep])


def _connectivity_wave(points, normals, oriented, spacing, adjacency, partner, side, paired_tree, paired):
    """New pairs (sources, twins, sides of the sources) that the mesh connectivity implies (see
    ``mesh_twins``), where the local mirror map puts the twin within CONNECTED_MATCH_DISTANCE
    and facing the mirrored way; None if none."""
    sources, twin = connectivity_twins(adjacency, partner)
    if len(sources) == 0:
        return None
    predicted, mapped_normals, neighbours = _predict(points, normals, partner, sources, paired_tree, paired)
    close = np.linalg.norm(predicted - points[twin], axis=1) < CONNECTED_MATCH_DISTANCE * spacing
    facing = (twin == sources) | (_agreement(mapped_normals, normals[twin], oriented) > MATCH_COSINE)
    votes = np.sign(side[neighbours].sum(axis=1)).astype(np.int8)
    keep = close & facing & ((twin == sources) | (votes != 0))
    return single_pairs(len(points), sources[keep], twin[keep], votes[keep])


def mirror_correspondence(points: np.ndarray, faces: np.ndarray, plane_normal, plane_offset: float,
                          fixed_pairs: tuple[np.ndarray, np.ndarray] | None = None,
                          fixed_midline: np.ndarray | None = None,
                          seed_pairs: tuple[np.ndarray, np.ndarray] | None = None,
                          complete: bool | None = None) -> MirrorCorrespondence:
    """Mirror twins of the vertices ``points`` (N, 3) of a mesh (``faces`` (F, 3), may be empty).

    ``plane_normal`` (3,), ``plane_offset``: the global mirror plane the seeds come
    from (normal . x = offset; the normal points to the left side). ``fixed_pairs``
    (left (n,), right (n,)) and ``fixed_midline`` (m,): vertex indices of known pairs
    (the user's landmarks), seeded as given and always kept. ``seed_pairs`` (left (k,),
    right (k,)): seeds found otherwise (e.g. by the intrinsic map), used instead of the
    plane's (the plane still sets the acceptance distance). When the geometric growth stalls,
    the tessellation's own mirror map grown from a seed (``mesh_twins.tessellation_mirror``)
    replaces the pairs if there is one, and the landmarks are held. At the end, pairs that
    disagree with the local mirror map of their neighbours are dropped (see ``OUTLIER``),
    unless their rings map onto their twins' on a tessellation that mirrors itself. Then, if
    ``complete`` (None: if the pairs' median misfit or the tessellation says the two sides'
    vertices mirror each other, ``exact_twins``; but a symmetrized output's pairs say so
    whatever the input, so later rounds pass the first round's answer), the vertices left are
    paired by ``_complete_by_assignment``.
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
    seeds = int(np.count_nonzero(partner >= 0))
    no_vertex = np.zeros(0, dtype=np.int64)
    left, right = (no_vertex, no_vertex) if fixed_pairs is None else fixed_pairs
    midline = no_vertex if fixed_midline is None else fixed_midline
    fixed = np.zeros(len(points), dtype=bool)
    fixed[np.concatenate([left, right, midline]).astype(np.int64)] = True

    def hold_landmarks(partner, side):
        """The user's pairs imposed on ``partner``, ``side`` (in place); a vertex paired with a landmark
        vertex otherwise loses its twin."""
        stale = np.isin(partner, np.flatnonzero(fixed))
        partner[stale], side[stale] = -1, 0
        partner[left], partner[right], partner[midline] = right, left, midline
        side[left], side[right], side[midline] = 1, -1, 0

    hold_landmarks(partner, side)
    adjacency = vertex_adjacency(faces, len(points)) if len(faces) else None
    waves = 0
    mirrored = None  # whether the tessellation mirrors itself: decided once the geometric growth stalls
    tessellated = False  # whether the pairs are the tessellation's own mirror map
    added = np.flatnonzero(partner >= 0)
    while np.count_nonzero(partner >= 0) >= 4:
        paired = np.flatnonzero(partner >= 0)
        paired_tree = cKDTree(points[paired])
        found = _geometric_wave(points, normals, oriented, tree, spacing, tolerance, partner, side, added,
                                paired_tree, paired)
        if found is None and adjacency is not None and mirrored is None:
            mirror = tessellation_mirror(adjacency, partner, side)
            mirrored = mirror is not None or mirrored_tessellation(adjacency, partner)
            if mirror is not None:  # the tessellation's own mirror map, from a right pair: it replaces the rest
                partner, side = mirror
                # Its pairs next to where the tessellation stops mirroring (spot's midline strip) can be
                # wrong; the geometric growth pairs them from the rings that map whole.
                _unpair(partner, side, ~ring_consistent(adjacency, partner))
                tessellated = True
                hold_landmarks(partner, side)
                added = np.flatnonzero(partner >= 0)
                continue
        if found is None and mirrored:
            found = _connectivity_wave(points, normals, oriented, spacing, adjacency, partner, side,
                                       paired_tree, paired)
        if found is None:
            break
        s, t, v = found
        partner[s], partner[t] = t, s
        side[s], side[t] = np.where(s == t, 0, v), np.where(s == t, 0, -v)
        added = np.unique(np.concatenate([s, t]))
        waves += 1
    outliers, median_misfit = _outliers(points, partner, spacing)
    outliers &= ~fixed
    if mirrored:
        outliers &= ~ring_consistent(adjacency, partner)
    _unpair(partner, side, outliers)
    exact_twins = bool(median_misfit < VERTEX_EXACT_MISFIT * spacing) or tessellated
    complete = exact_twins if complete is None else complete
    assigned = _complete_by_assignment(points, normals, oriented, spacing, adjacency, partner, side) if complete else 0
    return MirrorCorrespondence(partner, side, seeds, waves, exact_twins, assigned, tessellated)


def _unpair(partner: np.ndarray, side: np.ndarray, vertices: np.ndarray) -> None:
    """Unpair the ``vertices`` (N,) bool and their twins: both ends of each of their pairs (in place)."""
    vertices = vertices | (vertices[np.maximum(partner, 0)] & (partner >= 0))
    partner[vertices], side[vertices] = -1, 0


def _complete_by_assignment(points, normals, oriented, spacing, adjacency, partner, side) -> int:
    """Pair the vertices still unpaired (``partner``, ``side`` updated in place; nothing without
    triangles), by :func:`_complete_with` each twin predictor, :func:`_spline_twins` and
    :func:`_harmonic_twins`, keeping the pairs of the spline unless the connectivity's keep
    HARMONIC_MARGIN more of the mesh's edges (see :func:`mesh_twins.kept_edge_share`). Returns the number of
    vertices paired."""
    if adjacency is None:
        return 0
    trials = []
    for predictor, bias in ((_spline_twins, 0.0), (_harmonic_twins, -HARMONIC_MARGIN)):
        trial = partner.copy(), side.copy()
        count = _complete_with(predictor, points, normals, oriented, spacing, adjacency, *trial)
        trials.append((kept_edge_share(adjacency, partner, trial[0]) + bias if count else -1.0, count, trial))
    _, count, (best_partner, best_side) = max(trials, key=lambda trial: trial[0])
    partner[:], side[:] = best_partner, best_side
    return count


def _spline_twins(points, adjacency, partner, unpaired, paired):
    """(the unpaired vertices predicted, their positions, where their twins are predicted, the
    assignment radius): by the thin-plate spline through the mirror map of the nearest pairs
    (the local maps where it is undefined: those pairs all in one plane)."""
    try:
        predicted = RBFInterpolator(points[paired], points[partner[paired]], kernel="thin_plate_spline",
                                    neighbors=min(SPLINE_NEIGHBOURS, len(paired)))(points[unpaired])
    except np.linalg.LinAlgError:
        predicted = _predicted_twins(points, partner, unpaired, cKDTree(points[paired]), paired)[0]
    return unpaired, points[unpaired], predicted, SPLINE_RADIUS


def _harmonic_twins(points, adjacency, partner, unpaired, paired):
    """The same by the connectivity (:func:`mesh_twins.harmonic_twin_coordinates`)."""
    return (*harmonic_twin_coordinates(adjacency, partner, points), HARMONIC_RADIUS)


def _complete_with(predictor, points, normals, oriented, spacing, adjacency, partner, side) -> int:
    """Pair the vertices still unpaired, ring by ring from the paired region inwards, by
    :func:`twin_assignment.assigned_twins` on where ``predictor`` (:func:`_spline_twins` or
    :func:`_harmonic_twins`) puts their twins (``partner``, ``side`` updated in place). Returns the
    number of vertices paired."""
    before = np.count_nonzero(partner >= 0)
    while True:
        paired = np.flatnonzero(partner >= 0)
        unpaired, own, mirrored, radius = predictor(points, adjacency, partner, np.flatnonzero(partner < 0), paired)
        if len(unpaired) < 2 or len(paired) < NEIGHBOURS:
            break
        predicted, mapped_normals, neighbours = _predict(points, normals, partner, unpaired, cKDTree(points[paired]),
                                                         paired)

        def allowed(rows, columns):
            """Twins near where the local maps put them (see ASSIGNMENT_RATIO), facing the mirrored way."""
            error = np.linalg.norm(predicted[rows] - points[unpaired[columns]], axis=1)
            itself = np.linalg.norm(predicted[rows] - points[unpaired[rows]], axis=1)
            near = error < np.maximum(ASSIGNMENT_ERROR * spacing, ASSIGNMENT_RATIO * itself)
            return near & (_agreement(mapped_normals[rows], normals[unpaired[columns]], oriented) > ASSIGNMENT_COSINE)

        a, b = assigned_twins(own, mirrored, allowed, radius * spacing)
        rim = np.asarray(adjacency[unpaired][:, paired].sum(axis=1)).ravel() > 0
        votes = np.sign(side[neighbours[a]].sum(axis=1)).astype(np.int8)
        long = np.linalg.norm(points[unpaired[a]] - points[unpaired[b]], axis=1) > ASSIGNMENT_SHORT * spacing
        ring = (rim[a] | rim[b]) & long & (votes != 0)
        if not ring.any():
            break
        u, v = unpaired[a[ring]], unpaired[b[ring]]
        partner[u], partner[v] = v, u
        side[u], side[v] = votes[ring], -votes[ring]
    return int(np.count_nonzero(partner >= 0) - before)


def _misfits(points, partner) -> tuple[np.ndarray, np.ndarray]:
    """(paired vertices (n,), misfit (n,)): how far each paired vertex's twin is from where the
    local mirror map of the neighbouring pairs, fitted without the pair itself, puts it."""
    paired = np.flatnonzero(partner >= 0)
    if len(paired) <= NEIGHBOURS:
        return paired, np.zeros(len(paired))
    predicted, _, _ = _predicted_twins(points, partner, paired, cKDTree(points[paired]), paired, leave_out=True)
    return paired, np.linalg.norm(predicted - points[partner[paired]], axis=1)


def _outliers(points, partner, spacing) -> tuple[np.ndarray, float]:
    """Paired vertices (N,) bool whose misfit (see ``_misfits``) exceeds OUTLIER x spacing, or
    twice the median misfit where the pairs agree less well (scans whose two sides are
    tessellated differently); and that median (mesh units, inf if nothing is paired)."""
    paired, misfit = _misfits(points, partner)
    outliers = np.zeros(len(points), dtype=bool)
    if not len(paired):
        return outliers, np.inf
    median = float(np.median(misfit))
    outliers[paired] = misfit > max(OUTLIER * spacing, 2.0 * median)
    return outliers, median


def unmoved_pairs(points: np.ndarray, faces: np.ndarray, plane_normal, plane_offset: float):
    """Where a mesh is still exactly mirror-symmetric across the plane: (left (n,), right (n,),
    midline (m,)).

    The vertices whose reflection lands within MIN_MATCH_DISTANCE edge lengths of a vertex whose own
    reflection lands on them, facing the mirrored way, and whose neighbours are all so paired (a lone
    vertex can land on another by chance): on a shape whose two sides' vertices mirror each other,
    the parts a deformation left as they were (the body beside a swung limb). None unless they pair
    UNMOVED_SHARE of the vertices, nor without triangles.
    """
    points = np.asarray(points, dtype=float)
    none = np.zeros(0, dtype=np.int64)
    if not len(faces):
        return none, none, none
    normals, oriented = vertex_normals(points, faces)
    partner, side, _ = _seed(points, normals, oriented, cKDTree(points), mean_spacing(points, faces),
                             normalize(np.asarray(plane_normal, dtype=float)), plane_offset, exact=True)
    _unpair(partner, side, vertex_adjacency(faces, len(points)) @ (partner < 0).astype(float) > 0)
    if np.count_nonzero(partner >= 0) < UNMOVED_SHARE * len(points):
        return none, none, none
    left = np.flatnonzero(side > 0)
    return left, partner[left], np.flatnonzero(partner == np.arange(len(points)))


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
                                 *intrinsic_mirror_map(points, faces, initial), shortest=SHORT_PAIR)


def registered_correspondence(points: np.ndarray, faces: np.ndarray, plane_normal,
                              plane_offset: float) -> MirrorCorrespondence:
    """Mirror twins for a bent, compressed or articulated mesh, seeded by registering its
    reflection onto it (coherent point drift, see ``registration``)."""
    return mapped_correspondence(points, faces, plane_normal, plane_offset,
                                 *registered_mirror_map(points, faces, plane_normal, plane_offset), shortest=0.0)


def mapped_correspondence(points: np.ndarray, faces: np.ndarray, plane_normal, plane_offset: float,
                          sample: np.ndarray, twin: np.ndarray, round_trip: np.ndarray,
                          shortest: float) -> MirrorCorrespondence:
    """Mirror twins grown (as in :func:`mirror_correspondence`) from the twins ``twin`` (S,) that a
    mirror map gives a sample (S,) of the vertices, kept where the map is its own inverse
    (``round_trip`` (S,): the twin of the twin), the pair is longer than ``shortest`` (x spacing;
    the growth pairs the vertices nearer the midline, and the midline points) and agrees with
    the local mirror map of the neighbouring seeds, then grown again from the pairs longer than
    REGROW edges (the band around the midline predicted from both sides). The plane tells left from right: a twin
    lies on the side its partner's gap points from."""
    points = np.asarray(points, dtype=float)
    plane_normal = normalize(np.asarray(plane_normal, dtype=float))
    spacing = mean_spacing(points, faces)
    consistent = np.linalg.norm(points[round_trip] - points[sample], axis=1) < spacing
    sample, twin = sample[consistent], twin[consistent]
    far = np.linalg.norm(points[twin] - points[sample], axis=1) > shortest * spacing
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
    grown = mirror_correspondence(points, faces, plane_normal, plane_offset, seed_pairs=(left[both], right[both]),
                                  complete=False)
    left = np.flatnonzero(grown.side > 0)
    right = grown.partner[left]
    long = np.linalg.norm(points[right] - points[left], axis=1) > REGROW * spacing
    return mirror_correspondence(points, faces, plane_normal, plane_offset, seed_pairs=(left[long], right[long]),
                                 complete=False)


def first_correspondences(points: np.ndarray, faces: np.ndarray, normal: np.ndarray, offset: float):
    """Candidate mirror correspondences of a shape with no landmarks, for the first round.

    ``normal`` (3,), ``offset``: the surface's best mirror plane. Yields (name,
    correspondence or the GeometryError that stopped it): 'mirror plane' (right
    for a shape symmetric up to noise), 'whitened mirror plane' (the same after
    whitening: right for a uniformly compressed or sheared one), 'registration'
    (the reflection registered onto the shape: bent, compressed and bent,
    articulated) and, for meshes up to ``INTRINSIC_VERTEX_LIMIT`` vertices,
    'intrinsic' (bent or articulated ones). None is completed by the assignment: a
    completion can make a wrong candidate's output look as symmetric as a right one's
    (the cow with a limb swung 0.6 rad: the whitened plane's, 0.68 %, chosen over the
    intrinsic map's); the later rounds complete the one chosen.
    """
    yield "mirror plane", mirror_correspondence(points, faces, normal, offset, complete=False)
    matrix = whitening(points)
    white = (points - points.mean(axis=0)) @ matrix
    # Whitened, the principal axes say nothing (all variances are 1): start from the most
    # promising of many directions spread over the half sphere.
    starts = promising_normals(white, hemisphere_directions(WHITENED_DIRECTIONS), WHITENED_STARTS)
    white_normal, white_offset = fit_surface_mirror_plane(white, axes=starts)
    yield "whitened mirror plane", mirror_correspondence(white, faces, white_normal, white_offset, complete=False)
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

"""Every vertex's twin under the chosen mirror map, with a confidence from the map's own evidence.

Every vertex the map predicts a twin for is given one: the point of the surface nearest the prediction, a
vertex where the map lands within a tenth of an edge of one that is unambiguous and mutual (a mirrored
tessellation), else a point inside a triangle. The map *supports* its twin where the prediction lands on the
surface, within the landing tolerance, facing the mirrored way (:mod:`.twins`); elsewhere (a thin finger whose
carried normal flips, a limb the map misses) the twin is still the map's best guess, mostly right on a posed
body, with confidence 0. A supported twin need not come back: the round trip's error lowers its confidence.
(On the BCICP shapes, listing twins that fail the round trip raised the right twins of the 18 kept to check
from 89 % to 90 %, victoria2's from 73 % to 80 %; listing the unsupported ones raised ten shapes of the other
half from 0.901 to 0.911 on average, tr_reg_066 from 0.945 to 0.978; none fell.) A supported twin's
confidence weighs three kinds of evidence, each a length in units of the local vertex spacing ``s`` (a twin a
whole edge off is a wrong twin, whatever the mesh's size or resolution):

- the round trip: the twin's own twin, ``m(m(x))``, against ``x``;
- the landing: how far off the surface the map's prediction fell;
- the neighbours: where the affine map fitted to the ``local_neighbours`` nearest other pairs
  (leave-one-out) puts the twin, against the twin (a map that tears, or folds a limb onto the wrong one,
  disagrees with its neighbours).

``confidence = exp(-(e_trip^2 + e_land^2 + e_neighbours^2) / 2)`` with each error in units of ``s``:
1 where the map is exactly an involution that lands on the surface and is locally affine, 0.61 for
one error of an edge, below 0.5 (:data:`~filter_symblend.core.mirror_pairs.CONFIDENT`) beyond about
1.2 edges in all.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial import cKDTree

from ..core.mirror_pairs import CONFIDENT, DOUBTFUL_SHARE, MirrorPairs
from ..core.report import MirrorMapReport
from ..core.surface_points import on_surface
from .config import AutoConfig
from .growth import LOCAL_MAP_RIDGE, affine_mirror_maps
from .maps import MirrorMap
from .rivals import Rival, rival_agreement
from .surface import Surface
from .twins import find_twins


def _neighbour_misfit(positions: np.ndarray, twins: np.ndarray, config: AutoConfig) -> np.ndarray:
    """(k,) distance from each twin (k, 3) to where the affine map of the nearest other pairs puts it."""
    k = min(config.local_neighbours + 1, len(positions))
    if k < 5:
        return np.zeros(len(positions))
    _, nearest = cKDTree(positions).query(positions, k=k)
    others = nearest[:, 1:]
    predicted, _ = affine_mirror_maps(positions[others], twins[others], np.ones(others.shape), positions,
                                      LOCAL_MAP_RIDGE)
    return np.linalg.norm(predicted - twins, axis=1)


def evidence(mirror: MirrorMap, sources: np.ndarray, config: AutoConfig, tolerance: float):
    """(twins of ``sources`` (:class:`.twins.Twins`), supported (m,) bool: the prediction faces the mirrored
    way and lands within ``tolerance``, errors (m, 3) in units of the local spacing: round trip, landing,
    neighbours (0 where not supported))."""
    surface = mirror.surface
    twins = find_twins(mirror, sources, tolerance)
    supported = twins.facing & (twins.landing <= tolerance)
    errors = np.zeros((len(sources), 3))
    rows = np.flatnonzero(supported)
    if not len(rows):
        return twins, supported, errors
    spacing = np.maximum(surface.local_spacing[sources[rows]], 1e-12 * surface.diagonal)
    positions, point = surface.points[sources[rows]], twins.point[rows]
    back = surface.nearest_points(twins.returned[rows])[0]
    errors[rows, 0] = np.linalg.norm(back - positions, axis=1) / spacing
    errors[rows, 1] = twins.landing[rows] / spacing
    errors[rows, 2] = _neighbour_misfit(positions, point, config) / spacing
    return twins, supported, errors


@dataclasses.dataclass(frozen=True)
class _Candidate:
    """One map's twins of the source vertices (m,): ``listed`` (m,) bool (a twin is given), ``supported`` (m,)
    bool (the map supports it: :func:`evidence`), ``corners`` and barycentric ``weights`` (m, 3) on the input,
    ``point`` (m, 3) the twin there, ``errors`` (m, 3) the evidence in local spacings, ``confidence`` (m,) (0
    where not supported), ``landed`` (m,) bool: the prediction landed within the tolerance."""

    listed: np.ndarray
    supported: np.ndarray
    corners: np.ndarray
    weights: np.ndarray
    point: np.ndarray
    errors: np.ndarray
    confidence: np.ndarray
    landed: np.ndarray

    def where(self, better: np.ndarray, other: _Candidate) -> _Candidate:
        """Per source, ``other``'s twin where ``better`` (m,) bool, else this one's; landed by either."""
        rows = better[:, None]
        return _Candidate(np.where(better, other.listed, self.listed),
                          np.where(better, other.supported, self.supported),
                          np.where(rows, other.corners, self.corners),
                          np.where(rows, other.weights, self.weights), np.where(rows, other.point, self.point),
                          np.where(rows, other.errors, self.errors),
                          np.where(better, other.confidence, self.confidence), self.landed | other.landed)


def _candidate(mirror: MirrorMap, geometry: Surface, sources: np.ndarray, forbidden: np.ndarray,
               config: AutoConfig, rivals: list[Rival]) -> _Candidate:
    """``mirror``'s twins of the ``sources`` on ``geometry``, none on a ``forbidden`` vertex, with their
    confidence, lowered where ``rivals`` put the twin elsewhere (:func:`.rivals.rival_agreement`)."""
    tolerance = config.landing_tolerance * geometry.diagonal
    twins, supported, errors = evidence(mirror, sources, config, tolerance)
    listed = np.isfinite(twins.landing) & ~forbidden[twins.corners].any(axis=1)  # a finite prediction
    supported &= listed
    corners, weights = twins.corners.copy(), twins.weights.copy()
    # A twin that is a vertex (a mirrored tessellation: within a tenth of an edge, unambiguous, mutual) is that
    # vertex, not the point of a triangle the prediction's rounding reached.
    exact = twins.exact_vertex()
    corners[exact] = twins.vertex[exact, None]
    weights[exact] = [1.0, 0.0, 0.0]
    point = on_surface(geometry.points, corners, weights)
    confidence = _confidence(errors, geometry, sources, point, rivals)
    return _Candidate(listed, supported, corners, weights, point, errors, np.where(supported, confidence, 0.0),
                      twins.landing <= tolerance)


def _confidence(errors: np.ndarray, geometry: Surface, sources: np.ndarray, twins: np.ndarray,
                rivals: list[Rival]) -> np.ndarray:
    """(m,) ``exp(-(sum of the squared errors (m, 3))/2)`` (see the module doc), lowered where ``rivals`` put the
    twins (m, 3) of the ``sources`` (m,) elsewhere."""
    confidence = np.exp(-0.5 * np.sum(errors**2, axis=1))
    if rivals:
        spacing = np.maximum(geometry.local_spacing[sources], 1e-12 * geometry.diagonal)
        confidence *= rival_agreement(rivals, geometry.points[sources], twins, spacing)
    return confidence


def _vertex_map_candidate(partner: np.ndarray, geometry: Surface, sources: np.ndarray, forbidden: np.ndarray,
                          config: AutoConfig, rivals: list[Rival]) -> _Candidate:
    """The twins of the ``sources`` (m,) under a vertex map ``partner`` (N,) (-1: none), none on a ``forbidden``
    vertex, with the confidence of :func:`_candidate`'s evidence: the round trip ``partner[partner[x]]`` and the
    neighbours' affine map (a vertex map lands on the surface by construction). Infinite errors (no twin, or no
    way back) give confidence 0."""
    twin = partner[sources]
    listed = (twin >= 0) & ~forbidden[np.maximum(twin, 0)]
    rows = np.flatnonzero(listed)
    errors = np.full((len(sources), 3), np.inf)
    spacing = np.maximum(geometry.local_spacing[sources[rows]], 1e-12 * geometry.diagonal)
    positions, point = geometry.points[sources[rows]], geometry.points[twin[rows]]
    back = partner[twin[rows]]
    errors[rows, 0] = np.where(back >= 0, np.linalg.norm(geometry.points[back] - positions, axis=1), np.inf) / spacing
    errors[rows, 1] = 0.0
    errors[rows, 2] = _neighbour_misfit(positions, point, config) / spacing
    corners = np.where(listed, twin, 0)[:, None].repeat(3, axis=1)
    weights = np.zeros((len(sources), 3))
    weights[:, 0] = 1.0
    twins = geometry.points[corners[:, 0]]
    supported = listed & np.isfinite(errors[:, 0])
    return _Candidate(listed, supported, corners, weights, twins, errors,
                      _confidence(errors, geometry, sources, twins, rivals), listed)


def mirror_pairs(mirror: MirrorMap, geometry: Surface, forbidden: np.ndarray, config: AutoConfig,
                 rivals: list[Rival] = (), second: MirrorMap | None = None,
                 vertex_map: np.ndarray | None = None, posed: bool = False) -> MirrorPairs:
    """The twins of every pairable vertex of ``geometry`` (the input surface; ``mirror`` may live on a
    symmetrized output of it) that ``mirror`` predicts one for, with confidence 0 where it does not support it
    (see the module doc), none on or toward a ``forbidden`` (N,) bool vertex;
    duplicates of a vertex take its twin. Other symmetries that fit about as well (``rivals``, maps on
    ``geometry``) lower the confidence where they put the twin elsewhere (:func:`.rivals.rival_agreement`).
    A ``second`` map (the intrinsic mirror) gives the twin of each vertex where its own evidence is stronger (a
    hand the chosen map of space lost, which the intrinsic mirror follows), and where ``mirror`` gives none; unless
    the shape is ``posed`` (``mode='articulated'``), only where ``mirror``'s twin is not confident. A pose is an
    isometry, the intrinsic mirror's model, and a field can land a swung limb consistently on the wrong place; a
    bend or a compression is the map of space's, and there the intrinsic mirror's twins (right to a vertex or two,
    off under a compression) replaced a registered field's finer twins with confident wrong ones (spot remeshed,
    bent 1.2 rad: 59 % of the twins within 1 % of the diagonal, 20 % confident and off by 2 %, against 72 % and 6 %
    where the field's confident twins stand; docs/benchmarks.md). A ``vertex_map`` (N,) (the intrinsic mirror's
    own, :func:`.intrinsic_map.intrinsic_vertex_map`) is a third opinion, by the same rule. The report's
    ``coverage`` and ``consistency`` count supported twins."""
    sources = np.flatnonzero(geometry.usable & ~forbidden)
    chosen = _candidate(mirror, geometry, sources, forbidden, config, rivals)
    name = mirror.name
    opinions = []
    if second is not None and second is not mirror:
        opinions.append((second.name, _candidate(second, geometry, sources, forbidden, config, rivals)))
    if vertex_map is not None:
        opinions.append(("intrinsic vertex map",
                         _vertex_map_candidate(vertex_map, geometry, sources, forbidden, config, rivals)))
    for other_name, other in opinions:
        stronger = (other.confidence > chosen.confidence) & (posed | (chosen.confidence < CONFIDENT))
        better = stronger | (~chosen.listed & other.listed)
        if better.any():
            chosen = chosen.where(better, other)
            name += f"; the {other_name} for {np.count_nonzero(better) / len(sources):.0%} of the vertices"
    listed = chosen.listed
    rows = np.flatnonzero(listed)
    # Every vertex at a listed vertex's position (an OBJ's seam duplicates) takes its twin.
    row_of = np.full(len(geometry.points), -1)
    row_of[sources[rows]] = rows
    vertex = np.flatnonzero(row_of[geometry.representative] >= 0)
    rows = row_of[geometry.representative[vertex]]
    pairable = max(len(sources), 1)
    confident = chosen.confidence[listed] >= CONFIDENT
    errors = chosen.errors[listed]
    supported = chosen.supported[listed]
    summary = MirrorMapReport(name, float(np.count_nonzero(supported) / pairable),
                              float(np.count_nonzero(supported) / max(np.count_nonzero(chosen.landed), 1)),
                              float(np.count_nonzero(confident) / pairable), CONFIDENT,
                              dict(zip(("round_trip", "landing", "neighbours"),
                                       np.median(errors[supported], axis=0).tolist() if supported.any()
                                       else [None] * 3)),
                              {rival.mirror.name: rival.share for rival in rivals})
    return MirrorPairs(vertex, chosen.point[rows], chosen.corners[rows], chosen.weights[rows],
                       chosen.confidence[rows], len(geometry.points), summary)


def doubtful_map_warning(report: MirrorMapReport) -> str | None:
    """The warning a result deserves when too little of its map is confident (``report``: a
    :class:`MirrorPairs` report), or None."""
    share = report.confident_share
    if share >= DOUBTFUL_SHARE:
        return None
    return (f"only {share:.0%} of the surface has a confident mirror twin (map: {report.map}); the automatic pairs "
            "may mirror the wrong parts. Write them with `symblend pairs MESH -o pairs.pp` (find_mirror_pairs in "
            "Python), check and correct them in MeshLab's PickPoints, then symmetrize with -l pairs.pp; or place "
            "landmark pairs where the per-vertex symblend_pair_confidence is low.")

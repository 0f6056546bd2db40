"""The first mirror map of a shape with no landmarks: candidate maps, each registered, one score.

Every map is judged by one score over the whole surface: the share of it that the map mirrors (the
twin lands on the surface within ``landing_tolerance``, the map comes back, and the two face the
mirrored way). A plane that mirrors a body of revolution but not the parts on its sides loses to the
plane through the parts; a plane that mirrors the middle of a bent shape loses to a map that follows
the bend. The candidates, cheapest first:

1. The reflections across the best mirror planes of the surface, and across the plane of the whitened
   shape (a shape compressed or sheared as a whole). On a mesh whose tessellation mirrors itself, the
   tessellation's own mirror grown from their vertex twins (:mod:`.connectivity`) is exact whatever
   the bend, and ends the search; so does a plain map that mirrors ``plane_suffices`` of the surface
   (a rigid pose, a scan: a non-rigid map could mirror little more, and would slide on a round shape).
2. Otherwise the shape's intrinsic mirror (:mod:`.intrinsic_map`: its denoised vertex pairs and the
   local maps between them), which follows a swung limb and a bend where no plane does, is scored as it
   is; and each rough guess starts a smooth mirror field, registered onto the surface (:mod:`.field`):
   the plain maps; the coherent point drift of the best plane (:mod:`.registration`: a strong bend
   with a compression, which ICP from a plane does not reach); the intrinsic mirror; the drift of the
   second plane. The fields are compared registered on a small sample with a coarse field; the best is
   registered again on more vertices with finer fields, and kept unless the intrinsic mirror mirrors
   more of the surface (a swung limb, which no smooth field follows).

A shape that no map mirrors over ``min_coverage`` of its surface is refused; so is one that only a
registered field mirrors that much, but not within ``field_precision`` of the tolerance (a field fitted
onto any surface lands much of it somewhere: 80 % of a bunny).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..core.mesh_graph import one_pair_per_vertex
from ..core.mirror_planes import surface_mirror_planes
from ..errors import SymmetryNotFoundError
from .config import AutoConfig
from .connectivity import tessellation_mirror
from .field import MirrorField, field_centres, refitted, register, robust_fit, robust_tolerance
from .intrinsic_map import intrinsic_pairs
from .maps import MirrorMap, affine_map, field_map, pairs_map, plane_map, point_pairs_map
from .registration import MIN_DEVIATION, POOL, SAMPLES, coherent_point_drift, registration_sample
from .rivals import Rival, close_rivals
from .surface import Outline, Surface
from .twins import find_twins


def _strided(surface: Surface, count: int) -> np.ndarray:
    """At most ``count`` usable vertices, evenly strided (sorted)."""
    usable = surface.usable_index
    return usable if len(usable) <= count else usable[np.linspace(0, len(usable) - 1, count).astype(np.int64)]


def coverage(mirror: MirrorMap, sources: np.ndarray, config: AutoConfig, share: float = 1.0) -> float:
    """Share of the ``sources`` (m,) vertices that ``mirror`` mirrors (see the module doc), within ``share`` x
    the landing tolerance."""
    tolerance = share * config.landing_tolerance * mirror.surface.diagonal
    return float(np.mean(find_twins(mirror, sources, tolerance).covered(tolerance)))


def tessellation_map(surface: Surface, maps: list[MirrorMap], sources: np.ndarray, config: AutoConfig) -> MirrorMap | None:
    """The mirror map of the tessellation (:func:`.connectivity.tessellation_mirror`), grown from the vertex
    twins one of the geometric ``maps`` gives at the ``sources`` (tried in turn), or None: a point cloud, or a
    tessellation that does not mirror itself (a growth covering it cannot arise by chance, so any twin that
    passes the ratio test may seed it)."""
    if not surface.is_mesh:
        return None
    tolerance = config.landing_tolerance * surface.diagonal
    for mirror in maps:
        twins = find_twins(mirror, sources, tolerance)
        covered = twins.covered(tolerance)
        precision = robust_tolerance(twins.landing[covered], config.coincident * surface.diagonal)
        exact = twins.exact_vertex(precision, strict=False) & covered
        partner = np.full(len(surface.points), -1)
        seeds, twin = one_pair_per_vertex(sources[exact], twins.vertex[exact])
        partner[seeds], partner[twin] = twin, seeds
        mirrored = tessellation_mirror(surface.adjacency, partner, surface.usable)
        if mirrored is not None:
            return pairs_map(surface, mirrored, mirror.normal, config, "tessellation mirror")
    return None


def intrinsic_mirror_map(surface: Surface, normal: np.ndarray, config: AutoConfig) -> MirrorMap | None:
    """The intrinsic mirror's sound pairs as a map (:mod:`.intrinsic_map`), the left side along ``normal``;
    None for a point cloud, a mesh without a spectrum, or too few pairs to start a field."""
    pairs = intrinsic_pairs(surface, config)
    if pairs is None or len(pairs[0]) < config.screening_centres:
        return None
    return point_pairs_map(surface, *pairs, normal, config, "intrinsic mirror")


def _drift_predictions(start: MirrorMap, x: np.ndarray) -> np.ndarray:
    """Twin positions (m, 3) of ``x`` (m, 3) under ``start`` corrected by coherent point drift."""
    surface = start.surface
    sample = registration_sample(surface, SAMPLES, POOL)
    points, normals = surface.points[sample], surface.normals[sample]
    drift = coherent_point_drift(points, start.predict(points), normals, start.mirror_normals(normals, points),
                                 MIN_DEVIATION * surface.spacing)
    return drift(start.predict(x))


def _starts(surface: Surface, sample: np.ndarray, ranked: list[MirrorMap], intrinsic: MirrorMap | None,
            config: AutoConfig):
    """(name, vertices, twin positions) of each rough guess, cheapest first (see the module doc)."""
    x = surface.points[sample]
    for mirror in ranked:
        yield mirror.name, sample, mirror.predict(x)
    yield f"drift from the {ranked[0].name}", sample, _drift_predictions(ranked[0], x)
    if intrinsic is not None:
        yield intrinsic.name, sample, intrinsic.predict(x)
    for mirror in ranked[1:2]:
        yield f"drift from the {mirror.name}", sample, _drift_predictions(mirror, x)


def registered_field(surface: Surface, sample: np.ndarray, field: MirrorField, config: AutoConfig) -> MirrorField:
    """``field`` carried through ``config.field_widths`` (coarse to fine) on ``field_centres`` centres,
    registered at each on the ``sample`` vertices."""
    centres = field_centres(surface, sample, config.field_centres)
    for width in config.field_widths:
        field = refitted(field, surface.points[sample], centres, width * surface.diagonal)
        register(field, surface, sample, config.field_iterations, config)
    return field


class FirstMap(NamedTuple):
    """The map that mirrors the most of the surface (``map``), {name: share mirrored} of every candidate tried
    (``shares``), the surface's best mirror plane (normal, offset), the other symmetries that mirror about as
    much (``rivals``, :mod:`.rivals`), and the intrinsic mirror if it was computed (``intrinsic``: a second
    opinion on each vertex's twin, :func:`.confidence.mirror_pairs`)."""

    map: MirrorMap
    shares: dict
    plane: tuple
    rivals: list[Rival]
    intrinsic: MirrorMap | None = None


def first_map(surface: Surface, scored: np.ndarray, config: AutoConfig, progress=None) -> FirstMap:
    """The first mirror map (see the module doc); SymmetryNotFoundError when none mirrors ``min_coverage`` of
    the surface. ``scored`` (m,): the vertices the shares are measured on."""
    planes = surface_mirror_planes(surface.points[surface.usable_index])
    rigid = [plane_map(surface, *plane, name="mirror plane" if rank == 1 else f"mirror plane {rank}")
             for rank, plane in enumerate(planes[:3], 1)]
    if not isinstance(surface, Outline):  # a flat shape's mirrors are lines of its plane: the planes find them
        rigid.append(affine_map(surface))
    shares = {mirror.name: coverage(mirror, scored, config) for mirror in rigid}
    ranked = sorted(rigid, key=lambda mirror: -shares[mirror.name])
    mirrored = tessellation_map(surface, ranked[:2], scored, config)
    if mirrored is not None:  # the tessellation mirrors itself: its own mirror, exact whatever the bend
        shares[mirrored.name] = coverage(mirrored, scored, config)
        return FirstMap(mirrored, shares, planes[0], close_rivals(mirrored, rigid, shares, scored, config))
    if shares[ranked[0].name] >= config.plane_suffices:
        best = _refuse_or(ranked[0], shares, config)
        return FirstMap(best, shares, planes[0], close_rivals(best, rigid, shares, scored, config))
    intrinsic = intrinsic_mirror_map(surface, ranked[0].normal, config)
    if intrinsic is not None:
        shares[intrinsic.name] = coverage(intrinsic, scored, config)
    screening = _strided(surface, config.screening_samples)
    coarse = config.field_widths[0] * surface.diagonal
    centres = field_centres(surface, screening, config.screening_centres)
    candidates = []
    # A scan (a plane mirrors most of it) stops at the first field that mirrors as much as a plane would
    # need to; the costlier starts are for shapes no plane mirrors (a strong bend).
    enough = config.plane_suffices if shares[ranked[0].name] >= config.min_coverage else config.field_suffices
    for index, (name, vertices, twins) in enumerate(_starts(surface, screening, ranked, intrinsic, config)):
        if progress is not None:
            progress(min(60.0, 8.0 * index), f"finding a mirror map: {name}")
        field = robust_fit(surface.points[vertices], twins, centres, coarse)
        register(field, surface, screening, config.field_iterations, config)
        mirror = field_map(surface, field, f"registration from the {name}")
        shares[mirror.name] = coverage(mirror, scored, config)
        candidates.append((mirror, field))
        if shares[mirror.name] >= enough:
            break
    coarse_best, field = max(candidates, key=lambda entry: shares[entry[0].name])
    if progress is not None:
        progress(60.0, f"{coarse_best.name}, on {config.registration_samples} vertices")
    sample = _strided(surface, config.registration_samples)
    best = field_map(surface, registered_field(surface, sample, field, config), coarse_best.name)
    share = coverage(best, scored, config)
    if share >= shares[best.name]:  # finer fields mirror at least as much, as a rule; if not, the coarse one stays
        shares[best.name] = share
    else:
        best = coarse_best
    if intrinsic is not None and shares[intrinsic.name] > shares[best.name]:
        best = intrinsic  # a swung limb: the pairs follow it, no smooth field does
    tried = rigid + [mirror for mirror, _ in candidates] + ([] if intrinsic is None else [intrinsic])
    mirrored = tessellation_map(surface, [best], scored, config)
    if mirrored is not None:
        shares[mirrored.name] = coverage(mirrored, scored, config)
        return FirstMap(mirrored, shares, planes[0], _rivals(mirrored, tried + [best], shares, scored, config),
                        intrinsic)
    rigid_share = max(shares[mirror.name] for mirror in rigid)
    # A plain map that mirrors min_coverage shows a symmetry up to the scan's noise; else the field must
    # prove it within its own precision.
    best = _refuse_or(best, shares, config, None if rigid_share >= config.min_coverage else scored)
    return FirstMap(best, shares, planes[0], _rivals(best, tried, shares, scored, config), intrinsic)


def _rivals(best: MirrorMap, tried: list[MirrorMap], shares: dict, scored: np.ndarray,
            config: AutoConfig) -> list[Rival]:
    """:func:`.rivals.close_rivals` among the maps ``tried``, each once (the finer registration of a coarse
    candidate has its name, and its share)."""
    by_name = {mirror.name: mirror for mirror in tried}
    return close_rivals(best, list(by_name.values()), shares, scored, config)


def _refuse_or(best: MirrorMap, shares: dict, config: AutoConfig, scored: np.ndarray | None = None) -> MirrorMap:
    """``best``, or SymmetryNotFoundError if it mirrors less than ``min_coverage`` of the surface: within the
    landing tolerance, and for a registered field (which lands where it lands by fitting: give the ``scored``
    vertices) within ``field_precision`` of it too."""
    share = shares[best.name]
    listed = ", ".join(f"{name} {value:.0%}" for name, value in shares.items())
    found = f"mirrors {share:.0%} of the surface within {100 * config.landing_tolerance:g}% of its size"
    needs = f"needs {config.min_coverage:.0%}"
    refused = share < config.min_coverage
    if scored is not None and not refused:
        tolerance = config.field_precision * config.landing_tolerance
        precise = shares[f"{best.name}, within {100 * tolerance:g}%"] = coverage(best, scored, config,
                                                                                 config.field_precision)
        refused = precise < config.precise_coverage
        found += (f" but {precise:.0%} within {100 * tolerance:g}%, where a field fitted onto the surface lands "
                  "on a symmetric shape")
        needs = f"needs {config.precise_coverage:.0%} there"
    if refused:
        raise SymmetryNotFoundError(
            f"No mirror symmetry found: the best mirror map ({best.name}) {found} ({listed}); a mirror-symmetric "
            f"shape, even bent or compressed, {needs}. Place landmark pairs and use pairs='landmarks' "
            "(or 'landmarks+auto').")
    return best

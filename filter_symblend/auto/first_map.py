"""The first mirror map of a shape with no landmarks: candidate maps, one score, one rule.

Every map is judged by one score over the whole surface: the share of it that the map mirrors (the
twin lands on the surface within ``landing_tolerance``, the map comes back, and the two face the
mirrored way). A plane that mirrors a body of revolution but not the parts on its sides loses to the
plane through the parts; a plane that mirrors the middle of a bent shape loses to a map that follows
the bend. One rule chooses: the candidates are made cheapest first, each scored, until one mirrors
enough of the surface that no other could mirror much more (``plane_suffices``, or ``field_suffices`` where no
plain map mirrors ``min_coverage``: a strong bend, where a field can mirror 95 % and still slide; and on a posed
body, where a plane that mirrors 95 % can leave a swung limb unpaired); the one that
mirrors the most of all those made is the map, refused if it mirrors less than ``min_coverage``. The
candidates, in order:

1. The reflections across the best mirror planes of the surface, and across the plane of the whitened
   shape (a shape compressed or sheared as a whole).
2. On a mesh whose tessellation mirrors itself, the tessellation's own mirror grown from the two best
   plain maps' vertex twins (:mod:`.connectivity`): exact whatever the bend, it ends the search if a smooth
   field through its twins mirrors ``field_suffices`` of the surface (:func:`smoothed_coverage`: a tessellation
   can mirror itself across a plane the shape does not, an icosphere carrying unlike parts; otherwise the
   search goes on, and step 4 grows it again from the best map).
3. Mirror fields, each started from a rough guess and registered onto the surface on a small sample with a
   coarse field (:mod:`.field`): from each plain map; where the shape may be compressed (not a posed body), from
   the coherent point drift of the best plane (:mod:`.registration`: a strong bend with a compression, which ICP
   from a plane does not reach); then the shape's intrinsic mirror itself (:mod:`.intrinsic_map`: its denoised
   vertex pairs and the local maps between them, which follow a swung limb where no smooth field does) and a
   field from it; where the shape may be compressed, a field from the drift of the second plane, and if the
   whitened plane mirrors more than any plane, the intrinsic mirror of the whitened shape (a compression oblique
   to the mirror breaks the symmetry of surface distances, whitening restores it) and a field from it.
4. Last, the best field registered again on more vertices with finer fields and, unless the shape is a posed
   body, let slide along the surface toward its twins (:func:`.field.register`; it takes the
   coarse one's place if it mirrors at least as much), and the tessellation's own mirror grown from the best map's
   twins. An intrinsic mirror chosen is sharpened by the field that mirrors the most where that field lands
   precisely and agrees with it (:func:`.maps.sharpened_map`).

The intrinsic mirror is a candidate of every shape no plane mirrors, even when a field suffices before it
(it is computed anyway: its opinion on each twin is kept, :func:`.confidence.mirror_pairs`), in a thread beside
the fields from the moment no plane suffices. A registered field that mirrors ``min_coverage`` must also do so
within ``field_precision`` of the tolerance, unless a plain map mirrors that much (a field fitted onto any
surface lands much of it somewhere: 80 % of a bunny). On a posed body a registered field chosen so gives way to the
intrinsic mirror when the intrinsic mirror passes the same two tests itself (:func:`_intrinsic_if_sound`: a field can
slide along the surface, an isometry pairs vertex with vertex).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..core.mesh_graph import one_pair_per_vertex
from ..core.mirror_planes import surface_mirror_planes
from ..core.parallel import Beside
from ..errors import SymmetryNotFoundError
from .config import AutoConfig
from .connectivity import tessellation_mirror
from .field import MirrorField, field_centres, refitted, register, robust_fit, robust_tolerance
from .intrinsic_map import intrinsic_pairs
from .maps import (WHITENED_PLANE, MirrorMap, affine_map, field_map, pairs_map, plane_map, point_pairs_map,
                   sharpened_map)
from .registration import MIN_DEVIATION, POOL, SAMPLES, coherent_point_drift, registration_sample
from .rivals import Rival, close_rivals
from .surface import Outline, Surface
from .twins import covered_by, find_twins


TESSELLATION = "tessellation mirror"  # the name of the tessellation's own mirror map


def _strided(surface: Surface, count: int) -> np.ndarray:
    """At most ``count`` usable vertices, evenly strided (sorted)."""
    usable = surface.usable_index
    return usable if len(usable) <= count else usable[np.linspace(0, len(usable) - 1, count).astype(np.int64)]


def coverage(mirror: MirrorMap, sources: np.ndarray, config: AutoConfig, share: float = 1.0) -> float:
    """Share of the ``sources`` (m,) vertices that ``mirror`` mirrors (see the module doc), within ``share`` x
    the landing tolerance."""
    tolerance = share * config.landing_tolerance * mirror.surface.diagonal
    return float(np.mean(covered_by(mirror, sources, tolerance)))


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
            return pairs_map(surface, mirrored, mirror.normal, config, TESSELLATION)
    return None


def smoothed_coverage(mirror: MirrorMap, x: np.ndarray, centres: np.ndarray, sources: np.ndarray,
                      config: AutoConfig) -> float:
    """The share of the ``sources`` (m,) that a mirror field on ``centres`` (c, 3), fitted through ``mirror``'s
    twins of the positions ``x`` (s, 3) at the finest width, mirrors: the geometric score of a vertex map, whose
    own share says little (its twins are vertices, on the surface and mutual by construction). A tessellation that
    mirrors itself across a plane the shape does not fails it where the parts it swaps differ (a bent body of
    revolution carrying a knob and a ridge: 95 %); the shape's own mirror, bent, compressed or posed, passes
    (96-100 %)."""
    field = robust_fit(x, mirror.predict(x), centres, config.field_widths[-1] * mirror.surface.diagonal)
    return coverage(field_map(mirror.surface, field, mirror.name), sources, config)


INTRINSIC = "intrinsic mirror"  # the names of the intrinsic mirror's map and of the whitened shape's
WHITENED_INTRINSIC = "intrinsic mirror of the whitened shape"


def intrinsic_mirror_map(surface: Surface, normal: np.ndarray, config: AutoConfig,
                         whitened: bool = False) -> MirrorMap | None:
    """The intrinsic mirror's sound pairs as a map (:mod:`.intrinsic_map`; ``whitened``: the whitened shape's
    mirror), the left side along ``normal``; None for a point cloud, a mesh without a spectrum, or too few pairs
    to start a field."""
    pairs = intrinsic_pairs(surface, config, whitened)
    if pairs is None or len(pairs[0]) < config.screening_centres:
        return None
    return point_pairs_map(surface, *pairs, normal, config, WHITENED_INTRINSIC if whitened else INTRINSIC)


def _drift_predictions(start: MirrorMap, x: np.ndarray) -> np.ndarray:
    """Twin positions (m, 3) of ``x`` (m, 3) under ``start`` corrected by coherent point drift."""
    surface = start.surface
    sample = registration_sample(surface, SAMPLES, POOL)
    points, normals = surface.points[sample], surface.normals[sample]
    drift = coherent_point_drift(points, start.predict(points), normals, start.mirror_normals(normals, points),
                                 MIN_DEVIATION * surface.spacing)
    return drift(start.predict(x))


def registered_field(surface: Surface, sample: np.ndarray, field: MirrorField, config: AutoConfig,
                     sliding: bool) -> MirrorField:
    """``field`` carried through ``config.field_widths`` (coarse to fine) on ``field_centres`` centres,
    registered at each on the ``sample`` vertices, let slide or not (``sliding``, :func:`.field.register`)."""
    centres = field_centres(surface, sample, config.field_centres)
    for width in config.field_widths:
        field = refitted(field, surface.points[sample], centres, width * surface.diagonal)
        register(field, surface, sample, config.field_iterations, config, sliding)
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


class _Search:
    """The candidates tried, each scored once on the ``scored`` vertices: ``maps`` {name: map} and ``shares``
    {name: share}; ``best``, the one that mirrors the most (the first tried among equals); ``posed``: the shape is a
    posed body (``mode='articulated'``), whose search a plane does not end (:attr:`suffices`)."""

    def __init__(self, scored: np.ndarray, config: AutoConfig, posed: bool = False):
        self.scored, self.config, self.posed = scored, config, posed
        self.maps: dict[str, MirrorMap] = {}
        self.shares: dict[str, float] = {}
        self.rigid: list[MirrorMap] = []  # the plain maps: planes and the whitened plane
        self.fields: dict[str, MirrorField] = {}  # the registered candidates' fields, by name
        self.intrinsics: list[MirrorMap] = []  # the intrinsic mirrors, once taken
        self._intrinsic: Beside | None = None  # the intrinsic mirrors, being computed

    def begin_intrinsic(self, surface: Surface, normal: np.ndarray) -> None:
        """Start computing the intrinsic mirror (:func:`intrinsic_mirror_map`) in a thread beside the other
        candidates: its spectrum and ZoomOut take a third of a posed body's search."""
        self._intrinsic = Beside(lambda: intrinsic_mirror_map(surface, normal, self.config))

    @property
    def intrinsic_pending(self) -> bool:
        """Whether the intrinsic mirror was begun and not yet taken."""
        return self._intrinsic is not None

    def take_intrinsic(self) -> MirrorMap | None:
        """The intrinsic mirror begun, once computed (None if there is none: a point cloud, no spectrum)."""
        if self._intrinsic is None:
            return None
        intrinsic, self._intrinsic = self._intrinsic.result(), None
        if intrinsic is not None:
            self.intrinsics.append(intrinsic)
        return intrinsic

    @property
    def intrinsic(self) -> MirrorMap | None:
        """The intrinsic mirror taken that mirrors the most (None if none was taken and scored)."""
        scored = [mirror for mirror in self.intrinsics if mirror.name in self.shares]
        return max(scored, key=lambda mirror: self.shares[mirror.name], default=None)

    def close(self) -> None:
        """Wait for the intrinsic mirror if it is still being computed (the search ended by an error)."""
        if self._intrinsic is not None:
            self._intrinsic.close()

    def score(self, mirror: MirrorMap) -> None:
        """Score ``mirror``; a map named as one tried before (a finer registration of it) takes its place only
        if it mirrors at least as much."""
        share = coverage(mirror, self.scored, self.config)
        if mirror.name not in self.shares or share >= self.shares[mirror.name]:
            self.maps[mirror.name], self.shares[mirror.name] = mirror, share

    @property
    def best(self) -> MirrorMap:
        """The map that mirrors the most so far."""
        return max(self.maps.values(), key=lambda mirror: self.shares[mirror.name])

    @property
    def best_field(self) -> str:
        """The name of the registered field that mirrors the most so far (there is one: ``fields`` not empty)."""
        return max(self.fields, key=lambda name: self.shares[name])

    @property
    def suffices(self) -> bool:
        """Whether the best map mirrors enough of the surface that no other could mirror much more:
        ``plane_suffices`` where a plain map mirrors ``min_coverage`` (a rigid pose, a scan) or ``plane_suffices``
        itself, ``field_suffices`` where none does (a strong bend, a pose: a field can mirror 95 % and still
        slide) and for a posed body (``posed``: a plane that mirrors 95 % of it can leave a swung limb
        unpaired, which the intrinsic mirror pairs)."""
        config = self.config
        rigid = max(self.shares[mirror.name] for mirror in self.rigid)
        plain = rigid >= min(config.min_coverage, config.plane_suffices) and not self.posed
        enough = config.plane_suffices if plain else config.field_suffices
        return self.shares[self.best.name] >= enough


def _candidates(surface: Surface, planes: list, search: _Search, config: AutoConfig, progress):
    """Batches of candidate maps, cheapest first (see the module doc); each batch is scored before the next is
    made, which may read the shares so far. For a posed body (``search.posed``: no compression of the whole) the
    drifts are not made (on the 40 BCICP shapes they won three times, each where the intrinsic mirror's twins were as
    right or righter, and cost 1-2 s a shape)."""
    rigid = [plane_map(surface, *plane, name="mirror plane" if rank == 1 else f"mirror plane {rank}")
             for rank, plane in enumerate(planes[:3], 1)]
    if not isinstance(surface, Outline):  # a flat shape's mirrors are lines of its plane: the planes find them
        rigid.append(affine_map(surface))
    search.rigid = rigid
    yield rigid
    ranked = sorted(rigid, key=lambda mirror: -search.shares[mirror.name])
    screening = _strided(surface, config.screening_samples)  # the sample every field is fitted and registered on
    x = surface.points[screening]
    centres = field_centres(surface, screening, config.screening_centres)
    mirrored = tessellation_map(surface, ranked[:2], search.scored, config)
    if mirrored is not None and smoothed_coverage(mirrored, x, centres, search.scored, config) >= config.field_suffices:
        yield [mirrored]  # the tessellation mirrors itself as the shape does: its own mirror, exact whatever the bend
        return
    search.begin_intrinsic(surface, ranked[0].normal)  # no plane suffices: a candidate, and an opinion on each twin
    coarse = config.field_widths[0] * surface.diagonal

    def registered(name: str, twins: np.ndarray) -> list[MirrorMap]:
        if progress is not None:
            progress(min(60.0, 8.0 * len(search.fields)), f"finding a mirror map: {name}")
        field = robust_fit(x, twins, centres, coarse)
        register(field, surface, screening, config.field_iterations, config)
        mirror = field_map(surface, field, f"registration from the {name}")
        search.fields[mirror.name] = field
        return [mirror]

    for mirror in ranked:
        yield registered(mirror.name, mirror.predict(x))
    compression = not search.posed
    if compression:
        yield registered(f"drift from the {ranked[0].name}", _drift_predictions(ranked[0], x))
    intrinsic = search.take_intrinsic()
    if intrinsic is not None:
        yield [intrinsic]
        yield registered(intrinsic.name, intrinsic.predict(x))
    for mirror in ranked[1:2] if compression else []:
        yield registered(f"drift from the {mirror.name}", _drift_predictions(mirror, x))
    if compression and ranked[0].name == WHITENED_PLANE:  # a compression of the whole breaks the intrinsic symmetry
        whitened = intrinsic_mirror_map(surface, ranked[0].normal, config, whitened=True)
        if whitened is not None:
            search.intrinsics.append(whitened)
            yield [whitened]
            yield registered(whitened.name, whitened.predict(x))


def _refined_field(surface: Surface, search: _Search, config: AutoConfig, progress) -> None:
    """The search's best registered field registered again on more vertices with finer fields, let slide along the
    surface toward its twins (:func:`.field.register`; on a posed body not, since its sound intrinsic mirror takes a
    field's place: let slide, the 22 BCICP shapes chosen on kept their figures but cat4 took 8.6 -> 14.2 s); it
    takes the coarse one's place if it mirrors at least as much."""
    if search.fields:
        name = search.best_field
        if progress is not None:
            progress(60.0, f"{name}, on {config.registration_samples} vertices")
        sample = _strided(surface, config.registration_samples)
        field = registered_field(surface, sample, search.fields[name], config, sliding=not search.posed)
        search.score(field_map(surface, field, name))


def _tessellation_of_best(search: _Search, config: AutoConfig) -> None:
    """The search's last candidate: the tessellation's own mirror grown from the best map's twins (exact, if the
    tessellation mirrors itself; already tried from the plain maps)."""
    best = search.best
    if best.name not in {TESSELLATION, *(mirror.name for mirror in search.rigid)}:
        mirrored = tessellation_map(best.surface, [best], search.scored, config)
        if mirrored is not None:
            search.score(mirrored)


def first_map(surface: Surface, scored: np.ndarray, config: AutoConfig, compression: bool = True,
              progress=None) -> FirstMap:
    """The first mirror map (see the module doc); SymmetryNotFoundError when none mirrors ``min_coverage`` of
    the surface. ``scored`` (m,): the vertices the shares are measured on; ``compression``: whether the shape may
    be compressed as a whole (not a posed body, ``mode='articulated'``), so that the coherent point drifts and the
    whitened shape's intrinsic mirror are candidates; a posed body's search goes on past a plane that mirrors
    ``plane_suffices``."""
    planes = surface_mirror_planes(surface.points[surface.usable_index])
    search = _Search(scored, config, posed=not compression)
    try:
        for batch in _candidates(surface, planes, search, config, progress):
            for mirror in batch:
                search.score(mirror)
            if search.suffices:
                break
        _refined_field(surface, search, config, progress)
        if search.intrinsic_pending:  # a field sufficed first: the intrinsic mirror is still a candidate
            intrinsic = search.take_intrinsic()
            if intrinsic is not None:
                search.score(intrinsic)
    finally:
        search.close()
    _tessellation_of_best(search, config)
    rigid_share = max(search.shares[mirror.name] for mirror in search.rigid)
    best = search.best
    # A plain map that mirrors min_coverage shows a symmetry up to the scan's noise; else the field must
    # prove it within its own precision.
    best = _refuse_or(best, search.shares, config, None if rigid_share >= config.min_coverage else scored)
    if search.posed:
        best = _intrinsic_if_sound(best, search, config)
    best = _sharpened(best, search, config)
    rivals = close_rivals(best, list(search.maps.values()), search.shares, scored, config)
    return FirstMap(best, search.shares, planes[0], rivals, search.intrinsic)


def _intrinsic_if_sound(best: MirrorMap, search: _Search, config: AutoConfig) -> MirrorMap:
    """On a posed body, the intrinsic mirror in place of a registered field (``best``) when it passes the tests a
    field must pass itself (:func:`_soundness`). An isometry of the surface pairs vertex with vertex; a registered
    field lands on the surface but may slide along it, which its share cannot see and the rounds do not undo: on the
    40 BCICP shapes, wherever a field mirrored more than the intrinsic mirror, the intrinsic mirror's twins were as
    right or righter (docs/benchmarks.md). A plane or the tessellation's own mirror stays."""
    intrinsic = search.intrinsic
    if intrinsic is None or best.name not in search.fields:
        return best
    return intrinsic if _soundness(intrinsic, search.shares[intrinsic.name], config, search.scored).sound else best


def _sharpened(best: MirrorMap, search: _Search, config: AutoConfig) -> MirrorMap:
    """An intrinsic mirror chosen (``best``) sharpened by the registered field that mirrors the most, where the field
    lands as precisely and agrees (:func:`.maps.sharpened_map`); any other map as it is. Its share is measured (the
    report's, the rivals'), not compared: within the whole tolerance the seams between the two cost it a little
    (the remeshed spot with a leg swung 0.6 rad: 99.3 -> 99.1 %), while it lands more precisely."""
    if best.name not in {mirror.name for mirror in search.intrinsics} or not search.fields:
        return best
    sharpened = sharpened_map(search.maps[search.best_field], best, config)
    search.score(sharpened)
    return sharpened


class _Soundness(NamedTuple):
    """A map's ``share`` of the surface mirrored within the landing tolerance and, for a map that lands where it
    lands by fitting, its ``precise`` share within ``field_precision`` of it (None: not measured); ``sound``: both at
    least what a mirror-symmetric shape shows (``min_coverage``, ``precise_coverage``)."""

    share: float
    precise: float | None
    sound: bool


def _soundness(mirror: MirrorMap, share: float, config: AutoConfig, scored: np.ndarray | None) -> _Soundness:
    """The tests of :class:`_Soundness` for ``mirror``, whose ``share`` is measured; its precise share is measured on
    the ``scored`` vertices (None: a plain map, whose share shows a symmetry up to the scan's noise) if the share
    passes."""
    if share < config.min_coverage or scored is None:
        return _Soundness(share, None, share >= config.min_coverage)
    precise = coverage(mirror, scored, config, config.field_precision)
    return _Soundness(share, precise, precise >= config.precise_coverage)


def _refuse_or(best: MirrorMap, shares: dict, config: AutoConfig, scored: np.ndarray | None = None) -> MirrorMap:
    """``best``, or SymmetryNotFoundError if it is not sound (:func:`_soundness`; a registered field, which lands
    where it lands by fitting, is measured on the ``scored`` vertices too)."""
    soundness = _soundness(best, shares[best.name], config, scored)
    listed = ", ".join(f"{name} {value:.0%}" for name, value in shares.items())
    found = f"mirrors {soundness.share:.0%} of the surface within {100 * config.landing_tolerance:g}% of its size"
    needs = f"needs {config.min_coverage:.0%}"
    if soundness.precise is not None:
        tolerance = config.field_precision * config.landing_tolerance
        shares[f"{best.name}, within {100 * tolerance:g}%"] = soundness.precise
        found += (f" but {soundness.precise:.0%} within {100 * tolerance:g}%, where a field fitted onto the surface "
                  "lands on a symmetric shape")
        needs = f"needs {config.precise_coverage:.0%} there"
    if not soundness.sound:
        raise SymmetryNotFoundError(
            f"No mirror symmetry found: the best mirror map ({best.name}) {found} ({listed}); a mirror-symmetric "
            f"shape, even bent or compressed, {needs}. Place landmark pairs and use pairs='landmarks' "
            "(or 'landmarks+auto').")
    return best

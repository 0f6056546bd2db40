"""Automatic pairs, round by round: a mirror map, the pairs it gives, the paper's solve; again on the output.

The first map comes from the input (:mod:`.first_map`: candidates, each registered, one score; with
landmarks, the landmarks' solve and a field registered on its output). When no map mirrors enough of the
surface, ``mode='articulated'`` starts from the solve of the intrinsic mirror's own vertex pairs
(:mod:`.intrinsic_start`: a posed body) and maps its output; other modes refuse. Each round pairs a
spread sample under the current map (:mod:`.pairs`) and solves, with the same checks and solve as a
user's landmarks, on the input, with the pairs the output before was solved from wherever the round's own
pairs do not reach (:func:`.pairs.keeping_unreached`: a limb the intrinsic start restored, which the next
round's exact vertex growth does not enter). Where the map left part of the surface without twins (a strong
bend with a compression, a shape only partly mirrored by the first map), the output is more symmetric than
the input, so the next map is a field registered on the output, from its own plane, and pairs more of it.
The rounds stop when the map pairs ``plane_suffices`` of the sample, when the output no longer moves,
or when a round leaves it less mirror-symmetric than the one before (that round is not kept). A round
whose map pairs ``plane_suffices`` of the sample is the last and takes ``auto_pair_count`` pairs at once;
otherwise the last solve takes them from the best round's map (its pair search, made once), and is kept by
the same rule. Every result
carries that map: each vertex's twin with a confidence (:mod:`.confidence`). In ``mode='articulated'``,
rounds from a map of space that leave a part of the output far from its mirror image (a limb no smooth map
followed) are run again from the intrinsic start, and the more mirror-symmetric output is kept.
"""

from __future__ import annotations

import dataclasses
import time
import warnings

import numpy as np

from ..core.geometry import reflection_across_plane
from ..core.landmark_asymmetry import fit_mirror_plane
from ..core.landmark_pairs import LandmarkPairs, check_landmarks
from ..core.solve import SymmetrizationResult, scaled_progress, solve
from ..core.surface_points import vertex_points
from ..errors import (DegenerateNeighbourhoodError, DisconnectedPairsError, GeometryError, SymblendError,
                      SymblendWarning, SymmetryNotFoundError)
from ..parameters import CORE, options_of
from .confidence import doubtful_map_warning, mirror_pairs
from .config import DEFAULT, AutoConfig
from .field import MirrorField, field_centres, register
from .first_map import TESSELLATION, coverage, first_map, intrinsic_mirror_map
from .intrinsic_map import intrinsic_vertex_map
from .intrinsic_start import cannot_start, intrinsic_start
from .maps import MirrorMap, field_map, pairs_map, plane_map
from .pairs import AutomaticPairs, Constraints, FoundPairs, as_landmarks, keeping_unreached, search_pairs, spread
from .report import AutomaticPairsReport, Round
from .rivals import rival_warning
from .surface import Outline, Surface, build_surface

# The rounds stop when the output moves less than this (x the diagonal): numerically the same output.
CONVERGED_CHANGE = 1e-9
# Times theta_width may double where the automatic pairs' neighbourhoods are flat (a straight outline),
# which the user did not place and cannot move.
WIDENINGS = 4


def _solve_widening(points: np.ndarray, landmarks: LandmarkPairs, options: dict, progress,
                    widenings: int) -> tuple[SymmetrizationResult, dict]:
    """The solve of checked automatic ``landmarks`` on ``points`` with the widths they need, and the
    ``options`` it used: `phi_width` raised to connect the pairs where they fall apart into groups (the
    pieces of a mesh in several parts lie farther apart than the pairs on each), `theta_width` doubled, up to
    ``widenings`` times, where the neighbourhoods are flat."""
    widened = 0
    while True:
        try:
            return solve(points, landmarks, options, progress, warn=False), options
        except DisconnectedPairsError as error:
            if error.connecting_width <= options["phi_width"]:
                raise
            options = {**options, "phi_width": error.connecting_width}
        except DegenerateNeighbourhoodError:
            if widened == widenings:
                raise
            widened += 1
            options = {**options, "theta_width": 2.0 * options["theta_width"]}


def _exact_pairs_map(surface: Surface, partner: np.ndarray, mirror: MirrorMap, config: AutoConfig) -> MirrorMap:
    """The map of the exact vertex pairs ``partner`` (N,) the kept round found under ``mirror`` (a plane, a map of
    the output), which the reported twins follow: ``mirror`` paired them within its tolerance and the growth
    carried them on, over parts it does not follow itself (a swung limb, where its predictions land elsewhere).
    Its normal: the pairs' best mirror plane's, on ``mirror``'s side."""
    paired = np.flatnonzero((partner >= 0) & (partner != np.arange(len(partner))))
    normal = fit_mirror_plane(surface.points[paired], surface.points[partner[paired]]).normal
    normal = normal if normal @ mirror.normal >= 0 else -normal
    return pairs_map(surface, partner, normal, config, f"exact vertex pairs under the {mirror.name}")


def _output_map(surface: Surface, result: SymmetrizationResult, sample: np.ndarray, config: AutoConfig) -> MirrorMap:
    """The map of a symmetrized output: its plane, or on a mesh a field registered on it from its plane."""
    output = surface.moved(result.points)
    normal, offset = result.report.plane
    plane = plane_map(output, normal, offset, name="output plane")
    if isinstance(surface, Outline) or coverage(plane, sample, config) >= config.plane_suffices:
        return plane
    start = MirrorField(normal, offset, field_centres(output, sample, config.field_centres),
                        config.field_widths[-1] * output.diagonal)
    register(start, output, sample, config.field_iterations, config)
    return field_map(output, start, "output mirror field")


def surface_asymmetry(surface: Surface, result: SymmetrizationResult, sample: np.ndarray) -> float:
    """RMS distance of the ``sample`` vertices of the output to its reflection across its plane, / diagonal."""
    return output_asymmetry(surface, result, sample)[0]


def output_asymmetry(surface: Surface, result: SymmetrizationResult, sample: np.ndarray) -> tuple[float, float]:
    """The RMS and the 99th percentile of the distances of the ``sample`` vertices of the output to its
    reflection across its plane, / diagonal."""
    distances = plane_distances(surface.moved(result.points), result.report.plane.normal,
                                 result.report.plane.offset, sample)
    return float(np.sqrt(np.mean(distances**2))), float(np.percentile(distances, 99))


def plane_distances(surface: Surface, normal: np.ndarray, offset: float, sample: np.ndarray) -> np.ndarray:
    """(m,): distance of each of the ``sample`` vertices of ``surface`` to its reflection across the plane, /
    diagonal."""
    mirrored = reflection_across_plane(surface.points[sample], np.asarray(normal), offset)
    return surface.nearest_points(mirrored)[1] / surface.diagonal


def _refusal_saying(refusal: SymmetryNotFoundError, sentence: str) -> SymmetryNotFoundError:
    """``refusal`` with ``sentence`` said before its advice (to place landmark pairs)."""
    found, advice, rest = str(refusal).partition(" Place landmark pairs")
    return SymmetryNotFoundError(f"{found} {sentence}{advice}{rest}")


PART_LEFT_WARNING = (
    "the rounds from a map of space left a part of the output asymmetric (99th percentile {p99:.2%} of the "
    "diagonal); the intrinsic mirror's pairs (a posed body) restored it better (RMS distance to its reflection "
    "{maps:.3%} -> {intrinsic:.3%}) and were kept. The intrinsic mirror can mistake one symmetry for another: "
    "check the result, or the pairs (symblend pairs MESH -o pairs.pp; find_mirror_pairs in Python), and correct "
    "them in MeshLab's PickPoints.")
INTRINSIC_START_WARNING = (
    "no map of space mirrors enough of this shape; it was paired by its intrinsic mirror (a posed body), which "
    "can mistake one symmetry for another: check the result, or the pairs (symblend pairs MESH -o pairs.pp; "
    "find_mirror_pairs in Python), and correct them in MeshLab's PickPoints.")


def _intrinsic_first_output(points, surface, core, scored, config, refusal, progress):
    """The output of the intrinsic mirror's vertex pairs (:mod:`.intrinsic_start`), what was tried, and the pairs
    solved (:class:`.pairs.AutomaticPairs`, None with no output): when no map mirrors enough of the surface
    (``refusal``), the refusal, with the reason, if they give none; asked for (``refusal`` None), a None output
    then."""
    if progress is not None:
        progress(10.0, "no map mirrors enough of the surface: the intrinsic mirror's own pairs")
    solved = []

    def solve_pairs(left, right):
        ones = np.ones(len(left))
        checked = check_landmarks(points, left, right, np.arange(1, len(left) + 1), None, ones, ones)
        output = _solve_widening(points, checked, core, None, 0)[0]
        solved.append(AutomaticPairs(*vertex_points(left), *vertex_points(right), np.zeros(0, dtype=np.int64), None))
        return output

    result, tried = intrinsic_start(surface, config, solve_pairs, lambda out: surface_asymmetry(surface, out, scored))
    pairs = solved[-1] if result is not None else None
    if refusal is None:
        return result, tried, pairs
    if result is None:
        raise _refusal_saying(refusal, cannot_start(tried)) from None
    tried["refused_maps"] = str(refusal)
    return result, tried, pairs


def solve_with_automatic_pairs(points: np.ndarray, faces: np.ndarray, options: dict,
                               landmarks: LandmarkPairs | None = None, excluded: np.ndarray | None = None,
                               progress=None, config: AutoConfig = DEFAULT) -> SymmetrizationResult:
    """``pairs='auto'`` (``landmarks`` None) or ``'landmarks+auto'`` on checked ``points`` (N, 3) and
    ``faces`` (F, 3) (empty: a point cloud) with validated ``options``. ``excluded`` (k,): vertices no
    automatic pair may use, nor pair with (a missing or broken part).

    In ``mode='articulated'``, when the rounds from a map of space leave a part of the output asymmetric
    (the 99th percentile of its distance to its own reflection above ``part_left_asymmetric``: a limb that
    no smooth map followed), the rounds are run again from the intrinsic start, and the output that is the
    more mirror-symmetric (RMS) is kept; the report's ``intrinsic_start`` says why and what each gave."""
    surface, forbidden = _surface(points, faces, landmarks, excluded, config)
    excluded_count = 0 if excluded is None else len(excluded)
    first = _paired(points, surface, forbidden, excluded_count, options, "maps" if landmarks is None else landmarks,
                    progress, config)
    auto = first.report.auto_pairs
    if (landmarks is not None or options["mode"] != "articulated" or auto.intrinsic_start is not None
            or auto.output_asymmetry_p99 <= config.part_left_asymmetric):
        return _warned(first)
    if progress is not None:
        progress(100.0, f"a part left asymmetric ({auto.output_asymmetry_p99:.2%} of the diagonal): the rounds "
                        "again from the intrinsic start")
    why = {"because": f"the rounds from the {auto.mirror_map.map} left a part asymmetric (99th percentile "
                      f"{auto.output_asymmetry_p99:.3g} of the diagonal)", "maps_asymmetry": auto.output_asymmetry}
    try:
        second = _paired(points, surface, forbidden, excluded_count, options, "intrinsic", None, config)
    except SymblendError as error:  # the maps' output stands; the report says why the other is missing
        second, why["failed"] = None, " ".join(str(error).split())
    if second is None:
        why.setdefault("failed", "the intrinsic mirror gave no pairs to solve (no spectrum, or no map that keeps "
                                 "the heat kernel signatures)")
        kept_auto = dataclasses.replace(auto, intrinsic_start={**why, "kept": "maps"})
        return _warned(dataclasses.replace(first, report=first.report.replace(auto_pairs=kept_auto)))
    maps, intrinsic = auto.output_asymmetry, second.report.auto_pairs.output_asymmetry
    kept = second if intrinsic < maps else first
    why.update(intrinsic_asymmetry=intrinsic, kept="intrinsic" if kept is second else "maps")
    said = kept.report.auto_pairs.warnings
    if kept is second:
        said = (PART_LEFT_WARNING.format(p99=auto.output_asymmetry_p99, maps=maps, intrinsic=intrinsic), *said)
    kept_auto = dataclasses.replace(kept.report.auto_pairs, warnings=said,
                                    intrinsic_start={**(second.report.auto_pairs.intrinsic_start or {}), **why})
    return _warned(dataclasses.replace(kept, report=kept.report.replace(auto_pairs=kept_auto)))


def _warned(result: SymmetrizationResult) -> SymmetrizationResult:
    """``result``, its automatic pairs' warnings raised."""
    for message in result.report.auto_pairs.warnings:
        warnings.warn(message, SymblendWarning, stacklevel=4)
    return result


def _surface(points: np.ndarray, faces: np.ndarray, landmarks: LandmarkPairs | None, excluded: np.ndarray | None,
             config: AutoConfig) -> tuple[Surface, np.ndarray]:
    """(the surface the automatic pairs live on, forbidden (N,) bool: the vertices no automatic pair may use, the
    ``excluded`` ones and the user's ``landmarks``); GeometryError if fewer than 4 vertices can pair."""
    forbidden = np.zeros(len(points), dtype=bool)
    if excluded is not None:
        forbidden[excluded] = True
    if landmarks is not None:
        forbidden[np.concatenate([landmarks.left, landmarks.right, landmarks.midline])] = True
    surface = build_surface(points, faces, excluded=np.flatnonzero(forbidden))
    if len(surface.usable_index) < 4:
        if isinstance(surface, Outline):
            raise GeometryError(f"The mesh is flat (every vertex in one plane), so its outline is what is paired, and "
                                f"its outline has {len(surface.usable_index)} vertices that can be paired (a closed "
                                "surface flattened onto a plane has none); automatic pairs need 4 or more. Give "
                                "the mesh before it was flattened, or landmark pairs.")
        raise GeometryError(f"The mesh has {len(surface.usable_index)} vertices that can be paired (on a triangle "
                            "with an area, not excluded); automatic pairs need more.")
    return surface, forbidden


def _paired(points: np.ndarray, surface: Surface, forbidden: np.ndarray, excluded_count: int, options: dict,
            start: LandmarkPairs | str, progress, config: AutoConfig) -> SymmetrizationResult | None:
    """The rounds on ``surface`` (:func:`_surface`, with its ``forbidden`` vertices, ``excluded_count`` of them
    excluded by the user; the same surface for both runs, so the intrinsic mirrors are computed once), started
    from the user's landmark pairs (``start``), from the first map of space (``"maps"``: the intrinsic start if
    none mirrors enough, in articulated mode) or from the intrinsic start (``"intrinsic"``: None if it gives
    nothing); warnings in the report, not raised."""
    landmarks = start if isinstance(start, LandmarkPairs) else None
    clock = time.perf_counter()
    n = len(points)
    core = options_of(options, CORE)
    rounds_allowed = options["auto_iterations"]
    step = 70.0 / (rounds_allowed + 2)
    sample = spread(points, surface.usable_index, max(config.samples, 2 * options["auto_pair_count"]))
    scored = spread(points, surface.usable_index, config.score_samples)
    registration = spread(points, surface.usable_index, config.registration_samples)
    origin = {}  # how the rounds started: the first map's coverage and plane, or the intrinsic start
    history, messages, rivals = [], [], []
    solved_from = None  # the pairs the current output was solved from (the intrinsic start's, or a kept round's)
    intrinsic = None  # the intrinsic mirror, where computed: the twin of a vertex where it has more evidence
    refusal = None  # no map of space mirrors enough of the surface (in articulated mode: the intrinsic start)
    if landmarks is None and start == "maps":
        try:
            mirror, shares, plane, rivals, intrinsic = first_map(surface, scored, config,
                                                                 core["mode"] != "articulated",
                                                                 scaled_progress(progress, 0.0, 30.0))
            origin = {"coverage": shares, "surface_plane": plane}
            if rivals:
                messages.append(rival_warning(mirror.name, shares[mirror.name], rivals))
            result, best = None, np.inf
        except SymmetryNotFoundError as refused:  # a strongly posed body, or a shape with no mirror symmetry
            if core["mode"] != "articulated":  # the intrinsic mirror holds under isometries: a pose, not a compression
                raise _refusal_saying(refused, "If it is a posed body, mode='articulated' pairs it by its intrinsic "
                                               "mirror.") from None
            refusal = refused
    if landmarks is None and (start == "intrinsic" or refusal is not None):
        result, tried, solved_from = _intrinsic_first_output(points, surface, core, scored, config, refusal, progress)
        if result is None:  # only when asked for: after a refusal it raises
            return None
        origin = {"intrinsic_start": tried}
        best = surface_asymmetry(surface, result, scored)
        history.append(Round(best, start="intrinsic"))
        if refusal is not None:
            messages.append(INTRINSIC_START_WARNING)
        mirror = _output_map(surface, result, registration, config)
        intrinsic = intrinsic_mirror_map(surface, result.report.plane.normal, config)
    elif landmarks is not None:
        result = solve(points, landmarks, core, scaled_progress(progress, 0.0, 20.0))
        best = surface_asymmetry(surface, result, scored)
        history.append(Round(best, start="landmarks"))
        if progress is not None:
            progress(20.0, "registering a mirror field on the landmarks' output")
        mirror = _output_map(surface, result, registration, config)
    count = options["auto_pair_count"]
    round_count = min(count, config.round_pairs)
    exact_twins = None  # decided by the first round
    given = (0, 0) if landmarks is None else (len(landmarks.left), len(landmarks.midline))  # the user's pairs, midline
    constraints = Constraints(surface, landmarks, forbidden, config)

    def attempt(mirror: MirrorMap, pairs_wanted: int, start: float, found: FoundPairs | None = None):
        """The solve of ``pairs_wanted`` pairs under ``mirror`` (``found``: its search, if made before) with those
        of the output before where they do not reach (:func:`.pairs.keeping_unreached`), its round's entry, the
        search and the pairs solved."""
        nonlocal exact_twins
        found = search_pairs(mirror, sample, constraints, exact_twins) if found is None else found
        pairs, carried = keeping_unreached(found.chosen(pairs_wanted), solved_from, surface)
        exact_twins = pairs.search.twins_are == "exact vertices"
        solved, checked = as_landmarks(points, pairs, landmarks, options["landmark_priority"], config.coincident)
        candidate, solve_options = _solve_widening(solved, checked, core, scaled_progress(progress, start, step),
                                                   WIDENINGS)
        candidate = dataclasses.replace(candidate, points=candidate.points[:n], asymmetry=candidate.asymmetry[:n])
        entry = Round(surface_asymmetry(surface, candidate, scored), search=pairs.search,
                      pairs=int(len(checked.left) - given[0]), midline=int(len(checked.midline) - given[1]),
                      raised_widths={width: solve_options[width] for width in ("phi_width", "theta_width")
                                     if solve_options[width] != core[width]}, carried=carried)
        return candidate, entry, found, pairs

    stopped, source, source_found, solved_with = "round limit", mirror, None, 0
    for index in range(rounds_allowed):
        begin = 30.0 + index * step
        if progress is not None:
            progress(begin, f"automatic pairs, round {index + 1}")
        found = search_pairs(mirror, sample, constraints, exact_twins)
        # A round whose map pairs plane_suffices of the sample is the last: it takes all the pairs at once.
        wanted = count if found.search.share_paired >= config.plane_suffices else round_count
        candidate, entry, found, pairs = attempt(mirror, wanted, begin, found)
        previous = points if result is None else result.points  # round 1 of 'auto': against the input itself
        entry = dataclasses.replace(entry, change=float(np.abs(candidate.points - previous).max() / surface.diagonal))
        if entry.surface_asymmetry > best * (1.0 + 1e-9):
            history.append(dataclasses.replace(entry, kept=False))
            stopped = "no gain"
            break
        history.append(entry)
        gain = 1.0 - entry.surface_asymmetry / best if np.isfinite(best) and best > 0 else 1.0
        result, best, source, source_found, solved_with = candidate, entry.surface_asymmetry, mirror, found, wanted
        solved_from = pairs
        if entry.change < CONVERGED_CHANGE:
            stopped = "converged"
            break
        if entry.search.share_paired >= config.plane_suffices:  # exact pairs: the share paired
            stopped = "paired"
            break
        if gain < config.least_gain:
            stopped = "little gain"
            break
        mirror = _output_map(surface, result, registration, config)
    if count > solved_with and history[-1].search.candidates > round_count:
        # The rounds found the twins with fewer pairs; the output is solved with all of them.
        if progress is not None:
            progress(30.0 + rounds_allowed * step, f"automatic pairs: the solve with {count} pairs")
        candidate, entry, _, _ = attempt(source, count, 30.0 + rounds_allowed * step, source_found)
        better = entry.surface_asymmetry <= best * (1.0 + 1e-9)  # as a round: one less symmetric is not kept
        history.append(dataclasses.replace(entry, final=True, kept=better))
        if better:
            result = candidate
    if progress is not None:
        progress(98.0, "every vertex's twin, with its confidence")
    vertex_map = None if intrinsic is None else intrinsic_vertex_map(surface, config)
    if source_found is not None and source_found.partner is not None and source.name != TESSELLATION:
        source = _exact_pairs_map(surface, source_found.partner, source, config)
    twins = mirror_pairs(source, surface, forbidden, config, rivals, intrinsic, vertex_map,
                         posed=core["mode"] == "articulated")
    doubtful = doubtful_map_warning(twins.report)
    if doubtful is not None:
        messages.append(doubtful)
    if progress is not None:
        progress(100.0, "done")
    kept = [entry for entry in history if entry.kept and not entry.is_start]
    rms, p99 = output_asymmetry(surface, result, scored)
    report = AutomaticPairsReport(
        pair_count=result.report.pair_count - given[0], midline_count=result.report.midline_count - given[1],
        rounds=tuple(history), stopped=stopped, twins_are=kept[-1].search.twins_are if kept else None,
        consistency=kept[-1].search.consistency if kept else None, mirror_map=twins.report,
        excluded_vertices=int(excluded_count), output_asymmetry=rms, output_asymmetry_p99=p99,
        warnings=tuple(messages), **origin)
    return _final(points, surface.representative, result, landmarks, report, clock, twins)


def _final(points, representative, result, landmarks, report, clock, twins) -> SymmetrizationResult:
    """The result cut back to the input's vertices (each duplicate where its first copy went), with the
    automatic pairs' ``report``: the pair counts are the user's, the landmark asymmetry theirs alone."""
    final = result.report
    if landmarks is None:
        before = after = None
    else:
        before = fit_mirror_plane(points[landmarks.left], points[landmarks.right]).summary(final.diagonal)
        after = fit_mirror_plane(result.points[landmarks.left], result.points[landmarks.right]).summary(final.diagonal)
    out = final.replace(pair_count=final.pair_count - report.pair_count,
                        midline_count=final.midline_count - report.midline_count, auto_pairs=report,
                        landmark_asymmetry_before=before, landmark_asymmetry_after=after,
                        seconds=dataclasses.replace(final.seconds, total=time.perf_counter() - clock))
    points_out = result.points[representative]
    if not np.isfinite(points_out).all():
        raise GeometryError("The automatic pairs gave a non-finite output (a singular system went undetected); "
                            "please report this mesh.")
    return SymmetrizationResult(points_out, np.linalg.norm(points_out - points, axis=1), out, twins)

"""Automatic pairs, round by round: a mirror map, the pairs it gives, the paper's solve; again on the output.

The first map comes from the input (:mod:`.maps`; with landmarks, from their solve).
Each round finds the twins of a spread sample of vertices under the current map
(:mod:`.twins`), keeps those the map is consistent about and that land on the
surface, and turns them into pairs: exact vertex pairs, grown over the surface and
pruned (:mod:`.growth`), where a third of the twins are exact vertices (a mesh whose
vertices mirror each other); otherwise each sample vertex with the vertex nearest to
where its twin lands (a scan: a fraction of an edge off along the surface, but on it,
so that the output's triangles, not points inside them, come out mirror images). The pairs go through the same
checks and the same solve as a user's landmarks, on the input; the next map is the
output's own mirror plane. The rounds stop when the output no longer moves, or a round
leaves the output less mirror-symmetric than the one before (it is not kept).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
from scipy.sparse.csgraph import connected_components

from ..checks.surface_asymmetry import surface_mirror_planes
from ..core.geometry import reflection_across_plane, voxel_grid
from ..core.landmark_asymmetry import fit_mirror_plane
from ..core.neighbourhoods import connecting_width, mean_nearest_spacing, pair_weights
from ..core.symmetrize import CheckedLandmarks, SymmetrizationResult, check_landmarks, scaled_progress, solve
from ..errors import DegenerateNeighbourhoodError, GeometryError, SymmetryNotFoundError
from ..parameters import CORE, PARAMETERS
from .config import DEFAULT, AutoConfig
from .connectivity import ring_consistent, tessellation_mirror
from .growth import _one_pair_per_vertex, grow_and_prune
from .maps import MirrorMap, affine_map, pairs_map, plane_map, registered_map
from .surface import Surface, build_surface
from .twins import find_twins

COINCIDENT = 1e-9  # x diagonal: landmark positions closer than this are one position
CORE_NAMES = frozenset(p.name for p in PARAMETERS if p.layer in CORE)
SCREEN_SOURCES = 4000  # vertices on which maps and outputs are compared (a share is measured to about 1 %)
WIDENINGS = 4  # times theta_width may double where automatic pairs' neighbourhoods are flat (a straight outline)


@dataclasses.dataclass(frozen=True)
class AutomaticPairs:
    """Pairs found in one round: vertex indices ``left``, ``right`` (n,) and ``midline`` (m,); ``info``, what
    the round reports."""

    left: np.ndarray
    right: np.ndarray
    midline: np.ndarray
    info: dict


def _spread(points: np.ndarray, vertices: np.ndarray, count: int) -> np.ndarray:
    """At most about ``count`` of ``vertices`` spread evenly (one per cell of a voxel grid), in order."""
    if len(vertices) <= count:
        return vertices
    keys = voxel_grid(points[vertices], count, steps=16)
    _, first = np.unique(keys, return_index=True)
    return vertices[np.sort(first)]


def _first_map(surface: Surface, sources: np.ndarray, config: AutoConfig, progress) -> tuple[MirrorMap, dict, tuple]:
    """The map that mirrors the most of the surface (measured at the vertices ``sources``), its coverage of
    each map tried, and the input's mirror plane; SymmetryNotFoundError when none mirrors enough. Tried in
    turn, until one mirrors ``plane_suffices`` of the surface: the best mirror plane; the whitened one;
    registrations started from each of these and from the next best planes (compared on half the samples,
    the best one redone on all); the mirror map of the tessellation."""
    planes = surface_mirror_planes(surface.points[surface.usable_index])
    tolerance = config.landing_tolerance * surface.diagonal
    tried: list[tuple[MirrorMap, float]] = []

    def tried_map(mirror: MirrorMap | None) -> bool:
        """Record ``mirror`` and its coverage; whether it mirrors enough to stop looking."""
        if mirror is None:
            return False
        tried.append((mirror, float(np.mean(find_twins(mirror, sources, tolerance).covered(tolerance)))))
        return tried[-1][1] >= config.plane_suffices

    def report(percent: float) -> None:
        if progress is not None:
            progress(percent, "finding a mirror map")

    rigid = [plane_map(surface, *plane, name="mirror plane" if rank == 1 else f"mirror plane {rank}")
             for rank, plane in enumerate(planes[:3], 1)]
    done = tried_map(rigid[0])
    if not done:
        report(10.0)
        done = tried_map(affine_map(surface))
    if not done:
        starts = [rigid[0], tried[-1][0], *rigid[1:]]
        for index, start in enumerate(starts):
            if index >= 2 and max(share for _, share in tried) >= config.min_coverage:
                break  # the next planes are for a strong bend that leaves the first ones far off
            report(20.0 + 50.0 * index / len(starts))
            done = tried_map(registered_map(start, config, screening=True))
            if done:
                break
        if not done:
            report(70.0)
            screened = [share for _, share in tried[2:]]  # one per start tried, in order
            start = starts[int(np.argmax(screened))]
            refined = registered_map(start, config)
            done = tried_map(dataclasses.replace(refined, name=f"{refined.name} ({config.registration_samples} points)"))
    if not done:
        report(90.0)
        ranked = [mirror for mirror, _ in sorted(tried, key=lambda entry: -entry[1])]
        tried_map(_tessellation_map(surface, ranked[:2], sources, config))
    best, share = max(tried, key=lambda entry: entry[1])
    coverage = {mirror.name: value for mirror, value in tried}
    if share < config.min_coverage:
        listed = ", ".join(f"{name} {value:.0%}" for name, value in coverage.items())
        raise SymmetryNotFoundError(
            f"No mirror symmetry found: the best mirror map ({best.name}) mirrors {share:.0%} of the "
            f"surface within {100 * config.landing_tolerance:g}% of its size ({listed}); a mirror-symmetric shape, even "
            f"bent or compressed, needs {config.min_coverage:.0%}. Place landmark pairs and use pairs='landmarks' "
            "(or 'landmarks+auto').")
    return best, coverage, planes[0]


def _tessellation_map(surface: Surface, maps: list[MirrorMap], sources: np.ndarray, config: AutoConfig) -> MirrorMap | None:
    """The mirror map of the tessellation (:func:`.connectivity.tessellation_mirror`), grown from the exact
    vertex twins that one of the geometric ``maps`` gives (tried in turn); None for a point cloud or a
    tessellation that does not mirror itself."""
    if not surface.is_mesh:
        return None
    for mirror in maps:
        twins = find_twins(mirror, sources, config.landing_tolerance * surface.diagonal)
        covered = twins.covered(config.landing_tolerance * surface.diagonal)
        tolerance = _robust_tolerance(twins.landing[covered], config, COINCIDENT * surface.diagonal)
        exact = twins.exact_vertex(config, tolerance) & covered
        partner = np.full(len(surface.points), -1)
        seeds, twin = _one_pair_per_vertex(sources[exact], twins.vertex[exact])
        partner[seeds], partner[twin] = twin, seeds
        mirrored = tessellation_mirror(surface.adjacency, partner, surface.usable)
        if mirrored is not None:
            return pairs_map(surface, mirrored, mirror.normal, config, "tessellation mirror")
    return None


def _robust_tolerance(values: np.ndarray, config: AutoConfig, floor: float) -> float:
    """``robust_sigmas`` robust standard deviations of ``values`` (taken as |N(0, sigma)|), at least ``floor``."""
    return max(config.robust_sigmas * 1.4826 * float(np.median(values)), floor) if len(values) else floor


def find_pairs(mirror: MirrorMap, geometry: Surface, sources: np.ndarray, fixed: CheckedLandmarks | None,
               forbidden: np.ndarray, count: int, config: AutoConfig, exact: bool | None = None) -> AutomaticPairs:
    """Pairs under ``mirror`` for ``sources`` (see the module doc), checked on ``geometry`` (the input); none
    on a ``forbidden`` (N,) vertex (a landmark, an excluded part). ``fixed``: the user's landmarks, anchors
    of the growth. ``exact``: whether the twins are to be exact vertices; None: decided here, by the share
    of the twins that are (on a symmetrized output the pairs it was made from always are, so the later
    rounds pass the first round's answer)."""
    surface = mirror.surface
    n = len(surface.points)
    twins = find_twins(mirror, sources, config.landing_tolerance * geometry.diagonal)
    covered = twins.covered(config.landing_tolerance * geometry.diagonal)
    covered &= ~forbidden[twins.corners].any(axis=1)
    if not covered.any():
        raise GeometryError("Automatic pairing found no vertex whose mirror image lies on the surface.")
    floor = COINCIDENT * surface.diagonal
    tolerance = _robust_tolerance(twins.landing[covered], config, floor)
    partner = np.full(n, -1)
    if fixed is not None:
        partner[fixed.left], partner[fixed.right], partner[fixed.midline] = fixed.right, fixed.left, fixed.midline
    exact_twins = twins.exact_vertex(config, tolerance) & covered & ~forbidden[twins.vertex]
    beyond_chance = exact_twins & (surface.chance_ratio(twins.ratio) <= config.ratio)
    info = {"map": mirror.name, "twins": float(np.mean(covered)),
            "vertex_twins": float(np.count_nonzero(beyond_chance) / np.count_nonzero(covered))}
    index = np.arange(n)
    if exact is None:
        exact = info["vertex_twins"] >= config.vertex_twins
    if exact:
        seeds, twin = _one_pair_per_vertex(sources[exact_twins], twins.vertex[exact_twins])
        partner[seeds], partner[twin] = twin, seeds
        in_sample = np.zeros(n, dtype=bool)
        in_sample[sources] = True
        info.update(grow_and_prune(surface, geometry, partner, in_sample & ~forbidden, surface.usable & ~forbidden,
                                   forbidden, config, floor))
        if surface.is_mesh:
            mirrored = tessellation_mirror(surface.adjacency, partner, surface.usable & ~forbidden)
            info["tessellation_mirror"] = mirrored is not None
            if mirrored is not None:
                # Where the tessellation stops mirroring (a midline strip triangulated one way), its pairs can be
                # wrong: those are left to the geometric growth from the pairs whose rings map whole, which are
                # exact whatever the geometry around them (a joint), and so are not pruned.
                whole = ring_consistent(surface.adjacency, mirrored) & ~forbidden
                partner[:] = np.where(whole, mirrored, -1)
                if fixed is not None:
                    partner[fixed.left], partner[fixed.right] = fixed.right, fixed.left
                    partner[fixed.midline] = fixed.midline
                info.update(grow_and_prune(surface, geometry, partner, in_sample & ~forbidden,
                                           surface.usable & ~forbidden, forbidden | whole, config, floor))
        automatic = (partner >= 0) & ~forbidden
        gap = surface.points - surface.points[np.maximum(partner, 0)]
        left = np.flatnonzero(automatic & (partner != index) & (gap @ mirror.normal > 0))
        midline = np.flatnonzero(automatic & (partner == index))
        candidates = np.concatenate([left, midline])
        chosen = _spread(surface.points, candidates, count)
        on_plane = partner[chosen] == chosen
        return AutomaticPairs(chosen[~on_plane], partner[chosen[~on_plane]], chosen[on_plane],
                              {**info, "twins_are": "exact vertices", "candidates": len(candidates)})
    # Every sound twin on the surface (a scan's asymmetry is what the solve is to remove), as the vertex
    # nearest the prediction: tangentially a fraction of an edge off, but a vertex on the surface, so that
    # the output's triangles, not only points inside them, come out mirror images.
    twin = twins.vertex
    accepted = twins.sound & ~forbidden[twin] & ~forbidden[twins.corners].any(axis=1)
    by_distance = np.argsort(twins.vertex_distance, kind="stable")
    first_use = np.zeros(len(sources), dtype=bool)
    _, first = np.unique(twin[by_distance[accepted[by_distance]]], return_index=True)
    first_use[by_distance[accepted[by_distance]][first]] = True  # a vertex is the twin of one source
    itself = first_use & (twin == sources) & (twins.vertex_distance <= np.maximum(tolerance, twins_half_edge(surface, twin)))
    left = first_use & (twin != sources) & (twins.side > 0)
    candidates = np.sort(np.concatenate([sources[left], sources[itself]]))
    chosen = _spread(surface.points, candidates, count)
    rows = np.searchsorted(sources, chosen)  # sources are sorted
    on_plane = itself[rows]
    pairs = rows[~on_plane]
    return AutomaticPairs(sources[pairs], twin[pairs], sources[rows[on_plane]],
                          {**info, "twins_are": "nearest vertices", "candidates": len(candidates)})


def twins_half_edge(surface: Surface, vertices: np.ndarray) -> np.ndarray:
    """Half the local vertex spacing at ``vertices``: a vertex whose mirror image is nearer itself than this
    is on the midline, for a mesh whose two sides are sampled independently."""
    return 0.5 * surface.local_spacing[vertices]


def _landmarks(points: np.ndarray, pairs: AutomaticPairs, user: CheckedLandmarks | None,
               priority: float) -> CheckedLandmarks:
    """The user's and the automatic pairs as checked landmarks (automatic pairs on a landmark's vertex, or
    on a position another landmark holds, are left out); the user's weigh ``priority`` times more."""
    left, right, midline = pairs.left, pairs.right, pairs.midline
    if user is not None:
        taken = np.concatenate([user.left, user.right, user.midline])
        keep = ~np.isin(left, taken) & ~np.isin(right, taken)
        left, right, midline = left[keep], right[keep], midline[~np.isin(midline, taken)]
    left, right, midline = _distinct(points, left, right, midline, user)
    first = 1 if user is None or not len(user.ids) else int(np.max(user.ids)) + 1
    ids = np.arange(first, first + len(left))
    ones = np.ones(len(left))
    if user is None:
        return check_landmarks(points, left, right, ids, midline, ones, ones)
    both = check_landmarks(points, np.concatenate([user.left, left]), np.concatenate([user.right, right]),
                           np.concatenate([user.ids, ids]), np.concatenate([user.midline, midline]))
    return dataclasses.replace(both, left_weights=np.concatenate([priority * user.left_weights, ones]),
                               right_weights=np.concatenate([priority * user.right_weights, ones]))


def _distinct(points, left, right, midline, user):
    """The pairs and midline points whose positions differ from every other landmark's."""
    fixed = np.zeros(0, dtype=np.int64) if user is None else np.concatenate([user.left, user.right, user.midline])
    used = np.concatenate([left, right, midline, fixed])
    scale = COINCIDENT * float(np.linalg.norm(np.ptp(points[used], axis=0)) or 1.0)
    cells = np.round(points[used] / scale).astype(np.int64)
    _, inverse, counts = np.unique(cells, axis=0, return_inverse=True, return_counts=True)
    shared = counts[inverse.ravel()] > 1
    n = len(left)
    keep = ~shared[:n] & ~shared[n:2 * n]
    return left[keep], right[keep], midline[~shared[2 * n:2 * n + len(midline)]]


def _connected_options(points: np.ndarray, landmarks: CheckedLandmarks, options: dict) -> dict:
    """``options`` with `phi_width` raised, if needed, so that the pairs' weight graph is connected (the
    pieces of a mesh in several parts lie farther apart than the pairs on each)."""
    left = np.concatenate([points[landmarks.left], points[landmarks.midline]])
    right = np.concatenate([points[landmarks.right], points[landmarks.midline]])
    spacing = options["width_spacing"] or mean_nearest_spacing(np.vstack([points[landmarks.left], points[landmarks.right],
                                                                          points[landmarks.midline]]))
    weights = pair_weights(left, right, options["phi_width"] * spacing)
    if connected_components(weights, directed=False)[0] == 1:
        return options
    return {**options, "phi_width": max(options["phi_width"], connecting_width(left, right) / spacing)}


def _output_map(surface: Surface, result: SymmetrizationResult) -> MirrorMap:
    return plane_map(surface.moved(result.points), np.asarray(result.report["plane_normal"]),
                     result.report["plane_offset"], name="output plane")


def surface_asymmetry(surface: Surface, result: SymmetrizationResult, sample: np.ndarray) -> float:
    """RMS distance of the ``sample`` vertices of the output to its reflection across its plane, / diagonal."""
    output = surface.moved(result.points)
    mirrored = reflection_across_plane(output.points[sample], np.asarray(result.report["plane_normal"]),
                                       result.report["plane_offset"])
    distance = output.nearest_points(mirrored)[1]
    return float(np.sqrt(np.mean(distance**2)) / output.diagonal)


def symmetrize_automatic(points: np.ndarray, faces: np.ndarray, options: dict, landmarks: CheckedLandmarks | None = None,
                         excluded: np.ndarray | None = None, progress=None, config: AutoConfig = DEFAULT
                         ) -> SymmetrizationResult:
    """``pairs='auto'`` (``landmarks`` None) or ``'landmarks+auto'`` on checked ``points`` (N, 3) and
    ``faces`` (F, 3) (empty: a point cloud) with validated ``options``. ``excluded`` (k,): vertices no
    automatic pair may use, nor pair with (a missing or broken part)."""
    clock = time.perf_counter()
    n = len(points)
    forbidden = np.zeros(n, dtype=bool)
    if excluded is not None:
        forbidden[excluded] = True
    if landmarks is not None:
        forbidden[np.concatenate([landmarks.left, landmarks.right, landmarks.midline])] = True
    surface = build_surface(points, faces, excluded=np.flatnonzero(forbidden))
    if len(surface.usable_index) < 4:
        raise GeometryError(f"The mesh has {len(surface.usable_index)} vertices that can be paired (on a triangle "
                            "with an area, not excluded); automatic pairs need more.")
    core = {key: options[key] for key in options if key in CORE_NAMES}
    rounds_allowed = options["auto_iterations"]
    step = 80.0 / (rounds_allowed + 2)
    sample = _spread(points, surface.usable_index, max(config.samples, 2 * options["auto_pair_count"]))
    scored = _spread(points, surface.usable_index, SCREEN_SOURCES)
    report = {"excluded_vertices": int(0 if excluded is None else len(excluded))}
    if landmarks is None:
        mirror, coverage, plane = _first_map(surface, scored, config, scaled_progress(progress, 0.0, 20.0))
        report.update(coverage=coverage, surface_plane={"normal": plane[0].tolist(), "offset": plane[1]})
        result, best = None, np.inf
    else:
        result = solve(points, landmarks, core, scaled_progress(progress, 0.0, 20.0))
        best = surface_asymmetry(surface, result, scored)
        report["rounds"] = [{"landmarks_only": True, "surface_asymmetry": best}]
        mirror = _output_map(surface, result)
    history = report.setdefault("rounds", [])
    count = options["auto_pair_count"]
    round_count = min(count, config.round_pairs)

    exact_twins = None  # decided by the first round

    def attempt(mirror: MirrorMap, pairs_wanted: int, start: float):
        nonlocal exact_twins
        pairs = find_pairs(mirror, surface, sample, landmarks, forbidden, pairs_wanted, config, exact_twins)
        exact_twins = pairs.info["twins_are"] == "exact vertices"
        checked = _landmarks(points, pairs, landmarks, options["landmark_priority"])
        solve_options = _connected_options(points, checked, core)
        for widening in range(WIDENINGS + 1):
            try:
                candidate = solve(points, checked, solve_options, scaled_progress(progress, start, step), warn=False)
                break
            except DegenerateNeighbourhoodError:
                if widening == WIDENINGS:
                    raise
                solve_options = {**solve_options, "theta_width": 2.0 * solve_options["theta_width"]}
        entry = {**pairs.info, "pairs": int(len(checked.left) - (0 if landmarks is None else len(landmarks.left))),
                 "midline": int(len(checked.midline) - (0 if landmarks is None else len(landmarks.midline))),
                 "surface_asymmetry": surface_asymmetry(surface, candidate, scored)}
        for width in ("phi_width", "theta_width"):
            if solve_options[width] != core[width]:
                entry[width] = solve_options[width]
        return candidate, entry

    stopped, source = "round limit", mirror
    for index in range(rounds_allowed):
        start = 20.0 + index * step
        if progress is not None:
            progress(start, f"automatic pairs, round {index + 1}")
        candidate, entry = attempt(mirror, round_count, start)
        entry["change"] = np.inf if result is None else float(np.abs(candidate.points - result.points).max()
                                                                / surface.diagonal)
        history.append(entry)
        if entry["surface_asymmetry"] > best * (1.0 + 1e-9):
            entry["kept"] = False
            stopped = "no gain"
            break
        gain = 1.0 - entry["surface_asymmetry"] / best if np.isfinite(best) and best > 0 else 1.0
        result, best, source = candidate, entry["surface_asymmetry"], mirror
        if entry["change"] < config.converged_change:
            stopped = "converged"
            break
        if gain < config.least_gain:
            stopped = "little gain"
            break
        mirror = _output_map(surface, result)
    if count > round_count and history[-1]["candidates"] > round_count:
        # The rounds found the twins with fewer pairs; the output is solved with all of them.
        if progress is not None:
            progress(20.0 + rounds_allowed * step, f"automatic pairs: the solve with {count} pairs")
        result, entry = attempt(source, count, 20.0 + rounds_allowed * step)
        entry["final"] = True
        history.append(entry)
    if progress is not None:
        progress(100.0, "done")
    return _final(points, surface.representative, result, landmarks, report, stopped, clock)


def _final(points, representative, result, landmarks, report, stopped, clock) -> SymmetrizationResult:
    """The result cut back to the input's vertices (each duplicate where its first copy went), with the
    automatic pairs' report."""
    final = result.report
    user_pairs = 0 if landmarks is None else len(landmarks.left)
    user_midline = 0 if landmarks is None else len(landmarks.midline)
    kept = [entry for entry in report["rounds"] if entry.get("kept", True) and not entry.get("landmarks_only")]
    report.update(stopped=stopped, pair_count=int(final["pair_count"] - user_pairs),
                  midline_count=int(final["midline_count"] - user_midline),
                  twins_are=kept[-1]["twins_are"] if kept else None)
    out = {**final, "pair_count": user_pairs, "midline_count": user_midline, "auto_pairs": report}
    if landmarks is None:
        out.pop("landmark_asymmetry_before")
        out.pop("landmark_asymmetry_after")
    else:
        diagonal = final["diagonal"]
        out["landmark_asymmetry_before"] = fit_mirror_plane(points[landmarks.left], points[landmarks.right]).summary(diagonal)
        out["landmark_asymmetry_after"] = fit_mirror_plane(result.points[landmarks.left],
                                                           result.points[landmarks.right]).summary(diagonal)
    out["seconds"] = {**final["seconds"], "total": time.perf_counter() - clock}
    points_out = result.points[representative]
    if not np.isfinite(points_out).all():
        raise GeometryError("The automatic pairs gave a non-finite output (a singular system went undetected); "
                            "please report this mesh.")
    return SymmetrizationResult(points_out, np.linalg.norm(points_out - points, axis=1), out)

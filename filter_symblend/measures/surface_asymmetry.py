"""Mirror asymmetry of a whole surface: how far it is from its reflection across a mirror plane, the plane
of the pairs a run solved refined to the surface, or without pairs the surface's best (core/mirror_planes).
The asymmetry of a vertex is its distance to the reflected surface; by the reflection's symmetry the two
directions of the Hausdorff distance are equal, so one direction, sampled at the vertices, is the two-way
value. Planes and figures come from the vertices on the surface (core/mesh_quantities.on_surface): a vertex no
face uses is not part of it.
"""

from __future__ import annotations

import numpy as np

from ..core.geometry import MirrorPlane, bounding_diagonal, reflection_across_plane
from ..core.landmark_asymmetry import MirrorFit, fit_mirror_plane
from ..core.mesh_quantities import evenly, on_surface, surface_vertices
from ..core.mirror_fill import distance_to
from ..core.mirror_planes import (DISTINCT, SCREEN_SAMPLES, best_plane_from, fit_surface_mirror_plane,
                                  surface_mirror_planes)
from .verdict import SCAN_NOISE, SOLVED

# Vertices, evenly strided, at which the filter's report measures mirror asymmetry: the mean and RMS of
# 5,000 distances are within about 1.5 % of all of them, at a cost that does not grow with the mesh.
CHECK_SAMPLES = 5_000
# The before/after checks' ICP stop. Point-to-point reflection ICP creeps: on Igea (32k vertices) its
# trimmed RMS falls by about 0.002 % per iteration for 40 iterations after the plane has settled, so
# CONVERGED rarely stops it. Stopping at 1e-4 moved p90 by at most 0.3 % and RMS by at most 0.6 % on Igea,
# Homer, the bunny, Woody and the bent cow (less than the 1.5 % the 5,000-vertex sample costs) and took
# 5-40 % off finding and measuring the input's planes (1.15 -> 1.09 s on Igea, 0.87 -> 0.51 s on Homer).
CHECK_CONVERGED = 1e-4
# Another of the input's planes mirrors it "nearly as well" when its 90th percentile is within this fraction of
# the measured plane's. Distinct planes of a shape with one mirror symmetry differ by far more (the cow's second
# plane: several times the first's); those of a body of revolution agree to within their sampling.
NEARLY = 0.1
# Fewer solved pairs than this do not fix a plane (three points in general position do); the figures then use
# the surface's best plane.
PLANE_PAIRS = 3
BEST = "the input's best plane"  # a measured plane's ``plane_from`` without solved pairs (verdict.SOLVED with)


def distance_summary(distances: np.ndarray) -> dict[str, float]:
    """max, mean, RMS and the 50th, 90th and 99th percentiles of ``distances`` (mesh units)."""
    p50, p90, p99 = np.percentile(distances, [50, 90, 99])
    return {"max": float(distances.max()), "mean": float(distances.mean()),
            "rms": float(np.sqrt(np.mean(distances**2))), "p50": float(p50), "p90": float(p90), "p99": float(p99)}


def pairs_plane(first: np.ndarray, second: np.ndarray) -> MirrorPlane | None:
    """The least-squares mirror plane of the pairs (first[k], second[k]), each (k, 3), as the landmark
    asymmetry is measured (core/landmark_asymmetry.fit_mirror_plane); None with fewer than PLANE_PAIRS pairs
    or any not finite."""
    first, second = np.asarray(first, dtype=float), np.asarray(second, dtype=float)
    if len(first) < PLANE_PAIRS or not (np.isfinite(first).all() and np.isfinite(second).all()):
        return None
    fit = fit_mirror_plane(first, second)
    return MirrorPlane(fit.normal, float(fit.offset))


def before_and_after(before: tuple[np.ndarray, np.ndarray], after: tuple[np.ndarray, np.ndarray],
                     samples: int | None = CHECK_SAMPLES,
                     solved: tuple[MirrorPlane | None, MirrorPlane | None] = (None, None)) -> tuple[dict, dict]:
    """The mirror asymmetry (:func:`mirror_asymmetry`) of two surfaces ``(points (N, 3), faces (F, 3))`` by
    one rule: each against the plane of the solved pairs on it (``solved``: :func:`pairs_plane` on
    ``before`` and on ``after``) refined to the surface by reflection ICP; without them, the best of the
    distinct planes :func:`surface_mirror_planes` finds on ``before``, and for ``after`` the best it
    reaches from them (:func:`best_plane_from`). The filter's checks, ``symblend symmetrize`` and
    ``symblend report`` all measure this way, so the same two surfaces and pairs give the same figures;
    both relative to ``before``'s bounding-box diagonal."""
    starts = input_planes(*before, solved[0])
    diagonal = bounding_diagonal(before[0])
    return (input_asymmetry(*before, starts, diagonal, samples, solved[0]),
            output_asymmetry(*after, starts, diagonal, samples, solved[1]))


def input_planes(points: np.ndarray, faces: np.ndarray, solved: MirrorPlane | None = None) -> list[MirrorPlane]:
    """The distinct mirror planes of the input ``(points (N, 3), faces (F, 3))`` as the before/after checks
    find them (:func:`surface_mirror_planes` of its surface's vertices, each ICP stopped at CHECK_CONVERGED):
    without the ``solved`` pairs' plane, from the principal and the screened starts, best first; with it, from
    the principal starts and it, unpolished (they only name the other planes: the screening finds a plane
    where no pairs say which, and costs most of the checks)."""
    surface = surface_vertices(points, faces)
    if solved is None:
        return surface_mirror_planes(surface, converged=CHECK_CONVERGED)
    return surface_mirror_planes(surface, solved, converged=CHECK_CONVERGED, polish=False)


def input_asymmetry(points: np.ndarray, faces: np.ndarray, starts: list[MirrorPlane], diagonal: float,
                    samples: int | None = CHECK_SAMPLES, solved: MirrorPlane | None = None) -> dict:
    """The ``before`` side of :func:`before_and_after`: against the ``solved`` pairs' plane refined, or
    without it the best of its own ``starts`` (:func:`surface_mirror_planes` of ``points``), relative to
    ``diagonal``; ``plane_from`` says which (SOLVED or BEST); ``other_planes``: those of the ``starts``
    that mirror the input nearly as well (:func:`nearly_as_good`)."""
    plane = starts[0] if solved is None else best_plane_from(surface_vertices(points, faces), [solved], CHECK_CONVERGED)
    to_surface = distance_to(points, faces)  # one search tree for every plane measured
    measured = mirror_asymmetry(points, faces, plane=plane, samples=samples, diagonal=diagonal, to_surface=to_surface)
    return {**measured, "plane_from": BEST if solved is None else SOLVED,
            "other_planes": nearly_as_good(points, faces, plane, starts, diagonal, to_surface)}


def nearly_as_good(points: np.ndarray, faces: np.ndarray, measured: MirrorPlane, planes: list[MirrorPlane],
                   diagonal: float, to_surface=None) -> list[dict]:
    """The ``planes`` other than the ``measured`` one (normals more than DISTINCT apart) that mirror most of
    the input (median mirror asymmetry within a scan's noise, SCAN_NOISE of the diagonal) and whose 90th
    percentile is within NEARLY of the measured plane's, or a scan's noise above it, or below it; on
    SCREEN_SAMPLES evenly strided vertices. A body of revolution or a box has several mirror planes, and the
    one measured need not be the only symmetry; a strongly bent shape, mirrored about as badly by several
    planes, has none to name. Each as ``normal``, ``offset``, ``p90_relative`` (to ``diagonal``), best first.
    ``to_surface``: :func:`~filter_symblend.core.mirror_fill.distance_to` of the surface, if already built."""
    queries = evenly(surface_vertices(points, faces), SCREEN_SAMPLES)
    to_surface = to_surface or distance_to(points, faces)
    normal = np.asarray(measured[0], dtype=float)
    others = [plane for plane in planes if abs(np.asarray(plane[0], dtype=float) @ normal) < np.cos(DISTINCT)]
    if not others:
        return []
    bound = (1.0 + NEARLY) * np.percentile(mirror_distances(points, faces, *measured, queries, to_surface), 90) \
        + SCAN_NOISE * diagonal
    close = []
    for other_normal, offset in others:
        p50, p90 = np.percentile(mirror_distances(points, faces, other_normal, offset, queries, to_surface), [50, 90])
        if p50 < SCAN_NOISE * diagonal and p90 <= bound:
            close.append({"normal": np.asarray(other_normal, dtype=float).tolist(), "offset": float(offset),
                          "p90_relative": float(p90) / diagonal})
    return sorted(close, key=lambda plane: plane["p90_relative"])


def output_asymmetry(points: np.ndarray, faces: np.ndarray, starts: list[MirrorPlane], diagonal: float,
                     samples: int | None = CHECK_SAMPLES, solved: MirrorPlane | None = None) -> dict:
    """The ``after`` side of :func:`before_and_after`: against the ``solved`` pairs' plane on the output
    refined, or without it the best plane reached from the input's ``starts`` (:func:`best_plane_from`),
    relative to the input's ``diagonal``; ``plane_from`` says which."""
    plane = best_plane_from(surface_vertices(points, faces), starts if solved is None else [solved], CHECK_CONVERGED)
    measured = mirror_asymmetry(points, faces, plane=plane, samples=samples, diagonal=diagonal)
    return {**measured, "plane_from": BEST if solved is None else SOLVED}


def mirror_distances(points: np.ndarray, faces: np.ndarray, normal, offset: float,
                     queries: np.ndarray | None = None, to_surface=None) -> np.ndarray:
    """Distance (Q,) from each query (Q, 3) (default: every vertex) to the surface ``(points (N, 3), faces)``
    reflected across the plane, mesh units: the query is reflected instead, and its closest point found on
    the surface itself (by ``to_surface``, :func:`~filter_symblend.core.mirror_fill.distance_to` of it, when
    already built); on a point cloud, the nearest point."""
    mirrored = reflection_across_plane(points if queries is None else queries, np.asarray(normal, dtype=float), offset)
    return (to_surface or distance_to(points, faces))(mirrored)


def mirror_asymmetry(points: np.ndarray, faces: np.ndarray, initial: MirrorFit | None = None,
                     plane: MirrorPlane | None = None, samples: int | None = None,
                     diagonal: float | None = None, to_surface=None) -> dict:
    """The surface against its own reflection across its fitted plane.

    ``plane``: the result of ``fit_surface_mirror_plane`` of the surface's vertices from ``initial`` when it
    is already known, so it is not fitted again. ``samples``: measure at most that many evenly strided
    vertices of the surface (all by default; vertices no face uses are left out). ``diagonal``: the length the
    ``*_relative`` figures divide by (default the surface's own bounding-box diagonal). ``to_surface``:
    :func:`~filter_symblend.core.mirror_fill.distance_to` of the surface, if already built.

    Returns ``{"max", "mean", "rms", "p50", "p90", "p99"}`` (mesh units), the
    same relative to the bounding-box diagonal (``*_relative``), the plane (``plane_normal``,
    ``plane_offset``), ``measured_vertices`` and ``per_vertex`` distances (one per measured vertex; with
    ``samples`` None one per vertex, those no face uses included though not in the figures).
    """
    on = on_surface(faces, len(points))
    surface = points if on.all() else points[on]
    normal, offset = fit_surface_mirror_plane(surface, initial) if plane is None else plane
    queries = points if samples is None else evenly(surface, samples)
    distances = mirror_distances(points, faces, normal, offset, queries, to_surface)
    if diagonal is None:
        diagonal = bounding_diagonal(points)
    measured = distances[on] if samples is None else distances
    stats = distance_summary(measured)
    return {**stats, **{f"{k}_relative": v / diagonal for k, v in stats.items()},
            "plane_normal": np.asarray(normal, dtype=float).tolist(), "plane_offset": float(offset),
            "measured_vertices": len(measured), "per_vertex": distances}

"""Named curves in landmark files: numbered landmarks grouped into curves, resampled on the
surface into semilandmark pairs (the numerics are in semilandmarks.py).

A curve is two or more landmarks whose names differ only by a trailing number, any
separator: "L_zygomatic_arch_1" .. "L_zygomatic_arch_9" (Landmark Editor), "OC_L-1" ..
"OC_L-12" (SlicerMorph curves). The side word works as for single landmarks, so the left
curve pairs with the right curve of the same name; the two may have different numbers of
control points. A curve without a side word lies on the midline.
"""

from __future__ import annotations

import collections
import dataclasses
import warnings

import numpy as np

from ..core.geometry import bounding_diagonal
from ..core.landmark_pairs import LandmarkPairs
from ..core.mesh_graph import edge_graph
from ..core.neighbourhoods import mean_nearest_spacing
from ..errors import LandmarkError, SymblendWarning
from .formats import LandmarkSet
from .pairing import LEFT_WORDS, NUMBERED, RIGHT_WORDS, SnappedPairs, nearest_vertices, side_and_base
from .semilandmarks import resample_curve

DEFAULT_SPACING = 0.01  # of the bounding-box diagonal, when no spacing is given


@dataclasses.dataclass(frozen=True)
class NamedCurve:
    """Landmark indices of a curve in point-number order; ``right`` is None on the midline."""

    name: str
    left: list[int]
    right: list[int] | None


def find_curves(names: list[str], left_words=LEFT_WORDS, right_words=RIGHT_WORDS, midline: bool = False):
    """Curves among ``names`` and the indices of the other names (single landmarks)."""
    groups = collections.defaultdict(dict)
    for index, name in enumerate(names):
        number = NUMBERED.search(name)
        key = number and side_and_base(name[:number.start()], left_words, right_words)
        if key and key[1] not in (*left_words, *right_words):  # "L_12" is landmark 12, not a curve
            points = groups[key]
            if int(number.group(1)) in points:
                raise LandmarkError(f"Curve points {names[points[int(number.group(1))]]!r} and {name!r} have the "
                                    "same number; renumber one.")
            points[int(number.group(1))] = index
    curves = {key: [points[n] for n in sorted(points)] for key, points in groups.items() if len(points) > 1}
    for (side, base), indices in curves.items():
        other = {"left": "right", "right": "left"}.get(side)
        if other and (other, base) not in curves:
            raise LandmarkError(f"Curve {names[indices[0]]!r}..{names[indices[-1]]!r} ({side}) has no {other} "
                                f"curve named like it; add the {other} curve, or rename its points.")
        if side is None and not midline:
            raise LandmarkError(f"Curve {names[indices[0]]!r}..{names[indices[-1]]!r} has no side word; name it "
                                "with a side (L_/R_ prefix or _left/_right suffix), or declare midline curves "
                                "and landmarks (--midline).")
    found = [NamedCurve(base, indices, curves.get(("right", base))) for (side, base), indices in curves.items()
             if side in ("left", None)]
    in_curves = {i for indices in curves.values() for i in indices}
    return found, [i for i in range(len(names)) if i not in in_curves]


def add_curve_pairs(snapped: SnappedPairs, points: np.ndarray, faces: np.ndarray, landmarks: LandmarkSet,
                    curves: list[NamedCurve], *, spacing: float | None = None, source: str = "landmarks",
                    allow_far: bool = False) -> SnappedPairs:
    """``snapped`` with every curve resampled about ``spacing`` apart (mesh units; default 1 % of
    the diagonal) into pairs (or midline landmarks), after its single landmarks.

    Samples on a vertex already used (by a landmark, an earlier curve, or both sides of a
    curve that meet on the midline) are dropped and counted. The result's ``placed_spacing``
    is the mean nearest spacing of the placed points (landmarks and curve control points):
    the width unit that keeps the filter's widths as they would be without semilandmarks.
    """
    if not curves:
        return snapped
    if not len(faces):
        raise LandmarkError(f"{source}: curves are traced on the surface, and this mesh has no faces; "
                            "reconstruct a surface first (e.g. MeshLab's screened Poisson), or leave out --curves.")
    spacing = spacing or DEFAULT_SPACING * bounding_diagonal(points)
    names = landmarks.names()
    graph = edge_graph(points, faces)
    pairs, pair_names = snapped.pairs, list(snapped.pair_names)
    left, right, midline = [pairs.left], [pairs.right], [pairs.midline]
    midline_names, unplaced, summaries = list(snapped.midline_names), list(snapped.unplaced), []
    used = set(np.concatenate([pairs.left, pairs.right, pairs.midline]).tolist())
    placed_vertices = set(used)
    for curve in curves:
        sides = [curve.left] if curve.right is None else [curve.left, curve.right]  # one side: midline
        controls = [[i for i in side if landmarks.landmarks[i].placed] for side in sides]
        unplaced += [names[i] for side, kept in zip(sides, controls) for i in side if i not in kept]
        if min(map(len, controls)) < 2:
            warnings.warn(f"{source}: curve {curve.name!r} has fewer than 2 placed points on a side and is "
                          "left out.", SymblendWarning, stacklevel=2)
            continue
        control_names = [[names[i] for i in side] for side in controls]
        positions = [np.array([landmarks.landmarks[i].position for i in side], dtype=float) for side in controls]
        vertices = [nearest_vertices(points, where, side_names, source, allow_far)[1]
                    for where, side_names in zip(positions, control_names)]
        placed_vertices.update(np.concatenate(vertices).tolist())
        resampled = resample_curve(graph, points, vertices[0], vertices[1] if len(sides) == 2 else None, spacing,
                                   *control_names)
        samples = np.array([resampled.left] if resampled.right is None else [resampled.left, resampled.right])
        keep = ~np.isin(samples, list(used)).any(axis=0) & ((samples[0] != samples[-1]) | (len(samples) == 1))
        stems = [NUMBERED.sub("", side_names[0]) for side_names in control_names]
        if len(samples) == 1:
            midline.append(samples[0, keep])
            midline_names += [f"{stems[0]}:{k}" for k in np.flatnonzero(keep) + 1]
        else:
            left.append(samples[0, keep])
            right.append(samples[1, keep])
            pair_names += [(f"{stems[0]}:{k}", f"{stems[1]}:{k}") for k in np.flatnonzero(keep) + 1]
        used.update(samples[:, keep].ravel().tolist())
        summaries.append({"name": curve.name, "midline": len(samples) == 1,
                          "control_points": [len(side) for side in controls],
                          "surface_length": [resampled.left_length, resampled.right_length][:len(samples)],
                          "samples": int(keep.sum()), "dropped_on_used_vertices": int((~keep).sum())})
    left, right = np.concatenate(left), np.concatenate(right)
    added = len(left) - len(pairs.left)
    return SnappedPairs(LandmarkPairs(np.arange(1, len(left) + 1), left, right, np.concatenate(midline)),
                        pair_names, midline_names, np.vstack([snapped.snap_distances, np.zeros((added, 2))]),
                        unplaced, summaries,
                        mean_nearest_spacing(points[sorted(placed_vertices)]) if len(placed_vertices) > 1 else None)

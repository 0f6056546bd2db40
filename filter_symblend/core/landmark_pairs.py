"""Landmark pairs: decoding the per-vertex pair attribute and checking pairs against a mesh.

Encoding of the attribute (default name ``symblend_pair``): +k on the left
vertex of pair k, -k on the right vertex, 0 on every other vertex; k = 1..n in
any order, gaps allowed.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial import cKDTree

from ..errors import GeometryError, LandmarkError, id_list
from .geometry import flat_normal

FLAT_RATIO = 1e-6  # landmark spread below this fraction of the largest one counts as flat


@dataclasses.dataclass(frozen=True)
class LandmarkPairs:
    """n pairs of vertex indices: pair ``ids[k]`` joins ``left[k]`` (+k) and ``right[k]`` (-k);
    ``midline`` (m,) holds the vertices of midline landmarks (on the symmetry plane);
    ``left_weights``, ``right_weights`` (n,) in [0, 1], or None for all 1 (0: a missing side)."""

    ids: np.ndarray
    left: np.ndarray
    right: np.ndarray
    midline: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    left_weights: np.ndarray | None = None
    right_weights: np.ndarray | None = None


def pairs_from_attribute(values: np.ndarray, attribute: str) -> LandmarkPairs:
    """Decode the pair attribute ``values`` (N,) into pairs sorted by label k."""
    values = np.asarray(values, dtype=float)
    if not np.isfinite(values).all():
        raise LandmarkError(
            f"Attribute `{attribute}` is not finite at vertex {id_list(np.flatnonzero(~np.isfinite(values)))}; "
            "set those vertices to 0 (no landmark) or to a pair label +k / -k."
        )
    labels = np.rint(values)
    fractional = labels != values
    if fractional.any():
        v = np.flatnonzero(fractional)[0]
        raise LandmarkError(
            f"Attribute `{attribute}` holds {values[v]:g} at vertex {v}; pair labels are whole "
            "numbers (+k on the left vertex, -k on the right one, 0 elsewhere)."
        )
    labels = labels.astype(np.int64)
    sides = {}
    for name, sign in (("left", 1), ("right", -1)):
        vertices = np.flatnonzero(sign * labels > 0)
        ids = sign * labels[vertices]
        unique, counts = np.unique(ids, return_counts=True)
        if (counts > 1).any():
            k = unique[counts > 1][0]
            raise LandmarkError(
                f"Pair label {sign * k:+d} is used on {counts[unique == k][0]} vertices "
                f"({id_list(np.flatnonzero(sign * labels == k))}) of attribute `{attribute}`; each label "
                f"must appear once as +{k} and once as -{k}. Renumber the extra ones."
            )
        sides[name] = dict(zip(ids.tolist(), vertices.tolist()))
    for here, there, sign in (("left", "right", 1), ("right", "left", -1)):
        orphans = sorted(set(sides[here]) - set(sides[there]))
        if orphans:
            k = orphans[0]
            raise LandmarkError(
                f"Pair {k}: {sign * k:+d} on vertex {sides[here][k]} has no {-sign * k:+d} partner "
                f"in attribute `{attribute}`"
                + (f" (also unpaired: {', '.join(map(str, orphans[1:11]))})" if len(orphans) > 1 else "")
                + f". Put {-sign * k:+d} on the {there} vertex, or set {sign * k:+d} to 0."
            )
    ids = np.array(sorted(sides["left"]), dtype=np.int64)
    return LandmarkPairs(
        ids,
        np.array([sides["left"][k] for k in ids], dtype=np.int64),
        np.array([sides["right"][k] for k in ids], dtype=np.int64),
    )


def midline_labels(count: int) -> list[str]:
    """Message labels of ``count`` midline landmarks: "midline 1", "midline 2", ..."""
    return [f"midline {j}" for j in range(1, count + 1)]


def _label(label) -> str:
    return label if isinstance(label, str) else f"{label:+d}"


def check_points(points: np.ndarray) -> np.ndarray:
    """``points`` as a float (N, 3) array with finite coordinates, or GeometryError."""
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise GeometryError(f"Vertex coordinates must have shape (N, 3), got {points.shape}.")
    bad = ~np.isfinite(points).all(axis=1)
    if bad.any():
        raise GeometryError(
            f"Vertex coordinates are not finite (NaN or inf) at vertex {id_list(np.flatnonzero(bad))}; "
            "remove or repair those vertices first (e.g. MeshLab's remove unreferenced / "
            "duplicate vertices filters, or re-export the scan)."
        )
    return points


def check_pairs(points: np.ndarray, pairs: LandmarkPairs) -> None:
    """Raise LandmarkError / GeometryError unless ``pairs`` is a usable set on ``points`` (N, 3)."""
    if len(pairs.ids) == 0:
        raise LandmarkError("Found no landmark pair; the filter needs at least one pair (two mirror-image "
                            "landmarks) besides any midline landmarks. Add pairs.")
    for side, ids in ((pairs.left, pairs.ids), (pairs.right, pairs.ids),
                      (pairs.midline, midline_labels(len(pairs.midline)))):
        outside = (side < 0) | (side >= len(points))
        if outside.any():
            raise LandmarkError(
                f"Pair {np.asarray(ids)[outside][0]} names vertex {side[outside][0]}, but the mesh "
                f"has {len(points)} vertices (0..{len(points) - 1})."
            )
    same = pairs.left == pairs.right
    if same.any():
        k = pairs.ids[same][0]
        raise LandmarkError(
            f"Pair {k} pairs vertex {pairs.left[same][0]} with itself. A landmark on the "
            "symmetry plane is not a pair; give pair k two distinct mirror-image vertices."
        )
    vertices = np.concatenate([pairs.left, pairs.right, pairs.midline])
    labels = np.concatenate([pairs.ids.astype(object), -pairs.ids,
                             midline_labels(len(pairs.midline))]).astype(object)
    order = np.argsort(vertices, kind="stable")
    repeated = np.flatnonzero(np.diff(vertices[order]) == 0)
    if repeated.size:
        first, second = labels[order[repeated[0]]], labels[order[repeated[0] + 1]]
        raise LandmarkError(
            f"Vertex {vertices[order[repeated[0]]]} is used by two landmarks ({_label(first)} and "
            f"{_label(second)}); each vertex can hold one landmark."
        )
    positions = points[vertices]
    close = cKDTree(positions).query_pairs(0.0, output_type="ndarray")
    if len(close):
        i, j = close[np.lexsort((close[:, 1], close[:, 0]))[0]]  # deterministic: lowest first
        same_pair = not isinstance(labels[i], str) and not isinstance(labels[j], str) and abs(labels[i]) == abs(labels[j])
        what = (f"Pair {abs(labels[i])}: its two landmarks" if same_pair
                else f"Landmarks {_label(labels[i])} and {_label(labels[j])}")
        raise GeometryError(
            f"{what} sit at the same position (vertices {vertices[i]} and {vertices[j]}). "
            "Merge duplicate vertices (meshing_remove_duplicate_vertices) or move one "
            "landmark; a landmark on the symmetry plane is not a pair."
        )
    _require_plane_and_warp(points, pairs)


def _spread(positions: np.ndarray) -> np.ndarray:
    """Singular values (3,) of ``positions`` (k, 3) about their mean (zeros where k is too small)."""
    values = np.linalg.svd(positions - positions.mean(axis=0), compute_uv=False)
    return np.concatenate([values, np.zeros(3 - len(values))])


def _require_plane_and_warp(points: np.ndarray, pairs: LandmarkPairs) -> None:
    """What the mathematics needs, whatever the counts: a symmetry plane (the pair midpoints and the
    midline landmarks span it: 3 points not on one line, or a line across the pairs' direction) and a warp
    (4 landmarks not on one plane in all; 3 not on one line on a flat mesh). Any two mirror pairs lie on
    one plane, so the warp needs a third pair or a midline landmark off it."""
    on_plane = np.vstack([0.5 * (points[pairs.left] + points[pairs.right]), points[pairs.midline]])
    plane = _spread(on_plane)
    counts = f"{len(pairs.ids)} pair(s) and {len(pairs.midline)} midline landmark(s)"
    spanned = plane[1] > FLAT_RATIO * plane[0]
    if not spanned and plane[0] > 0:  # a line: the plane holds it and is normal to the pairs' direction
        line = np.linalg.svd(on_plane - on_plane.mean(axis=0), full_matrices=False)[2][0]
        across = points[pairs.left] - points[pairs.right]
        spanned = bool((np.abs(across @ line) < (1 - FLAT_RATIO) * np.linalg.norm(across, axis=1)).any())
    if not spanned:
        found = "one point" if plane[0] == 0 else "points on one line along the pairs"
        raise GeometryError(
            f"The symmetry plane is undefined: the pairs' midpoints and the midline landmarks must span it (3 "
            f"points not on one line, or a line across the pairs), and {counts} give {found}. Add a pair or a "
            "midline landmark (--midline) off that line.")
    every = _spread(points[np.concatenate([pairs.left, pairs.right, pairs.midline])])
    if every[1] <= FLAT_RATIO * every[0]:
        raise GeometryError(
            "All landmarks lie (nearly) on one line; the symmetry plane and the warp are "
            "undefined. Add pairs away from that line."
        )
    if every[2] <= FLAT_RATIO * every[0] and flat_normal(points) is None:
        raise GeometryError(
            f"All landmarks ({counts}) lie (nearly) on one plane, and the mesh does not; the 3D warp needs 4 "
            "landmarks not on one plane, and is undefined off that plane. Add pairs off it."
        )

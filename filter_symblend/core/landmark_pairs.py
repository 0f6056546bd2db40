"""Landmark pairs, the one type every layer uses, and their checks against a mesh: each error names the
argument, pair or vertex at fault."""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial import cKDTree

from ..errors import GeometryError, LandmarkError, id_list
from .geometry import flat_normal

FLAT_RATIO = 1e-6  # landmark spread below this fraction of the largest one counts as flat


@dataclasses.dataclass(frozen=True)
class LandmarkPairs:
    """The landmarks, in the one form every layer uses: n pairs of vertex indices, pair ``ids[k]`` (its
    label in messages) joining ``left[k]`` (+k) and ``right[k]`` (-k); ``midline`` (m,) the vertices of
    midline landmarks (on the symmetry plane); ``left_weights``, ``right_weights`` (n,) >= 0, how much each
    landmark's input geometry counts (0: a missing side; above 1: a pair that counts more; all 1 when not
    given). Readers (files, attributes, pairing) and the array API build them as found (the array API's
    may hold None or lists); :func:`check_landmarks` checks them against a mesh, once, into arrays, and
    everything after it trusts them."""

    ids: np.ndarray
    left: np.ndarray
    right: np.ndarray
    midline: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    left_weights: np.ndarray | None = None
    right_weights: np.ndarray | None = None

    def __post_init__(self):
        for side in ("left_weights", "right_weights"):
            if getattr(self, side) is None and isinstance(self.ids, np.ndarray):  # a reader's: labels known
                object.__setattr__(self, side, np.ones(len(self.ids)))

    def is_weighted(self) -> bool:
        """Whether any landmark has a weight other than 1 (a missing side, a pair of priority); weights not
        given (None) are all 1."""
        return any(weights is not None and np.any(np.asarray(weights) != 1)
                   for weights in (self.left_weights, self.right_weights))

    def both_sides(self) -> tuple[np.ndarray, np.ndarray]:
        """(left, right) vertices (c,) of the pairs given on both sides (weight > 0 on each): the pairs that
        say where the mirror plane is."""
        both = (self.left_weights > 0) & (self.right_weights > 0)
        return self.left[both], self.right[both]


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


def _integer_indices(name: str, values) -> np.ndarray:
    values = np.asarray(values).ravel()
    if values.size and values.dtype.kind not in "iu":
        raise LandmarkError(f"`{name}` must hold integer vertex indices, got {values.dtype} values.")
    return values.astype(np.int64)


def _landmark_weights(name: str, weights, count: int, ids) -> np.ndarray:
    if weights is None:
        return np.ones(count)
    weights = np.asarray(weights, dtype=float).ravel()
    if len(weights) != count:
        raise LandmarkError(f"`{name}` must have one weight per pair ({count}), got {len(weights)}.")
    bad = ~((weights >= 0) & (weights <= 1))
    if bad.any():
        raise LandmarkError(f"`{name}` must lie in [0, 1]; pair {ids[bad][0]} has {weights[bad][0]:g}. "
                            "Use 0 for a missing or broken landmark, 1 for a sound one.")
    return weights


def check_landmarks(points: np.ndarray, left, right, pair_ids=None, midline=None, left_weights=None,
                    right_weights=None) -> LandmarkPairs:
    """The landmarks as :class:`LandmarkPairs`, or a LandmarkError / GeometryError naming the fault."""
    left, right = _integer_indices("left", left), _integer_indices("right", right)
    midline = _integer_indices("midline", [] if midline is None else midline)
    ids = np.arange(1, len(left) + 1) if pair_ids is None else np.asarray(pair_ids).ravel()
    if not (len(left) == len(right) == len(ids)):
        raise LandmarkError(
            f"`left`, `right` and `pair_ids` must have one entry per pair; got {len(left)}, "
            f"{len(right)} and {len(ids)}.")
    check_pairs(points, LandmarkPairs(ids, left, right, midline))
    wl = _landmark_weights("left_weights", left_weights, len(left), ids)
    wr = _landmark_weights("right_weights", right_weights, len(left), ids)
    both_missing = (wl == 0) & (wr == 0)
    if both_missing.any():
        raise LandmarkError(f"Pair {ids[both_missing][0]} has weight 0 on both sides, so nothing "
                            "says where it goes; give the sound side weight 1, or remove the pair.")
    return LandmarkPairs(ids, left, right, midline, wl, wr)


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

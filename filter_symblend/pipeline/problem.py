"""The problem a run solves, converted and validated once: the options by ``parameters.validate_parameters``
(an ``Options``, which no door checks again), then ``build_problem`` checks the other arguments in a fixed
order (the points, the faces, the vertices kept out, the missing region, whether the landmarks fit the pair
source, and the landmarks themselves), each message naming the argument, as scipy's RBFInterpolator does;
every adapter (the MeshSet filter, the command, a batch row, a filter script) builds one and hands it to
:func:`filter_symblend.pipeline.solve_problem`."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from ..auto import DEFAULT, AutoConfig
from ..core.geometry import bounding_diagonal
from ..core.landmark_pairs import LandmarkPairs, check_landmarks, check_points
from ..errors import LandmarkError, ParameterError

MINIMUM_UNITS = 3  # landmark pairs and midline landmarks the jackknife needs: each left out leaves two


@dataclasses.dataclass(frozen=True)
class MissingRegion:
    """A part of the mesh that takes the mirror shape of the intact side: ``vertices`` (N,) in [0, 1], how
    much each vertex is missing (1: wholly), and ``faces`` (F,) bool, faces that are not intact surface though
    their vertices are (a hole filler's patch; None: none). As given, unchecked (``vertices`` None: faces
    given alone, which ``build_problem`` refuses), until ``build_problem``."""

    vertices: np.ndarray
    faces: np.ndarray | None = None


@dataclasses.dataclass(frozen=True)
class Problem:
    """One symmetrization, validated: ``points`` (N, 3) float, ``faces`` (F, 3) int (none: a point cloud),
    ``landmarks`` (None with ``pairs='auto'``), ``options`` (every parameter, validated by
    ``parameters.validate_parameters``), ``excluded`` vertex indices (k,) the automatic pairs may not use
    (or None), the ``missing`` region (checked: its faces a (F,) bool array; None without one), and the
    automatic pairs' ``auto_config``."""

    points: np.ndarray
    faces: np.ndarray
    landmarks: LandmarkPairs | None
    options: dict
    excluded: np.ndarray | None
    missing: MissingRegion | None
    auto_config: AutoConfig

    @functools.cached_property
    def diagonal(self) -> float:
        """The bounding-box diagonal of ``points``, mesh units: what relative figures divide by."""
        return bounding_diagonal(self.points)


def build_problem(points, options: dict, landmarks: LandmarkPairs | None = None, faces=None, auto_excluded=None,
                  auto_config=None, missing: MissingRegion | None = None) -> Problem:
    """The :class:`Problem` of these arguments (see ``filter_symblend.symmetrize``), checked in the order of the
    module doc; ``options`` already validated (``parameters.validate_parameters``), ``landmarks`` and the
    ``missing`` region as a reader or the caller gave them (unchecked; None: none given). Raises
    ParameterError or LandmarkError / GeometryError naming the argument, pair or vertex at fault."""
    points = check_points(points)
    faces = _faces(faces, len(points))
    excluded = _excluded_vertices(auto_excluded, len(points), options["pairs"])
    region = None if missing is None else _missing(missing, points, faces)
    if region is not None and options["pairs"] != "landmarks":  # its pairs would pull the intact side toward it
        excluded = np.union1d(np.zeros(0, dtype=np.int64) if excluded is None else excluded,
                              np.flatnonzero(region.vertices > 0))
    if options["pairs"] == "auto" and landmarks is not None:
        raise LandmarkError("`pairs='auto'` finds its own pairs and ignores landmarks; to use "
                            "yours as well, pass pairs='landmarks+auto'.")
    if options["pairs"] != "auto" and (landmarks is None or landmarks.left is None or landmarks.right is None):
        raise LandmarkError(f"`pairs='{options['pairs']}'` needs landmark pairs: pass `left` and "
                            "`right` vertex indices, or use pairs='auto'.")
    if landmarks is not None:
        landmarks = check_landmarks(points, landmarks.left, landmarks.right, landmarks.ids, landmarks.midline,
                                    landmarks.left_weights, landmarks.right_weights)
    _check_uncertainty(options, landmarks)
    return Problem(points, faces, landmarks, options, excluded, region, auto_config or DEFAULT)


def _check_uncertainty(options: dict, landmarks) -> None:
    """ParameterError if ``uncertainty`` cannot be measured for these pairs."""
    placement = options["uncertainty"] == "placement"
    if placement != (options["landmark_precision"] > 0):
        raise ParameterError("`uncertainty='placement'` needs `landmark_precision`: how far a placed landmark lies "
                             "from its true place, an RMS distance in mesh units (place a few landmarks several "
                             "times and measure their scatter)." if placement else
                             f"`landmark_precision` ({options['landmark_precision']:g}) is used only by "
                             "uncertainty='placement'; set that, or leave `landmark_precision` at 0.")
    if options["uncertainty"] == "none":
        return
    if options["pairs"] != "landmarks":
        raise ParameterError(f"`uncertainty='{options['uncertainty']}'` leaves out each landmark pair in turn; with "
                             f"pairs='{options['pairs']}' the automatic pairs are not measured yet. Use "
                             "pairs='landmarks' (e.g. the pairs written by `symblend pairs`), or uncertainty='none'.")
    units = len(landmarks.left) + len(landmarks.midline)
    if units < MINIMUM_UNITS:
        raise ParameterError(f"`uncertainty='{options['uncertainty']}'` leaves out each landmark pair and midline "
                             f"landmark in turn, and needs at least {MINIMUM_UNITS} of them; there are {units}. "
                             "Add landmarks, or use uncertainty='none'.")


def _excluded_vertices(auto_excluded, count: int, pairs: str) -> np.ndarray | None:
    """``auto_excluded`` (a (count,) bool mask or vertex indices) as distinct vertex indices (k,)."""
    if auto_excluded is None:
        return None
    if pairs == "landmarks":
        raise ParameterError("`auto_excluded` keeps vertices out of the automatic pairs, and pairs='landmarks' "
                             "finds none; use pairs='auto' or 'landmarks+auto', or leave it out.")
    values = np.asarray(auto_excluded)
    if values.dtype == bool:
        if values.shape != (count,):
            raise ParameterError(f"`auto_excluded` as a mask needs one entry per vertex ({count}), got shape "
                                 f"{values.shape}.")
        return np.flatnonzero(values)
    values = values.ravel()
    if values.size and values.dtype.kind not in "iu":
        raise ParameterError(f"`auto_excluded` must hold integer vertex indices, got {values.dtype} values.")
    indices = values.astype(np.int64)
    outside = (indices < 0) | (indices >= count)
    if outside.any():
        raise ParameterError(f"`auto_excluded` holds vertex {indices[outside][0]}, but the mesh has vertices "
                             f"0..{count - 1}.")
    return np.unique(indices)


def _faces(faces, count: int) -> np.ndarray:
    if faces is None:
        return np.zeros((0, 3), dtype=np.int64)
    faces = np.asarray(faces)
    if faces.size and (faces.ndim != 2 or faces.shape[1] != 3 or faces.dtype.kind not in "iu"):
        raise ParameterError(f"`faces` must be an (F, 3) array of vertex indices, got shape {faces.shape} of "
                             f"{faces.dtype}.")
    faces = faces.reshape(-1, 3).astype(np.int64)
    outside = (faces < 0) | (faces >= count)
    if outside.any():
        row = int(np.flatnonzero(outside.any(axis=1))[0])
        raise ParameterError(f"`faces` row {row} refers to vertex {faces[outside][0]}, but there are {count} "
                             f"vertices (0..{count - 1}).")
    return faces


def _missing(missing: MissingRegion, points: np.ndarray, faces: np.ndarray) -> MissingRegion:
    """The ``missing`` region checked: its vertices (N,) clipped to [0, 1], its faces a (F,) bool array."""
    if missing.vertices is None:
        raise ParameterError("`missing_faces` marks faces of the missing region; give `missing` too.")
    if len(faces) == 0:
        raise ParameterError("`missing` vertices take the mirror shape of the intact surface, and there is none "
                             "without faces; pass `faces`, or leave `missing` out.")
    values = np.asarray(missing.vertices, dtype=float)
    if values.shape != (len(points),) or not np.isfinite(values).all():
        raise ParameterError(f"`missing` needs one finite value in [0, 1] per vertex ({len(points)}), got "
                             f"shape {values.shape}.")
    excluded = np.zeros(len(faces), dtype=bool) if missing.faces is None else np.asarray(missing.faces, dtype=bool)
    if excluded.shape != (len(faces),):
        raise ParameterError(f"`missing_faces` needs one bool per face ({len(faces)}), got shape {excluded.shape}.")
    return MissingRegion(np.clip(values, 0.0, 1.0), excluded)

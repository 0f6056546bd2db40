"""``filter_symblend.symmetrize``: the paper's method with landmark pairs, automatic pairs, or both."""

from __future__ import annotations

import dataclasses
import inspect

import numpy as np

from .auto import DEFAULT, symmetrize_automatic
from .core.landmark_pairs import check_points
from .core.mirror_fill import fill_from_mirror
from .core.symmetrize import SymmetrizationResult, check_landmarks, solve
from .errors import LandmarkError, ParameterError
from .parameters import ARRAYS, CORE, keyword_signature, parameters_doc, validate_parameters


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


def _missing(missing, missing_faces, points: np.ndarray, faces: np.ndarray):
    """(missing (N,) in [0, 1], faces left out of the intact surface (F,) bool) checked, or None."""
    if missing is None:
        if missing_faces is not None:
            raise ParameterError("`missing_faces` marks faces of the missing region; give `missing` too.")
        return None
    if len(faces) == 0:
        raise ParameterError("`missing` vertices take the mirror shape of the intact surface, and there is none "
                             "without faces; pass `faces`, or leave `missing` out.")
    values = np.asarray(missing, dtype=float)
    if values.shape != (len(points),) or not np.isfinite(values).all():
        raise ParameterError(f"`missing` needs one finite value in [0, 1] per vertex ({len(points)}), got "
                             f"shape {values.shape}.")
    excluded = np.zeros(len(faces), dtype=bool) if missing_faces is None else np.asarray(missing_faces, dtype=bool)
    if excluded.shape != (len(faces),):
        raise ParameterError(f"`missing_faces` needs one bool per face ({len(faces)}), got shape {excluded.shape}.")
    return np.clip(values, 0.0, 1.0), excluded


def _filled(result: SymmetrizationResult, points, faces, missing, missing_faces, frame: str) -> SymmetrizationResult:
    """``result`` (input frame) with the missing region given the mirror shape of the intact side, then in
    ``frame``; the asymmetry stays the distance moved in the input frame."""
    report = result.report
    filled = fill_from_mirror(result.points, faces, missing, report["plane_normal"], report["plane_offset"],
                              missing_faces)
    report["filled_vertices"] = int(np.count_nonzero(missing))
    result = dataclasses.replace(result, points=filled, asymmetry=np.linalg.norm(filled - points, axis=1))
    if frame == "canonical":
        transform = np.array(report["canonical_from_input"])
        result = dataclasses.replace(result, points=result.points @ transform[:3, :3].T + transform[:3, 3])
        report.update(output_frame="canonical", plane_normal=[1.0, 0.0, 0.0], plane_offset=0.0)
    return result


def symmetrize(points, left=None, right=None, pair_ids=None, midline=None, left_weights=None,
               right_weights=None, progress=None, faces=None, auto_excluded=None, auto_config=None,
               missing=None, missing_faces=None, **params) -> SymmetrizationResult:
    options = validate_parameters(params, ARRAYS)
    points = check_points(points)
    faces = _faces(faces, len(points))
    excluded = _excluded_vertices(auto_excluded, len(points), options["pairs"])
    region = _missing(missing, missing_faces, points, faces)
    if region is None:
        return _symmetrize(points, left, right, pair_ids, midline, left_weights, right_weights, progress, faces,
                           excluded, auto_config, options)
    if options["pairs"] != "landmarks":  # a missing part's pairs would pull the intact side toward it
        excluded = np.union1d(np.zeros(0, dtype=np.int64) if excluded is None else excluded,
                              np.flatnonzero(region[0] > 0))
    result = _symmetrize(points, left, right, pair_ids, midline, left_weights, right_weights, progress, faces,
                         excluded, auto_config, {**options, "output_frame": "input"})
    return _filled(result, points, faces, *region, options["output_frame"])


def _symmetrize(points, left, right, pair_ids, midline, left_weights, right_weights, progress, faces,
                excluded, auto_config, options) -> SymmetrizationResult:
    """The run for checked ``points``, ``faces`` and ``excluded`` vertex indices (k,) or None."""
    if progress is not None:
        progress(0.0, "checking the input")
    core = {key: value for key, value in options.items() if key in validate_parameters({}, CORE)}
    given = left is not None or right is not None or midline is not None
    if options["pairs"] == "auto":
        if given:
            raise LandmarkError("`pairs='auto'` finds its own pairs and ignores landmarks; to use "
                                "yours as well, pass pairs='landmarks+auto'.")
        return symmetrize_automatic(points, faces, options, None, excluded, progress, auto_config or DEFAULT)
    if left is None or right is None:
        raise LandmarkError(f"`pairs='{options['pairs']}'` needs landmark pairs: pass `left` and "
                            "`right` vertex indices, or use pairs='auto'.")
    landmarks = check_landmarks(points, left, right, pair_ids, midline, left_weights, right_weights)
    if options["pairs"] == "landmarks+auto":
        return symmetrize_automatic(points, faces, options, landmarks, excluded, progress, auto_config or DEFAULT)
    return solve(points, landmarks, core, progress)


symmetrize.__signature__ = keyword_signature(
    *(inspect.Parameter(name, inspect.Parameter.POSITIONAL_OR_KEYWORD, default=default)
      for name, default in (("points", inspect.Parameter.empty), ("left", None), ("right", None),
                            ("pair_ids", None), ("midline", None), ("left_weights", None),
                            ("right_weights", None), ("progress", None), ("faces", None),
                            ("auto_excluded", None), ("auto_config", None), ("missing", None),
                            ("missing_faces", None))),
    layers=ARRAYS)
symmetrize.__doc__ = f"""Symmetrize ``points`` (N, 3) from landmark pairs (left[k], right[k]), automatic pairs, or both.

Implements Ghosh, Amenta and Kazhdan, *Closed-form Blending of Local
Symmetries* (SGP 2010): a local transform per pair (Step 1), one sparse
least-squares solve for a single global bilateral symmetry (Step 2), and a
thin-plate-spline warp of every point. With ``pairs='auto'`` the pairs are
found on the surface (``filter_symblend.auto``) and go through the same checks.

Parameters
----------
points : (N, 3) float array
    Vertex coordinates, any unit.
left, right : (n,) int arrays
    Vertex indices of the left and right landmark of each pair, n >= 1, with
    ``midline`` spanning a symmetry plane and 4 landmarks off one plane in all
    (3 pairs, or 2 pairs and a midline landmark; none with ``pairs='auto'``).
pair_ids : (n,) int array, optional
    Pair labels used in messages (default 1..n).
midline : (m,) int array, optional
    Vertices of midline landmarks: they end up exactly on the symmetry plane.
left_weights, right_weights : (n,) float arrays in [0, 1], optional
    How much each landmark's input geometry counts (default 1). 0 marks a
    missing or broken side: it becomes the mirror image of the other side.
progress : callable(percent: float, message: str), optional
    Called at the start of each stage, as MeshLab filters report progress.
    An exception it raises (or Ctrl-C) stops the run; nothing is changed.
faces : (F, 3) int array, optional
    Triangles, used by the automatic pairs (the surface between the
    vertices); without them the points are treated as a point cloud.
auto_excluded : (N,) bool array or (k,) int array of vertex indices, optional
    Vertices no automatic pair may use, nor pair with (a missing or broken
    part, whose shape must not shape the other side); only with
    ``pairs='auto'`` or ``'landmarks+auto'``.
auto_config : filter_symblend.auto.AutoConfig, optional
    The automatic pairs' settings (default ``AutoConfig()``; see its fields).
missing : (N,) float array in [0, 1], optional
    How much of each vertex is missing or broken: after the solve it moves
    that far toward its closest point on the intact surface reflected across
    the symmetry plane (the paper's Figure 9), faded in at the border; with
    automatic pairs these vertices are kept out of the pairs. Needs ``faces``.
missing_faces : (F,) bool array, optional
    Faces that are not intact surface though their vertices are (e.g. the
    patch a hole filler spanned); only with ``missing``.
{parameters_doc(ARRAYS)}

Returns
-------
SymmetrizationResult
    ``points`` (N, 3) output, ``asymmetry`` (N,) distance moved per vertex,
    ``report`` dict (see the docs).

Raises
------
SymblendError (a ValueError) naming the parameter, pair or vertex at fault;
SymmetryNotFoundError when automatic pairs find no mirror symmetry.

Examples
--------
>>> import numpy as np, filter_symblend
>>> from filter_symblend import synthetic
>>> points, faces = synthetic.icosphere(3)
>>> result = filter_symblend.symmetrize(synthetic.bend(synthetic.bumpy(points), 0.3), faces=faces, pairs="auto")
>>> result.report["auto_pairs"]["twins_are"]
'exact vertices'
"""

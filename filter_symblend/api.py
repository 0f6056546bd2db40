"""The public API on arrays: ``filter_symblend.symmetrize`` and ``filter_symblend.find_mirror_pairs``
(the package root re-exports them). Each builds one validated problem (pipeline/problem) and solves it
(pipeline/run); the MeshSet filter and the ``symblend`` command are the other doors to the same two
steps."""

from __future__ import annotations

import inspect

from .core.landmark_pairs import LandmarkPairs
from .core.mirror_pairs import MirrorPairs
from .core.solve import SymmetrizationResult
from .errors import ParameterError
from .parameters import ARRAYS, keyword_signature, parameters_doc, validate_parameters
from .pipeline import MissingRegion, build_problem, solve_problem


def symmetrize(points, left=None, right=None, pair_ids=None, midline=None, left_weights=None,
               right_weights=None, progress=None, faces=None, auto_excluded=None, auto_config=None,
               missing=None, missing_faces=None, **params) -> SymmetrizationResult:
    given = None if left is None and right is None and midline is None else \
        LandmarkPairs(pair_ids, left, right, midline, left_weights, right_weights)
    region = None if missing is None and missing_faces is None else MissingRegion(missing, missing_faces)
    problem = build_problem(points, validate_parameters(params, ARRAYS), given, faces, auto_excluded, auto_config,
                            region)
    return solve_problem(problem, progress)


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
    ``report`` (a :class:`~filter_symblend.core.report.Report`: typed
    attributes; ``report.to_dict()`` is the JSON form, docs/method.md).

Raises
------
SymblendError (a ValueError) naming the parameter, pair or vertex at fault;
SymmetryNotFoundError when automatic pairs find no mirror symmetry.

Examples
--------
>>> import numpy as np, filter_symblend
>>> from filter_symblend.testing import synthetic
>>> points, faces = synthetic.icosphere(3)
>>> result = filter_symblend.symmetrize(synthetic.bend(synthetic.bumpy(points), 0.3), faces=faces, pairs="auto")
>>> result.report.auto_pairs.twins_are
'exact vertices'
"""


def find_mirror_pairs(points, faces=None, left=None, right=None, pair_ids=None, midline=None, progress=None,
                      auto_excluded=None, auto_config=None, **params) -> MirrorPairs:
    """Every vertex's mirror twin on the surface of ``points`` (N, 3) with ``faces`` (F, 3) (None: a point
    cloud), as ``symmetrize(..., pairs='auto')`` finds them, or ``'landmarks+auto'`` when landmark pairs
    ``left``, ``right`` (n,) are given (their vertices, and ``auto_excluded``, get no twin).

    ``params``: the automatic pairs' options of :func:`symmetrize` (``pairs`` must not be 'landmarks').
    The map is the one the symmetrization's last kept round used, so finding it costs a symmetrization.

    Returns a :class:`~filter_symblend.core.mirror_pairs.MirrorPairs`: ``vertex`` (k,) with a twin,
    ``twin`` (k, 3) on the input surface, ``confidence`` (k,) in [0, 1], and ``report`` (which map, the
    share of pairable vertices with a twin and with a confident one).

    >>> import filter_symblend
    >>> from filter_symblend.testing import synthetic
    >>> points, faces = synthetic.icosphere(3)
    >>> twins = filter_symblend.find_mirror_pairs(synthetic.bend(synthetic.bumpy(points), 0.3), faces)
    >>> bool(twins.report.confident_share > 0.9)
    True
    """
    params.setdefault("pairs", "auto" if left is None else "landmarks+auto")
    if params["pairs"] == "landmarks":
        raise ParameterError("find_mirror_pairs finds automatic pairs: use pairs='auto', or 'landmarks+auto' "
                             "with landmark pairs (left, right); pairs='landmarks' has no mirror map to return.")
    return symmetrize(points, left, right, pair_ids, midline, progress=progress, faces=faces,
                      auto_excluded=auto_excluded, auto_config=auto_config, **params).mirror_pairs

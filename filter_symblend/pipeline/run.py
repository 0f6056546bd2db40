"""A problem validated once (pipeline/problem) solved: the paper's method with landmark pairs, automatic
pairs, or both, then the missing region's fill, the output frame and the uncertainty; behind
``filter_symblend.symmetrize`` (api), the MeshSet filter and the command."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np

from ..auto import solve_with_automatic_pairs
from ..core.mirror_fill import fill_from_mirror
from ..core.geometry import MirrorPlane
from ..core.placement import placement_spread
from ..core.solve import SymmetrizationResult, landmark_targets, scaled_progress, solve
from ..core.uncertainty import jackknife
from ..errors import SymblendWarning
from ..parameters import CORE, options_of
from .problem import MissingRegion, Problem


def _filled(result: SymmetrizationResult, points, faces, missing: MissingRegion, frame: str) -> SymmetrizationResult:
    """``result`` (input frame) with the missing region given the mirror shape of the intact side, then in
    ``frame``; the asymmetry stays the distance moved in the input frame."""
    report = result.report
    filled = fill_from_mirror(result.points, faces, missing.vertices, report.plane.normal, report.plane.offset,
                              missing.faces)
    asymmetry = np.linalg.norm(filled - points, axis=1)
    report = report.replace(filled_vertices=int(np.count_nonzero(missing.vertices)))
    if frame == "canonical":
        transform = report.canonical_from_input
        filled = filled @ transform[:3, :3].T + transform[:3, 3]
        report = report.replace(output_frame="canonical", plane=MirrorPlane(np.array([1.0, 0.0, 0.0]), 0.0))
    return dataclasses.replace(result, points=filled, asymmetry=asymmetry, report=report)


def _with_uncertainty(result: SymmetrizationResult, problem: Problem, core: dict, progress) -> SymmetrizationResult:
    """``result`` with the jackknife of its landmarks (core/uncertainty) and, with 'placement', the spread
    their placement error causes (core/placement): per-vertex values and the report's ``uncertainty``."""
    if progress is not None:
        progress(70.0, f"uncertainty: {len(problem.landmarks.left) + len(problem.landmarks.midline)} landmarks "
                       "left out in turn")
    full = landmark_targets(problem.points, problem.landmarks, core)
    measured = jackknife(problem.points, problem.landmarks, core, full)
    if core["uncertainty"] == "placement":
        measured = dataclasses.replace(measured, per_vertex=placement_spread(
            problem.points, problem.faces, problem.landmarks, core, full, core["landmark_precision"]))
    summary = measured.summary(result.report.diagonal, core["uncertainty"], core["landmark_precision"] or None)
    for message in summary.warnings:
        warnings.warn(message, SymblendWarning, stacklevel=4)
    if progress is not None:
        progress(100.0, "done")
    return dataclasses.replace(result, uncertainty=measured.per_vertex,
                               report=result.report.replace(uncertainty=summary))


def solve_problem(problem: Problem, progress=None) -> SymmetrizationResult:
    """The symmetrization of a validated ``problem``: the landmarks' solve, the automatic pairs' rounds, or
    both, then the missing part filled from its mirror; ``progress(percent, message)`` at each stage."""
    options = problem.options
    if problem.missing is not None:  # filled in the input frame, then moved to the frame asked for
        options = {**options, "output_frame": "input"}
    if progress is not None:
        progress(0.0, "input checked")
    if options["pairs"] == "landmarks":
        core = options_of(options, CORE)
        result = solve(problem.points, problem.landmarks, core, scaled_progress(progress, 0.0, 70.0)
                       if options["uncertainty"] != "none" else progress)
        if options["uncertainty"] != "none":
            result = _with_uncertainty(result, problem, core, progress)
    else:
        result = solve_with_automatic_pairs(problem.points, problem.faces, options, problem.landmarks,
                                            problem.excluded, progress, problem.auto_config)
    if problem.missing is None:
        return result
    return _filled(result, problem.points, problem.faces, problem.missing, problem.options["output_frame"])

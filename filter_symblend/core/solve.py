"""The paper's method on arrays, from checked landmarks (``landmark_pairs``): Step 1, Step 2, warp,
report. No pymeshlab here, and nothing about where the pairs come from (automatic pairs are a layer
above, ``filter_symblend.auto``)."""

from __future__ import annotations

import dataclasses
import time
import warnings

import numpy as np

from ..errors import GeometryError, SymblendWarning, id_list
from .geometry import MirrorPlane, bounding_diagonal, flat_normal, minimal_rotation, normalize, rigid_fit
from .global_solve import MINUS_X, global_solve
from .landmark_asymmetry import fit_mirror_plane
from .landmark_pairs import LandmarkPairs, midline_labels
from .local_symmetries import LocalSymmetries, local_symmetries
from .mirror_pairs import MirrorPairs
from .neighbourhoods import mean_nearest_spacing, pair_weights_at, require_connected, scaled_weights
from .report import LocalFit, Report, Spread, Timings, Widths
from .warp import thin_plate_spline

# A pair's own mirror misfit, in neighbourhood radii, above which it is reported.
# Measured on the cow and spot: sound pairs stay below 1.2 under bends, compression
# and articulation; a landmark paired with a vertex half a diagonal away scores
# above 2 with 60 pairs. Subtler mispairings cannot be told from real deformation.
POOR_PAIR_MISFIT = 1.5
SWAPPED_COSINE = -0.5  # a pair whose gap points this far against its local normal looks swapped


@dataclasses.dataclass(frozen=True)
class SymmetrizationResult:
    """Output of :func:`symmetrize`.

    points (N, 3): the warped vertices, in the frame chosen by ``output_frame``.
    asymmetry (N,): distance each vertex moved, measured in the input frame.
    report: what was measured (core/report): pair count, plane, landmark asymmetry before/after,
    widths, seconds; ``report.to_dict()`` is its JSON form.
    mirror_pairs: with automatic pairs, the mirror map they came from (every vertex's twin, with its
    confidence); None with landmark pairs alone.
    uncertainty (N,): with ``uncertainty='jackknife'``, the jackknife standard error of each restored
    vertex (core/uncertainty); with 'placement', its RMS change under the landmarks' placement error
    (core/placement); mesh units; else None.
    """

    points: np.ndarray
    asymmetry: np.ndarray
    report: Report
    mirror_pairs: MirrorPairs | None = None
    uncertainty: np.ndarray | None = None


def _warn_about_local_fits(local: LocalSymmetries, left, right, ids: np.ndarray, mode: str) -> None:
    gaps = np.einsum("nij,nj->ni", local.gap_transforms, right - left)
    cosine = np.einsum("ni,ni->n", local.normals, normalize(gaps))
    swapped = cosine < SWAPPED_COSINE
    if swapped.any():
        warnings.warn(
            f"Pair(s) {id_list(ids[swapped])} look swapped: the +k landmark "
            "lies on the right-hand (-k) side of its local mirror plane. Exchange +k and -k.",
            SymblendWarning, stacklevel=3)
    poor = local.pair_misfits > POOR_PAIR_MISFIT
    if poor.any():
        worst = np.argmax(local.pair_misfits)
        warnings.warn(
            f"Pair(s) {id_list(ids[poor])} are not mirror images of each other "
            f"under their local '{mode}' symmetry (misfit up to {local.pair_misfits[worst]:.2f} "
            f"neighbourhood radii at pair {ids[worst]}; sound pairs stay below 0.5). Check that "
            "each of them joins the right two vertices.", SymblendWarning, stacklevel=3)
    if local.point_reflections.any():
        warnings.warn(
            f"Around pair(s) {id_list(ids[local.point_reflections])} one side is "
            "turned half a revolution against the other, so no local rotation axis exists; "
            "no rotation was applied there.", SymblendWarning, stacklevel=3)


def _kept_flat(warped: np.ndarray, reference: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """``warped`` (N, 3) with its coordinate along the flat input's ``normal`` (3,) that of ``reference``
    (N, 3): exactly, when the normal is a coordinate axis (a drawing at z = 0 stays at z = 0)."""
    axis = int(np.argmax(np.abs(normal)))
    if abs(normal[axis]) == 1.0:
        out = warped.copy()
        out[:, axis] = reference[:, axis] if reference is not warped else np.mean(reference[:, axis])
        return out
    return warped - np.outer((warped - reference) @ normal, normal) if reference is not warped else \
        warped - np.outer(warped @ normal - np.mean(warped @ normal), normal)


def _report_progress(progress, percent: float, message: str) -> None:
    if progress is not None:
        progress(percent, message)


_MEASURED = object()  # landmark_targets' default ``flat``: measure it


@dataclasses.dataclass(frozen=True)
class LandmarkTargets:
    """Steps 1 and 2 on checked landmarks: where each landmark vertex goes. ``vertices`` (k,): the landmark
    vertices (left sides, right sides, midline), ``target`` (k, 3) their symmetric positions in the input
    frame; ``solved`` (k, 3) the same in the canonical frame (plane x = 0) and ``rotation``, ``translation``
    the rigid map from it to the input frame; ``local`` Step 1; the widths and spacings used."""

    vertices: np.ndarray
    target: np.ndarray
    solved: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    local: LocalSymmetries
    flat: np.ndarray | None
    measured_spacing: float
    spacing: float
    phi_h: float
    theta_h: float

    @property
    def plane(self) -> MirrorPlane:
        """The restored symmetry's plane in the input frame: the canonical frame's x = 0 moved by the rigid map."""
        normal = self.rotation[:, 0]
        return MirrorPlane(normal, float(normal @ self.translation))


def landmark_targets(points: np.ndarray, landmarks: LandmarkPairs, options: dict, progress=None,
                     warn: bool = False, clock: dict | None = None, flat=_MEASURED) -> LandmarkTargets:
    """Step 1 and Step 2 (the paper's local symmetries and their blend) for checked ``landmarks`` on
    ``points`` (N, 3), with validated core ``options``; ``warn``: warn about pairs that look swapped or
    are poor mirror images; ``clock``: stage end times are added to it; ``flat``: the input's
    :func:`~.geometry.flat_normal` when already known (a repeated solve on the same input), else measured."""
    clock = {} if clock is None else clock
    left, right, ids, midline = landmarks.left, landmarks.right, landmarks.ids, landmarks.midline
    wl, wr = landmarks.left_weights, landmarks.right_weights
    # Midline landmarks join the solve as pairs whose two sides are one vertex,
    # held on the plane; labels for messages.
    n, m = len(left), len(midline)
    all_left, all_right = np.concatenate([left, midline]), np.concatenate([right, midline])
    labels = np.concatenate([ids.astype(object), midline_labels(m)])
    wl, wr = np.concatenate([wl, np.ones(m)]), np.concatenate([wr, np.ones(m)])
    on_plane = np.arange(n + m) >= n
    unique = np.concatenate([left, right, midline])  # each landmark vertex once: warp centres

    p, q = points[all_left], points[all_right]
    centre = points[unique].mean(axis=0)
    p0, q0 = p - centre, q - centre
    measured_spacing = mean_nearest_spacing(points[unique])
    spacing = options["width_spacing"] or measured_spacing
    phi_h, theta_h = options["phi_width"] * spacing, options["theta_width"] * spacing
    phi, theta = pair_weights_at(p0, q0, [phi_h, theta_h])  # one neighbour search for both
    require_connected(phi, p0, q0, labels, spacing, "phi_width", options["phi_width"])
    if (wl * wr != 1).any():  # a broken side must not shape the local symmetries around it,
        theta = scaled_weights(theta, np.ones(n + m), wl * wr)  # a landmark of priority shapes them more
    clock["neighbourhoods"] = time.perf_counter()
    _report_progress(progress, 10.0, f"local symmetries ({options['mode']})")

    flat = flat_normal(points) if flat is _MEASURED else flat  # a flat (2D) input: every stage keeps to its plane
    local = local_symmetries(options["mode"], theta, p0, q0, labels, flat)
    if warn:
        _warn_about_local_fits(local, p0, q0, labels, options["mode"])
    clock["local_transforms"] = time.perf_counter()
    _report_progress(progress, 25.0, f"global solve ({n + m} pairs)")

    # Pre-align: the mean local normal goes to -x, so the smallest rotations Q_i
    # of Step 2 are taken relative to the global symmetry and the result does not
    # depend on the input pose (bent cow, three poses: shape error 0.24-1.31% of
    # the diagonal without this, 0.23% with it).
    frame = minimal_rotation(normalize(local.normals.mean(axis=0)), MINUS_X)[0]
    r, s = global_solve(phi, p0 @ frame.T, q0 @ frame.T, local.rotated(frame), options["alpha"],
                        weights=(wl, wr), on_plane=on_plane)
    solved = np.vstack([r[:n], s[:n], r[n:]])
    if not np.isfinite(solved).all():
        raise GeometryError(
            "The solve gave non-finite coordinates: its system is singular for these pairs (e.g. pairs far "
            "from each other at this `phi_width`, or landmarks in a degenerate layout). Check the pairs, or "
            "raise `phi_width`.")
    rotation, translation = rigid_fit(solved, points[unique], np.concatenate([wl[:n], wr[:n], np.ones(m)]))
    clock["global_solve"] = time.perf_counter()
    return LandmarkTargets(unique, solved @ rotation.T + translation, solved, rotation, translation, local, flat,
                           measured_spacing, spacing, phi_h, theta_h)


def solve(points: np.ndarray, landmarks: LandmarkPairs, options: dict, progress=None,
          warn: bool = True) -> SymmetrizationResult:
    """Step 1, Step 2 and the warp for checked ``landmarks`` on ``points`` (N, 3), with validated core
    ``options``; ``warn``: warn about pairs that look swapped or are poor mirror images."""
    clock = {"start": time.perf_counter()}
    left, right = landmarks.left, landmarks.right
    steps = landmark_targets(points, landmarks, options, progress, warn, clock)
    unique, solved, rotation, translation = steps.vertices, steps.solved, steps.rotation, steps.translation
    flat, local, centres = steps.flat, steps.local, points[unique]
    diagonal = bounding_diagonal(points)
    _report_progress(progress, 50.0, f"warping {len(points)} vertices")

    target = steps.target
    spline = thin_plate_spline(centres, target - centres, flat)
    warped = points.copy()
    warped[unique] = target
    others = np.ones(len(points), dtype=bool)  # the landmarks' own values are the targets: not evaluated
    others[unique] = False
    warped[others] += spline(points[others], None if progress is None else
                             lambda fraction: progress(50.0 + 50.0 * fraction, f"warping {len(points)} vertices"))
    if not np.isfinite(warped).all():
        raise GeometryError(
            "The solve gave non-finite coordinates in the warp: its system is singular for these landmarks "
            "(e.g. several at nearly the same position). Check the landmarks.")
    if flat is not None:
        warped = _kept_flat(warped, points, flat)
    asymmetry = np.linalg.norm(warped - points, axis=1)
    if options["output_frame"] == "canonical":
        warped = (warped - translation) @ rotation
        warped[unique] = solved
        if flat is not None:
            warped = _kept_flat(warped, warped, rotation.T @ flat)
        plane = MirrorPlane(np.array([1.0, 0.0, 0.0]), 0.0)
    else:
        plane = steps.plane
    clock["warp"] = time.perf_counter()
    _report_progress(progress, 100.0, "done")

    stages = ("neighbourhoods", "local_transforms", "global_solve", "warp")
    ends = [clock["start"]] + [clock[stage] for stage in stages]
    report = Report(
        pair_count=int(len(left)),
        midline_count=int(len(landmarks.midline)),
        mode=options["mode"],
        output_frame=options["output_frame"],
        plane=plane,
        canonical_from_input=np.block([[rotation.T, (-rotation.T @ translation)[:, None]],
                                       [np.zeros((1, 3)), np.ones((1, 1))]]),
        landmark_asymmetry_before=fit_mirror_plane(points[left], points[right]).summary(diagonal),
        landmark_asymmetry_after=fit_mirror_plane(warped[left], warped[right]).summary(diagonal),
        vertex_displacement=Spread.of(asymmetry),
        diagonal=diagonal,
        widths=Widths(steps.measured_spacing, steps.spacing, options["phi_width"], steps.phi_h,
                      options["theta_width"], steps.theta_h, options["alpha"]),
        local_fit=LocalFit(float(np.median(local.residuals)), float(local.residuals.max()),
                           float(local.stretch.min()), float(local.stretch.max())),
        warp=spline.description,
        seconds=Timings({stage: end - begin for stage, begin, end in zip(stages, ends, ends[1:])},
                        ends[-1] - ends[0]),
    )
    return SymmetrizationResult(warped, asymmetry, report)


def scaled_progress(progress, start: float, width: float):
    """``progress`` for a sub-task that reports 0..100 % into start..start + width."""
    if progress is None:
        return None
    return lambda percent, message: progress(start + width * percent / 100.0, message)

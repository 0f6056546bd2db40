"""The whole method on arrays: validate, Step 1, Step 2, warp, report. No pymeshlab here."""

from __future__ import annotations

import dataclasses
import inspect
import time
import warnings
from typing import Any

import numpy as np

from .asymmetry import fit_mirror_plane
from .auto_pairs import first_correspondences, mirror_correspondence, spread_pairs, unmoved_pairs
from .errors import GeometryError, LandmarkError, ParameterError, SymblendWarning, id_list
from .geometry import minimal_rotation, normalize, rigid_fit
from .global_solve import MINUS_X, global_solve
from .landmarks import MIN_PAIRS, LandmarkPairs, check_pairs, check_points, midline_labels
from .local_symmetries import LocalSymmetries, local_symmetries
from .mesh_geometry import mean_spacing
from .neighbourhoods import mean_nearest_spacing, pair_weights, require_connected, scaled_weights
from .parameters import keyword_signature, parameters_doc, validate_parameters
from .surface_symmetry import fit_surface_mirror_plane, mirror_distances
from .warp import ApproximateThinPlateSpline, thin_plate_spline

# A pair's own mirror misfit, in neighbourhood radii, above which it is reported.
# Measured on the cow and spot: sound pairs stay below 1.2 under bends, compression
# and articulation; a landmark paired with a vertex half a diagonal away scores
# above 2 with 60 pairs. Subtler mispairings cannot be told from real deformation.
POOR_PAIR_MISFIT = 1.5
SWAPPED_COSINE = -0.5  # a pair whose gap points this far against its local normal looks swapped
CONVERGED_CHANGE = 1e-3  # automatic pairing has converged when fewer vertices than this change twin
# A candidate's pairs are not mirror pairs when their median local fit residual (Step 1,
# relative to the neighbourhood radius) exceeds SOUND_LOCAL_FIT, or when it pairs fewer than
# SOUND_PAIRED of the vertices (the outliers it drops leave little). Measured on the cow and
# spot (symmetric, bent, articulated, sheared, Figure 1 map; every candidate): residual
# 0-0.135, and a plane through a random Gaussian cloud 0.19; paired 0.25-1.0 where the
# pairs are sound or only slid along the surface, 0.09-0.14 on the cow under the Figure 1
# map, where symmetrizing them made the cow less symmetric than its input.
SOUND_LOCAL_FIT = 0.15
SOUND_PAIRED = 0.2
# A candidate that pairs this fraction of the vertices is taken without trying the others:
# one plane pairs 97-100 % of the exactly symmetric cow and spot, 93 % of spot with one
# leg swung (where the intrinsic candidate is right), at most 84 % of other deformed ones.
GLOBALLY_SYMMETRIC = 0.95
SCORE_SAMPLES = 50_000  # evenly strided vertices at which an output's mirror asymmetry is scored
TWIN_MOVE = 2.0  # reported: twins that moved farther than this many mean edge lengths


@dataclasses.dataclass(frozen=True)
class SymmetrizationResult:
    """Output of :func:`symmetrize`.

    points (N, 3): the warped vertices, in the frame chosen by ``output_frame``.
    asymmetry (N,): distance each vertex moved, measured in the input frame.
    report: pair count, plane, landmark asymmetry before/after, widths, seconds.
    """

    points: np.ndarray
    asymmetry: np.ndarray
    report: dict[str, Any]


def _rotated(local: LocalSymmetries, rotation: np.ndarray) -> LocalSymmetries:
    """Step 1 output expressed in a frame rotated by ``rotation`` (3, 3)."""

    def conj(m):
        return rotation @ m @ rotation.T

    return dataclasses.replace(
        local, normals=local.normals @ rotation.T, left_transforms=conj(local.left_transforms),
        right_transforms=conj(local.right_transforms), gap_transforms=conj(local.gap_transforms))


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


def _summary(values: np.ndarray) -> dict[str, float]:
    return {"mean": float(values.mean()), "rms": float(np.sqrt(np.mean(values**2))),
            "max": float(values.max())}


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


def _report_progress(progress, percent: float, message: str) -> None:
    if progress is not None:
        progress(percent, message)


def _solve(points: np.ndarray, left, right, ids, midline, wl, wr, options: dict, progress,
           warn: bool = True) -> SymmetrizationResult:
    """Step 1, Step 2 and the warp for checked pairs. ``wl``, ``wr`` (n,) >= 0 weigh each
    landmark's input geometry (0: missing side; above 1: a pair that counts more)."""
    clock = {"start": time.perf_counter()}
    # Midline landmarks join the solve as pairs whose two sides are one vertex,
    # held on the plane; labels for messages.
    n, m = len(left), len(midline)
    all_left, all_right = np.concatenate([left, midline]), np.concatenate([right, midline])
    labels = np.concatenate([ids.astype(object), midline_labels(m)])
    wl, wr = np.concatenate([wl, np.ones(m)]), np.concatenate([wr, np.ones(m)])
    on_plane = np.arange(n + m) >= n
    unique = np.concatenate([left, right, midline])  # each landmark vertex once: warp centres

    p, q = points[all_left], points[all_right]
    landmarks = points[unique]
    diagonal = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    centre = landmarks.mean(axis=0)
    p0, q0 = p - centre, q - centre
    measured_spacing = mean_nearest_spacing(landmarks)
    spacing = options["width_spacing"] or measured_spacing
    phi_h, theta_h = options["phi_width"] * spacing, options["theta_width"] * spacing
    phi = pair_weights(p0, q0, phi_h)
    require_connected(phi, p0, q0, labels, spacing, "phi_width", options["phi_width"])
    theta = phi if theta_h == phi_h else pair_weights(p0, q0, theta_h)
    if (wl * wr != 1).any():  # a broken side must not shape the local symmetries around it,
        theta = scaled_weights(theta, np.ones(n + m), wl * wr)  # a landmark of priority shapes them more
    clock["neighbourhoods"] = time.perf_counter()
    _report_progress(progress, 10.0, f"local symmetries ({options['mode']})")

    local = local_symmetries(options["mode"], theta, p0, q0, labels)
    if warn:
        _warn_about_local_fits(local, p0, q0, labels, options["mode"])
    clock["local_transforms"] = time.perf_counter()
    _report_progress(progress, 25.0, f"global solve ({n + m} pairs)")

    # Pre-align: the mean local normal goes to -x, so the smallest rotations Q_i
    # of Step 2 are taken relative to the global symmetry and the result does not
    # depend on the input pose (bent cow, three poses: shape error 0.24-1.31% of
    # the diagonal without this, 0.23% with it).
    frame = minimal_rotation(normalize(local.normals.mean(axis=0)), MINUS_X)[0]
    r, s = global_solve(phi, p0 @ frame.T, q0 @ frame.T, _rotated(local, frame), options["alpha"],
                        wl, wr, on_plane)
    solved = np.vstack([r[:n], s[:n], r[n:]])
    rotation, translation = rigid_fit(solved, landmarks, np.concatenate([wl[:n], wr[:n], np.ones(m)]))
    clock["global_solve"] = time.perf_counter()
    _report_progress(progress, 50.0, f"warping {len(points)} vertices")

    target = solved @ rotation.T + translation
    spline = thin_plate_spline(landmarks, target - landmarks)
    warped = points + spline(points, None if progress is None else
                             lambda fraction: progress(50.0 + 50.0 * fraction, f"warping {len(points)} vertices"))
    warped[unique] = target
    asymmetry = np.linalg.norm(warped - points, axis=1)
    if options["output_frame"] == "canonical":
        warped = (warped - translation) @ rotation
        warped[unique] = solved
        normal, offset = np.array([1.0, 0.0, 0.0]), 0.0
    else:
        normal = rotation[:, 0]
        offset = float(normal @ translation)
    clock["warp"] = time.perf_counter()
    _report_progress(progress, 100.0, "done")

    report = {
        "pair_count": int(n),
        "midline_count": int(m),
        "mode": options["mode"],
        "output_frame": options["output_frame"],
        "plane_normal": normal.tolist(),
        "plane_offset": offset,
        # 4x4 rigid map from the input frame to the canonical one (plane x = 0).
        "canonical_from_input": np.block([[rotation.T, (-rotation.T @ translation)[:, None]],
                                          [np.zeros((1, 3)), np.ones((1, 1))]]).tolist(),
        "landmark_asymmetry_before": fit_mirror_plane(points[left], points[right]).summary(diagonal),
        "landmark_asymmetry_after": fit_mirror_plane(warped[left], warped[right]).summary(diagonal),
        "vertex_displacement": _summary(asymmetry),
        "diagonal": diagonal,
        "mean_landmark_spacing": measured_spacing,
        "width_spacing": spacing,
        "phi_width": options["phi_width"],
        "phi_h": phi_h,
        "theta_width": options["theta_width"],
        "theta_h": theta_h,
        "alpha": options["alpha"],
        "local_fit_residual": {"median": float(np.median(local.residuals)),
                               "max": float(local.residuals.max())},
        "local_stretch": {"min": float(local.stretch.min()), "max": float(local.stretch.max())},
        "warp": (f"thin-plate spline through {spline.coarse_count} of the {len(landmarks)} landmarks plus local "
                 "splines of its residual on patches, exact at all" if isinstance(spline, ApproximateThinPlateSpline)
                 else f"exact thin-plate spline through the {len(landmarks)} landmarks"),
        "seconds": {},
    }
    stages = ["neighbourhoods", "local_transforms", "global_solve", "warp"]
    previous = clock["start"]
    for stage in stages:
        report["seconds"][stage] = clock[stage] - previous
        previous = clock[stage]
    report["seconds"]["total"] = previous - clock["start"]
    return SymmetrizationResult(warped, asymmetry, report)


def _checked_landmarks(points, left, right, pair_ids, midline, left_weights, right_weights):
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
    return left, right, ids, midline, wl, wr


def symmetrize(points, left=None, right=None, pair_ids=None, midline=None, left_weights=None,
               right_weights=None, progress=None, faces=None, auto_excluded=None, **params) -> SymmetrizationResult:
    _report_progress(progress, 0.0, "checking landmarks")
    options = validate_parameters(params, adapter=False)
    points = check_points(points)
    faces = np.zeros((0, 3), dtype=np.int64) if faces is None else np.asarray(faces, dtype=np.int64)
    excluded = _excluded_vertices(auto_excluded, len(points), options["pairs"])
    given = left is not None or right is not None or midline is not None
    if options["pairs"] == "auto":
        if given:
            raise LandmarkError("`pairs='auto'` finds its own pairs and ignores landmarks; to use "
                                "yours as well, pass pairs='landmarks+auto'.")
        return _auto_symmetrize(points, faces, None, options, progress, excluded)
    if left is None or right is None:
        raise LandmarkError(f"`pairs='{options['pairs']}'` needs landmark pairs: pass `left` and "
                            "`right` vertex indices, or use pairs='auto'.")
    landmarks = _checked_landmarks(points, left, right, pair_ids, midline, left_weights, right_weights)
    if options["pairs"] == "landmarks+auto":
        return _auto_symmetrize(points, faces, landmarks, options, progress, excluded)
    return _solve(points, *landmarks, options, progress)


def _excluded_vertices(auto_excluded, count: int, pairs: str) -> np.ndarray:
    """``auto_excluded`` (a (count,) bool mask or vertex indices) as distinct vertex indices (k,)."""
    if auto_excluded is None:
        return np.zeros(0, dtype=np.int64)
    if pairs == "landmarks":
        raise ParameterError("`auto_excluded` keeps vertices out of the automatic pairs, and pairs='landmarks' "
                             "finds none; use pairs='auto' or 'landmarks+auto', or leave it out.")
    values = np.asarray(auto_excluded)
    if values.dtype == bool:
        if values.shape != (count,):
            raise ParameterError(f"`auto_excluded` as a mask needs one entry per vertex ({count}), got shape "
                                 f"{values.shape}.")
        return np.flatnonzero(values)
    indices = _integer_indices("auto_excluded", values)
    outside = (indices < 0) | (indices >= count)
    if outside.any():
        raise ParameterError(f"`auto_excluded` holds vertex {indices[outside][0]}, but the mesh has vertices "
                             f"0..{count - 1}.")
    return np.unique(indices)


def _auto_symmetrize(points: np.ndarray, faces: np.ndarray, landmarks, options: dict,
                    progress, excluded: np.ndarray) -> SymmetrizationResult:
    """The 'auto' and 'landmarks+auto' modes: rounds of (pair on the current output, solve on
    the input), each kept only if its output is more mirror-symmetric as a surface (RMS
    distance of the vertices to the reflected output, :func:`mirror_distances`), until the
    mirror correspondence stops changing or a round no longer helps.

    ``landmarks``: None, or the checked (left, right, ids, midline, wl, wr) of the user's pairs,
    solved alone first and always kept, weighted ``landmark_priority`` times more. ``excluded``
    (k,): vertices (a missing or broken part) that no automatic pair may use, nor pair with. Without
    landmarks the first round tries the candidates of :func:`first_correspondences` in turn,
    rejects those whose pairs are not sound, takes the first that pairs GLOBALLY_SYMMETRIC of
    the vertices at once, or else the one with the most mirror-symmetric output. Where the first
    pairing says the two sides' vertices mirror each other (``exact_twins``), the later rounds
    pair the vertices the growth leaves by an assignment, and hold the pairs where the input is
    still exactly mirror-symmetric (:func:`unmoved_pairs`; on the output they can be off by a
    vertex, where the solve distorts the surface next to a joint).
    """
    clock = time.perf_counter()
    rounds = options["auto_iterations"]
    step = 90.0 / (rounds + 2)
    no_index, no_weight = np.zeros(0, dtype=np.int64), np.zeros(0)
    user = (no_index, no_index, no_index, no_index, no_weight, no_weight) if landmarks is None else landmarks
    fixed = np.concatenate([user[0], user[1], user[3], excluded])  # no automatic pair uses these
    edge_length = mean_spacing(points, faces)

    def solved(correspondence, paired_on, start, width):
        """The solve on the input with pairs spread over ``paired_on``, the points they were found on."""
        left, right, midline = spread_pairs(paired_on, correspondence, options["auto_pair_count"], fixed)
        if len(left) + len(user[0]) < MIN_PAIRS:
            raise GeometryError(
                f"Automatic pairing found {len(left)} mirror pair(s) on the surface; it needs at least "
                f"{MIN_PAIRS}.")
        result = _solve_with_automatic_pairs(points, user, left, right, midline, options,
                                             _scaled_progress(progress, start, width))
        entry = {"pairs": int(len(left)), "midline": int(len(midline)),
                 "paired_vertices": float(correspondence.paired_fraction),
                 "grown_vertices": correspondence.grown_fraction,
                 "growth_waves": correspondence.waves, "tessellation_mirror": correspondence.tessellated,
                 "surface_asymmetry": _surface_asymmetry(result, faces),
                 "local_fit_residual": result.report["local_fit_residual"]["median"]}
        return result, entry

    def unmoved():
        """The input's :func:`unmoved_pairs`, held in every later round, none on a vertex of ``fixed``."""
        plane = surface_plane if landmarks is None else fit_surface_mirror_plane(
            points, initial=fit_mirror_plane(points[user[0]], points[user[1]]))
        left, right, midline = unmoved_pairs(points, faces, *plane)
        keep = ~np.isin(left, fixed) & ~np.isin(right, fixed)
        return left[keep], right[keep], midline[~np.isin(midline, fixed)]

    history, candidates = [], {}
    if landmarks is None:
        _report_progress(progress, 2.0, "fitting the mirror plane and first pairs")
        surface_plane = fit_surface_mirror_plane(points)
        best = None
        for index, (name, correspondence) in enumerate(first_correspondences(points, faces, *surface_plane)):
            try:
                if isinstance(correspondence, GeometryError):
                    raise correspondence
                result, entry = solved(correspondence, points, 5.0 + index * step, step)
            except GeometryError as error:
                candidates[name] = str(error)
                continue
            if entry["local_fit_residual"] > SOUND_LOCAL_FIT:
                candidates[name] = (f"rejected: its pairs are not locally mirror-symmetric (median local fit "
                                    f"residual {entry['local_fit_residual']:.2f} > {SOUND_LOCAL_FIT})")
                continue
            if entry["paired_vertices"] < SOUND_PAIRED:
                candidates[name] = (f"rejected: it pairs {entry['paired_vertices']:.0%} of the vertices, "
                                    f"fewer than {SOUND_PAIRED:.0%}")
                continue
            candidates[name] = {key: entry[key] for key in ("surface_asymmetry", "local_fit_residual",
                                                            "paired_vertices")}
            at_once = entry["paired_vertices"] >= GLOBALLY_SYMMETRIC
            if at_once or best is None or entry["surface_asymmetry"] < best[1]["surface_asymmetry"]:
                best = result, {**entry, "first_pairs": name}, correspondence.partner, correspondence.exact_twins
            if at_once:
                break
        if best is None:
            raise GeometryError(
                "Automatic pairing found no usable mirror pairs ("
                + "; ".join(f"{name}: {reason}" for name, reason in candidates.items())
                + "). The shape may be too far from mirror-symmetric for automatic pairs: place a few "
                "landmark pairs and use pairs='landmarks+auto'.")
        result, entry, previous, exact_twins = best
        first_round, slots = 1, 2
    else:
        result = _solve(points, *landmarks, options, _scaled_progress(progress, 5.0, step))
        entry, previous = {"landmarks_only": True, "surface_asymmetry": _surface_asymmetry(result, faces)}, None
        exact_twins = None  # decided by the first pairing, on the landmarks' output
        first_round, slots = 0, 1
    history.append(entry)
    held = unmoved() if exact_twins else (no_index, no_index, no_index)
    stopped = "round limit"
    for round_index in range(first_round, rounds):
        start = 5.0 + (round_index + slots) * step
        _report_progress(progress, start, f"automatic pairs, round {round_index + 1}")
        current = result.points
        # Whether the twins are exact is decided on the first pairing, not on an output: an output is
        # exactly symmetric at its pairs even where the input's two sides are tessellated differently.
        kept_pairs = (np.concatenate([user[0], held[0]]), np.concatenate([user[1], held[1]]))
        correspondence = mirror_correspondence(current, faces, np.asarray(result.report["plane_normal"]),
                                               result.report["plane_offset"], kept_pairs,
                                               np.concatenate([user[3], held[2]]), complete=exact_twins)
        if exact_twins is None:
            exact_twins = correspondence.exact_twins
            held = unmoved() if exact_twins else held
        partner = correspondence.partner
        change = {} if previous is None else {
            "changed_vertices": float(np.mean(partner != previous)),
            "moved_twins": _moved_twins(current, partner, previous, edge_length)}
        if change and change["changed_vertices"] < CONVERGED_CHANGE:
            history.append({"paired_vertices": float(correspondence.paired_fraction), **change})
            stopped = "pairs unchanged"
            break
        try:
            candidate, entry = solved(correspondence, current, start, step)
        except GeometryError as error:  # too few pairs, or pairs that fall apart: keep the last result
            history.append({"paired_vertices": float(correspondence.paired_fraction), **change,
                            "kept": False, "failed": str(error)})
            stopped = "round failed"
            break
        entry.update(change)
        history.append(entry)
        if entry["surface_asymmetry"] >= history[-2]["surface_asymmetry"]:
            entry["kept"] = False
            stopped = "no gain"
            break
        result, previous = candidate, partner
    _report_progress(progress, 100.0, "done")
    pair_count = len(user[0])
    report = {**result.report, "pair_count": int(pair_count), "midline_count": int(len(user[3])),
              "auto_pairs": {"pair_count": int(result.report["pair_count"] - pair_count),
                             "midline_count": int(result.report["midline_count"] - len(user[3])),
                             "rounds": history, "converged": stopped in ("pairs unchanged", "no gain"),
                             "exact_twins": bool(exact_twins), "unmoved_pairs": int(len(held[0])),
                             "stopped": stopped, "excluded_vertices": int(len(excluded))}}
    if landmarks is None:
        report["auto_pairs"]["first_candidates"] = candidates
        report["auto_pairs"]["surface_plane"] = {"normal": surface_plane[0].tolist(), "offset": surface_plane[1]}
        report.pop("landmark_asymmetry_before")
        report.pop("landmark_asymmetry_after")
    else:
        report["landmark_asymmetry_before"] = fit_mirror_plane(points[user[0]], points[user[1]]).summary(
            report["diagonal"])
        report["landmark_asymmetry_after"] = fit_mirror_plane(
            result.points[user[0]], result.points[user[1]]).summary(report["diagonal"])
    report["seconds"] = {**report["seconds"], "total": time.perf_counter() - clock}
    return dataclasses.replace(result, report=report)


def _surface_asymmetry(result: SymmetrizationResult, faces: np.ndarray) -> float:
    """RMS distance of the output's vertices (at most about SCORE_SAMPLES, evenly strided) to its
    reflection across its plane, / the diagonal."""
    distances = mirror_distances(result.points, faces, np.asarray(result.report["plane_normal"]),
                                 result.report["plane_offset"], every=max(1, len(result.points) // SCORE_SAMPLES))
    return float(np.sqrt(np.mean(distances**2)) / result.report["diagonal"])


def _solve_with_automatic_pairs(points, user, left, right, midline, options, progress) -> SymmetrizationResult:
    """The solve on the user's checked landmarks ``user`` (left, right, ids, midline, wl, wr),
    weighted ``landmark_priority`` times more, plus automatic pairs ``left``, ``right`` (n,)
    and ``midline`` (m,) of weight 1."""
    user_left, user_right, user_ids, user_midline, user_wl, user_wr = user
    ids = np.concatenate([user_ids, [f"automatic {k}" for k in range(1, len(left) + 1)]])
    priority = options["landmark_priority"]
    wl = np.concatenate([priority * user_wl, np.ones(len(left))])
    wr = np.concatenate([priority * user_wr, np.ones(len(left))])
    return _solve(points, np.concatenate([user_left, left]), np.concatenate([user_right, right]), ids,
                  np.concatenate([user_midline, midline]), wl, wr, options, progress, warn=False)


def _moved_twins(points: np.ndarray, partner: np.ndarray, previous: np.ndarray, edge_length: float) -> float:
    """Fraction of the vertices, paired in both rounds, whose twin is more than TWIN_MOVE mean
    edge lengths from the previous one on ``points`` (N, 3): a report that tells twins hopping
    between neighbouring vertices (scans whose two sides are tessellated differently) from
    twins that move. Convergence still counts every change of twin: stopping on this measure
    stopped the landmarks+auto rounds on the cow too early (symmetry error 0.079 % instead of
    0.047 % after a 1.2 rad bend), because there small moves still improve the result."""
    both = (partner >= 0) & (previous >= 0)
    far = np.linalg.norm(points[partner[both]] - points[previous[both]], axis=1) > TWIN_MOVE * edge_length
    return float(np.count_nonzero(far) / len(partner))


def _scaled_progress(progress, start: float, width: float):
    """``progress`` for a sub-task that reports 0..100 % into start..start + width."""
    if progress is None:
        return None
    return lambda percent, message: progress(start + width * percent / 100.0, message)


symmetrize.__signature__ = keyword_signature(
    *(inspect.Parameter(name, inspect.Parameter.POSITIONAL_OR_KEYWORD, default=default)
      for name, default in (("points", inspect.Parameter.empty), ("left", None), ("right", None),
                            ("pair_ids", None), ("midline", None), ("left_weights", None),
                            ("right_weights", None), ("progress", None), ("faces", None),
                            ("auto_excluded", None))),
    adapter=False)
symmetrize.__doc__ = f"""Symmetrize ``points`` (N, 3) so that each pair (left[k], right[k]) becomes mirror-symmetric.

Implements Ghosh, Amenta and Kazhdan, *Closed-form Blending of Local
Symmetries* (SGP 2010): a local transform per pair (Step 1), one sparse
least-squares solve for a single global bilateral symmetry (Step 2), and a
thin-plate-spline warp of every point.

Parameters
----------
points : (N, 3) float array
    Vertex coordinates, any unit.
left, right : (n,) int arrays
    Vertex indices of the left and right landmark of each pair, n >= 4
    (none with ``pairs='auto'``).
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
    Triangles, used by the automatic pairs (normals, edge length); without
    them the points are treated as a point cloud.
auto_excluded : (N,) bool array or (k,) int array of vertex indices, optional
    Vertices no automatic pair may use, nor pair with (a missing or broken
    part, whose shape must not shape the other side); only with
    ``pairs='auto'`` or ``'landmarks+auto'``.
{parameters_doc(adapter=False)}

Returns
-------
SymmetrizationResult
    ``points`` (N, 3) output, ``asymmetry`` (N,) distance moved per vertex,
    ``report`` dict (see the README).

Raises
------
SymblendError (a ValueError) naming the parameter, pair or vertex at fault.
"""

"""The mirror plane of a shape's surface, fitted by reflection ICP (the surface matched to its own mirror
image) from several starting planes, keeping the best: the planes normal to the principal axes and the
most promising of many directions spread over the half sphere. The automatic pairs start from these
planes, and the before/after checks measure against them (measures/surface_asymmetry)."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from .geometry import MirrorPlane, flat_normal, hemisphere_directions, normalize, reflection_across_plane
from .landmark_asymmetry import MirrorFit, fit_mirror_plane
from .mesh_quantities import evenly

ICP_SAMPLES = 10000  # vertices used to refine the best plane
ICP_ITERATIONS = 40
ANDERSON_MEMORY = 5  # ICP steps the acceleration combines
TRIM_FRACTION = 0.8  # correspondences kept per ICP step: the closest 80 %
CONVERGED = 1e-5  # ICP stops when its trimmed RMS improves by less than this fraction
DISTINCT = np.radians(5.0)  # planes whose normals are this far apart are distinct candidates
SCREEN_SAMPLES = 1000  # vertices used to screen starting planes and to compare the starts
# Starting planes added to the principal axes' by default: the SCREENED_STARTS most promising of
# SCREENED_DIRECTIONS spread directions. On the cow under the paper's Figure 1 map (bend 1.2 rad,
# oblique compression to 0.65, shear 0.15) the principal axes' planes end 14-87 degrees from the
# plane of its true pairs; the best screened start ends 2.8 degrees from it, with a lower trimmed
# RMS (0.039 against 0.043 mesh units). Screening costs 0.4-1 s whatever the mesh size.
SCREENED_DIRECTIONS = 200
SCREENED_STARTS = 3


def _in_plane(normal: np.ndarray, flat: np.ndarray | None) -> np.ndarray:
    """``normal`` with its component along the flat normal removed: a flat shape's mirror normal lies in
    its plane (the plane itself reflects a flat shape onto itself, trivially)."""
    return normal if flat is None else normalize(normal - (normal @ flat) * flat)


def _workers(queries: int) -> int:
    """Threads for a KD-tree query of ``queries`` points: below about 50,000 starting them costs more."""
    return -1 if queries > 50_000 else 1


def _refine_plane(points: np.ndarray, tree: cKDTree, normal: np.ndarray, offset: float, flat=None,
                  converged: float = CONVERGED):
    """Reflection ICP from one plane, with Anderson acceleration; returns (normal, offset, trimmed RMS
    distance). Stops when the trimmed RMS improves by less than ``converged`` (relative) or after
    ICP_ITERATIONS.

    Plain reflection ICP creeps on a shape that is not symmetric: each step moves the plane by a nearly
    constant fraction of the way left (a linear rate of about 0.95 on the deformed Igea). Anderson
    acceleration over the last ANDERSON_MEMORY steps (as AA-ICP, Pavlov et al., ICRA 2018) extrapolates
    them; a step that does not lower the trimmed RMS is replaced by the plain one. Hand-written:
    scipy.optimize.anderson solves F(x) = 0 without the safeguard that the correspondences' jumps need.
    On eight corpus meshes it comes within 0.1 % of the trimmed RMS of 200 plain steps in 10-33 steps, in
    0.4-0.8x the time of the plain 40 (docs/benchmarks.md, "The mirror plane's ICP")."""
    best = None
    plane = np.append(normal, offset)
    history, plain = [], None  # (plane, its ICP step) of the last steps; the plain step behind an extrapolation
    for _ in range(ICP_ITERATIONS):
        distance, nearest = tree.query(reflection_across_plane(points, plane[:3], plane[3]),
                                       workers=_workers(len(points)))
        cut = np.quantile(distance, TRIM_FRACTION)
        keep = distance <= cut
        rms = float(np.sqrt(np.mean(distance[keep] ** 2)))
        if best is not None and rms >= best[2] * (1.0 - converged):
            if plain is None:
                break
            plane, plain, history = plain, None, []  # the extrapolation did not pay: the plain step instead
            continue
        best = (plane[:3], float(plane[3]), rms)
        # points[i] mirrors to near points[nearest[i]]: they are a mirror pair.
        fit = fit_mirror_plane(points[keep], points[nearest[keep]])
        fitted = _in_plane(fit.normal, flat)
        if not np.any(fitted):
            break
        middle = 0.5 * (points[keep] + points[nearest[keep]])
        step = np.append(fitted, fit.offset if flat is None else float(fitted @ middle.mean(axis=0)))
        if step[:3] @ plane[:3] < 0:  # one plane, two signs: keep the side
            step = -step
        history = (history + [(plane, step)])[-ANDERSON_MEMORY:]
        plane, plain = _extrapolated(history, flat), step
        if plane is None:
            plane, plain = step, None
    return best


def _extrapolated(history: list[tuple[np.ndarray, np.ndarray]], flat) -> np.ndarray | None:
    """Anderson's extrapolation of the ICP steps ``history`` ((plane (4,), its step (4,)), oldest first): the
    combination of the steps whose residuals (step - plane) combine to the least, as a plane; None with
    fewer than two steps or a degenerate one."""
    if len(history) < 2:
        return None
    planes, steps = (np.array(side) for side in zip(*history))
    residuals = steps - planes
    weights = np.linalg.lstsq(np.diff(residuals, axis=0).T, residuals[-1], rcond=None)[0]
    plane = steps[-1] - np.diff(steps, axis=0).T @ weights
    normal = _in_plane(plane[:3], flat)
    length = np.linalg.norm(normal)
    if not np.isfinite(plane).all() or length == 0:
        return None
    return np.append(normal / length, plane[3])


def fit_surface_mirror_plane(points: np.ndarray, initial: MirrorFit | None = None,
                             axes: np.ndarray | None = None) -> MirrorPlane:
    """Best mirror plane of a point set (N, 3) (the first of
    :func:`surface_mirror_planes`)."""
    return surface_mirror_planes(points, initial, axes)[0]


def surface_mirror_planes(points: np.ndarray, initial: MirrorFit | MirrorPlane | None = None,
                          axes: np.ndarray | None = None, converged: float = CONVERGED,
                          polish: bool = True) -> list[MirrorPlane]:
    """Mirror planes of a point set (N, 3), best first.

    Starts from the planes through the centroid normal to the rows of ``axes``
    (k, 3) (default the three principal axes, and without ``initial`` the
    SCREENED_STARTS most :func:`promising_normals` too), and from ``initial``
    (e.g. the landmarks' plane; given one, the screening is skipped), refines
    each by trimmed reflection ICP on a sample of SCREEN_SAMPLES vertices, and
    returns the distinct planes they end in (normals more than DISTINCT apart), by
    trimmed RMS distance, the best refined again on at most ``ICP_SAMPLES`` evenly
    strided vertices (a strongly bent shape's own plane can rank second; not with ``polish`` False); each
    ICP stops as ``converged`` says (:func:`_refine_plane`). The normal of a flat point set lies in its plane.
    """
    sample = evenly(points, ICP_SAMPLES)
    centre = sample.mean(axis=0)
    flat = flat_normal(points)
    if axes is None:
        _, _, axes = np.linalg.svd(sample - centre, full_matrices=False)
        if initial is None:
            screened = promising_normals(points, hemisphere_directions(SCREENED_DIRECTIONS), SCREENED_STARTS, flat)
            axes = np.vstack([axes, screened])
    axes = normalize(np.array([_in_plane(normalize(axis), flat) for axis in np.asarray(axes, dtype=float)]))
    starts = [(axis, float(axis @ centre)) for axis in axes if np.any(axis)]
    if initial is not None:
        starts.insert(0, (_in_plane(normalize(initial.normal), flat), initial.offset))
    # Every start on a small sample, then the best one on the large sample (5x faster at scan size).
    coarse = evenly(sample, SCREEN_SAMPLES)
    tree = cKDTree(coarse)
    ends = sorted((_refine_plane(coarse, tree, n, d, flat, converged) for n, d in starts), key=lambda fit: fit[2])
    distinct = []
    for normal, offset, _ in ends:
        if all(abs(normal @ other) < np.cos(DISTINCT) for other, _ in distinct):
            distinct.append(MirrorPlane(normal, float(offset)))
    if polish and len(coarse) < len(sample):
        distinct[0] = MirrorPlane(*_refine_plane(sample, cKDTree(sample), *distinct[0], flat, converged)[:2])
    return distinct


def promising_normals(points: np.ndarray, normals: np.ndarray, keep: int, flat: np.ndarray | None = None) -> np.ndarray:
    """The ``keep`` rows of ``normals`` (n, 3) whose planes through the centroid reflect a sample of
    ``points`` (N, 3) closest onto itself (trimmed RMS, one nearest-neighbour query for all): cheap
    starts for :func:`fit_surface_mirror_plane` where the principal axes mislead (an oblique
    compression) or say nothing (a whitened shape). With ``flat``, the normals are taken in the plane."""
    if flat is not None:
        normals = normalize(normals - np.outer(normals @ flat, flat))
        normals = normals[np.linalg.norm(normals, axis=1) > 0.5]
    sample = evenly(points, SCREEN_SAMPLES)
    centre = sample.mean(axis=0)
    heights = (sample - centre) @ normals.T  # (m, n)
    mirrored = sample[None, :, :] - 2.0 * heights.T[:, :, None] * normals[:, None, :]  # (n, m, 3)
    # Far reflections cost a KD-tree most; beyond a quarter of the extent a plane is poor anyway.
    cap = 0.25 * float(np.ptp(sample, axis=0).max())
    distance, _ = cKDTree(sample).query(mirrored.reshape(-1, 3), distance_upper_bound=cap,
                                  workers=_workers(len(normals) * len(sample)))
    scores = np.quantile(np.minimum(distance, cap).reshape(len(normals), len(sample)), TRIM_FRACTION, axis=1)
    return normals[np.argsort(scores)[:keep]]


def best_plane_from(points: np.ndarray, starts: list[MirrorPlane], converged: float = CONVERGED) -> MirrorPlane:
    """The best mirror plane of ``points`` (N, 3) reached by reflection ICP from each of ``starts``
    (on SCREEN_SAMPLES vertices; the best refined again on ICP_SAMPLES), as surface_mirror_planes does."""
    sample = evenly(points, ICP_SAMPLES)
    coarse = evenly(sample, SCREEN_SAMPLES)
    flat = flat_normal(points)
    tree = cKDTree(coarse)
    ends = [_refine_plane(coarse, tree, _in_plane(normalize(np.asarray(n, dtype=float)), flat), float(d), flat,
                          converged) for n, d in starts]
    normal, offset, _ = min(ends, key=lambda end: end[2])
    if len(coarse) < len(sample):
        normal, offset, _ = _refine_plane(sample, cKDTree(sample), normal, offset, flat, converged)
    return MirrorPlane(normal, float(offset))

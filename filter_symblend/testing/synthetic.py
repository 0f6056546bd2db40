"""Ground truth for tests, the demo and the benchmark: exact mirror pairs of a
symmetric mesh, known deformations (bend, compression, articulation) and error
measures against the undeformed mesh.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..core.geometry import normalize, rotation_about_axis, similarity_fit, voxel_grid
from ..core.landmark_asymmetry import fit_mirror_plane
from ..core.mesh_quantities import farthest_point_order


def mirror_partners(points: np.ndarray, tolerance: float = 1e-4):
    """Mirror partner of every vertex across the bbox mid-plane normal to x.

    Returns (offset, partner): the plane is x = offset; ``partner`` (N,) holds
    the index of each vertex's mirror image, itself for vertices on the plane,
    -1 where none lies within ``tolerance`` x the bbox diagonal.
    """
    offset = 0.5 * (points[:, 0].min() + points[:, 0].max())
    mirrored = points * [-1.0, 1.0, 1.0] + [2.0 * offset, 0.0, 0.0]
    distance, partner = cKDTree(points).query(mirrored)
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    partner[distance > tolerance * diagonal] = -1
    unique = partner[partner >= 0]
    partner[partner >= 0] = np.where(partner[unique] == np.flatnonzero(partner >= 0), unique, -1)
    return offset, partner


def exactly_symmetric(points: np.ndarray, offset: float, partner: np.ndarray) -> np.ndarray:
    """A copy of ``points`` whose partnered vertices are exact mirror images (to rounding):
    right-side vertices are replaced by the mirror of their left partner, vertices
    paired with themselves are put on the plane."""
    out = points.copy()
    index = np.arange(len(points))
    left = (partner >= 0) & (points[:, 0] > offset) & (partner != index)
    out[partner[left]] = points[left] * [-1.0, 1.0, 1.0] + [2.0 * offset, 0.0, 0.0]
    out[partner == index, 0] = offset
    return out


def _left_candidates(points: np.ndarray, offset: float, partner: np.ndarray, margin: float) -> np.ndarray:
    """Vertices with a mirror partner at least ``margin`` x diagonal on the left (x > offset)."""
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    return np.flatnonzero((partner >= 0) & (points[:, 0] > offset + margin * diagonal))


def farthest_point_pairs(points: np.ndarray, offset: float, partner: np.ndarray, count: int,
                         margin: float = 0.02):
    """``count`` pairs (left (count,), right (count,)) spread over the surface by farthest-point
    sampling of the left vertices at least ``margin`` x diagonal off the plane."""
    candidates = _left_candidates(points, offset, partner, margin)
    if count > len(candidates):
        raise ValueError(f"Only {len(candidates)} mirror pairs are available, {count} asked.")
    left = candidates[farthest_point_order(points[candidates], count, start=0)]
    return left, partner[left]


def bend(points: np.ndarray, angle: float, along: int = 2, toward: int = 0) -> np.ndarray:
    """Bend the points sideways: the ``along`` axis is wrapped onto a circular arc in the
    (``toward``, ``along``) plane turning by ``angle`` radians over the extent."""
    out = points.copy()
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    length = np.ptp(points[:, along])
    radius = length / angle
    phase = (points[:, along] - centre[along]) / radius
    lateral = radius - (points[:, toward] - centre[toward])
    out[:, toward] = centre[toward] + radius - lateral * np.cos(phase)
    out[:, along] = centre[along] + lateral * np.sin(phase)
    return out


def compress(points: np.ndarray, direction, factor: float, shear: float = 0.0) -> np.ndarray:
    """Global affine map: scale by ``factor`` along unit ``direction`` (3,), plus a shear of
    x by ``shear`` x z. Compression along the mirror normal alone keeps a shape
    symmetric, so use an oblique direction to hide the symmetry."""
    d = normalize(np.asarray(direction, dtype=float))
    matrix = np.eye(3) + (factor - 1.0) * np.outer(d, d)
    matrix[0, 2] += shear
    centre = points.mean(axis=0)
    return (points - centre) @ matrix.T + centre


def rotate_region(points: np.ndarray, weights: np.ndarray, pivot, axis, angle: float) -> np.ndarray:
    """Articulate: rotate each point about ``pivot``/``axis`` by ``angle`` x its weight in [0, 1]
    (weight 1 on the limb, 0 on the body, a smooth ramp at the joint)."""
    axis = normalize(np.asarray(axis, dtype=float))
    rotations = rotation_about_axis(np.broadcast_to(axis, points.shape), angle * weights)
    return np.einsum("nij,nj->ni", rotations, points - pivot) + pivot


def figure_1_deformation(points: np.ndarray) -> np.ndarray:
    """The paper's Figure 1 cow: bent sideways (1.2 rad), then compressed to 65% along an
    oblique direction with a 0.15 shear."""
    return compress(bend(points, 1.2), [1, 1, 0], 0.65, shear=0.15)


def random_rigid(points: np.ndarray, seed: int) -> np.ndarray:
    """``points`` moved by a random rotation and a translation of about one diagonal."""
    rng = np.random.default_rng(seed)
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return points @ q.T + rng.normal(size=3) * np.linalg.norm(np.ptp(points, axis=0))


def shape_error(points: np.ndarray, reference: np.ndarray) -> float:
    """RMS distance to ``reference`` (N, 3) after the best similarity alignment, / its diagonal."""
    aligned = similarity_fit(points, reference)
    return float(np.sqrt(np.mean(np.sum((aligned - reference) ** 2, axis=1)))
                 / np.linalg.norm(np.ptp(reference, axis=0)))


def symmetry_error(points: np.ndarray, left: np.ndarray, right: np.ndarray) -> float:
    """RMS over the pairs of |left - mirror(right)| across the best mirror plane, / diagonal."""
    deviations = fit_mirror_plane(points[left], points[right]).deviations
    return float(np.sqrt(np.mean(deviations**2)) / np.linalg.norm(np.ptp(points, axis=0)))


# A front-left limb of each test mesh, in coordinates normalized to the bbox
# (0..1 per axis): the x and z bands it occupies, the height of its joint and
# the height over which the rotation ramps in (a soft joint, no tear).
LIMBS = {
    "cow": {"x": (0.58, 1.0), "z": (0.557, 0.756), "joint": 0.434, "ramp": 0.11},
    "spot": {"x": (0.55, 1.0), "z": (0.72, 1.0), "joint": 0.2, "ramp": 0.08},
}


def limb_weights(points: np.ndarray, x, z, joint: float, ramp: float) -> np.ndarray:
    """Weights (N,) in [0, 1]: 1 on the limb below the joint, 0 off it (see ``LIMBS``)."""
    unit = (points - points.min(axis=0)) / np.ptp(points, axis=0)
    inside = (unit[:, 0] > x[0]) & (unit[:, 0] <= x[1]) & (unit[:, 2] > z[0]) & (unit[:, 2] <= z[1])
    return np.clip((joint - unit[:, 1]) / ramp, 0.0, 1.0) * inside


def articulate_limb(points: np.ndarray, weights: np.ndarray, angle: float) -> np.ndarray:
    """Swing the weighted limb by ``angle`` radians about the x axis through its joint."""
    limb = weights > 0
    joint_height = points[limb & (weights < 1), 1].max() if np.any(limb & (weights < 1)) else points[limb, 1].max()
    pivot = [points[limb, 0].mean(), joint_height, points[limb, 2].mean()]
    return rotate_region(points, weights, pivot, [1.0, 0.0, 0.0], angle)


def spread_pairs(points: np.ndarray, offset: float, partner: np.ndarray, count: int, margin: float = 0.005):
    """About ``count`` pairs (left, right) spread evenly by a voxel grid: one left vertex per
    occupied voxel, the voxel size found by bisection. Fast where farthest-point sampling
    (O(count x N)) is not: 10^5 pairs on 10^6 vertices in about a second."""
    candidates = _left_candidates(points, offset, partner, margin)
    if count >= len(candidates):
        return candidates, partner[candidates]
    diagonal = float(np.linalg.norm(np.ptp(points, axis=0)))
    keys = voxel_grid(points[candidates], count, steps=40, low=1e-5 * diagonal, high=diagonal)
    _, first = np.unique(keys, return_index=True)
    left = candidates[np.sort(first)]
    return left, partner[left]


def icosphere(subdivisions: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """A unit sphere triangulated from a subdivided icosahedron: (points (N, 3), faces (F, 3)). Its
    vertex set and its triangles are closed under x -> -x (and y, z): a mirrored tessellation."""
    t = (1.0 + np.sqrt(5.0)) / 2.0
    points = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
              (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    points, faces = [np.array(p, dtype=float) / np.linalg.norm(p) for p in points], np.array(faces)
    for _ in range(subdivisions):
        middle: dict[tuple[int, int], int] = {}

        def midpoint(a: int, b: int) -> int:
            key = (min(a, b), max(a, b))
            if key not in middle:
                point = points[a] + points[b]
                points.append(point / np.linalg.norm(point))
                middle[key] = len(points) - 1
            return middle[key]

        finer = []
        for a, b, c in faces:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            finer += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = np.array(finer)
    return np.array(points), faces


def bumpy(points: np.ndarray) -> np.ndarray:
    """A unit sphere's points pushed out by bumps even in x and in nothing else: one mirror plane, x = 0."""
    x, y, z = points.T
    return points * (1.0 + 0.25 * np.cos(3.0 * x) * np.exp(y) + 0.2 * z**3 + 0.15 * x**2 * y)[:, None]


def several_pieces(subdivisions: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """An exactly mirror-symmetric (x = 0) closed mesh of five separate pieces: a bumpy body, a lid and a
    spout on the plane (each its own mirror image), and two ears, each the other's mirror image."""
    sphere, faces = icosphere(subdivisions)
    small, small_faces = icosphere(max(1, subdivisions - 1))
    ear = small * 0.25 + [0.95, 0.55, -0.3]
    pieces = [(bumpy(sphere) * [1.0, 0.8, 1.2], faces),
              (small * [0.35, 0.2, 0.35] + [0.0, 1.15, 0.0], small_faces),
              (small * [0.15, 0.15, 0.45] + [0.0, 0.1, 1.75], small_faces),
              (ear, small_faces), (ear * [-1.0, 1.0, 1.0], small_faces[:, ::-1])]
    points, triangles, count = [], [], 0
    for piece_points, piece_faces in pieces:
        points.append(piece_points)
        triangles.append(piece_faces + count)
        count += len(piece_points)
    return np.vstack(points), np.vstack(triangles)


def cropped(points: np.ndarray, faces: np.ndarray, keep: np.ndarray):
    """The mesh restricted to the vertices ``keep`` (N,) bool: (points, faces, kept vertex indices); faces
    with a vertex left out go too (a scan with one side cut away)."""
    index = np.full(len(points), -1)
    index[keep] = np.arange(np.count_nonzero(keep))
    inside = keep[faces].all(axis=1)
    return points[keep], index[faces[inside]], np.flatnonzero(keep)


def with_seams(points: np.ndarray, faces: np.ndarray, selected: np.ndarray):
    """The mesh with the vertices of the ``selected`` (F,) bool faces duplicated for them (as UV seams split an
    OBJ): (points (N + k, 3), faces); copies sit exactly on their originals."""
    used = np.unique(faces[selected])
    copies = np.full(len(points), -1)
    copies[used] = len(points) + np.arange(len(used))
    faces = faces.copy()
    faces[selected] = copies[faces[selected]]
    return np.vstack([points, points[used]]), faces


def flat_region(outline: np.ndarray, rings: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """A flat mesh (z = 0) filling the star-shaped (about the origin) closed ``outline`` (n, 2): the outline
    and ``rings - 1`` copies shrunk toward the origin, joined by strips of triangles, and a fan at the
    origin: (points (rings * n + 1, 3), faces); the first n points are the outline."""
    n = len(outline)
    scales = np.arange(rings, 0, -1) / rings
    points2d = np.vstack([outline * scale for scale in scales] + [np.zeros((1, 2))])
    i = np.arange(n)
    faces = []
    for ring in range(rings - 1):
        a, b = ring * n + i, ring * n + (i + 1) % n
        c, d = a + n, b + n
        faces += [np.column_stack([a, b, d]), np.column_stack([a, d, c])]
    inner = (rings - 1) * n
    faces.append(np.column_stack([inner + i, inner + (i + 1) % n, np.full(n, rings * n)]))
    return np.column_stack([points2d, np.zeros(len(points2d))]), np.vstack(faces)


def body_with_two_parts(subdivisions: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """A body of revolution about z (an ellipsoid) carrying a round knob on the +x side and a long ridge on
    the -x side, both even in y: its only mirror plane is y = 0, while every plane through the z axis
    mirrors the body, most of the surface. (points, faces)"""
    sphere, faces = icosphere(subdivisions)
    x, y, z = sphere.T
    knob = 0.45 * np.exp(-((x - 1.0) ** 2 + y**2 + (z - 0.3) ** 2) / 0.06)
    ridge = 0.3 * np.exp(-((x + 1.0) ** 2 + y**2) / 0.04 - (z + 0.1) ** 2 / 0.5)
    return sphere * (1.0 + knob + ridge)[:, None] * [1.0, 1.0, 1.6], faces

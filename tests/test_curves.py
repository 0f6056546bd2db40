"""Curves to semilandmarks: naming, tracing on the surface, equal spacing, exact twins on a
symmetric mesh, and a measured gain over the curves' control points alone."""

import numpy as np
import pymeshlab
import pytest
from scipy.spatial import cKDTree

from filter_symblend import LandmarkError, SymblendWarning, symmetrize
from filter_symblend.core.mesh_graph import edge_graph
from filter_symblend.core.mesh_quantities import farthest_point_order
from filter_symblend.core.neighbourhoods import mean_nearest_spacing
from filter_symblend.landmarks.curves import add_curve_pairs, find_curves
from filter_symblend.landmarks.formats import Landmark, LandmarkSet
from filter_symblend.landmarks.pairing import snap_pairs
from filter_symblend.landmarks.semilandmarks import arc_lengths, equal_arc_samples, resample_curve, surface_path
from filter_symblend.testing import synthetic

from conftest import symmetric_blob, twins


def test_numbered_names_group_into_curves_in_number_order():
    names = ["L_zygomatic_arch_2", "L_zygomatic_arch_1", "L_zygomatic_arch_10", "R_zygomatic_arch_1",
             "R_zygomatic_arch_2", "OC_L-1", "OC_L-2", "OC_R-1", "OC_R-2", "OC_R-3", "L_porion", "R_porion",
             "midsagittal_1", "midsagittal_2", "L_molar_1", "R_molar_1", "L_7", "R_7", "L_8", "R_8"]
    curves, singles = find_curves(names, midline=True)
    by_name = {c.name: c for c in curves}
    assert by_name["zygomatic_arch"].left == [1, 0, 2] and by_name["zygomatic_arch"].right == [3, 4]
    assert by_name["oc"].left == [5, 6] and by_name["oc"].right == [7, 8, 9]
    assert by_name["midsagittal"].left == [12, 13] and by_name["midsagittal"].right is None
    assert singles == [10, 11, 14, 15, 16, 17, 18, 19]  # numbered, but not curves: one point per side, or no name


def test_curve_naming_errors():
    with pytest.raises(LandmarkError, match=r"'L_arch_2' and 'l-arch-2' have the same number; renumber one"):
        find_curves(["L_arch_1", "L_arch_2", "l-arch-2"])
    with pytest.raises(LandmarkError, match=r"Curve 'L_arch_1'..'L_arch_3' \(left\) has no right curve"):
        find_curves(["L_arch_1", "L_arch_2", "L_arch_3"])
    with pytest.raises(LandmarkError, match=r"Curve 'keel_1'..'keel_2' has no side word.*\(--midline\)"):
        find_curves(["keel_1", "keel_2"])


def flat_grid(size: int = 41):
    """A flat triangulated square [0, 1]^2 at z = 0, every quad split along the same diagonal."""
    x, y = np.meshgrid(np.linspace(0, 1, size), np.linspace(0, 1, size), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    at = np.arange(size * size).reshape(size, size)
    a, b, c, d = at[:-1, :-1].ravel(), at[1:, :-1].ravel(), at[1:, 1:].ravel(), at[:-1, 1:].ravel()
    return points, np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])


def test_paths_on_a_plane_are_nearly_straight():
    points, faces = flat_grid()
    start, end = 0, 40 * 41 + 20  # (0, 0) to (1, 0.5): not along an edge or a diagonal
    path = surface_path(edge_graph(points, faces), points, [start, end])
    assert path[0] == start and path[-1] == end
    straight = np.linalg.norm(points[end] - points[start])
    assert arc_lengths(points, path)[-1] < 1.03 * straight  # edge paths alone: 1.08 x here


def test_a_curve_follows_the_surface_not_the_chord_and_is_equally_spaced():
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=5)
    points, faces = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    tree = cKDTree(points)
    north, equator, south = tree.query([[0, 0, 1], [1, 0, 0], [0, 0, -1]])[1]
    path = surface_path(edge_graph(points, faces), points, [north, equator, south])
    assert arc_lengths(points, path)[-1] == pytest.approx(np.pi, rel=0.03)  # the chord is 2
    assert np.abs(np.linalg.norm(points[path], axis=1) - 1).max() < 1e-6
    samples = equal_arc_samples(points, path, 11)
    angles = np.arccos(np.clip(np.sum(points[samples[1:]] * points[samples[:-1]], axis=1), -1, 1))
    assert samples[0] == north and samples[-1] == south
    assert angles.mean() == pytest.approx(np.pi / 10, rel=0.03) and angles.std() < 0.15 * angles.mean()


@pytest.fixture(scope="module")
def blob_curves():
    """The symmetric blob and six left curves of three control vertices about 0.2 diagonals
    apart, with their exact mirror twins."""
    points, faces = symmetric_blob(5)
    twin = twins(points)
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    left = np.flatnonzero(points[:, 0] > 1e-9 * diagonal)
    rng = np.random.default_rng(1)
    curves = []
    for start in left[farthest_point_order(points[left], 6)]:
        direction = rng.normal(size=3) * [0, 1, 1]
        direction /= np.linalg.norm(direction)
        targets = points[start] + np.outer([0.2, 0.4], direction) * diagonal
        curves.append(np.concatenate([[start], left[cKDTree(points[left]).query(targets)[1]]]))
    return points, faces, twin, diagonal, left, curves


def test_curves_on_an_exactly_symmetric_mesh_give_exact_twins(blob_curves):
    points, faces, twin, diagonal, _, curves = blob_curves
    graph = edge_graph(points, faces)
    for controls in curves:
        curve = resample_curve(graph, points, controls, twin[controls], spacing=0.01 * diagonal)
        assert len(curve.left) >= 4 and curve.left[0] == controls[0] and curve.right[-1] == twin[controls[-1]]
        np.testing.assert_array_equal(twin[curve.left], curve.right)
        assert curve.left_length == pytest.approx(curve.right_length)


def test_semilandmarks_make_the_surface_near_the_curves_more_symmetric(blob_curves):
    points, faces, twin, diagonal, left, curves = blob_curves
    bent = synthetic.bend(points, 0.4, along=1)
    graph = edge_graph(bent, faces)
    controls = np.unique(np.concatenate(curves))
    semi_left, semi_right = [controls], [twin[controls]]
    for curve in curves:
        resampled = resample_curve(graph, bent, curve, twin[curve], spacing=0.01 * diagonal)
        new = ~np.isin(resampled.left, np.concatenate(semi_left)) & ~np.isin(resampled.right, np.concatenate(semi_right))
        semi_left.append(resampled.left[new])
        semi_right.append(resampled.right[new])
    semi_left, semi_right = np.concatenate(semi_left), np.concatenate(semi_right)
    assert len(semi_left) > 3 * len(controls)
    paths = np.concatenate([surface_path(edge_graph(points, faces), points, c) for c in curves])
    near = left[cKDTree(points[paths]).query(points[left])[0] < 0.015 * diagonal]
    placed_spacing = mean_nearest_spacing(np.vstack([bent[controls], bent[twin[controls]]]))
    alone = symmetrize(bent, controls, twin[controls], mode="affine").points
    with_curves = symmetrize(bent, semi_left, semi_right, mode="affine", width_spacing=placed_spacing).points
    # measured: near the curves 0.00228 -> 0.00091 of the diagonal; everywhere 0.0155 -> 0.0141
    assert synthetic.symmetry_error(with_curves, near, twin[near]) < 0.6 * synthetic.symmetry_error(alone, near, twin[near])
    assert synthetic.symmetry_error(with_curves, left, twin[left]) < synthetic.symmetry_error(alone, left, twin[left])
    assert synthetic.shape_error(with_curves, points) <= synthetic.shape_error(alone, points)


def named_curves(points, twin, curves):
    landmarks = []
    for k, controls in enumerate(curves):
        for number, vertex in enumerate(controls, start=1):
            landmarks += [Landmark(f"L_curve{k}_{number}", tuple(points[vertex])),
                          Landmark(f"R_curve{k}_{number}", tuple(points[twin[vertex]]))]
    return LandmarkSet(landmarks)


def test_named_curves_become_pairs_after_the_landmarks(blob_curves):
    points, faces, twin, diagonal, left, curves = blob_curves
    landmarks = named_curves(points, twin, curves)
    single = left[np.argmax(points[left, 2])]
    landmarks.landmarks += [Landmark("L_top", tuple(points[single])), Landmark("R_top", tuple(points[twin[single]]))]
    found, singles = find_curves(landmarks.names())
    assert len(found) == 6 and [landmarks.names()[i] for i in singles] == ["L_top", "R_top"]
    snapped = add_curve_pairs(snap_pairs(points, landmarks, [(singles[0], singles[1])], []), points, faces,
                              landmarks, found, spacing=0.01 * diagonal)
    pairs = snapped.pairs
    assert pairs.left[0] == single and snapped.pair_names[0] == ("L_top", "R_top")
    assert snapped.pair_names[1] == ("L_curve0:1", "R_curve0:1")
    np.testing.assert_array_equal(twin[pairs.left], pairs.right)
    assert len(np.unique(np.concatenate([pairs.left, pairs.right]))) == 2 * len(pairs.left)
    assert len(pairs.ids) == 1 + sum(c["samples"] for c in snapped.curves) and snapped.snap_distances.shape == (len(pairs.ids), 2)
    controls = np.concatenate([[single, twin[single]], *curves, *(twin[c] for c in curves)])
    assert snapped.placed_spacing == pytest.approx(mean_nearest_spacing(points[np.unique(controls)]))


def test_midline_curves_and_dropped_samples(blob_curves):
    points, faces, twin, diagonal, _, _ = blob_curves
    on_plane = np.flatnonzero(np.abs(points[:, 0]) < 1e-9 * diagonal)
    ends = on_plane[[np.argmax(points[on_plane, 2]), np.argmax(points[on_plane, 1])]]
    landmarks = LandmarkSet([Landmark("keel_1", tuple(points[ends[0]])), Landmark("keel_2", tuple(points[ends[1]])),
                             Landmark("top", tuple(points[ends[0]]))])
    found, singles = find_curves(landmarks.names(), midline=True)
    snapped = add_curve_pairs(snap_pairs(points, landmarks, [], singles, midline=True), points, faces, landmarks,
                              found, spacing=0.02 * diagonal)
    midline = snapped.pairs.midline
    assert midline[0] == ends[0] and snapped.midline_names[0] == "top"
    assert np.abs(points[midline, 0]).max() < 1e-9 * diagonal  # a midline curve stays on the midline
    assert snapped.curves[0]["midline"] and snapped.curves[0]["dropped_on_used_vertices"] == 1  # "top" holds its start
    assert len(midline) == 1 + snapped.curves[0]["samples"] > 5


def test_curve_errors_and_warnings(blob_curves):
    points, faces, twin, diagonal, _, curves = blob_curves
    landmarks = named_curves(points, twin, curves[:1])
    found, _ = find_curves(landmarks.names())
    empty = snap_pairs(points, LandmarkSet([]), [], [])
    with pytest.raises(LandmarkError, match=r"curves are traced on the surface, and this mesh has no faces"):
        add_curve_pairs(empty, points, np.zeros((0, 3), dtype=int), landmarks, found)
    far_piece = np.vstack([points, points[faces[0]] + 10 * diagonal])
    pieces = np.vstack([faces, len(points) + np.arange(3)])
    landmarks.landmarks[1].position = tuple(far_piece[-1])  # R_curve0_1 on a separate triangle
    with pytest.raises(LandmarkError, match=r"R_curve0_1 \(vertex \d+\) and R_curve0_2 \(vertex \d+\) lie on "
                                            r"separate pieces of the mesh"):
        add_curve_pairs(empty, far_piece, pieces, landmarks, found)
    landmarks = named_curves(points, twin, curves[:1])
    landmarks.landmarks[0].placed = landmarks.landmarks[2].placed = False  # L_curve0_1, L_curve0_2
    with pytest.warns(SymblendWarning, match=r"curve 'curve0' has fewer than 2 placed points on a side"):
        snapped = add_curve_pairs(empty, points, faces, landmarks, found)
    assert snapped.curves == [] and snapped.unplaced == ["L_curve0_1", "L_curve0_2"]

"""Missing regions take the mirror shape: closest points, the fill, and the hole-filling pipeline."""

import numpy as np
import pytest

import filter_symblend
from filter_symblend import MeshSetError, SymblendWarning
from filter_symblend.core.mirror_fill import (TriangleSurface, closest_points_on_surface, closest_points_on_triangles,
                                             fill_from_mirror)
from conftest import meshset_with_pairs


def test_closest_points_on_triangles_match_a_dense_sampling():
    rng = np.random.default_rng(0)
    a, b, c = (rng.normal(size=(200, 3)) for _ in range(3))
    points = rng.normal(size=(200, 3)) * 2
    closest = closest_points_on_triangles(points, a, b, c)
    u, v = np.meshgrid(np.linspace(0, 1, 201), np.linspace(0, 1, 201))
    inside = (u + v) <= 1
    u, v = u[inside], v[inside]
    for i in range(0, 200, 7):
        samples = a[i] + u[:, None] * (b[i] - a[i]) + v[:, None] * (c[i] - a[i])
        brute = np.linalg.norm(samples - points[i], axis=1).min()
        found = np.linalg.norm(closest[i] - points[i])
        assert found <= brute + 1e-12 and found > brute - 0.02 * np.linalg.norm(b[i] - a[i])
        # the answer lies on the triangle: barycentric coordinates in [0, 1]
        weights = np.linalg.lstsq(np.column_stack([b[i] - a[i], c[i] - a[i]]), closest[i] - a[i], rcond=None)[0]
        assert weights.min() > -1e-9 and weights.sum() < 1 + 1e-9


@pytest.mark.parametrize("batches", ["one", "several, on every core"])
def test_the_surface_search_finds_what_every_triangle_measured_finds(cow, batches, monkeypatch):
    """The search measures only the candidates that can beat the nearest centroid's triangle; queries near the
    surface, on it and at vertices (where several triangles tie) get the distance and point that measuring every
    triangle gives, and the first triangle of equal ones: in one batch, and in batches on every core."""
    from filter_symblend.core import mirror_fill
    if batches != "one":
        monkeypatch.setattr(mirror_fill, "QUERY_CHUNK", 200)
        monkeypatch.setattr(mirror_fill, "PARALLEL_QUERIES", 100)
    rng = np.random.default_rng(3)
    diagonal = np.linalg.norm(np.ptp(cow.points, axis=0))
    queries = np.vstack([cow.points[::9] + rng.normal(size=(len(cow.points[::9]), 3)) * 0.01 * diagonal,
                         cow.points[::13], cow.points[cow.faces[::17]].mean(axis=1) * [-1.0, 1.0, 1.0]])
    face, closest, distance = TriangleSurface(cow.points, cow.faces).nearest(queries)
    corners = cow.points[cow.faces]
    for index, query in enumerate(queries):
        every = closest_points_on_triangles(np.repeat(query[None], len(corners), axis=0), *corners.transpose(1, 0, 2))
        gaps = np.linalg.norm(every - query, axis=1)
        assert distance[index] == pytest.approx(gaps.min(), abs=1e-12 * diagonal)
        np.testing.assert_allclose(closest[index], every[np.argmin(gaps)], atol=1e-9 * diagonal)
        assert gaps[face[index]] == pytest.approx(gaps.min(), abs=1e-12 * diagonal)


def test_closest_points_on_a_box_are_the_points_clamped_to_it():
    """Outside an axis-aligned box the closest surface point is the point clamped to the box (an independent
    formula); on its faces, the point itself."""
    corners = np.array([[x, y, z] for x in (0.0, 2.0) for y in (0.0, 1.0) for z in (0.0, 3.0)])
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    faces = np.array([tri for a, b, c, d in quads for tri in ((a, b, c), (a, c, d))])
    rng = np.random.default_rng(3)
    outside = rng.uniform(-2.0, 5.0, size=(2000, 3))
    outside = outside[((outside < corners.min(axis=0)) | (outside > corners.max(axis=0))).any(axis=1)]
    clamped = np.clip(outside, corners.min(axis=0), corners.max(axis=0))
    np.testing.assert_allclose(closest_points_on_surface(corners, faces, outside), clamped, atol=1e-12)
    np.testing.assert_allclose(closest_points_on_surface(corners, faces, clamped), clamped, atol=1e-12)


def _cow_with_a_hole(cow, radius=0.06, pairs=150):
    """The exactly symmetric cow with a patch of its left flank cut out, landmarks outside the hole."""
    centre = cow.points[np.argmax(cow.points[:, 0])]
    cut = np.linalg.norm(cow.points - centre, axis=1) < radius * cow.diagonal
    faces = cow.faces[~cut[cow.faces].any(axis=1)]
    used = np.unique(faces)
    remap = -np.ones(len(cow.points), dtype=int)
    remap[used] = np.arange(len(used))
    left, right = cow.landmarks(pairs)
    kept = (remap[left] >= 0) & (remap[right] >= 0)
    ms = meshset_with_pairs(cow.points[used], remap[faces], remap[left[kept]], remap[right[kept]])
    return ms, cut


def _distance_to_truth(cow, points):
    return np.linalg.norm(closest_points_on_surface(cow.points, cow.faces, points) - points, axis=1)


def test_a_filled_hole_takes_the_shape_of_its_mirror_twin(cow):
    ms, _ = _cow_with_a_hole(cow)
    before = ms.current_mesh().vertex_number()
    ms.meshing_close_holes(maxholesize=300, newfaceselected=True, refinehole=True, selected=False)
    filled = ms.current_mesh().vertex_matrix()
    new = np.arange(before, len(filled))
    assert len(new) >= 10
    report = ms.generate_symmetrized_mesh(missing_region="selection")
    output = ms.current_mesh().vertex_matrix()
    hole_filling_alone = _distance_to_truth(cow, filled[new])
    mirrored = _distance_to_truth(cow, output[new])
    # measured: mean 0.0198 -> 0.0028, max 0.035 -> 0.0073 (diagonal 2.14)
    assert mirrored.mean() < hole_filling_alone.mean() / 4
    assert mirrored.max() < hole_filling_alone.max() / 3
    assert report["filled_vertices"] == len(new)
    # the intact part of an exactly symmetric mesh does not move
    assert np.abs(output[:before] - filled[:before]).max() < 1e-9 * cow.diagonal


def broken_cow(cow):
    """The cow with a bump pushed out of one side (a broken part): (bumped points, broken (N,) bool, left and
    right landmark vertices off the broken part)."""
    centre = cow.points[np.argmax(cow.points[:, 0])]
    broken = np.linalg.norm(cow.points - centre, axis=1) < 0.07 * cow.diagonal
    bumped = cow.points.copy()
    bumped[broken, 0] += 0.03 * cow.diagonal
    left, right = cow.landmarks(150)
    sound = ~broken[left] & ~broken[right]
    return bumped, broken, left[sound], right[sound]


def test_weight_attribute_marks_a_broken_part(cow):
    bumped, broken, left, right = broken_cow(cow)
    ms = meshset_with_pairs(bumped, cow.faces, left, right)
    ms.current_mesh().add_vertex_custom_scalar_attribute(np.where(broken, 0.0, 1.0), "symblend_weight")
    ms.generate_symmetrized_mesh(missing_region="weight")
    output = ms.current_mesh().vertex_matrix()
    # measured: worst distance to the true surface 0.064 -> 0.0011 (diagonal 2.14)
    assert _distance_to_truth(cow, output[broken]).max() < _distance_to_truth(cow, bumped[broken]).max() / 3


def test_missing_region_errors_and_warning(cow):
    ms, _ = _cow_with_a_hole(cow, radius=0.0)
    with pytest.raises(MeshSetError, match="reads the per-vertex attribute `symblend_weight`"):
        ms.generate_symmetrized_mesh(missing_region="weight")
    with pytest.warns(SymblendWarning, match="nothing is filled"):
        ms.generate_symmetrized_mesh(missing_region="selection")
    cloud = meshset_with_pairs(cow.points, None, *cow.landmarks(40))
    with pytest.raises(MeshSetError, match="is a point cloud; use missing_region='none'"):
        cloud.generate_symmetrized_mesh(missing_region="selection")


def test_a_fill_with_no_intact_face_left_is_an_error(cow):
    everything = np.ones(len(cow.points))
    with pytest.raises(filter_symblend.GeometryError, match="No intact face is left to mirror"):
        fill_from_mirror(cow.points, cow.faces, everything, [1.0, 0.0, 0.0], cow.offset)


def test_the_fill_runs_on_arrays_as_in_the_filter_and_in_either_frame(cow):
    """`symmetrize(..., missing=...)` is what the filter's missing_region does; the canonical frame is
    the same fill moved rigidly."""
    from filter_symblend import ParameterError, symmetrize
    bumped, broken, left, right = broken_cow(cow)
    missing = np.where(broken, 1.0, 0.0)
    result = symmetrize(bumped, left, right, faces=cow.faces, missing=missing)
    ms = meshset_with_pairs(bumped, cow.faces, left, right)
    ms.current_mesh().add_vertex_custom_scalar_attribute(1.0 - missing, "symblend_weight")
    ms.generate_symmetrized_mesh(missing_region="weight")
    np.testing.assert_allclose(result.points, ms.current_mesh().vertex_matrix(), atol=1e-9)
    assert result.report.filled_vertices == broken.sum()
    assert _distance_to_truth(cow, result.points[broken]).max() < _distance_to_truth(cow, bumped[broken]).max() / 3
    canonical = symmetrize(bumped, left, right, faces=cow.faces, missing=missing, output_frame="canonical")
    transform = canonical.report.canonical_from_input
    np.testing.assert_allclose(canonical.points, result.points @ transform[:3, :3].T + transform[:3, 3], atol=1e-9)
    with pytest.raises(ParameterError, match=r"`missing` vertices take the mirror shape .* pass `faces`"):
        symmetrize(bumped, left, right, missing=missing)
    with pytest.raises(ParameterError, match=r"`missing` needs one finite value in \[0, 1\] per vertex"):
        symmetrize(bumped, left, right, faces=cow.faces, missing=missing[:10])
    with pytest.raises(ParameterError, match=r"`missing_faces` marks faces .* give `missing` too"):
        symmetrize(bumped, left, right, faces=cow.faces, missing_faces=np.zeros(len(cow.faces), bool))
    with pytest.raises(ParameterError, match=r"`missing_faces` needs one bool per face"):
        symmetrize(bumped, left, right, faces=cow.faces, missing=missing, missing_faces=[True])


def test_a_surface_point_from_its_barycentric_weights_is_that_point_of_its_triangle():
    from filter_symblend.core.surface_points import barycentric, on_surface, vertex_points
    rng = np.random.default_rng(3)
    points = rng.normal(size=(10, 3))
    corners = np.array([[0, 1, 2], [3, 4, 5], [7, 8, 9]])
    weights = rng.dirichlet(np.ones(3), size=3)
    expected = np.array([w @ points[c] for c, w in zip(corners, weights)])
    np.testing.assert_allclose(on_surface(points, corners, weights), expected, atol=1e-14)
    np.testing.assert_allclose(barycentric(points[corners], expected), weights, atol=1e-12)  # and back
    np.testing.assert_array_equal(on_surface(points, *vertex_points(np.array([6, 2]))), points[[6, 2]])

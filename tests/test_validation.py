"""Every bad input raises a SymblendError naming the problem and the fix; nothing changes."""

import threading
import warnings

import numpy as np
import pymeshlab
import pytest

import filter_symblend
from filter_symblend import (GeometryError, LandmarkError, MeshSetError, ParameterError, SymblendError,
                             symmetrize)

from conftest import meshset_with_pairs


def snapshot(ms):
    """Everything the filter could change: layer ids, current id, every layer's coordinates."""
    ids = [i for i in range(ms.mesh_number() + 8) if ms.mesh_id_exists(i)]
    current = ms.current_mesh_id() if ms.mesh_number() else None
    return ids, current, [ms.mesh(i).vertex_matrix().copy() for i in ids]


def assert_unchanged(ms, before):
    after = snapshot(ms)
    assert after[0] == before[0] and after[1] == before[1]
    for a, b in zip(after[2], before[2]):
        np.testing.assert_array_equal(a, b)


def cube_pairs():
    """A symmetric point set: 8 pairs on a box, left at x > 0."""
    grid = np.array([[x, y, z] for x in (1.0, 2.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
    return np.vstack([grid, grid * [-1, 1, 1]]), np.arange(8), np.arange(8, 16)


def meshset_with_labels(points, labels, attribute="symblend_pair"):
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=points))
    ms.current_mesh().add_vertex_custom_scalar_attribute(np.asarray(labels, dtype=float), attribute)
    return ms


def labels_for(n_vertices, left, right):
    labels = np.zeros(n_vertices)
    labels[left] = np.arange(1, len(left) + 1)
    labels[right] = -np.arange(1, len(right) + 1)
    return labels


def run_and_expect(ms, error, pattern, **params):
    """The filter raises ``error`` matching ``pattern``, leaves ``ms`` as it was, and no numpy warning
    comes before the error (from any thread: the checks run beside the warp)."""
    before = snapshot(ms)
    with warnings.catch_warnings(record=True) as caught, pytest.raises(error, match=pattern) as info:
        warnings.simplefilter("always")
        ms.generate_symmetrized_mesh(**params)
    assert isinstance(info.value, SymblendError) and isinstance(info.value, ValueError)
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]
    assert_unchanged(ms, before)


def test_empty_meshset():
    run_and_expect(pymeshlab.MeshSet(), MeshSetError, r"no current mesh.*load_new_mesh")


def test_missing_attribute_names_it_and_how_to_add_it():
    points, left, right = cube_pairs()
    ms = meshset_with_labels(points, labels_for(16, left, right), attribute="other")
    run_and_expect(ms, LandmarkError, r"no per-vertex custom scalar attribute `symblend_pair`.*add_vertex_custom_scalar_attribute")


def test_custom_attribute_name_is_used():
    points, left, right = cube_pairs()
    ms = meshset_with_labels(points, labels_for(16, left, right), attribute="my_pairs")
    ms.generate_symmetrized_mesh(pair_attribute="my_pairs")
    assert ms.mesh_number() == 2


@pytest.mark.parametrize("edit, pattern", [
    (lambda lab: lab.__setitem__(8 + 2, 0), r"Pair 3: \+3 on vertex 2 has no -3 partner.*Put -3 on the right vertex"),
    (lambda lab: lab.__setitem__(2, 0), r"Pair 3: -3 on vertex 10 has no \+3 partner"),
    (lambda lab: lab.__setitem__(4, 2), r"Pair label \+2 is used on 2 vertices \(1, 4\)"),
    (lambda lab: lab.__setitem__(12, -2), r"Pair label -2 is used on 2 vertices \(9, 12\)"),
    (lambda lab: lab.__setitem__(5, 1.5), r"holds 1.5 at vertex 5; pair labels are whole numbers"),
    (lambda lab: lab.__setitem__(5, np.nan), r"not finite at vertex 5"),
])
def test_malformed_pair_labels(edit, pattern):
    points, left, right = cube_pairs()
    labels = labels_for(16, left, right)
    edit(labels)
    run_and_expect(meshset_with_labels(points, labels), LandmarkError, pattern)


def test_the_minimum_is_a_plane_and_a_warp_not_a_pair_count():
    points, left, right = cube_pairs()
    run_and_expect(meshset_with_labels(points, np.zeros(16)), LandmarkError,
                   r"Found no landmark pair; the filter needs at least one pair")
    with pytest.raises(GeometryError, match=r"The symmetry plane is undefined: the pairs' midpoints and the "
                                            r"midline landmarks must span it .* and 1 pair\(s\) and 0 midline "
                                            r"landmark\(s\) give one point. Add a pair or a midline landmark"):
        symmetrize(points, left[:1], right[:1])
    # Two mirror pairs always lie on one plane: the warp needs a third landmark off it ...
    with pytest.raises(GeometryError, match=r"All landmarks \(2 pair\(s\) and 0 midline landmark\(s\)\) lie "
                                            r"\(nearly\) on one plane.*needs 4 landmarks not on one plane"):
        symmetrize(points, left[:2], right[:2])
    # ... and a midline landmark off it will do: 2 pairs + 1 midline landmark are the minimum.
    square = np.array([[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [-1.0, 1.0, 0.0], [0.0, 0.5, 1.0]])
    result = symmetrize(square, [0, 1], [2, 3], midline=[4])
    assert result.report.landmark_asymmetry_after.max_relative < 1e-12
    normal, offset = np.array(result.report.plane.normal), result.report.plane.offset
    assert abs(result.points[4] @ normal - offset) < 1e-12


def test_vertex_paired_with_itself():
    points, left, right = cube_pairs()
    right = right.copy()
    right[2] = left[2]
    with pytest.raises(LandmarkError, match=r"Pair 3 pairs vertex 2 with itself"):
        symmetrize(points, left, right)


def test_vertex_in_two_pairs():
    points, left, right = cube_pairs()
    right = right.copy()
    right[2] = left[5]
    with pytest.raises(LandmarkError, match=r"Vertex 5 is used by two landmarks \(\+6 and -3\); each vertex can hold one"):
        symmetrize(points, left, right)


def test_non_integer_index_arrays():
    points, left, right = cube_pairs()
    with pytest.raises(LandmarkError, match=r"`left` must hold integer vertex indices, got float64"):
        symmetrize(points, left + 0.5, right)


def test_mismatched_index_arrays():
    points, left, right = cube_pairs()
    with pytest.raises(LandmarkError, match=r"one entry per pair; got 8, 7 and 8"):
        symmetrize(points, left, right[:7])


def test_vertex_index_out_of_range():
    points, left, right = cube_pairs()
    with pytest.raises(LandmarkError, match=r"Pair 1 names vertex 99, but the mesh has 16 vertices"):
        symmetrize(points, np.r_[99, left[1:]], right)


def test_non_finite_coordinates():
    points, left, right = cube_pairs()
    points = np.vstack([points, [np.inf, 0, 0]])
    ms = meshset_with_labels(points, labels_for(17, left, right))
    run_and_expect(ms, GeometryError, r"not finite \(NaN or inf\) at vertex 16")


def test_landmarks_at_one_position():
    points, left, right = cube_pairs()
    doubled = np.vstack([points, points[3], points[11]])  # vertices 16, 17 duplicate 3, 11
    with pytest.raises(GeometryError, match=r"Landmarks \+4 and \+9 sit at the same position \(vertices 3 and 16\)"
                                            r".*meshing_remove_duplicate_vertices"):
        symmetrize(doubled, np.r_[left, 16], np.r_[right, 17])
    close = np.vstack([points, points[3]])
    with pytest.raises(GeometryError, match=r"Pair 4: its two landmarks sit at the same position"):
        symmetrize(close, left, np.r_[right[:3], 16, right[4:]])


def test_collinear_and_coplanar_landmarks():
    line = np.column_stack([np.r_[1:6, -np.arange(1, 6)].astype(float), np.zeros(10), np.zeros(10)])
    with pytest.raises(GeometryError, match=r"on one line"):
        symmetrize(line, np.arange(5), np.arange(5, 10))
    plane = np.array([[x, y, 0.0] for x in (1.0, 2.0) for y in (0.0, 1.0, 2.0)])
    plane = np.vstack([plane, plane * [-1, 1, 1]])
    off_the_plane = np.vstack([plane, [[0.0, 1.0, 3.0], [0.5, 0.0, -2.0]]])  # the mesh is not flat
    with pytest.raises(GeometryError, match=r"All landmarks \(6 pair\(s\) and 0 midline landmark\(s\)\) lie \(nearly\) "
                                            r"on one plane, and the mesh does not; the 3D warp needs 4 landmarks not on "
                                            r"one plane.*Add pairs off it"):
        symmetrize(off_the_plane, np.arange(6), np.arange(6, 12))
    result = symmetrize(plane, np.arange(6), np.arange(6, 12))  # a flat mesh: its landmarks are in its plane
    assert (result.points[:, 2] == 0.0).all()


def flat_patch_and_far_cluster():
    """A flat 5 x 5 patch of pairs (z = 0) and, far away, a small 3D cluster of pairs."""
    patch = np.array([[x, y, 0.0] for x in (1.0, 1.5, 2.0, 2.5, 3.0) for y in np.linspace(0, 2, 5)])
    cluster = np.array([[1.0, 20.0, 20.0], [1.5, 20.0, 20.5], [1.2, 20.5, 20.0], [1.8, 20.4, 20.6]])
    left = np.vstack([patch, cluster])
    return np.vstack([left, left * [-1, 1, 1]]), np.arange(29), np.arange(29, 58)


def test_affine_mode_rejects_a_flat_neighbourhood():
    points, left, right = flat_patch_and_far_cluster()
    with pytest.raises(GeometryError, match=r"around pair\(s\) 1, 2, .* \(nearly\) coplanar.*`theta_width`"):
        symmetrize(points, left, right, mode="affine", theta_width=1, phi_width=100)


def test_articulated_mode_rejects_a_collinear_neighbourhood():
    line = np.array([[1.0, y, 0.0] for y in np.linspace(0, 4, 9)])
    cluster = np.array([[1.0, 20.0, 20.0], [1.5, 20.0, 20.5], [1.2, 20.5, 20.0], [1.8, 20.4, 20.6]])
    left = np.vstack([line, cluster])
    points = np.vstack([left, left * [-1, 1, 1]])
    with pytest.raises(GeometryError, match=r"around pair\(s\) 1, .* \(nearly\) collinear"):
        symmetrize(points, np.arange(13), np.arange(13, 26), mode="articulated", theta_width=1, phi_width=100)


def test_disconnected_pairs_name_the_isolated_ones_and_the_width_that_connects_them():
    points, left, right = flat_patch_and_far_cluster()
    with pytest.raises(GeometryError, match=r"fall apart into 2 groups at `phi_width` = 5: pairs 26, 27, 28, 29 "
                                            r"are not connected to the other 25\. Set `phi_width` to [0-9.]+ or more, or place") as info:
        symmetrize(points, left, right)
    needed = float(str(info.value).split("Set `phi_width` to ")[1].split(" ")[0])
    symmetrize(points, left, right, phi_width=needed)  # the suggested width connects them
    with pytest.raises(GeometryError, match="fall apart"):
        symmetrize(points, left, right, phi_width=0.9 * needed)


@pytest.mark.parametrize("params, error, pattern", [
    ({"mode": "stretch"}, ParameterError, r"`mode` must be one of 'standard', 'affine', 'articulated', got 'stretch'"),
    ({"alpha": 0}, ParameterError, r"`alpha` must be in \(0, 100\], got 0"),
    ({"alpha": float("nan")}, ParameterError, r"`alpha` must be finite"),
    ({"phi_width": 0.1}, ParameterError, r"`phi_width` must be in \[0.5, 1000\]"),
    ({"theta_width": "5"}, ParameterError, r"`theta_width` must be a number, got '5'"),
    ({"output_frame": "world"}, ParameterError, r"`output_frame` must be one of 'input', 'canonical'"),
    ({"pair_attribute": "my pairs"}, ParameterError, r"`pair_attribute` must be an attribute name"),
    ({"alhpa": 0.1}, ParameterError, r"Unknown parameter `alhpa`\. Did you mean `alpha`\?"),
])
def test_bad_parameters(params, error, pattern):
    points, left, right = cube_pairs()
    run_and_expect(meshset_with_labels(points, labels_for(16, left, right)), error, pattern, **params)


@pytest.mark.parametrize("params", [{"pair_attribute": "symblend_asymmetry"},
                                    {"midline_attribute": "symblend_pair_confidence"},
                                    {"weight_attribute": "symblend_midline"}])
def test_attribute_names_must_differ(params):
    points, left, right = cube_pairs()
    ms = meshset_with_labels(points, labels_for(16, left, right),
                             attribute=params.get("pair_attribute", "symblend_pair"))
    run_and_expect(ms, ParameterError, r"must be three different names, none of them `symblend_asymmetry`, "
                   r"`symblend_twin`, `symblend_pair_confidence`, `symblend_uncertainty` \(the filter writes them\)", **params)


def test_pair_attribute_is_not_a_parameter_of_the_array_core():
    points, left, right = cube_pairs()
    with pytest.raises(ParameterError, match=r"Unknown parameter `pair_attribute`"):
        symmetrize(points, left, right, pair_attribute="x")


def test_failure_while_building_the_layer_leaves_the_meshset_as_it_was(cow, monkeypatch):
    left, right = cow.landmarks(40)
    ms = meshset_with_pairs(cow.points, cow.faces, left, right)
    ms.load_new_mesh(str(__import__("conftest").SAMPLE_MESHES / "cube.obj"))
    ms.set_current_mesh(0)
    before = snapshot(ms)

    def broken(*args, **kwargs):
        raise pymeshlab.PyMeshLabException("simulated failure")

    monkeypatch.setattr(pymeshlab.MeshSet, "compute_normal_per_vertex", broken)
    with pytest.raises(pymeshlab.PyMeshLabException, match="simulated"):
        ms.generate_symmetrized_mesh()
    assert_unchanged(ms, before)
    assert filter_symblend.FILTER_NAME == "generate_symmetrized_mesh"


def test_failure_of_a_check_beside_the_layer_removes_the_layer(cow, monkeypatch):
    """The checks run in a thread while the layer is built: if one fails once the layer exists, the
    layer goes too, and the check's own error reaches the caller."""
    from filter_symblend.meshlab import meshset_filter

    left, right = cow.landmarks(40)
    ms = meshset_with_pairs(cow.points, cow.faces, left, right)
    before = snapshot(ms)
    normals_done = threading.Event()  # the layer's last MeshLab filter has run
    compute_normals = pymeshlab.MeshSet.compute_normal_per_vertex

    def normals_then_signal(self, *args, **kwargs):
        compute_normals(self, *args, **kwargs)
        normals_done.set()

    def failing_check(*args, **kwargs):
        assert normals_done.wait(timeout=60)
        raise MemoryError("simulated failure of a check")

    monkeypatch.setattr(pymeshlab.MeshSet, "compute_normal_per_vertex", normals_then_signal)
    monkeypatch.setattr(meshset_filter, "_mirror_check", failing_check)
    with pytest.raises(MemoryError, match="simulated failure of a check"):
        ms.generate_symmetrized_mesh()
    assert normals_done.is_set()
    assert_unchanged(ms, before)

"""Automatic mirror pairs: exact on exactly symmetric shapes, dense on landmark runs, clear errors."""

import re
import warnings

import numpy as np
import pymeshlab
import pytest

import filter_symblend  # noqa: F401  (binds the filter)
from filter_symblend import (GeometryError, LandmarkError, ParameterError, SymblendError, SymblendWarning,
                             symmetrize, synthetic)
from filter_symblend.auto_pairs import mirror_correspondence
from filter_symblend.mesh_geometry import mean_spacing, vertex_normals
from filter_symblend.mirror_fill import closest_points_on_surface
from filter_symblend.surface_symmetry import mirror_asymmetry

from conftest import SHARED_DATA, meshset_with_pairs


def symmetric_blob(subdivisions: int = 4):
    """An exactly mirror-symmetric closed mesh with one mirror plane (x = 0): an icosphere (whose
    vertex set is closed under x -> -x) with bumps that are even in x but not in y or z."""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=subdivisions)
    mesh = ms.current_mesh()
    points, faces = mesh.vertex_matrix(), mesh.face_matrix()
    x, y, z = points.T
    radius = 1.0 + 0.25 * np.cos(3.0 * x) * np.exp(y) + 0.2 * z**3 + 0.15 * x**2 * y
    return points * radius[:, None], faces


def twins(points):
    """The exact mirror twin of every vertex across x = 0."""
    from scipy.spatial import cKDTree
    distance, twin = cKDTree(points).query(points * [-1.0, 1.0, 1.0])
    assert distance.max() < 1e-9
    return twin


@pytest.fixture(scope="module")
def blob():
    return symmetric_blob()


def test_an_exactly_symmetric_mesh_in_a_random_pose_is_unchanged_and_its_plane_found(blob):
    points, faces = blob
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    rng = np.random.default_rng(3)
    for seed in (1, 2):
        posed = synthetic.random_rigid(points, seed)
        rotation = np.linalg.lstsq(np.column_stack([points, np.ones(len(points))]), posed, rcond=None)[0][:3].T
        result = symmetrize(posed, faces=faces, pairs="auto", mode=rng.choice(["standard", "affine"]))
        assert np.abs(result.points - posed).max() < 1e-6 * diagonal
        true_normal = rotation @ [1.0, 0.0, 0.0]
        angle = np.degrees(np.arccos(min(1.0, abs(np.dot(result.report["plane_normal"], true_normal)))))
        assert angle < 0.1
        auto = result.report["auto_pairs"]
        assert auto["converged"] and auto["pair_count"] > 500 and auto["midline_count"] > 0
        assert len(auto["rounds"]) == 2 and auto["rounds"][1]["changed_vertices"] == 0.0


def test_the_correspondence_of_a_symmetric_mesh_is_its_exact_mirror_map(blob):
    points, faces = blob
    correspondence = mirror_correspondence(points, faces, [1.0, 0.0, 0.0], 0.0)
    twin = twins(points)
    paired = correspondence.partner >= 0
    assert paired.mean() > 0.99
    np.testing.assert_array_equal(correspondence.partner[paired], twin[paired])
    on_left = paired & (twin != np.arange(len(points)))
    np.testing.assert_array_equal(correspondence.side[on_left], np.sign(points[on_left, 0]))


def test_the_correspondence_grows_past_where_one_plane_can_pair(blob):
    """Slightly bent (as after a landmark solve), the blob's ends no longer mirror across the plane
    within the acceptance distance; local mirror maps pair them, correctly."""
    points, faces = blob
    correspondence = mirror_correspondence(synthetic.bend(points, 0.05, along=1), faces, [1.0, 0.0, 0.0], 0.0)
    assert correspondence.seeds < 0.8 * len(points) and correspondence.waves > 0  # measured 78 %
    np.testing.assert_array_equal(correspondence.partner, twins(points))


def test_mild_asymmetry_is_more_than_halved_without_landmarks(cow):
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=synthetic.random_rigid(synthetic.bend(cow.points, 0.2), 6),
                               face_matrix=cow.faces))
    report = ms.generate_symmetrized_mesh(pairs="auto")
    assert report["pair_count"] == 0 and "landmark_asymmetry_before" not in report
    # the input's asymmetry is measured across the surface plane the pairing started from, as fitted afresh
    independent = mirror_asymmetry(ms.mesh(report["input_mesh_id"]).vertex_matrix(), cow.faces)
    assert report["mirror_asymmetry_before"]["plane_normal"] == report["auto_pairs"]["surface_plane"]["normal"]
    assert report["mirror_asymmetry_before"]["rms"] == pytest.approx(independent["rms"], rel=1e-12)
    assert report["mirror_asymmetry_after"]["rms"] < report["mirror_asymmetry_before"]["rms"] / 2
    assert report["hausdorff_input_output"]["max"] > 0
    assert ms.current_mesh().vertex_number() == len(cow.points)


@pytest.mark.parametrize("deformation", ["bend", "figure 1"])
def test_landmarks_plus_auto_makes_every_vertex_pair_more_symmetric(cow, deformation):
    deform = {"bend": lambda p: synthetic.bend(p, 1.2), "figure 1": synthetic.figure_1_deformation}[deformation]
    deformed = synthetic.random_rigid(deform(cow.points), seed=3)
    left, right = cow.landmarks(100)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SymblendWarning)
        alone = symmetrize(deformed, left, right, mode="affine")
        dense = symmetrize(deformed, left, right, faces=cow.faces, pairs="landmarks+auto", mode="affine")
    error_alone = synthetic.symmetry_error(alone.points, cow.all_left, cow.all_right)
    error_dense = synthetic.symmetry_error(dense.points, cow.all_left, cow.all_right)
    assert error_dense < error_alone / 2  # measured 4.3x (bend) and 2.5x (figure 1)
    assert synthetic.shape_error(dense.points, cow.points) <= synthetic.shape_error(alone.points, cow.points)
    # the user's landmarks stay exact mirror images
    assert dense.report["landmark_asymmetry_after"]["max_relative"] < 1e-9
    assert dense.report["pair_count"] == 100 and dense.report["auto_pairs"]["pair_count"] > 500


@pytest.mark.parametrize("deformation", ["bend 0.4 rad", "bend 0.4 rad + compression 0.85"])
def test_fifty_landmarks_plus_auto_beat_a_hundred_landmarks_five_times(cow, deformation):
    """The README's advice for a moderately deformed specimen: half the landmarks, plus automatic pairs,
    give every vertex pair a fifth of the asymmetry that twice as many landmarks leave alone."""
    bent = synthetic.bend(cow.points, 0.4)
    deformed = bent if deformation == "bend 0.4 rad" else synthetic.compress(bent, [1, 1, 0], 0.85, shear=0.05)
    deformed = synthetic.random_rigid(deformed, seed=7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SymblendWarning)
        hundred = symmetrize(deformed, *cow.landmarks(100), mode="affine")
        fifty = symmetrize(deformed, *cow.landmarks(50), faces=cow.faces, pairs="landmarks+auto", mode="affine")
    errors = [synthetic.symmetry_error(out.points, cow.all_left, cow.all_right) for out in (hundred, fifty)]
    print(deformation, "symmetry error, 100 landmarks / 50 landmarks + auto:", errors)
    assert errors[1] < errors[0] / 5  # measured 18x for both
    assert synthetic.shape_error(fifty.points, cow.points) <= synthetic.shape_error(hundred.points, cow.points)


def _cow_with_a_subtle_dent(cow, depth=0.1):
    """The exactly symmetric cow with a patch of its left flank pushed out along the normals by
    ``depth`` mean edge lengths: shallow enough for automatic pairs to accept. (points, patch mask,
    mirror twins of the patch, mean edge length)."""
    spacing = mean_spacing(cow.points, cow.faces)
    normals, _ = vertex_normals(cow.points, cow.faces)
    centre = cow.points[np.argmax(cow.points[:, 0])]
    patch = np.linalg.norm(cow.points - centre, axis=1) < 0.07 * cow.diagonal
    dented = cow.points.copy()
    dented[patch] += depth * spacing * normals[patch]
    twins = cow.partner[patch]
    return dented, patch, twins[twins >= 0], spacing


def test_excluded_vertices_do_not_pull_the_sound_side_toward_them(cow):
    dented, patch, twins, spacing = _cow_with_a_subtle_dent(cow)
    paired = symmetrize(dented, faces=cow.faces, pairs="auto", mode="affine")
    excluded = symmetrize(dented, faces=cow.faces, pairs="auto", mode="affine", auto_excluded=patch)
    moved = [np.linalg.norm(out.points[twins] - cow.points[twins], axis=1).max() / spacing
             for out in (paired, excluded)]
    assert moved[0] > 0.04  # measured 0.055: the sound twins meet the dent halfway
    assert moved[1] < 1e-3  # measured 1e-4: they follow the warp of the pairs around
    assert excluded.report["auto_pairs"]["excluded_vertices"] == np.count_nonzero(patch)
    same = symmetrize(dented, faces=cow.faces, pairs="auto", mode="affine", auto_excluded=np.flatnonzero(patch))
    np.testing.assert_array_equal(same.points, excluded.points)  # a mask or indices


def test_a_missing_region_is_left_out_of_the_automatic_pairs_and_filled_from_the_sound_side(cow):
    """With landmarks+auto as with landmarks alone, the dent (marked missing) takes the mirror shape of
    the sound side, which does not move."""
    dented, patch, twins, spacing = _cow_with_a_subtle_dent(cow)
    left, right = cow.landmarks(150)
    sound = ~patch[left] & ~patch[right]
    off_surface = {}
    for pairs in ("landmarks", "landmarks+auto"):
        ms = meshset_with_pairs(dented, cow.faces, left[sound], right[sound])
        ms.current_mesh().add_vertex_custom_scalar_attribute(np.where(patch, 0.0, 1.0), "symblend_weight")
        report = ms.generate_symmetrized_mesh(missing_region="weight", pairs=pairs, mode="affine")
        stored, output = ms.mesh(0).vertex_matrix(), ms.current_mesh().vertex_matrix()  # as pymeshlab holds them
        assert np.linalg.norm(output[twins] - stored[twins], axis=1).max() < 1e-3 * spacing  # measured 3e-5
        on_surface = closest_points_on_surface(cow.points, cow.faces, output[patch])
        off_surface[pairs] = np.linalg.norm(on_surface - output[patch], axis=1) / spacing
    assert report["auto_pairs"]["excluded_vertices"] == np.count_nonzero(patch)
    # measured: 0.1 edge lengths -> mean 0.016, max 0.066 (the fill fades in over two edges), as with landmarks
    # alone; before the missing region was left out of the automatic pairs: mean 0.051, sound twins moved 0.05
    assert off_surface["landmarks+auto"].mean() < 0.03
    assert off_surface["landmarks+auto"].max() <= off_surface["landmarks"].max() + 1e-3


@pytest.mark.parametrize(("excluded", "pairs", "message"), [
    (np.ones(4, dtype=bool), "landmarks+auto", r"`auto_excluded` as a mask needs one entry per vertex \(2904\), got shape \(4,\)"),
    ([5000], "landmarks+auto", r"`auto_excluded` holds vertex 5000, but the mesh has vertices 0\.\.2903\."),
    ([-1], "landmarks+auto", r"`auto_excluded` holds vertex -1"),
    ([0.5], "landmarks+auto", r"`auto_excluded` must hold integer vertex indices, got float64 values\."),
    ([3], "landmarks", r"`auto_excluded` keeps vertices out of the automatic pairs, and pairs='landmarks' finds none"),
])
def test_bad_exclusions_are_refused_naming_the_fix(cow, excluded, pairs, message):
    left, right = cow.landmarks(20)
    with pytest.raises(SymblendError, match=message):
        symmetrize(cow.points, left, right, faces=cow.faces, pairs=pairs, auto_excluded=excluded)


def test_progress_covers_every_round(blob):
    points, faces = blob
    seen = []
    symmetrize(points, faces=faces, pairs="auto", progress=lambda percent, message: seen.append((percent, message)))
    percents = [percent for percent, _ in seen]
    assert percents == sorted(percents) and percents[-1] == 100.0
    assert any("round 2" in message for _, message in seen)


def test_auto_refuses_landmarks():
    with pytest.raises(LandmarkError, match=r"pairs='auto'.*ignores landmarks.*pairs='landmarks\+auto'"):
        symmetrize(np.eye(3), [0], [1], pairs="auto")


def test_landmark_modes_need_landmarks():
    with pytest.raises(LandmarkError, match=r"`pairs='landmarks\+auto'` needs landmark pairs.*pairs='auto'"):
        symmetrize(np.eye(3), pairs="landmarks+auto")


def test_a_shape_without_mirror_symmetry_is_refused_with_advice():
    points = np.random.default_rng(0).normal(size=(300, 3)) * [3.0, 2.0, 1.0]
    with pytest.raises(GeometryError, match=r"Automatic pairing found no usable mirror pairs \(mirror plane: "
                       r"rejected: it pairs \d+% of the vertices, fewer than 20%;.*landmarks\+auto") as raised:
        symmetrize(points, pairs="auto")
    message = str(raised.value)
    assert message.count("landmarks+auto") == 1  # the advice once, not once per candidate
    assert re.search(r"whitened mirror plane: rejected: its pairs are not locally mirror-symmetric "
                     r"\(median local fit residual 0\.\d\d > 0\.15\)", message)


@pytest.mark.parametrize(("value", "message"), [
    (2.5, r"`auto_pair_count` must be a whole number, got 2.5"),
    (5, r"`auto_pair_count` must be in 10..100000, got 5"),
    ("many", r"`auto_pair_count` must be a number, got 'many'"),
    (float("inf"), r"`auto_pair_count` must be finite, got inf"),
])
def test_integer_parameters_are_checked(value, message):
    with pytest.raises(ParameterError, match=message):
        symmetrize(np.eye(3), pairs="auto", auto_pair_count=value)


def test_auto_on_a_meshset_ignores_the_landmark_attributes(cow):
    left, right = cow.landmarks(30)
    from conftest import meshset_with_pairs
    ms = meshset_with_pairs(synthetic.random_rigid(cow.points, 2), cow.faces, left, right)
    ms.current_mesh().add_vertex_custom_scalar_attribute(np.full(len(cow.points), 0.5), "symblend_midline")
    report = ms.generate_symmetrized_mesh(pairs="auto")  # a bad midline attribute is not even read
    assert report["pair_count"] == 0 and report["auto_pairs"]["converged"]


def test_igea_scan_mirror_asymmetry_is_at_least_halved():
    path = SHARED_DATA / "igea.ply"
    if not path.exists():
        pytest.skip(f"{path} is absent (shared test data not available)")
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    ms.meshing_decimation_quadric_edge_collapse(targetfacenum=40000)
    report = ms.generate_symmetrized_mesh(pairs="auto")
    assert report["mirror_asymmetry_after"]["rms"] < report["mirror_asymmetry_before"]["rms"] / 2
    assert report["hausdorff_input_output"]["max"] > 0
    assert report["auto_pairs"]["exact_twins"] is False  # its sides are tessellated differently: not completed
    rounds = report["auto_pairs"]["rounds"]  # twins hop between neighbours (changed) but barely move
    assert rounds[-1]["moved_twins"] < 0.01 < 0.1 < rounds[-1]["changed_vertices"]


def test_twins_that_hop_to_a_neighbour_or_lose_their_pair_do_not_count_as_moved():
    from importlib import import_module
    moved_twins = import_module("filter_symblend.symmetrize")._moved_twins
    points = np.column_stack([np.arange(10.0), np.zeros(10), np.zeros(10)])  # a row, edges 1 apart
    previous = np.array([9, 8, 7, 6, 5, 4, 3, 2, 1, 0])
    hop = np.array([8, 8, 7, 6, 5, 4, 3, 2, 1, 0])  # vertex 0's twin moves one edge
    lost = np.array([-1, -1, 7, 6, 5, 4, 3, 2, 1, 0])  # vertices 0 and 1 fail the acceptance test
    jump = np.array([5, 8, 7, 6, 5, 4, 3, 2, 1, 0])  # vertex 0's twin moves four edges
    assert moved_twins(points, hop, previous, 1.0) == moved_twins(points, lost, previous, 1.0) == 0.0
    assert moved_twins(points, jump, previous, 1.0) == 0.1

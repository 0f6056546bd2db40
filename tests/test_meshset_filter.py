"""The pymeshlab face: binding, the one new layer, what it keeps, and chaining with MeshLab filters."""

import inspect
import time
import warnings

import numpy as np
import pymeshlab
import pytest

import filter_symblend
from filter_symblend import ASYMMETRY_ATTRIBUTE, PARAMETERS, SymblendWarning
from filter_symblend.testing import synthetic

from conftest import SAMPLE_MESHES, meshlab_mirror_distance, meshset_with_pairs


def test_import_binds_the_filter_onto_meshset_with_the_declared_parameters():
    method = pymeshlab.MeshSet.generate_symmetrized_mesh
    declared = {p.name: p.default for p in PARAMETERS}
    signature = inspect.signature(method)
    assert {name: p.default for name, p in signature.parameters.items() if name != "self"} == {**declared, "progress": None}
    assert inspect.signature(filter_symblend.generate_symmetrized_mesh).parameters.keys() - {"ms", "progress"} == declared.keys()
    for p in PARAMETERS:
        assert f"{p.name} : {p.kind} = {p.default!r}" in method.__doc__
    assert filter_symblend.DISPLAY_NAME in method.__doc__


@pytest.fixture()
def bent_cow_meshset(cow):
    left, right = cow.landmarks(100)
    deformed = synthetic.random_rigid(synthetic.bend(cow.points, 1.0), seed=1)
    ms = meshset_with_pairs(deformed, cow.faces, left, right)
    return ms, deformed, left, right


def test_adds_one_current_layer_and_leaves_the_input_alone(bent_cow_meshset):
    ms, deformed, left, right = bent_cow_meshset
    labels = ms.current_mesh().vertex_custom_scalar_attribute_array("symblend_pair").copy()
    report = ms.generate_symmetrized_mesh(mode="affine")
    assert ms.mesh_number() == 2
    assert report["input_mesh_id"] == 0 and report["output_mesh_id"] == ms.current_mesh_id() != 0
    out, source = ms.current_mesh(), ms.mesh(0)
    np.testing.assert_array_equal(source.vertex_matrix(), deformed)
    np.testing.assert_array_equal(source.vertex_custom_scalar_attribute_array("symblend_pair"), labels)
    np.testing.assert_array_equal(out.face_matrix(), source.face_matrix())
    assert out.vertex_number() == source.vertex_number()
    moved = np.linalg.norm(out.vertex_matrix() - deformed, axis=1)
    np.testing.assert_allclose(out.vertex_scalar_array(), moved, atol=1e-12)
    np.testing.assert_allclose(out.vertex_custom_scalar_attribute_array(ASYMMETRY_ATTRIBUTE), moved, atol=1e-12)
    np.testing.assert_array_equal(out.vertex_custom_scalar_attribute_array("symblend_pair"), labels)
    assert out.label() == f"{source.label()}_symmetrized"
    mirrored = out.vertex_matrix()[right]
    normal, offset = np.array(report["plane_normal"]), report["plane_offset"]
    mirrored = mirrored - 2 * (mirrored @ normal - offset)[:, None] * normal
    assert np.abs(mirrored - out.vertex_matrix()[left]).max() < 1e-12


def test_each_landmark_attribute_is_read_once_and_the_output_carries_it(bent_cow_meshset, monkeypatch):
    """The pair, midline and weight attributes are read from the mesh once per call (the landmarks, the
    missing region and the output layer share what was read), and the output carries the same values."""
    ms, deformed, left, right = bent_cow_meshset
    mesh = ms.current_mesh()
    weights = np.ones(mesh.vertex_number())
    weights[right[:3]] = 0.0  # three broken right landmarks, also the region to fill
    mesh.add_vertex_custom_scalar_attribute(weights, "symblend_weight")
    midline = np.zeros(mesh.vertex_number())
    mesh.add_vertex_custom_scalar_attribute(midline, "symblend_midline")
    reads = []
    original = pymeshlab.Mesh.vertex_custom_scalar_attribute_array
    monkeypatch.setattr(pymeshlab.Mesh, "vertex_custom_scalar_attribute_array",
                        lambda m, name: reads.append(name) or original(m, name))
    ms.generate_symmetrized_mesh(mode="affine", missing_region="weight", checks="none")
    assert sorted(reads) == ["symblend_midline", "symblend_pair", "symblend_weight"]
    output = ms.current_mesh()
    for name, values in (("symblend_weight", weights), ("symblend_midline", midline)):
        np.testing.assert_array_equal(output.vertex_custom_scalar_attribute_array(name), values)


def test_output_matches_the_array_core(bent_cow_meshset):
    ms, deformed, left, right = bent_cow_meshset
    ms.generate_symmetrized_mesh(mode="articulated", phi_width=4, output_frame="canonical")
    core = filter_symblend.symmetrize(deformed, left, right, mode="articulated", phi_width=4, output_frame="canonical")
    # The adapter warps in the input frame, then maps rigidly to the canonical one: rounding only.
    np.testing.assert_allclose(ms.current_mesh().vertex_matrix(), core.points, rtol=0, atol=1e-14)


def test_normals_are_recomputed_for_the_warped_surface(bent_cow_meshset):
    ms, *_ = bent_cow_meshset
    ms.generate_symmetrized_mesh()
    warped_normals = ms.current_mesh().vertex_normal_matrix().copy()
    ms.compute_normal_per_vertex()
    np.testing.assert_allclose(warped_normals, ms.current_mesh().vertex_normal_matrix(), atol=1e-12)


def test_keeps_colours_textures_and_uvs():
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(SAMPLE_MESHES / "bunny10k_textured.obj"))
    mesh = ms.current_mesh()
    points = mesh.vertex_matrix()
    offset, partner = synthetic.mirror_partners(points, tolerance=0.05)
    left, right = synthetic.farthest_point_pairs(points, offset, partner, 30)
    labels = np.zeros(len(points))
    labels[left], labels[right] = np.arange(1, 31), -np.arange(1, 31)
    mesh.add_vertex_custom_scalar_attribute(labels, "symblend_pair")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SymblendWarning)
        ms.generate_symmetrized_mesh()
    out, source = ms.current_mesh(), ms.mesh(0)
    assert out.textures().keys() == source.textures().keys() and out.texture_number() == 1
    np.testing.assert_array_equal(out.wedge_tex_coord_matrix(), source.wedge_tex_coord_matrix())
    np.testing.assert_array_equal(out.vertex_color_matrix(), source.vertex_color_matrix())


def test_point_clouds_work(cow):
    left, right = cow.landmarks(60)
    deformed = synthetic.bend(cow.points, 1.0)
    ms = meshset_with_pairs(deformed, None, left, right)
    assert ms.current_mesh().is_point_cloud()
    ms.generate_symmetrized_mesh()
    assert ms.current_mesh().is_point_cloud() and ms.current_mesh().vertex_number() == len(deformed)
    np.testing.assert_array_equal(ms.current_mesh().vertex_matrix(),
                                  filter_symblend.symmetrize(deformed, left, right).points)


def test_chains_with_meshlab_hausdorff(bent_cow_meshset):
    """MeshLab's own Hausdorff distance agrees with the filter's displacement bound."""
    ms, *_ = bent_cow_meshset
    report = ms.generate_symmetrized_mesh()
    out_id = report["output_mesh_id"]
    ms.generate_copy_of_current_mesh()  # Hausdorff overwrites the sampled mesh's quality: use a copy
    copy_id = ms.current_mesh_id()
    hausdorff = ms.get_hausdorff_distance(sampledmesh=copy_id, targetmesh=0, samplevert=True, sampleface=False,
                                          maxdist=pymeshlab.PureValue(report["diagonal"]))
    assert 0 < hausdorff["max"] <= report["vertex_displacement"]["max"] + 1e-9
    np.testing.assert_allclose(ms.mesh(out_id).vertex_scalar_array(),
                               ms.mesh(out_id).vertex_custom_scalar_attribute_array(ASYMMETRY_ATTRIBUTE))


def test_function_form_equals_method_form(cow):
    left, right = cow.landmarks(50)
    deformed = synthetic.bend(cow.points, 0.7)
    first = meshset_with_pairs(deformed, cow.faces, left, right)
    second = meshset_with_pairs(deformed, cow.faces, left, right)
    first.generate_symmetrized_mesh(alpha=0.1)
    filter_symblend.generate_symmetrized_mesh(second, alpha=0.1)
    np.testing.assert_array_equal(first.current_mesh().vertex_matrix(), second.current_mesh().vertex_matrix())


def test_progress_is_reported_in_order(bent_cow_meshset):
    ms, *_ = bent_cow_meshset
    calls = []
    ms.generate_symmetrized_mesh(progress=lambda percent, message: calls.append((percent, message)))
    percents = [p for p, _ in calls]
    assert percents == sorted(percents) and percents[0] == 0 and percents[-1] == 100
    assert any("global solve" in m for _, m in calls) and any("warping 2904 vertices" in m for _, m in calls)


def test_interrupting_from_progress_leaves_the_meshset_unchanged(bent_cow_meshset):
    from test_validation import assert_unchanged, snapshot

    ms, *_ = bent_cow_meshset
    before = snapshot(ms)

    def interrupt(percent, message):
        if percent >= 50:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        ms.generate_symmetrized_mesh(progress=interrupt)
    assert_unchanged(ms, before)


@pytest.mark.parametrize("checks", ["mirror", "full", "none"])
def test_checks_measure_each_surface_against_its_reflection(bent_cow_meshset, cow, checks):
    """Mirror asymmetry: every vertex's distance to the surface reflected across the reported plane (each
    surface's own, fitted by one rule: the output's lands on the solve's plane), against MeshLab's
    Hausdorff; the Hausdorff only with 'full'."""
    ms, deformed, left, right = bent_cow_meshset
    report = ms.generate_symmetrized_mesh(mode="affine", checks=checks)
    assert ("hausdorff_input_output" in report) == (checks == "full")
    if checks == "none":
        assert "mirror_asymmetry_before" not in report and "mirror_asymmetry_after" not in report
        return
    output = ms.current_mesh().vertex_matrix()
    after = report["mirror_asymmetry_after"]
    cosine = abs(np.dot(after["plane_normal"], report["plane_normal"]))
    assert np.degrees(np.arccos(min(cosine, 1.0))) < 0.5
    centre = output.mean(axis=0)
    assert abs(np.dot(after["plane_normal"], centre) - after["plane_offset"]) == pytest.approx(
        abs(np.dot(report["plane_normal"], centre) - report["plane_offset"]), abs=1e-3 * report["diagonal"])
    for key, points in (("mirror_asymmetry_before", deformed), ("mirror_asymmetry_after", output)):
        assert meshlab_mirror_distance(points, cow.faces, report[key]) == pytest.approx(
            [report[key][k] for k in ("max", "mean", "rms")], rel=2e-3, abs=1e-7)  # MeshLab works in float32
    # The undeformed cow's own plane makes the bent input far from symmetric, the output nearly so.
    assert after["rms_relative"] < report["mirror_asymmetry_before"]["rms_relative"] / 5
    if checks == "full":  # against MeshLab's Hausdorff at the vertices, both ways
        found = [ms.get_hausdorff_distance(sampledmesh=a, targetmesh=b, samplevert=True, sampleface=False,
                                           maxdist=pymeshlab.PureValue(report["diagonal"]))
                 for a, b in ((0, report["output_mesh_id"]), (report["output_mesh_id"], 0))]
        hausdorff = report["hausdorff_input_output"]
        assert hausdorff["max"] == pytest.approx(max(f["max"] for f in found), rel=1e-4)
        assert hausdorff["rms"] == pytest.approx(np.mean([f["RMS"] for f in found]), rel=2e-3)
        assert 0 < hausdorff["max"] <= report["vertex_displacement"]["max"] + 1e-9


def test_mirror_asymmetry_on_a_sample_estimates_all_vertices(cow):
    """The report's sample of evenly strided vertices gives the mean and RMS of all of them closely."""
    from filter_symblend.measures.surface_asymmetry import mirror_asymmetry
    bent = synthetic.bend(cow.points, 0.6)
    plane = (np.array([1.0, 0.0, 0.0]), cow.offset)
    every, sample = (mirror_asymmetry(bent, cow.faces, plane=plane, samples=count) for count in (None, 1000))
    assert every["measured_vertices"] == len(bent) and sample["measured_vertices"] == 1000
    assert sample["rms"] == pytest.approx(every["rms"], rel=0.1) and sample["max"] <= every["max"]


def test_vertices_no_face_uses_are_not_measured_as_surface():
    """pymeshlab's bone.ply has 359 vertices no face uses, off its surface: the Hausdorff distance of the
    mesh to itself is 0 (it measured 8.9 % of the diagonal when they were sampled), and its mirror
    asymmetry is that of the mesh without them."""
    from filter_symblend.measures.hausdorff import two_way_distance
    from filter_symblend.measures.surface_asymmetry import before_and_after, mirror_asymmetry
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(SAMPLE_MESHES / "bone.ply"))
    points, faces = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    ms.meshing_remove_unreferenced_vertices()
    clean, clean_faces = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    assert len(points) - len(clean) == 359
    hausdorff = two_way_distance(points, faces, points, faces, samples=len(points))
    assert hausdorff["max"] == 0.0 and hausdorff["samples"] == len(clean)
    plane = (np.array([1.0, 0.0, 0.0]), float(np.median(clean[:, 0])))
    for samples in (None, 1000):
        stray, without = (mirror_asymmetry(p, f, plane=plane, samples=samples) for p, f in
                          ((points, faces), (clean, clean_faces)))
        assert stray["measured_vertices"] == without["measured_vertices"]
        assert stray["max"] == pytest.approx(without["max"], rel=1e-12)
        assert stray["rms"] == pytest.approx(without["rms"], rel=1e-12)
    assert len(mirror_asymmetry(points, faces, plane=plane)["per_vertex"]) == len(points)  # one per vertex
    moved = points + 0.01 * np.sin(points[:, [1, 2, 0]])  # the stray vertices ride along
    figures = before_and_after((points, faces), (moved, faces)), \
        before_and_after((clean, clean_faces), (clean + 0.01 * np.sin(clean[:, [1, 2, 0]]), clean_faces))
    for side in range(2):
        assert figures[0][side]["plane_normal"] == pytest.approx(figures[1][side]["plane_normal"], abs=1e-9)
        assert figures[0][side]["p90"] == pytest.approx(figures[1][side]["p90"], rel=1e-9)


@pytest.mark.parametrize("checks, measured", [("none", set()),
                                              ("mirror", {"input_planes", "mirror_asymmetry_before", "mirror_asymmetry_after"}),
                                              ("full", {"input_planes", "mirror_asymmetry_before", "mirror_asymmetry_after",
                                                        "hausdorff_input_output"})])
def test_the_report_times_the_whole_call_and_each_check(bent_cow_meshset, checks, measured):
    """The core's stages sum to its total; each check that ran has its own seconds (run beside the core, they
    may exceed what they add); the whole call, timed here from outside, includes the core."""
    ms, *_ = bent_cow_meshset
    start = time.perf_counter()
    seconds = ms.generate_symmetrized_mesh(checks=checks)["seconds"]
    outside = time.perf_counter() - start
    stages = ("neighbourhoods", "local_transforms", "global_solve", "warp")
    assert sum(seconds[stage] for stage in stages) == pytest.approx(seconds["total"])
    assert set(seconds["checks"]) == measured and all(value > 0 for value in seconds["checks"].values())
    assert seconds["total"] < seconds["filter"] <= outside

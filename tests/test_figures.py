"""Before/after figures: one measurement in every command, percentiles, warnings said out loud, the
picture in the object's own frame."""

import json
import re
import warnings

import numpy as np
import pymeshlab
import pytest

from filter_symblend.commands.main import main
from filter_symblend.core.geometry import reflection_across_plane
from filter_symblend.core.landmark_asymmetry import fit_mirror_plane
from filter_symblend.landmarks.formats import Landmark, LandmarkSet, write_landmarks
from filter_symblend.measures.verdict import LEFT_ASYMMETRIC, PART_LEFT_ASYMMETRIC
from filter_symblend.testing import synthetic
from conftest import meshset_with_pairs, symmetric_blob, twins

KEYS = ("p50", "p90", "p99", "rms", "max", "mean")


def _files(tmp_path, points, faces, left, right, midline=()):
    mesh = tmp_path / "input.ply"
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(points, faces))
    ms.save_current_mesh(str(mesh))
    marks = [Landmark(f"{side}_{k}", tuple(points[v])) for k, (a, b) in enumerate(zip(left, right))
             for side, v in (("L", a), ("R", b))]
    marks += [Landmark(f"mid_{k}", tuple(points[v])) for k, v in enumerate(midline)]
    landmarks = tmp_path / "input.pp"
    write_landmarks(landmarks, LandmarkSet(marks))
    return mesh, landmarks


def torus():
    """A CAD-like part, exactly mirror-symmetric, with 40 landmark pairs."""
    ms = pymeshlab.MeshSet()
    ms.create_torus(hradius=3, vradius=1, hsubdiv=48, vsubdiv=24)
    points, faces = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    offset, partner = synthetic.mirror_partners(points)
    left, right = synthetic.farthest_point_pairs(points, offset, partner, 40)
    return points, faces, left, right, []


def bent(cow, pairs):
    left, right = cow.landmarks(pairs)
    midline = np.flatnonzero(cow.partner == np.arange(len(cow.points)))[::20][:4] if pairs < 10 else []
    return synthetic.bend(cow.points, 0.8), cow.faces, left, right, midline


@pytest.mark.parametrize("case", ["cad", "bent", "sparse", "pot", "automatic"])
def test_symmetrize_and_report_give_the_same_figures_for_the_same_files(tmp_path, cow, case, capsys):
    """One measurement: the report reads the pairs solved from the output (the landmark pairs' attribute, or the
    automatic pairs' twins) and measures against their plane, as the filter did."""
    points, faces, left, right, midline = {"cad": lambda: torus(), "bent": lambda: bent(cow, 100),
                                           "sparse": lambda: bent(cow, 3), "pot": lambda: (*pot(0.6), []),
                                           "automatic": lambda: bent(cow, 100)}[case]()
    mesh, landmarks = _files(tmp_path, points, faces, left, right, midline)
    output, filter_json, report_json = tmp_path / "out.ply", tmp_path / "filter.json", tmp_path / "report.json"
    pairs = ["--pairs", "auto"] if case == "automatic" else ["-l", str(landmarks)] + (["--midline"] if len(midline) else [])
    assert main(["symmetrize", str(mesh), *pairs, "-o", str(output), "--report", str(filter_json)]) == 0
    printed = capsys.readouterr().out
    assert "mirror asymmetry of the diagonal, before -> after: median " in printed and "p90 " in printed
    assert main(["report", str(mesh), str(output), "--json", str(report_json)]) == 0
    by_filter, by_report = json.loads(filter_json.read_text()), json.loads(report_json.read_text())
    floor = 1e-9 * by_filter["diagonal"]  # an exactly symmetric output: both figures are rounding noise
    for side in ("mirror_asymmetry_before", "mirror_asymmetry_after"):
        assert by_report[side]["plane_from"] == by_filter[side]["plane_from"] == "the solved pairs"
        for key in KEYS:
            assert by_report[side][key] == pytest.approx(by_filter[side][key], rel=0.01, abs=floor), (side, key)
            assert by_report[side][key + "_relative"] == pytest.approx(by_report[side][key] / by_filter["diagonal"])
    # The same verdicts (the filter's name the landmark fix, the report's cannot: it has no landmarks).
    kinds = [[w.split(":")[0] for w in data["warnings"] if not w.startswith("the mesh moved")]
             for data in (by_filter, by_report)]
    assert kinds[0] == kinds[1] == {"cad": ["nothing to restore"]}.get(case, kinds[0])


def test_an_input_already_symmetric_comes_back_unchanged_and_says_so(tmp_path, capsys):
    points, faces, left, right, _ = torus()
    mesh, landmarks = _files(tmp_path, points, faces, left, right)
    output, report = tmp_path / "out.ply", tmp_path / "out.json"
    assert main(["symmetrize", str(mesh), "-l", str(landmarks), "-o", str(output), "--checks", "full",
                 "--report", str(report)]) == 0
    err = capsys.readouterr().err
    assert "warning: nothing to restore: the input is already mirror-symmetric within " in err
    assert "of its diagonal (99th percentile); the output is the input, unchanged." in err
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(output))
    ms.load_new_mesh(str(mesh))
    np.testing.assert_array_equal(ms.mesh(0).vertex_matrix(), ms.mesh(1).vertex_matrix())  # bit for bit
    written = json.loads(report.read_text())
    assert written["nothing_to_restore"] is True and written["hausdorff_input_output"]["max"] == 0.0
    assert written["mirror_asymmetry_after"] == written["mirror_asymmetry_before"]
    assert main(["report", str(mesh), str(output)]) == 0
    assert "warning: nothing to restore" in capsys.readouterr().err


def _scan(amplitude: float, bend: float):
    """A bumpy sphere with one mirror plane and 48 landmark pairs, each vertex moved at random by ``amplitude`` of
    the diagonal (a scan's noise, which no smooth warp removes), then bent ``bend`` rad (which a warp removes)."""
    points, faces = symmetric_blob(4)
    left = np.flatnonzero(points[:, 0] > 0.1)[::25]
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    noisy = points + amplitude * diagonal * np.random.default_rng(3).normal(size=points.shape) / np.sqrt(3)
    return meshset_with_pairs(synthetic.bend(noisy, bend) if bend else noisy, faces, left, twins(points)[left])


def test_an_input_symmetric_within_a_scans_noise_comes_back_unchanged_unless_symmetrizing_helps(tmp_path):
    from filter_symblend import save_filter_script
    from filter_symblend.meshlab.filter_script import read_filter_script
    ms = _scan(2e-4, 0.0)
    report = ms.generate_symmetrized_mesh()
    save_filter_script(ms, tmp_path / "pipeline.mlx")  # the layer built again is still one call of the filter
    assert [node.is_symblend for node in read_filter_script(tmp_path / "pipeline.mlx")] == [True]
    before = report["mirror_asymmetry_before"]
    assert 1e-4 < before["p99_relative"] < 1e-3 and report["symmetrized_asymmetry"]["p90"] > 0.95 * before["p90"]
    assert report["nothing_to_restore"] is True
    assert report["warnings"][0].startswith("nothing to restore: the input is already mirror-symmetric within ")
    assert ", a scan's noise, and symmetrizing does not make it more so (90th percentile " in report["warnings"][0]
    np.testing.assert_array_equal(ms.current_mesh().vertex_matrix(), ms.mesh(report["input_mesh_id"]).vertex_matrix())
    bent = _scan(2e-4, 0.01)  # a small bend the warp does remove: the output is kept
    report = bent.generate_symmetrized_mesh()
    assert report["mirror_asymmetry_before"]["p99_relative"] < 1e-3
    assert report["mirror_asymmetry_after"]["p90"] < 0.95 * report["mirror_asymmetry_before"]["p90"]
    assert "nothing_to_restore" not in report and not report["warnings"]


def _misplaced(cow, bend, distance):
    """The cow bent ``bend`` rad, 3 landmark pairs and 4 midline landmarks, the second pair's right
    landmark on a vertex ``distance`` (fraction of the diagonal) from its true place."""
    left, right = cow.landmarks(3)
    far = np.linalg.norm(cow.points - cow.points[right[1]], axis=1)
    right[1] = np.argmin(np.abs(far - distance * cow.diagonal))
    ms = meshset_with_pairs(synthetic.bend(cow.points, bend), cow.faces, left, right)
    labels = np.zeros(len(cow.points))
    labels[np.flatnonzero(cow.partner == np.arange(len(cow.points)))[::20][:4]] = 1
    ms.current_mesh().add_vertex_custom_scalar_attribute(labels, "symblend_midline")
    return ms


def test_a_result_worse_than_its_input_says_so_with_the_fix(cow):
    report = _misplaced(cow, 0.1, 0.08).generate_symmetrized_mesh(checks="full")
    before, after = report["mirror_asymmetry_before"], report["mirror_asymmetry_after"]
    assert after["p90"] > 1.5 * before["p90"]
    assert report["warnings"] == [
        f"the output is more asymmetric than the input: 90th percentile {100 * before['p90_relative']:.3g} % -> "
        f"{100 * after['p90_relative']:.3g} % of the diagonal; with 3 landmark pairs, add dense pairs from the "
        "surface: --pairs landmarks+auto (pairs=\"landmarks+auto\" in Python)."]


def test_a_mesh_moved_far_beyond_its_asymmetry_says_so(cow):
    report = _misplaced(cow, 0.02, 0.2).generate_symmetrized_mesh(checks="full")
    moved, largest = report["hausdorff_input_output"]["max"], report["mirror_asymmetry_before"]["max"]
    assert moved > 3 * largest
    assert report["warnings"][-1] == (
        f"the mesh moved up to {moved:.4g} (two-way Hausdorff), {moved / largest:.1f}x the input's largest mirror "
        f"asymmetry ({largest:.4g}): more than symmetrizing needs; check for a landmark pair far off its place, or a "
        "wrong --mesh-frame.")


def test_a_result_that_got_better_has_no_warning(cow):
    points, faces, left, right, _ = bent(cow, 100)
    report = meshset_with_pairs(points, faces, left, right).generate_symmetrized_mesh(checks="full")
    assert report["mirror_asymmetry_after"]["p90"] < report["mirror_asymmetry_before"]["p90"] / 3
    assert report["warnings"] == []


def test_report_per_vertex_distances_and_the_distance_mesh(tmp_path, cow, capsys):
    points, faces, left, right, midline = bent(cow, 100)
    mesh, landmarks = _files(tmp_path, points, faces, left, right)
    output, numbers, distance = tmp_path / "out.ply", tmp_path / "numbers.json", tmp_path / "distance.ply"
    assert main(["symmetrize", str(mesh), "-l", str(landmarks), "-o", str(output)]) == 0
    assert main(["report", str(mesh), str(output), "--json", str(numbers), "--per-vertex",
                 "--distance-ply", str(distance)]) == 0
    data = json.loads(numbers.read_text())
    forward = np.array(data["hausdorff_per_vertex"]["before_to_after"])
    backward = np.array(data["hausdorff_per_vertex"]["after_to_before"])
    assert len(forward) == len(backward) == len(points)
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(output))
    ms.load_new_mesh(str(mesh))
    found = ms.get_hausdorff_distance(sampledmesh=0, targetmesh=1, samplevert=True, sampleface=False,
                                      maxdist=pymeshlab.PureValue(cow.diagonal))
    assert backward.max() == pytest.approx(found["max"], rel=1e-4)  # MeshLab, the other way round
    assert max(forward.max(), backward.max()) == pytest.approx(data["hausdorff_before_after"]["max"], rel=1e-6)
    written = pymeshlab.MeshSet()
    written.load_new_mesh(str(distance))
    np.testing.assert_allclose(written.current_mesh().vertex_scalar_array(), backward, atol=1e-6)


def test_the_picture_looks_along_the_mirror_plane_and_its_normal(tmp_path, cow, capsys):
    pytest.importorskip("matplotlib")
    points, faces, left, right, _ = bent(cow, 100)
    rotation, _ = np.linalg.qr(np.random.default_rng(5).normal(size=(3, 3)))
    points = points @ rotation.T  # a file whose axes are not the object's
    mesh, landmarks = _files(tmp_path, points, faces, left, right)
    output, numbers, picture = tmp_path / "out.ply", tmp_path / "numbers.json", tmp_path / "check.png"
    assert main(["symmetrize", str(mesh), "-l", str(landmarks), "-o", str(output)]) == 0
    assert main(["report", str(mesh), str(output), "--json", str(numbers), "--png", str(picture)]) == 0
    data = json.loads(numbers.read_text())
    views = dict((title, np.array(direction)) for title, direction in data["png_views"])
    normal = np.array(data["mirror_asymmetry_after"]["plane_normal"])
    assert abs(views["along the normal, one side"] @ normal) == pytest.approx(1.0, abs=1e-9)
    assert abs(views["along the plane, left | right"] @ normal) < 1e-9
    assert abs(views["along the long axis"] @ normal) < 1e-9
    # The long axis: the in-plane direction of largest spread of the output, computed here independently.
    out = pymeshlab.MeshSet()
    out.load_new_mesh(str(output))
    centred = out.current_mesh().vertex_matrix() - out.current_mesh().vertex_matrix().mean(axis=0)
    in_plane = centred - np.outer(centred @ normal, normal)
    long_axis = np.linalg.svd(in_plane, full_matrices=False)[2][0]
    assert abs(views["along the long axis"] @ long_axis) == pytest.approx(1.0, abs=1e-3)
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_body_of_revolution_is_said_to_have_several_mirror_planes():
    """A cone with scan noise (1e-3 of its diagonal): every plane through its axis mirrors it about as well, and
    the figures, measured against one of them, say so; the cow's distinct planes mirror it far worse than its own
    (test_a_result_that_got_better_has_no_warning)."""
    ms = pymeshlab.MeshSet()
    ms.create_cone(r0=1, r1=0.6, h=2, subdiv=64)
    points, faces = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
    mirror = np.argmin(np.linalg.norm(points[:, None] * [-1.0, 1.0, 1.0] - points[None], axis=2), axis=1)
    left = np.flatnonzero(points[:, 0] > 0.2)[::8]
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    noisy = points + 1e-3 * diagonal * np.random.default_rng(5).normal(size=points.shape) / np.sqrt(3)
    report = meshset_with_pairs(noisy, faces, left, mirror[left]).generate_symmetrized_mesh()
    others = report["mirror_asymmetry_before"]["other_planes"]
    assert len(others) >= 2 and all(abs(np.asarray(o["normal"]) @ [0.0, 1.0, 0.0]) < 1e-2 for o in others)  # through y
    assert report["mirror_asymmetry_before"]["plane_from"] == "the solved pairs"
    assert any(w.startswith(f"the input has {len(others)} other mirror plane(s) that mirror most of it as well as the "
                            "one measured, or better") and w.endswith("the before/after figures use the plane of the "
                            "pairs solved: check in the picture (symblend report --png) that they are on the symmetry "
                            "you mean to restore.") for w in report["warnings"])


def pot(bend: float):
    """A body of revolution about y (radius 0.8 + 0.4 sin, widest at y = 4/3) with a handle (a torus) at +z and a
    spout (a cone) at -z, 7 % of the vertices, mirror-symmetric across x = 0 only, bent ``bend`` rad along y toward
    x (its body keeps the plane z = 0, which mirrors the handle onto the spout's side), moved rigidly; with 40
    ground-truth landmark pairs. (points, faces, left, right)"""
    n, rings = 96, 64
    theta, height = 2 * np.pi * np.arange(n) / n, np.linspace(0.0, 2.0, rings)
    radius = 0.8 + 0.4 * np.sin(0.375 * np.pi * height)
    body = np.stack([np.outer(radius, np.sin(theta)), np.repeat(height[:, None], n, 1),
                     np.outer(radius, np.cos(theta))], -1).reshape(-1, 3)
    quad = np.array([[(i * n + j, i * n + (j + 1) % n, (i + 1) * n + (j + 1) % n, (i + 1) * n + j)
                      for j in range(n)] for i in range(rings - 1)]).reshape(-1, 4)
    ms = pymeshlab.MeshSet()
    ms.create_torus(hradius=0.5, vradius=0.12, hsubdiv=32, vsubdiv=12)  # a ring in the x-y plane
    handle = (ms.current_mesh().vertex_matrix()[:, [2, 1, 0]] + [0.0, 1.2, 1.55], ms.current_mesh().face_matrix()[:, [0, 2, 1]])
    ms.create_cone(r0=0.25, r1=0.08, h=1.0, subdiv=32)  # along y
    tilt = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(0.9), np.sin(0.9)], [0.0, -np.sin(0.9), np.cos(0.9)]])
    spout = (ms.current_mesh().vertex_matrix() @ tilt.T + [0.0, 0.7, -1.2], ms.current_mesh().face_matrix())
    parts = [(body, np.vstack([quad[:, [0, 1, 2]], quad[:, [0, 2, 3]]])), handle, spout]
    starts = np.cumsum([0] + [len(points) for points, _ in parts[:-1]])
    points = np.vstack([points for points, _ in parts])
    faces = np.vstack([faces + start for (_, faces), start in zip(parts, starts)])
    offset, partner = synthetic.mirror_partners(points)
    assert offset == pytest.approx(0.0, abs=1e-12) and (partner >= 0).all()  # exactly symmetric across x = 0
    left, right = synthetic.farthest_point_pairs(points, offset, partner, 40)
    return synthetic.random_rigid(synthetic.bend(points, bend, along=1, toward=0), 3), faces, left, right


def test_a_bent_pot_is_measured_against_the_plane_of_its_pairs():
    """Its body mirrors about the plane z = 0 exactly, bent or not; the pairs restore x = 0, bent apart. The
    figures measure the symmetry the pairs restored, and name the body's plane as one that mirrors most of it."""
    points, faces, left, right = pot(0.6)
    report = meshset_with_pairs(points, faces, left, right).generate_symmetrized_mesh()
    before, after = report["mirror_asymmetry_before"], report["mirror_asymmetry_after"]
    moved = synthetic.random_rigid(np.vstack([np.zeros(3), np.eye(3)]), 3)
    truth = moved[1:] - moved[0]  # the axes x, y, z, moved as the pot was
    pairs_normal = fit_mirror_plane(points[left], points[right]).normal
    assert abs(np.asarray(before["plane_normal"]) @ pairs_normal) > np.cos(np.radians(5))
    assert abs(np.asarray(before["plane_normal"]) @ truth[0]) > np.cos(np.radians(10))  # near x = 0 moved, bent
    assert before["p90_relative"] > 5e-3 and after["p90_relative"] < 0.2 * before["p90_relative"]  # bend, restored
    assert before["plane_from"] == after["plane_from"] == "the solved pairs"
    body = [o for o in before["other_planes"] if abs(np.asarray(o["normal"]) @ truth[2]) > np.cos(np.radians(5))]
    assert body and body[0]["p90_relative"] < 0.2 * before["p90_relative"]  # the body's plane z = 0, named
    assert not any(w.startswith("the output is more asymmetric") for w in report["warnings"])
    assert any(w.startswith("the input has") for w in report["warnings"])


def test_report_without_the_pairs_measures_each_file_against_its_best_plane(tmp_path, capsys):
    """An OBJ output keeps no attribute: `symblend report` cannot know the pairs solved and says which plane it
    used; on the bent pot that is its body's, which mirrors all but the handle and spout."""
    points, faces, left, right = pot(0.6)
    mesh, landmarks = _files(tmp_path, points, faces, left, right)
    output, numbers = tmp_path / "out.obj", tmp_path / "numbers.json"
    assert main(["symmetrize", str(mesh), "-l", str(landmarks), "-o", str(output)]) == 0
    assert main(["report", str(mesh), str(output), "--json", str(numbers)]) == 0
    data = json.loads(numbers.read_text())
    moved = synthetic.random_rigid(np.vstack([np.zeros(3), np.eye(3)]), 3)
    assert data["mirror_asymmetry_before"]["plane_from"] == data["mirror_asymmetry_after"]["plane_from"] == \
        "the input's best plane"
    assert abs(np.asarray(data["mirror_asymmetry_before"]["plane_normal"]) @ (moved[3] - moved[0])) > np.cos(np.radians(5))


def test_automatic_pairs_that_leave_the_output_asymmetric_say_so(remeshed_cow):
    """The remeshed cow (no vertex has an exact twin) bent 1.2 and 0.2 rad: its automatic pairs restore it
    (ground truth: at most 0.3x the input's symmetry error; measured 0.21x and 0.11x) and leave the output's
    90th percentile under LEFT_ASYMMETRIC and its 99th under PART_LEFT_ASYMMETRIC (measured 1.64 % bent 1.2 rad),
    so nothing is said. (Before the checks' and the first map's planes were reached by accelerated ICP, bent 1.2
    rad came back at 0.34x with p90 0.67 % and was warned about.) An output whose p90 is above it, as the failed
    restorations of the benchmark leave it (test_a_posed_dog_whose_automatic_pairs_fail_is_not_silent, on the
    BCICP dataset), or whose p99 is (a part left: test_a_part_whose_twin_is_broken_off_is_said), is said with
    the fix."""
    from filter_symblend.measures.verdict import result_warnings
    for angle in (1.2, 0.2):
        deformed = synthetic.random_rigid(synthetic.bend(remeshed_cow.points, angle), 7)
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(deformed, remeshed_cow.faces))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the map's own doubts, if any, are not what is tested here
            report = ms.generate_symmetrized_mesh(pairs="auto", mode="affine")
        output = ms.current_mesh().vertex_matrix()
        assert remeshed_cow.symmetry_error(output) < 0.3 * remeshed_cow.symmetry_error(deformed)
        assert report["mirror_asymmetry_after"]["p90_relative"] < LEFT_ASYMMETRIC
        assert report["mirror_asymmetry_after"]["p99_relative"] < PART_LEFT_ASYMMETRIC
        assert not any(w.startswith("the automatic pairs left the output asymmetric") for w in report["warnings"])
    before = report["mirror_asymmetry_before"]
    after = dict(report["mirror_asymmetry_after"], p90_relative=1.5 * LEFT_ASYMMETRIC)
    message, = result_warnings(before, after, automatic=True)
    assert message.startswith("the automatic pairs left the output asymmetric: 90th percentile 0.525 %, 99th ")
    assert message.endswith("then symmetrize with -l pairs.pp.")
    assert not result_warnings(before, after, landmark_pairs=100)  # landmark pairs alone
    part = dict(report["mirror_asymmetry_after"], p99_relative=1.5 * PART_LEFT_ASYMMETRIC)  # the 90th as measured
    message, = result_warnings(before, part, automatic=True)
    assert ", 99th 3 % of the diagonal" in message and "missing_region='selection'" in message
    assert not result_warnings(before, dict(part, p99_relative=0.99 * PART_LEFT_ASYMMETRIC), automatic=True)


def test_a_part_whose_twin_is_broken_off_is_said(cow):
    """The cow with a part of one side broken off (the vertices within 12 % of the diagonal of that side's
    farthest vertex along -z), bent 0.3 rad: the automatic pairs restore what has both sides, but the intact twin
    of the broken part has nothing to mirror, so the output's 99th percentile stays far above PART_LEFT_ASYMMETRIC
    while its 90th is nil (measured 4.3 % and 1e-14 %): the warning says so, with the fix. The part far from its
    mirror image is the one whose twin is gone (measured independently: distances to the reflected output). Closing
    the hole as the warning says and filling it from its mirror (missing_region='selection') leaves nothing to say
    (99th percentile measured 1.0 %)."""
    from filter_symblend.core.mirror_fill import distances_to_surface
    points, faces = cow.points, cow.faces
    diagonal = np.linalg.norm(np.ptp(points, axis=0))
    right = np.flatnonzero(points[:, 0] < cow.offset - 0.05 * diagonal)
    tip = right[np.argmin(points[right, 2])]
    keep = np.linalg.norm(points - points[tip], axis=1) > 0.12 * diagonal
    cut, cut_faces, kept = synthetic.cropped(points, faces, keep)
    bent = synthetic.bend(cut, 0.3)
    index = np.full(len(points), -1)
    index[kept] = np.arange(len(kept))
    twin = np.maximum(cow.partner, 0)
    alone = index[np.flatnonzero(keep & (cow.partner >= 0) & ~keep[twin])]  # the intact twins of the broken part
    said = {}
    for fill in (False, True):
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(bent, cut_faces))
        if fill:
            ms.meshing_close_holes(maxholesize=1000, newfaceselected=True, refinehole=True)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the map's own doubts, if any, are not what is tested here
            report = ms.generate_symmetrized_mesh(pairs="auto", mode="affine",
                                                  missing_region="selection" if fill else "none")
        after = report["mirror_asymmetry_after"]
        said[fill] = [w for w in report["warnings"] if w.startswith("the automatic pairs left the output asymmetric")]
        print("filled" if fill else "broken", after["p90_relative"], after["p99_relative"], said[fill])
        if not fill:
            output = ms.current_mesh().vertex_matrix()
            mirrored = reflection_across_plane(output, np.asarray(report["plane_normal"]), report["plane_offset"])
            far = np.flatnonzero(distances_to_surface(mirrored, cut_faces, output) > PART_LEFT_ASYMMETRIC * diagonal)
            assert after["p90_relative"] < LEFT_ASYMMETRIC < PART_LEFT_ASYMMETRIC < after["p99_relative"]
            assert len(far) > 10 and np.isin(far, alone).mean() > 0.9
        else:
            assert after["p99_relative"] < PART_LEFT_ASYMMETRIC
    message, = said[False]
    assert re.search(r"99th [0-9.]+ % of the diagonal", message) and "a part has no twin" in message
    assert "meshing_close_holes(newfaceselected=True, refinehole=True)" in message
    assert said[True] == []


@pytest.mark.corpus
def test_a_posed_dog_whose_automatic_pairs_fail_is_not_silent(bcicp):
    """On public ground truth (the BCICP dataset, read in place; skipped without it): TOSCA's dog10, which no map
    of space mirrors (its automatic output keeps 2.5x the error of 100 ground-truth landmark pairs), is warned
    that it rests on the intrinsic mirror, and that little of its map is confident or that its output is left
    asymmetric (its confident share sits at the 80 % bound: 80 % before the torn pieces were mended, 81 % after,
    the second warning naming the same fix); dog7, whose hind leg the maps
    of space once left unrestored (4.5x), is now followed (0.8x: the intrinsic mirror chosen among ten) and, like
    dog3 (1.1x), not warned at all. Silent only where the result is about as good as the landmarks'."""
    from benchmarks.mirror_maps import landmark_output, symmetry_error
    for name, warned in (("dog10", True), ("dog7", False), ("dog3", False)):
        points, faces, a, b = bcicp.shape("TOSCA", name)
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(points, faces))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            report = ms.generate_symmetrized_mesh(pairs="auto", mode="articulated")
            landmarks = symmetry_error(landmark_output(points, a, b, "articulated"), a, b)
        ratio = symmetry_error(ms.current_mesh().vertex_matrix(), a, b) / landmarks
        said = report["warnings"] + report["auto_pairs"].get("warnings", [])  # the checks', the pairs'
        print(name, f"auto / 100 landmarks {ratio:.2f}", said)
        if warned:
            assert ratio > 1.5
            assert any(w.startswith("no map of space mirrors enough of this shape; it was paired by its intrinsic "
                                    "mirror") for w in said)
            assert any(re.match(r"only \d+% of the surface has a confident mirror twin", w)
                       or w.startswith("the automatic pairs left the output asymmetric") for w in said)
        else:
            assert ratio < 1.5 and said == []

"""Numbered landmarks (no side in their names) paired by geometry, against the mesh's known mirror."""

import json

import numpy as np
import pymeshlab
import pytest

from filter_symblend import LandmarkError
from filter_symblend.commands.main import main
from filter_symblend.core.geometry import reflection_across_plane
from filter_symblend.core.mesh_quantities import farthest_point_order
from filter_symblend.landmarks.formats import Landmark, LandmarkSet, write_landmarks
from filter_symblend.landmarks.from_file import pairs_from_landmark_file
from filter_symblend.landmarks.geometric_pairing import pair_by_geometry
from filter_symblend.testing import synthetic

PAIRS, MIDLINE = 14, 12


def _pose(points, seed):
    """A rigid motion of ``points``: no axis of the file is the mirror's."""
    rng = np.random.default_rng(seed)
    rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return points @ rotation.T + rng.normal(size=3)


@pytest.fixture(scope="module")
def numbered(cow):
    """The cow in a random pose with 14 landmark pairs and 12 midline landmarks, numbered 1..40 in a
    shuffled order, each 0.3-0.6 % of the diagonal off the surface: (points, faces, landmarks, the true
    pairs as name sets, the true midline names)."""
    points = _pose(cow.points, 3)
    left, right = synthetic.farthest_point_pairs(cow.points, cow.offset, cow.partner, PAIRS)
    on_plane = np.flatnonzero(cow.partner == np.arange(len(cow.points)))
    midline = on_plane[farthest_point_order(cow.points[on_plane], MIDLINE, start=0)]
    vertices = np.concatenate([left, right, midline])
    rng = np.random.default_rng(7)
    directions = rng.normal(size=(len(vertices), 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    positions = points[vertices] + directions * rng.uniform(0.003, 0.006, len(vertices))[:, None] * cow.diagonal
    order = rng.permutation(len(vertices))
    name = {slot: f"skull-{number}" for number, slot in enumerate(order, start=1)}
    landmarks = LandmarkSet([Landmark(name[slot], tuple(positions[slot])) for slot in order])
    pairs = {frozenset((name[k], name[k + PAIRS])) for k in range(PAIRS)}
    return points, cow.faces, landmarks, pairs, {name[2 * PAIRS + k] for k in range(MIDLINE)}


def test_numbered_landmarks_pair_exactly_as_the_mirror_with_and_without_the_surface(numbered):
    points, _, landmarks, pairs, midline = numbered
    positions = np.array([lm.position for lm in landmarks.landmarks])
    names = landmarks.names()
    for surface in (points, None):
        found = pair_by_geometry(positions, surface)
        assert {frozenset((names[a], names[b])) for a, b in found.pairs} == pairs
        assert {names[i] for i in found.midline} == midline and found.ambiguous == []
        first, second = np.array(found.pairs).T
        assert np.all(positions[first] @ found.plane.normal >= positions[second] @ found.plane.normal)


def test_a_landmark_file_with_numbered_landmarks_needs_no_pair_table(tmp_path, numbered):
    points, faces, landmarks, pairs, midline = numbered
    path = tmp_path / "template.mrk.json"
    write_landmarks(path, LandmarkSet(landmarks.landmarks, None))
    snapped = pairs_from_landmark_file(points, faces, path)
    assert snapped.pairing == "geometry"
    assert {frozenset(p) for p in snapped.pair_names} == pairs and set(snapped.midline_names) == midline


def test_an_ambiguous_landmark_is_refused_by_name_and_check_writes_the_pairs_found(tmp_path, numbered, capsys):
    points, faces, landmarks, pairs, _ = numbered
    a, b = sorted(min(pairs, key=sorted))
    position = {lm.name: np.array(lm.position) for lm in landmarks.landmarks}
    plane = pair_by_geometry(np.array(list(position.values())), points).plane
    image = reflection_across_plane(position[a][None], *plane)[0]
    twin = 2 * image - position[b]  # a's mirror image lands halfway between b and this one
    path = tmp_path / "template.mrk.json"
    write_landmarks(path, LandmarkSet(landmarks.landmarks + [Landmark("skull-99", tuple(twin))], None))
    written = path.read_bytes()
    with pytest.raises(LandmarkError) as error:
        pairs_from_landmark_file(points, faces, path)
    message = str(error.value)
    assert message.startswith(f"{path}: the names carry no side, and by geometry ")
    assert f"'{a}'" in message and "'skull-99'" in message
    assert message.endswith("Give a pair table (--pair-table); `symblend landmarks check` writes the pairs found "
                            "as one, to complete.")
    assert path.read_bytes() == written
    mesh = _mesh_file(tmp_path, points, faces)
    assert main(["landmarks", "check", str(mesh), "-l", str(path)]) == 1
    table = tmp_path / "template.pairs.csv"
    assert (f"The {len(error.value.pair_names)} pairs found are in {table}: add the ambiguous ones, then use "
            f"--pair-table {table} --midline.") in capsys.readouterr().err
    found = {frozenset(row.split(",")) for row in table.read_text().splitlines()[1:]}
    assert found and found <= pairs and frozenset((a, b)) not in found


def test_too_few_numbered_landmarks_are_refused(tmp_path, numbered):
    points, faces, landmarks, _, _ = numbered
    path = tmp_path / "two.csv"
    write_landmarks(path, LandmarkSet(landmarks.landmarks[:2]))
    with pytest.raises(LandmarkError, match=r"two.csv: the landmark names carry no side \(L_/R_ prefix or _left/_right "
                                            r"suffix\) and 2 placed landmarks are too few to pair by their mirror "
                                            r"symmetry; give a pair table \(--pair-table\)"):
        pairs_from_landmark_file(points, faces, path)


def _mesh_file(tmp_path, points, faces):
    path = tmp_path / "skull.ply"
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(points, faces))
    ms.save_current_mesh(str(path))
    return path


def test_symmetrize_without_a_table_writes_the_table_and_matches_the_run_with_it(tmp_path, numbered, capsys):
    points, faces, landmarks, pairs, midline = numbered
    mesh = _mesh_file(tmp_path, points, faces)
    marks = tmp_path / "template.csv"
    write_landmarks(marks, landmarks)
    inputs = {p: p.read_bytes() for p in (mesh, marks)}
    out = tmp_path / "out"
    out.mkdir()
    assert main(["symmetrize", str(mesh), "-l", str(marks), "-o", str(out / "a.ply"), "--report",
                 str(out / "a.json")]) == 0
    err = capsys.readouterr().err
    table = out / "template.pairs.csv"
    assert f"{marks}: no name carries a side; paired by geometry: {PAIRS} pairs (" in err
    assert f"pair table: {table} (check or edit it, then use --pair-table {table} --midline)" in err
    report = json.loads((out / "a.json").read_text())["landmarks"]
    assert report["pairing"] == "geometry" and report["pair_table_written"] == str(table)
    assert {frozenset(p) for p in report["pairs"]} == pairs and set(report["midline"]) == midline
    assert main(["symmetrize", str(mesh), "-l", str(marks), "--pair-table", str(table), "--midline",
                 "-o", str(out / "b.ply")]) == 0
    a, b = pymeshlab.MeshSet(), pymeshlab.MeshSet()
    a.load_new_mesh(str(out / "a.ply"))
    b.load_new_mesh(str(out / "b.ply"))
    np.testing.assert_array_equal(a.current_mesh().vertex_matrix(), b.current_mesh().vertex_matrix())
    assert all(p.read_bytes() == text for p, text in inputs.items())


def test_landmarks_check_prints_the_pairing_and_never_overwrites_a_table(tmp_path, numbered, capsys):
    points, faces, landmarks, pairs, _ = numbered
    mesh = _mesh_file(tmp_path, points, faces)
    marks = tmp_path / "template.fcsv"
    write_landmarks(marks, LandmarkSet(landmarks.landmarks, None))
    assert main(["landmarks", "check", str(mesh), "-l", str(marks)]) == 0
    captured = capsys.readouterr()
    assert f"paired by geometry: {PAIRS} pairs, {MIDLINE} midline" in captured.out
    table = tmp_path / "template.pairs.csv"
    rows = table.read_text().splitlines()
    assert rows[0].startswith("left,right,midline (use --midline): skull-")
    assert {frozenset(row.split(",")) for row in rows[1:]} == pairs
    table.write_text("edited by hand\n")
    assert main(["landmarks", "check", str(mesh), "-l", str(marks)]) == 0
    assert f"pair table not written: {table} exists (choose a file with --save-pair-table)" in capsys.readouterr().err
    assert table.read_text() == "edited by hand\n"
    chosen = tmp_path / "mine.csv"
    assert main(["landmarks", "check", str(mesh), "-l", str(marks), "--save-pair-table", str(chosen)]) == 0
    assert chosen.read_text().splitlines()[1:] and table.read_text() == "edited by hand\n"


def test_a_pair_table_output_in_a_missing_folder_is_refused_before_any_work(tmp_path, numbered, capsys):
    points, faces, landmarks, _, _ = numbered
    mesh = _mesh_file(tmp_path, points, faces)
    marks = tmp_path / "template.csv"
    write_landmarks(marks, landmarks)
    target = tmp_path / "absent" / "pairs.csv"
    assert main(["symmetrize", str(mesh), "-l", str(marks), "-o", str(tmp_path / "out.ply"),
                 "--save-pair-table", str(target)]) == 1
    assert f"{target}: the folder {target.parent} does not exist; create it first." in capsys.readouterr().err
    assert not (tmp_path / "out.ply").exists()


def test_two_landmarks_in_one_place_are_named_ambiguous(tmp_path, numbered):
    points, faces, landmarks, _, _ = numbered
    copy = Landmark("skull-98", landmarks.landmarks[0].position)
    path = tmp_path / "doubled.csv"
    write_landmarks(path, LandmarkSet(landmarks.landmarks + [copy]))
    with pytest.raises(LandmarkError) as error:
        pairs_from_landmark_file(points, faces, path)
    assert f"'{landmarks.landmarks[0].name}'" in str(error.value) and "'skull-98'" in str(error.value)

"""The symblend command, through main([...]) and once as a real process."""

import json
import pathlib
import re
import subprocess
import sys

import numpy as np
import pymeshlab
import pytest

from filter_symblend import DISPLAY_NAME, PARAMETERS
from filter_symblend.commands.main import main
from filter_symblend.testing import synthetic
from conftest import meshlab_mirror_distance
from filter_symblend.landmarks.formats import Landmark, LandmarkSet, read_landmarks, write_landmarks


@pytest.fixture()
def bent_cow_files(tmp_path, cow):
    """A bent cow as OBJ and its landmarks, named L_k / R_k, as a MeshLab .pp file."""
    left, right = cow.landmarks(80)
    deformed = synthetic.bend(cow.points, 1.0)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=deformed, face_matrix=cow.faces))
    mesh_path = tmp_path / "cow_bent.obj"
    ms.save_current_mesh(str(mesh_path))
    landmarks = LandmarkSet([Landmark(f"{side}_{k}", tuple(deformed[v]))
                             for k, (a, b) in enumerate(zip(left, right)) for side, v in (("L", a), ("R", b))])
    landmark_path = tmp_path / "cow_bent_picked_points.pp"
    write_landmarks(landmark_path, landmarks)
    return mesh_path, landmark_path, deformed, left, right


def test_symmetrize_writes_the_mesh_and_the_report(tmp_path, bent_cow_files, capsys):
    mesh_path, landmark_path, deformed, left, right = bent_cow_files
    output, report = tmp_path / "out.ply", tmp_path / "report.json"
    assert main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "-o", str(output),
                 "--report", str(report), "--mode", "articulated", "--phi-width", "6",
                 "--checks", "full"]) == 0
    assert "80 landmark pairs, mode articulated" in capsys.readouterr().out
    data = json.loads(report.read_text())
    assert data["mode"] == "articulated" and data["phi_width"] == 6 and data["pair_count"] == 80
    # No point of the output is farther from the input than the farthest moved vertex.
    assert 0 < data["hausdorff_input_output"]["max"] <= data["vertex_displacement"]["max"] + 1e-9
    assert data["landmarks"]["snap_distance_max"] < 1e-5
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(output))
    written = ms.current_mesh()
    from filter_symblend import symmetrize

    expected = symmetrize(deformed, left, right, mode="articulated", phi_width=6)
    np.testing.assert_allclose(written.vertex_matrix(), expected.points, atol=1e-9)
    np.testing.assert_allclose(written.vertex_scalar_array(), expected.asymmetry, atol=1e-9)


def test_errors_are_one_line_and_write_nothing(tmp_path, bent_cow_files, capsys):
    mesh_path, landmark_path, *_ = bent_cow_files
    landmarks = read_landmarks(landmark_path)
    landmarks.landmarks.append(Landmark("nasion", landmarks.landmarks[0].position))
    broken = tmp_path / "broken.pp"
    write_landmarks(broken, landmarks)
    before = landmark_path.read_bytes()
    output = tmp_path / "out.ply"
    assert main(["symmetrize", str(mesh_path), "-l", str(broken), "-o", str(output)]) == 1
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "symblend: error:" in error and "'nasion'" in error
    assert not output.exists() and not list(tmp_path.glob(".*partial*"))
    assert landmark_path.read_bytes() == before
    assert main(["symmetrize", str(tmp_path / "none.obj"), "-l", str(broken), "-o", str(output)]) == 1
    assert "none.obj: no such mesh file" in capsys.readouterr().err
    assert main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "-o", str(output), "--alpha", "0"]) == 1
    assert "`alpha` must be in (0, 100]" in capsys.readouterr().err


def test_check_and_convert(tmp_path, bent_cow_files, capsys):
    mesh_path, landmark_path, *_ = bent_cow_files
    assert main(["landmarks", "check", str(mesh_path), "-l", str(landmark_path)]) == 0
    out = capsys.readouterr().out
    assert "80 pairs" in out and "L_0 -> vertex" in out and "ok: the pairs can be symmetrized" in out
    converted = tmp_path / "points.fcsv"
    assert main(["landmarks", "convert", str(landmark_path), str(converted)]) == 0
    assert read_landmarks(converted).names() == read_landmarks(landmark_path).names()


def test_pair_table_option(tmp_path, bent_cow_files, capsys):
    mesh_path, landmark_path, *_ = bent_cow_files
    landmarks = read_landmarks(landmark_path)
    renamed = LandmarkSet([Landmark(f"p{i}", lm.position) for i, lm in enumerate(landmarks.landmarks, 1)])
    write_landmarks(tmp_path / "numbered.csv", renamed)
    (tmp_path / "pairs.csv").write_text("\n".join(f"{2 * k + 1},{2 * k + 2}" for k in range(80)))
    assert main(["landmarks", "check", str(mesh_path), "-l", str(tmp_path / "numbered.csv"),
                 "--pair-table", str(tmp_path / "pairs.csv")]) == 0
    assert "80 pairs" in capsys.readouterr().out


def test_help_lists_every_parameter_with_its_choices_default_and_unit(capsys):
    with pytest.raises(SystemExit) as exit:
        main(["symmetrize", "--help"])
    assert exit.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    for p in PARAMETERS:
        option = f"--{p.name.replace('_', '-')}"
        shown = f"{option} {{{','.join(p.choices)}}}" if p.kind == "enum" else option
        assert shown in text and f"default {p.default}" in text and p.unit in text
    assert "--mode {standard,affine,articulated}" in text and "--pairs {landmarks,auto,landmarks+auto}" in text
    assert len(text) < 6000  # the long explanations are in the docs


def test_version(capsys):
    with pytest.raises(SystemExit) as exit:
        main(["--version"])
    assert exit.value.code == 0 and capsys.readouterr().out.startswith("symblend (filter-symblend) ")


def test_real_process(tmp_path, bent_cow_files):
    mesh_path, landmark_path, *_ = bent_cow_files
    output = tmp_path / "out.ply"
    result = subprocess.run([sys.executable, "-m", "filter_symblend.commands", "symmetrize", str(mesh_path),
                             "-l", str(landmark_path), "-o", str(output)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert output.exists() and "landmark asymmetry" in result.stdout


def test_ply_output_round_trips_its_attributes_and_symmetrizes_again(tmp_path, bent_cow_files):
    from filter_symblend.meshlab.ply_attributes import load_mesh_with_attributes, read_ply_vertex_properties

    mesh_path, landmark_path, *_ = bent_cow_files
    output = tmp_path / "out.ply"
    assert main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "-o", str(output)]) == 0
    properties = read_ply_vertex_properties(output)
    np.testing.assert_allclose(properties["symblend_asymmetry"], properties["quality"])
    ms = pymeshlab.MeshSet()
    assert sorted(load_mesh_with_attributes(ms, output)) == ["symblend_asymmetry", "symblend_pair"]
    labels = ms.current_mesh().vertex_custom_scalar_attribute_array("symblend_pair")
    assert labels.max() == 80 and labels.min() == -80
    before = ms.current_mesh().vertex_matrix().copy()
    ms.generate_symmetrized_mesh()
    assert np.abs(ms.current_mesh().vertex_matrix() - before).max() < 1e-8  # already symmetric


def test_the_landmark_file_alone_gives_the_pairs_whatever_attributes_the_mesh_file_carries(tmp_path, bent_cow_files):
    """The command hands the file's pairs to the filter as pairs, not through the mesh's attributes: a mesh
    file that carries a stale weight attribute (0 at two landmarks, as an earlier run with ``--missing``
    leaves it) changes nothing, and the output carries the file's pairs alone."""
    from filter_symblend.commands.shared.mesh_io import save_mesh
    from filter_symblend.meshlab.ply_attributes import load_mesh_with_attributes

    mesh_path, landmark_path, deformed, left, right = bent_cow_files
    clean, stale = tmp_path / "clean.json", tmp_path / "stale.json"
    assert main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "-o", str(tmp_path / "clean.ply"),
                 "--report", str(clean)]) == 0
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(mesh_path))
    weights = np.ones(len(deformed))
    weights[[left[2], right[3]]] = 0.0
    ms.current_mesh().add_vertex_custom_scalar_attribute(weights, "symblend_weight")
    save_mesh(ms, tmp_path / "stale.ply")
    output = tmp_path / "out.ply"
    assert main(["symmetrize", str(tmp_path / "stale.ply"), "-l", str(landmark_path), "-o", str(output),
                 "--report", str(stale)]) == 0
    ms = pymeshlab.MeshSet()
    assert sorted(load_mesh_with_attributes(ms, output)) == ["symblend_asymmetry", "symblend_pair"]
    before, after = (json.loads(path.read_text()) for path in (clean, stale))
    assert after["vertex_displacement"] == pytest.approx(before["vertex_displacement"], rel=1e-9)


def test_ascii_ply_properties(tmp_path):
    from filter_symblend.meshlab.ply_attributes import read_ply_vertex_properties

    path = tmp_path / "a.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                    "property float z\nproperty double symblend_pair\nelement face 0\n"
                    "property list uchar int vertex_indices\nend_header\n0 0 0 1\n1 0 0 -1\n")
    assert read_ply_vertex_properties(path)["symblend_pair"].tolist() == [1.0, -1.0]
    path.write_text("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty list uchar double twin\n"
                    "property float q\nend_header\n0 3 1 2 3 7\n1 3 4 5 6 8\n")
    properties = read_ply_vertex_properties(path)
    assert properties["twin"].tolist() == [[1, 2, 3], [4, 5, 6]] and properties["q"].tolist() == [7, 8]


def test_midline_and_missing_options(tmp_path, bent_cow_files, cow):
    from test_ground_truth import midline_vertices

    mesh_path, landmark_path, deformed, left, right = bent_cow_files
    landmarks = read_landmarks(landmark_path)
    midline = midline_vertices(cow, 6)
    landmarks.landmarks += [Landmark(f"mid_{j}", tuple(deformed[v])) for j, v in enumerate(midline)]
    with_midline = tmp_path / "with_midline.pp"
    write_landmarks(with_midline, landmarks)
    output, report = tmp_path / "out.ply", tmp_path / "r.json"
    assert main(["symmetrize", str(mesh_path), "-l", str(with_midline), "-o", str(output)]) == 1
    assert main(["symmetrize", str(mesh_path), "-l", str(with_midline), "-o", str(output), "--midline",
                 "--missing", "R_3,R_4", "--report", str(report)]) == 0
    data = json.loads(report.read_text())
    assert data["midline_count"] == 6 and data["landmarks"]["missing"] == ["R_3", "R_4"]
    ms = pymeshlab.MeshSet()
    from filter_symblend.meshlab.ply_attributes import load_mesh_with_attributes

    assert "symblend_weight" in load_mesh_with_attributes(ms, output)
    out = ms.current_mesh().vertex_matrix()
    normal, offset = np.array(data["plane_normal"]), data["plane_offset"]
    assert np.abs(out[midline] @ normal - offset).max() < 1e-9


def test_unreadable_mesh_unwritable_output_and_side_words(tmp_path, bent_cow_files, capsys):
    mesh_path, landmark_path, *_ = bent_cow_files
    garbage = tmp_path / "garbage.ply"
    garbage.write_text("not a mesh")
    assert main(["symmetrize", str(garbage), "-l", str(landmark_path), "-o", str(tmp_path / "o.ply")]) == 1
    assert "garbage.ply: pymeshlab cannot read it" in capsys.readouterr().err
    assert main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "-o",
                 str(tmp_path / "no_such_dir" / "o.ply")]) == 1
    err = capsys.readouterr().err
    assert err.startswith("symblend: error:") and "no_such_dir does not exist; create it first" in err
    assert err.count("\n") == 1
    assert not (tmp_path / "no_such_dir").exists()
    assert main(["landmarks", "check", str(mesh_path), "-l", str(landmark_path), "--side-words", "left"]) == 1
    assert "--side-words 'left': give LEFT,.../RIGHT,..." in capsys.readouterr().err
    assert main(["landmarks", "check", str(mesh_path), "-l", str(landmark_path), "--side-words", "L/R"]) == 0


@pytest.mark.parametrize("header, pattern", [
    (b"solid cube\n", r"not a PLY file"),
    (b"ply\nformat ascii 1.0\nelement vertex 1\n", r"has no end_header line"),
    (b"ply\nformat ascii 1.0\nelement face 0\nelement vertex 1\nproperty float x\nend_header\n",
     r"the vertex element must come first"),
    (b"ply\nformat ascii 1.0\nelement vertex 2\nproperty list uchar int x\nend_header\n1 5 0\n2 5 6\n",
     r"the vertex property 'x' is a list of varying length; only lists of one length"),
    (b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty list uchar int x\nend_header\n"
     + bytes([1]) + (5).to_bytes(4, "little") + bytes([2]) + (5).to_bytes(4, "little") + (6).to_bytes(4, "little"),
     r"the vertex property 'x' is a list of varying length; only lists of one length"),
    (b"ply\nformat binary_middle_endian 1.0\nelement vertex 1\nproperty float x\nend_header\n",
     r"unknown PLY format 'binary_middle_endian'"),
])
def test_unreadable_ply_properties(tmp_path, header, pattern):
    from filter_symblend import SymblendError
    from filter_symblend.meshlab.ply_attributes import read_ply_vertex_properties

    path = tmp_path / "bad.ply"
    path.write_bytes(header)
    with pytest.raises(SymblendError, match=pattern):
        read_ply_vertex_properties(path)


def _damaged_obj(path: pathlib.Path, damage: str) -> pathlib.Path:
    """A small closed OBJ (a tetrahedron) with a vertex 'nan nan nan' or a face that refers to a missing vertex."""
    vertices = ["v 0 0 0", "v 1 0 0", "v 0 1 0", "v 0 0 1"]
    faces = ["f 1 3 2", "f 1 2 4", "f 2 3 4", "f 1 4 3"]
    if damage == "nan":
        vertices.insert(1, "v nan nan nan")
        faces = [" ".join(["f"] + [str(int(i) + (int(i) > 1)) for i in face.split()[1:]]) for face in faces]
    else:
        faces.append("f 1 2 99")
    path.write_text("\n".join(vertices + faces) + "\n")
    return path


def _damaged_ply(path: pathlib.Path) -> pathlib.Path:
    """An ASCII PLY tetrahedron with a fifth vertex 'nan nan nan' (pymeshlab drops it and renumbers)."""
    path.write_text("ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
                    "0 0 0\nnan nan nan\n1 0 0\n0 1 0\n0 0 1\n3 0 3 2\n3 0 2 4\n3 2 3 4\n3 0 4 3\n")
    return path


def _damaged_off(path: pathlib.Path) -> pathlib.Path:
    """An OFF tetrahedron with a fifth vertex 'nan nan nan'."""
    path.write_text("OFF\n5 4 0\n0 0 0\nnan nan nan\n1 0 0\n0 1 0\n0 0 1\n3 0 3 2\n3 0 2 4\n3 2 3 4\n3 0 4 3\n")
    return path


def _probe_arguments(tmp_path, mesh_path, landmark_path):
    """(name, arguments, the one-line error expected): bad outputs and damaged meshes, each refused before
    any computation."""
    folder = tmp_path / "missing"
    return [
        ("output is the input", ["-o", str(mesh_path)], r"cow_bent.obj: is the input file; .*--overwrite"),
        ("output is a folder", ["-o", str(tmp_path)], r"is a folder; give the output mesh a file name"),
        ("nan vertex in a PLY", ["-o", str(tmp_path / "out.ply"), "INPUT", str(_damaged_ply(tmp_path / "nan.ply"))],
         r"nan.ply: the file declares 5 vertices and 4 could be read"),
        ("nan vertex in an OFF", ["-o", str(tmp_path / "out.ply"), "INPUT", str(_damaged_off(tmp_path / "nan.off"))],
         r"nan.off: the file declares 5 vertices and 4 could be read"),
        ("no extension", ["-o", str(tmp_path / "out")], r"out: no extension; the output mesh needs one pymeshlab "
                                                          r"writes: .*\.ply"),
        ("unknown extension", ["-o", str(tmp_path / "out.xyzzy")], r"out.xyzzy: the extension '.xyzzy'"),
        ("missing folder", ["-o", str(folder / "out.ply")], r"the folder .*missing does not exist; create it first"),
        ("report in a missing folder", ["-o", str(tmp_path / "out.ply"), "--report", str(folder / "r.json")],
         r"r.json: the folder .*missing does not exist"),
        ("report over the output", ["-o", str(tmp_path / "out.ply"), "--report", str(tmp_path / "out.ply")],
         r"out.ply: given for two outputs"),
        ("nan vertex", ["-o", str(tmp_path / "out.ply"), "INPUT", str(_damaged_obj(tmp_path / "nan.obj", "nan"))],
         r"nan.obj: the file declares 5 vertices and 4 could be read .*renumbered"),
        ("missing vertex", ["-o", str(tmp_path / "out.ply"), "INPUT",
                            str(_damaged_obj(tmp_path / "hole.obj", "missing"))],
         r"hole.obj: the file declares 5 faces and only 4 could be read .*missing vertices"),
    ]


def test_bad_outputs_and_damaged_meshes_are_refused_before_any_work(tmp_path, bent_cow_files, capsys, monkeypatch):
    import hashlib

    import filter_symblend.meshlab.meshset_filter as meshset_filter

    mesh_path, landmark_path, *_ = bent_cow_files

    def never(*args, **kwargs):
        raise AssertionError("the filter ran")

    monkeypatch.setattr(meshset_filter, "generate_symmetrized_mesh", never)
    digest = hashlib.sha256(mesh_path.read_bytes()).hexdigest()
    before = set(tmp_path.rglob("*"))
    for name, arguments, expected in _probe_arguments(tmp_path, mesh_path, landmark_path):
        source = mesh_path
        if "INPUT" in arguments:
            source = pathlib.Path(arguments[arguments.index("INPUT") + 1])
            arguments = arguments[:arguments.index("INPUT")]
        before |= {source}
        assert main(["symmetrize", str(source), "-l", str(landmark_path), *arguments]) == 1, name
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and re.search(expected, err), (name, err)
    assert set(tmp_path.rglob("*")) == before  # nothing written, no partial file
    assert hashlib.sha256(mesh_path.read_bytes()).hexdigest() == digest


def test_overwrite_replaces_the_input_only_when_asked_and_at_the_end(tmp_path, bent_cow_files, capsys):
    mesh_path, landmark_path, deformed, left, right = bent_cow_files
    output = mesh_path
    assert main(["symmetrize", str(output), "-l", str(landmark_path), "-o", str(output), "--overwrite"]) == 0
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(output))
    points = ms.current_mesh().vertex_matrix()
    assert points.shape == deformed.shape and np.abs(points - deformed).max() > 1e-3  # symmetrized in place


def test_usage_errors_are_one_line_with_status_2(capsys):
    for arguments in (["symmetrize"], ["symmetrize", "a.obj", "-o", "b.ply", "--mode", "stretchy"], ["nonsense"]):
        with pytest.raises(SystemExit) as exit:
            main(arguments)
        err = capsys.readouterr().err
        assert exit.value.code == 2 and err.count("\n") == 1 and "--help" in err, err
    with pytest.raises(SystemExit):
        main(["symmetrize", "a.obj", "-o", "b.ply", "--mode", "stretchy"])
    assert "invalid choice: 'stretchy' (choose from 'standard', 'affine', 'articulated')" in capsys.readouterr().err


def test_every_mesh_format_listed_is_one_pymeshlab_writes(tmp_path):
    # In a fresh interpreter: a writer's failure then names its format, whatever earlier tests left in
    # this process (a crash inside pymeshlab's writers was seen once in ~10 runs of the whole suite,
    # never in 3,000 writes from a fresh process).
    from filter_symblend.commands.shared.mesh_io import MESH_SAVE_FORMATS
    code = ("import sys, pymeshlab; ms = pymeshlab.MeshSet(); ms.create_sphere(subdiv=1)\n"
            "for extension in sys.argv[2:]:\n"
            "    print(extension, flush=True); ms.save_current_mesh(f'{sys.argv[1]}/sphere.{extension}')\n")
    done = subprocess.run([sys.executable, "-c", code, str(tmp_path), *MESH_SAVE_FORMATS],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, f"writing .{done.stdout.split()[-1]} failed: {done.stderr[-2000:]}"
    assert sorted(p.suffix[1:] for p in tmp_path.glob("sphere.*")) == sorted(MESH_SAVE_FORMATS)


def test_ctrl_c_while_loading_exits_130_with_one_line():
    code = ("import os, signal, sys, time; sys.argv[0] = 'symblend'; "
            "from filter_symblend.commands.start import quiet_interrupt_while_loading; "
            "quiet_interrupt_while_loading(); os.kill(os.getpid(), signal.SIGINT); time.sleep(5)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 130 and done.stderr == "symblend: interrupted; no output written\n"


def test_far_landmarks_are_an_error_unless_allowed(tmp_path, bent_cow_files, capsys):
    mesh_path, landmark_path, deformed, left, right = bent_cow_files
    landmarks = read_landmarks(landmark_path)
    moved = [Landmark(m.name, tuple(np.add(m.position, [0, 0, 0.5])) if m.name == "L_3" else m.position)
             for m in landmarks.landmarks]
    far = tmp_path / "far.pp"
    write_landmarks(far, LandmarkSet(moved))
    output = tmp_path / "out.ply"
    assert main(["symmetrize", str(mesh_path), "-l", str(far), "-o", str(output)]) == 1
    err = capsys.readouterr().err
    assert "L_3 (" in err and "--allow-far-landmarks" in err and not output.exists()
    assert main(["symmetrize", str(mesh_path), "-l", str(far), "-o", str(output), "--allow-far-landmarks"]) == 0
    assert "warning: " in capsys.readouterr().err and output.exists()


def test_a_landmark_script_without_a_landmark_file_says_to_give_one(tmp_path, bent_cow_files, capsys):
    mesh_path, *_ = bent_cow_files
    preset = pathlib.Path(__file__).resolve().parents[1] / "mlx_presets" / "fossil_restoration.mlx"
    assert main(["mlx", str(preset), str(mesh_path), "-o", str(tmp_path / "out.ply")]) == 1
    err = capsys.readouterr().err
    assert "give the landmark file with -l LANDMARKS" in err and err.count("\n") == 1


@pytest.mark.auto
def test_symmetrize_with_automatic_pairs_needs_no_landmark_file(tmp_path, cow, capsys):
    mesh_path, output, report = tmp_path / "scan.obj", tmp_path / "out.ply", tmp_path / "report.json"
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=synthetic.bend(cow.points, 0.2), face_matrix=cow.faces))
    ms.save_current_mesh(str(mesh_path))
    assert main(["symmetrize", str(mesh_path), "--pairs", "auto", "--auto-pair-count", "800", "-o", str(output),
                 "--report", str(report)]) == 0
    printed = capsys.readouterr().out
    data = json.loads(report.read_text())
    automatic = data["auto_pairs"]
    assert 760 <= automatic["pair_count"] + automatic["midline_count"] <= 800 and data["landmarks"] is None
    assert f"0 landmark pairs + {automatic['pair_count']} automatic pairs" in printed
    assert "landmark asymmetry" not in printed
    assert data["mirror_asymmetry_after"]["rms"] < data["mirror_asymmetry_before"]["rms"] / 2


@pytest.mark.parametrize(("pairs", "extra", "message"), [
    ("auto", ["-l", "LANDMARKS"],
     "--pairs auto finds its own pairs; leave out -l and --missing, or use --pairs landmarks+auto."),
    ("auto", ["--missing", "L_1"], "--pairs auto finds its own pairs; leave out -l and --missing"),
    ("landmarks", [], "Give a landmark file (-l LANDMARKS), or --pairs auto to find pairs on the surface"),
    ("landmarks+auto", [], "Give a landmark file (-l LANDMARKS), or --pairs auto"),
])
def test_symmetrize_checks_the_landmark_file_against_the_pair_source(tmp_path, bent_cow_files, capsys, pairs,
                                                                      extra, message):
    mesh_path, landmark_path, *_ = bent_cow_files
    output = tmp_path / "out.ply"
    arguments = ["symmetrize", str(mesh_path), "--pairs", pairs, "-o", str(output)]
    assert main(arguments + [str(landmark_path) if word == "LANDMARKS" else word for word in extra]) == 1
    assert message in capsys.readouterr().err and not output.exists()


def test_mlx_runs_a_preset_with_a_landmark_file(tmp_path, bent_cow_files, capsys):
    mesh_path, landmark_path, *_ = bent_cow_files
    preset = pathlib.Path(__file__).resolve().parents[1] / "mlx_presets" / "articulated_pose.mlx"
    output, report = tmp_path / "clean.ply", tmp_path / "steps.json"
    assert main(["mlx", str(preset), str(mesh_path), "-l", str(landmark_path), "-o", str(output),
                 "--report", str(report)]) == 0
    assert "1 filters of" in capsys.readouterr().out
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(output))
    assert ms.current_mesh().face_number() == 5804
    steps = json.loads(report.read_text())["steps"]
    assert steps[0]["output"]["pair_count"] == 80


def test_mlx_error_writes_nothing(tmp_path, bent_cow_files, capsys):
    mesh_path, *_ = bent_cow_files
    bad = tmp_path / "bad.mlx"
    bad.write_text('<FilterScript><filter name="Close Hole"/></FilterScript>')
    output = tmp_path / "out.ply"
    assert main(["mlx", str(bad), str(mesh_path), "-o", str(output)]) == 1
    assert "no version of MeshLab had a filter of this name" in capsys.readouterr().err
    assert not output.exists() and list(tmp_path.glob(".*partial*")) == []


def test_mlx_runs_a_script_of_meshlab_1_3_and_says_what_it_translated(tmp_path, bent_cow_files, capsys):
    mesh_path, landmark_path, *_ = bent_cow_files
    old = tmp_path / "old.mlx"
    old.write_text('<!DOCTYPE FilterScript>\n<FilterScript>\n <filter name="Remove Duplicated Vertex"/>\n'
                   f' <filter name="{DISPLAY_NAME}"/>\n</FilterScript>\n')
    written = old.read_bytes()
    output, report = tmp_path / "out.ply", tmp_path / "steps.json"
    assert main(["mlx", str(old), str(mesh_path), "-l", str(landmark_path), "-o", str(output),
                 "--report", str(report)]) == 0
    err = capsys.readouterr().err
    assert (f"{old}, filter 1: 'Remove Duplicated Vertex' (MeshLab 1.3.4BETA) runs as today's "
            "'Remove Duplicate Vertices'\n") in err
    assert json.loads(report.read_text())["steps"][0]["translated"].startswith("'Remove Duplicated Vertex'")
    assert output.exists() and old.read_bytes() == written


def test_mlx_accepts_a_replacement_when_told_prints_it_and_records_it(tmp_path, bent_cow_files, capsys):
    mesh_path, *_ = bent_cow_files
    old = tmp_path / "old.mlx"
    old.write_text('<!DOCTYPE FilterScript>\n<FilterScript>\n <filter name="Compact vertices"/>\n</FilterScript>\n')
    output, report = tmp_path / "out.ply", tmp_path / "steps.json"
    assert main(["mlx", str(old), str(mesh_path), "-o", str(output)]) == 1
    assert "--accept-replacements" in capsys.readouterr().err and not output.exists()
    assert main(["mlx", str(old), str(mesh_path), "-o", str(output), "--report", str(report),
                 "--accept-replacements"]) == 0
    assert (f"{old}, filter 1: 'Compact vertices' (removed in MeshLab 2021.10) dropped, as accepted: drop the step: "
            "pymeshlab compacts a mesh itself\n") in capsys.readouterr().err
    written = json.loads(report.read_text())
    assert written["accept_replacements"] is True and "dropped, as accepted" in written["steps"][0]["translated"]


def test_report_numbers_match_an_independent_computation(tmp_path, bent_cow_files, capsys):
    mesh_path, landmark_path, *_ = bent_cow_files
    output, numbers, picture = tmp_path / "out.ply", tmp_path / "numbers.json", tmp_path / "check.png"
    assert main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "-o", str(output)]) == 0
    assert main(["report", str(mesh_path), str(output), "--json", str(numbers), "--png", str(picture)]) == 0
    printed = capsys.readouterr().out
    assert "mirror asymmetry after" in printed and f"picture: {picture}" in printed
    data = json.loads(numbers.read_text())
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # Independent: MeshLab's Hausdorff from each mesh to its reflection across the reported plane.
    for key, path in (("mirror_asymmetry_before", mesh_path), ("mirror_asymmetry_after", output)):
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(path))
        points, faces = ms.current_mesh().vertex_matrix(), ms.current_mesh().face_matrix()
        assert data[key]["measured_vertices"] == len(points)  # all of them for the picture
        assert meshlab_mirror_distance(points, faces, data[key]) == pytest.approx(
            [data[key][k] for k in ("max", "mean", "rms")], rel=2e-3, abs=1e-7)  # MeshLab works in float32
    assert data["mirror_asymmetry_after"]["rms"] < data["mirror_asymmetry_before"]["rms"] / 5
    assert data["hausdorff_before_after"]["max"] > 0


def test_report_png_without_matplotlib_says_how_to_install_it(tmp_path, bent_cow_files, capsys, monkeypatch):
    import builtins

    mesh_path, *_ = bent_cow_files
    real_import = builtins.__import__

    def no_matplotlib(name, *args, **kwargs):
        if name.startswith("matplotlib"):
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_matplotlib)
    assert main(["report", str(mesh_path), str(mesh_path), "--png", str(tmp_path / "x.png")]) == 1
    assert "pip install 'filter-symblend[plot]'" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


@pytest.fixture()
def curve_files(tmp_path, bent_cow_files):
    """The bent cow's first 12 pairs as landmarks, and 3 curves through the next 12 pairs: 4 control
    points on the left, 3 on the right (the right curves skip their second point)."""
    mesh_path, _, deformed, left, right = bent_cow_files
    landmarks = [Landmark(f"{side}_{k}", tuple(deformed[v]))
                 for k in range(12) for side, v in (("L", left[k]), ("R", right[k]))]
    for c in range(3):
        chain = range(12 + 4 * c, 16 + 4 * c)
        landmarks += [Landmark(f"L_arch{c}_{n}", tuple(deformed[left[k]])) for n, k in enumerate(chain, start=1)]
        landmarks += [Landmark(f"R_arch{c}-{n}", tuple(deformed[right[k]]))
                      for n, k in enumerate(chain, start=1) if n != 2]
    path = tmp_path / "curves.pts"
    write_landmarks(path, LandmarkSet(landmarks))
    return mesh_path, path


def test_curves_become_semilandmark_pairs(tmp_path, curve_files, capsys):
    mesh_path, landmark_path = curve_files
    output, report = tmp_path / "out.ply", tmp_path / "report.json"
    assert main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "--curves", "--curve-spacing", "0.05",
                 "-o", str(output), "--report", str(report)]) == 0
    data = json.loads(report.read_text())
    curves = data["landmarks"]["curves"]
    assert [c["name"] for c in curves] == ["arch0", "arch1", "arch2"]
    assert all(c["control_points"] == [4, 3] and c["samples"] >= 5 for c in curves)
    assert data["pair_count"] == 12 + sum(c["samples"] for c in curves)
    assert data["landmarks"]["pairs"][12] == ["L_arch0:1", "R_arch0:1"]
    assert data["width_spacing"] == data["landmarks"]["placed_point_spacing"] > data["mean_landmark_spacing"]
    assert data["landmark_asymmetry_after"]["rms_relative"] < 1e-9
    assert f"{data['pair_count']} landmark pairs" in capsys.readouterr().out
    assert main(["landmarks", "check", str(mesh_path), "-l", str(landmark_path), "--curves"]) == 0
    assert "curve arch1: 4/3 control points, surface length" in capsys.readouterr().out


def test_curve_option_errors(tmp_path, curve_files, capsys):
    mesh_path, landmark_path = curve_files
    output = tmp_path / "out.ply"
    assert main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "-o", str(output)]) == 1
    assert "'L_arch0_2'" in (error := capsys.readouterr().err) and "is a point of a curve, pass --curves" in error
    with pytest.raises(SystemExit):
        main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "--curves", "--curve-spacing", "-1",
              "-o", str(output)])
    assert "'-1' is not a positive length in mesh units" in capsys.readouterr().err
    assert main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "--curve-spacing", "0.05",
                 "-o", str(output)]) == 1
    assert "`curve_spacing` spaces the semilandmarks of curves; set curves=True (--curves)" in capsys.readouterr().err
    preset = pathlib.Path(__file__).resolve().parents[1] / "mlx_presets" / "fossil_restoration.mlx"
    assert main(["mlx", str(preset), str(mesh_path), "-l", str(landmark_path), "--curves", "-o", str(output)]) == 0
    assert "has width_spacing 0, so its widths are multiples of the semilandmark spacing; set width_spacing to" \
        in capsys.readouterr().err
    assert output.exists()


def test_pairs_from_a_landmark_file_in_python_are_what_the_command_uses(bent_cow_files, cow):
    from filter_symblend import pairs_from_landmark_file, symmetrize
    mesh_path, landmark_path, deformed, left, right = bent_cow_files
    snapped = pairs_from_landmark_file(deformed, cow.faces, landmark_path)
    np.testing.assert_array_equal(snapped.pairs.left, left)  # placed exactly on these vertices
    np.testing.assert_array_equal(snapped.pairs.right, right)
    assert snapped.pair_names[0] == ("L_0", "R_0") and snapped.frame_note == "coordinates used as stored"
    result = symmetrize(deformed, snapped.pairs.left, snapped.pairs.right, faces=cow.faces)
    assert result.report.landmark_asymmetry_after.max_relative < 1e-9


@pytest.mark.parametrize("mode", ["standard", "affine", "articulated"])
def test_a_flat_mesh_is_symmetrized_in_every_mode_and_stays_flat(tmp_path, mode):
    """A 2D shape (z = 0 everywhere, like the paper's WoodDoll) bent in its plane: every mode applies in
    2D, the landmark pairs come out symmetric and every vertex keeps z = 0 exactly."""
    angle = np.linspace(0, 2 * np.pi, 80, endpoint=False)
    points, faces = synthetic.flat_region(np.c_[np.cos(angle) * (1 + 0.3 * np.cos(2 * angle)), 0.7 * np.sin(angle)],
                                          rings=8)
    twin = np.argmin(np.linalg.norm(points[:, None] - points[None] * [-1, 1, 1], axis=2), axis=1)
    bent = points + np.c_[0.15 * points[:, 1] ** 2, np.zeros((len(points), 2))]
    left = np.flatnonzero(points[:, 0] > 0.05)[::2]
    mesh_path, landmark_path, output = tmp_path / "flat.ply", tmp_path / "flat.pp", tmp_path / "out.ply"
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=bent, face_matrix=faces))
    ms.save_current_mesh(str(mesh_path))
    write_landmarks(landmark_path, LandmarkSet([Landmark(f"{side}_{k}", tuple(bent[v])) for k, a in enumerate(left)
                                                for side, v in (("L", a), ("R", twin[a]))]))
    assert main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "-o", str(output), "--mode", mode]) == 0
    ms.load_new_mesh(str(output))
    result = ms.current_mesh().vertex_matrix()
    assert np.all(result[:, 2] == 0.0)
    assert synthetic.symmetry_error(result, left, twin[left]) < 1e-9
    assert synthetic.symmetry_error(bent, left, twin[left]) > 1e-2


def test_library_warnings_are_silenced_and_ours_are_one_line(tmp_path, capsys, monkeypatch):
    import warnings

    import filter_symblend.commands.landmark_files as landmark_files
    from filter_symblend import SymblendWarning

    def noisy(args):
        warnings.warn("overflow encountered in multiply", RuntimeWarning)
        warnings.warn("a pair looks swapped:\n  check it", SymblendWarning)
        return 0

    monkeypatch.setattr(landmark_files, "run_convert", noisy)
    assert main(["landmarks", "convert", str(tmp_path / "a.pp"), str(tmp_path / "b.pp")]) == 0
    assert capsys.readouterr().err == "symblend: warning: a pair looks swapped: check it\n"


def test_a_tps_study_with_three_pairs_and_midline_landmarks(tmp_path, cow, capsys):
    """Morpho's own example's shape: 3 pairs and 4 midline landmarks, from the second specimen of a .tps
    file, paired by number through a pair table."""
    left, right = cow.landmarks(3)
    on_plane = np.flatnonzero(np.abs(cow.points[:, 0] - cow.offset) < 1e-12)
    midline = on_plane[np.argsort(cow.points[on_plane, 1])][np.linspace(0, len(on_plane) - 1, 4).astype(int)]
    bent = synthetic.bend(cow.points, 0.3)
    mesh_path, tps, table, output = (tmp_path / name for name in ("cow.obj", "study.tps", "pairs.csv", "out.ply"))
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=bent, face_matrix=cow.faces))
    ms.save_current_mesh(str(mesh_path))
    order = [left[0], right[0], left[1], right[1], left[2], right[2], *midline]
    rows = "".join(" ".join(repr(float(v)) for v in bent[i] * 10) + "\n" for i in order)  # in mm: SCALE=0.1
    tps.write_text(f"LM3=1\n0 0 0\nID=other\nLM3={len(order)}\n{rows}ID=specimen-2\nSCALE=0.1\n")
    table.write_text("left,right\n1,2\n3,4\n5,6\n")
    arguments = ["symmetrize", str(mesh_path), "-l", str(tps), "--specimen", "specimen-2", "--pair-table",
                 str(table), "--midline", "-o", str(output), "--report", str(tmp_path / "r.json")]
    assert main(arguments) == 0
    data = json.loads((tmp_path / "r.json").read_text())
    assert data["pair_count"] == 3 and data["midline_count"] == 4 and data["landmarks"]["snap_distance_max"] < 1e-9
    assert data["landmark_asymmetry_after"]["max_relative"] < 1e-9
    assert main(["landmarks", "convert", str(tps), str(tmp_path / "second.pp"), "--specimen", "2"]) == 0
    assert read_landmarks(tmp_path / "second.pp").names()[:2] == ["1", "2"]
    assert main(["landmarks", "check", str(mesh_path), "-l", str(tps), "--pair-table", str(table), "--midline"]) == 1
    assert "holds 2 specimens (other, specimen-2); the first (other) is used" in capsys.readouterr().err


def test_an_unwritable_output_folder_is_refused_first(tmp_path, bent_cow_files, capsys, monkeypatch):
    import filter_symblend.commands.shared.mesh_io as command_files
    mesh_path, landmark_path, *_ = bent_cow_files
    monkeypatch.setattr(command_files.os, "access", lambda path, mode: False)  # as a user without rights sees it
    assert main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "-o", str(tmp_path / "out.ply")]) == 1
    assert f"the folder {tmp_path} is not writable" in capsys.readouterr().err
    assert not (tmp_path / "out.ply").exists()


def test_help_texts_say_what_each_command_takes(capsys):
    from filter_symblend.parameters import PARAMETERS_BY_NAME
    with pytest.raises(SystemExit):
        main(["mlx", "--help"])
    text = capsys.readouterr().out
    assert "--pairs" not in text and "for scripts whose filter uses landmarks" in " ".join(text.split())
    assert PARAMETERS_BY_NAME["width_spacing"].range_text() == "[0, inf)"  # inf itself is not a width


def test_a_loaded_mesh_with_non_finite_coordinates_is_refused(tmp_path):
    """pymeshlab's readers drop such vertices (the header count then catches it); whatever reader keeps
    one, the check names it."""
    from filter_symblend import SymblendError
    from filter_symblend.commands.shared.mesh_io import check_loaded_mesh
    points = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, np.inf, 0.0]])
    with pytest.raises(SymblendError, match=r"scan.stl: vertex 2 has non-finite coordinates \(1 such vertices\); "
                                            r"repair the mesh"):
        check_loaded_mesh(tmp_path / "scan.stl", points, np.array([[0, 1, 2]]))


def test_sigterm_while_the_output_is_written_exits_143_and_leaves_nothing(tmp_path, bent_cow_files):
    """A batch scheduler's SIGTERM arriving while the output mesh is being written (here: right after
    pymeshlab wrote the temporary file): one line, status 143, no output and no partial file."""
    mesh_path, landmark_path, *_ = bent_cow_files
    output = tmp_path / "out.ply"
    code = ("import os, signal, sys, time, pymeshlab\n"
            "from filter_symblend.commands.main import main\n"
            "original = pymeshlab.MeshSet.save_current_mesh\n"
            "def written_then_terminated(self, *args, **kwargs):\n"
            "    original(self, *args, **kwargs)\n"
            "    os.kill(os.getpid(), signal.SIGTERM)\n"
            "    time.sleep(5)\n"
            "pymeshlab.MeshSet.save_current_mesh = written_then_terminated\n"
            "sys.exit(main(sys.argv[1:]))\n")
    before = sorted(p.name for p in tmp_path.iterdir())
    done = subprocess.run([sys.executable, "-c", code, "symmetrize", str(mesh_path), "-l", str(landmark_path),
                           "-o", str(output)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 143, done.stderr
    assert done.stderr.endswith("symblend: terminated; no output written\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # no out.ply, no .out.symblend-partial.ply


def test_a_report_that_cannot_be_written_leaves_no_mesh_either(tmp_path, bent_cow_files, capsys, monkeypatch):
    """A full disk when the report is written (after the mesh): one line naming the report and the reason,
    status 1, and neither the mesh nor the report nor a partial file is left (the outputs are one result)."""
    import errno
    mesh_path, landmark_path, *_ = bent_cow_files
    output, report = tmp_path / "out.ply", tmp_path / "report.json"
    original = pathlib.Path.write_text

    def disk_full_for_json(self, *args, **kwargs):
        if self.suffix == ".json":
            raise OSError(errno.ENOSPC, "No space left on device")  # as a write() or close() raises it: no file name
        return original(self, *args, **kwargs)

    monkeypatch.setattr(pathlib.Path, "write_text", disk_full_for_json)
    before = sorted(p.name for p in tmp_path.iterdir())
    assert main(["symmetrize", str(mesh_path), "-l", str(landmark_path), "-o", str(output),
                 "--report", str(report)]) == 1
    assert capsys.readouterr().err == f"symblend: error: {report}: No space left on device\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_file_names_that_are_not_utf8_work(tmp_path, bent_cow_files, capsys):
    """Linux file names are bytes: 'caf\\xe9 cow.obj' (Latin-1) is read, symmetrized and written like any other,
    with nothing left beside it (pymeshlab, which takes UTF-8 text, is given ASCII names)."""
    import os
    import shutil
    mesh_path, landmark_path, *_ = bent_cow_files
    folder = tmp_path / "latin1"
    folder.mkdir()
    mesh = folder / os.fsdecode(b"caf\xe9 cow.obj")
    landmarks = folder / os.fsdecode(b"caf\xe9 cow_picked_points.pp")
    shutil.copy(mesh_path, mesh)
    shutil.copy(landmark_path, landmarks)
    output, report = folder / os.fsdecode(b"caf\xe9 out.ply"), folder / os.fsdecode(b"r\xe9port.json")
    assert main(["symmetrize", str(mesh), "-l", str(landmarks), "-o", str(output), "--report", str(report)]) == 0
    assert "80 landmark pairs" in capsys.readouterr().out
    assert sorted(os.listdir(os.fsencode(folder))) == sorted(
        [b"caf\xe9 cow.obj", b"caf\xe9 cow_picked_points.pp", b"caf\xe9 out.ply", b"r\xe9port.json"])
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(shutil.copy(output, tmp_path / "check.ply")))
    assert ms.current_mesh().vertex_number() == len(bent_cow_files[2])

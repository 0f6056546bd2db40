"""Runs that fail say the true reason in one line and leave nothing behind (issue 51)."""

import os

import numpy as np
import pymeshlab
import pytest

from filter_symblend import GeometryError, symmetrize
from filter_symblend.commands.main import main
from filter_symblend.testing import synthetic


@pytest.fixture()
def sphere_file(tmp_path):
    points, faces = synthetic.icosphere(2)
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(synthetic.bumpy(points), faces))
    path = tmp_path / "sphere.obj"
    ms.save_current_mesh(str(path))
    return path


def test_a_pipe_or_a_folder_given_as_the_mesh_is_not_a_regular_file(tmp_path, capsys):
    pipe = tmp_path / "mesh.ply"
    os.mkfifo(pipe)
    for given in (pipe, tmp_path):
        assert main(["symmetrize", str(given), "--pairs", "auto", "-o", str(tmp_path / "out.ply")]) == 1
        assert capsys.readouterr().err == (f"symblend: error: {given}: not a regular file (a folder, a pipe or a "
                                           "device); give a mesh file.\n")
    assert main(["symmetrize", str(tmp_path / "none.ply"), "--pairs", "auto", "-o", str(tmp_path / "out.ply")]) == 1
    assert "none.ply: no such mesh file." in capsys.readouterr().err


def test_a_closed_surface_flattened_onto_a_plane_is_refused_for_what_it_is():
    points, faces = synthetic.icosphere(2)
    with pytest.raises(GeometryError, match=r"^The mesh is flat \(every vertex in one plane\), so its outline is what "
                                            r"is paired, and its outline has 0 vertices that can be paired \(a closed "
                                            r"surface flattened onto a plane has none\)"):
        symmetrize(points * [1.0, 1.0, 0.0], faces=faces, pairs="auto")


def test_an_output_format_without_faces_is_refused_before_any_work(sphere_file, tmp_path, capsys):
    output = tmp_path / "out.xyz"
    assert main(["symmetrize", str(sphere_file), "--pairs", "auto", "-o", str(output)]) == 1
    assert capsys.readouterr().err == (
        f"symblend: error: {output}: a .xyz file holds points only, and {sphere_file} has faces: they would be lost "
        "with the per-vertex asymmetry; write .ply (or .obj, .off for the faces alone).\n")
    assert not output.exists()
    cloud = tmp_path / "cloud.xyz"
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(sphere_file))
    ms.save_current_mesh(str(cloud))  # a point cloud: .xyz holds all of it
    assert main(["symmetrize", str(cloud), "--pairs", "auto", "-o", str(tmp_path / "cloud_out.xyz")]) == 0
    assert np.isfinite(np.loadtxt(tmp_path / "cloud_out.xyz")).all()


def test_an_obj_cut_short_is_refused_as_cut_short(sphere_file, tmp_path, capsys):
    """An OBJ declares no counts: one copied half-way is read as its first vertices and no faces, then
    refused for an unrelated reason. It is refused as what it is, before any work."""
    whole = sphere_file.read_bytes()
    half = tmp_path / "half.obj"
    line_end = whole.index(b"\n", whole.index(b"\nv ", len(whole) // 4) + 1)
    half.write_bytes(whole[:line_end - 2])  # ends inside a vertex line's third coordinate
    last = half.read_bytes().rsplit(b"\n", 1)[-1].decode()
    assert main(["symmetrize", str(half), "--pairs", "auto", "-o", str(tmp_path / "out.ply")]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"symblend: error: {half}: the file ends in the middle of a line ('{last.strip()}') and no "
                          "face could be read: it looks cut short (a copy or a download that stopped); pymeshlab read ")
    assert err.endswith("Copy the whole file again (a whole point cloud: end it with a newline).\n")
    assert not (tmp_path / "out.ply").exists()
    whole_without_final_newline = tmp_path / "whole.obj"
    whole_without_final_newline.write_bytes(whole.rstrip(b"\n"))  # a whole last line without its newline is fine
    assert main(["landmarks", "check", str(whole_without_final_newline), "-l", str(tmp_path / "none.pp")]) == 1
    assert "none.pp" in capsys.readouterr().err  # got past the mesh to the missing landmark file


def test_symblend_report_writes_all_its_files_or_none(sphere_file, tmp_path, capsys, monkeypatch):
    """symblend report's distance mesh and JSON are one result: a full disk on the JSON (written last) leaves
    neither, nor any partial file; written whole otherwise."""
    import errno
    import pathlib
    after = tmp_path / "after.ply"
    assert main(["symmetrize", str(sphere_file), "--pairs", "auto", "-o", str(after)]) == 0
    capsys.readouterr()
    distance, numbers = tmp_path / "distance.ply", tmp_path / "numbers.json"
    original = pathlib.Path.write_text

    def disk_full_for_json(self, *args, **kwargs):
        if self.suffix == ".json":
            raise OSError(errno.ENOSPC, "No space left on device")
        return original(self, *args, **kwargs)

    before = sorted(p.name for p in tmp_path.iterdir())
    with monkeypatch.context() as patched:
        patched.setattr(pathlib.Path, "write_text", disk_full_for_json)
        assert main(["report", str(sphere_file), str(after), "--distance-ply", str(distance),
                     "--json", str(numbers)]) == 1
    assert capsys.readouterr().err.endswith(f"symblend: error: {numbers}: No space left on device\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == before
    assert main(["report", str(sphere_file), str(after), "--distance-ply", str(distance), "--json", str(numbers)]) == 0
    assert distance.exists() and numbers.exists()


def test_too_little_free_space_is_refused_before_any_work(sphere_file, tmp_path, capsys, monkeypatch):
    """The outputs need room for the mesh (up to 4x its input file) and the report; a folder with less is refused
    before anything is computed or written, naming the folder, what is free and what is needed."""
    import collections
    from filter_symblend.commands.shared import mesh_io
    usage = collections.namedtuple("usage", "total used free")
    needed = 4 * sphere_file.stat().st_size + 2**20  # the mesh and the report
    output, report = tmp_path / "out.ply", tmp_path / "out.json"
    for free, status in ((needed - 1, 1), (needed, 0)):
        monkeypatch.setattr(mesh_io.shutil, "disk_usage", lambda folder, free=free: usage(10 * needed, 0, free))
        assert main(["symmetrize", str(sphere_file), "--pairs", "auto", "-o", str(output), "--report", str(report)]) \
            == status
        if status:
            assert capsys.readouterr().err == (
                f"symblend: error: {tmp_path}: {(needed - 1) / 1e6:.1f} MB free, and the outputs written there need "
                f"about {needed / 1e6:.1f} MB (an output mesh up to 4x its input file); free some space, or write "
                "the outputs to another disk.\n")
            assert sorted(p.name for p in tmp_path.iterdir()) == ["sphere.obj"]
    assert output.stat().st_size <= 4 * sphere_file.stat().st_size  # the estimate holds for this one


def test_a_point_cloud_whose_twins_fall_on_shared_points_is_still_paired(cow):
    """pymeshlab's cow (symmetric to about 1e-4 of its size) cut after 2,489 vertices, as an OBJ cut at a line
    end reads: a point cloud whose twins are points, many sources sharing one. One pair per shared point is kept
    (all of them were dropped, and the run refused with 'Found no landmark pair', about landmarks never given).
    Where both twins remain the cloud comes back mirror-symmetric, its shape nearly unchanged."""
    from conftest import SAMPLE_MESHES
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(SAMPLE_MESHES / "cow.obj"))
    cloud = ms.current_mesh().vertex_matrix()[:2489]
    both = (cow.all_left < 2489) & (cow.all_right < 2489)
    result = symmetrize(cloud, pairs="auto")
    assert result.report.auto_pairs.twins_are == "points of the surface"
    assert synthetic.symmetry_error(result.points, cow.all_left[both], cow.all_right[both]) < 1e-3  # measured 4.7e-4
    assert synthetic.shape_error(result.points, cloud) < 5e-3  # measured 1.1e-3

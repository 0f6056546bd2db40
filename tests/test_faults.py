"""Runs that fail say the true reason in one line and leave nothing behind (issue 51)."""

import os

import numpy as np
import pymeshlab
import pytest

from filter_symblend import GeometryError, symmetrize, synthetic
from filter_symblend.commands.main import main


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

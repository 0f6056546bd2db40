"""Shared ground truth: exactly mirror-symmetric meshes and their vertex pairs."""

from __future__ import annotations

import dataclasses
import os
import pathlib

import numpy as np
import pymeshlab
import pytest

from filter_symblend.testing import synthetic
from filter_symblend.testing.remeshing import remeshed
from filter_symblend.testing.surface_truth import SurfaceTruth

SAMPLE_MESHES = pathlib.Path(pymeshlab.__file__).parent / "tests" / "sample_meshes"
SHARED_DATA = pathlib.Path(__file__).resolve().parents[1].parent / "shared" / "data"
SCRIPTS = pathlib.Path(__file__).resolve().parents[1] / "scripts"  # the benchmarks' helpers (benchmarks.mirror_maps)


@pytest.fixture
def bcicp():
    """The BCICP dataset's FAUST and TOSCA shapes with their ground-truth self-symmetry, read in place by the
    mirror-map benchmark's loader (``benchmarks.mirror_maps`` importable from then on); skips the test without it."""
    import sys
    if str(SCRIPTS) not in sys.path:
        sys.path.insert(0, str(SCRIPTS))
    from benchmarks.mirror_maps import find_dataset
    dataset = find_dataset(None)
    if dataset is None:
        pytest.skip("the BCICP dataset is absent (fetch llorz/SGA18_orientation_BCICP_dataset, or $BCICP_DATASET)")
    return dataset


@dataclasses.dataclass
class GroundTruth:
    """An exactly symmetric mesh: points (N, 3), faces, all mirror pairs, and landmark pairs."""

    points: np.ndarray
    faces: np.ndarray
    all_left: np.ndarray
    all_right: np.ndarray
    offset: float
    partner: np.ndarray

    def landmarks(self, count: int):
        return synthetic.farthest_point_pairs(self.points, self.offset, self.partner, count)

    @property
    def diagonal(self) -> float:
        return float(np.linalg.norm(np.ptp(self.points, axis=0)))


def load_ground_truth(path: os.PathLike) -> GroundTruth:
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(path))
    mesh = ms.current_mesh()
    raw = mesh.vertex_matrix()
    offset, partner = synthetic.mirror_partners(raw)
    points = synthetic.exactly_symmetric(raw, offset, partner)
    left = np.flatnonzero((partner >= 0) & (points[:, 0] > offset))
    return GroundTruth(points, mesh.face_matrix(), left, partner[left], offset, partner)


@pytest.fixture(scope="session")
def cow() -> GroundTruth:
    return load_ground_truth(SAMPLE_MESHES / "cow.obj")


@pytest.fixture(scope="session", params=["cow", "spot"])
def symmetric_mesh(request) -> GroundTruth:
    """The cow, and spot when ../shared/data is present."""
    if request.param == "cow":
        return load_ground_truth(SAMPLE_MESHES / "cow.obj")
    path = SHARED_DATA / "spot.obj"
    if not path.exists():
        pytest.skip(f"{path} is absent (shared test data not available)")
    return load_ground_truth(path)


def remeshed_ground_truth(path: os.PathLike, edge_percent: float) -> SurfaceTruth:
    """The exactly symmetric mesh at ``path`` remeshed (edges ``edge_percent`` % of the diagonal): no vertex
    has an exact twin."""
    truth = load_ground_truth(path)
    return remeshed(truth.points, truth.faces, truth.offset, edge_percent)


@pytest.fixture(scope="session")
def remeshed_cow() -> SurfaceTruth:
    return remeshed_ground_truth(SAMPLE_MESHES / "cow.obj", 2.0)


def symmetric_blob(subdivisions: int = 4):
    """An exactly mirror-symmetric closed mesh with one mirror plane (x = 0): pymeshlab's icosphere (whose
    vertex set and triangles are closed under x -> -x) with bumps even in x but not in y or z. (points, faces)"""
    ms = pymeshlab.MeshSet()
    ms.create_sphere(subdiv=subdivisions)
    mesh = ms.current_mesh()
    return synthetic.bumpy(mesh.vertex_matrix()), mesh.face_matrix()


def twins(points: np.ndarray) -> np.ndarray:
    """The exact mirror twin (N,) of every vertex across x = 0."""
    from scipy.spatial import cKDTree
    distance, twin = cKDTree(points).query(points * [-1.0, 1.0, 1.0])
    assert distance.max() < 1e-9
    return twin


def meshset_with_pairs(points, faces, left, right, attribute="symblend_pair") -> pymeshlab.MeshSet:
    """A MeshSet whose current mesh carries the pair attribute (+k left, -k right)."""
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=points, face_matrix=faces)
                if faces is not None and len(faces) else pymeshlab.Mesh(vertex_matrix=points))
    labels = np.zeros(len(points))
    labels[left] = np.arange(1, len(left) + 1)
    labels[right] = -np.arange(1, len(right) + 1)
    ms.current_mesh().add_vertex_custom_scalar_attribute(labels, attribute)
    return ms


def saved_with_landmarks(folder: pathlib.Path, points, faces, left, right) -> tuple[pathlib.Path, pathlib.Path]:
    """``folder``/bent.ply (the mesh) and ``folder``/bent.pp (the pairs as landmarks L_point{k} / R_point{k})."""
    from filter_symblend.landmarks.formats import Landmark, LandmarkSet, write_landmarks
    mesh, landmarks = folder / "bent.ply", folder / "bent.pp"
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(points, faces))
    ms.save_current_mesh(str(mesh))
    write_landmarks(landmarks, LandmarkSet([Landmark(f"{side}_point{k}", tuple(points[vertex]))
                                            for k in range(len(left))
                                            for side, vertex in (("L", left[k]), ("R", right[k]))]))
    return mesh, landmarks


def meshlab_mirror_distance(points, faces, measured: dict) -> list[float]:
    """[max, mean, RMS] of MeshLab's Hausdorff from the mesh to its reflection across the plane that
    ``measured`` (a mirror asymmetry of the report) names: an independent computation of it."""
    normal, offset = np.array(measured["plane_normal"]), measured["plane_offset"]
    mirrored = points - 2 * (points @ normal - offset)[:, None] * normal
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(points, faces))
    ms.add_mesh(pymeshlab.Mesh(mirrored, faces[:, ::-1]))
    found = ms.get_hausdorff_distance(sampledmesh=0, targetmesh=1, samplevert=True, sampleface=False,
                                      maxdist=pymeshlab.PureValue(10.0 * float(np.ptp(points, axis=0).max())))
    return [found["max"], found["mean"], found["RMS"]]

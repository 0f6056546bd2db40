"""Before/after checks between two layers of a MeshSet: the two-way Hausdorff distance and the mirror
asymmetry of each on arrays (measures/), and the two-way Hausdorff by MeshLab's own filter (for scripts
that chain it)."""

from __future__ import annotations

import numpy as np
import pymeshlab
from scipy.spatial import cKDTree

from ..core.mirror_fill import TriangleSurface
from ..core.surface_points import barycentric, on_surface
from ..errors import LandmarkError
from ..measures.hausdorff import two_way_distance
from ..measures.surface_asymmetry import CHECK_SAMPLES, before_and_after, pairs_plane
from .attributes import optional_attribute, read_landmark_attributes
from .output_layer import CONFIDENCE_ATTRIBUTE, TWIN_ATTRIBUTE


def compare_layers(ms: pymeshlab.MeshSet, before: int, after: int, samples: int | None = CHECK_SAMPLES) -> dict:
    """``{"hausdorff_before_after", "mirror_asymmetry_before", "mirror_asymmetry_after"}`` for two
    layers of ``ms``; each mirror asymmetry is measured at ``samples`` evenly strided vertices (None:
    all) and holds their distances as ``per_vertex``, each against its plane fitted as the filter fits it
    (:func:`before_and_after`), from the pairs the output carries (:func:`solved_planes`). The layers are
    not changed."""
    meshes = [(ms.mesh(i).vertex_matrix(), ms.mesh(i).face_matrix()) for i in (before, after)]
    result = {"hausdorff_before_after": two_way_distance(*meshes[0], *meshes[1])}
    result["mirror_asymmetry_before"], result["mirror_asymmetry_after"] = before_and_after(
        *meshes, samples, solved_planes(ms.mesh(before), ms.mesh(after)))
    return result


def solved_planes(before: pymeshlab.Mesh, after: pymeshlab.Mesh) -> tuple:
    """The planes (measures/surface_asymmetry.pairs_plane) on ``before`` and on ``after`` of the pairs the
    filter solved, as its output carries them: the automatic twins the map supports (TWIN_ATTRIBUTE, points of
    the output, with confidence above 0; on the input, the same material points), else the landmark pairs of
    the default pair attribute on the output or the input (both sides weighted above 0). (None, None) without
    them, or when the two meshes do not share their vertices (not a run's input and output)."""
    if before.vertex_number() != after.vertex_number():
        return None, None
    points, moved = before.vertex_matrix(), after.vertex_matrix()
    twins = _point_attribute(after, TWIN_ATTRIBUTE)
    if twins is not None:
        confidence = optional_attribute(after, CONFIDENCE_ATTRIBUTE)
        vertex = np.flatnonzero(np.isfinite(twins).all(axis=1) & (True if confidence is None else confidence > 0))
        return pairs_plane(points[vertex], _on_input(twins[vertex], moved, points, after.face_matrix())), \
            pairs_plane(moved[vertex], twins[vertex])
    for mesh in (after, before):
        try:
            pairs = read_landmark_attributes(mesh)
        except LandmarkError:  # none, or not the filter's pairs: the figures use the best plane, and say so
            continue
        left, right = pairs.both_sides()
        return pairs_plane(points[left], points[right]), pairs_plane(moved[left], moved[right])
    return None, None


def _on_input(twins: np.ndarray, moved: np.ndarray, points: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The twins (k, 3), points of the output surface (``moved`` (N, 3), ``faces``), as the same material points of
    the input (``points`` (N, 3)): by their barycentric weights in the output triangle they lie on (each twin's
    nearest vertex instead without triangles)."""
    if not len(faces):
        return points[cKDTree(moved).query(twins)[1]]
    face, closest, _ = TriangleSurface(moved, faces).nearest(twins)
    weights = barycentric(moved[faces[face]], closest)
    return on_surface(points, faces[face], weights)


def _point_attribute(mesh: pymeshlab.Mesh, name: str) -> np.ndarray | None:
    """The per-vertex custom point attribute ``name`` (N, 3), or None when the mesh has none."""
    try:
        return mesh.vertex_custom_point_attribute_matrix(name)
    except pymeshlab.PyMeshLabException:
        return None


def two_way_hausdorff(ms: pymeshlab.MeshSet, a: int, b: int) -> dict[str, float]:
    """max, mean and RMS of MeshLab's ``get_hausdorff_distance`` in both directions between
    layers ``a`` and ``b``, sampled at the vertices (max: the larger direction; mean, RMS: their average).

    Samples copies of the layers, because the filter overwrites the sampled
    mesh's quality; the MeshSet ends with the same layers and current mesh.
    """
    current = ms.current_mesh_id()
    diagonal = max(ms.mesh(a).bounding_box().diagonal(), ms.mesh(b).bounding_box().diagonal())
    results = []
    for sampled, target in ((a, b), (b, a)):
        ms.set_current_mesh(sampled)
        ms.generate_copy_of_current_mesh()
        try:
            results.append(ms.get_hausdorff_distance(
                sampledmesh=ms.current_mesh_id(), targetmesh=target, samplevert=True, sampleface=False,
                maxdist=pymeshlab.PureValue(diagonal)))
        finally:
            ms.delete_current_mesh()
    ms.set_current_mesh(current)
    return {"max": max(r["max"] for r in results),
            "mean": sum(r["mean"] for r in results) / 2, "rms": sum(r["RMS"] for r in results) / 2}

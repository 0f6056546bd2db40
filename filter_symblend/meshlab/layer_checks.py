"""Before/after checks between two layers of a MeshSet: the two-way Hausdorff distance and the mirror
asymmetry of each on arrays (checks/), and the two-way Hausdorff by MeshLab's own filter (for scripts
that chain it)."""

from __future__ import annotations

import pymeshlab

from ..checks.hausdorff import two_way_distance
from ..checks.surface_asymmetry import CHECK_SAMPLES, before_and_after


def compare_layers(ms: pymeshlab.MeshSet, before: int, after: int, samples: int | None = CHECK_SAMPLES) -> dict:
    """``{"hausdorff_before_after", "mirror_asymmetry_before", "mirror_asymmetry_after"}`` for two
    layers of ``ms``; each mirror asymmetry is measured at ``samples`` evenly strided vertices (None:
    all) and holds their distances as ``per_vertex``, each against its own plane fitted as the filter
    fits it (:func:`before_and_after`). The layers are not changed."""
    meshes = [(ms.mesh(i).vertex_matrix(), ms.mesh(i).face_matrix()) for i in (before, after)]
    result = {"hausdorff_before_after": two_way_distance(*meshes[0], *meshes[1])}
    result["mirror_asymmetry_before"], result["mirror_asymmetry_after"] = before_and_after(*meshes, samples)
    return result


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

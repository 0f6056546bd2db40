"""Two-way Hausdorff distance between layers with MeshLab's own filter."""

from __future__ import annotations

import pymeshlab


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

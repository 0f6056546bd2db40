"""Distances between surfaces with MeshLab's own Hausdorff filter (its uniform grid), sampled at the vertices."""

from __future__ import annotations

import numpy as np
import pymeshlab


def _sampled(ms: pymeshlab.MeshSet, sampled: int, target: int, limit: float) -> dict:
    return ms.get_hausdorff_distance(sampledmesh=sampled, targetmesh=target, samplevert=True, sampleface=False,
                                     maxdist=pymeshlab.PureValue(limit))


def distances_to_surface(queries: np.ndarray, points: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Distance (Q,) from each query (Q, 3) to the triangle surface ``(points (V, 3), faces (F, 3))``,
    mesh units: MeshLab's ``get_hausdorff_distance`` sampled at the queries, in a MeshSet of its own."""
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(queries, dtype=float)))
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=np.asarray(points, dtype=float), face_matrix=faces))
    both = np.vstack([queries, points])
    limit = 2.0 * float(np.linalg.norm(np.ptp(both, axis=0))) + 1.0  # nothing farther: no sample is dropped
    _sampled(ms, 0, 1, limit)
    return ms.mesh(0).vertex_scalar_array()


def two_way_hausdorff(ms: pymeshlab.MeshSet, a: int, b: int) -> dict[str, float]:
    """max, mean and RMS of MeshLab's ``get_hausdorff_distance`` in both directions between
    layers ``a`` and ``b``, sampled at the vertices (max: the larger direction; mean, RMS: their
    average).

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
            results.append(_sampled(ms, ms.current_mesh_id(), target, 2.0 * diagonal))
        finally:
            ms.delete_current_mesh()
    ms.set_current_mesh(current)
    return {"max": max(r["max"] for r in results),
            "mean": sum(r["mean"] for r in results) / 2, "rms": sum(r["RMS"] for r in results) / 2}

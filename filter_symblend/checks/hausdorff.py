"""Two-way Hausdorff distance between surfaces: on arrays at sampled vertices (the filter's and the
report's checks), and between layers with MeshLab's own filter (for scripts that chain it)."""

from __future__ import annotations

import numpy as np
import pymeshlab

from ..core.mirror_fill import distances_to_surface
from .surface_asymmetry import distance_summary, evenly

# Vertices, evenly strided, sampled on each surface for the two-way distance. Closest points on a
# centroid KD-tree cost the same whatever the distance; MeshLab's grid slows down on far samples
# (3.8 s on a 61k-vertex pair moved 0.3 % of its size, minutes at 1M vertices).
HAUSDORFF_SAMPLES = 20_000


def two_way_distance(a: np.ndarray, a_faces: np.ndarray, b: np.ndarray, b_faces: np.ndarray,
                     samples: int = HAUSDORFF_SAMPLES) -> dict[str, float]:
    """max, mean and RMS of the distance (mesh units) from at most ``samples`` evenly strided vertices of
    each surface ``(points (N, 3), faces (F, 3))`` to the other (max: the larger direction; mean, RMS:
    their average), its 50th, 90th and 99th percentiles over both directions' samples, and ``samples``
    used per surface. A point cloud (no faces) is its points."""
    directions = [distances_to_surface(b, b_faces, evenly(a, samples)),
                  distances_to_surface(a, a_faces, evenly(b, samples))]
    pooled = distance_summary(np.concatenate(directions))
    return {"max": float(max(d.max() for d in directions)),
            "mean": float(np.mean([d.mean() for d in directions])),
            "rms": float(np.mean([np.sqrt(np.mean(d**2)) for d in directions])),
            **{key: pooled[key] for key in ("p50", "p90", "p99")},
            "samples": int(min(samples, len(a), len(b)))}


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

"""Two-way Hausdorff distance between surfaces, on arrays at sampled vertices (the filter's and the
report's checks; meshlab/layer_checks has MeshLab's own filter between layers)."""

from __future__ import annotations

import numpy as np

from ..core.mesh_quantities import evenly, surface_vertices
from ..core.mirror_fill import distances_to_surface
from .surface_asymmetry import distance_summary

# Vertices, evenly strided, sampled on each surface for the two-way distance. Closest points on a
# centroid KD-tree cost the same whatever the distance; MeshLab's grid slows down on far samples
# (3.8 s on a 61k-vertex pair moved 0.3 % of its size, minutes at 1M vertices).
HAUSDORFF_SAMPLES = 20_000


def two_way_distance(a: np.ndarray, a_faces: np.ndarray, b: np.ndarray, b_faces: np.ndarray,
                     samples: int = HAUSDORFF_SAMPLES) -> dict[str, float]:
    """max, mean and RMS of the distance (mesh units) from at most ``samples`` evenly strided vertices of
    each surface ``(points (N, 3), faces (F, 3))`` to the other (max: the larger direction; mean, RMS:
    their average), its 50th, 90th and 99th percentiles over both directions' samples, and ``samples``
    used per surface. Vertices no face uses are not sampled (they are not on the surface); a point cloud
    (no faces) is its points."""
    on_a, on_b = surface_vertices(a, a_faces), surface_vertices(b, b_faces)
    directions = [distances_to_surface(b, b_faces, evenly(on_a, samples)),
                  distances_to_surface(a, a_faces, evenly(on_b, samples))]
    pooled = distance_summary(np.concatenate(directions))
    return {"max": float(max(d.max() for d in directions)),
            "mean": float(np.mean([d.mean() for d in directions])),
            "rms": float(np.mean([np.sqrt(np.mean(d**2)) for d in directions])),
            **{key: pooled[key] for key in ("p50", "p90", "p99")},
            "samples": int(min(samples, len(on_a), len(on_b)))}

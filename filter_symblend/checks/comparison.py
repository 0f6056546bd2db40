"""Before/after checks of a symmetrization: Hausdorff between the meshes, mirror asymmetry of each."""

from __future__ import annotations

import pymeshlab

from .hausdorff import two_way_distance
from .surface_asymmetry import CHECK_SAMPLES, before_and_after


def compare_layers(ms: pymeshlab.MeshSet, before: int, after: int, samples: int | None = CHECK_SAMPLES) -> dict:
    """``{"hausdorff_before_after", "mirror_asymmetry_before", "mirror_asymmetry_after"}`` for two
    layers of ``ms``; each mirror asymmetry is measured at ``samples`` evenly strided vertices (None:
    all) and holds their distances as ``per_vertex``, each against its own plane fitted as the filter
    fits it (:func:`before_and_after`). The layers are not changed."""
    meshes = [(ms.mesh(i).vertex_matrix(), ms.mesh(i).face_matrix()) for i in (before, after)]
    result = {"hausdorff_before_after": two_way_distance(*meshes[0], *meshes[1])}
    result["mirror_asymmetry_before"], result["mirror_asymmetry_after"] = before_and_after(*meshes, samples)
    return result

"""Ground truth that does not mirror its tessellation, for tests and the benchmark: an exactly symmetric
mesh remeshed by pymeshlab so that no vertex has an exact twin (its twins are points of the surface)."""

from __future__ import annotations

import numpy as np
import pymeshlab

from .surface_truth import SurfaceTruth, surface_truth


def remeshed(points: np.ndarray, faces: np.ndarray, offset: float, edge_percent: float) -> SurfaceTruth:
    """The mesh (``points`` (N, 3), ``faces`` (F, 3), symmetric across x = ``offset``) remeshed isotropically
    with edges ``edge_percent`` % of the diagonal, and its true twins. One side's triangles are split first
    (the surface unchanged) and no crease is kept, so that no vertex keeps an exact twin."""
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=points, face_matrix=faces))
    ms.compute_selection_by_condition_per_face(condselect=f"(x0 + x1 + x2) / 3 > {float(offset)!r}")
    ms.meshing_surface_subdivision_midpoint(iterations=1, threshold=pymeshlab.PercentageValue(0.0), selected=True)
    ms.set_selection_none()
    ms.meshing_isotropic_explicit_remeshing(iterations=6, targetlen=pymeshlab.PercentageValue(edge_percent),
                                            featuredeg=180.0)
    ms.meshing_remove_unreferenced_vertices()
    mesh = ms.current_mesh()
    return surface_truth(mesh.vertex_matrix(), mesh.face_matrix(), offset)
